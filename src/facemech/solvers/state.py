"""The explicit, immutable state of the face model, and the controls of one frame.

Both the forward simulation and the inverse solver advance a :class:`State` with a solver's
``step(solver_state, state, controls)`` (:mod:`facemech.solvers.explicit`,
:mod:`facemech.solvers.implicit`; :meth:`facemech.solvers.step.Stepper.advance` makes the
:class:`Controls`); a state can be kept and restarted from at any frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class State:
    """Model state at one instant.

    Attributes
    ----------
    positions : (nodes, 3) array, metres
    velocities : (nodes, 3) array, m/s
    muscle_force : (muscles,) array, N -- the filtered force M of eq. (4)
    muscle_force_rate : (muscles,) array, N/s -- dM/dt
    jaw_angle : float, radians (positive opens the mouth)
    time : float, seconds
    jaw_shift : (2,) array, m -- the condyles' shift (y, z) from rest; with ``jaw_angle`` the
        jaw's pose (:mod:`facemech.solvers.mandible`)
    """

    positions: np.ndarray
    velocities: np.ndarray
    muscle_force: np.ndarray
    muscle_force_rate: np.ndarray
    jaw_angle: float = 0.0
    time: float = 0.0
    jaw_shift: np.ndarray | None = None

    def __post_init__(self):
        for name in ("positions", "velocities", "muscle_force", "muscle_force_rate"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        shift = np.zeros(2) if self.jaw_shift is None else self.jaw_shift
        shift = _frozen(shift)
        if shift.shape != (2,):
            raise ValueError(f"jaw_shift must have shape (2,), got {shift.shape}")
        object.__setattr__(self, "jaw_shift", shift)

    @property
    def jaw_pose(self) -> np.ndarray:
        """(3,) the jaw's pose: angle (rad), shift_y (m), shift_z (m)."""
        return np.array([self.jaw_angle, *self.jaw_shift])

    @classmethod
    def at_rest(cls, rest_positions: np.ndarray, n_muscles: int, jaw_angle: float = 0.0,
                time: float = 0.0, jaw_shift: np.ndarray | None = None) -> State:
        """The rest state: rest positions, no motion, no muscle force."""
        return cls(rest_positions, np.zeros_like(rest_positions), np.zeros(n_muscles),
                   np.zeros(n_muscles), jaw_angle, time, jaw_shift)


@dataclass(frozen=True, eq=False)
class Controls:
    """What drives the face over one frame.

    Attributes
    ----------
    activity : (groups,) array in [0, 1] -- muscle activity per group
        (:data:`~facemech.params.MUSCLE_GROUPS`), held over the frame
    jaw_start : (3,) array -- the jaw's pose (angle rad, shift_y m, shift_z m) at the frame's
        start
    jaw_end : (3,) array -- its pose at the frame's end; the pose moves linearly from one to
        the other over the frame (equal: the jaw holds its pose)
    """

    activity: np.ndarray
    jaw_start: np.ndarray
    jaw_end: np.ndarray

    def __post_init__(self):
        for name in ("activity", "jaw_start", "jaw_end"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        for name in ("jaw_start", "jaw_end"):
            if getattr(self, name).shape != (3,):
                raise ValueError(f"{name} must have shape (3,), got {getattr(self, name).shape}")
