"""The generic face fitted to a photo's 68 iBUG landmarks: its shape, its size and the camera.

A frontal photo gives the face's outline in the image plane, not its size or depth.
:func:`fit_frontal` reads the photo through a pinhole camera at a stated distance and
(1) levels the eyes and takes the metric scale from the interpupillary distance (given, or
:data:`IPD_NORM`, Dodgson 2004); (2) back-projects every point to the generic face's depth
there; (3) warps the generic surface by the 2-D spline that takes its iBUG points onto those
(:func:`_spline`: the linear radial kernel with a constant part) and scales its depth;
(4) optionally corrects the midline's depth from a profile silhouette (:func:`profile_depth`).
A detector's jaw line (iBUG 0-16), its least certain part, is made mirror-symmetric
(:func:`symmetric_jaw`) and fitted loosely (:data:`JAW_SMOOTHING`), the chin's heights
(:func:`chin_points`) interpolated. The result is "a scan": vertices, triangles and 3-D iBUG
points, metres, facemech's axes, with the camera that sees it as the photo did
(:class:`PhotoCamera`), to paint the photo on it (:mod:`photo_texture`). Docs: docs/photo.md.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import RBFInterpolator

from ..errors import InputError
from . import generic
from .ibug import SPLINE_POINTS, generic_ibug68, ibug_to_landmarks

#: adult interpupillary distance, m: the mean of adults in Dodgson (2004), "Variation and
#: extrema of human interpupillary distance", Proc. SPIE 5291 (63.4 mm, SD 3.8 mm; men 64.7,
#: women 62.3), the norm the scale is taken from when none is given
IPD_NORM = 0.0634
#: the span of plausible adult interpupillary distances, m (Dodgson 2004: 50 to 75 mm)
IPD_RANGE = (0.050, 0.080)
#: iBUG points of the eyes: the subject's right (36-41) and left (42-47)
RIGHT_EYE, LEFT_EYE = np.arange(36, 42), np.arange(42, 48)
#: the mirror image of each iBUG point (the point on the other side of the face, or itself)
MIRROR = np.array([*range(16, -1, -1), *range(26, 16, -1), 27, 28, 29, 30, *range(35, 30, -1),
                   45, 44, 43, 42, 47, 46, 39, 38, 37, 36, 41, 40, 54, 53, 52, 51, 50, 49, 48,
                   59, 58, 57, 56, 55, 64, 63, 62, 61, 60, 67, 66, 65])
#: where dlib's predictor puts the 68 points on the generic face, mm (x to the subject's left, y
#: up) from facemech's own placement (:func:`ibug.generic_ibug68`): the jaw line on the face's
#: outline, the eye corners where the rendered fissure ends. Measured by
#: ``tools/photo_detector_offsets.py`` on four frontal renders of the built-in face (image
#: sizes 420-900 px, cameras 0.7-2.5 m; the largest standard deviation over them 1.85 mm), and
#: made mirror-symmetric.
DLIB_OFFSETS_MM = np.array([
    # jaw, 0 (right ear) to 16
    (-6.7, 5.5), (-6.7, 9.5), (-7.8, 12.3), (-10.2, 13.6), (-12.8, 12.4), (-13.8, 9.6),
    (-12.4, 5.8), (-8.1, 1.7), (0.0, 1.0), (8.1, 1.7), (12.4, 5.8), (13.8, 9.6), (12.8, 12.4),
    (10.2, 13.6), (7.8, 12.3), (6.7, 9.5), (6.7, 5.5),
    # brows
    (-3.1, 0.0), (-1.9, 1.5), (-1.1, 1.0), (0.2, -0.1), (2.2, -2.2), (-2.2, -2.2), (-0.2, -0.1),
    (1.1, 1.0), (1.9, 1.5), (3.1, 0.0),
    # nose
    (0.0, -4.0), (0.0, -2.7), (0.0, -1.5), (0.0, 0.8), (1.6, -1.2), (1.0, -0.7), (0.0, 0.0),
    (-1.0, -0.7), (-1.6, -1.2),
    # eyes
    (4.8, -0.3), (4.2, 0.6), (3.3, 0.6), (2.9, -2.0), (2.6, -0.5), (4.0, -0.4), (-2.9, -2.0),
    (-3.3, 0.6), (-4.2, 0.6), (-4.8, -0.3), (-4.0, -0.4), (-2.6, -0.5),
    # lips
    (0.5, -0.7), (-0.7, 1.7), (-1.0, 1.7), (0.0, -0.3), (1.0, 1.7), (0.7, 1.7), (-0.5, -0.7),
    (1.1, -2.1), (1.9, -3.0), (0.0, -3.4), (-1.9, -3.0), (-1.1, -2.1), (-0.1, -0.4), (0.9, 2.2),
    (0.0, 1.8), (-0.9, 2.2), (0.1, -0.4), (-0.8, -0.2), (0.0, -0.9), (0.8, -0.2),
])  # fmt: skip
#: the jaw line's iBUG points (0 on the subject's right, 8 the menton, 16 on the left)
JAW = np.arange(17)
#: how loosely the spline follows a detector's jaw-line points (their x, and their y but at the
#: chin): scipy's smoothing (:class:`scipy.interpolate.RBFInterpolator`, the spline's kernel
#: in metres; the inner points get 0, interpolated). 0 would interpolate the jaw line; a value
#: much larger than the kernel (|r|, about 0.1 m) leaves it out, the inner points alone shaping
#: the face's width there. On facemech's renders through dlib (24 photos of two faces, six
#: sizes and six turns each; docs/photo.md) the worst landmark's mean falls by 0.4-1.6 mm from
#: 0.002 to 1 and moves by 0.25 mm at most from 0.5 to 1000
JAW_SMOOTHING = 1.0
#: iBUG points a face's turn about the vertical is read from (:func:`estimate_yaw`): the nose
#: (27-35), the eyes (36-47) and the mouth's corners (48, 54); not the jaw line or the brows,
#: which a detector places least surely on a turned face
YAW_POINTS = np.r_[27:48, 48, 54]
#: rad, the smallest turn :func:`fit_frontal` takes out of the points; a smaller one is fitted
#: as frontal, as before (frontal renders of the test faces read 0.2 and 2.6 degrees through
#: dlib: the variant's mouth and chin are its own, the generic face's are not)
YAW_MIN = float(np.radians(3.0))
#: rad, the turns :func:`estimate_yaw` tries (0.25-degree steps; photos turned more than 20
#: degrees are refused before, :func:`facemech.io.photo.frontal_landmarks`)
YAW_SEARCH = np.radians(np.arange(-25.0, 25.0 + 1e-9, 0.25))
#: a mouth whose inner lips lie further apart than this share of its width (corner to corner)
#: is open: :func:`closed_mouth` closes it for the talker's rest
OPEN_MOUTH = 0.05
#: a mouth whose corners lie above its inner lips' middle by this share of its width smiles
SMILE = 0.06
#: the least share of the generic face's lip heights (each lip point's height over or under the
#: mouth's middle line) a fitted face keeps: thin lips in a photo would squeeze the generic
#: face's lips until its tissue folds
LIP_FLOOR = 0.8
#: the generic mesh the photo face is made from: (rows, columns) of :func:`generic.make_surface`,
#: the built-in face's (about 2 mm between nodes at the lips)
PHOTO_RESOLUTION = (48, 41)


@dataclass(frozen=True)
class PhotoCamera:
    """A pinhole camera facing the subject, as the photo was taken.

    The camera sits ``distance`` in front of the plane ``z = plane_z`` (model axes), on the line
    through ``(centre_x, centre_y)``, and is turned by ``roll`` about its axis; ``metres_per_px``
    is the size of a pixel on that plane.

    Attributes
    ----------
    centre_px : (2,) image point (x right, y down; pixel centres at integers + 0.5) of the
        model point (centre_x, centre_y, plane_z)
    centre_m : (2,) m, that model point's x and y
    plane_z : m, depth of the reference plane
    metres_per_px : m per pixel on the reference plane
    distance : m from the camera to the reference plane
    roll : rad, the image's turn about the camera axis (counter-clockwise in the image)
    size : (height, width) of the photo, pixels
    yaw : rad, the face's turn to its left about the vertical through ``(centre_x, plane_z)``
        (:func:`turn_about_vertical`) before the view; 0 for a frontal photo
    """

    centre_px: np.ndarray
    centre_m: np.ndarray
    plane_z: float
    metres_per_px: float
    distance: float
    roll: float
    size: tuple[int, int]
    yaw: float = 0.0

    @property
    def pivot(self) -> np.ndarray:
        """(3,) m, a point of the vertical the face turns about (its y is the eyes')."""
        return np.array([self.centre_m[0], self.centre_m[1], self.plane_z])

    def project(self, points: np.ndarray) -> np.ndarray:
        """Image points (n, 2) px (x right, y down) of model points (n, 3) m."""
        p = np.atleast_2d(np.asarray(points, float))
        if self.yaw:
            p = turn_about_vertical(p, self.yaw, self.pivot)
        k = self.distance / np.maximum(self.distance - (p[:, 2] - self.plane_z), 1e-3)
        dx = (p[:, 0] - self.centre_m[0]) * k / self.metres_per_px
        dy = -(p[:, 1] - self.centre_m[1]) * k / self.metres_per_px
        c, s = np.cos(self.roll), np.sin(self.roll)
        return np.column_stack([self.centre_px[0] + c * dx + s * dy,
                                self.centre_px[1] - s * dx + c * dy])

    def back_project(self, image_points: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Model points (n, 3) m on the rays of image points (n, 2) px, at depths z (n,) m; a
        camera without a turn (``yaw`` 0) only."""
        if self.yaw:
            raise ValueError("back_project needs a camera without a turn (yaw 0)")
        q = np.asarray(image_points, float) - self.centre_px
        c, s = np.cos(self.roll), np.sin(self.roll)
        dx = c * q[:, 0] - s * q[:, 1]
        dy = s * q[:, 0] + c * q[:, 1]
        k = (self.distance - (np.asarray(z, float) - self.plane_z)) / self.distance
        return np.column_stack([self.centre_m[0] + dx * self.metres_per_px * k,
                                self.centre_m[1] - dy * self.metres_per_px * k, z])

    def view_direction(self, points: np.ndarray) -> np.ndarray:
        """Unit vectors (n, 3) from model points towards the camera."""
        eye = np.array([self.centre_m[0], self.centre_m[1], self.plane_z + self.distance])
        if self.yaw:  # the camera, turned back into the face's frame
            eye = turn_about_vertical(eye[None], -self.yaw, self.pivot)[0]
        d = eye - np.atleast_2d(points)
        return d / np.linalg.norm(d, axis=1, keepdims=True)


@dataclass(frozen=True)
class PhotoFit:
    """The generic face fitted to a photo.

    Attributes
    ----------
    vertices : (n, 3) m, the fitted surface (the generic grid warped)
    faces : (f, 3) int, its triangles (the generic grid's)
    generic_vertices : (n, 3) m, the same nodes on the generic face (for texture coordinates)
    ibug : (68, 3) m, the iBUG points on the fitted face, in facemech's placement
    landmarks : name -> (3,) m, facemech's 18 landmarks on the fitted face
    camera : the photo's camera
    image_points : (68, 2) px, the landmarks found in the photo
    ipd : m, the interpupillary distance the scale was set by
    scale_source : ``"given"`` or the norm's citation
    size_factor : the fitted face's size over the generic face's (its depth is scaled by it)
    profile_correction : (rows,) m, the midline depth correction from a profile photo, or None
    """

    vertices: np.ndarray
    faces: np.ndarray
    generic_vertices: np.ndarray
    ibug: np.ndarray
    landmarks: dict
    camera: PhotoCamera
    image_points: np.ndarray
    ipd: float
    scale_source: str
    size_factor: float
    profile_correction: np.ndarray | None = None
    mouth_gap: float = 0.0
    smiling: bool = False

    def note(self) -> str:
        """One line: the scale and where it came from; whether the photo's mouth was open or
        smiling (closed and neutral for the talker's rest)."""
        turn = (f"; turned {abs(np.degrees(self.camera.yaw)):.1f} degrees to its "
                f"{'left' if self.camera.yaw > 0 else 'right'}, taken out"
                if self.camera.yaw else "")
        mouth = []
        if self.mouth_gap:
            mouth.append(f"open {self.mouth_gap * 1e3:.0f} mm")
        if self.smiling:
            mouth.append("smiling")
        warn = (f"; the photo's mouth is {' and '.join(mouth)}: the talker rests with it closed "
                "and neutral, its lips in the photo's lip colour (a neutral photo with the "
                "mouth closed makes the best talker)" if mouth else "")
        return (f"scale: interpupillary distance {self.ipd * 1e3:.1f} mm ({self.scale_source}); "
                f"face {self.size_factor:.3f} x the generic face{turn}{warn}")


def eye_centres(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The centres of the subject's right and left eyes (means of their six iBUG points)."""
    p = np.asarray(points, float)
    return p[RIGHT_EYE].mean(axis=0), p[LEFT_EYE].mean(axis=0)


def closed_mouth(points: np.ndarray, closed: np.ndarray | None = None
                 ) -> tuple[np.ndarray, float]:
    """The image points (68, 2) px (y down) with an open mouth closed, and its gap, px.

    The inner lips' gap is the distance of each upper inner lip point (iBUG 61-63) above its
    lower partner (67-65), less the gap the detector leaves on a closed mouth: ``closed``
    (68, 2 or 3) are the detector's points on a closed mouth (y up; None: no gap). Where its
    mean passes :data:`OPEN_MOUTH` of the mouth's width, each upper lip point moves down by half
    its column's gap and each lower one up by as much (the outer lips' ends 49, 53, 59, 55 by
    a quarter), and the chin (iBUG 6-10; 5 and 11 half as much) up by half the mean gap: the
    lips meet as at rest. Under it the points are returned as they are.
    """
    p = np.array(points, float)
    upper, lower = np.array([61, 62, 63]), np.array([67, 66, 65])
    width = float(np.linalg.norm(p[54] - p[48]))
    rest = np.zeros(3)
    if closed is not None:
        c = np.asarray(closed, float)
        rest = (c[upper, 1] - c[lower, 1]) / float(np.linalg.norm(c[54, :2] - c[48, :2]))
    gaps = p[lower, 1] - p[upper, 1] - rest * width
    gap = float(gaps.mean())
    if gap <= OPEN_MOUTH * width:
        return p, 0.0
    half = 0.5 * np.clip(gaps, 0.0, None)
    p[upper, 1] += half
    p[[50, 51, 52], 1] += half
    p[[49, 53], 1] += 0.5 * half[[0, 2]]
    p[lower, 1] -= half
    p[[58, 57, 56], 1] -= half
    p[[59, 55], 1] -= 0.5 * half[[0, 2]]
    p[6:11, 1] -= 0.5 * gap
    p[[5, 11], 1] -= 0.25 * gap
    return p, gap


def _lip_floor(fitted: np.ndarray, generic_points: np.ndarray) -> np.ndarray:
    """The fitted points (68, 3) m with each lip point (iBUG 48-67) at least :data:`LIP_FLOOR`
    of the generic face's (``generic_points``, (68, 3) m, scaled) height over or under the
    mouth's middle line (the inner lips' mean height)."""
    out = np.array(fitted, float)
    lips = np.arange(48, 68)
    mid_f, mid_g = out[60:68, 1].mean(), generic_points[60:68, 1].mean()
    d_f, d_g = out[lips, 1] - mid_f, generic_points[lips, 1] - mid_g
    floor = LIP_FLOOR * np.abs(d_g)
    thin = (np.abs(d_f) < floor) | (np.sign(d_f) != np.sign(d_g))
    out[lips[thin], 1] = mid_f + np.sign(d_g[thin]) * floor[thin]
    return out


def smiling(points: np.ndarray) -> bool:
    """Whether the mouth's corners (iBUG 48, 54) lie above the inner lips' middle (the mean of
    61-63 and 65-67) by :data:`SMILE` of the mouth's width (image points (68, 2) px, y down)."""
    p = np.asarray(points, float)
    width = float(np.linalg.norm(p[54] - p[48]))
    middle = p[[61, 62, 63, 65, 66, 67], 1].mean()
    return bool(middle - p[[48, 54], 1].mean() > SMILE * width)


def _generic_grid() -> tuple[np.ndarray, np.ndarray]:
    surf = generic.make_surface(*PHOTO_RESOLUTION)
    return surf.vertices * 1e-3, surf.faces


def fit_frontal(points: np.ndarray, size: tuple[int, int], *, ipd: float | None = None,
                distance: float = 1.0, profile: ProfileSilhouette | None = None,
                offsets: np.ndarray | None = DLIB_OFFSETS_MM,
                loose_jaw: bool | None = None, yaw: float | None = None,
                close_mouth: bool = True, source: str | None = None) -> PhotoFit:
    """Fit the generic face to the 68 iBUG points of a frontal photo.

    A face turned a little from the camera (at least :data:`YAW_MIN`) is turned back first: its
    turn is read from the points (:func:`estimate_yaw`), each point is moved by as much as the
    turn moves the generic face's (scaled) point in the photo's camera, the frontal fit is made
    of the moved points, and the fit's camera keeps the turn (``camera.yaw``) for the photo's
    texture.

    Parameters
    ----------
    points : (68, 2) image points, px (x right, y down), iBUG order (point 0 on the subject's
        right, the image's left)
    size : (height, width) of the photo, pixels
    ipd : the subject's interpupillary distance, m; None takes the adult norm :data:`IPD_NORM`
    distance : m from the camera to the face (its eyes); 0.3 to 20
    profile : the silhouette of a profile photo (:func:`profile_silhouette`), to correct the
        midline depth; None keeps the generic face's depth, scaled
    offsets : (68, 2) mm, where the points' detector puts the iBUG points on the generic face
        from facemech's own placement (default: dlib's, :data:`DLIB_OFFSETS_MM`); None for
        points in facemech's placement (e.g. projected from a known face)
    loose_jaw : treat the jaw line (iBUG 0-16) as a detector's: made mirror-symmetric about
        its middle (:func:`symmetric_jaw`) and followed loosely by the spline
        (:data:`JAW_SMOOTHING`), the chin's heights apart (:func:`chin_points`); None: when
        ``offsets`` are given (a detector's points), not for points in facemech's placement
    yaw : rad, the face's turn to its left (positive) to take out; None reads it from the points
        (:func:`estimate_yaw`, none under :data:`YAW_MIN`); 0 fits the points as frontal
    close_mouth : fit an open mouth closed (:func:`closed_mouth`): the talker rests with its
        lips together whatever the photo's expression
    source : the photo's name, for errors

    Returns
    -------
    PhotoFit

    Raises
    ------
    InputError
        Points not (68, 2) finite, an interpupillary distance outside :data:`IPD_RANGE`, a
        distance outside 0.3-20 m, or a face whose landmarks fold (a mirrored or garbled
        detection).
    """
    pts = np.asarray(points, float)
    if pts.shape != (68, 2) or not np.all(np.isfinite(pts)):
        raise InputError(f"expected 68 finite image points, got shape {pts.shape}",
                         source=source, field="landmarks")
    if ipd is not None and not IPD_RANGE[0] <= ipd <= IPD_RANGE[1]:
        raise InputError(f"interpupillary distance {ipd * 1e3:.1f} mm is outside "
                         f"{IPD_RANGE[0] * 1e3:.0f}-{IPD_RANGE[1] * 1e3:.0f} mm", field="ipd")
    if not 0.3 <= distance <= 20.0:
        raise InputError(f"camera distance {distance:g} m is outside 0.3-20 m", field="distance")
    photo_pts = pts
    own = generic_ibug68()
    gen = own if offsets is None else _detector_points(offsets)
    gap_px = 0.0
    if close_mouth:
        pts, gap_px = closed_mouth(pts, gen)
    v_gen, faces = _generic_grid()
    ipd_m = IPD_NORM if ipd is None else float(ipd)
    own_ipd = float(np.linalg.norm(np.subtract(*eye_centres(own))))
    size_factor = ipd_m / own_ipd
    cam, z, g_mid = _frontal_camera(pts, gen, size, ipd_m, own_ipd, size_factor, distance,
                                    source)
    scaled = g_mid + size_factor * (gen - g_mid)  # the generic points on the fitted face
    turn = estimate_yaw(pts, scaled, cam) if yaw is None else float(yaw)
    if yaw is None and abs(turn) < YAW_MIN:
        turn = 0.0
    used = pts
    if turn:
        # each point moved back by as much as the turn moves the generic face's in the photo
        used = pts + cam.project(scaled) - cam.project(turn_about_vertical(scaled, turn,
                                                                            g_mid))
        cam, z, g_mid = _frontal_camera(used, gen, size, ipd_m, own_ipd, size_factor,
                                        distance, source)
    fitted = cam.back_project(used, z)
    _check_order(fitted, source)
    fitted = _lip_floor(fitted, scaled)
    smooth_x, smooth_y = np.zeros(len(SPLINE_POINTS)), np.zeros(len(SPLINE_POINTS))
    if offsets is not None if loose_jaw is None else loose_jaw:
        fitted = symmetric_jaw(fitted)
        jaw = np.isin(SPLINE_POINTS, JAW)
        smooth_x[jaw] = JAW_SMOOTHING
        smooth_y[jaw & ~np.isin(SPLINE_POINTS, chin_points(gen[JAW, :2]))] = JAW_SMOOTHING
    warp = _spline(gen[SPLINE_POINTS, :2], fitted[SPLINE_POINTS, :2] - gen[SPLINE_POINTS, :2],
                   smooth_x, smooth_y)

    def warped(p: np.ndarray) -> np.ndarray:
        out = np.empty_like(p)
        out[:, :2] = p[:, :2] + warp(p[:, :2])
        out[:, 2] = g_mid[2] + size_factor * (p[:, 2] - g_mid[2])
        return out

    verts = warped(v_gen)
    ibug = warped(own)  # facemech's own iBUG points, carried by the same warp
    correction = None
    if profile is not None:
        correction = profile.depth_correction(verts, faces, ibug)
        verts[:, 2] += correction(verts)
        ibug[:, 2] += correction(ibug)
    lm = ibug_to_landmarks(ibug, verts, faces)
    if turn:
        cam = replace(cam, yaw=float(turn))
    return PhotoFit(verts, faces, v_gen, ibug, lm, cam, photo_pts.copy(), ipd_m,
                    "given" if ipd is not None else "adult norm, Dodgson 2004",
                    float(size_factor), None if correction is None else correction.values,
                    mouth_gap=float(gap_px * cam.metres_per_px), smiling=smiling(photo_pts))


def _frontal_camera(pts: np.ndarray, gen: np.ndarray, size, ipd_m: float, own_ipd: float,
                    size_factor: float, distance: float, source: str | None):
    """The frontal camera of 68 image points: its roll from the eye line, its pixel size from
    the eye centres ``ipd_m`` apart; with the generic (detector's) points' depths (68,) m on the
    fitted face and the generic eye midpoint (3,) m the face is scaled about."""
    er, el = eye_centres(pts)
    if el[0] <= er[0]:
        raise InputError("the landmarks' left and right are swapped (a mirrored image?)",
                         source=source, field="landmarks")
    roll = float(np.arctan2(-(el[1] - er[1]), el[0] - er[0]))
    g_er, g_el = eye_centres(gen)
    # the detector's eye centres lie apart by the generic face's ratio of its two placements
    eyes_m = ipd_m * float(np.linalg.norm(g_el - g_er)) / own_ipd
    # the reference plane: the eyes' depth on the fitted face; the generic face is scaled
    # about its eye midpoint, which stays where the generic face has it
    g_mid = 0.5 * (g_er + g_el)
    cam = PhotoCamera(centre_px=0.5 * (er + el), centre_m=g_mid[:2].copy(),
                      plane_z=float(g_mid[2]), metres_per_px=0.0, distance=float(distance),
                      roll=roll, size=(int(size[0]), int(size[1])))
    z = g_mid[2] + size_factor * (gen[:, 2] - g_mid[2])
    # the eye centres lie at their own depth; the pixel size on the plane follows from them
    cam = _with_pixel(cam, eyes_m, er, el, z[RIGHT_EYE].mean(), z[LEFT_EYE].mean())
    return cam, z, g_mid


def turn_about_vertical(points: np.ndarray, angle: float, pivot: np.ndarray) -> np.ndarray:
    """Points (n, 3) m turned by ``angle`` (rad) about the vertical through ``pivot`` (3,): a
    positive angle turns the face to its left (its front, +z, towards +x)."""
    p = np.atleast_2d(np.asarray(points, float))
    c, s = np.cos(angle), np.sin(angle)
    dx, dz = p[:, 0] - pivot[0], p[:, 2] - pivot[2]
    return np.column_stack([pivot[0] + c * dx + s * dz, p[:, 1], pivot[2] - s * dx + c * dz])


def estimate_yaw(points: np.ndarray, generic_points: np.ndarray | None = None,
                 camera: PhotoCamera | None = None) -> float:
    """How far (rad) a face is turned to its left about the vertical, from its image points.

    The generic face's points (``generic_points``, (68, 3) m; default: where dlib puts them,
    :data:`DLIB_OFFSETS_MM`) are turned by each angle of :data:`YAW_SEARCH` about the vertical
    through their eyes' midpoint, seen through ``camera`` (a pinhole near the face: the turned
    face's near side looks larger) or from far (None: x right, y down), and fitted to the image
    points (68, 2) px by a 2-D similarity (scale, rotation, translation; least squares over
    :data:`YAW_POINTS`); the angle that leaves the least residual is returned, refined by a
    parabola through its neighbours. The generic face's own points turned and seen so give
    their angle back (tests/viz/test_photo.py).
    """
    pts = np.asarray(points, float)[YAW_POINTS]
    gen = _detector_points(DLIB_OFFSETS_MM) if generic_points is None else np.asarray(
        generic_points, float)
    pivot = 0.5 * np.add(*eye_centres(gen))
    used = gen[YAW_POINTS]
    b = pts - pts.mean(axis=0)
    res = np.empty(len(YAW_SEARCH))
    for i, a in enumerate(YAW_SEARCH):
        g = turn_about_vertical(used, a, pivot)
        q = (np.column_stack([g[:, 0], -g[:, 1]]) if camera is None
             else camera.project(g))
        q -= q.mean(axis=0)
        # the best similarity's residual: |b|^2 - (sum of singular values of q^T b)^2 / |q|^2
        sv = np.linalg.svd(q.T @ b, compute_uv=False)
        res[i] = float((b * b).sum() - sv.sum() ** 2 / (q * q).sum())
    k = int(np.argmin(res))
    if 0 < k < len(res) - 1:
        den = res[k - 1] - 2.0 * res[k] + res[k + 1]
        if den > 0:
            step = YAW_SEARCH[1] - YAW_SEARCH[0]
            return float(YAW_SEARCH[k] + 0.5 * step * (res[k - 1] - res[k + 1]) / den)
    return float(YAW_SEARCH[k])


def _spline(src: np.ndarray, disp: np.ndarray, smooth_x: np.ndarray, smooth_y: np.ndarray):
    """The spline of 2-D displacements ``disp`` (n, 2) m at ``src`` (n, 2) m, its x and y each
    with its own smoothing per point (n,) (0: interpolated). Returns a function of points
    (k, 2) m giving their displacements (k, 2) m.

    The kernel is the linear radial one, -|r| (the polyharmonic spline of order 1), with a
    constant part only. Its weights sum to zero, so far from the points the displacement levels
    off to a bounded value, where a thin-plate spline with an affine part would carry the inner
    points' trend outward (why: docs/design-log.md, "The photo fit's spline").
    """
    fx, fy = (RBFInterpolator(src, disp[:, i], kernel="linear", degree=0, smoothing=sm)
              for i, sm in enumerate((smooth_x, smooth_y)))
    return lambda p: np.column_stack([fx(p), fy(p)])


def chin_points(jaw: np.ndarray) -> np.ndarray:
    """Indices of the jaw line's points (17, 2) (x, y) where it runs more across than down: the
    chin's, whose height is the jaw line's normal (iBUG 6-10 on the generic face, in facemech's
    placement and dlib's)."""
    tangent = np.gradient(np.asarray(jaw, float), axis=0)
    return np.flatnonzero(np.abs(tangent[:, 0]) > np.abs(tangent[:, 1]))


def symmetric_jaw(points: np.ndarray) -> np.ndarray:
    """The points with their jaw line (iBUG 0-16) made mirror-symmetric about its own middle.

    The middle is the jaw line's mean x: where the jaw line lies stays (a face turned a little
    from the camera shows its jaw off the nose's line), its shape becomes symmetric. Each jaw
    point and its mirror partner take the mean of their distances from the middle (x) and of
    their heights (y); the menton (8) goes onto the middle.

    Parameters
    ----------
    points : (68, 2) or (68, 3) points, m, in a levelled frame (x to the subject's left, y up)

    Returns
    -------
    (68, 2) or (68, 3) m: the same points, the jaw line's x and y replaced (any z kept)
    """
    p = np.array(points, float)
    mid = float(p[JAW, 0].mean())
    partner = MIRROR[JAW]
    out = p.copy()
    out[JAW, 0] = mid + 0.5 * ((p[JAW, 0] - mid) - (p[partner, 0] - mid))
    out[JAW, 1] = 0.5 * (p[JAW, 1] + p[partner, 1])
    return out


def _detector_points(offsets_mm: np.ndarray) -> np.ndarray:
    """The generic face's iBUG points (68, 3) m where a detector puts them: facemech's frontal
    placement shifted by ``offsets_mm`` (68, 2), back on the surface."""
    from .ibug import _generic_xy

    off = np.asarray(offsets_mm, float)
    if off.shape != (68, 2):
        raise ValueError(f"detector offsets must be (68, 2) mm, got {off.shape}")
    xy = _generic_xy() + off
    return generic.surface_point(xy[:, 0], xy[:, 1]) * 1e-3


def _with_pixel(cam: PhotoCamera, ipd_m: float, er, el, z_r: float, z_l: float) -> PhotoCamera:
    """The camera whose pixel size puts the two eye centres ``ipd_m`` apart at their depths."""
    probe = replace(cam, metres_per_px=1.0)
    a = probe.back_project(np.array([er]), np.array([z_r]))[0]
    b = probe.back_project(np.array([el]), np.array([z_l]))[0]
    return replace(cam, metres_per_px=ipd_m / float(np.linalg.norm(a[:2] - b[:2])))


def _check_order(p: np.ndarray, source: str | None) -> None:
    """Refuse landmarks in an impossible order: brows under the eyes, nose under the mouth."""
    brows = p[17:27, 1].mean()
    eyes = p[36:48, 1].mean()
    nose = p[30, 1]
    mouth = p[48:60, 1].mean()
    chin = p[8, 1]
    if not brows > eyes > nose > mouth > chin:
        raise InputError("the landmarks are not in a face's order (brows, eyes, nose, mouth, "
                         "chin from the top): an upside-down photo or a failed detection",
                         source=source, field="landmarks")


# ---- the profile -----------------------------------------------------------------------------
@dataclass(frozen=True)
class DepthCorrection:
    """A smooth depth change (m along +z) over the face: the midline's, fading sideways.

    ``heights`` (k,) m and ``values`` (k,) m sample the midline correction; it fades with the
    distance from the midline as a Gaussian of ``width`` m (the nose and lips are the parts
    that differ between faces in profile; the cheeks follow the generic face).
    """

    heights: np.ndarray
    values: np.ndarray
    width: float

    def __call__(self, points: np.ndarray) -> np.ndarray:
        p = np.atleast_2d(points)
        along = np.interp(p[:, 1], self.heights, self.values, left=self.values[0],
                          right=self.values[-1])
        return along * np.exp(-0.5 * (p[:, 0] / self.width) ** 2)


@dataclass(frozen=True)
class ProfileSilhouette:
    """The facial outline of a profile photo: per image row, how far forward the face reaches.

    Attributes
    ----------
    rows : (k,) image rows, px (y down)
    front : (k,) the outline's forward extent on each row, px, measured towards the face's
        front (larger is further forward)
    source : the photo's name
    """

    rows: np.ndarray
    front: np.ndarray
    source: str = ""

    def nasion_and_tip(self) -> tuple[int, int]:
        """Indices of the nasion and the pronasale.

        The pronasale is the most forward point of the middle of the outline. The nasion is
        the bottom of the notch above it: the point furthest behind the outline's forward
        hull (the upper convex hull of (row, front)) between the pronasale and the hull's next
        corner above it. The hull, not a window of rows, keeps the answer on the face whatever
        the head carries above it: a forehead that recedes into hair lies on or near the hull,
        and the notch between brow and nose is the deepest place under it.
        """
        k = len(self.rows)
        mid = slice(k // 5, 4 * k // 5)
        tip = mid.start + int(np.argmax(self.front[mid]))
        if tip == 0:
            return tip, tip
        r, f = self.rows[:tip + 1], self.front[:tip + 1]
        hull = _upper_hull(r, f)
        chord = np.interp(r, r[hull], f[hull])
        return int(np.argmax(chord - f)), tip

    def depth_correction(self, vertices: np.ndarray, faces: np.ndarray,
                         ibug: np.ndarray) -> DepthCorrection:
        """The midline depth change that makes the fitted face's profile the photo's.

        The profile is registered to the fitted face at the pronasale's height (iBUG 30: the
        outline's most forward point), at the depth of the median difference between the two
        midlines (the differences are local: a nose, a chin), and scaled by the pixel size
        that lays the outline closest (mean absolute depth difference) on the fitted face's
        midline from the menton to above the brows, searched 25 % either side of the size that
        the nasion's height gives. The depth difference, smoothed over 2 mm, becomes the
        correction.
        """
        i_n, i_t = self.nasion_and_tip()
        if i_t - i_n < 3:
            raise InputError("the profile's nose is not found (no nasion above the nose tip)",
                             source=self.source or None, field="--profile")
        y_n, y_t = ibug[27, 1], ibug[30, 1]
        top = y_n + 0.6 * (y_n - y_t)
        bottom = ibug[8, 1]
        guess = (y_n - y_t) / float(self.rows[i_t] - self.rows[i_n])
        mid_y = np.linspace(bottom, top, 200)
        mid_z = _midline_depth(vertices, faces, mid_y)
        ok = np.isfinite(mid_z)
        if ok.sum() < 20:
            raise InputError("the fitted face has no midline to compare the profile with",
                             source=self.source or None, field="--profile")
        mid_y, mid_z = mid_y[ok], mid_z[ok]

        def photo_depth(m_per_px: float) -> np.ndarray:
            """The outline's depth (m) at the fitted midline's heights, at the depth where
            half the midline lies in front of the fitted face and half behind."""
            heights = y_t - (self.rows - self.rows[i_t]) * m_per_px
            depth = (self.front - self.front[i_t]) * m_per_px
            out = np.interp(mid_y, heights[::-1], depth[::-1], left=np.nan, right=np.nan)
            return out - np.nanmedian(out - mid_z)

        # the pixel size: the one that lays the outline best on the fitted midline (brow,
        # lips and chin in place), searched 25 % either side of the nasion's guess
        sizes = guess * np.linspace(0.75, 1.25, 101)
        costs = []
        for m in sizes:
            d = photo_depth(m) - mid_z
            costs.append(np.nanmean(np.abs(d)) if np.isfinite(d).sum() > 0.8 * len(d)
                         else np.inf)
        m_per_px = float(sizes[int(np.argmin(costs))])
        diff = photo_depth(m_per_px) - mid_z
        keep = np.isfinite(diff)
        if keep.sum() < 5:
            raise InputError("the profile's outline does not cover the face", field="--profile",
                             source=self.source or None)
        h, d = mid_y[keep], diff[keep]
        grid = np.arange(h[0], h[-1], 5e-4)
        dg = np.interp(grid, h, d)
        kernel = np.exp(-0.5 * (np.arange(-16, 17) * 5e-4 / 2e-3) ** 2)
        kernel /= kernel.sum()
        dg = np.convolve(np.pad(dg, 16, mode="edge"), kernel, mode="valid")
        # fade to nothing above the brows and below the chin
        ramp = np.clip((grid - bottom + 0.004) / 0.008, 0, 1) * np.clip(
            (top + 0.004 - grid) / 0.008, 0, 1)
        return DepthCorrection(grid, dg * ramp, width=0.018)



def _upper_hull(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Indices of the upper convex hull of the points (x, y), x increasing (Andrew's monotone
    chain)."""
    hull: list[int] = []
    for i in range(len(x)):
        while len(hull) >= 2:
            a, b = hull[-2], hull[-1]
            if (x[b] - x[a]) * (y[i] - y[a]) - (y[b] - y[a]) * (x[i] - x[a]) >= 0:
                hull.pop()
            else:
                break
        hull.append(i)
    return np.array(hull)

def _midline_depth(vertices: np.ndarray, faces: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """Depth (m) of the surface where the plane x = 0 cuts it, at each height (nan off it)."""
    v = vertices
    tri = v[faces]
    out = np.full(len(heights), np.nan)
    # the midline edges: triangle edges that cross x = 0
    segs = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        pa, pb = tri[:, a], tri[:, b]
        cross = (pa[:, 0] <= 0) != (pb[:, 0] <= 0)
        t = pa[cross, 0] / (pa[cross, 0] - pb[cross, 0])
        segs.append(pa[cross] + t[:, None] * (pb[cross] - pa[cross]))
    pts = np.concatenate(segs)
    if len(pts) < 2:
        return out
    order = np.argsort(pts[:, 1])
    y, z = pts[order, 1], pts[order, 2]
    inside = (heights >= y[0]) & (heights <= y[-1])
    out[inside] = np.interp(heights[inside], y, z)
    return out


def profile_silhouette(image: np.ndarray, *, source: str = "") -> ProfileSilhouette:
    """The facial outline of a profile photo against a plain background.

    The background is the median colour of the image's border; the subject is the largest
    connected region that differs from it by more than 12 % of full scale (sRGB distance). The
    face looks towards the side whose outline has the larger bump (the nose) over its running
    median in the middle half of the rows.

    Raises
    ------
    InputError
        No subject distinct from the background, or one touching both sides of the image.
    """
    from scipy import ndimage

    img = np.asarray(image, float)[..., :3] / 255.0
    h, w = img.shape[:2]
    border = np.concatenate([img[0], img[-1], img[:, 0], img[:, -1]])
    bg = np.median(border, axis=0)
    fg = np.linalg.norm(img - bg, axis=-1) > 0.12
    lab, n = ndimage.label(fg)
    if n == 0:
        raise InputError("no subject distinct from the background in the profile photo",
                         source=source or None, field="--profile")
    sizes = ndimage.sum(fg, lab, index=np.arange(1, n + 1))
    sub = lab == 1 + int(np.argmax(sizes))
    sub = ndimage.binary_fill_holes(sub)
    rows = np.flatnonzero(sub.any(axis=1))
    if len(rows) < 20:
        raise InputError("the subject in the profile photo is too small", source=source or None,
                         field="--profile")
    left = np.array([np.argmax(sub[r]) for r in rows], float)
    right = np.array([w - 1 - np.argmax(sub[r, ::-1]) for r in rows], float)
    k = len(rows)
    mid = slice(k // 4, 3 * k // 4)
    window = max(k // 6, 3)
    bump_left = np.max((ndimage.median_filter(left, window, mode="nearest") - left)[mid])
    bump_right = np.max((right - ndimage.median_filter(right, window, mode="nearest"))[mid])
    front = -left if bump_left > bump_right else right
    return ProfileSilhouette(rows.astype(float), front, source)
