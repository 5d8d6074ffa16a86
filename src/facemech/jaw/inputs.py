"""The jaw's inputs of a command, each group declared once (:mod:`facemech.inputs`): where a
simulation's jaw comes from (:class:`JawSource`) and which markers of an inverted recording are
on the jaw (:class:`JawMarkers`); both are checked when made."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..checks import check_value
from ..errors import InputError
from ..inputs import option

__all__ = ["JawMarkers", "JawSource"]


@dataclass(frozen=True)
class JawSource:
    """Where a simulation's jaw trajectory comes from: at most one of ``angles`` (a CSV of
    ``time`` and ``jaw_angle`` rad or ``jaw_angle_deg``) and ``markers`` (a marker file; lengths
    in ``units`` if the file does not say); neither: the jaw stays closed. In the marker file,
    either a skin chin marker ``chin_marker`` (default ``R01``) and, for a two-marker drive, a
    second mandible marker ``second_marker``; or points on the bone: a lower-incisor sensor
    ``incisor`` and optionally a molar pellet ``molar`` (without names or a chin marker, a file
    whose sensors carry articulography roles gives its ``lower_incisor`` and ``molar``).
    ``bite_block`` holds the jaw at its first pose whatever the source."""

    angles: Path | None = option(None, "CSV: time, jaw_angle (rad) or jaw_angle_deg",
                                 key="jaw_angle")
    markers: Path | None = option(None, "marker file with the jaw's markers (chin, or incisor "
                                  "and molar)", key="jaw_chin")
    chin_marker: str | None = option(None, "the chin marker (default R01)")
    second_marker: str | None = option(None, "a second mandible marker in the --jaw-chin file",
                                       key="jaw_second_marker")
    units: str | None = option(None, "length unit if the file has none")
    bite_block: bool = option(False, "hold the jaw at its initial pose")
    incisor: str | None = option(None, "lower-incisor sensor in --jaw-chin (default: its role)",
                                 key="jaw_incisor")
    molar: str | None = option(None, "a molar pellet in --jaw-chin, with --jaw-incisor",
                               key="jaw_molar")

    def __post_init__(self):
        if self.markers is not None and self.angles is not None:
            raise InputError("give at most one of --jaw-chin and --jaw-angle", field="jaw")
        for name, opt in ((self.second_marker, "jaw-second-marker"),
                          (self.incisor, "jaw-incisor"), (self.molar, "jaw-molar")):
            if name is not None and self.markers is None:
                raise InputError(f"--{opt} names a marker of the --jaw-chin file: give "
                                 "--jaw-chin too", field=opt)
        if self.incisor is not None and (self.chin_marker or self.second_marker) is not None:
            raise InputError("give one jaw drive: bone points (--jaw-incisor) or skin markers "
                             "(--chin-marker)", field="jaw-incisor")
        if self.molar is not None and self.incisor is None:
            raise InputError("a molar point needs the lower incisor too (--jaw-incisor)",
                             field="jaw-molar")


@dataclass(frozen=True)
class JawMarkers:
    """The jaw's markers of an inverted recording (its jaw source), checked when made.

    Attributes
    ----------
    chin_marker : a skin jaw marker: its vertical drop gives the jaw angle, ``jaw_lead`` frames
        early, estimated further with the muscles unless ``jaw_fixed``
    jaw_second_marker : a second point on the mandible with ``chin_marker``: the two markers'
        planar rigid motion drives the jaw's three degrees of freedom, held as given
    jaw_incisor, jaw_molar : a lower-incisor sensor and a molar pellet, points on the bone
        (default: the sensors of roles ``lower_incisor`` and ``molar``, when there is no
        ``chin_marker``): they give the jaw's angle, glide and protrusion, held as given, and
        are not compared with the skin
    jaw_fixed : hold the recorded jaw as given
    jaw_lead : frames by which the jaw drive is moved earlier (None: 2 for a skin marker, 0
        for bone points)
    """

    chin_marker: str | None = option(None, "a jaw marker: its drop gives the jaw")
    jaw_second_marker: str | None = option(None, "another: rotation and glide")
    jaw_incisor: str | None = option(None, "lower-incisor sensor: a bone point that drives the "
                                     "jaw, not skin")
    jaw_molar: str | None = option(None, "a molar pellet on the mandible, with --jaw-incisor")
    jaw_fixed: bool = option(False, "hold the recorded jaw as given")
    jaw_lead: int | None = option(None, "frames the recorded jaw leads the skin (default: skin "
                                  "2, bone 0)", unit="frames")

    def __post_init__(self):
        if self.jaw_second_marker is not None and self.chin_marker is None:
            raise InputError("--jaw-second-marker needs --chin-marker (the first jaw marker)",
                             field="jaw-second-marker")
        if self.jaw_lead is not None and self.jaw_lead < 0:
            raise InputError(f"jaw lead must be >= 0 frames (got {self.jaw_lead})",
                             field="jaw-lead")
        if self.jaw_lead is not None:  # the command line's interval (facemech.checks)
            check_value("jaw_lead", self.jaw_lead)
