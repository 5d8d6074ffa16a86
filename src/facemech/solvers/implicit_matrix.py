"""The constant matrix of the implicit methods: ``A = M + g C + g^2 K`` over the moving nodes.

M the masses (with a drag proportional to them, exactly), C the damping, K a rest stiffness,
isotropic (the same for x, y and z) so that one sparse Cholesky factorisation of a nodes x nodes
matrix serves the three axes (:mod:`.cholesky`); the muscles join the solve through their beads
by the Sherman-Morrison-Woodbury identity (:mod:`.muscle_implicit`). For the seeds' constants K
is the rest tangent of springs, shape and restoration terms and C the damping graph Laplacian;
for the continuum tissue C is exact and K holds a share of each spring's stiff branch, the
volume term's Gram matrices and the tethers (docs/model.md, Integration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..geometry.prism import volume_gradients
from ..physics.assembly import Physics
from ..stepping import StepOptions
from .cholesky import factorise
from .krylov_region import KrylovRegion, krylov_region
from .muscle_implicit import MuscleJacobian
from .solver_state import implicit_forces


@dataclass(frozen=True, eq=False)
class ImplicitSystem:
    """The constant matrices of an implicit method over the moving nodes, shared by the axes.

    Attributes
    ----------
    stiffness : (d, d) sparse CSR, N/m -- the constant stiffness K
    damping : (d, d) sparse CSR, N s/m -- the damping C
    mass : (d,) kg
    lu : the factorisation of ``M + g C + g^2 K`` (:func:`.cholesky.factorise`: a ``solve``)
    factor_step : float, s -- g (h for linear implicit Euler, gamma h for ROS2)
    muscles : MuscleJacobian or None -- the muscles' bead-space Jacobian and the Woodbury solve
        (the continuum tissue); None: the muscles stay explicit
    predictor : bool -- linear implicit Euler evaluates the forces at the explicit predictor
        ``x + h v`` and solves ``A dv = h f(x + h v, v)`` (``Parameters.predictor``)
    """

    stiffness: sp.csr_matrix
    damping: sp.csr_matrix
    mass: np.ndarray
    lu: object
    factor_step: float
    muscles: MuscleJacobian | None
    predictor: bool = False
    krylov: int = 0
    drag: float = 0.0
    #: (d, nodes) sparse CSR, N/m -- the constant stiffness's coupling of the moving nodes to
    #: the kinematic ones (the jaw's and the skull's nodes; zero columns for the moving nodes)
    boundary: sp.csr_matrix | None = None
    #: (t,) N/m -- the tethers' stiffness, coupling each tied node to its anchor on the bone
    tether_k: np.ndarray | None = None
    #: (t,) int64 -- the tied nodes' rows among the moving nodes
    tether_rows: np.ndarray | None = None
    #: the region about the mouth to which the Krylov correction is confined
    #: (``Parameters.krylov_region``, :mod:`.krylov_region`); None: the whole face
    region: KrylovRegion | None = None

    def linearise(self, pos, vel, m_force, m_steady):
        """The muscles' Jacobian at a state (None: no muscle in the solve)."""
        if self.muscles is None:
            return None
        return self.muscles.linearise(pos, vel, m_force, m_steady)

    def solve(self, rhs: np.ndarray, jac, h: float) -> np.ndarray:
        """Solve the implicit system (with the muscles' Jacobian ``jac``) for rhs (d, 3)."""
        if self.muscles is None:
            return self.lu.solve(rhs)
        return self.muscles.solve(rhs, jac, h)

    def apply_stiffness(self, v: np.ndarray, jac) -> np.ndarray:
        """The system's stiffness times v (d, 3): constant part and muscles."""
        out = self.stiffness @ v
        if self.muscles is not None:
            out += self.muscles.apply_stiffness(v, jac)
        return out

    def apply_boundary(self, vel: np.ndarray, anchor_vel: np.ndarray) -> np.ndarray:
        """The constant stiffness's coupling to the kinematic nodes moving at ``vel`` (nodes,
        3) and to the tethers' anchors moving at ``anchor_vel`` (t, 3): (d, 3), N/m times m/s.
        Zero when neither moves."""
        out = self.boundary @ vel
        np.subtract.at(out, self.tether_rows, self.tether_k[:, None] * anchor_vel)
        return out


