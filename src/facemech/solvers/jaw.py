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


#: the held jaw angles of :func:`skin_drop_curve` (rad) and the frames each is held
CURVE_ANGLES = np.radians([4.0, 8.0, 13.0, 19.0])
CURVE_HOLD_FRAMES = 48
_CURVES: dict = {}


def skin_drop_curve(model, params, node: int) -> tuple[np.ndarray, np.ndarray]:
    """How an epidermal node moves down as the jaw opens, at rest, in the tissue of a preset.

    The jaw is opened in steps (4, 8, 13 and 19 degrees, each held 0.8 s, no muscle active) and
    the node's vertical displacement read at the end of each hold, where the tissue has settled:
    (angles rad, drops m, negative down), from 0, increasing. In the seeds' thin tissue the skin
    moves with the bone under it; in the anatomical tissue (14 mm of it over the chin, whose pad
    slides on the bone) it does not, so a chin marker on the skin must be matched by the skin's
    own response. Cached per face, preset and node.
    """
    from .forward import simulate

    key = (id(model), repr(params), int(node))
    hit = _CURVES.get(key)
    if hit is not None and hit[0] is model:
        return hit[1], hit[2]
    angles = np.repeat(CURVE_ANGLES, CURVE_HOLD_FRAMES)
    angles = np.concatenate([[0.0], angles])
    sim = simulate(model, np.zeros((len(angles), 16)), angles, params=params)
    ends = np.arange(1, len(CURVE_ANGLES) + 1) * CURVE_HOLD_FRAMES
    drop = sim.positions[ends, node, 1] - sim.positions[0, node, 1]
    out = (np.concatenate([[0.0], CURVE_ANGLES]),
           np.minimum.accumulate(np.concatenate([[0.0], drop])))
    _CURVES[key] = (model, *out)
    if len(_CURVES) > 16:
        _CURVES.pop(next(iter(_CURVES)))
    return out


def jaw_angles_from_marker(model, params, node: int, marker_y: np.ndarray, *,
                           lead: int = JAW_LEAD_SAMPLES, bite_block: bool = False,
                           source: str | None = None) -> np.ndarray:
    """Jaw angles (rad) per frame from a chin marker's vertical position (m) on the skin.

    ``node`` is the marker's epidermal node. With the seeds' tissue the angle is the one that
    gives the skull node under the marker the marker's displacement (Lucero & Munhall 1999,
    :func:`angles_from_chin`); with the anatomical tissue, the one that gives the skin node that
    displacement in the tissue's quasi-static response to the jaw (:func:`skin_drop_curve`).
    Upward displacements (closing past rest) follow the curve's slope at rest. The lead and the
    bite block act as in :func:`angles_from_chin`.
    """
    from ..geometry.builder import for_tissue

    model = for_tissue(model, params.tissue)
    marker_y = np.asarray(marker_y, float)
    if not params.is_continuum:
        return angles_from_chin(marker_y, model.rest_positions[node + 2 * model.n_surface],
                                model.hinge_point, model.hinge_axis, lead=lead,
                                bite_block=bite_block)
    if marker_y.ndim != 1 or len(marker_y) == 0:
        raise InputError("chin trajectory must be a non-empty 1-D series", source=source,
                         field="chin")
    if not np.all(np.isfinite(marker_y)):
        bad = int(np.nonzero(~np.isfinite(marker_y))[0][0])
        raise InputError(f"chin trajectory has a gap at sample {bad}", source=source,
                         field="chin")
    angles, drop = skin_drop_curve(model, params, node)
    d = marker_y - marker_y[0]
    if d.min() < 1.25 * drop[-1]:
        raise InputError(f"a chin drop of {-d.min() * 1e3:.1f} mm is more than the jaw opens "
                         f"({np.degrees(angles[-1]):.0f} degrees drop the chin "
                         f"{-drop[-1] * 1e3:.1f} mm)", source=source, field="chin")
    from scipy.interpolate import PchipInterpolator

    # a monotone curve through the settled points; beyond the last, and for rises above rest,
    # the end slopes carry on
    curve = PchipInterpolator(-drop, angles, extrapolate=True)
    slope = (drop[1] - drop[0]) / (angles[1] - angles[0])
    out = np.where(d <= 0, curve(np.minimum(-d, -drop[-1] * 1.25)), d / slope)
    if np.any(out < -MAX_JAW_ANGLE):
        raise InputError("the chin rises more than the jaw can close", source=source,
                         field="chin")
    if lead > 0:
        out = np.concatenate([out[lead:], np.repeat(out[-1:], min(lead, len(out)))])[
            : len(marker_y)]
    if bite_block:
        out = np.full_like(out, out[0])
    return out
