"""What every solver makes once for a face model (its :class:`SolverState`) and the start and
end of a frame that all of them share.

A solver (:class:`~facemech.solvers.explicit.ExplicitEuler`,
:class:`~facemech.solvers.implicit.LinearImplicitEuler`,
:class:`~facemech.solvers.implicit.Rosenbrock2`) is a small frozen description of the method;
``solver.init(physics)`` returns a :class:`SolverState` (the model's kernel bundles, the step, and
for the implicit methods the factorised matrix) and ``solver.step(solver_state, state,
controls)`` returns the next :class:`~facemech.solvers.state.State`, one frame later. Nothing
is mutated between calls: each step works on its own copies of the state's arrays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba as nb
import numpy as np

from ..physics.assembly import Physics
from ..physics.bundles import Anchors, ForceBundles
from ..physics.muscle import activation_exact_damped, max_force
from .contacts import ImplicitContacts, split_contacts
from .mandible import JawBundle, jaw_bundle, place_jaw, set_jaw_nodes
from .state import Controls, State
from .volume_floor import VolumeFloor

if TYPE_CHECKING:
    from .implicit import ImplicitSystem


@dataclass(frozen=True, eq=False)
class SolverState:
    """A solver's constants for one face model: made by ``init``, read by ``step``.

    Attributes
    ----------
    forces : ForceBundles -- the force kernel's constant arguments: the model's own
        (:attr:`~facemech.physics.assembly.Physics.forces`), less the contacts an implicit
        method steps apart
    jaw : JawBundle -- what the mandible carries (:func:`~facemech.solvers.mandible.jaw_bundle`)
    dynamic : (d,) int64 -- the nodes that move under forces, ascending
    inv_mass : (nodes,) 1/kg -- 0 for kinematic nodes
    muscle_group : (muscles,) int64 -- the group (column of the activity) of each instance
    max_force : (muscles,) N -- k_f S, the steady force at full activity (eq. 3)
    tau : float, s -- the time constant of the activation filter (eq. 4)
    frame_duration : float, s
    n_steps : int -- steps per frame
    step : float, s -- ``frame_duration / n_steps``
    system : ImplicitSystem or None -- the implicit methods' factorised constant matrix and
        the muscles' Jacobian (:mod:`facemech.solvers.implicit`); None for explicit Euler
    zeta : float -- the damping ratio of the activation filter (eq. 4; 1 in the seeds)
    contacts : ImplicitContacts -- the stiff contacts the implicit methods step apart
        (:mod:`facemech.solvers.contacts`); left out of ``forces``; empty otherwise
    volume_floor : VolumeFloor -- the prisms' volume floor the implicit methods step apart
        (:mod:`facemech.solvers.volume_floor`); empty unless the preset sets one
    """

    forces: ForceBundles
    jaw: JawBundle
    dynamic: np.ndarray
    inv_mass: np.ndarray
    muscle_group: np.ndarray
    max_force: np.ndarray
    tau: float
    frame_duration: float
    n_steps: int
    step: float
    system: ImplicitSystem | None = None
    zeta: float = 1.0
    contacts: ImplicitContacts = ImplicitContacts.empty()
    volume_floor: VolumeFloor = VolumeFloor.empty()

    def steady_force(self, activity: np.ndarray) -> np.ndarray:
        """M_bar (muscles,) N of each instance from group activity (groups,) in [0, 1] (eq. 3)."""
        return self.max_force * np.asarray(activity)[self.muscle_group]


def solver_state(physics: Physics, n_steps: int,
                 system: ImplicitSystem | None = None) -> SolverState:
    """The :class:`SolverState` of a model stepped ``n_steps`` times per frame.

    With an implicit ``system``, the continuum's tissue and ``params.implicit_contacts``, the
    bone and lip contacts leave the force kernel and are stepped implicitly after each solve
    (:mod:`.contacts`)."""
    p = physics.params
    frame = 1.0 / p.frame_rate
    forces, contacts = physics.forces, ImplicitContacts.empty()
    if system is not None:
        forces, contacts = implicit_forces(physics)
    floor = VolumeFloor.empty()
    if system is not None and p.is_continuum and p.volume_floor > 0.0:
        prisms = physics.forces.prisms
        floor = VolumeFloor.of(prisms.nodes, prisms.rest_volume, p.volume_floor,
                               p.volume_floor_modulus)
    return SolverState(
        forces=forces, contacts=contacts, volume_floor=floor, jaw=jaw_bundle(physics),
        dynamic=physics.dynamic,
        inv_mass=physics.inv_mass, muscle_group=physics.muscle_group,
        max_force=max_force(p.k_force, physics.muscle_area), tau=p.tau_activation,
        frame_duration=frame, n_steps=int(n_steps), step=frame / n_steps, system=system,
        zeta=float(p.activation_damping))


def implicit_forces(physics: Physics) -> tuple[ForceBundles, ImplicitContacts]:
    """The force kernel's bundles of an implicit method and the contacts it steps apart: with
    the continuum's tissue and ``params.implicit_contacts`` the bone and lip contacts leave the
    kernel (:func:`.contacts.split_contacts`); otherwise the model's own bundles and none."""
    p = physics.params
    if p.is_continuum and p.implicit_contacts:
        return split_contacts(physics.forces)
    return physics.forces, ImplicitContacts.empty()


