"""Jaw drives that run the simulator: a chin marker on the skin gives the jaw's angle.

In the seeds' thin tissue the skin moves with the bone under it, so a chin marker gives the
angle directly (:func:`facemech.solvers.jaw.angles_from_chin`); in the anatomical tissue the
skin's own response to the jaw is measured first, by running the face
(:func:`skin_drop_curve`), and inverted (:func:`jaw_angles_from_marker`). This module sits above
:mod:`facemech.solvers.forward`; the jaw's kinematics (:mod:`facemech.solvers.jaw`) below it.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..errors import InputError
from ..params import MUSCLE_GROUPS
from .forward import simulate
from .jaw import JAW_LEAD_SAMPLES, MAX_JAW_ANGLE, _lead, angles_from_chin, glide_of

__all__ = ["clear_curves", "jaw_angles_from_marker", "skin_drop_curve"]


#: the held jaw angles of :func:`skin_drop_curve` (rad) and the frames each is held
CURVE_ANGLES = np.radians([4.0, 8.0, 13.0, 19.0])
CURVE_HOLD_FRAMES = 48
#: the curves computed: (id of the face, preset, node) -> (angles, drops). An entry lives as long
#: as its face: a finalizer removes it when the face is collected, so a new face that reuses
#: the id never finds an old face's curve (:func:`clear_curves` empties it)
_CURVES: dict = {}


def clear_curves() -> None:
    """Forget every :func:`skin_drop_curve` computed so far."""
    _CURVES.clear()


def skin_drop_curve(model, node: int) -> tuple[np.ndarray, np.ndarray]:
    """How an epidermal node moves down as the jaw opens, at rest, in the tissue of a preset.

    The jaw is opened in steps (4, 8, 13 and 19 degrees, each held 0.8 s, no muscle active) and
    the node's vertical displacement read at the end of each hold, where the tissue has settled:
    (angles rad, drops m, negative down), from 0, increasing. In the seeds' thin tissue the skin
    moves with the bone under it; in the anatomical tissue (14 mm of it over the chin, whose pad
    slides on the bone) it does not, so a chin marker on the skin must be matched by the skin's
    own response. ``model``: a :class:`~facemech.physics.model.Model`. Cached per face, preset
    and node while the face lives (:data:`_CURVES`).
    """
    face, params = model.face, model.params
    key = (id(face), repr(params), int(node))
    hit = _CURVES.get(key)
    if hit is not None:
        return hit
    angles = np.repeat(CURVE_ANGLES, CURVE_HOLD_FRAMES)
    angles = np.concatenate([[0.0], angles])
    sim = simulate(model, np.zeros((len(angles), len(MUSCLE_GROUPS))), angles)
    ends = np.arange(1, len(CURVE_ANGLES) + 1) * CURVE_HOLD_FRAMES
    drop = sim.positions[ends, node, 1] - sim.positions[0, node, 1]
    out = (np.concatenate([[0.0], CURVE_ANGLES]),
           np.minimum.accumulate(np.concatenate([[0.0], drop])))
    _CURVES[key] = out
    weakref.finalize(face, _CURVES.pop, key, None)
    if len(_CURVES) > 16:
        _CURVES.pop(next(iter(_CURVES)))
    return out


def jaw_angles_from_marker(model, node: int, marker_y: np.ndarray, *,
                           lead: int = JAW_LEAD_SAMPLES, bite_block: bool = False,
                           source: str | None = None) -> np.ndarray:
    """Jaw angles (rad) per frame from a chin marker's vertical position (m) on the skin.

    ``model`` is a :class:`~facemech.physics.model.Model`; ``node`` the marker's epidermal
    node. With the seeds' tissue the angle is the one that
    gives the skull node under the marker the marker's displacement (Lucero & Munhall 1999,
    :func:`angles_from_chin`); with the anatomical tissue, the one that gives the skin node that
    displacement in the tissue's quasi-static response to the jaw (:func:`skin_drop_curve`).
    Both move the jaw as the preset's ``jaw_kinematics`` says (the coupled glide or the hinge),
    as :func:`~facemech.solvers.forward.simulate` will for the angles returned.
    Upward displacements (closing past rest) follow the curve's slope at rest. The lead and the
    bite block act as in :func:`angles_from_chin`.
    """
    face, params = model.face, model.params
    marker_y = np.asarray(marker_y, float)
    if not params.is_continuum:
        return angles_from_chin(marker_y, face.rest_positions[node + 2 * face.n_surface],
                                face.hinge_point, face.hinge_axis, lead=lead,
                                bite_block=bite_block, glide=glide_of(params))
    if marker_y.ndim != 1 or len(marker_y) == 0:
        raise InputError("chin trajectory must be a non-empty 1-D series", source=source,
                         field="chin")
    if not np.all(np.isfinite(marker_y)):
        bad = int(np.nonzero(~np.isfinite(marker_y))[0][0])
        raise InputError(f"chin trajectory has a gap at sample {bad}", source=source,
                         field="chin")
    angles, drop = skin_drop_curve(model, node)
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
    out = _lead(out, lead)
    if bite_block:
        out = np.full_like(out, out[0])
    return out
