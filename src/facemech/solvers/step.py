"""Time stepping: the paper's explicit Euler and two fast implicit integrators.

Each advances an immutable :class:`~facemech.solvers.state.State` through one control frame
(1/60 s) with the muscle activity held constant, as in Lucero & Munhall (1999):

``euler`` (the paper's integrator)
    explicit Euler with dt = 0.33 ms, 50 steps per frame. The velocity is updated first and the
    position from the new velocity (the Euler-Cromer ordering of explicit mass-spring codes;
    the other ordering is unstable on undamped modes). The muscle filter of eq. (4) is stepped
    with the same explicit Euler.
``implicit``
    linearly implicit (Baraff-Witkin) Euler with a constant matrix ``A = M + h C + h^2 K``
    (masses M, damping C, a rest stiffness K), factorised once with SuperLU and reused:
    ``A dv = h (f(x, v) - h K v)``. The nonlinear forces are evaluated exactly each step, so
    only the stability, not the consistency, rests on K.
``rosenbrock``
    the two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999), second order for any
    approximation of the Jacobian, so one constant factorised matrix (gamma h in place of h)
    serves every step: two force evaluations and two solves per step.

The implicit methods integrate the muscle filter exactly. K and C are isotropic (the same for
x, y and z) so one factorisation of a nodes x nodes matrix serves the three axes.

For the seeds' constants K is the rest tangent of springs, shape and restoration terms and C
the damping graph Laplacian. For the continuum tissue (the anatomical preset) C is exact (each
spring's dashpot acts on the whole relative velocity of its ends), and K holds a share
(``IMPLICIT_STIFFNESS_SHARE``) of each spring's stiff branch, the volume term (the Gram matrix
of each prism's volume gradient, within a factor 3 of its true rank-one Hessian) and the
tethers: with the exact damping in the matrix, the stiffness left explicit is stable for steps
below 2 b / ((1 - share) k_high) (docs/model.md). Physiological muscle forces make the velocity
term of the Hill law (eq. 6) and the geometric stiffness of a tension stiff on the insertion
nodes; both are taken into the implicit solve exactly, through the muscles' beads, by the
Sherman-Morrison-Woodbury identity on the constant factorisation
(:class:`~facemech.solvers.muscle_implicit.MuscleJacobian`).

The jaw (``jaw_drive``): ``"ramp"`` (default) moves the mandible's pose (angle, condyle shift)
linearly from the state's pose to the frame's over the frame; ``"hold"`` sets the frame's pose at
the start of the frame and holds it, as the paper does. Each jaw node turns by its jaw weight
times the angle and moves by its weight times the shift (1 on the mandible; the anatomical
tissue blends from 1 to 0 lateral to the mouth; :mod:`.mandible`).
The skull nodes that slide (lips, vestibule, chin pad) rest on the teeth and bone through a
one-sided penalty against the bone's tangent plane under each (turned with the jaw), part of the
force evaluation: contacts stay out of the constant matrix, whose isotropic entries would act as
a viscosity on sliding and lifting off.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..errors import InputError, SimulationBlowUp
from ..physics.assembly import Physics, accumulate_forces, force_arguments
from ..physics.muscle import activation_euler, activation_exact
from ..physics.volume import volume_gradients
from .jaw import jaw_poses
from .mandible import place_jaw
from .muscle_implicit import MuscleJacobian
from .state import State

INTEGRATORS = ("euler", "implicit", "rosenbrock")
JAW_DRIVES = ("ramp", "hold")
ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
#: share of the springs' stiffness (of their stiff branch) that the constant matrix of the
#: continuum carries: with the exact damping in the matrix, the rest left explicit is stable at
#: 4 steps per frame and the lips do not ring (docs/model.md, Integration)
IMPLICIT_STIFFNESS_SHARE = 0.3


@nb.njit(cache=True)
def _euler_frame(pos, vel, m_force, m_rate, m_steady, n_steps, dt, inv_mass, dynamic, tau,
                 out, fargs, jaw_start, jaw_rate, jargs):
    """One frame of explicit Euler steps; the jaw's pose (3,) goes from ``jaw_start`` at its
    ``jaw_rate`` (3,) (rad/s, m/s, m/s)."""
    moving = jaw_rate[0] != 0.0 or jaw_rate[1] != 0.0 or jaw_rate[2] != 0.0
    for step in range(n_steps):
        if moving:
            t = step * dt
            place_jaw(pos, vel, jaw_start[0] + jaw_rate[0] * t, jaw_start[1] + jaw_rate[1] * t,
                      jaw_start[2] + jaw_rate[2] * t, jaw_rate[0], jaw_rate[1], jaw_rate[2],
                      *jargs)
        accumulate_forces(pos, vel, out, *fargs)
        for q in range(dynamic.shape[0]):
            i = dynamic[q]
            for a in range(3):
                vel[i, a] += dt * inv_mass[i] * out[i, a]
                pos[i, a] += dt * vel[i, a]
        for m in range(m_force.shape[0]):
            m_force[m], m_rate[m] = activation_euler(m_force[m], m_rate[m], m_steady[m], tau, dt)


@nb.njit(cache=True)
def _filter_exact(m_force, m_rate, m_steady, tau, dt):
    for m in range(m_force.shape[0]):
        m_force[m], m_rate[m] = activation_exact(m_force[m], m_rate[m], m_steady[m], tau, dt)


class Stepper:
    """Advances states of one face model with one integrator.

    Parameters
    ----------
    physics : Physics
    integrator : {"euler", "implicit", "rosenbrock"}, optional
        Default: the preset's (``params.integrator``): ``euler`` for the seeds' presets,
        ``implicit`` for the anatomical one, whose physiological forces and tissue viscosity
        make explicit steps unstable.
    substeps : int, optional
        Steps per frame of the implicit integrators (default: the preset's, 4: h = 4.2 ms).
    dt : float, optional
        Step of the explicit integrator (default: the preset's 0.33 ms). With an implicit
        integrator it may only repeat the step that ``substeps`` gives (an error otherwise).
    jaw_drive : {"ramp", "hold"}
    """

    def __init__(self, physics: Physics, *, integrator: str | None = None,
                 substeps: int | None = None, dt: float | None = None,
                 jaw_drive: str = "ramp"):
        p = physics.params
        integrator = p.integrator if integrator is None else integrator
        substeps = p.substeps if substeps is None else substeps
        if integrator not in INTEGRATORS:
            raise InputError(f"unknown integrator {integrator!r} (expected one of "
                             f"{', '.join(INTEGRATORS)})", field="integrator")
        if jaw_drive not in JAW_DRIVES:
            raise InputError(f"unknown jaw drive {jaw_drive!r} (expected ramp or hold)",
                             field="jaw_drive")
        if integrator == "euler" and p.is_continuum:
            raise InputError(f"the {p.name} preset needs an implicit integrator (implicit or "
                             "rosenbrock): its muscle forces and tissue viscosity make explicit "
                             "Euler steps unstable", field="integrator")
        self.physics = physics
        self.integrator = integrator
        self.jaw_drive = jaw_drive
        self.frame_duration = 1.0 / p.frame_rate
        if integrator == "euler":
            step = p.dt if dt is None else float(dt)
            if not step > 0:
                raise InputError("dt must be positive", field="dt")
            self.n_steps = max(1, int(self.frame_duration / step + 1e-9))  # 50 at 0.33 ms
        else:
            if substeps < 1:
                raise InputError("substeps must be at least 1", field="substeps")
            self.n_steps = int(substeps)
            h = self.frame_duration / self.n_steps
            if dt is not None and abs(float(dt) - h) > 1e-9 * h:
                raise InputError(f"dt ({float(dt) * 1e3:.3g} ms) is the explicit Euler step; the "
                                 f"{integrator} integrator takes {self.n_steps} steps per frame "
                                 f"({h * 1e3:.3g} ms): set substeps instead", field="dt")
        self.dt = self.frame_duration / self.n_steps
        if integrator != "euler":
            gamma = ROS2_GAMMA if integrator == "rosenbrock" else 1.0
            self._K, self._lu = self._factorise(gamma * self.dt)
        model = physics.model
        self._out = np.zeros_like(model.rest_positions)
        rest = model.rest_positions
        tied_rest0 = rest[physics.tied]
        tied_normal0 = model.skull_normals[physics.tied_skull]
        self._tied_rest = tied_rest0.copy()
        self._tied_normal = tied_normal0.copy()
        self._jargs = (
            np.asarray(model.hinge_point, float), np.asarray(model.hinge_axis, float),
            physics.jaw_nodes, physics.jaw_weights, rest[physics.jaw_nodes] - model.hinge_point,
            physics.tied_weight, tied_rest0, tied_normal0, self._tied_rest, self._tied_normal,
        )
        self._muscles = (MuscleJacobian(physics, self._lu)
                         if integrator != "euler" and p.is_continuum else None)
        self._warm_up()

    def _warm_up(self) -> None:
        """Compile (or load) the numba kernels now, so that timings of the first frame are not
        the compiler's: a frame of zero steps touches every kernel and changes nothing."""
        ph = self.physics
        pos = ph.model.rest_positions.copy()
        vel = np.zeros_like(pos)
        m = np.zeros(ph.n_muscles)
        self._place(pos, vel, np.zeros(3), np.zeros(3), 0.0)
        fargs = force_arguments(ph, m, self._tied_rest, self._tied_normal, ph.model.lip_normals)
        if self.integrator == "euler":
            _euler_frame(pos, vel, m, m.copy(), m.copy(), 0, self.dt, ph.inv_mass, ph.dynamic,
                         ph.params.tau_activation, self._out, fargs, np.zeros(3), np.zeros(3),
                         self._jargs)
        else:
            accumulate_forces(pos, vel, self._out, *fargs)
            _filter_exact(m, m.copy(), m.copy(), ph.params.tau_activation, self.dt)
            if self._muscles is not None:
                self._muscles.linearise(pos, vel, m + 1.0, m)

    # -- the implicit system --------------------------------------------------------------
    def _factorise(self, h: float):
        """Constant scalar matrices over the moving nodes, shared by the x, y and z axes.

        Seeds' constants: K is the isotropic (per-axis) rest tangent stiffness: springs (mean of
        the elongation slope k and the compression slope pi sigma k / 2 of eqs. 1-2), the shape
        term of eq. (9) and the restoration of eq. (11); C is r times the spring graph Laplacian
        (eq. 8). The isotropic K over-estimates the transverse stiffness of unloaded springs,
        which only adds numerical damping; the exact forces are evaluated every step.

        Continuum: C is the exact Laplacian of the springs' dashpots; K a share of the springs'
        stiff branch, the volume term's Gram matrices and the tethers (see the module doc).
        """
        ph, p = self.physics, self.physics.params
        nd = ph.n_dynamic
        row = np.full(ph.model.n_nodes, -1, np.int64)
        row[ph.dynamic] = np.arange(nd)
        si, sj = row[ph.spring_i], row[ph.spring_j]
        pn = row[ph.prism_nodes]
        a_idx = np.repeat(np.arange(6), 6)
        b_idx = np.tile(np.arange(6), 6)
        ra, rb = pn[:, a_idx].reshape(-1), pn[:, b_idx].reshape(-1)
        ok = (ra >= 0) & (rb >= 0)
        if p.is_continuum:
            # damping exactly as the forces have it (the springs' dashpots): a matrix that
            # over-damps acts as inertia and makes the step ring; stiffness: a share of each
            # spring's stiff branch, the volume term's Gram matrices (within a factor 3 of its
            # rank-one Hessian) and the tethers
            damp = _graph_matrix(si, sj, ph.spring_damping, nd)
            k_springs = _graph_matrix(si, sj, IMPLICIT_STIFFNESS_SHARE * ph.spring_k_high, nd)
            grads = volume_gradients(ph.model.rest_positions[ph.prism_nodes])  # (p, 6, 3)
            gram = np.einsum("pac,pbc->pab", grads, grads) * ph.prism_bulk[:, None, None]
            tether = np.zeros(nd)
            np.add.at(tether, row[ph.tied], ph.restore_k)
            stiff = (k_springs + sp.csc_matrix((gram.reshape(-1)[ok], (ra[ok], rb[ok])),
                                               shape=(nd, nd)) + sp.diags(tether)).tocsc()
            mass = 1.0 / ph.inv_mass[ph.dynamic]
        else:
            k_tan = ph.spring_k_low * 0.5 * (1.0 + 0.5 * np.pi * p.sigma)
            stiff = _graph_matrix(si, sj, k_tan, nd)
            # shape term of eq. (9): d(-k_e2 (x_a - centroid))/dx_b = -k_e2 (delta_ab - 1/6)
            coef = p.k_shape * ((a_idx == b_idx).astype(float) - 1.0 / 6.0)
            cv = np.broadcast_to(coef, (len(pn), 36)).reshape(-1)
            stiff = stiff + sp.csc_matrix((cv[ok], (ra[ok], rb[ok])), shape=(nd, nd))
            restore = np.zeros(nd)
            restore[row[ph.tied]] = ph.restore_k
            stiff = stiff + sp.diags(restore)
            damp = _graph_matrix(si, sj, ph.spring_damping, nd)
            mass = np.full(nd, p.node_mass)
        stiff = stiff.tocsc()
        a_mat = (sp.diags(mass) + h * damp + h * h * stiff).tocsc()
        self._mass = mass
        self._damp_matrix = damp.tocsr()  # kept for checks of the solve against a direct one
        # the matrix is symmetric positive definite: no pivoting and a symmetric ordering fill in
        # less than SuperLU's general settings (a third faster to solve here)
        return stiff.tocsr(), splu(a_mat, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                   options={"SymmetricMode": True})

    def _solve(self, rhs, jac, h):
        """Solve the implicit system (with the muscles' Jacobian ``jac``) for rhs (nodes, 3)."""
        if self._muscles is None:
            return self._lu.solve(rhs)
        return self._muscles.solve(rhs, jac, h)

    def _stiffness(self, v, jac):
        """The system's stiffness times v (moving nodes, 3): constant part and muscles."""
        out = self._K @ v
        if self._muscles is not None:
            out += self._muscles.apply_stiffness(v, jac)
        return out

    def _frame_force_bound(self, m_force, m_rate, m_steady):
        """The larger of each muscle's filtered force now and at the frame's end (eq. 4)."""
        end = m_force.copy()
        _filter_exact(end, m_rate.copy(), m_steady, self.physics.params.tau_activation,
                      self.frame_duration)
        return np.maximum(m_force, end)

    def _linearise(self, pos, vel, m_force, m_steady):
        if self._muscles is None:
            return None
        return self._muscles.linearise(pos, vel, m_force, m_steady)

    def _ros2_stage(self, r_x, r_v, jac):
        """Solve (I - gamma h J) k = r for the state (x, v) with the constant matrices.

        With J = [[0, I], [-K/m, -C/m]]: (m + g C + g^2 K) k_v = m r_v - g K r_x and
        k_x = r_x + g k_v, g = gamma h (the factorised matrix).
        """
        g = ROS2_GAMMA * self.dt
        m = self._mass[:, None]
        k_v = self._solve(m * r_v - g * self._stiffness(r_x, jac), jac, g)
        return r_x + g * k_v, k_v

    def _place(self, pos, vel, start, rate, t):
        """Put the jaw in its pose at ``t`` s into the frame: ``start`` (3,) + ``rate`` (3,) t."""
        place_jaw(pos, vel, start[0] + rate[0] * t, start[1] + rate[1] * t,
                  start[2] + rate[2] * t, rate[0], rate[1], rate[2], *self._jargs)

    def jaw_pose(self, jaw) -> np.ndarray:
        """The jaw pose (3,) (angle rad, shift_y m, shift_z m) of a frame's jaw target: a (3,)
        pose as given, or an angle completed by the preset's ``jaw_kinematics`` (the coupled
        condyle glide, or no shift for the hinge; :func:`~facemech.solvers.jaw.jaw_poses`)."""
        pose = np.asarray(jaw, float)
        if pose.ndim == 0:
            return jaw_poses(float(pose), self.physics.params)
        if pose.shape != (3,):
            raise InputError(f"a jaw target is an angle or a (3,) pose, got shape {pose.shape}",
                             field="jaw")
        return pose.copy()

    # -- one frame ------------------------------------------------------------------------
    def advance(self, state: State, activity: np.ndarray, jaw) -> State:
        """Advance ``state`` by one frame with ``activity`` (16 groups, [0, 1]).

        The jaw goes from the state's pose (``jaw_angle``, ``jaw_shift``) to ``jaw``, as
        ``jaw_drive`` says: ``ramp`` moves the pose linearly over the frame, ``hold`` sets it
        at the frame's start. ``jaw`` is an angle (rad; the condyles' shift then follows the
        preset's ``jaw_kinematics``: the coupled glide, or none for the hinge) or a (3,) pose
        (angle rad, shift_y m, shift_z m). Returns a new :class:`State`; ``state`` is not
        modified.
        """
        ph = self.physics
        p = ph.params
        pos = np.array(state.positions)
        vel = np.array(state.velocities)
        m_force = np.array(state.muscle_force)
        m_rate = np.array(state.muscle_force_rate)
        m_steady = ph.steady_force(activity)
        target = self.jaw_pose(jaw)
        if self.jaw_drive == "hold":
            start, rate = target, np.zeros(3)
        else:
            start = state.jaw_pose
            rate = (target - start) / self.frame_duration
        self._place(pos, vel, start, rate, 0.0)
        fargs = force_arguments(ph, m_force, self._tied_rest, self._tied_normal,
                                ph.model.lip_normals)
        dyn = ph.dynamic
        h = self.dt
        inv_m = ph.inv_mass[dyn][:, None]
        if self.integrator == "euler":
            try:
                _euler_frame(pos, vel, m_force, m_rate, m_steady, self.n_steps, h, ph.inv_mass,
                             dyn, p.tau_activation, self._out, fargs, start, rate, self._jargs)
            except ZeroDivisionError:  # a spring or prism collapsed: nodes met mid-frame
                frame = int(round(state.time * p.frame_rate)) + 1
                raise SimulationBlowUp(
                    "nodes collapsed onto each other within the frame; likely cause: the time "
                    f"step ({h * 1e3:.3g} ms) is too large for the stiffness and damping (try a "
                    "smaller --dt)", frame=frame) from None
        elif self.integrator == "implicit":
            jac = self._linearise(pos, vel, self._frame_force_bound(m_force, m_rate, m_steady),
                                  m_steady)
            for step in range(self.n_steps):
                self._place(pos, vel, start, rate, step * h)
                accumulate_forces(pos, vel, self._out, *fargs)
                v0 = vel[dyn]
                rhs = h * (self._out[dyn] - h * self._stiffness(v0, jac))
                vel[dyn] = v0 + self._solve(rhs, jac, h)
                pos[dyn] += h * vel[dyn]
                _filter_exact(m_force, m_rate, m_steady, p.tau_activation, h)
        else:
            jac = self._linearise(pos, vel, self._frame_force_bound(m_force, m_rate, m_steady),
                                  m_steady)
            for step in range(self.n_steps):
                x0, v0 = pos[dyn].copy(), vel[dyn].copy()
                self._place(pos, vel, start, rate, step * h)
                accumulate_forces(pos, vel, self._out, *fargs)
                k1x, k1v = self._ros2_stage(v0, self._out[dyn] * inv_m, jac)
                pos[dyn] = x0 + h * k1x
                vel[dyn] = v0 + h * k1v
                _filter_exact(m_force, m_rate, m_steady, p.tau_activation, h)
                self._place(pos, vel, start, rate, (step + 1) * h)
                accumulate_forces(pos, vel, self._out, *fargs)
                k2x, k2v = self._ros2_stage(vel[dyn] - 2.0 * k1x,
                                            self._out[dyn] * inv_m - 2.0 * k1v, jac)
                pos[dyn] = x0 + h * (1.5 * k1x + 0.5 * k2x)
                vel[dyn] = v0 + h * (1.5 * k1v + 0.5 * k2v)
        self._place(pos, vel, target, rate, 0.0)
        return State(pos, vel, m_force, m_rate, float(target[0]), state.time + self.frame_duration,
                     target[1:])


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
