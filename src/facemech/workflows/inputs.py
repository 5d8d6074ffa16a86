"""The input groups of ``simulate`` and ``invert``, each declared once (:mod:`facemech.inputs`):
the command line's options, the batch manifest's keys and the workflows' Python signatures are
made from these dataclasses (the jaw's groups: :mod:`facemech.jaw.inputs`; the fit's:
:mod:`facemech.inverse.options`). Pure Python: the command line imports it for ``--help``."""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from ..errors import InputError
from ..inputs import REQUIRED, option

__all__ = ["Controls", "MarkerFile", "PresetChoice", "Stepping"]


@dataclass(frozen=True)
class Controls:
    """Where the muscle input comes from: exactly one of ``activity`` (a CSV, time and muscle
    groups in [0, 1]) and ``emg`` (raw EMG, CSV or C3D, the seeds' seven channels), with the
    EMG's rest interval ``emg_baseline`` (start, stop) s and a calibration recording of maximal
    gestures ``emg_calibration`` (its channels those of ``emg``)."""

    activity: Path | None = option(None, "activity CSV")
    emg: Path | None = option(None, "raw EMG (CSV or C3D), 7 channels")
    emg_baseline: str | tuple[float, float] | None = option(
        None, "EMG rest interval START,STOP (s)", unit="s", cli=str | None)
    emg_calibration: Path | None = option(None, "EMG of maximal gestures")

    def __post_init__(self):
        if (self.activity is None) == (self.emg is None):
            raise InputError("give exactly one of --activity and --emg", field="activity")


@dataclass(frozen=True)
class Stepping:
    """How a simulation steps (None: the preset's): the jaw's kinematics (``hinge`` or
    ``glide``), the integrator (``euler``, ``implicit`` or ``rosenbrock``), the steps per frame
    of the implicit integrators, the explicit Euler step ``dt`` (s) and the jaw's drive within
    a frame (``ramp`` or ``hold``), as :func:`facemech.solvers.forward.simulate` takes them."""

    jaw_kinematics: str | None = option(None, "hinge or glide")
    integrator: str | None = option(None, "euler, implicit or rosenbrock")
    substeps: int | None = option(None, "steps per frame (implicit)")
    dt: float | None = option(None, "explicit Euler step, s", unit="s")
    jaw_drive: str = option("ramp", "ramp or hold")

    def solver_options(self) -> dict:
        """The options of :func:`facemech.solvers.forward.simulate` (all but the kinematics)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "jaw_kinematics"}


@dataclass(frozen=True)
class MarkerFile:
    """The marker file of an inversion and how its markers are laid on the face.

    Attributes
    ----------
    path : marker file: motion capture in the model's frame and at its frame rate, or
        articulography (resampled, its lips laid on the face's vermilion points)
    units : length unit of a file that carries none
    map_file : marker,node CSV (default: the closest nodes)
    scale_pair : "A,B": adapt the markers by per-axis scaling from two markers far apart
    """

    path: Path = option(REQUIRED, "mocap in the model's frame and rate, or articulography "
                        "(.ema .est .txy), resampled", key="markers")
    units: str | None = option(None, "length unit if the file has none")
    map_file: Path | None = option(None, "marker,node CSV (default: closest nodes)",
                                   flags=("--map",))
    scale_pair: str | None = option(None, "A,B: scale the markers per axis")


@dataclass(frozen=True)
class PresetChoice:
    """The preset of an inversion (a name or a preset ``.json``) with a command's overrides: the
    jaw's kinematics (``hinge`` or ``glide``) and the explicit Euler step ``dt`` (s) of every
    evaluation (its method's ``fast_dt``)."""

    preset: str = option("anatomical", "anatomical, lucero1999, pitermann2001, calibrated or a "
                         "preset .json", kind="file_or_name")
    jaw_kinematics: str | None = option(None, "hinge or glide (or the preset's)")
    dt: float | None = option(None, "Euler step of every evaluation, s (default: the "
                              "preset's)", unit="s")

    def resolve(self):
        """The :class:`~facemech.params.Preset` with the overrides."""
        from ..params import Preset, preset_pair

        params, steps = preset_pair(self.preset)
        if self.jaw_kinematics is not None:
            params = params.with_(jaw_kinematics=self.jaw_kinematics)
        return Preset(params, steps if self.dt is None else steps.with_(fast_dt=self.dt))
