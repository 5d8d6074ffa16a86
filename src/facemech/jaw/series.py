"""A simulation's jaw from files (:class:`~.inputs.JawSource`): a CSV of angles, or the jaw's
markers in a marker file read onto the run's times and driven by :func:`.drive.jaw_drive`;
the bite block. Time in s, angles rad, poses (angle rad, shift_y m, shift_z m)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..plausibility import check_jaw_angles
from .drive import default_lead, jaw_drive
from .inputs import JawMarkers, JawSource

__all__ = ["bite_block", "jaw_from_bone", "jaw_from_chin", "jaw_from_csv",
           "jaw_from_two_markers", "jaw_series"]


def jaw_from_csv(path: str | Path, times: np.ndarray) -> np.ndarray:
    """Jaw angles (frames,) rad at ``times`` (s) from a CSV of ``time`` and ``jaw_angle`` (rad)
    or ``jaw_angle_deg``, interpolated linearly; the file must cover ``times``."""
    from ..io.tables import read_table

    t, cols = read_table(path)
    cols.pop("__meta__")
    if "jaw_angle" in cols:
        a = cols["jaw_angle"]
    elif "jaw_angle_deg" in cols:
        a = np.radians(cols["jaw_angle_deg"])
    else:
        raise InputError("needs a jaw_angle (rad) or jaw_angle_deg column", source=str(path),
                         field="jaw_angle")
    if not np.all(np.isfinite(a)):
        raise InputError("empty or NaN values", source=str(path), field="jaw_angle")
    check_jaw_angles(a, source=str(path),
                     field="jaw_angle" if "jaw_angle" in cols else "jaw_angle_deg")
    if times[0] < t[0] - 1e-6 or times[-1] > t[-1] + 1e-6:
        raise InputError("the jaw series does not cover the activity's time span",
                         source=str(path), field="time")
    return np.interp(times, t, a)


def _marker_node(face, name: str) -> int:
    """The face's epidermal node of marker ``name``, or its chin landmark."""
    return face.markers.get(name, face.landmarks["chin"])


def jaw_from_chin(path: str | Path, marker: str, model, times: np.ndarray, *,
                  units: str | None = None) -> np.ndarray:
    """Jaw angles (frames,) rad at ``times`` (s) from the vertical trajectory of a chin marker
    in a marker file (model axes), 33 ms early; the marker is the face's node of that name, or
    its chin landmark (``model``: a :class:`~facemech.physics.model.Model`). The file must
    cover ``times``."""
    from ..io.trajectories import trajectories

    pts = trajectories(path, [marker], units=units, times=times, cover="the chin trajectory")[1]
    return jaw_drive(pts, model, JawMarkers(marker), lead=default_lead(JawMarkers(), False),
                     chin_node=_marker_node(model.face, marker), source=str(path))[0]


def jaw_from_two_markers(path: str | Path, first: str, second: str, model, times: np.ndarray,
                         *, units: str | None = None) -> np.ndarray:
    """Jaw poses (frames, 3) at ``times`` from two mandible markers of a marker file (model
    axes), the recording moved so that the first marker's first sample sits on the face's node
    of that name (the chin landmark if the face has none); about the face's hinge."""
    from ..io.trajectories import trajectories

    pts = trajectories(path, [first, second], units=units, times=times,
                       cover="the jaw markers")[1]
    offset = model.face.rest_positions[_marker_node(model.face, first)] - pts[first][0]
    names = JawMarkers(first, second)
    return jaw_drive({n: p + offset for n, p in pts.items()}, model, names,
                     lead=default_lead(names, False), source=str(path))[0]


def jaw_from_bone(path: str | Path, model, times: np.ndarray, *, incisor: str | None = None,
                  molar: str | None = None, units: str | None = None) -> np.ndarray | None:
    """Jaw poses (frames, 3) at ``times`` from points on the bone in a marker file (model
    axes): the lower-incisor sensor ``incisor`` and the molar pellet ``molar``, or, without
    names, the sensors of roles ``lower_incisor`` and ``molar``
    (:func:`facemech.kinematics.roles.bone_points`); None when there is neither. No lead."""
    from ..io.markers import read_markers
    from ..kinematics.roles import bone_points

    ms = read_markers(path, units=units)
    incisor, molar, _ = bone_points(ms, incisor=incisor, molar=molar)
    if incisor is None:
        return None
    if times[0] < ms.time[0] - 1e-6 or times[-1] > ms.time[-1] + 1e-6:
        raise InputError("the jaw's bone points do not cover the activity's time span",
                         source=str(path), field="time")
    pts = {n: np.column_stack([np.interp(times, ms.time, ms.marker(n)[:, a]) for a in range(3)])
           for n in (incisor, molar) if n is not None}
    names = JawMarkers(jaw_incisor=incisor, jaw_molar=molar)
    return jaw_drive(pts, model, names, lead=default_lead(names, True), source=str(path))[0]


def bite_block(jaw: np.ndarray) -> np.ndarray:
    """A jaw series (frames,) or (frames, 3) held at its first value: a bite block."""
    jaw = np.asarray(jaw, float)
    return np.repeat(jaw[:1], len(jaw), axis=0)


def jaw_series(source: JawSource, model, times: np.ndarray) -> tuple[np.ndarray, dict]:
    """The jaw of ``source`` at ``times`` (s) for ``model`` (a
    :class:`~facemech.physics.model.Model`).

    Returns
    -------
    jaw : (frames,) angles rad, or (frames, 3) poses for a two-marker or bone-point drive;
        zeros without a source; held at the first value under a bite block (the one place it
        is applied)
    inputs : input name -> file hash
    """
    from ..io.results import file_hash

    chin, path, units = source.chin_marker or "R01", source.markers, source.units
    bone = None
    if path is not None and source.chin_marker is None and source.second_marker is None:
        bone = jaw_from_bone(path, model, times, incisor=source.incisor, molar=source.molar,
                             units=units)
    if bone is not None:
        jaw = bone
    elif path is not None and source.second_marker is not None:
        jaw = jaw_from_two_markers(path, chin, source.second_marker, model, times, units=units)
    elif path is not None:
        jaw = jaw_from_chin(path, chin, model, times, units=units)
    elif source.angles is not None:
        jaw = jaw_from_csv(source.angles, times)
    else:
        return np.zeros(len(times)), {}
    inputs = {"jaw_chin" if path is not None else "jaw_angle": file_hash(path or source.angles)}
    return (bite_block(jaw) if source.bite_block else jaw), inputs
