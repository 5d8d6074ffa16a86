"""A scan's unit and axes: inferred from its size and its landmarks, checked against the declared.

A face is 100-300 mm wide (with the neck and the back of the head, at most 600 mm across), so
the size of a scan tells its length unit: the units facemech reads are at least ten times
apart, and only one of them makes the numbers of a file face-sized. The landmarks tell the
axes: the brows lie above the chin (up), the nose tip ahead of the mouth corners, cheeks and
jaw angles (forward); facemech's frame is right-handed, +x the subject's left, +y up, +z forward.

An axes string names, for facemech's x, y and z in turn, the file's axis (with its sign) that
points that way: ``"x,z,-y"`` is a scan with +z up and -y forward (Blender's front view).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..plausibility import FACE_SIZE_M
from ..units import LENGTH_TO_M, length_scale

#: the unit names used in messages
UNIT_WORDS = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "um": "micrometres"}
#: degrees: the detected up or forward direction must lie this close to one of the file's axes
MAX_TILT_DEG = 35.0
#: degrees: after ``--axes``, the landmarks' up and forward must lie this close to +y and +z
MAX_AXES_DISAGREEMENT_DEG = 50.0
#: the midline landmark ahead of the bilateral pairs, and the pairs themselves
_FRONT = "nose_tip"
_BACK_PAIRS = (("mouth_corner_left", "mouth_corner_right"), ("cheek_left", "cheek_right"),
               ("jaw_angle_left", "jaw_angle_right"))
_TOP_PAIR = ("brow_left", "brow_right")
_BOTTOM = ("chin", "menton")


def infer_unit(extent: float, *, limits_m: tuple[float, float] = FACE_SIZE_M) -> str | None:
    """The length unit that makes a scan's largest extent face-sized, or None if none does.

    Parameters
    ----------
    extent : the scan's largest extent along the file's axes, in the file's numbers
    limits_m : (smallest, largest) extent of a face scan, metres
    """
    fits = [u for u, s in LENGTH_TO_M.items() if limits_m[0] <= extent * s <= limits_m[1]]
    return fits[0] if len(fits) == 1 else None


def check_unit(extent: float, declared: str | None, *, source: str | None = None,
               field: str = "units", limits_m: tuple[float, float] = FACE_SIZE_M) -> str:
    """The scan's length unit: the declared one if the scan is face-sized in it, else an error.

    Parameters
    ----------
    extent : the scan's largest extent, in the file's numbers
    declared : the unit the user gave (``m``, ``cm``, ``mm``, ``um``), or None to infer it
    source, field : the file and the option, for the message
    limits_m : (smallest, largest) accepted extent, metres

    Returns
    -------
    str
        The unit.

    Raises
    ------
    InputError
        The scan is not face-sized in the declared unit (the message names the unit it looks
        like, and the option to give), or no unit makes it face-sized.
    """
    lo, hi = limits_m
    guess = infer_unit(extent, limits_m=limits_m)
    if declared is None:
        if guess is None:
            raise InputError(f"the surface spans {extent:,.4g} units and no length unit makes "
                             f"it face-sized ({lo * 1e3:g}-{hi * 1e3:g} mm): give --units",
                             source=source, field=field)
        return guess
    unit = declared.strip().lower()
    size_mm = extent * length_scale(unit, source=source, field=field) * 1e3
    if lo <= size_mm * 1e-3 <= hi:
        return unit
    if guess is None:  # no unit fits: the one that comes nearest a face's 150 mm
        guess = min(LENGTH_TO_M, key=lambda u: abs(np.log(extent * LENGTH_TO_M[u] / 0.15)))
        if guess == unit:
            raise InputError(f"the surface is {_mm(size_mm)} mm across read in {unit} (a face "
                             f"is {lo * 1e3:g}-{hi * 1e3:g} mm): is it a face?", source=source,
                             field=field)
    in_guess = _mm(extent * LENGTH_TO_M[guess] * 1e3)
    raise InputError(f"the surface is {_mm(size_mm)} mm across read in {unit} (a face is "
                     f"{lo * 1e3:g}-{hi * 1e3:g} mm; {in_guess} mm in {guess}): it looks like "
                     f"{UNIT_WORDS[guess]}; the file says {unit}; use --units {guess}",
                     source=source, field=field)


def _mm(value: float) -> str:
    """A length in mm for a message: ``18,000``, ``152``, ``0.18``."""
    return f"{value:,.0f}" if value >= 100 else f"{value:.3g}"


def parse_axes(spec: str, *, field: str = "axes") -> np.ndarray:
    """The matrix (3, 3) taking a file's coordinates to facemech's, from an axes string.

    Parameters
    ----------
    spec : three comma-separated signed axis names, for facemech's x (left), y (up) and z
        (forward) in turn: ``"x,z,-y"``; ``"-x,y,z"`` un-mirrors a left-handed scan

    Returns
    -------
    (3, 3) signed permutation matrix ``R``: facemech point ``= R @ file point``

    Raises
    ------
    InputError
        Not three axes, an unknown name, or an axis named twice.
    """
    words = [w.strip().lower() for w in str(spec).split(",")]
    rows = []
    for w in words:
        sign = -1.0 if w.startswith("-") else 1.0
        name = w.lstrip("+-")
        if name not in ("x", "y", "z") or len(w) - len(name) > 1:
            raise InputError(f"axes {spec!r}: {w!r} is not an axis (x, y, z with an optional "
                             "sign)", field=field)
        row = np.zeros(3)
        row["xyz".index(name)] = sign
        rows.append(row)
    r = np.array(rows)
    if len(rows) != 3 or not np.allclose(np.abs(r).sum(axis=0), 1.0):
        raise InputError(f"axes {spec!r}: name each of x, y and z once, for facemech's left, up "
                         "and forward (e.g. x,z,-y)", field=field)
    return r


def axes_text(r: np.ndarray) -> str:
    """The axes string of a signed permutation matrix (the inverse of :func:`parse_axes`)."""
    out = []
    for row in np.asarray(r):
        j = int(np.argmax(np.abs(row)))
        out.append(("-" if row[j] < 0 else "") + "xyz"[j])
    return ",".join(out)


def landmark_directions(landmarks: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The face's up and forward unit vectors (3,), in the landmarks' own frame.

    Up runs from the chin (and menton) to the brows; forward from the mouth corners, cheeks and
    jaw angles to the nose tip, less its part along up. Both use only midline points and the
    midpoints of left-right pairs, so they hold whether or not the sides are swapped.
    """
    def mean(names):
        return np.mean([np.asarray(landmarks[n], float) for n in names], axis=0)

    up = mean(_TOP_PAIR) - mean(_BOTTOM)
    up = up / np.linalg.norm(up)
    fwd = np.asarray(landmarks[_FRONT], float) - mean([n for p in _BACK_PAIRS for n in p])
    fwd = fwd - (fwd @ up) * up
    return up, fwd / np.linalg.norm(fwd)


