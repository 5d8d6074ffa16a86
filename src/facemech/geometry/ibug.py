"""The iBUG 68-point landmarks (dlib, face-alignment, menpo) read and mapped to facemech's names.

Indices are 0-based here (the ``.pts`` files' rows in order; the iBUG papers count from 1, so
add 1 to compare with their figures). Point 0 is on the subject's right (the image's left), 8
is the bottom of the chin, 16 on the subject's left.

Ten facemech landmarks are iBUG points (:data:`DIRECT`) and the stomion the middle of the inner
lips (62 and 66). The other seven (the chin, cheeks, jaw angles and eye centres) have no iBUG
point: they are carried from the generic face by the thin-plate spline that takes the generic
face's iBUG points (:func:`generic_ibug68`) onto the subject's, then put on the surface. On the
generic face itself the mapping gives its own landmarks back.

Only 3-D points (x, y, z in the surface's frame and unit) can place landmarks on a scan; 2-D
image points are refused.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import length_scale
from . import generic

N_POINTS = 68
#: facemech name -> iBUG index (0-based)
DIRECT: dict[str, int] = {
    "nasion": 27, "nose_tip": 30, "subnasale": 33, "upper_lip_center": 51,
    "lower_lip_center": 57, "mouth_corner_right": 48, "mouth_corner_left": 54, "menton": 8,
    "brow_right": 19, "brow_left": 24,
}  # fmt: skip
#: the stomion: the middle of the inner lips, upper (62) and lower (66)
STOMION = (62, 66)
#: facemech landmarks carried from the generic face by the spline over the iBUG points
WARPED = ("chin", "cheek_left", "cheek_right", "jaw_angle_left", "jaw_angle_right", "eye_left",
          "eye_right")
#: the iBUG points the spline is fitted to: all but the inner lips (they coincide when the mouth
#: is closed)
SPLINE_POINTS = np.arange(60)


def _generic_xy() -> np.ndarray:
    """The 68 iBUG points on the generic face, frontal (x, y) mm (+x the subject's left)."""
    k = np.arange(9)
    theta = np.pi + 0.5 * np.pi * k / 8  # the jaw line, from the right ear (0) to the chin (8)
    right_jaw = np.column_stack([62.0 * np.cos(theta), -10.0 + 112.0 * np.sin(theta)])
    jaw = np.concatenate([right_jaw, right_jaw[:-1][::-1] * [-1.0, 1.0]])
    right_brow = np.array([[-48, 8], [-40, 12], [-30, 13], [-21, 12], [-13, 10]], float)
    left_brow = right_brow[::-1] * [-1.0, 1.0]
    nose = np.array([[0, 0], [0, -13], [0, -26], [0, -40], [-13, -48], [-7, -50], [0, -52],
                     [7, -50], [13, -48]], float)
    right_eye = np.array([[-44, -3], [-37, 1], [-27, 1], [-20, -3], [-27, -7], [-37, -7]], float)
    left_eye = np.array([[20, -3], [27, 1], [37, 1], [44, -3], [37, -7], [27, -7]], float)
    m, s = generic.MOUTH_HALF_WIDTH, generic.Y_STOMION
    outer = np.array([[-m, s], [-16, -68], [-6, -64.5], [0, -64], [6, -64.5], [16, -68], [m, s],
                      [16, -79], [6, -81.5], [0, -82], [-6, -81.5], [-16, -79]], float)
    inner = np.array([[-20, s], [-8, s], [0, s], [8, s], [20, s], [8, s], [0, s], [-8, s]])
    return np.concatenate([jaw, right_brow, left_brow, nose, right_eye, left_eye, outer, inner])


def generic_ibug68() -> np.ndarray:
    """The generic face's 68 iBUG points (68, 3), metres, on its surface."""
    xy = _generic_xy()
    return generic.surface_point(xy[:, 0], xy[:, 1]) * 1e-3


def ibug_to_landmarks(points: np.ndarray, vertices: np.ndarray | None = None,
                      faces: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """facemech's 18 landmarks from 68 iBUG points.

    Parameters
    ----------
    points : (68, 3) iBUG points, metres, in the surface's frame (any axes)
    vertices, faces : the surface (metres), to put the derived landmarks on it; without it they
        stay where the spline puts them

    Returns
    -------
    dict name -> (3,) metres, in :data:`generic.LANDMARK_XY`'s order
    """
    from scipy.interpolate import RBFInterpolator

    from .closest import closest_points
    from .warp import generic_landmarks

    points = np.asarray(points, float)
    gen = generic_ibug68()
    src, dst = gen[SPLINE_POINTS], points[SPLINE_POINTS]
    spline = RBFInterpolator(src, dst - src, kernel="thin_plate_spline", degree=1)
    lm_gen = generic_landmarks()
    derived = {n: lm_gen[n] + spline(lm_gen[n][None])[0] for n in WARPED}
    derived["stomion"] = points[list(STOMION)].mean(axis=0)
    if vertices is not None and faces is not None:
        names = list(derived)
        on, _ = closest_points(np.array([derived[n] for n in names]), vertices, faces)
        derived = dict(zip(names, on, strict=True))
    out = {n: points[DIRECT[n]] for n in DIRECT}
    out.update(derived)
    return {n: np.asarray(out[n], float) for n in generic.LANDMARK_XY}


# ---- files -----------------------------------------------------------------------------------
def _checked(points: np.ndarray, source: str, field: str) -> np.ndarray:
    """68 finite 3-D points, or the one-line error."""
    if points.ndim != 2 or len(points) != N_POINTS:
        raise InputError(f"{len(points)} points; the iBUG convention has {N_POINTS}",
                         source=source, field=field)
    if points.shape[1] == 2:
        raise InputError("2-D iBUG points (image coordinates) cannot place landmarks on a scan: "
                         "give x, y, z on the surface (3-D landmarks, e.g. face-alignment's 3D "
                         "mode, or 2-D points projected onto the scan)", source=source,
                         field=field)
    if points.shape[1] != 3:
        raise InputError(f"points with {points.shape[1]} coordinates; expected x, y, z",
                         source=source, field=field)
    if not np.all(np.isfinite(points)):
        k = int(np.argmax(~np.all(np.isfinite(points), axis=1)))
        raise InputError(f"point {k} (0-based) is missing or not finite", source=source,
                         field=field)
    return points


def read_pts(path: str | Path) -> np.ndarray:
    """The points of an iBUG ``.pts`` file (``version: 1``, ``n_points: 68``, ``{ x y z ... }``),
    (68, 3) in the file's unit."""
    path = Path(path)
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise InputError("not a text file", source=str(path), field="points") from None
    head, brace, rest = text.partition("{")
    body, close, _ = rest.partition("}")
    if not brace or not close:
        raise InputError("no '{ ... }' block of points", source=str(path), field="points")
    declared = None
    for line in head.splitlines():
        key, _, value = line.partition(":")
        if key.strip().lower() == "n_points":
            try:
                declared = int(value)
            except ValueError:
                raise InputError(f"n_points {value.strip()!r} is not a number",
                                 source=str(path), field="n_points") from None
    rows = [ln.split() for ln in body.splitlines() if ln.strip()]
    if len({len(r) for r in rows}) > 1:
        raise InputError("rows with different numbers of coordinates", source=str(path),
                         field="points")
    try:
        points = np.array(rows, float).reshape(len(rows), -1)
    except ValueError:
        raise InputError("coordinates are not numbers", source=str(path),
                         field="points") from None
    if declared is not None and declared != len(points):
        raise InputError(f"n_points says {declared}, the file holds {len(points)}",
                         source=str(path), field="n_points")
    return _checked(points, str(path), "points")


def read_ljson(path: str | Path) -> np.ndarray:
    """The points of a menpo ``.ljson`` file (versions 1, 2 and 3, ordered by their labels:
    :mod:`scan_ljson`), (68, 3) in the file's unit."""
    from .scan_ljson import read_ljson_points

    path = Path(path)
    found = read_ljson_points(path)
    points = found.points
    if points.shape[1] == 3 and not np.all(np.isfinite(points)):
        k = int(np.argmax(~np.all(np.isfinite(points), axis=1)))
        raise InputError(f"iBUG point {k} (0-based; row {int(found.rows[k])} of the file) is "
                         "null or not finite: every point must be on the scan", source=str(path),
                         field=found.field)
    return _checked(points, str(path), found.field)


def read_ibug_csv(path: str | Path) -> np.ndarray:
    """The points of a CSV of 68 rows ``x,y,z``: with a header (an optional ``index`` or
    ``name`` column holding 0-67 or 1-68 orders the rows) or without one; (68, 3)."""
    path = Path(path)
    try:
        rows = [r for r in csv.reader(path.read_text().splitlines()) if any(c.strip() for c in r)]
    except UnicodeDecodeError:
        raise InputError("not a text file", source=str(path), field="points") from None
    if not rows:
        raise InputError("no points", source=str(path), field="points")
    header = [c.strip().lower() for c in rows[0]]
    if all(_is_number(c) for c in header):
        header, body = [], rows
    else:
        body = rows[1:]
    index = None
    if header:
        coords = [c for c in ("x", "y", "z") if c in header]
        if coords[:2] != ["x", "y"]:
            raise InputError("missing column", source=str(path), field="x")
        cols = [header.index(c) for c in coords]
        label = next((header.index(c) for c in ("index", "name", "point") if c in header), None)
        if label is not None:
            index = [r[label].strip() for r in body]
    else:
        cols = list(range(len(rows[0])))
    try:
        points = np.array([[float(r[c]) for c in cols] for r in body])
    except (ValueError, IndexError):
        raise InputError("coordinates are not numbers", source=str(path),
                         field="points") from None
    points = _checked(points.reshape(len(body), -1), str(path), "points")
    if index is not None:
        try:
            k = np.array([int(i) for i in index])
        except ValueError:
            raise InputError("the index column must hold the point numbers 0-67 or 1-68",
                             source=str(path), field="index") from None
        k = k - k.min()
        if sorted(k.tolist()) != list(range(N_POINTS)):
            raise InputError("the index column must number the points 0-67 or 1-68, once each",
                             source=str(path), field="index")
        points = points[np.argsort(k)]
    return points


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_ibug68(path: str | Path, *, units: str = "mm") -> np.ndarray:
    """68 iBUG points (68, 3), metres, from a ``.pts``, ``.ljson`` or CSV file in ``units``."""
    path = Path(path)
    scale = length_scale(units, source=str(path))
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    suffix = path.suffix.lower()
    reader = {".pts": read_pts, ".ljson": read_ljson}.get(suffix, read_ibug_csv)
    return reader(path) * scale


def is_ibug_file(path: str | Path) -> bool:
    """Whether a landmark file holds iBUG points: a ``.pts`` or ``.ljson`` file, or a CSV whose
    header has no ``name`` column of facemech landmark names."""
    path = Path(path)
    if path.suffix.lower() in (".pts", ".ljson"):
        return True
    try:
        with path.open(newline="") as fh:
            first = next(csv.reader(fh), [])
            second = next(csv.reader(fh), [])
    except (OSError, UnicodeDecodeError):
        return False
    header = [c.strip().lower() for c in first]
    if "name" not in header:
        return True
    name = second[header.index("name")].strip() if len(second) > header.index("name") else ""
    return name not in generic.LANDMARK_XY and _is_number(name)


def write_pts(path: str | Path, points: np.ndarray) -> None:
    """Write 68 points (metres) as an iBUG ``.pts`` file in mm (3 coordinates a row)."""
    from ..atomic import atomic_path

    points = np.asarray(points, float) * 1e3
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(f"version: 1\nn_points: {len(points)}\n{{\n")
        fh.writelines(" ".join(f"{c:.6f}" for c in p) + "\n" for p in points)
        fh.write("}\n")
