"""Muscle outputs: tension, length, lengthening velocity and activation state per instance.

What OpenSim and ArtiSynth users read from a simulation, evaluated exactly as the force kernel
of :mod:`facemech.physics.assembly` uses them (Lucero & Munhall 1999, eqs. 4-7): the length l and
its rate dl/dt come from :func:`~facemech.physics.assembly.muscle_lengths` (the definition the
force kernels share), the tension from :func:`~facemech.physics.muscle.hill_force`:

``F = M fl(l) [f1 + f2 atan(f3 + f4 dl/dt)] + [k_m (l - l0)]^+``

with M the activation state (the filtered force of eq. 4, a :class:`~facemech.solvers.state.State`'s
``muscle_force``). A linear muscle's length runs from its origin to its insertion (the weighted
mean of its insertion nodes); a sphincter's is the length of its path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np

from ..params import MUSCLE_GROUPS
from .assembly import Physics, muscle_lengths
from .muscle import hill_force

#: the quantities of :class:`MuscleSeries` as (attribute, results variable, units, long name)
OUTPUT_VARIABLES = (
    ("force", "muscle_force", "N", "muscle tension F (eqs. 5-7)"),
    ("length", "muscle_length", "m", "muscle length l"),
    ("velocity", "muscle_velocity", "m/s", "muscle lengthening velocity dl/dt (lengthening > 0)"),
    ("activation", "muscle_activation", "N", "activation state M (filtered force of eq. 4)"),
)


@nb.njit(cache=True)
def _tensions(m_filtered, length, rate, rest_length, k_passive, f1, f2, f3, f4, out):
    for m in range(length.shape[0]):
        out[m] = hill_force(m_filtered[m], length[m], rest_length[m], rate[m], k_passive[m],
                            f1, f2, f3, f4[m])


@dataclass(frozen=True)
class MuscleOutputs:
    """Muscle outputs at one instant, per muscle instance (``Physics.model.muscles.names``).

    Attributes
    ----------
    force : (muscles,) N -- total tension F of eqs. (5)-(7)
    length : (muscles,) m
    velocity : (muscles,) m/s -- dl/dt, positive when lengthening
    activation : (muscles,) N -- activation state M, the filtered force of eq. (4)
    """

    force: np.ndarray
    length: np.ndarray
    velocity: np.ndarray
    activation: np.ndarray


def muscle_outputs(physics: Physics, positions: np.ndarray, velocities: np.ndarray,
                   activation: np.ndarray) -> MuscleOutputs:
    """Tension, length, lengthening velocity and activation of every muscle instance.

    Parameters
    ----------
    physics : Physics
    positions, velocities : (nodes, 3) arrays, m and m/s -- all nodes of ``physics.model``
        (a :class:`~facemech.solvers.state.State`'s ``positions`` and ``velocities``)
    activation : (muscles,) array, N -- the filtered force M of eq. (4) (``State.muscle_force``)

    Returns
    -------
    MuscleOutputs
    """
    p = physics.params
    pos = np.ascontiguousarray(positions, float)
    vel = np.ascontiguousarray(velocities, float)
    act = np.ascontiguousarray(activation, float)
    muscles = physics.forces.muscles
    length, rate = muscle_lengths(muscles, pos, vel)
    force = np.empty(physics.n_muscles)
    _tensions(act, length, rate, muscles.rest_length, muscles.k_passive, p.f1, p.f2, p.f3,
              muscles.f4, force)
    return MuscleOutputs(force, length, rate, act.copy())


def state_muscle_outputs(physics: Physics, state) -> MuscleOutputs:
    """:func:`muscle_outputs` of a :class:`~facemech.solvers.state.State`."""
    return muscle_outputs(physics, state.positions, state.velocities, state.muscle_force)


@dataclass(frozen=True)
class MuscleSeries:
    """Muscle outputs over frames: (frames, muscles) arrays and the instances' names.

    Attributes
    ----------
    names : instance names, e.g. ``"OOS_R"``, ``"ZYG_L"`` (group, then side)
    groups : group of each instance, one of :data:`~facemech.params.MUSCLE_GROUPS`
    force : (frames, muscles) N -- total tension F of eqs. (5)-(7)
    length : (frames, muscles) m
    velocity : (frames, muscles) m/s -- lengthening positive
    activation : (frames, muscles) N -- activation state M (filtered force of eq. 4)
    max_force : (muscles,) N -- k_f S, the steady force at full activity (eq. 3)
    """

    names: tuple[str, ...]
    groups: tuple[str, ...]
    force: np.ndarray
    length: np.ndarray
    velocity: np.ndarray
    activation: np.ndarray
    max_force: np.ndarray

    @property
    def normalised_activation(self) -> np.ndarray:
        """M / (k_f S) (frames, muscles): the activation state as a share of full activity."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.max_force > 0, self.activation / self.max_force, 0.0)


class MuscleRecorder:
    """Fills a :class:`MuscleSeries` frame by frame (what :func:`~facemech.solvers.forward.simulate`
    uses in its frame loop).

    Parameters
    ----------
    physics : Physics
    frames : number of frames to record
    """

    def __init__(self, physics: Physics, frames: int):
        self.physics = physics
        n = physics.n_muscles
        self._arrays = {name: np.full((frames, n), np.nan) for name, *_ in OUTPUT_VARIABLES}

    def record(self, frame: int, state) -> None:
        """Store the outputs of ``state`` as frame ``frame``."""
        out = state_muscle_outputs(self.physics, state)
        for name, arr in self._arrays.items():
            arr[frame] = getattr(out, name)

    def series(self) -> MuscleSeries:
        physics = self.physics
        return MuscleSeries(
            names=tuple(physics.model.muscles.names),
            groups=tuple(MUSCLE_GROUPS[g] for g in physics.muscle_group),
            max_force=physics.params.k_force * physics.muscle_area,
            **self._arrays)


def muscle_series(physics: Physics, states: Sequence) -> MuscleSeries:
    """The muscle outputs of a sequence of states as (frames, muscles) arrays.

    Parameters
    ----------
    physics : Physics -- the one the states belong to
    states : sequence of :class:`~facemech.solvers.state.State`, one per frame

    Returns
    -------
    MuscleSeries
    """
    rec = MuscleRecorder(physics, len(states))
    for k, st in enumerate(states):
        rec.record(k, st)
    return rec.series()


def muscle_output_variables(physics: Physics, states: Sequence | MuscleSeries) -> dict:
    """Results-file variables of the muscle outputs, for ``write_results(..., extra=...)``.

    Parameters
    ----------
    physics : Physics
    states : the accepted :class:`~facemech.solvers.state.State` of every frame (in frame order,
        as many as the results' ``time``), or a :class:`MuscleSeries` already computed

    Returns
    -------
    dict
        name -> :class:`xarray.DataArray` with units in its attrs: ``muscle_force`` (N),
        ``muscle_length`` (m), ``muscle_velocity`` (m/s, lengthening positive),
        ``muscle_activation`` (N), each on (time, muscle_instance); ``muscle_group`` and
        ``muscle_max_force`` (N, k_f S) on (muscle_instance). The ``muscle_instance``
        coordinate holds the instance names (``"OOS_R"``, ...): the results' ``muscle``
        coordinate is taken by every group of ``activity``.

    Examples
    --------
    >>> write_results(path, sim, extra=muscle_output_variables(physics, accepted_states))
    """
    s = states if isinstance(states, MuscleSeries) else muscle_series(physics, states)
    return series_variables(s)


def series_variables(s: MuscleSeries) -> dict:
    """The results-file variables of a :class:`MuscleSeries` (see
    :func:`muscle_output_variables`)."""
    import xarray as xr

    dims = ("time", "muscle_instance")
    coord = {"muscle_instance": list(s.names)}
    out = {}
    for attr, var, units, long_name in OUTPUT_VARIABLES:
        out[var] = xr.DataArray(getattr(s, attr), dims=dims, coords=coord,
                                attrs={"units": units, "long_name": long_name})
    out["muscle_group"] = xr.DataArray(np.array(s.groups, dtype=object), dims=("muscle_instance",),
                                       coords=coord,
                                       attrs={"long_name": "muscle group of each instance"})
    out["muscle_max_force"] = xr.DataArray(
        s.max_force, dims=("muscle_instance",), coords=coord,
        attrs={"units": "N", "long_name": "k_f S: steady force at full activity (eq. 3)"})
    return out
