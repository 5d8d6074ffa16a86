"""Landmark plausibility: on the skin, one point each, and the subject's left on the left.

A landmark file that reads without complaint can still be wrong: a landmark typed 100 mm off,
one point copied under two names, the left and right sides swapped (or a mirrored scan). Each
builds a face with a different jaw and muscles, so each is refused here with one line naming
the landmark file and the landmark.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .closest import closest_points

#: m, the farthest a landmark may lie from the surface
MAX_OFF_SURFACE_M = 5e-3
#: m, two landmarks closer than this are the same point given twice
MIN_SEPARATION_M = 1e-3
#: (subject's left, subject's right) pairs that the left-is-left check compares, first present
#: pair first
SIDE_PAIRS: tuple[tuple[str, str], ...] = (
    ("mouth_corner_left", "mouth_corner_right"), ("eye_left", "eye_right"),
    ("brow_left", "brow_right"), ("cheek_left", "cheek_right"),
    ("jaw_angle_left", "jaw_angle_right"),
)  # fmt: skip


def check_landmarks(vertices: np.ndarray, faces: np.ndarray, landmarks: dict[str, np.ndarray],
                    *, source: str | None = None,
                    max_off_m: float = MAX_OFF_SURFACE_M,
                    min_separation_m: float = MIN_SEPARATION_M) -> dict[str, float]:
    """Refuse landmarks off the surface, given twice, or with left and right swapped.

    Parameters
    ----------
    vertices : (n, 3) surface vertices, metres, in facemech's axes (+x the subject's left,
        +y up, +z forward)
    faces : (f, 3) int triangles
    landmarks : name -> (3,) metres, same frame
    source : the landmark file, for the message
    max_off_m, min_separation_m : the limits, metres

    Returns
    -------
    dict name -> distance from the surface, metres

    Raises
    ------
    InputError
        Field: the landmark. A landmark farther than ``max_off_m`` from the surface (its
        distance in mm), two landmarks closer than ``min_separation_m`` (both named), or a
        left landmark to the subject's right of its right twin.
    """
    names = list(landmarks)
    pts = np.array([landmarks[n] for n in names], float).reshape(-1, 3)
    _, dist = closest_points(pts, vertices, faces)
    worst = int(np.argmax(dist)) if len(dist) else 0
    if len(dist) and dist[worst] > max_off_m:
        raise InputError(f"landmark {names[worst]!r} lies {dist[worst] * 1e3:.1f} mm from the "
                         f"surface (at most {max_off_m * 1e3:g} mm): a typing error, another "
                         "unit, or landmarks of another scan", source=source,
                         field=names[worst])
    check_unique(names, pts, source=source, min_separation_m=min_separation_m)
    check_left_is_left(landmarks, source=source)
    return dict(zip(names, map(float, dist), strict=True))


def check_unique(names: list[str], points: np.ndarray, *, source: str | None = None,
                 min_separation_m: float = MIN_SEPARATION_M) -> None:
    """Refuse two landmarks closer than ``min_separation_m`` (points (k, 3), metres)."""
    if len(points) < 2:
        return
    d = np.linalg.norm(points[:, None] - points[None], axis=-1)
    d[np.tril_indices(len(points))] = np.inf
    i, j = np.unravel_index(int(np.argmin(d)), d.shape)
    if d[i, j] < min_separation_m:
        raise InputError(f"landmarks {names[i]!r} and {names[j]!r} are {d[i, j] * 1e3:.2f} mm "
                         f"apart: one point given twice (at least {min_separation_m * 1e3:g} mm "
                         "apart expected)", source=source, field=names[j])


def check_left_is_left(landmarks: dict[str, np.ndarray], *, source: str | None = None) -> None:
    """Refuse a left landmark at smaller x than its right twin (+x is the subject's left).

    In facemech's right-handed frame (+y up, +z forward) the subject's left is +x; a left
    landmark on the -x side means the two sides were swapped in the landmark file, or the scan
    is mirrored (written in a left-handed frame).
    """
    for left, right in SIDE_PAIRS:
        if left in landmarks and right in landmarks:
            xl, xr = float(landmarks[left][0]), float(landmarks[right][0])
            if xl <= xr:
                raise InputError(
                    f"{left!r} (x {xl * 1e3:.1f} mm) is not to the subject's left of {right!r} "
                    f"(x {xr * 1e3:.1f} mm): the left and right landmarks are swapped, or the "
                    "scan is mirrored (then give the axes, e.g. --axes=-x,y,z)",
                    source=source, field=left)
