"""Standard errors and identifiability of inverted activity, from each frame's linearisation.

Around a frame's solution the marker residual is linear in the window's controls, r = J x + r0
(mm; J in mm per unit of control), and the regularisation adds rows R x + b. For independent
marker noise of standard deviation sigma (mm, per coordinate) the regularised least-squares
estimate has the covariance (the sandwich form)

    Cov(x) = sigma^2 H^-1 J^T J H^-1,    H = J^T J + R^T R,

whose first block is the frame's own controls. It treats the frame's starting state as known
and leaves out the bounds, so it is the spread of the estimate given the past, to first order.

Identifiability of control j is the length (mm per unit) of the part of its column of the
markers' step responses S (each control held from rest for 100 ms, :func:`step_responses`) that
the other controls cannot reproduce, d_j = 1 / sqrt((S^T S)^-1_jj): the marker change that a
sustained unit change of j alone makes, orthogonal to everything else (for two muscles that
pull the same way, such as zygomaticus major and levator anguli oris, it is small: the markers
see their sum, not each). A control is called identifiable when
max(sigma, NOISE_FLOOR_MM) / d_j <= IDENTIFIABLE_SE: at the data's noise, or at a good
motion-capture system's precision if the data are cleaner than that, the markers fix it to
within a tenth of full activity.
"""

from __future__ import annotations

import numpy as np

from .columns import map_columns

#: mm: the noise at which identifiability is judged at least (a good motion-capture system)
NOISE_FLOOR_MM = 0.1
#: activity units: the largest standard error of an identifiable control
IDENTIFIABLE_SE = 0.1


def _pinv_sym(h: np.ndarray) -> np.ndarray:
    """Pseudo-inverse of a symmetric positive semi-definite matrix (relative cut 1e-12)."""
    w, v = np.linalg.eigh(h)
    keep = w > max(w.max(initial=0.0), 0.0) * 1e-12
    inv = np.zeros_like(w)
    inv[keep] = 1.0 / w[keep]
    return (v * inv) @ v.T


def unit_standard_errors(jm: np.ndarray, a_reg: np.ndarray, n_own: int) -> np.ndarray:
    """Standard errors of the frame's own controls at unit marker noise (1 mm).

    Parameters
    ----------
    jm : (residuals, window x controls) marker Jacobian, mm per unit
    a_reg : (rows, window x controls) regularisation rows, mm per unit
    n_own : controls of the frame (the first block of columns)

    Returns
    -------
    (n_own,) standard errors in units of the controls per mm of noise (inf where the markers
    and the regularisation together do not fix a control)
    """
    jtj = jm.T @ jm
    h = jtj + a_reg.T @ a_reg
    hinv = _pinv_sym(h)
    cov = hinv @ jtj @ hinv
    se = np.sqrt(np.clip(np.diag(cov)[:n_own], 0.0, None))
    null = np.diag(h)[:n_own] <= 0
    se[null] = np.inf
    return se


def identifiability(j0: np.ndarray) -> np.ndarray:
    """Per control: mm per unit of its column of ``j0`` (residuals, controls) that the other
    columns cannot reproduce (0 for a control the markers do not see at all)."""
    if j0.size == 0:
        return np.zeros(j0.shape[1])
    _, sv, vt = np.linalg.svd(j0, full_matrices=True)  # vt: every direction of the controls
    s = np.zeros(j0.shape[1])
    s[: len(sv)] = sv  # fewer residuals than controls: the rest is a null space
    keep = s > s.max(initial=0.0) * 1e-9
    diag = np.sum((vt[keep] / s[keep, None]) ** 2, axis=0)  # diag of (J^T J)^+
    lost = np.sum(vt[~keep] ** 2, axis=0) > 1e-6  # a component in the null space
    out = np.where(diag > 0, 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0)), 0.0)
    out[lost] = 0.0
    return out


#: frames a control is held in the step responses that judge identifiability (100 ms)
STEP_FRAMES = 6
#: size of the held change (control units) of those step responses
STEP_SIZE = 0.2


def step_responses(advance, rest_state, nodes, n_controls, *, frames=STEP_FRAMES,
                   size=STEP_SIZE) -> np.ndarray:
    """Marker responses (3 markers, controls), mm per unit, to each control held from rest.

    ``advance(state, controls)`` steps the model one frame under a (controls,) vector; each
    control in turn is held at ``size`` for ``frames`` frames from ``rest_state`` and the
    markers' displacement at the end, divided by ``size``, is its column. The columns are
    shared between the cores (:func:`~facemech.inverse.columns.map_columns`).
    """
    def held(j):  # the markers after ``frames`` frames of control j (-1: none) held
        c = np.zeros(n_controls)
        if j >= 0:
            c[j] = size
        s = rest_state
        for _ in range(frames):
            s = advance(s, c)
        return s.positions[nodes] * 1e3

    ends = map_columns(lambda j: held(j - 1), n_controls + 1)
    base = ends[0]
    out = np.empty((base.size, n_controls))
    for j in range(n_controls):
        out[:, j] = (ends[j + 1] - base).reshape(-1) / size
    return out


def noise_from_residuals(rss: np.ndarray, dof: np.ndarray) -> float:
    """Marker noise (mm, per coordinate) estimated from the frames' fitted residuals.

    ``rss`` (frames,) mm^2 and ``dof`` (frames,) residual rows minus fitted controls; the pooled
    estimate sqrt(sum rss / sum dof). Model error counts as noise here: with real data it
    widens the standard errors, as it should.
    """
    rss = np.asarray(rss, float)
    dof = np.asarray(dof, float)
    ok = np.isfinite(rss) & (dof > 0)
    if not ok.any():
        return float("nan")
    return float(np.sqrt(rss[ok].sum() / dof[ok].sum()))


def identifiable(distance: np.ndarray, sigma_mm: float) -> np.ndarray:
    """True where ``max(sigma, NOISE_FLOOR_MM) / distance <= IDENTIFIABLE_SE``."""
    s = max(float(sigma_mm), NOISE_FLOOR_MM) if np.isfinite(sigma_mm) else NOISE_FLOOR_MM
    d = np.asarray(distance, float)
    return d * IDENTIFIABLE_SE >= s
