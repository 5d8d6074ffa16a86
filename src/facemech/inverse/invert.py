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
    bounded Gauss-Newton on the marker residuals, activity in [0, 1] (or [-1, 1] without the
    positive constraint): a forward-difference Jacobian (each column one step from the frame's
    state) taken once at the warm start and renewed only when a step fails, each linearised step
    solved exactly within the bounds. Optional regularisation rows, weights in
    mm per unit of activity: ``smooth`` (a - a_previous), ``effort`` (a), ``prior`` (a - EMG).
    Per frame it reports the residual, the controls on a bound and the Jacobian's condition
    number, and warns when the muscles are barely identifiable.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..errors import InputError
from ..markerset import MarkerSet
from ..params import EMG_CHANNELS, MUSCLE_GROUPS, Parameters
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
    dt: float = 1e-3,
    smooth: float = 0.0,
    effort: float = 0.0,
    prior: np.ndarray | None = None,
    prior_weight: float = 0.0,
    max_evaluations: int = 400,
    window: int = 3,
    tol: float = 1e-3,
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
    dt : explicit Euler step used by every evaluation (s; the paper's is 0.33e-3)
    smooth, effort, prior_weight : regularisation weights (mm per unit activity), lsq only
    prior : (frames, c) prior activity (e.g. processed EMG) for ``prior_weight``
    window : frames ahead in each frame's cost (lsq): the trial activity is held over
        ``window`` frames and the markers of all of them are fitted, but only the first frame
        is kept (a receding horizon; 1 is the seeds' one-frame inversion, which on this model
        swings between the bounds from frame to frame: the activation filter makes one frame's
        activity show mostly in the frames after it)
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
    params = params or Parameters()
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
    stepper = Stepper(Physics.build(face, params), integrator="euler", dt=dt)
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
    jm_prev = None  # the chord Jacobian carried from frame to frame (lsq)
    t0 = time.perf_counter()
    for k in range(frames - 1):
        target = data[k + 1] * 1e3  # mm
        ok = np.all(np.isfinite(target), axis=1)
        if 3 * ok.sum() < nc:
            raise InputError(f"frame {k + 1}: {int(ok.sum())} usable markers for {nc} muscles",
                             field="markers")
        gaps += int((~ok).sum())
        frame = _FrameProblem(stepper, state, gmat, nodes, data, jaw, k, ok, target,
                              window if method == "lsq" else 1)
        if method == "powell":
            c = frame.powell(c_prev, positive, lo, hi, max_evaluations)
        else:
            c, cond[k + 1], jm_prev = frame.lsq(c_prev, lo, hi, max_evaluations, smooth,
                                                effort, None if prior is None else prior[k],
                                                prior_weight, jm_prev, tol)
        state, _ = frame.nodes_after(c)
        counter = frame.counter
        out_c[k] = c
        c_prev = c
        bound[k + 1] = (c <= lo + 1e-6) | (c >= hi - 1e-6)
        model_now = state.positions[nodes]
        d = model_now[ok] - data[k + 1][ok]
        rms[k + 1] = np.sqrt(np.sum(d * d) / ok.sum())
        used[k + 1] = int(ok.sum())
        nfev[k + 1] = counter[0]
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
    """One frame's fit: trial activity held from the frame's state, markers compared (mm)."""

    def __init__(self, stepper, state, gmat, nodes, data, jaw, k, ok, target, horizon):
        self.stepper, self.state, self.gmat, self.nodes = stepper, state, gmat, nodes
        self.data, self.jaw, self.k, self.ok, self.target = data, jaw, k, ok, target
        self.horizon = min(horizon, len(data) - 1 - k)
        self.counter = [0]
        self.nc = gmat.shape[1]
        self._cache: dict = {}
        self._last = None  # (activity, state after one frame) of the latest evaluation

    def nodes_after(self, c):
        """State and marker nodes (mm) one frame after the frame's state under activity c."""
        c = np.array(c, float)
        if self._last is not None and np.array_equal(self._last[0], c):
            return self._last[1], self._last[1].positions[self.nodes] * 1e3
        self.counter[0] += 1
        s = self.stepper.advance(self.state, self.gmat @ c, self.jaw[self.k + 1])
        self._last = (c, s)
        return s, s.positions[self.nodes] * 1e3

    def marker_residual(self, c):
        s, pos = self.nodes_after(c)
        parts = [(pos[self.ok] - self.target[self.ok]).reshape(-1)]
        for j in range(2, self.horizon + 1):
            s = self.stepper.advance(s, self.gmat @ c, self.jaw[self.k + j])
            tj = self.data[self.k + j] * 1e3
            okj = np.all(np.isfinite(tj), axis=1)
            parts.append((s.positions[self.nodes][okj] * 1e3 - tj[okj]).reshape(-1))
        return np.concatenate(parts)

    def powell(self, c_prev, positive, lo, hi, max_evaluations):
        def cost(c):
            neg = c[c < 0]
            if positive and neg.size:  # E' of the paper: no simulation needed
                return PENALTY * (1.0 + abs(neg.sum()))
            try:
                return float(np.sum(self.marker_residual(c) ** 2))
            except (ZeroDivisionError, FloatingPointError):
                return PENALTY * 10.0

        # activity is normalised to at most 1 (and at least -1 without the positive
        # constraint), so that a wild trial step cannot collapse the mesh; negative values with
        # the constraint meet the published penalty instead of a bound
        res = minimize(cost, c_prev, method="Powell",
                       bounds=[(None if positive else lo, hi)] * self.nc,
                       options={"xtol": 1e-3, "ftol": 1e-9, "maxfev": max_evaluations})
        return res.x

    def jacobian(self, c, r0, hi):
        """Forward-difference Jacobian (residuals x controls) at c, one step per column."""
        jm = np.empty((len(r0), self.nc))
        for j in range(self.nc):
            h = 1e-3 if c[j] + 1e-3 <= hi else -1e-3
            cj = c.copy()
            cj[j] += h
            jm[:, j] = (self.marker_residual(cj) - r0) / h
        return jm

    def lsq(self, c_prev, lo, hi, max_evaluations, smooth, effort, prior, prior_weight,
            jm_prev=None, tol=1e-3):
        """Bounded Gauss-Newton with a chord Jacobian.

        The chord Jacobian is the previous frame's (``jm_prev``) or is computed at the warm start;
        each iteration solves the linearised problem with bounds exactly (bounded-variable least
        squares) and is accepted if the full residual falls. A new Jacobian is taken only when a
        step fails; the iterations stop when an accepted step lowers the RMS marker residual by
        less than ``tol`` mm, and after at most ``max_evaluations`` step-function calls. Returns
        the activity, the condition number and the Jacobian (to seed the next frame).
        """
        from scipy.optimize import lsq_linear

        nc = self.nc
        regs = []  # regularisation rows: (weight, offset)
        if smooth > 0:
            regs.append((smooth, np.asarray(c_prev, float)))
        if effort > 0:
            regs.append((effort, np.zeros(nc)))
        if prior is not None and prior_weight > 0:
            regs.append((prior_weight, np.asarray(prior, float)))

        def total(c, r):
            return float(np.sum(r * r) + sum(np.sum((w * (c - off)) ** 2) for w, off in regs))

        c = np.clip(np.asarray(c_prev, float), lo, hi)
        r = self.marker_residual(c)
        if jm_prev is not None and jm_prev.shape == (len(r), nc):
            jm, fresh = jm_prev, False
        else:
            jm, fresh = self.jacobian(c, r, hi), True
        self._cache.update({"jm": jm, "x": c.copy(), "r": r})
        cost = total(c, r)
        for _ in range(12):
            if self.counter[0] >= max_evaluations:
                break
            a = np.vstack([jm, *(w * np.eye(nc) for w, _ in regs)])
            b = -np.concatenate([r, *(w * (c - off) for w, off in regs)])
            step = lsq_linear(a, b, bounds=(lo - c, hi - c), method="bvls").x
            if np.max(np.abs(step)) < 1e-5:
                break
            trial = np.clip(c + step, lo, hi)
            r_trial = self.marker_residual(trial)
            cost_trial = total(trial, r_trial)
            if cost_trial < cost:
                gain = (np.sqrt(cost) - np.sqrt(cost_trial)) / np.sqrt(max(len(r), 1) / 3)
                improvement = (cost - cost_trial) / max(cost, 1e-30)
                c, r, cost = trial, r_trial, cost_trial
                fresh = False
                if improvement < 1e-4 or gain < tol:
                    break
            elif fresh:
                break  # even a fresh Jacobian's step does not help: done
            else:
                jm = self.jacobian(c, r, hi)  # the chord went stale: renew it
                fresh = True
        self._cache.update({"jm": jm, "x": c.copy(), "r": r})
        sv = np.linalg.svd(jm, compute_uv=False)
        cond = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
        return c, cond, jm
