"""The paper's integrator: explicit Euler steps (Lucero & Munhall 1999).

With dt = 0.33 ms, 50 steps per frame. The velocity is updated first and the position from the
new velocity (the Euler-Cromer ordering of explicit mass-spring codes; the other ordering is
unstable on undamped modes). The muscle filter of eq. (4) is stepped with the same explicit
Euler. A whole frame runs in one compiled kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numba as nb
import numpy as np

from ..errors import InputError, SimulationBlowUp
from ..physics.assembly import Physics, accumulate_forces, rest_anchors
from ..physics.muscle import activation_euler
from ..physics.threads import kernel_threads
from .mandible import place_jaw, set_jaw_nodes
from .solver_state import SolverState, solver_state
from .state import Controls, State


class EulerSteps(NamedTuple):
    """How one frame of explicit steps runs.

    Attributes
    ----------
    n_steps : int -- steps per frame
    dt : float, s -- the step
    tau : float, s -- the activation filter's time constant (eq. 4)
    dynamic : (d,) int64 -- the nodes that move under forces
    inv_mass : (nodes,) 1/kg
    zeta : float -- the damping ratio of the activation filter (eq. 4; 1 in the seeds)
    """

    n_steps: int
    dt: float
    tau: float
    dynamic: np.ndarray
    inv_mass: np.ndarray
    zeta: float = 1.0


@nb.njit(cache=True, inline="always")
def euler_cromer(nodes, q0, q1, inv_mass, dt, out, pos, vel):
    """One Euler-Cromer update of ``nodes[q0:q1]``: the velocity from the forces ``out``
    (nodes, 3) N, then the position from the new velocity."""
    for q in range(q0, q1):
        i = nodes[q]
        for a in range(3):
            vel[i, a] += dt * inv_mass[i] * out[i, a]
            pos[i, a] += dt * vel[i, a]


@nb.njit(cache=True, parallel=True)
def band_update(nodes, ptr, inv_mass, dt, out, pos, vel):
    """:func:`euler_cromer` of the bands of ``nodes`` (band q is ``ptr[q]:ptr[q + 1]``) on
    numba's threads: the same numbers, each node's in its band's thread."""
    for q in nb.prange(ptr.shape[0] - 1):
        euler_cromer(nodes, ptr[q], ptr[q + 1], inv_mass, dt, out, pos, vel)


@nb.njit(cache=True)
def euler_frame(forces, jaw, steps, pos, vel, m_force, m_rate, m_steady, anchors, jaw_start,
                jaw_rate):
    """One frame of explicit Euler steps.

    Parameters
    ----------
    forces : ForceBundles
    jaw : JawBundle
    steps : EulerSteps
    pos, vel : (nodes, 3) m and m/s -- at the frame's start, the jaw placed
    m_force, m_rate : (muscles,) N and N/s -- the activation filter's state (eq. 4)
    m_steady : (muscles,) N -- its target M_bar (eq. 3)
    anchors : Anchors -- the tied nodes' anchors at the frame's start
    jaw_start, jaw_rate : (3,) -- the jaw's pose at the start and its rate (rad/s, m/s, m/s)

    Returns
    -------
    pos, vel, m_force, m_rate : new arrays, one frame on (the jaw nodes where the last step
        left them)
    """
    pos = pos.copy()
    vel = vel.copy()
    m_force = m_force.copy()
    m_rate = m_rate.copy()
    out = np.zeros_like(pos)
    dt = steps.dt
    dynamic = steps.dynamic
    inv_mass = steps.inv_mass
    moving = jaw_rate[0] != 0.0 or jaw_rate[1] != 0.0 or jaw_rate[2] != 0.0
    slabs = forces.slabs
    banded = kernel_threads() > 1 and slabs.dynamic_ptr.shape[0] > 2
    for step in range(steps.n_steps):
        if moving:
            jaw_pos, jaw_vel, anchors = place_jaw(jaw, jaw_start + jaw_rate * (step * dt),
                                                  jaw_rate)
            set_jaw_nodes(jaw, jaw_pos, jaw_vel, pos, vel)
        accumulate_forces(forces, pos, vel, m_force, anchors, out)
        if banded:  # each thread moves the nodes of its band of the face
            band_update(slabs.dynamic, slabs.dynamic_ptr, inv_mass, dt, out, pos, vel)
        else:
            euler_cromer(dynamic, 0, dynamic.shape[0], inv_mass, dt, out, pos, vel)
        for m in range(m_force.shape[0]):
            m_force[m], m_rate[m] = activation_euler(m_force[m], m_rate[m], m_steady[m],
                                                     steps.tau, dt, steps.zeta)
    return pos, vel, m_force, m_rate


