"""The jaw: the mandible as a planar rigid body, or the seeds' hinge (Lucero & Munhall 1999).

The skull nodes of the mandible rotate about a horizontal axis through the condyles (positive
angles open the mouth: the chin moves down and back) while the condyles glide in the sagittal
plane: a jaw pose is (angle rad, shift_y m, shift_z m) (:mod:`.mandible`). With one degree of
freedom, a preset's ``jaw_kinematics`` completes an angle into a pose: ``"glide"`` (the
anatomical preset) couples the condyle's forward and downward glide to the opening
(:func:`condyle_glide`), ``"hinge"`` (the seeds' presets) keeps the condyles still.

Drives: the angle of each frame from one jaw marker (:func:`angles_from_chin` for a point on
the bone; :func:`facemech.solvers.jaw_drive.jaw_angles_from_marker`, which runs the simulator,
for a chin marker on the skin), applied two 60-Hz
samples (33 ms) early to make up for the delay of propagation from the skull to the skin; or
the whole pose from two markers on the mandible (:func:`jaw_poses_from_points`). Points on the
bone itself (a lower-incisor sensor, a molar pellet) give the angle and a free protrusion of
the condyles along the eminence, without lead (:mod:`.jaw_bone`).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..errors import InputError
from ..geometry.jaw import rotate_about, rotation_matrix  # noqa: F401 (re-exported)
from ..params import GLIDE_RATE, GLIDE_SLOPE

JAW_LEAD_SAMPLES = 2  #: 33 ms at 60 Hz
MAX_JAW_ANGLE = np.radians(30.0)
#: m, the largest condyle shift a two-marker drive accepts
MAX_JAW_SHIFT = 0.020
#: m, the closest two jaw markers may be for a two-marker drive
MIN_MARKER_SEPARATION = 0.010


def condyle_glide(angle, rate: float = GLIDE_RATE, slope: float = GLIDE_SLOPE):
    """The condyles' shift (shift_y, shift_z) in m for a jaw opening ``angle`` (rad).

    As the mouth opens the condyle glides forward and down along the articular eminence:
    ``rate`` metres of travel per radian of opening, along a path ``slope`` radians below the
    horizontal (+z forward, +y up)::

        shift_y = -rate * max(angle, 0) * sin(slope)
        shift_z = +rate * max(angle, 0) * cos(slope)

    Closing past rest (angle <= 0) leaves the condyle seated (no shift).

    The defaults (:data:`~facemech.params.GLIDE_RATE` 28 mm/rad along
    :data:`~facemech.params.GLIDE_SLOPE` 35 degrees, a typical inclination of the articular
    eminence) are calibrated on the default face to a real speech recording (X-ray microbeam
    pellets, repeated "sa"): a lower incisor drop of 22 mm with 3.6 mm of motion front
    to back, a molar point dropping 15 mm. The rate that moves the default face's lower incisor
    (:func:`lower_incisor_point`) 3.6 mm back at a 22-mm drop is 28.4 mm/rad; at 28 it moves
    3.7 mm (3.1 mm at a 20-mm drop, 15.5 degrees of opening; a hinge through the condyles: 13.1
    mm at 20.4 degrees), and a point halfway from the incisor to the condyle drops 61 % as far
    as the incisor (the hinge: 50 %; docs/model.md, "The jaw").

    Parameters
    ----------
    angle : float or array, rad
    rate : m/rad
    slope : rad below the horizontal

    Returns
    -------
    (shift_y, shift_z) : floats or arrays shaped like ``angle``, m
    """
    a = np.maximum(np.asarray(angle, float), 0.0)
    d = rate * a
    sy, sz = -d * np.sin(slope), d * np.cos(slope)
    if np.ndim(angle) == 0:
        return float(sy), float(sz)
    return sy, sz


def jaw_poses(angles, params) -> np.ndarray:
    """Jaw poses (..., 3) (angle rad, shift_y m, shift_z m) of jaw angles under a preset's
    ``jaw_kinematics``: the coupled glide (:func:`condyle_glide` with the preset's rate and
    slope) or, for ``"hinge"``, no shift."""
    a = np.asarray(angles, float)
    out = np.zeros(a.shape + (3,))
    out[..., 0] = a
    if params.jaw_kinematics == "glide":
        out[..., 1], out[..., 2] = condyle_glide(a, params.glide_rate, params.glide_slope)
    return out


def move_points(points: np.ndarray, pose, hinge_point: np.ndarray, hinge_axis: np.ndarray,
                weights: np.ndarray | None = None) -> np.ndarray:
    """Points (k, 3) m carried by the mandible into ``pose`` (angle, shift_y, shift_z), each by
    its jaw weight (default 1), with the stepper's own kernel (:mod:`.mandible`)."""
    from .mandible import moved_anchors

    pts = np.ascontiguousarray(np.atleast_2d(np.asarray(points, float)))
    w = np.ones(len(pts)) if weights is None else np.asarray(weights, float)
    pose = np.asarray(pose, float)
    out, _ = moved_anchors(pose, np.asarray(hinge_point, float), np.asarray(hinge_axis, float),
                           w, pts, np.zeros_like(pts))
    return out


