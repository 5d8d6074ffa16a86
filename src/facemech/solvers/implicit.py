"""Two fast implicit integrators on one constant, factorised matrix.

:class:`LinearImplicitEuler`
    linearly implicit (Baraff-Witkin) Euler with a constant matrix ``A = M + h C + h^2 K``
    (masses M, damping C, a rest stiffness K), factorised once (a sparse Cholesky factor,
    :mod:`.cholesky`) and reused:
    ``A dv = h (f(x, v) - h K v)``. The nonlinear forces are evaluated exactly each step, so
    only the stability, not the consistency, rests on K. The matrix is over the moving nodes;
    ``K v`` takes in its coupling to the kinematic nodes (the jaw's bone) and to the tethers'
    anchors moving with it (:meth:`ImplicitSystem.apply_boundary`), so that tissue carried by
    the jaw meets no drag from a bone taken as still (docs/model.md, "The bone's motion in
    the step").
:class:`Rosenbrock2`
    the two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999), second order for any
    approximation of the Jacobian, so one constant factorised matrix (gamma h in place of h)
    serves every step: two force evaluations and two solves per step.

With ``Parameters.predictor`` linear implicit Euler instead evaluates the forces at the
explicit predictor, ``A dv = h f(x + h v, v)`` (the step linearised about the predictor; the
same as backward Euler when K is the true stiffness): the matrix then acts only on the change of
velocity, so it resists no steady rigid turn (the corrected form's drag), but its excess over
the true stiffness becomes added inertia, and the step is stable only when the matrix holds at
least 3/4 of each stiffness (:data:`facemech.params.PREDICTOR_LEAST_SHARES`; docs/model.md).

Both integrate the muscle filter of eq. (4) exactly. K and C are isotropic (the same for x, y
and z) so one factorisation of a nodes x nodes matrix serves the three axes.

For the seeds' constants K is the rest tangent of springs, shape and restoration terms and C
the damping graph Laplacian. For the continuum tissue (the anatomical preset) C is exact (each
spring's dashpot acts on the whole relative velocity of its ends), and K holds a share
(:data:`IMPLICIT_STIFFNESS_SHARE`) of each spring's stiff branch, the volume term (the Gram
matrix of each prism's volume gradient, within a factor 3 of its true rank-one Hessian) and the
tethers: with the exact damping in the matrix, the stiffness left explicit is stable for steps
below 2 b / ((1 - share) k_high) (docs/model.md). Physiological muscle forces make the velocity
term of the Hill law (eq. 6) and the geometric stiffness of a tension stiff on the insertion
nodes; both are taken into the implicit solve exactly, through the muscles' beads, by the
Sherman-Morrison-Woodbury identity on the constant factorisation
(:class:`~facemech.solvers.muscle_implicit.MuscleJacobian`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..geometry.prism import volume_gradients
from ..params import Parameters
from ..physics.assembly import Physics, accumulate_forces, rest_anchors
from .cholesky import factorise
from .contacts import resolve_contacts
from .krylov_region import KrylovRegion, displace, krylov_region, restore, tangent_product
from .mandible import moved_anchors
from .muscle_implicit import MuscleJacobian
from .solver_state import (
    SolverState,
    filter_exact,
    finish_frame,
    implicit_forces,
    place_jaw_into,
    solver_state,
    start_frame,
)
from .state import Controls, State
from .volume_floor import resolve_volume_floor

ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
#: the most the Krylov correction may grow the constant matrix's step (its largest velocity
#: change); beyond it the correction is not taken (see :func:`_krylov_step`)
KRYLOV_GROWTH = 10.0
#: share of the springs' stiffness (of their stiff branch) that the constant matrix of the
#: continuum carries by default (``Parameters.implicit_stiffness_share``): with the exact
#: damping in the matrix, the rest left explicit is stable at 4 steps per frame and the lips do
#: not ring (docs/model.md, Integration)
IMPLICIT_STIFFNESS_SHARE = Parameters.implicit_stiffness_share


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


def implicit_system(physics: Physics, h: float) -> ImplicitSystem:
    """The constant matrices of a model, factorised for the step ``h`` s.

    Seeds' constants: K is the isotropic (per-axis) rest tangent stiffness: springs (mean of
    the elongation slope k and the compression slope pi sigma k / 2 of eqs. 1-2), the shape
    term of eq. (9) and the restoration of eq. (11); C is r times the spring graph Laplacian
    (eq. 8). The isotropic K over-estimates the transverse stiffness of unloaded springs,
    which only adds numerical damping; the exact forces are evaluated every step.

    Continuum: C is the exact Laplacian of the springs' dashpots; K a share of the springs'
    stiff branch, the volume term's Gram matrices and the tethers (see the module doc); the
    muscles join the solve through their beads.
    """
    p = physics.params
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
        k_springs = _graph_matrix(si, sj, p.implicit_stiffness_share * springs.k_high, nd)
        grads = volume_gradients(physics.model.rest_positions[prisms.nodes])  # (p, 6, 3)
        gram = (np.einsum("pac,pbc->pab", grads, grads) * prisms.bulk[:, None, None]
                * p.implicit_volume_scale)
        tether = np.zeros(nd)
        np.add.at(tether, row[restoration.nodes], restoration.k_restore)
        stiff = (k_springs + sp.csc_matrix((gram.reshape(-1)[ok], (ra[ok], rb[ok])),
                                           shape=(nd, nd)) + sp.diags(tether)).tocsc()
        mass = 1.0 / physics.inv_mass[physics.dynamic]
        boundary = _boundary_matrix(si, sj, springs, p.implicit_stiffness_share, ra, rb,
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
    a_mat = (sp.diags(mass * (1.0 + h * p.mass_drag)) + h * damp + h * h * stiff).tocsc()
    # the matrix is symmetric positive definite: its Cholesky factor
    lu = factorise(a_mat)
    muscles = MuscleJacobian(physics, lu) if p.is_continuum else None
    region = None
    if p.krylov_region > 0.0 and p.krylov_iterations:
        region = krylov_region(physics, implicit_forces(physics)[0], a_mat,
                               None if muscles is None else muscles.W, p.krylov_region)
    return ImplicitSystem(stiffness=stiff.tocsr(), damping=damp.tocsr(), mass=mass, lu=lu,
                          factor_step=h, muscles=muscles,
                          predictor=bool(p.predictor), krylov=int(p.krylov_iterations),
                          drag=float(p.mass_drag), boundary=boundary, tether_k=tether_k,
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


def _anchor_velocity(jaw, pose, rate, anchors, h):
    """(t, 3) m/s: the tethers' anchors' velocity over the step (their places at the step's
    end less at its start, over h)."""
    nxt, _ = moved_anchors(pose + rate * h, jaw.hinge_point, jaw.hinge_axis,
                           jaw.anchor_weights, jaw.anchor_rest, jaw.anchor_normal)
    return (nxt - anchors.rest) / h


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


def _check_substeps(substeps) -> int:
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise InputError(f"substeps must be a whole number of steps per frame, at least 1 "
                         f"(got {substeps!r})", field="substeps")
    return int(substeps)


def _init(physics: Physics, substeps: int, gamma: float) -> SolverState:
    frame = 1.0 / physics.params.frame_rate
    system = implicit_system(physics, gamma * (frame / substeps))
    prepared = solver_state(physics, substeps, system)
    _warm_up(prepared, physics)
    return prepared


def _warm_up(solver_state: SolverState, physics: Physics) -> None:
    """Compile (or load) the kernels now, so that timings of the first frame are not the
    compiler's."""
    pos = physics.model.rest_positions.copy()
    vel = np.zeros_like(pos)
    m = np.zeros(len(solver_state.muscle_group))
    place_jaw_into(solver_state.jaw, np.zeros(3), np.zeros(3), pos, vel)
    anchors = rest_anchors(physics)
    accumulate_forces(solver_state.forces, pos, vel, m, anchors, np.zeros_like(pos))
    _contacts(solver_state, pos, vel, anchors)
    filter_exact(m, m, m, solver_state.tau, solver_state.step, solver_state.zeta)
    solver_state.system.linearise(pos, vel, m + 1.0, m)