@dataclass(frozen=True)
class ExplicitEuler:
    """Explicit (Euler-Cromer) steps of ``dt`` s: the paper's integrator.

    Parameters
    ----------
    dt : float, s
        The step asked for: a frame takes ``int(frame / dt)`` steps (50 at the paper's 0.33 ms
        and 60 Hz), so the step taken, ``frame / steps`` (``SolverState.step``), is ``dt`` or
        just above it where ``dt`` does not divide the frame.

    Explicit steps are unstable under the continuum tissue's physiological forces and viscosity:
    :meth:`init` refuses its presets.
    """

    dt: float
    name: ClassVar[str] = "euler"

    def __post_init__(self):
        try:
            dt = float(self.dt)
        except (TypeError, ValueError):
            dt = float("nan")
        if not dt > 0:
            raise InputError(f"dt must be a positive number of seconds (got {self.dt!r})",
                             field="dt")
        object.__setattr__(self, "dt", dt)

    def steps_per_frame(self, frame_rate: float) -> int:
        """Steps per frame at ``frame_rate`` Hz."""
        return max(1, int(1.0 / frame_rate / self.dt + 1e-9))  # 50 at 0.33 ms

    def init(self, physics: Physics) -> SolverState:
        """The solver state of a model (the kernels compiled or loaded on the way)."""
        p = physics.params
        if p.is_continuum:
            raise InputError(f"the {p.name} preset needs an implicit integrator (implicit or "
                             "rosenbrock): its muscle forces and tissue viscosity make explicit "
                             "Euler steps unstable", field="integrator")
        prepared = solver_state(physics, self.steps_per_frame(p.frame_rate))
        _warm_up(prepared, physics)
        return prepared

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State:
        """``state`` advanced by one frame under ``controls`` (a new :class:`State`)."""
        f = solver_state.frame.start(state, controls)
        steps = _euler_steps(solver_state, solver_state.n_steps)
        try:
            pos, vel, m_force, m_rate = euler_frame(
                solver_state.forces, solver_state.jaw, steps, f.positions, f.velocities,
                f.muscle_force, f.muscle_force_rate, f.muscle_steady, f.anchors, f.jaw_start,
                f.jaw_rate)
        except ZeroDivisionError:  # a spring or prism collapsed: nodes met mid-frame
            frame = int(round(state.time / solver_state.frame_duration)) + 1
            raise SimulationBlowUp(
                "nodes collapsed onto each other within the frame; likely cause: the time "
                f"step ({solver_state.step * 1e3:.3g} ms) is too large for the stiffness and "
                "damping (try a smaller --dt)", frame=frame) from None
        return solver_state.frame.finish(state, controls, pos, vel, m_force, m_rate,
                                         f.jaw_rate)


def _warm_up(solver_state: SolverState, physics: Physics) -> None:
    """Compile (or load) the kernels now, so that timings of the first frame are not the
    compiler's: a frame of zero steps touches every kernel and changes nothing."""
    pos = physics.model.rest_positions.copy()
    m = np.zeros(len(solver_state.muscle_group))
    anchors = rest_anchors(physics)
    steps = _euler_steps(solver_state, 0)
    euler_frame(solver_state.forces, solver_state.jaw, steps, pos, np.zeros_like(pos), m, m, m,
                anchors, np.zeros(3), np.zeros(3))
    accumulate_forces(solver_state.forces, pos, np.zeros_like(pos), m, anchors,
                      np.zeros_like(pos))


def _euler_steps(solver_state: SolverState, n_steps: int) -> EulerSteps:
    """The :class:`EulerSteps` of ``n_steps`` steps of a solver state."""
    return EulerSteps(n_steps, solver_state.step, solver_state.tau, solver_state.dynamic,
                      solver_state.inv_mass, solver_state.zeta)


__all__ = ["ExplicitEuler", "EulerSteps", "euler_frame"]
