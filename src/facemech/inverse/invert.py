"""Frame-by-frame dynamic inversion: muscle activity from marker trajectories.

Pitermann & Munhall (2001, II.C): for each 60-Hz frame, starting from the current state
(positions, velocities, muscle filter), find the activity that, held for one frame through the
full dynamics, brings the model's marker nodes closest to the next frame's markers; the answer
seeds the next frame, zero seeds the first. Every cost evaluation is one call of the same step
function as the forward simulation, so the accepted states form the re-animation.

Methods:

``powell`` (the seeds')
    Powell's direction-set minimisation of E = sum_i |m_i - n_i|^2 (mm^2); with the positive
    constraint, E' = E if every activity is >= 0, else 1e6 (1 + |sum of the negative ones|).
``lsq`` (default)
    a receding horizon: the activity of each of the next ``window`` frames is fitted to the
    markers of those frames and only the first frame's is kept. Bounded Gauss-Newton on the
    marker residuals, activity in [0, 1] (or [-1, 1] without the positive constraint): the
    Jacobian is built from forward differences of the markers with respect to the first frame's
    activity (one roll of the window per control, from the frame's state), taken as
    time-invariant within the window, carried from frame to frame and renewed only when a step
    fails; each linearised step is solved exactly within the bounds. Regularisation rows,
    weights in mm per unit of activity: ``bend`` (second differences of activity across the
    window; on by default, 0.03), ``smooth`` (first differences, from the previous frame's),
    ``effort`` (a), ``prior`` (a - EMG). Per frame it reports the residual, the controls on a
    bound and the condition number of the frame's own Jacobian columns, and warns when the
    muscles are barely identifiable.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..errors import InputError, SimulationBlowUp
from ..markerset import MarkerSet
from ..params import EMG_CHANNELS, MUSCLE_GROUPS, Parameters, default_parameters
from ..physics.assembly import Physics
from ..solvers.state import State
from ..solvers.step import Stepper

PENALTY = 1e6  #: the positive constraint of Pitermann & Munhall (2001)
ILL_POSED_CONDITION = 1e4  #: Jacobian condition number above which a frame is flagged


def control_matrix(controls) -> tuple[tuple[str, ...], np.ndarray]:
    """Names of the inverted controls and the (16, controls) map to group activity.

    ``"emg7"``: the seeds' seven EMG channels (ZYG follows LAO); ``"all"``: the 16 groups; or
    a list of group names.
    """
    if controls == "emg7":
        names = EMG_CHANNELS
    elif controls == "all":
        names = MUSCLE_GROUPS
    else:
        names = tuple(controls)
    g = np.zeros((len(MUSCLE_GROUPS), len(names)))
    for j, n in enumerate(names):
        if n not in MUSCLE_GROUPS:
            raise InputError(f"unknown muscle group (expected {', '.join(MUSCLE_GROUPS)})",
                             field=n)
        g[MUSCLE_GROUPS.index(n), j] = 1.0
    if controls == "emg7":
        g[MUSCLE_GROUPS.index("ZYG"), names.index("LAO")] = 1.0
    return tuple(names), g


@dataclass(frozen=True, eq=False)
class InversionResult:
    """Activity recovered from markers, the re-animation, and per-frame diagnostics.

    ``activity`` (frames, 16) is the group activity of each frame's interval (the last row repeats
    the one before); ``controls`` (frames, c) are the inverted controls; ``positions`` (frames,
    n_surface, 3) m and ``model_markers`` (frames, markers, 3) m are the re-animation.
    """

    names: tuple[str, ...]
    control_names: tuple[str, ...]
    controls: np.ndarray
    activity: np.ndarray
    positions: np.ndarray
    model_markers: np.ndarray
    data_markers: np.ndarray
    jaw_angle: np.ndarray
    rms_error: np.ndarray  # (frames,) m, sqrt(E/N) after each frame's fit (0 for frame 0)
    markers_used: np.ndarray  # (frames,)
    on_bound: np.ndarray  # (frames, c) bool
    condition: np.ndarray  # (frames,) Jacobian condition number (lsq; NaN for powell)
    evaluations: np.ndarray  # (frames,) step-function calls
    method: str
    positive: bool
    wall_seconds: float
    notes: list = field(default_factory=list)


def invert(
    face,
    markers: MarkerSet,
    mapping: dict[str, int],
    *,
    method: str = "lsq",
    positive: bool = True,
    controls="emg7",
    jaw_angle: np.ndarray | None = None,
    params: Parameters | None = None,
    dt: float | None = None,
    smooth: float = 0.0,
    effort: float = 0.0,
    prior: np.ndarray | None = None,
    prior_weight: float = 0.0,
    max_evaluations: int = 400,
    window: int = 3,
    tol: float = 1e-3,
    bend: float = 0.03,
    progress: Callable[[int, int], None] | None = None,
) -> InversionResult:
    """Recover muscle activity frame by frame (see the module doc).

    Parameters
    ----------
    face : FaceModel
    markers : MarkerSet in the model's frame (metres) at the model's frame rate (60 Hz)
    mapping : marker name -> epidermal node (see :func:`facemech.closest_nodes`)
    method : "lsq" or "powell"
    positive : activity kept >= 0 (bounds for lsq, the published penalty for powell)
    controls : "emg7", "all" or a list of groups
    jaw_angle : (frames,) rad, optional (default: jaw closed)
    params : Parameters (default: the default preset, ``anatomical``)
    dt : explicit Euler step used by every evaluation (s; default ``params.fast_dt``: 1 ms for
        ``lucero1999``, the paper's 0.33 ms for ``pitermann2001`` and ``calibrated``); the
        anatomical preset steps with its implicit integrator (4.2 ms), and another ``dt`` is an
        error there
    smooth, effort, prior_weight : regularisation weights (mm per unit activity), lsq only
    prior : (frames, c) prior activity (e.g. processed EMG) for ``prior_weight``
    window : frames in each frame's fit (lsq): the activity of each of them is fitted to
        their markers and only the first frame's is kept (a receding horizon; 1 is the seeds'
        one-frame inversion, which on this model swings between the bounds from frame to frame:
        the activation filter makes one frame's activity show mostly in the frames after it)
    bend : weight (mm per unit activity) of the second differences of activity across the
        window (lsq); it settles the last frames of the window, which their markers barely see,
        and does not bias activity that changes at a steady rate
    tol : mm (lsq). A frame's iterations stop once a step lowers the RMS marker residual by
        less than ``tol``. The default, 1 um, lies far below any motion-capture precision; a
        smaller one costs more steps without a better answer (the extra steps only move activity
        along directions the markers barely see; see docs/inversion.md)
    """
    if method not in ("lsq", "powell"):
        raise InputError(f"unknown method {method!r} (lsq or powell)", field="method")
    if window < 1:
        raise InputError(f"window must be at least 1 frame (got {window})", field="window")
    if not tol >= 0:
        raise InputError(f"tol must be >= 0 mm (got {tol})", field="tol")
    for name, value in (("smooth", smooth), ("effort", effort), ("prior_weight", prior_weight),
                        ("bend", bend)):
        if not value >= 0:
            raise InputError(f"{name} must be >= 0 (got {value})", field=name)
    params = params or default_parameters()
    dt = params.fast_dt if dt is None else dt
    if abs(markers.rate - params.frame_rate) > 1e-3 * params.frame_rate:
        raise InputError(f"markers at {markers.rate:g} Hz, the model runs at "
                         f"{params.frame_rate:g} Hz: resample first (facemech markers resample)",
                         source=markers.meta.get("source"), field="rate")
    names = [n for n in markers.names if n in mapping]
    if not names:
        raise InputError("no marker has a node", field="mapping")
    cnames, gmat = control_matrix(controls)
    nc = len(cnames)
    if 3 * len(names) < nc:
        raise InputError(f"{len(names)} markers give {3 * len(names)} coordinates for {nc} "
                         "muscles: use more markers or fewer controls", field="markers")
    data = markers.select(names).positions
    nodes = np.array([mapping[n] for n in names])
    frames = len(data)
    jaw = np.zeros(frames) if jaw_angle is None else np.asarray(jaw_angle, float)
    if jaw.shape != (frames,):
        raise InputError("jaw angle series and markers differ in length", field="jaw_angle")
    if prior is not None and np.shape(prior) != (frames, nc):
        raise InputError(f"prior must be (frames, {nc})", field="prior")
    physics = Physics.build(face, params)
    face = physics.model  # with the preset's tissue geometry (same epidermal nodes)
    stepper = Stepper(physics, dt=dt)
    lo, hi = (0.0, 1.0) if positive else (-1.0, 1.0)
    state = State.at_rest(face.rest_positions, stepper.physics.n_muscles, float(jaw[0]))
    c_prev = np.zeros(nc)
    out_c = np.zeros((frames, nc))
    rms = np.zeros(frames)
    used = np.zeros(frames, int)
    bound = np.zeros((frames, nc), bool)
    cond = np.full(frames, np.nan)
    nfev = np.zeros(frames, int)
    positions = np.empty((frames, face.n_surface, 3))
    positions[0] = state.positions[: face.n_surface]
    notes: list[str] = []
    gaps = 0
    # carried from frame to frame (lsq): lag responses, window solution, its states
    lags_prev = x_prev = None
    states_prev: list = []
    t0 = time.perf_counter()
    for k in range(frames - 1):
        ok = np.all(np.isfinite(data[k + 1]), axis=1)
        if 3 * ok.sum() < nc:
            raise InputError(f"frame {k + 1}: {int(ok.sum())} usable markers for {nc} muscles",
                             field="markers")
        gaps += int((~ok).sum())
        frame = _FrameProblem(stepper, state, gmat, nodes, data, jaw, k,
                              window if method == "lsq" else 1)
        if method == "powell":
            c = frame.powell(c_prev, positive, lo, hi, max_evaluations)
            state = frame.state_after(c)
        elif frame.horizon < window and x_prev is not None and len(x_prev) > 1:
            # the data end inside the window: the last full window already fitted every frame
            # left, so its activity is kept rather than refitted on ever fewer frames
            c = x_prev[1].copy()
            x_prev = x_prev[1:]
            state = states_prev[1]  # simulated in that window's accepted roll
            states_prev = states_prev[1:]
            cond[k + 1] = cond[k]
        else:
            c, state, cond[k + 1], x_prev, lags_prev, states_prev = frame.lsq(
                c_prev, x_prev, lo, hi, max_evaluations, smooth=smooth, effort=effort,
                prior=prior, prior_weight=prior_weight, bend=bend, lags_prev=lags_prev, tol=tol,
                known=states_prev[1:])
        out_c[k] = c
        c_prev = c
        bound[k + 1] = (c <= lo + 1e-6) | (c >= hi - 1e-6)
        model_now = state.positions[nodes]
        d = model_now[ok] - data[k + 1][ok]
        rms[k + 1] = np.sqrt(np.sum(d * d) / ok.sum())
        used[k + 1] = int(ok.sum())
        nfev[k + 1] = frame.counter[0]
        positions[k + 1] = state.positions[: face.n_surface]
        if progress is not None:
            progress(k + 1, frames - 1)
    out_c[-1] = out_c[-2] if frames > 1 else out_c[-1]
    if gaps:
        notes.append(f"{gaps} missing marker samples were left out of their frames' costs")
    bad = np.nonzero(cond > ILL_POSED_CONDITION)[0]
    if len(bad):
        msg = (f"ill-posed: the Jacobian condition number exceeds {ILL_POSED_CONDITION:.0e} in "
               f"{len(bad)} of {frames - 1} frames (median {np.nanmedian(cond):.3g}); some "
               "muscles are barely identifiable from these markers (try regularisation)")
        notes.append(msg)
        warnings.warn(msg, stacklevel=2)
    return InversionResult(
        names=tuple(names), control_names=cnames, controls=out_c, activity=out_c @ gmat.T,
        positions=positions, model_markers=positions[:, nodes], data_markers=data,
        jaw_angle=jaw, rms_error=rms, markers_used=used, on_bound=bound, condition=cond,
        evaluations=nfev, method=method, positive=positive,
        wall_seconds=time.perf_counter() - t0, notes=notes,
    )


class _FrameProblem:
    """One frame's fit over a window of ``horizon`` frames, markers compared in mm.

    The unknowns are the activity of each frame of the window, ``x`` of shape (horizon, c);
    the residual stacks the markers of frames ``k + 1 ... k + horizon`` (missing ones left out
    frame by frame). Only the first frame's activity is kept (a receding horizon).
    """

    def __init__(self, stepper, state, gmat, nodes, data, jaw, k, horizon):
        self.stepper, self.state, self.gmat, self.nodes = stepper, state, gmat, nodes
        self.data, self.jaw, self.k = data, jaw, k
        self.horizon = min(horizon, len(data) - 1 - k)
        self.targets = data[k + 1:k + 1 + self.horizon] * 1e3  # (w, markers, 3) mm
        self.oks = np.all(np.isfinite(self.targets), axis=2)  # (w, markers)
        self.counter = [0]  # step-function calls (one per frame simulated)
        self.nc = gmat.shape[1]
        self._last = None  # (x, state after the first frame) of the latest roll
        self.states: list = []  # states of the latest roll, one per frame of the window

    def _window(self, x) -> np.ndarray:
        x = np.asarray(x, float)
        return x.reshape(-1, self.nc)[: self.horizon]

    def roll(self, x, known=()):
        """Simulate the window under x: marker nodes (w, markers, 3) mm and the first state.

        ``known`` are states already simulated for the first frames of the window under the
        same activity (the previous frame's accepted roll); they are used as they are.
        """
        x = self._window(x)
        s, states, pos = self.state, [], []
        for a in range(len(x)):
            if a < len(known):
                s = known[a]
            else:
                s = self.stepper.advance(s, self.gmat @ x[a], self.jaw[self.k + 1 + a])
                self.counter[0] += 1
            states.append(s)
            pos.append(s.positions[self.nodes] * 1e3)
        self._last = (x.copy(), states[0])
        self.states = states
        return np.array(pos), states[0]

    def residual_of(self, pos) -> np.ndarray:
        return np.concatenate([(pos[a][ok] - self.targets[a][ok]).reshape(-1)
                               for a, ok in enumerate(self.oks[: len(pos)])])

    def marker_residual(self, x) -> np.ndarray:
        """Marker residuals (mm) of the window under x (flattened or (w, c); for a one-frame
        window, x may be the c activities of the frame)."""
        return self.residual_of(self.roll(x)[0])

    def state_after(self, c) -> State:
        """The state one frame on when the frame's activity is c (reuses the latest roll)."""
        c = np.asarray(c, float)
        if self._last is not None and np.array_equal(self._last[0][0], c):
            return self._last[1]
        self.counter[0] += 1
        return self.stepper.advance(self.state, self.gmat @ c, self.jaw[self.k + 1])

    def powell(self, c_prev, positive, lo, hi, max_evaluations):
        def cost(c):
            neg = c[c < 0]
            if positive and neg.size:  # E' of the paper: no simulation needed
                return PENALTY * (1.0 + abs(neg.sum()))
            try:
                return float(np.sum(self.marker_residual(c) ** 2))
            except (ZeroDivisionError, FloatingPointError, SimulationBlowUp):
                return PENALTY * 10.0

        # activity is normalised to at most 1 (and at least -1 without the positive
        # constraint), so that a wild trial step cannot collapse the mesh; negative values with
        # the constraint meet the published penalty instead of a bound
        res = minimize(cost, c_prev, method="Powell",
                       bounds=[(None if positive else lo, hi)] * self.nc,
                       options={"xtol": 1e-3, "ftol": 1e-9, "maxfev": max_evaluations})
        return res.x

    def lag_responses(self, x, pos0, hi) -> np.ndarray:
        """Forward differences of all marker nodes with respect to the first frame's activity.

        Returns H of shape (w, 3 markers, c): ``H[a]`` is the response of frame ``k + 1 + a`` to
        the activity of frame ``k`` (one roll of the window per control, from the frame's state).
        """
        x = self._window(x)
        h_all = np.empty((len(x), pos0[0].size, self.nc))
        for j in range(self.nc):
            h = 1e-3 if x[0, j] + 1e-3 <= hi else -1e-3
            xj = x.copy()
            xj[0, j] += h
            h_all[:, :, j] = (self.roll(xj)[0] - pos0).reshape(len(x), -1) / h
        return h_all

    def jacobian(self, lags) -> np.ndarray:
        """Window Jacobian (residuals x w c) from lag responses, taken as time-invariant
        within the window: the block of frame a and activity b is ``lags[a - b]``."""
        w, nc = self.horizon, self.nc
        rows = [np.repeat(ok, 3) for ok in self.oks]
        jm = np.zeros((sum(int(r.sum()) for r in rows), w * nc))
        r0 = 0
        for a in range(w):
            n = int(rows[a].sum())
            for b in range(a + 1):
                jm[r0:r0 + n, b * nc:(b + 1) * nc] = lags[a - b][rows[a]]
            r0 += n
        return jm

    def regularisation(self, c_prev, smooth, effort, prior, prior_weight, bend):
        """Rows (A, b) of the regularisation residual A x + b (mm) over the window."""
        w, nc = self.horizon, self.nc
        eye = np.eye(nc)
        blocks, offsets = [], []

        def row(terms, offset, weight):
            a = np.zeros((nc, w * nc))
            for idx, coef in terms:
                a[:, idx * nc:(idx + 1) * nc] += coef * eye
            blocks.append(weight * a)
            offsets.append(weight * offset)

        c_prev = np.asarray(c_prev, float)
        if bend > 0:  # second differences within the window (x_0 itself stays free)
            for a in range(1, w - 1):
                row([(a - 1, 1.0), (a, -2.0), (a + 1, 1.0)], np.zeros(nc), bend)
        if smooth > 0:  # first differences, x_{-1} = c_prev
            for a in range(w):
                row([(a, 1.0)] + ([(a - 1, -1.0)] if a > 0 else []),
                    -c_prev if a == 0 else np.zeros(nc), smooth)
        if effort > 0:
            for a in range(w):
                row([(a, 1.0)], np.zeros(nc), effort)
        if prior is not None and prior_weight > 0:
            for a in range(min(w, len(prior) - self.k)):
                row([(a, 1.0)], -np.asarray(prior[self.k + a], float), prior_weight)
        if not blocks:
            return np.zeros((0, w * nc)), np.zeros(0)
        return np.vstack(blocks), np.concatenate(offsets)

    def lsq(self, c_prev, x_prev, lo, hi, max_evaluations, *, smooth=0.0, effort=0.0,
            prior=None, prior_weight=0.0, bend=0.0, lags_prev=None, tol=1e-3, known=()):
        """Bounded Gauss-Newton over the window with a chord Jacobian.

        The lag responses are the previous frame's (``lags_prev``) or are taken at the warm
        start; each iteration solves the linearised problem with bounds exactly (bounded-variable
        least squares) and is accepted if the full cost falls. New lag responses are taken only
        when a step fails; the iterations stop when an accepted step lowers the residual (the
        markers' and the regularisation rows', as an RMS per marker) by less than ``tol`` mm,
        and after at most ``max_evaluations`` frame steps.

        ``known``: states of the warm start's first frames already simulated (the previous
        frame's accepted roll, shifted), reused in the first roll.

        Returns the frame's activity, the state one frame on, the condition number of the
        frame's own Jacobian columns, the window solution (to warm-start the next frame), the
        lag responses (to seed its chord) and the states of the accepted roll.
        """
        from scipy.optimize import lsq_linear

        w, nc = self.horizon, self.nc
        if x_prev is not None and len(x_prev):
            x = np.vstack([x_prev[1:], x_prev[-1:]])
            x = np.vstack([x, np.repeat(x[-1:], max(0, w - len(x)), axis=0)])[:w]
        else:
            x = np.tile(np.asarray(c_prev, float), (w, 1))
        x = np.clip(x, lo, hi)
        a_reg, b_reg = self.regularisation(c_prev, smooth, effort, prior, prior_weight, bend)

        def total(xv, r):
            q = a_reg @ xv.reshape(-1) + b_reg
            return float(r @ r + q @ q)

        pos, first = self.roll(x, known if x_prev is not None else ())
        states = self.states
        r = self.residual_of(pos)
        n_markers = max(len(r) / 3.0, 1.0)
        if lags_prev is not None and lags_prev.shape[0] >= w and lags_prev.shape[1] == pos[0].size:
            lags, fresh = lags_prev[:w], False
        else:
            lags, fresh = self.lag_responses(x, pos, hi), True
        jm = self.jacobian(lags)
        cost = total(x, r)
        for _ in range(12):
            if self.counter[0] >= max_evaluations:
                break
            a = np.vstack([jm, a_reg])
            b = -np.concatenate([r, a_reg @ x.reshape(-1) + b_reg])
            flat = x.reshape(-1)
            step = lsq_linear(a, b, bounds=(lo - flat, hi - flat), method="bvls").x
            if np.max(np.abs(step)) < 1e-6:
                break
            trial = np.clip(flat + step, lo, hi).reshape(w, nc)
            try:
                pos_t, first_t = self.roll(trial)
            except SimulationBlowUp:  # a wild trial collapsed the mesh: a failed step
                pos_t = None
            if pos_t is None:
                cost_trial = np.inf
            else:
                r_trial = self.residual_of(pos_t)
                cost_trial = total(trial, r_trial)
            if cost_trial < cost:
                gain = (np.sqrt(cost) - np.sqrt(cost_trial)) / np.sqrt(n_markers)
                x, r, cost, pos, first = trial, r_trial, cost_trial, pos_t, first_t
                states = self.states
                fresh = False
                if gain < tol:
                    break
            elif fresh:
                break  # even fresh responses give no better step: done
            else:
                lags, fresh = self.lag_responses(x, pos, hi), True  # the chord went stale
                jm = self.jacobian(lags)
        own = jm[:, :nc]
        sv = np.linalg.svd(own, compute_uv=False) if own.size else np.zeros(1)
        cond = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
        self._last = (x.copy(), first)
        return x[0].copy(), first, cond, x, lags, states