def _frame_force_bound(solver_state: SolverState, m_force, m_rate, m_steady):
    """The larger of each muscle's filtered force now and at the frame's end (eq. 4)."""
    end, _ = filter_exact(m_force, m_rate, m_steady, solver_state.tau,
                          solver_state.frame_duration, solver_state.zeta)
    return np.maximum(m_force, end)


@dataclass(frozen=True)
class LinearImplicitEuler:
    """Linearly implicit Euler with the constant factorised matrix (see the module doc).

    Parameters
    ----------
    substeps : int
        Steps per frame (4 at 60 Hz: h = 4.2 ms).
    """

    substeps: int
    name: ClassVar[str] = "implicit"

    def __post_init__(self):
        object.__setattr__(self, "substeps", _check_substeps(self.substeps))

    def init(self, physics: Physics) -> SolverState:
        """The solver state of a model: its matrix factorised for h = frame / substeps."""
        return _init(physics, self.substeps, 1.0)

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State:
        """``state`` advanced by one frame under ``controls`` (a new :class:`State`)."""
        system = solver_state.system
        f = start_frame(solver_state, state, controls)
        pos, vel = f.positions, f.velocities
        m_force, m_rate, m_steady = f.muscle_force, f.muscle_force_rate, f.muscle_steady
        dyn = solver_state.dynamic
        h = solver_state.step
        out = np.zeros_like(pos)
        jac = system.linearise(pos, vel,
                               _frame_force_bound(solver_state, m_force, m_rate, m_steady),
                               m_steady)
        region = system.region.linearise(jac, h) if system.region is not None else None
        for step in range(solver_state.n_steps):
            anchors = place_jaw_into(solver_state.jaw, f.jaw_start + f.jaw_rate * (step * h),
                                     f.jaw_rate, pos, vel)
            v0 = vel[dyn]
            # with the predictor the forces at x + h v: the matrix then only corrects the change
            # of velocity, and resists no steady rigid turn
            at = pos + h * vel if system.predictor else pos
            accumulate_forces(solver_state.forces, at, vel, m_force, anchors, out)
            if system.drag:
                out[dyn] -= system.drag * system.mass[:, None] * v0
            if not system.predictor:
                kv = system.apply_stiffness(v0, jac)
                if system.boundary is not None and np.any(f.jaw_rate):  # the bone moves
                    kv += system.apply_boundary(vel, _anchor_velocity(
                        solver_state.jaw, f.jaw_start + f.jaw_rate * (step * h), f.jaw_rate,
                        anchors, h))
                rhs = h * (out[dyn] - h * kv)
                dv = system.solve(rhs, jac, h)
            elif system.region is not None:
                dv = _region_krylov_step(solver_state, system, region, at, vel, m_force,
                                         anchors, out, h * out[dyn], jac, h)
            elif system.krylov:
                dv = _krylov_step(solver_state, system, at, vel, m_force, anchors, out,
                                  h * out[dyn], jac, h)
            else:
                dv = system.solve(h * out[dyn], jac, h)
            vel[dyn] = v0 + dv
            pos[dyn] += h * vel[dyn]
            _contacts(solver_state, pos, vel, anchors)
            m_force, m_rate = filter_exact(m_force, m_rate, m_steady, solver_state.tau, h,
                                           solver_state.zeta)
        return finish_frame(solver_state, state, controls, pos, vel, m_force, m_rate, f.jaw_rate)