def angle_for_drop(node_rest: np.ndarray, point: np.ndarray, axis: np.ndarray,
                   drop: float, glide: tuple[float, float] | None = None) -> float:
    """Jaw angle (rad) that moves ``node_rest`` (on the mandible) by ``drop`` metres along y
    (negative: down): about the hinge alone, or with the coupled ``glide`` (rate m/rad, slope
    rad) of :func:`condyle_glide`."""
    def f(th):
        y = rotate_about(node_rest, point, axis, th)[1]
        if glide is not None:
            y += condyle_glide(th, *glide)[0]
        return y - node_rest[1] - drop

    lo, hi = -MAX_JAW_ANGLE, MAX_JAW_ANGLE
    if f(lo) * f(hi) > 0:
        raise InputError(f"a vertical chin displacement of {drop * 1e3:.1f} mm cannot be reached "
                         "by the jaw", field="chin")
    return float(brentq(f, lo, hi, xtol=1e-10))


def _lead(series: np.ndarray, lead: int) -> np.ndarray:
    """``series`` shifted ``lead`` samples earlier along its first axis, the last value held."""
    if lead <= 0:
        return series
    n = len(series)
    return np.concatenate([series[lead:], np.repeat(series[-1:], min(lead, n), axis=0)])[:n]


def angles_from_chin(chin_y: np.ndarray, chin_node_rest: np.ndarray, hinge_point: np.ndarray,
                     hinge_axis: np.ndarray, *, lead: int = JAW_LEAD_SAMPLES,
                     bite_block: bool = False,
                     glide: tuple[float, float] | None = None) -> np.ndarray:
    """Jaw angles (rad) per 60-Hz frame from the vertical position (m) of a point on the bone.

    The point (a chin marker over the seeds' thin tissue, or the lower incisor,
    :func:`lower_incisor_point`) rests at ``chin_node_rest`` and moves with the mandible. The
    displacement is taken from the first (rest) sample. ``glide`` (rate m/rad, slope rad): the
    condyle glides with the opening (:func:`condyle_glide`, a preset's ``"glide"``
    kinematics); None: a hinge. ``lead`` shifts the series earlier by that many samples (the
    last value is held). With ``bite_block`` the angle stays at its initial value.
    """
    chin_y = np.asarray(chin_y, float)
    if chin_y.ndim != 1 or len(chin_y) == 0:
        raise InputError("chin trajectory must be a non-empty 1-D series", field="chin")
    if not np.all(np.isfinite(chin_y)):
        bad = int(np.nonzero(~np.isfinite(chin_y))[0][0])
        raise InputError(f"chin trajectory has a gap at sample {bad}", field="chin")
    drops = chin_y - chin_y[0]
    angles = np.array([angle_for_drop(chin_node_rest, hinge_point, hinge_axis, d, glide)
                       for d in drops])
    angles = _lead(angles, lead)
    if bite_block:
        angles = np.full_like(angles, angles[0])
    return angles


def glide_of(params) -> tuple[float, float] | None:
    """(rate m/rad, slope rad) of a preset's coupled glide, or None for its hinge."""
    if params.jaw_kinematics == "glide":
        return params.glide_rate, params.glide_slope
    return None


def planar_rigid_fit(before: np.ndarray, after: np.ndarray) -> tuple[float, np.ndarray]:
    """Least-squares planar rigid motion (rotation about x, translation in y-z) of point sets.

    Parameters
    ----------
    before, after : (k, 2) (y, z) m of the same k >= 2 points

    Returns
    -------
    angle : rad, about +x (positive turns +y towards +z: the jaw's opening direction)
    centres : (2, 2) the centroids of ``before`` and ``after``: the motion takes ``p`` to
        ``R(angle) (p - centres[0]) + centres[1]``
    """
    ca, cb = before.mean(axis=0), after.mean(axis=0)
    a, b = before - ca, after - cb
    # rotation about +x in (y, z): y' = y cos - z sin, z' = y sin + z cos
    s = np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    c = np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])
    return float(np.arctan2(s, c)), np.stack([ca, cb])


