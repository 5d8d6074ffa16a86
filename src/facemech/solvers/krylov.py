"""The Krylov correction of the predictor's step: GMRES on the step's true linearisation.

The linearly implicit step about the explicit predictor, ``A_t dv = h f(x + h v, v)``, with the
forces' Jacobian applied by a finite difference of the forces and the constant matrix
(:mod:`.implicit_matrix`) as the right preconditioner; over the whole face
(:func:`krylov_step`) or over the region about the mouth only (:func:`region_krylov_step`,
:mod:`.krylov_region`). A correction that runs away (tissue giving way) is not taken.
"""

from __future__ import annotations

import numpy as np

from ..physics.assembly import accumulate_forces
from .krylov_region import displace, restore, tangent_product

#: the most the Krylov correction may grow the constant matrix's step (its largest velocity
#: change); beyond it the correction is not taken (see :func:`krylov_step`)
KRYLOV_GROWTH = 10.0


def krylov_step(solver_state, system, x_p, vel, m_force, anchors, f_p, rhs, jac, h):
    """The predictor's step ``A_t dv = h f(x + h v, v)`` with the forces' true linearisation
    ``A_t u = M u - h (df/dx h u + df/dv u)`` (a finite difference of the forces about the
    predictor), solved by right-preconditioned GMRES started from the constant matrix's solve,
    ``system.krylov`` iterations, the constant matrix (with the muscles' Woodbury terms) the
    preconditioner: its excess stiffness no longer acts as inertia."""
    dyn = solver_state.dynamic
    mass = system.mass[:, None]
    base = f_p[dyn] + system.drag * mass * vel[dyn]  # the forces alone (the drag is exact)
    xp = x_p.copy()
    vp = vel.copy()
    work = np.zeros_like(f_p)

    def apply(u):
        scale = float(np.abs(u).max())
        if scale == 0.0:
            return np.zeros_like(u)
        eps = 1e-7 / (h * scale)  # moves a node by 1e-7 m at most
        xp[dyn] = x_p[dyn] + eps * h * u
        vp[dyn] = vel[dyn] + eps * u
        accumulate_forces(solver_state.forces, xp, vp, m_force, anchors, work)
        return (1.0 + h * system.drag) * mass * u - h * (work[dyn] - base) / eps

    def precond(r):
        return system.solve(r, jac, h)

    x0 = precond(rhs)
    correction = _gmres(rhs - apply(x0), apply, precond, system.krylov)
    if correction is None:
        return x0
    return _growth_guard(x0, x0 + correction)


def region_krylov_step(solver_state, system, region_system, x_p, vel, m_force, anchors, f_p,
                        rhs, jac, h):
    """The predictor's step solved by the constant matrix over the whole face, then
    corrected by GMRES on the true linearisation over the region about the mouth only
    (:mod:`.krylov_region`): ``system.krylov`` iterations, each one solve of the region's
    constant block (with the muscles' Woodbury terms, ``region_system``) and one evaluation of
    the forces that touch the region."""
    region = system.region
    dyn = solver_state.dynamic
    rows, nodes = region.rows, region.nodes
    mass = system.mass[rows]
    inertia = (1.0 + h * system.drag) * mass
    forces = region.forces
    anc = region.anchors(anchors)
    x0 = system.solve(rhs, jac, h)
    # every force on a node of the region comes from what touches it: the whole face's forces
    # there are the region's own
    base = f_p[nodes] + system.drag * mass[:, None] * vel[nodes]
    xp = x_p.copy()
    vp = vel.copy()
    work = np.zeros_like(f_p)

    def product(u, moved, values):
        """The step's matrix on ``u`` (r, 3), the nodes ``moved`` moved by ``values``."""
        scale = float(np.abs(values).max())
        if scale == 0.0:
            return inertia[:, None] * u
        eps = 1e-7 / (h * scale)  # moves a node by 1e-7 m at most
        displace(xp, vp, x_p, vel, moved, values, eps * h, eps)
        accumulate_forces(forces, xp, vp, m_force, anc, work)
        restore(xp, vp, x_p, vel, moved)
        return tangent_product(inertia, u, work, nodes, base, h / eps)

    # the residual of the whole face's step on the region: every node moved by x0, since the
    # nodes beside the region pull on it too
    residual = rhs[rows] - product(x0[rows], dyn, x0)
    correction = _gmres(residual, lambda u: product(u, nodes, u),
                        lambda r: region.solve(r, region_system), system.krylov)
    if correction is None:
        return x0
    dv = x0.copy()
    dv[rows] += correction
    return _growth_guard(x0, dv)


def _gmres(r0, apply, precond, iterations):
    """The right-preconditioned GMRES correction (``iterations`` at most) of a step whose
    residual is ``r0``; None when the residual is zero."""
    beta = float(np.sqrt((r0 * r0).sum()))
    if beta == 0.0:
        return None
    m = iterations
    basis = [r0 / beta]
    z = []
    hess = np.zeros((m + 1, m))
    for j in range(m):
        z.append(precond(basis[j]))
        w = apply(z[j])
        for i in range(j + 1):
            hess[i, j] = float((w * basis[i]).sum())
            w = w - hess[i, j] * basis[i]
        hess[j + 1, j] = float(np.sqrt((w * w).sum()))
        if hess[j + 1, j] < 1e-14 * beta:
            m = j + 1
            break
        basis.append(w / hess[j + 1, j])
    e1 = np.zeros(m + 1)
    e1[0] = beta
    y, *_ = np.linalg.lstsq(hess[: m + 1, :m], e1, rcond=None)
    return sum(y[k] * z[k] for k in range(m))


def _growth_guard(x0, dv):
    """``dv``, or the constant matrix's step ``x0`` where the correction ran away: where the
    true linearisation is not positive (tissue giving way: a prism turning inside out) its
    solve can grow without bound; the constant matrix's step is stable."""
    if not np.all(np.isfinite(dv)) or np.abs(dv).max() > KRYLOV_GROWTH * np.abs(x0).max():
        return x0
    return dv



__all__ = ["KRYLOV_GROWTH", "krylov_step", "region_krylov_step"]