@dataclass(frozen=True)
class Rosenbrock2:
    """The two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999) with the constant
    factorised matrix (see the module doc).

    Parameters
    ----------
    substeps : int
        Steps per frame (each two force evaluations and two solves).
    """

    substeps: int
    name: ClassVar[str] = "rosenbrock"

    def __post_init__(self):
        object.__setattr__(self, "substeps", _check_substeps(self.substeps))

    def init(self, physics: Physics) -> SolverState:
        """The solver state of a model: its matrix factorised for gamma h."""
        if physics.params.predictor:
            raise InputError("predictor=True is a form of the linearly implicit Euler step "
                             "(integrator 'implicit'), not of 'rosenbrock'", field="predictor")
        return _init(physics, self.substeps, ROS2_GAMMA)

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State:
        """``state`` advanced by one frame under ``controls`` (a new :class:`State`)."""
        system = solver_state.system
        f = start_frame(solver_state, state, controls)
        pos, vel = f.positions, f.velocities
        m_force, m_rate, m_steady = f.muscle_force, f.muscle_force_rate, f.muscle_steady
        dyn = solver_state.dynamic
        h = solver_state.step
        inv_m = solver_state.inv_mass[dyn][:, None]
        out = np.zeros_like(pos)
        jac = system.linearise(pos, vel,
                               _frame_force_bound(solver_state, m_force, m_rate, m_steady),
                               m_steady)
        for step in range(solver_state.n_steps):
            x0, v0 = pos[dyn].copy(), vel[dyn].copy()
            anchors = place_jaw_into(solver_state.jaw, f.jaw_start + f.jaw_rate * (step * h),
                                     f.jaw_rate, pos, vel)
            accumulate_forces(solver_state.forces, pos, vel, m_force, anchors, out)
            k1x, k1v = _ros2_stage(solver_state, v0, out[dyn] * inv_m, jac)
            pos[dyn] = x0 + h * k1x
            vel[dyn] = v0 + h * k1v
            m_force, m_rate = filter_exact(m_force, m_rate, m_steady, solver_state.tau, h,
                                           solver_state.zeta)
            anchors = place_jaw_into(solver_state.jaw, f.jaw_start + f.jaw_rate * ((step + 1) * h),
                                     f.jaw_rate, pos, vel)
            accumulate_forces(solver_state.forces, pos, vel, m_force, anchors, out)
            k2x, k2v = _ros2_stage(solver_state, vel[dyn] - 2.0 * k1x,
                                   out[dyn] * inv_m - 2.0 * k1v, jac)
            pos[dyn] = x0 + h * (1.5 * k1x + 0.5 * k2x)
            vel[dyn] = v0 + h * (1.5 * k1v + 0.5 * k2v)
            _contacts(solver_state, pos, vel, anchors)
        return finish_frame(solver_state, state, controls, pos, vel, m_force, m_rate, f.jaw_rate)


