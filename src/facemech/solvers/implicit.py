"""Two fast implicit integrators on one constant, factorised matrix.

:class:`LinearImplicitEuler`: linearly implicit (Baraff-Witkin) Euler with a constant matrix
``A = M + h C + h^2 K`` (masses, damping, a rest stiffness), factorised once (:mod:`.cholesky`):
``A dv = h (f(x, v) - h K v)``; the forces are evaluated exactly each step, so only stability
rests on K. ``K v`` includes the coupling to the jaw's kinematic nodes and moving tether anchors
(:meth:`ImplicitSystem.apply_boundary`). With ``StepOptions.predictor`` the forces are taken at
the explicit predictor, ``A dv = h f(x + h v, v)``; the matrix must then hold at least 3/4 of each
stiffness (:data:`facemech.params.PREDICTOR_LEAST_SHARES`).
:class:`Rosenbrock2`: the two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999), second order
for any Jacobian approximation, on the same kind of matrix.

K and C are isotropic, so one nodes x nodes factorisation serves x, y and z. The muscles' Hill
velocity term and geometric stiffness enter exactly through the Woodbury identity
(:class:`~facemech.solvers.muscle_implicit.MuscleJacobian`). The matrix's contents per preset and
the step's stability bound: docs/model.md, "The step".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import InputError
from ..physics.assembly import Physics, accumulate_forces, rest_anchors
from ..stepping import StepOptions
from .frame import place_jaw_into
from .implicit_matrix import ImplicitSystem, implicit_system
from .krylov import KRYLOV_GROWTH, krylov_step, region_krylov_step
from .mandible import moved_anchors
from .solver_state import SolverState, solver_state
from .state import Controls, State

ROS2_GAMMA = 1.0 + 1.0 / np.sqrt(2.0)
#: share of the springs' stiffness (of their stiff branch) that the constant matrix of the
#: continuum carries by default (``Parameters.implicit_stiffness_share``): with the exact
#: damping in the matrix, the rest left explicit is stable at 4 steps per frame and the lips do
#: not ring (docs/model.md, Integration)
IMPLICIT_STIFFNESS_SHARE = StepOptions.implicit_stiffness_share


def _anchor_velocity(jaw, pose, rate, anchors, h):
    """(t, 3) m/s: the tethers' anchors' velocity over the step (their places at the step's
    end less at its start, over h)."""
    nxt, _ = moved_anchors(pose + rate * h, jaw.hinge_point, jaw.hinge_axis,
                           jaw.anchor_weights, jaw.anchor_rest, jaw.anchor_normal)
    return (nxt - anchors.rest) / h



def _check_substeps(substeps) -> int:
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise InputError(f"substeps must be a whole number of steps per frame, at least 1 "
                         f"(got {substeps!r})", field="substeps")
    return int(substeps)


def _init(physics: Physics, substeps: int, gamma: float, options: StepOptions) -> SolverState:
    frame = 1.0 / physics.params.frame_rate
    system = implicit_system(physics, gamma * (frame / substeps), options)
    prepared = solver_state(physics, substeps, system, options)
    _warm_up(prepared, physics)
    return prepared


def _warm_up(solver_state: SolverState, physics: Physics) -> None:
    """Compile (or load) the kernels now, so that timings of the first frame are not the
    compiler's."""
    frame = solver_state.frame
    pos = physics.model.rest_positions.copy()
    vel = np.zeros_like(pos)
    m = np.zeros(len(solver_state.muscle_group))
    place_jaw_into(frame.jaw, np.zeros(3), np.zeros(3), pos, vel)
    anchors = rest_anchors(physics)
    accumulate_forces(solver_state.forces, pos, vel, m, anchors, np.zeros_like(pos))
    frame.constraints(pos, vel, anchors, solver_state.step)
    frame.filter(m, m, m, solver_state.step)
    solver_state.system.linearise(pos, vel, m + 1.0, m)


def _frame_force_bound(solver_state: SolverState, m_force, m_rate, m_steady):
    """The larger of each muscle's filtered force now and at the frame's end (eq. 4)."""
    end, _ = solver_state.frame.filter(m_force, m_rate, m_steady, solver_state.frame_duration)
    return np.maximum(m_force, end)


