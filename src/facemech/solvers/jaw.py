"""The jaw: a kinematic hinge (Lucero & Munhall 1999, II.C).

The skull nodes of the mandible rotate about a horizontal axis through the condyles. Positive
angles open the mouth (the chin moves down and back). The angle of each frame can come from a
chin-marker trajectory: the angle that gives the chin node the marker's vertical displacement
from rest, applied two 60-Hz samples (33 ms) early to make up for the delay of propagation from
the skull to the skin.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..errors import InputError

JAW_LEAD_SAMPLES = 2  #: 33 ms at 60 Hz
MAX_JAW_ANGLE = np.radians(30.0)


def rotation_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def rotate_about(points: np.ndarray, point: np.ndarray, axis: np.ndarray,
                 angle: float) -> np.ndarray:
    """Points (..., 3) rotated by ``angle`` about the line through ``point`` along ``axis``."""
    r = rotation_matrix(axis, angle)
    return (np.asarray(points) - point) @ r.T + point


def angle_for_drop(node_rest: np.ndarray, point: np.ndarray, axis: np.ndarray,
                   drop: float) -> float:
    """Hinge angle (rad) that moves ``node_rest`` by ``drop`` metres along y (negative: down)."""
    def f(th):
        return rotate_about(node_rest, point, axis, th)[1] - node_rest[1] - drop

    lo, hi = -MAX_JAW_ANGLE, MAX_JAW_ANGLE
    if f(lo) * f(hi) > 0:
        raise InputError(f"a vertical chin displacement of {drop * 1e3:.1f} mm cannot be reached "
                         "by the jaw hinge", field="chin")
    return float(brentq(f, lo, hi, xtol=1e-10))


def angles_from_chin(chin_y: np.ndarray, chin_node_rest: np.ndarray, hinge_point: np.ndarray,
                     hinge_axis: np.ndarray, *, lead: int = JAW_LEAD_SAMPLES,
                     bite_block: bool = False) -> np.ndarray:
    """Jaw angles (rad) per 60-Hz frame from a chin marker's vertical position (metres).

    The displacement is taken from the first (rest) sample. ``lead`` shifts the series earlier by
    that many samples (the last value is held). With ``bite_block`` the angle stays at its
    initial value.
    """
    chin_y = np.asarray(chin_y, float)
    if chin_y.ndim != 1 or len(chin_y) == 0:
        raise InputError("chin trajectory must be a non-empty 1-D series", field="chin")
    if not np.all(np.isfinite(chin_y)):
        bad = int(np.nonzero(~np.isfinite(chin_y))[0][0])
        raise InputError(f"chin trajectory has a gap at sample {bad}", field="chin")
    drops = chin_y - chin_y[0]
    angles = np.array([angle_for_drop(chin_node_rest, hinge_point, hinge_axis, d)
                       for d in drops])
    if lead > 0:
        angles = np.concatenate([angles[lead:], np.repeat(angles[-1:], min(lead, len(angles)))])
        angles = angles[: len(chin_y)]
    if bite_block:
        angles = np.full_like(angles, angles[0])
    return angles