def implicit_system(physics: Physics, h: float, options: StepOptions) -> ImplicitSystem:
    """The constant matrices of a model, factorised for the step ``h`` s, as ``options``
    says (the matrix's shares of the stiffness, the drag, the predictor and its Krylov
    correction).

    Seeds' constants: K is the isotropic (per-axis) rest tangent stiffness: springs (mean of
    the elongation slope k and the compression slope pi sigma k / 2 of eqs. 1-2), the shape
    term of eq. (9) and the restoration of eq. (11); C is r times the spring graph Laplacian
    (eq. 8). The isotropic K over-estimates the transverse stiffness of unloaded springs,
    which only adds numerical damping; the exact forces are evaluated every step.

    Continuum: C is the exact Laplacian of the springs' dashpots; K a share of the springs'
    stiff branch, the volume term's Gram matrices and the tethers (see the module doc); the
    muscles join the solve through their beads.
    """
    p, o = physics.params, options
    forces = physics.forces
    springs, prisms, restoration = forces.springs, forces.prisms, forces.restoration
    nd = physics.n_dynamic
    row = np.full(physics.model.n_nodes, -1, np.int64)
    row[physics.dynamic] = np.arange(nd)
    si, sj = row[springs.i], row[springs.j]
    pn = row[prisms.nodes]
    a_idx = np.repeat(np.arange(6), 6)
    b_idx = np.tile(np.arange(6), 6)
    ra, rb = pn[:, a_idx].reshape(-1), pn[:, b_idx].reshape(-1)
    ok = (ra >= 0) & (rb >= 0)
    if p.is_continuum:
        # damping exactly as the forces have it (the springs' dashpots): a matrix that
        # over-damps acts as inertia and makes the step ring; stiffness: a share of each
        # spring's stiff branch, the volume term's Gram matrices (within a factor 3 of its
        # rank-one Hessian) and the tethers
        damp = _graph_matrix(si, sj, springs.damping, nd)
        k_springs = _graph_matrix(si, sj, o.implicit_stiffness_share * springs.k_high, nd)
        grads = volume_gradients(physics.model.rest_positions[prisms.nodes])  # (p, 6, 3)
        gram = (np.einsum("pac,pbc->pab", grads, grads) * prisms.bulk[:, None, None]
                * o.implicit_volume_scale)
        tether = np.zeros(nd)
        np.add.at(tether, row[restoration.nodes], restoration.k_restore)
        stiff = (k_springs + sp.csc_matrix((gram.reshape(-1)[ok], (ra[ok], rb[ok])),
                                           shape=(nd, nd)) + sp.diags(tether)).tocsc()
        mass = 1.0 / physics.inv_mass[physics.dynamic]
        boundary = _boundary_matrix(si, sj, springs, o.implicit_stiffness_share, ra, rb,
                                    prisms.nodes[:, b_idx].reshape(-1), gram, nd,
                                    physics.model.n_nodes)
        tether_rows = row[restoration.nodes]
        tether_k = np.asarray(restoration.k_restore, float)
    else:
        k_tan = springs.k_low * 0.5 * (1.0 + 0.5 * np.pi * p.sigma)
        stiff = _graph_matrix(si, sj, k_tan, nd)
        # shape term of eq. (9): d(-k_e2 (x_a - centroid))/dx_b = -k_e2 (delta_ab - 1/6)
        coef = p.k_shape * ((a_idx == b_idx).astype(float) - 1.0 / 6.0)
        cv = np.broadcast_to(coef, (len(pn), 36)).reshape(-1)
        stiff = stiff + sp.csc_matrix((cv[ok], (ra[ok], rb[ok])), shape=(nd, nd))
        restore = np.zeros(nd)
        restore[row[restoration.nodes]] = restoration.k_restore
        stiff = stiff + sp.diags(restore)
        damp = _graph_matrix(si, sj, springs.damping, nd)
        mass = np.full(nd, p.node_mass)
        boundary, tether_rows, tether_k = None, None, None
    stiff = stiff.tocsc()
    # a drag proportional to the mass (Parameters.mass_drag) is diagonal: exactly in the matrix
    a_mat = (sp.diags(mass * (1.0 + h * o.mass_drag)) + h * damp + h * h * stiff).tocsc()
    # the matrix is symmetric positive definite: its Cholesky factor
    lu = factorise(a_mat)
    muscles = MuscleJacobian(physics, lu) if p.is_continuum else None
    region = None
    if o.krylov_region > 0.0 and o.krylov_iterations:
        region = krylov_region(physics, implicit_forces(physics, o)[0], a_mat,
                               None if muscles is None else muscles.W, o.krylov_region)
    return ImplicitSystem(stiffness=stiff.tocsr(), damping=damp.tocsr(), mass=mass, lu=lu,
                          factor_step=h, muscles=muscles,
                          predictor=bool(o.predictor), krylov=int(o.krylov_iterations),
                          drag=float(o.mass_drag), boundary=boundary, tether_k=tether_k,
                          tether_rows=tether_rows, region=region)


def _boundary_matrix(si, sj, springs, share, ra, rb, cb, gram, nd, n_nodes):
    """(d, nodes) CSR: the constant stiffness's entries between a moving node's row and a
    kinematic node's column (springs with one kinematic end, the volume Gram blocks of prisms
    with kinematic corners), which :func:`_graph_matrix` and the Gram assembly leave out of the
    matrix. ``ra``, ``rb``: the Gram entries' moving rows (-1: kinematic), ``cb``: their
    column nodes."""
    k = share * springs.k_high
    i_kin, j_kin = si < 0, sj < 0
    a = (~i_kin) & j_kin
    b = i_kin & (~j_kin)
    rows = [si[a], sj[b]]
    cols = [np.asarray(springs.j)[a], np.asarray(springs.i)[b]]
    vals = [-k[a], -k[b]]
    sel = (ra >= 0) & (rb < 0)
    rows.append(ra[sel])
    cols.append(cb[sel])
    vals.append(gram.reshape(-1)[sel])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(nd, n_nodes))



def _graph_matrix(i: np.ndarray, j: np.ndarray, w: np.ndarray, nd: int) -> sp.csc_matrix:
    """Weighted graph Laplacian of edges (i, j) over rows 0..nd-1 (-1: a kinematic node).

    An edge to a kinematic node keeps its diagonal term only.
    """
    i = np.asarray(i)
    j = np.asarray(j)
    ii = i >= 0
    jj = j >= 0
    both = ii & jj
    rows = np.concatenate([i[ii], j[jj], i[both], j[both]])
    cols = np.concatenate([i[ii], j[jj], j[both], i[both]])
    vals = np.concatenate([w[ii], w[jj], -w[both], -w[both]])
    return sp.csc_matrix((vals, (rows, cols)), shape=(nd, nd))




__all__ = ["ImplicitSystem", "implicit_system"]