@dataclass(frozen=True, eq=False)
class FrameStart:
    """Working copies of a state at a frame's start, the jaw placed (owned by one step).

    Attributes
    ----------
    positions, velocities : (nodes, 3) m and m/s -- the jaw nodes in the start pose
    muscle_force, muscle_force_rate : (muscles,) N and N/s -- the filter of eq. (4)
    muscle_steady : (muscles,) N -- M_bar of the frame's activity (eq. 3)
    jaw_start, jaw_rate : (3,) -- the jaw's pose at the start and its rate of change
        (rad/s, m/s, m/s)
    anchors : Anchors -- the tied nodes' anchors in the start pose
    """

    positions: np.ndarray
    velocities: np.ndarray
    muscle_force: np.ndarray
    muscle_force_rate: np.ndarray
    muscle_steady: np.ndarray
    jaw_start: np.ndarray
    jaw_rate: np.ndarray
    anchors: Anchors


def start_frame(solver_state: SolverState, state: State, controls: Controls) -> FrameStart:
    """Copies of ``state``'s arrays with the jaw placed in the frame's start pose."""
    pos = np.array(state.positions)
    vel = np.array(state.velocities)
    start = np.array(controls.jaw_start)
    rate = (np.asarray(controls.jaw_end) - start) / solver_state.frame_duration
    anchors = place_jaw_into(solver_state.jaw, start + rate * 0.0, rate, pos, vel)
    return FrameStart(pos, vel, np.array(state.muscle_force), np.array(state.muscle_force_rate),
                      solver_state.steady_force(controls.activity), start, rate, anchors)


def place_jaw_into(jaw: JawBundle, pose: np.ndarray, rate: np.ndarray, pos: np.ndarray,
                   vel: np.ndarray) -> Anchors:
    """Put the jaw nodes of a step's own working arrays ``pos`` and ``vel`` (nodes, 3) in
    ``pose`` moving at ``rate`` (3,); return the moved anchors."""
    jaw_pos, jaw_vel, anchors = place_jaw(jaw, pose, rate)
    set_jaw_nodes(jaw, jaw_pos, jaw_vel, pos, vel)
    return anchors


def finish_frame(solver_state: SolverState, state: State, controls: Controls, pos: np.ndarray,
                 vel: np.ndarray, m_force: np.ndarray, m_rate: np.ndarray,
                 jaw_rate: np.ndarray) -> State:
    """The state at the frame's end: the jaw nodes set in the end pose (moving at
    ``jaw_rate``), time one frame on."""
    target = np.asarray(controls.jaw_end)
    place_jaw_into(solver_state.jaw, target + jaw_rate * 0.0, jaw_rate, pos, vel)
    return State(pos, vel, m_force, m_rate, float(target[0]),
                 state.time + solver_state.frame_duration, target[1:])


@nb.njit(cache=True)
def filter_exact(m_force, m_rate, m_steady, tau, dt, zeta=1.0):
    """The activation filter of eq. (4) (damping ratio ``zeta``) advanced exactly by ``dt`` s
    from (M, dM/dt) (muscles,) towards ``m_steady`` (N): new arrays ``(M, dM/dt)``."""
    force = np.empty_like(m_force)
    rate = np.empty_like(m_rate)
    for m in range(m_force.shape[0]):
        force[m], rate[m] = activation_exact_damped(m_force[m], m_rate[m], m_steady[m], tau,
                                                       zeta, dt)
    return force, rate


__all__ = ["SolverState", "solver_state", "FrameStart", "start_frame", "finish_frame",
           "place_jaw_into", "filter_exact"]