def _krylov_step(solver_state, system, x_p, vel, m_force, anchors, f_p, rhs, jac, h):
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


def _region_krylov_step(solver_state, system, region_system, x_p, vel, m_force, anchors, f_p,
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


def _contacts(solver_state: SolverState, pos: np.ndarray, vel: np.ndarray, anchors) -> None:
    """The stiff contacts' own implicit step after a step's solve (:mod:`.contacts`), then
    the prisms' volume floor's (:mod:`.volume_floor`)."""
    c = solver_state.contacts
    if len(c.bone_k) or len(c.lip_k):
        resolve_contacts(pos, vel, solver_state.inv_mass, c.tied, c.bone_k, anchors.rest,
                         anchors.normal, c.pairs, c.normals, c.lip_k, solver_state.step)
    floor = solver_state.volume_floor
    if len(floor.floor):
        resolve_volume_floor(pos, vel, solver_state.inv_mass, floor.nodes, floor.floor,
                             floor.kappa, solver_state.step)


def _ros2_stage(solver_state: SolverState, r_x, r_v, jac):
    """Solve (I - gamma h J) k = r for the state (x, v) with the constant matrices.

    With J = [[0, I], [-K/m, -C/m]]: (m + g C + g^2 K) k_v = m r_v - g K r_x and
    k_x = r_x + g k_v, g = gamma h (the factorised matrix).
    """
    system = solver_state.system
    g = ROS2_GAMMA * solver_state.step
    m = system.mass[:, None]
    k_v = system.solve(m * r_v - g * system.apply_stiffness(r_x, jac), jac, g)
    return r_x + g * k_v, k_v


__all__ = ["LinearImplicitEuler", "Rosenbrock2", "ImplicitSystem", "implicit_system",
           "ROS2_GAMMA", "IMPLICIT_STIFFNESS_SHARE"]