@dataclass(frozen=True)
class LinearImplicitEuler:
    """Linearly implicit Euler with the constant factorised matrix (see the module doc).

    Parameters
    ----------
    substeps : int
        Steps per frame (4 at 60 Hz: h = 4.2 ms).
    options : StepOptions
        The matrix's shares of the stiffness, the predictor and its Krylov correction, the
        drag, the contacts and volume floor stepped after each solve (its ``substeps`` and
        ``dt`` are not read).
    """

    substeps: int
    options: StepOptions = field(default_factory=StepOptions)
    name: ClassVar[str] = "implicit"

    def __post_init__(self):
        object.__setattr__(self, "substeps", _check_substeps(self.substeps))

    def init(self, physics: Physics) -> SolverState:
        """The solver state of a model: its matrix factorised for h = frame / substeps."""
        return _init(physics, self.substeps, 1.0, self.options)

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State:
        """``state`` advanced by one frame under ``controls`` (a new :class:`State`)."""
        system, frame = solver_state.system, solver_state.frame
        f = frame.start(state, controls)
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
            anchors = frame.place_jaw(f, step * h, pos, vel)
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
                        frame.jaw, f.jaw_start + f.jaw_rate * (step * h), f.jaw_rate,
                        anchors, h))
                rhs = h * (out[dyn] - h * kv)
                dv = system.solve(rhs, jac, h)
            elif system.region is not None:
                dv = region_krylov_step(solver_state, system, region, at, vel, m_force,
                                        anchors, out, h * out[dyn], jac, h)
            elif system.krylov:
                dv = krylov_step(solver_state, system, at, vel, m_force, anchors, out,
                                 h * out[dyn], jac, h)
            else:
                dv = system.solve(h * out[dyn], jac, h)
            vel[dyn] = v0 + dv
            pos[dyn] += h * vel[dyn]
            frame.constraints(pos, vel, anchors, h)
            m_force, m_rate = frame.filter(m_force, m_rate, m_steady, h)
        return frame.finish(state, controls, pos, vel, m_force, m_rate, f.jaw_rate)


@dataclass(frozen=True)
class Rosenbrock2:
    """The two-stage Rosenbrock-W method ROS2 (Verwer et al. 1999) with the constant
    factorised matrix (see the module doc).

    Parameters
    ----------
    substeps : int
        Steps per frame (each two force evaluations and two solves).
    options : StepOptions
        As :class:`LinearImplicitEuler`'s (no predictor: a form of the linear implicit step).
    """

    substeps: int
    options: StepOptions = field(default_factory=StepOptions)
    name: ClassVar[str] = "rosenbrock"

    def __post_init__(self):
        object.__setattr__(self, "substeps", _check_substeps(self.substeps))

    def init(self, physics: Physics) -> SolverState:
        """The solver state of a model: its matrix factorised for gamma h."""
        if self.options.predictor:
            raise InputError("predictor=True is a form of the linearly implicit Euler step "
                             "(integrator 'implicit'), not of 'rosenbrock'", field="predictor")
        return _init(physics, self.substeps, ROS2_GAMMA, self.options)

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State:
        """``state`` advanced by one frame under ``controls`` (a new :class:`State`)."""
        system, frame = solver_state.system, solver_state.frame
        f = frame.start(state, controls)
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
            anchors = frame.place_jaw(f, step * h, pos, vel)
            accumulate_forces(solver_state.forces, pos, vel, m_force, anchors, out)
            k1x, k1v = _ros2_stage(solver_state, v0, out[dyn] * inv_m, jac)
            pos[dyn] = x0 + h * k1x
            vel[dyn] = v0 + h * k1v
            m_force, m_rate = frame.filter(m_force, m_rate, m_steady, h)
            anchors = frame.place_jaw(f, (step + 1) * h, pos, vel)
            accumulate_forces(solver_state.forces, pos, vel, m_force, anchors, out)
            k2x, k2v = _ros2_stage(solver_state, vel[dyn] - 2.0 * k1x,
                                   out[dyn] * inv_m - 2.0 * k1v, jac)
            pos[dyn] = x0 + h * (1.5 * k1x + 0.5 * k2x)
            vel[dyn] = v0 + h * (1.5 * k1v + 0.5 * k2v)
            frame.constraints(pos, vel, anchors, h)
        return frame.finish(state, controls, pos, vel, m_force, m_rate, f.jaw_rate)


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
           "ROS2_GAMMA", "IMPLICIT_STIFFNESS_SHARE", "KRYLOV_GROWTH"]
