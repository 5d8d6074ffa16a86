"""The palpebral fissures of a textured face: cut out of its own texture, and its eye colours.

A face without its own texture gets its fissures cut by the procedural skin
(:func:`.textures.skin_texture`). A face with a texture image (a scan, a photo talker) carries
its eyes painted on the skin: they could neither blink nor look around. Here the same fissure
(:func:`.textures.eye_mask`, an adult's: 28 mm long, 10 mm high, centred on the face's
``eye_left`` / ``eye_right`` landmark) is cut from that image's alpha, so that the renderer's
eyeballs and lids (:func:`.face_parts.eye_parts`) are seen through it, and the lids and the
iris take the colours the texture has around and inside each fissure.

Every texel of the image that lies on the skin within :data:`NEAR` of an eye is found by
rasterising the skin's triangles in texture space (:func:`texels_near`): the texel's point on the
rest skin is the barycentric mix of its triangle's corners. The cut is then the fissure's depth
at that point's frontal (x, y) over two texels, as the procedural skin's (the alpha crosses one
half on the margin, and the renderer's bilinear alpha test follows that contour).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import textures as T
from .look import FaceLook

#: m, how far from an eye's landmark (3-D) the skin's triangles are searched for its texels:
#: the fissure's half length (14 mm) and the lids around it (up to 6 mm above and below)
NEAR = 0.024
#: m, the band of the upper and lower lid's skin whose colour the drawn lids take: from this far
#: beyond the fissure's margin (past the lashes) to :data:`LID_BAND`'s second value
LID_BAND = (0.0015, 0.006)
#: m, the iris's colour is read within this distance of the eye's centre (the iris, 11.8 mm
#: across, fills it when the gaze is ahead)
IRIS_READ = 0.0045
#: m, the rim outside the cut whose texels, where brighter than the lids' skin, are painted with
#: it: a photo's eye white showing past the drawn fissure (a fit places the photo's eye within a
#: millimetre of the landmark; on the tests' photo talker the eye white reached 0.4 and 1.0 mm
#: past the cut); full to the first value, fading out at the second
RIM = (0.0010, 0.0016)
#: the luminance (0-1) over the lids' skin's at which a rim texel is painted over fully
RIM_BRIGHTER = 0.08
#: m, the steps and the farthest shift of the fissure tried against the texture's own eye
#: (:func:`register_eye`)
SHIFT_STEP, SHIFT_MAX = 0.0005, 0.003
#: m, the ring outside the fissure its contrast is taken against (:func:`register_eye`)
RING = (0.0005, 0.0025)
#: at most about this many texels are compared per shift (every k-th of those round the eye)
REGISTER_TEXELS = 12000
#: sides of the face: (sign of x, eye landmark)
SIDES = ((1, "eye_left"), (-1, "eye_right"))


@dataclass(frozen=True)
class EyeColours:
    """The colours a textured face's drawn eyes take from its texture (sRGB in [0, 1]).

    Attributes
    ----------
    lid : (3,) the skin of the lids (the texture's median over :data:`LID_BAND`)
    iris : (3,) the iris (the median of the texels within :data:`IRIS_READ` of the eye's
        centre inside the fissure between the fifth and the seventh tenth of their luma: the
        darkest, pupil and lashes, and the brightest, eye white and glints, left out); both
        eyes take that of the eye with fewer clipped texels there
    """

    lid: np.ndarray
    iris: np.ndarray


@dataclass(frozen=True)
class Fissures:
    """A textured face's fissures cut from its image, and its eye colours per side.

    Attributes
    ----------
    alpha : (h, w) float in [0, 1], the image's alpha: 0 inside the fissures
    colours : eye landmark name -> :class:`EyeColours`
    image : (h, w, 3) float sRGB in [0, 1], the image with the rim round each cut (:data:`RIM`)
        painted with the lids' skin where it was brighter
    eyes : eye landmark name -> (3,) m, the fissure's centre cut and drawn: the landmark moved
        onto the texture's own eye (:func:`register_eye`)
    """

    alpha: np.ndarray
    colours: dict
    image: np.ndarray
    eyes: dict


def can_cut(look: FaceLook) -> bool:
    """Whether the face's eyes can be drawn: it has both eye landmarks, and either no texture of
    its own (the procedural skin cuts the fissures) or a texture image with texture coordinates
    (vertex colours cannot be cut)."""
    if not all(name in look.landmarks for _, name in SIDES):
        return False
    if not look.textured:
        return True
    return look.image is not None and look.uv is not None


def texels_near(look: FaceLook, shape: tuple[int, int], centre: np.ndarray,
                radius: float = NEAR) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The texels of a textured skin whose triangle lies within ``radius`` of ``centre``.

    Parameters
    ----------
    look : a face with ``uv`` (f, 3, 2) per-corner texture coordinates (OpenGL: v up)
    shape : (h, w) of the texture image
    centre : (3,) m, rest position
    radius : m; a triangle is taken when one of its corners lies within it (3-D)

    Returns
    -------
    rows, cols : (k,) int, the texels (row 0 at the image's top)
    points : (k, 3) m, each texel's point on the rest skin
    size : (k,) m, the texel's size on the skin there (the square root of its triangle's area
        over the triangle's area in texels)
    """
    h, w = shape
    tri = np.asarray(look.triangles)
    corners = look.rest[tri]  # (f, 3, 3)
    near = np.linalg.norm(corners - np.asarray(centre, float), axis=2).min(axis=1) < radius
    rows, cols, pts, size = [], [], [], []
    for f in np.flatnonzero(near):
        uv = np.asarray(look.uv[f], float)
        q = np.column_stack([uv[:, 0] * w, (1.0 - uv[:, 1]) * h])  # texel units, y down
        e1, e2 = q[1] - q[0], q[2] - q[0]
        det = e1[0] * e2[1] - e1[1] * e2[0]
        if abs(det) < 1e-12:
            continue
        c0, r0 = np.floor(q.min(axis=0)).astype(int)
        c1, r1 = np.ceil(q.max(axis=0)).astype(int)
        cc, rr = np.meshgrid(np.arange(max(c0, 0), min(c1, w - 1) + 1),
                             np.arange(max(r0, 0), min(r1, h - 1) + 1))
        d = np.column_stack([cc.ravel() + 0.5, rr.ravel() + 0.5]) - q[0]
        b1 = (d[:, 0] * e2[1] - d[:, 1] * e2[0]) / det
        b2 = (e1[0] * d[:, 1] - e1[1] * d[:, 0]) / det
        inside = (b1 >= -1e-9) & (b2 >= -1e-9) & (b1 + b2 <= 1.0 + 1e-9)
        if not inside.any():
            continue
        b1, b2 = b1[inside], b2[inside]
        p = corners[f]
        pts.append(p[0] + b1[:, None] * (p[1] - p[0]) + b2[:, None] * (p[2] - p[0]))
        rows.append(rr.ravel()[inside])
        cols.append(cc.ravel()[inside])
        area = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
        size.append(np.full(len(b1), np.sqrt(area / (0.5 * abs(det)))))
    if not rows:
        return (np.zeros(0, int), np.zeros(0, int), np.zeros((0, 3)), np.zeros(0))
    return (np.concatenate(rows), np.concatenate(cols), np.concatenate(pts),
            np.concatenate(size))


def cut_fissures(look: FaceLook, image: np.ndarray) -> Fissures:
    """The fissures of a textured face cut from its image (h, w, 3) sRGB in [0, 1] (the
    image the renderer uses, :func:`.face_parts._fit_texture`), and its eye colours.

    A texel that two triangles share (the texture's seams) takes the smaller alpha. Without
    texels near an eye (no texture there) that side keeps the generic colours.
    """
    h, w = image.shape[:2]
    alpha = np.ones((h, w))
    out = np.array(image[..., :3], float)
    colours, clipped, eyes = {}, {}, {}
    for side, name in SIDES:
        e = np.asarray(look.landmarks[name], float)
        rows, cols, pts, size = texels_near(look, (h, w), e)
        if len(rows) == 0:
            continue
        rgb = image[rows, cols, :3]
        e = e + np.array([*register_eye(rgb, pts, e, side), 0.0])
        eyes[name] = e
        depth = T.eye_mask(pts[:, 0], pts[:, 1], e, side)  # m, > 0 inside the fissure
        np.minimum.at(alpha, (rows, cols), np.clip(0.5 - depth / (2.0 * size), 0.0, 1.0))
        eye, clipped[name] = _eye_colours(rgb, pts, e, side)
        colours[name] = eye
        # the rim: brighter than the lids' skin is the photo's eye white past the cut
        rim = np.clip((depth + RIM[1]) / (RIM[1] - RIM[0]), 0.0, 1.0) * (depth < 0)
        brighter = np.clip((_luma(rgb) - _luma(eye.lid)) / RIM_BRIGHTER, 0.0, 1.0)
        k = (rim * brighter)[:, None]
        out[rows, cols] = rgb * (1.0 - k) + k * eye.lid
    if colours:
        # one iris colour for both eyes: the eye whose iris texels are the least clipped
        best = colours[min(clipped, key=clipped.get)].iris
        colours = {n: replace(c, iris=best) for n, c in colours.items()}
    return Fissures(alpha, colours, out, eyes)


def register_eye(rgb: np.ndarray, pts: np.ndarray, eye: np.ndarray, side: int) -> np.ndarray:
    """(2,) m: how far to move the fissure (x, y) onto the eye the texture shows.

    A face's eye landmark can lie a millimetre or two off the eye its texture shows (a fitted
    mesh's landmarks sit on its nodes, 2 mm apart; a scan's are annotated by hand). The
    fissure is shifted by each step of :data:`SHIFT_STEP` up to :data:`SHIFT_MAX` each way,
    and the shift whose fissure differs most from the ring round it (:data:`RING`) is kept:
    the mean distance of the colours inside from the area's median colour (the skin), less
    that of the ring. Ties keep the smallest shift.

    Parameters
    ----------
    rgb : (k, 3) the texels' colours round the eye
    pts : (k, 3) m, their points on the rest skin
    eye : (3,) m, the eye's landmark
    side : 1 for the left eye (+x), -1 for the right
    """
    every = max(len(pts) // REGISTER_TEXELS, 1)  # a sample of the texels is enough
    rgb, pts = np.asarray(rgb, float)[::every], np.asarray(pts, float)[::every]
    odd = np.linalg.norm(rgb - np.median(rgb, axis=0), axis=1)
    steps = np.arange(-SHIFT_MAX, SHIFT_MAX + 1e-12, SHIFT_STEP)
    best, best_score = np.zeros(2), -np.inf
    for dx in steps:
        for dy in steps:
            m = T.eye_mask(pts[:, 0], pts[:, 1], eye + np.array([dx, dy, 0.0]), side)
            inside, ring = m > 0, (m < -RING[0]) & (m > -RING[1])
            if inside.sum() < 8 or ring.sum() < 8:
                continue
            score = odd[inside].mean() - odd[ring].mean()
            if score > best_score + 1e-12 or (abs(score - best_score) <= 1e-12
                                               and np.hypot(dx, dy) < np.hypot(*best)):
                best, best_score = np.array([dx, dy]), score
    return best


def _eye_colours(rgb: np.ndarray, pts: np.ndarray, eye: np.ndarray,
                 side: int) -> tuple[EyeColours, float]:
    """The lid and iris colours (sRGB) of one eye from its texels' colours (k, 3) and rest
    points (k, 3) m, and the share of the iris's texels with a channel at 0 or 1 (clipped:
    a photo's texture divided by the renderer's light loses the dark iris where it takes out
    the skin's highlight, :mod:`.photo_texture`)."""
    s, hh = T.eye_frame(pts[:, 0], pts[:, 1], eye, side)
    up, lo = T.fissure_heights(s)
    along = np.abs(s) < 0.8
    beyond = np.maximum(hh - up, lo - hh)  # m past the nearer margin (< 0 inside)
    band = along & (beyond > LID_BAND[0]) & (beyond < LID_BAND[1])
    lid = np.median(rgb[band], axis=0) if band.sum() >= 8 else T.SKIN.copy()
    inside = (np.abs(s) < 1.0) & (np.minimum(up - hh, hh - lo) > 5e-4)
    near = inside & (np.hypot(pts[:, 0] - eye[0], pts[:, 1] - eye[1]) < IRIS_READ)
    iris, clipped = T.IRIS.copy(), 1.0
    if near.sum() >= 8:
        c = rgb[near]
        order = np.argsort(_luma(c))
        n = len(order)
        c = c[order[int(0.2 * n):max(int(0.7 * n), int(0.2 * n) + 1)]]
        iris = np.median(c, axis=0)
        clipped = float(np.mean(np.any((c <= 1.0 / 255.0) | (c >= 254.0 / 255.0), axis=1)))
    return EyeColours(np.clip(lid, 0.0, 1.0), np.clip(iris, 0.0, 1.0)), clipped


def _luma(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luma of sRGB colours (..., 3)."""
    return np.asarray(rgb, float) @ np.array([0.2126, 0.7152, 0.0722])