def detect_axes(landmarks: dict[str, np.ndarray], *, source: str | None = None,
                max_tilt_deg: float = MAX_TILT_DEG) -> np.ndarray:
    """The rotation (3, 3) taking the scan's axes to facemech's, detected from its landmarks.

    The nearest file axes (with signs) to the landmarks' up and forward become +y and +z, and
    +x is their cross product: a proper rotation (a signed permutation), never a mirror; a
    mirrored scan is then found by :func:`~facemech.geometry.landmark_checks.check_left_is_left`.

    Raises
    ------
    InputError
        Field ``axes``: up or forward more than ``max_tilt_deg`` from every axis of the file, or
        both nearest the same axis.
    """
    up, fwd = landmark_directions(landmarks)
    rows = []
    for what, v in (("up", up), ("forward", fwd)):
        j = int(np.argmax(np.abs(v)))
        tilt = float(np.degrees(np.arccos(min(1.0, abs(v[j])))))
        if tilt > max_tilt_deg:
            raise InputError(f"the face's {what} direction (from the landmarks) is {tilt:.0f} "
                             f"degrees from every axis of the scan: straighten the scan or give "
                             "--axes", source=source, field="axes")
        row = np.zeros(3)
        row[j] = np.sign(v[j])
        rows.append(row)
    y, z = rows
    if abs(y @ z) > 0.5:
        raise InputError("the landmarks give the same axis for up and forward", source=source,
                         field="axes")
    return np.array([np.cross(y, z), y, z])


def check_axes(landmarks: dict[str, np.ndarray], *, spec: str, source: str | None = None,
               max_deg: float = MAX_AXES_DISAGREEMENT_DEG) -> None:
    """Refuse landmarks (already in facemech's axes by ``--axes spec``) whose up or forward is
    more than ``max_deg`` from +y or +z: the given axes do not fit this scan."""
    up, fwd = landmark_directions(landmarks)
    for what, v, k in (("up", up, 1), ("forward", fwd, 2)):
        angle = float(np.degrees(np.arccos(np.clip(v[k], -1.0, 1.0))))
        if angle > max_deg:
            raise InputError(f"with --axes {spec} the face's {what} direction (from the "
                             f"landmarks) is {angle:.0f} degrees from facemech's "
                             f"+{'xyz'[k]}: those axes do not fit this scan", source=source,
                             field="axes")
