"""The :class:`Solver` protocol and what a solver makes once for a face model, its
:class:`SolverState`.

A solver (:class:`~facemech.solvers.explicit.ExplicitEuler`,
:class:`~facemech.solvers.implicit.LinearImplicitEuler`,
:class:`~facemech.solvers.implicit.Rosenbrock2`, or any object with the protocol's ``name``,
``init`` and ``step``) is a small frozen description of the method; ``solver.init(physics)``
returns a :class:`SolverState` (the model's kernel bundles, the step, the physics' side of a
frame, :class:`~facemech.solvers.frame.FrameTerms`, and any matrix the method keeps) and
``solver.step(solver_state, state, controls)`` returns the next
:class:`~facemech.solvers.state.State`, one frame later. Nothing is mutated between calls.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from ..physics.assembly import Physics
from ..physics.bundles import ForceBundles
from ..physics.muscle import max_force
from ..stepping import StepOptions
from .contacts import ImplicitContacts, split_contacts
from .frame import FrameStart, FrameTerms, filter_exact, place_jaw_into
from .mandible import JawBundle, jaw_bundle
from .state import Controls, State
from .volume_floor import VolumeFloor


@runtime_checkable
class Solver(Protocol):
    """An integrator: a frozen description of its method and options.

    ``name`` is how presets and the command line call it; ``init(physics)`` makes its
    :class:`SolverState` once per model; ``step(solver_state, state, controls)`` returns the
    state one frame later. A new integrator is one module with such a class.
    """

    name: ClassVar[str]

    def init(self, physics: Physics) -> SolverState: ...

    def step(self, solver_state: SolverState, state: State, controls: Controls) -> State: ...


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
    system : the method's own constants, or None: the implicit methods' factorised constant
        matrix and the muscles' Jacobian (:class:`~facemech.solvers.implicit_matrix.
        ImplicitSystem`); None for explicit Euler
    zeta : float -- the damping ratio of the activation filter (eq. 4; 1 in the seeds)
    contacts : ImplicitContacts -- the stiff contacts the implicit methods step apart
        (:mod:`facemech.solvers.contacts`); left out of ``forces``; empty otherwise
    volume_floor : VolumeFloor -- the prisms' volume floor the implicit methods step apart
        (:mod:`facemech.solvers.volume_floor`); empty unless the preset sets one
    frame : FrameTerms -- the start and end of a frame, the jaw, the activation filter, the
        contacts and the volume floor, as every solver calls them (made from the above)
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
    system: Any = None
    zeta: float = 1.0
    contacts: ImplicitContacts = ImplicitContacts.empty()
    volume_floor: VolumeFloor = VolumeFloor.empty()

    def __post_init__(self):
        object.__setattr__(self, "frame", FrameTerms(
            jaw=self.jaw, inv_mass=self.inv_mass, muscle_group=self.muscle_group,
            max_force=self.max_force, tau=self.tau, zeta=self.zeta,
            frame_duration=self.frame_duration, contacts=self.contacts,
            volume_floor=self.volume_floor))

    def steady_force(self, activity: np.ndarray) -> np.ndarray:
        """M_bar (muscles,) N of each instance from group activity (groups,) in [0, 1] (eq. 3)."""
        return self.frame.steady_force(activity)


def solver_state(physics: Physics, n_steps: int, system: Any = None,
                 options: StepOptions | None = None) -> SolverState:
    """The :class:`SolverState` of a model stepped ``n_steps`` times per frame.

    With an implicit ``system``, the continuum's tissue and ``options.implicit_contacts``, the
    bone and lip contacts leave the force kernel and are stepped implicitly after each solve
    (:mod:`.contacts`); with ``options.volume_floor``, the prisms' floor too."""
    p = physics.params
    frame = 1.0 / p.frame_rate
    forces, contacts = physics.forces, ImplicitContacts.empty()
    if system is not None:
        forces, contacts = implicit_forces(physics, options)
    floor = VolumeFloor.empty()
    if (system is not None and options is not None and p.is_continuum
            and options.volume_floor > 0.0):
        prisms = physics.forces.prisms
        floor = VolumeFloor.of(prisms.nodes, prisms.rest_volume, options.volume_floor,
                               options.volume_floor_modulus)
    return SolverState(
        forces=forces, contacts=contacts, volume_floor=floor, jaw=jaw_bundle(physics),
        dynamic=physics.dynamic,
        inv_mass=physics.inv_mass, muscle_group=physics.muscle_group,
        max_force=max_force(p.k_force, physics.muscle_area), tau=p.tau_activation,
        frame_duration=frame, n_steps=int(n_steps), step=frame / n_steps, system=system,
        zeta=float(p.activation_damping))


def implicit_forces(physics: Physics,
                    options: StepOptions | None) -> tuple[ForceBundles, ImplicitContacts]:
    """The force kernel's bundles of an implicit method and the contacts it steps apart: with
    the continuum's tissue and ``options.implicit_contacts`` the bone and lip contacts leave the
    kernel (:func:`.contacts.split_contacts`); otherwise the model's own bundles and none."""
    if physics.params.is_continuum and options is not None and options.implicit_contacts:
        return split_contacts(physics.forces)
    return physics.forces, ImplicitContacts.empty()


__all__ = ["Solver", "SolverState", "solver_state", "FrameStart", "FrameTerms", "start_frame",
           "finish_frame", "place_jaw_into", "filter_exact"]


def start_frame(solver_state: SolverState, state: State, controls: Controls) -> FrameStart:
    """:meth:`FrameTerms.start` of a solver state."""
    return solver_state.frame.start(state, controls)


def finish_frame(solver_state: SolverState, state: State, controls: Controls, pos, vel, m_force,
                 m_rate, jaw_rate) -> State:
    """:meth:`FrameTerms.finish` of a solver state."""
    return solver_state.frame.finish(state, controls, pos, vel, m_force, m_rate, jaw_rate)
