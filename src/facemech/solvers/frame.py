"""The physics' side of a frame, the same for every integrator: :class:`FrameTerms`.

An integrator owns its method (steps, matrices, iterations); what a frame asks of the face
model is here, once: the jaw nodes placed in the jaw's pose at a time of the frame
(:mod:`.mandible`), the activation filter of eq. (4) advanced exactly, the stiff contacts and
the prisms' volume floor stepped after a solve (:mod:`.contacts`, :mod:`.volume_floor`), and
the state at the frame's start and end. Every solver calls it; none mutates its arguments
but the step's own working arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from ..physics.bundles import Anchors
from ..physics.muscle import activation_exact_damped
from .contacts import ImplicitContacts, resolve_contacts
from .mandible import JawBundle, place_jaw, set_jaw_nodes
from .state import Controls, State
from .volume_floor import VolumeFloor, resolve_volume_floor


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


@dataclass(frozen=True, eq=False)
class FrameTerms:
    """What a frame asks of the model, for every solver.

    Attributes
    ----------
    jaw : JawBundle -- what the mandible carries
    inv_mass : (nodes,) 1/kg
    muscle_group : (muscles,) int64 -- the activity's column of each muscle instance
    max_force : (muscles,) N -- k_f S (eq. 3)
    tau : float, s; zeta : float -- the activation filter of eq. (4)
    frame_duration : float, s
    contacts : ImplicitContacts -- the stiff contacts stepped after a solve (empty: none)
    volume_floor : VolumeFloor -- the prisms' floor stepped after a solve (empty: none)
    """

    jaw: JawBundle
    inv_mass: np.ndarray
    muscle_group: np.ndarray
    max_force: np.ndarray
    tau: float
    zeta: float
    frame_duration: float
    contacts: ImplicitContacts
    volume_floor: VolumeFloor

    def steady_force(self, activity: np.ndarray) -> np.ndarray:
        """M_bar (muscles,) N of each instance from group activity (groups,) in [0, 1] (eq. 3)."""
        return self.max_force * np.asarray(activity)[self.muscle_group]

    def start(self, state: State, controls: Controls) -> FrameStart:
        """Copies of ``state``'s arrays with the jaw placed in the frame's start pose."""
        pos = np.array(state.positions)
        vel = np.array(state.velocities)
        start = np.array(controls.jaw_start)
        rate = (np.asarray(controls.jaw_end) - start) / self.frame_duration
        anchors = place_jaw_into(self.jaw, start + rate * 0.0, rate, pos, vel)
        return FrameStart(pos, vel, np.array(state.muscle_force),
                          np.array(state.muscle_force_rate), self.steady_force(controls.activity),
                          start, rate, anchors)

    def place_jaw(self, f: FrameStart, t: float, pos: np.ndarray, vel: np.ndarray) -> Anchors:
        """The jaw nodes of ``pos``, ``vel`` placed in the pose ``t`` s into the frame ``f``;
        the moved anchors."""
        return place_jaw_into(self.jaw, f.jaw_start + f.jaw_rate * t, f.jaw_rate, pos, vel)

    def filter(self, m_force, m_rate, m_steady, dt: float):
        """The activation filter of eq. (4) advanced exactly by ``dt`` s: ``(M, dM/dt)``."""
        return filter_exact(m_force, m_rate, m_steady, self.tau, dt, self.zeta)

    def constraints(self, pos: np.ndarray, vel: np.ndarray, anchors: Anchors, h: float) -> None:
        """The stiff contacts' own implicit step of ``h`` s after a solve, then the volume
        floor's (in place on ``pos``, ``vel``)."""
        c = self.contacts
        if len(c.bone_k) or len(c.lip_k):
            resolve_contacts(pos, vel, self.inv_mass, c.tied, c.bone_k, anchors.rest,
                             anchors.normal, c.pairs, c.normals, c.lip_k, h)
        floor = self.volume_floor
        if len(floor.floor):
            resolve_volume_floor(pos, vel, self.inv_mass, floor.nodes, floor.floor, floor.kappa,
                                 h)

    def finish(self, state: State, controls: Controls, pos: np.ndarray, vel: np.ndarray,
               m_force: np.ndarray, m_rate: np.ndarray, jaw_rate: np.ndarray) -> State:
        """The state at the frame's end: the jaw nodes set in the end pose (moving at
        ``jaw_rate``), time one frame on."""
        target = np.asarray(controls.jaw_end)
        place_jaw_into(self.jaw, target + jaw_rate * 0.0, jaw_rate, pos, vel)
        return State(pos, vel, m_force, m_rate, float(target[0]),
                     state.time + self.frame_duration, target[1:])


def place_jaw_into(jaw: JawBundle, pose: np.ndarray, rate: np.ndarray, pos: np.ndarray,
                   vel: np.ndarray) -> Anchors:
    """Put the jaw nodes of a step's own working arrays ``pos`` and ``vel`` (nodes, 3) in
    ``pose`` moving at ``rate`` (3,); return the moved anchors."""
    jaw_pos, jaw_vel, anchors = place_jaw(jaw, pose, rate)
    set_jaw_nodes(jaw, jaw_pos, jaw_vel, pos, vel)
    return anchors


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


__all__ = ["FrameStart", "FrameTerms", "place_jaw_into", "filter_exact"]