def checked_trajectory(p, name: str, source: str | None = None, *,
                       hint: str = "") -> np.ndarray:
    """A jaw marker's (frames, 3) trajectory as floats, checked: an InputError naming the
    marker for another shape or a gap (a non-finite sample), ``hint`` added to the latter."""
    p = np.asarray(p, float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0:
        raise InputError(f"{name} must be a (frames, 3) trajectory, got {p.shape}",
                         source=source, field=name)
    bad = ~np.all(np.isfinite(p), axis=1)
    if bad.any():
        raise InputError(f"{name} has a gap at sample {int(np.nonzero(bad)[0][0])}{hint}",
                         source=source, field=name)
    return p


def jaw_poses_from_points(p1: np.ndarray, p2: np.ndarray, *, hinge_point: np.ndarray,
                          lead: int = JAW_LEAD_SAMPLES, bite_block: bool = False,
                          names: tuple[str, str] = ("jaw marker", "second jaw marker"),
                          source: str | None = None) -> np.ndarray:
    """Jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) from two markers on the mandible.

    Each frame's pose is the least-squares planar rigid motion (a rotation about the x axis and
    a translation in the y-z plane; :func:`planar_rigid_fit`) that takes the two markers' first
    -frame positions to their positions in that frame, written as a rotation about the hinge
    point (the condyles) plus the shift of the hinge. The markers are taken as fixed to the
    mandible: the lower incisor or the chin, and a second point such as a molar pellet. The
    first frame is taken as the jaw's rest (pose 0); x is not used.

    Parameters
    ----------
    p1, p2 : (frames, 3) m, model axes (+y up, +z forward)
    hinge_point : (3,) m, the model's hinge (``FaceModel.hinge_point``)
    lead : samples by which the poses are moved earlier (the last held), as the one-marker
        drive's 33 ms (:data:`JAW_LEAD_SAMPLES`); 0 for none
    bite_block : hold the first pose throughout
    names : the markers' names, for messages
    source : the file the markers came from, for messages

    Raises
    ------
    InputError
        For a gap (a non-finite sample), markers closer than 10 mm, or a pose beyond the jaw's
        range (angle over 30 degrees, a shift over 20 mm), naming the marker or ``jaw``.
    """
    pts = []
    for p, name in zip((p1, p2), names, strict=True):
        p = checked_trajectory(p, name, source)
        pts.append(p[:, 1:])
    if len(pts[0]) != len(pts[1]):
        raise InputError(f"the jaw markers have {len(pts[0])} and {len(pts[1])} samples",
                         source=source, field=names[1])
    a, b = pts
    sep = np.linalg.norm(a[0] - b[0])
    if sep < MIN_MARKER_SEPARATION:
        raise InputError(f"{names[0]} and {names[1]} are {sep * 1e3:.1f} mm apart in the "
                         f"sagittal plane; a two-marker jaw drive needs at least "
                         f"{MIN_MARKER_SEPARATION * 1e3:.0f} mm", source=source, field=names[1])
    h = np.asarray(hinge_point, float)[1:]
    before = np.stack([a[0], b[0]])
    poses = np.empty((len(a), 3))
    for k in range(len(a)):
        angle, (ca, cb) = planar_rigid_fit(before, np.stack([a[k], b[k]]))
        c, s = np.cos(angle), np.sin(angle)
        d = h - ca
        shift = np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]]) + cb - h
        poses[k] = angle, shift[0], shift[1]
    too_far = np.abs(poses[:, 0]) > MAX_JAW_ANGLE
    too_far_shift = np.hypot(poses[:, 1], poses[:, 2]) > MAX_JAW_SHIFT
    if too_far.any() or too_far_shift.any():
        k = int(np.nonzero(too_far | too_far_shift)[0][0])
        raise InputError(f"the jaw markers at sample {k} give a jaw angle of "
                         f"{np.degrees(poses[k, 0]):.1f} degrees and a condyle shift of "
                         f"{np.hypot(*poses[k, 1:]) * 1e3:.1f} mm, beyond the jaw's range "
                         f"({np.degrees(MAX_JAW_ANGLE):.0f} degrees, "
                         f"{MAX_JAW_SHIFT * 1e3:.0f} mm)", source=source, field="jaw")
    poses = _lead(poses, lead)
    if bite_block:
        poses = np.repeat(poses[:1], len(poses), axis=0)
    return poses
