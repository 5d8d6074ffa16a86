"""A face scan as it comes, read and checked into what the builder needs.

:func:`load_scan` is the path from the files a lab has (a surface in any of the usual units and
axes, with fragments and texture seams; facemech or iBUG-68 landmarks) to a surface and
landmarks in metres and facemech's axes, each step refusing in one line what it cannot use:

1. read the surface (texture seams merged, :mod:`surface_io`);
2. the unit: the declared one must make the scan face-sized, or none is declared and the size
   gives it (:mod:`scan_frame`);
3. the landmarks: facemech's CSV, or 68 iBUG points (:mod:`ibug`) in the same unit;
4. loose fragments dropped (:mod:`scan_cleanup`);
5. the axes: detected from the landmarks and the scan turned to them, or given (``axes``);
   then a head cropped to the face (hairline, under the chin, the ears), and a surface still
   closed refused (:mod:`scan_cleanup`);
6. a mouth open in the middle refused; the landmarks on the skin, unique, the left on the left
   (:mod:`landmark_checks`);
7. a coarse mouth region refined to the lips' spacing (:mod:`refine`);
8. no degenerate triangles (:mod:`scan_cleanup`);
9. the vertices numbered from the top of the face down, as the force kernel's threads read
   them fastest (:mod:`scan_order`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import length_scale
from .appearance import Appearance


@dataclass(frozen=True)
class Scan:
    """A face surface and its landmarks, checked, in metres and facemech's axes.

    Attributes
    ----------
    vertices : (n, 3) float array, metres (+x the subject's left, +y up, +z forward)
    faces : (f, 3) int array
    landmarks : name -> (3,) metres
    appearance : texture or vertex colours, or None
    unit : the file's length unit (declared or inferred)
    axes : the axes string that took the file to facemech's frame (``"x,y,z"`` when none)
    notes : what was done to the scan, one line each (the command prints them on stderr)
    """

    vertices: np.ndarray
    faces: np.ndarray
    landmarks: dict[str, np.ndarray]
    appearance: Appearance | None
    unit: str
    axes: str
    notes: list[str] = field(default_factory=list)


def load_scan(surface: str | Path, landmarks: str | Path, *, units: str | None = "mm",
              axes: str | None = None) -> Scan:
    """Read a face scan and its landmarks; check and normalise them for :func:`build_face`.

    Parameters
    ----------
    surface : OBJ (with MTL and texture), PLY or STL
    landmarks : facemech landmark CSV ``name,x,y,z``, or 68 iBUG points (``.pts``, menpo
        ``.ljson``, or a CSV of 68 rows ``x,y,z``), in the surface's unit and axes
    units : the length unit of both files (``m``, ``cm``, ``mm``, ``um``); None infers it from
        the scan's size (and says so in a note)
    axes : the file's axes for facemech's x (left), y (up), z (forward), e.g. ``"x,z,-y"``
        (:func:`~facemech.geometry.scan_frame.parse_axes`); None detects them from the landmarks

    Returns
    -------
    Scan

    Raises
    ------
    InputError
        One line naming the file and the field: the unit disagrees with the size; landmarks in
        another unit, off the skin, given twice or with the sides swapped (or a mirrored scan);
        a tilted scan; the surface in several large pieces, closed, or with degenerate
        triangles.
    """
    from .landmark_checks import check_landmarks
    from .refine import refine_perioral
    from .scan_cleanup import (
        check_mouth_closed,
        check_open,
        check_triangles,
        crop_to_face,
        drop_fragments,
    )
    from .scan_frame import check_unit
    from .scan_order import top_down
    from .surface_io import read_surface_with_appearance

    surface, landmarks = Path(surface), Path(landmarks)
    src, lm_src = str(surface), str(landmarks)
    notes: list[str] = []
    raw, faces, look = read_surface_with_appearance(surface, units="m")  # the file's numbers
    unit = check_unit(float(np.ptp(raw, axis=0).max()), units, source=src)
    if units is None:
        notes.append(f"{surface.name}: read in {unit} (from its size)")
    vertices = raw * length_scale(unit)
    vertices, faces, look, note = drop_fragments(vertices, faces, look, source=src)
    if note:
        notes.append(f"{surface.name}: {note}")
    lm = _read_scan_landmarks(landmarks, vertices, faces, unit, notes)
    vertices, lm, spec = _turned(vertices, lm, axes, surface.name, lm_src, notes)
    vertices, faces, look, note = crop_to_face(vertices, faces, lm, look)
    if note:
        notes.append(f"{surface.name}: {note}")
    check_open(faces, source=src)
    check_mouth_closed(vertices, faces, lm, source=src)
    check_landmarks(vertices, faces, lm, source=lm_src)
    vertices, faces, look, note = refine_perioral(vertices, faces, lm, look)
    if note:
        notes.append(f"{surface.name}: {note}")
    check_triangles(vertices, faces, lm, source=src)
    vertices, faces, look = top_down(vertices, faces, look)
    return Scan(vertices, faces, lm, look, unit, spec, notes)


def _read_scan_landmarks(landmarks: Path, vertices, faces, unit: str, notes: list) -> dict:
    """A scan's landmarks (name -> (3,) m): facemech's CSV, or 68 iBUG points mapped to
    facemech's names (said in ``notes``); both checked against the surface's unit."""
    from .ibug import ibug_to_landmarks, is_ibug_file, read_ibug68
    from .surface_io import read_landmarks

    lm_src = str(landmarks)
    if is_ibug_file(landmarks):
        points = read_ibug68(landmarks, units=unit)
        check_landmark_unit(points, vertices, unit, source=lm_src)
        notes.append(f"{landmarks.name}: 68 iBUG points mapped to facemech's landmarks")
        return ibug_to_landmarks(points, vertices, faces)
    lm = read_landmarks(landmarks, units=unit)
    check_landmark_unit(np.array(list(lm.values())), vertices, unit, source=lm_src)
    return lm


def _turned(vertices, lm: dict, axes: str | None, name: str, lm_src: str, notes: list):
    """The surface and landmarks in facemech's axes, from ``axes`` or detected from the
    landmarks (said in ``notes``); (vertices, landmarks, the axes' text)."""
    from .scan_frame import axes_text, check_axes, detect_axes, parse_axes

    if axes is None:
        turn = detect_axes(lm, source=lm_src)
        spec = axes_text(turn)
        if spec != "x,y,z":
            notes.append(f"{name}: turned to facemech's axes (x left, y up, z forward) "
                         f"from the landmarks, as --axes {spec}")
    else:
        turn = parse_axes(axes)
        spec = axes_text(turn)
    if spec != "x,y,z":
        vertices = vertices @ turn.T
        lm = {k: turn @ v for k, v in lm.items()}
    if axes is not None:
        check_axes(lm, spec=spec, source=lm_src)
    return vertices, lm, spec


def check_landmark_unit(points: np.ndarray, vertices: np.ndarray, unit: str, *,
                        source: str | None = None) -> None:
    """Refuse landmarks whose spread says they are in another unit than the surface.

    The landmarks of a face span about half to all of its scan; a ratio near a power of ten
    away from that means the landmark file is in another unit (field ``units``).
    """
    from ..units import LENGTH_TO_M

    span = float(np.ptp(points, axis=0).max())
    whole = float(np.ptp(vertices, axis=0).max())
    ratio = span / whole if whole > 0 else 1.0
    if 0.15 <= ratio <= 2.0:
        return
    # the unit that brings the landmarks' spread to about 0.6 of the scan's
    file_numbers = span / LENGTH_TO_M[unit]
    guess = min(LENGTH_TO_M, key=lambda u: abs(np.log(file_numbers * LENGTH_TO_M[u]
                                                      / (0.6 * whole))))
    hint = f"; they look like {guess}" if guess != unit else ""
    raise InputError(f"the landmarks span {span * 1e3:.4g} mm and the surface "
                     f"{whole * 1e3:.4g} mm read in {unit}: the landmark file is in another "
                     f"unit{hint}", source=source, field="units")
