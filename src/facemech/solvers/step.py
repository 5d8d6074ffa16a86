"""Time stepping: the paper's explicit Euler and two fast implicit integrators.

Each advances an immutable :class:`~facemech.solvers.state.State` through one control frame
(1/60 s) with the muscle activity held constant, as in Lucero & Munhall (1999):

``euler`` (the paper's integrator)
    explicit Euler with dt = 0.33 ms, 50 steps per frame. The velocity is updated first and the
    position from the new velocity (the Euler-Cromer ordering of explicit mass-spring codes;
    the other ordering is unstable on undamped modes). The muscle filter of eq. (4) is stepped
    with the same explicit Euler.
``implicit``
    linearly implicit (Baraff-Witkin) Euler with a constant matrix ``A = m I + h C + h^2 K``
    (damping C, rest tangent stiffness K of springs, shape and restoration terms), factorised
    once with SuperLU and reused: ``A dv = h (f(x, v) - h K v)``. The nonlinear forces are
    evaluated exactly each step, so only the stability, not the consistency, rests on K.
``rosenbrock``
    the two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999), second order for any
    approximation of the Jacobian, so one constant factorised matrix (gamma h in place of h)
    serves every step: two force evaluations and two solves per step.

The implicit methods integrate the muscle filter exactly. K and C are isotropic (the same for
x, y and z) so one factorisation of a nodes x nodes matrix serves the three axes.

The jaw (``jaw_drive``): ``"ramp"`` (default) turns the mandible at a constant rate from the
state's angle to the frame's angle over the frame; ``"hold"`` sets the frame's angle at the start
of the frame and holds it, as the paper does. Holding jolts the skull at 60 Hz, and the skin's
response to those steps is so sensitive to the step size that even the paper integrator changes
by about 0.1-0.2 mm between dt = 0.33 and 0.1 ms; the ramp removes the jolt.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..errors import InputError, SimulationBlowUp
from ..physics.assembly import Physics, accumulate_forces, force_arguments
from ..physics.muscle import activation_euler, activation_exact
from .state import State

INTEGRATORS = ("euler", "implicit", "rosenbrock")
JAW_DRIVES = ("ramp", "hold")
ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)


@nb.njit(cache=True)
def place_jaw(pos, vel, angle, rate, hinge_point, hinge_axis, jaw_nodes, jaw_rest,
              tied_jaw, tied_rest0, tied_normal0, tied_rest, tied_normal):
    """Turn the mandible to ``angle`` (rad) turning at ``rate`` (rad/s), in place.

    Sets the positions and velocities of the jaw's skull nodes and the rotated rest positions
    and skull normals under the tied fascia nodes that lie over the jaw (indices ``tied_jaw``).
    """
    ax, ay, az = hinge_axis[0], hinge_axis[1], hinge_axis[2]
    c = np.cos(angle)
    s = np.sin(angle)
    t = 1.0 - c
    r = np.empty((3, 3))
    r[0, 0] = c + ax * ax * t
    r[0, 1] = ax * ay * t - az * s
    r[0, 2] = ax * az * t + ay * s
    r[1, 0] = ay * ax * t + az * s
    r[1, 1] = c + ay * ay * t
    r[1, 2] = ay * az * t - ax * s
    r[2, 0] = az * ax * t - ay * s
    r[2, 1] = az * ay * t + ax * s
    r[2, 2] = c + az * az * t
    for k in range(jaw_nodes.shape[0]):
        i = jaw_nodes[k]
        for a in range(3):
            pos[i, a] = hinge_point[a] + (r[a, 0] * jaw_rest[k, 0] + r[a, 1] * jaw_rest[k, 1]
                                          + r[a, 2] * jaw_rest[k, 2])
        dx = pos[i, 0] - hinge_point[0]
        dy = pos[i, 1] - hinge_point[1]
        dz = pos[i, 2] - hinge_point[2]
        vel[i, 0] = rate * (ay * dz - az * dy)
        vel[i, 1] = rate * (az * dx - ax * dz)
        vel[i, 2] = rate * (ax * dy - ay * dx)
    for q in range(tied_jaw.shape[0]):
        k = tied_jaw[q]
        for a in range(3):
            tied_rest[k, a] = hinge_point[a]
            tied_normal[k, a] = 0.0
            for b in range(3):
                tied_rest[k, a] += r[a, b] * (tied_rest0[k, b] - hinge_point[b])
                tied_normal[k, a] += r[a, b] * tied_normal0[k, b]


@nb.njit(cache=True)
def _euler_frame(pos, vel, m_force, m_rate, m_steady, n_steps, dt, inv_mass, n_dynamic, tau,
                 out, fargs, jaw_start, jaw_rate, jargs):
    for step in range(n_steps):
        if jaw_rate != 0.0:
            place_jaw(pos, vel, jaw_start + jaw_rate * step * dt, jaw_rate, *jargs)
        accumulate_forces(pos, vel, out, *fargs)
        for i in range(n_dynamic):
            for a in range(3):
                vel[i, a] += dt * inv_mass * out[i, a]
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
    integrator : {"euler", "implicit", "rosenbrock"}
    substeps : int, optional
        Steps per frame of the implicit integrators (default 4, h = 4.2 ms).
    dt : float, optional
        Step of the explicit integrator (default: the preset's 0.33 ms).
    jaw_drive : {"ramp", "hold"}
    """

    def __init__(self, physics: Physics, *, integrator: str = "euler", substeps: int = 4,
                 dt: float | None = None, jaw_drive: str = "ramp"):
        if integrator not in INTEGRATORS:
            raise InputError(f"unknown integrator {integrator!r} (expected one of "
                             f"{', '.join(INTEGRATORS)})", field="integrator")
        if jaw_drive not in JAW_DRIVES:
            raise InputError(f"unknown jaw drive {jaw_drive!r} (expected ramp or hold)",
                             field="jaw_drive")
        self.physics = physics
        self.integrator = integrator
        self.jaw_drive = jaw_drive
        p = physics.params
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
        self.dt = self.frame_duration / self.n_steps
        if integrator != "euler":
            gamma = ROS2_GAMMA if integrator == "rosenbrock" else 1.0
            self._K, self._lu = self._factorise(gamma * self.dt)
        model = physics.model
        self._out = np.zeros_like(model.rest_positions)
        tied_rest0 = model.rest_positions[physics.tied]
        tied_normal0 = model.skull_normals[physics.tied_skull]
        self._tied_rest = tied_rest0.copy()
        self._tied_normal = tied_normal0.copy()
        self._jargs = (
            np.asarray(model.hinge_point, float), np.asarray(model.hinge_axis, float),
            physics.jaw_nodes, model.rest_positions[physics.jaw_nodes] - model.hinge_point,
            np.nonzero(physics.tied_on_jaw)[0], tied_rest0, tied_normal0,
            self._tied_rest, self._tied_normal,
        )
        self._warm_up()

    def _warm_up(self) -> None:
        """Compile (or load) the numba kernels now, so that timings of the first frame are not
        the compiler's: a frame of zero steps touches every kernel and changes nothing."""
        ph = self.physics
        pos = ph.model.rest_positions.copy()
        vel = np.zeros_like(pos)
        m = np.zeros(ph.n_muscles)
        place_jaw(pos, vel, 0.0, 0.0, *self._jargs)
        fargs = force_arguments(ph, m, self._tied_rest, self._tied_normal, ph.model.lip_normals)
        if self.integrator == "euler":
            _euler_frame(pos, vel, m, m.copy(), m.copy(), 0, self.dt, 1.0, ph.n_dynamic,
                         ph.params.tau_activation, self._out, fargs, 0.0, 0.0, self._jargs)
        else:
            accumulate_forces(pos, vel, self._out, *fargs)
            _filter_exact(m, m.copy(), m.copy(), ph.params.tau_activation, self.dt)

    # -- the implicit system --------------------------------------------------------------
    def _factorise(self, h: float):
        """Constant scalar matrices over the dynamic nodes, shared by the x, y and z axes.

        K is the isotropic (per-axis) rest tangent stiffness: springs (mean of the elongation
        slope k and the compression slope pi sigma k / 2 of eqs. 1-2), the shape term of eq. (9)
        and the restoration of eq. (11); C is r times the spring graph Laplacian (eq. 8). The
        isotropic K over-estimates the transverse stiffness of unloaded springs, which only adds
        numerical damping; the exact forces are evaluated every step.
        """
        ph, p = self.physics, self.physics.params
        nd = ph.n_dynamic
        k_tan = ph.spring_k_low * 0.5 * (1.0 + 0.5 * np.pi * p.sigma)
        stiff = _graph_matrix(ph.spring_i, ph.spring_j, k_tan, nd)
        # shape term of eq. (9): d(-k_e2 (x_a - centroid))/dx_b = -k_e2 (delta_ab - 1/6)
        pn = ph.prism_nodes
        a_idx = np.repeat(np.arange(6), 6)
        b_idx = np.tile(np.arange(6), 6)
        coef = p.k_shape * ((a_idx == b_idx).astype(float) - 1.0 / 6.0)
        ra, rb = pn[:, a_idx].reshape(-1), pn[:, b_idx].reshape(-1)
        cv = np.broadcast_to(coef, (len(pn), 36)).reshape(-1)
        ok = (ra < nd) & (rb < nd)
        stiff = stiff + sp.csc_matrix((cv[ok], (ra[ok], rb[ok])), shape=(nd, nd))
        restore = np.zeros(nd)
        restore[ph.tied] = p.k_restore
        stiff = (stiff + sp.diags(restore)).tocsc()
        damp = p.damping * _graph_matrix(ph.spring_i, ph.spring_j, np.ones(len(ph.spring_i)), nd)
        a_mat = (sp.identity(nd, format="csc") * p.node_mass + h * damp + h * h * stiff).tocsc()
        return stiff.tocsr(), splu(a_mat, permc_spec="COLAMD")

    def _ros2_stage(self, r_x, r_v):
        """Solve (I - gamma h J) k = r for the state (x, v) with the constant matrices.

        With J = [[0, I], [-K/m, -C/m]]: (m + g C + g^2 K) k_v = m r_v - g K r_x and
        k_x = r_x + g k_v, g = gamma h (the factorised matrix).
        """
        g = ROS2_GAMMA * self.dt
        m = self.physics.params.node_mass
        k_v = self._lu.solve(m * r_v - g * (self._K @ r_x))
        return r_x + g * k_v, k_v

    # -- one frame ------------------------------------------------------------------------
    def advance(self, state: State, activity: np.ndarray, jaw_angle: float) -> State:
        """Advance ``state`` by one frame with ``activity`` (16 groups, [0, 1]).

        The jaw goes from ``state.jaw_angle`` to ``jaw_angle`` (rad) as ``jaw_drive`` says.
        Returns a new :class:`State`; ``state`` is not modified.
        """
        ph = self.physics
        p = ph.params
        pos = np.array(state.positions)
        vel = np.array(state.velocities)
        m_force = np.array(state.muscle_force)
        m_rate = np.array(state.muscle_force_rate)
        m_steady = ph.steady_force(activity)
        target = float(jaw_angle)
        if self.jaw_drive == "hold":
            start, rate = target, 0.0
        else:
            start = float(state.jaw_angle)
            rate = (target - start) / self.frame_duration
        place_jaw(pos, vel, start, rate, *self._jargs)
        fargs = force_arguments(ph, m_force, self._tied_rest, self._tied_normal,
                                ph.model.lip_normals)
        nd = ph.n_dynamic
        h = self.dt
        inv_m = 1.0 / p.node_mass
        if self.integrator == "euler":
            try:
                _euler_frame(pos, vel, m_force, m_rate, m_steady, self.n_steps, h, inv_m, nd,
                             p.tau_activation, self._out, fargs, start, rate, self._jargs)
            except ZeroDivisionError:  # a spring or prism collapsed: nodes met mid-frame
                frame = int(round(state.time * p.frame_rate)) + 1
                raise SimulationBlowUp(
                    "nodes collapsed onto each other within the frame; likely cause: the time "
                    f"step ({h * 1e3:.3g} ms) is too large for the stiffness and damping (try a "
                    "smaller --dt)", frame=frame) from None
        elif self.integrator == "implicit":
            for step in range(self.n_steps):
                place_jaw(pos, vel, start + rate * step * h, rate, *self._jargs)
                accumulate_forces(pos, vel, self._out, *fargs)
                rhs = h * (self._out[:nd] - h * (self._K @ vel[:nd]))
                vel[:nd] += self._lu.solve(rhs)
                pos[:nd] += h * vel[:nd]
                _filter_exact(m_force, m_rate, m_steady, p.tau_activation, h)
        else:
            for step in range(self.n_steps):
                x0, v0 = pos[:nd].copy(), vel[:nd].copy()
                place_jaw(pos, vel, start + rate * step * h, rate, *self._jargs)
                accumulate_forces(pos, vel, self._out, *fargs)
                k1x, k1v = self._ros2_stage(v0, self._out[:nd] * inv_m)
                pos[:nd] = x0 + h * k1x
                vel[:nd] = v0 + h * k1v
                _filter_exact(m_force, m_rate, m_steady, p.tau_activation, h)
                place_jaw(pos, vel, start + rate * (step + 1) * h, rate, *self._jargs)
                accumulate_forces(pos, vel, self._out, *fargs)
                k2x, k2v = self._ros2_stage(vel[:nd] - 2.0 * k1x,
                                            self._out[:nd] * inv_m - 2.0 * k1v)
                pos[:nd] = x0 + h * (1.5 * k1x + 0.5 * k2x)
                vel[:nd] = v0 + h * (1.5 * k1v + 0.5 * k2v)
        place_jaw(pos, vel, target, rate, *self._jargs)
        return State(pos, vel, m_force, m_rate, target, state.time + self.frame_duration)


def _graph_matrix(i: np.ndarray, j: np.ndarray, w: np.ndarray, nd: int) -> sp.csc_matrix:
    """Weighted graph Laplacian of edges (i, j) restricted to nodes < nd.

    An edge to a kinematic node (>= nd) keeps its diagonal term only.
    """
    both = (i < nd) & (j < nd)
    rows = np.concatenate([i[i < nd], j[j < nd], i[both], j[both]])
    cols = np.concatenate([i[i < nd], j[j < nd], j[both], i[both]])
    vals = np.concatenate([w[i < nd], w[j < nd], -w[both], -w[both]])
    return sp.csc_matrix((vals, (rows, cols)), shape=(nd, nd))
