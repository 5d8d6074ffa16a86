"""One frame's fit of the inversion (Pitermann & Munhall 2001, II.C), over a window of frames.

The unknowns of frame k are the controls of frames k ... k + w - 1, ``x`` of shape (w, c): the
muscle controls (mapped to every group by ``gmat``) and, when the jaw is estimated, one more
column, the jaw angle reached at the end of the frame in units of ``JAW_UNIT`` rad. The residual
stacks the markers of frames k + 1 ... k + w (missing ones left out frame by frame), in mm. Only
the first frame's controls are kept (a receding horizon).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear, minimize

from ..errors import SimulationBlowUp
from ..solvers.state import State

PENALTY = 1e6  #: the positive constraint of Pitermann & Munhall (2001)
JAW_UNIT = 0.1  #: rad per unit of the jaw control (so that it is scaled like activity)
FD_STEP = 1e-3  #: forward-difference step of the lag responses, control units


class FrameProblem:
    """One frame's fit over a window of ``horizon`` frames, markers compared in mm.

    Parameters
    ----------
    stepper : Stepper
    state : State at frame k
    gmat : (groups, muscle controls) map from muscle controls to group activity
    nodes : (markers,) model nodes of the markers
    data : (frames, markers, 3) m, the markers
    jaw : (frames,) rad or (frames, 3) poses, the jaw where it is given (ignored for an
        estimated jaw)
    k : the frame
    horizon : window length (cut at the data's end)
    estimate_jaw : the last control is the jaw angle
    lo, hi : (c,) bounds of the controls
    """

    def __init__(self, stepper, state, gmat, nodes, data, jaw, k, horizon, *,
                 estimate_jaw=False, lo=None, hi=None):
        self.stepper, self.state, self.gmat, self.nodes = stepper, state, gmat, nodes
        self.data, self.jaw, self.k = data, jaw, k
        self.horizon = min(horizon, len(data) - 1 - k)
        self.targets = data[k + 1:k + 1 + self.horizon] * 1e3  # (w, markers, 3) mm
        self.oks = np.all(np.isfinite(self.targets), axis=2)  # (w, markers)
        self.counter = [0]  # step-function calls (one per frame simulated)
        self.n_muscle = gmat.shape[1]
        self.estimate_jaw = estimate_jaw
        self.nc = self.n_muscle + (1 if estimate_jaw else 0)
        self.lo = np.zeros(self.nc) if lo is None else np.asarray(lo, float)
        self.hi = np.ones(self.nc) if hi is None else np.asarray(hi, float)
        self._last = None  # (x, state after the first frame) of the latest roll
        self.states: list = []  # states of the latest roll, one per frame of the window

    def _window(self, x) -> np.ndarray:
        x = np.asarray(x, float)
        return x.reshape(-1, self.nc)[: self.horizon]

    def _advance(self, s: State, xa: np.ndarray, frame: int) -> State:
        act = self.gmat @ xa[: self.n_muscle]
        jaw = xa[-1] * JAW_UNIT if self.estimate_jaw else self.jaw[frame]
        self.counter[0] += 1
        return self.stepper.advance(s, act, jaw)

    def roll(self, x, known=()):
        """Simulate the window under x: marker nodes (w, markers, 3) mm and the first state.

        ``known`` are states already simulated for the first frames of the window under the
        same controls (the previous frame's accepted roll); they are used as they are.
        """
        x = self._window(x)
        s, states, pos = self.state, [], []
        for a in range(len(x)):
            s = known[a] if a < len(known) else self._advance(s, x[a], self.k + 1 + a)
            states.append(s)
            pos.append(s.positions[self.nodes] * 1e3)
        self._last = (x.copy(), states[0])
        self.states = states
        return np.array(pos), states[0]

    def residual_of(self, pos) -> np.ndarray:
        return np.concatenate([(pos[a][ok] - self.targets[a][ok]).reshape(-1)
                               for a, ok in enumerate(self.oks[: len(pos)])])

    def marker_residual(self, x) -> np.ndarray:
        """Marker residuals (mm) of the window under x."""
        return self.residual_of(self.roll(x)[0])

    def state_after(self, c) -> State:
        """The state one frame on when the frame's controls are c (reuses the latest roll)."""
        c = np.asarray(c, float)
        if self._last is not None and np.array_equal(self._last[0][0], c):
            return self._last[1]
        return self._advance(self.state, c, self.k + 1)

    # -- Powell, the seeds' method ----------------------------------------------------------
    def powell(self, c_prev, positive, method):
        nm = self.n_muscle

        def cost(c):
            neg = c[:nm][c[:nm] < 0]
            if positive and neg.size:  # E' of the paper: no simulation needed
                return PENALTY * (1.0 + abs(neg.sum()))
            try:
                return float(np.sum(self.marker_residual(c) ** 2))
            except (ZeroDivisionError, FloatingPointError, SimulationBlowUp):
                return PENALTY * 10.0

        # activity is normalised to at most 1 (and at least -1 without the positive
        # constraint), so that a wild trial step cannot collapse the mesh; negative values with
        # the constraint meet the published penalty instead of a bound
        bounds = [(None if positive else self.lo[j], self.hi[j]) for j in range(nm)]
        bounds += [(self.lo[j], self.hi[j]) for j in range(nm, self.nc)]
        res = minimize(cost, c_prev, method="Powell", bounds=bounds,
                       options={"xtol": method.xtol, "ftol": method.ftol,
                                "maxfev": method.max_evaluations})
        return res.x

    # -- least squares ----------------------------------------------------------------------
    def lag_responses(self, x, pos0) -> np.ndarray:
        """Forward differences of all marker nodes with respect to the first frame's controls.

        Returns H of shape (w, 3 markers, c): ``H[a]`` is the response of frame ``k + 1 + a``
        to the controls of frame ``k`` (one roll of the window per control).
        """
        x = self._window(x)
        h_all = np.empty((len(x), pos0[0].size, self.nc))
        for j in range(self.nc):
            h = FD_STEP if x[0, j] + FD_STEP <= self.hi[j] else -FD_STEP
            xj = x.copy()
            xj[0, j] += h
            h_all[:, :, j] = (self.roll(xj)[0] - pos0).reshape(len(x), -1) / h
        return h_all

    def jacobian(self, lags) -> np.ndarray:
        """Window Jacobian (residuals x w c) from lag responses, taken as time-invariant
        within the window: the block of frame a and controls b is ``lags[a - b]``."""
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

    def regularisation(self, c_prev, method, prior, jaw_prior):
        """Rows (A, b) of the regularisation residual A x + b (mm) over the window.

        ``bend`` and ``smooth`` act on every control, ``effort`` and ``prior`` on the muscles,
        ``jaw_prior`` (frames,) rad on the estimated jaw.
        """
        w, nc, nm = self.horizon, self.nc, self.n_muscle
        blocks, offsets = [], []

        def row(terms, offset, weight, cols):
            a = np.zeros((len(cols), w * nc))
            for idx, coef in terms:
                for r, j in enumerate(cols):
                    a[r, idx * nc + j] += coef
            blocks.append(weight * a)
            offsets.append(weight * np.asarray(offset, float))

        every = np.arange(nc)
        muscles = np.arange(nm)
        c_prev = np.asarray(c_prev, float)
        if method.bend > 0:  # second differences within the window (x_0 itself stays free)
            for a in range(1, w - 1):
                row([(a - 1, 1.0), (a, -2.0), (a + 1, 1.0)], np.zeros(nc), method.bend, every)
        if method.smooth > 0:  # first differences, x_{-1} = c_prev
            for a in range(w):
                row([(a, 1.0)] + ([(a - 1, -1.0)] if a > 0 else []),
                    -c_prev if a == 0 else np.zeros(nc), method.smooth, every)
        if method.effort > 0:
            for a in range(w):
                row([(a, 1.0)], np.zeros(nm), method.effort, muscles)
        if prior is not None and method.prior_weight > 0:
            for a in range(min(w, len(prior) - self.k)):
                row([(a, 1.0)], -np.asarray(prior[self.k + a], float), method.prior_weight,
                    muscles)
        if self.estimate_jaw and jaw_prior is not None and method.jaw_prior_weight > 0:
            for a in range(w):
                f = min(self.k + 1 + a, len(jaw_prior) - 1)
                row([(a, 1.0)], [-jaw_prior[f] / JAW_UNIT], method.jaw_prior_weight, [nc - 1])
        if not blocks:
            return np.zeros((0, w * nc)), np.zeros(0)
        return np.vstack(blocks), np.concatenate(offsets)

    def window_bounds(self, c_prev, method) -> tuple[np.ndarray, np.ndarray]:
        """(w, c) lower and upper bounds of the window's controls: the controls' own, and for
        the muscles within ``max_rate / frame rate`` per frame of ``c_prev`` (a rate bound)."""
        w, nm = self.horizon, self.n_muscle
        lo, hi = np.tile(self.lo, (w, 1)), np.tile(self.hi, (w, 1))
        step = getattr(method, "max_rate", 0.0) / self.stepper.physics.params.frame_rate
        if step > 0:
            reach = step * np.arange(1, w + 1)[:, None]
            c = np.asarray(c_prev, float)[:nm]
            lo[:, :nm] = np.maximum(lo[:, :nm], c - reach)
            hi[:, :nm] = np.minimum(hi[:, :nm], c + reach)
        return lo, hi

    def _try(self, trial, total):
        """A trial step's roll: (positions, first state, residual, cost); the cost infinite
        where the trial collapsed the mesh (a failed step)."""
        try:
            pos_t, first_t = self.roll(trial)
        except SimulationBlowUp:
            return None, None, None, np.inf
        r_trial = self.residual_of(pos_t)
        return pos_t, first_t, r_trial, total(trial, r_trial)

    def lsq(self, c_prev, x_prev, method, *, prior=None, jaw_prior=None, lags_prev=None,
            known=(), expected_rms=None):
        """Bounded Gauss-Newton over the window with a chord Jacobian.

        The lag responses are the previous frame's (``lags_prev``) or are taken at the warm
        start; each iteration solves the linearised problem with bounds exactly (bounded-variable
        least squares) and is accepted if the full cost falls. New lag responses are taken only
        when a step fails; if a step along fresh responses fails too, it is halved (twice at
        most); the iterations stop when an accepted step lowers the residual (the
        markers' and the regularisation rows', as an RMS per marker) by less than ``tol`` mm,
        and after at most ``max_evaluations`` frame steps. A step the linearisation predicts
        to gain less than ``tol`` is not tried; but if the residual has grown past 1.5 times
        ``expected_rms`` (the last frame's, mm) the responses are renewed first.

        Returns a :class:`FrameFit`.
        """
        w, nc = self.horizon, self.nc
        lo, hi = self.window_bounds(c_prev, method)
        x = np.clip(_warm_start(x_prev, c_prev, w), lo, hi)
        a_reg, b_reg = self.regularisation(c_prev, method, prior, jaw_prior)

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
            lags, fresh = self.lag_responses(x, pos), True
        jm = self.jacobian(lags)
        cost = total(x, r)
        lo_f, hi_f = lo.reshape(-1), hi.reshape(-1)
        scale = 1.0  # of the Gauss-Newton step: halved when even fresh responses overshoot
        for _ in range(12):
            if self.counter[0] >= method.max_evaluations:
                break
            a = np.vstack([jm, a_reg])
            b = -np.concatenate([r, a_reg @ x.reshape(-1) + b_reg])
            flat = x.reshape(-1)
            step = lsq_linear(a, b, bounds=(lo_f - flat, hi_f - flat), method="bvls").x
            if np.max(np.abs(step)) < 1e-6:
                break
            res_lin = a @ step - b  # the linearised residual after the step
            if (np.sqrt(cost) - np.sqrt(res_lin @ res_lin)) / np.sqrt(n_markers) < method.tol:
                # not worth a roll, the model predicts less than tol of gain: done, unless the
                # residual has grown well past the last frame's and the responses are old
                now = np.sqrt(r @ r / n_markers)
                if fresh or expected_rms is None or now < 1.5 * expected_rms + 2 * method.tol:
                    break
                lags, fresh = self.lag_responses(x, pos), True
                jm = self.jacobian(lags)
                continue
            trial = np.clip(flat + scale * step, lo_f, hi_f).reshape(w, nc)
            pos_t, first_t, r_trial, cost_trial = self._try(trial, total)
            if cost_trial < cost:
                gain = (np.sqrt(cost) - np.sqrt(cost_trial)) / np.sqrt(n_markers)
                x, r, cost, pos, first = trial, r_trial, cost_trial, pos_t, first_t
                states = self.states
                scale = 1.0
                if gain < method.tol:
                    break
            elif scale > 0.4 or (fresh and scale > 0.2):
                scale *= 0.5  # the full step overshoots: a shorter one along it
            elif fresh:
                break  # even a short step along this frame's responses is no better: done
            else:
                lags, fresh, scale = self.lag_responses(x, pos), True, 1.0  # the chord is stale
                jm = self.jacobian(lags)
        self._last = (x.copy(), first)
        return FrameFit(x=x, state=first, states=states, lags=lags, jm=jm, a_reg=a_reg,
                        rss=float(r @ r), rows=len(r))


def _warm_start(x_prev, c_prev, w: int) -> np.ndarray:
    """The window's first controls (w, c): the previous window's shifted by a frame, its last
    frame repeated, or else the previous frame's controls throughout."""
    if x_prev is not None and len(x_prev):
        x = np.vstack([x_prev[1:], x_prev[-1:]])
        return np.vstack([x, np.repeat(x[-1:], max(0, w - len(x)), axis=0)])[:w]
    return np.tile(np.asarray(c_prev, float), (w, 1))


class FrameFit:
    """What one frame's least-squares fit leaves: the window's controls ``x`` (w, c), the state
    one frame on, the accepted roll's states, the lag responses, the Jacobian ``jm`` and the
    regularisation rows ``a_reg`` at the solution, the residual sum of squares (mm^2) and its
    number of rows."""

    __slots__ = ("x", "state", "states", "lags", "jm", "a_reg", "rss", "rows")

    def __init__(self, **kw):
        for k, v in kw.items():
            setattr(self, k, v)
