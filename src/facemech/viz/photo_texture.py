"""A photo painted on the fitted face: texture coordinates, the baked texture and its blend.

The fitted face (:mod:`photo_fit`) keeps the generic grid, whose nodes lie on rows of constant
height and columns of constant angle around the head. That grid, unrolled, is the texture's
layout: ``u`` runs with the angle from the right ear (0) to the left ear (1), ``v`` with the
generic height from the throat (0) to the hairline (1). Every texel is a point of the fitted
surface; :func:`bake_photo_texture` looks it up in the photo through the fitted camera, and
blends it into a skin tone taken from the photo where the photo sees the skin at a grazing
angle or not at all (the sides towards the ears, under the chin).

The photo's expression is not the talker's skin: its lips, teeth and mouth interior are not
painted on it (:func:`_neutral_mouth`). Texels on the fitted (closed) lips take the photo's lip
colour, those around them the skin near the mouth; hair over the forehead gives way to the skin
tone (:func:`_hair_free`); the hair's colour is measured above the forehead
(:func:`.photo_hair.hair_colour`) and kept with the texture for the renderer's hair. The
renderer lights the texture (:func:`facemech.viz.raster.vertex_light`); a photo is already
lit. With ``delight`` the photo is divided by the renderer's own light at each texel's normal
(seen from the front), so that a frontal re-render gives the photo's colours back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import generic
from ..geometry.appearance import Appearance
from ..geometry.mesh import vertex_normals
from ..geometry.photo_fit import PhotoFit
from .photo_hair import hair_colour

#: texels of the baked texture, (height, width)
TEXTURE_SIZE = (1024, 1024)
#: the cosine between the skin's normal and the view to the camera under which the photo is not
#: used, and over which it is used alone (a smooth step between)
GRAZING = (0.15, 0.45)
#: the renderer's skin gloss (strength, exponent), as :func:`facemech.viz.face_parts.skin_part`
SKIN_GLOSS = (0.10, 16.0)
#: the width of the blend inside the face's outline in the photo, a share of the jaw's width
FEATHER = 0.04
#: the weakest renderer light a texel is divided by (deep shadow would blow the colour up)
MIN_LIGHT = 0.3
#: texels, the Gaussian over which the photo's skin is carried out beyond what it sees, and the
#: share of seen texels in it under which it fades into the one skin tone of the whole head
FILL_SIGMA, FILL_FADE = 48.0, 0.35


@dataclass(frozen=True)
class BakedTexture:
    """The texture of a photo face.

    Attributes
    ----------
    appearance : the :class:`Appearance`: per-corner texture coordinates of the fitted surface's
        triangles and the baked image
    coverage : (h, w) float in [0, 1], how much of each texel is the photo (the rest is skin)
    skin : (3,) uint8, the skin tone the unseen parts are painted with (sRGB)
    lips : (3,) uint8, the lip colour painted on the fitted lips (sRGB), or None where the
        photo's lips are not seen
    hair : (3,) uint8, the hair's colour (sRGB), or None where no hair is found (the
        renderer keeps its own)
    note : a phrase on the hair's colour
    """

    appearance: Appearance
    coverage: np.ndarray
    skin: np.ndarray
    lips: np.ndarray | None = None
    hair: np.ndarray | None = None
    note: str = ""


def grid_uv(fit: PhotoFit) -> np.ndarray:
    """Texture coordinates (n, 2) of the fitted face's nodes (OpenGL: u right, v up)."""
    g = fit.generic_vertices * 1e3
    w = generic._width(np.clip(g[:, 1], generic.Y_BOTTOM, generic.Y_TOP))
    e = 2.0 / generic.SUPERELLIPSE_N
    s = np.clip(g[:, 0] / w, -1.0, 1.0)
    theta = np.arcsin(np.sign(s) * np.abs(s) ** (1.0 / e))
    tmax = np.abs(theta).max()
    u = 0.5 + 0.5 * theta / tmax
    v = (g[:, 1] - generic.Y_BOTTOM) / (generic.Y_TOP - generic.Y_BOTTOM)
    return np.clip(np.column_stack([u, v]), 0.0, 1.0)


def bake_photo_texture(fit: PhotoFit, photo: np.ndarray, *, delight: bool = True,
                       source: str = "", size: tuple[int, int] = TEXTURE_SIZE) -> BakedTexture:
    """Bake the photo onto the fitted face's texture.

    Parameters
    ----------
    fit : the generic face fitted to the photo
    photo : (h, w, 3) uint8 sRGB, the photo the fit was made on
    delight : divide the photo by the renderer's light (see the module's docstring)
    source : the photo's file, kept as the appearance's source
    size : (height, width) of the texture, texels

    Returns
    -------
    BakedTexture
    """
    uv = grid_uv(fit)
    rows, cols = _grid_shape(uv)
    th, tw = size
    order = np.argsort(uv[::cols, 1])
    normals = vertex_normals(fit.vertices, fit.faces)
    field = np.concatenate([fit.vertices, normals], axis=1).reshape(rows, cols, 6)[order]
    tu = (np.arange(tw) + 0.5) / tw
    tv = 1.0 - (np.arange(th) + 0.5) / th  # row 0 at the top of the image
    field = _lerp_axis(_lerp_axis(field, uv[:cols, 0], tu, 1), uv[::cols, 1][order], tv, 0)
    pts, nrm = field[..., :3].reshape(-1, 3), field[..., 3:].reshape(-1, 3)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    cosine = np.einsum("ij,ij->i", nrm, fit.camera.view_direction(pts))
    px = fit.camera.project(pts)
    photo_h, photo_w = photo.shape[:2]
    lo, hi = GRAZING
    t = np.clip((cosine - lo) / (hi - lo), 0.0, 1.0)
    weight = (t * t * (3 - 2 * t) * ((px[:, 0] >= 0.5) & (px[:, 0] <= photo_w - 0.5)
                                     & (px[:, 1] >= 0.5) & (px[:, 1] <= photo_h - 0.5)))
    seen = np.flatnonzero(weight > 0)  # the photo is looked up only where it is used
    top = float(fit.camera.project(fit.vertices)[:, 1].min())
    weight[seen] *= _outline_weight(fit.image_points, (photo_h, photo_w), px[seen], top)
    seen = seen[weight[seen] > 0]
    colour = np.zeros((len(pts), 3))
    colour[seen] = _photo_colour(photo, px[seen], nrm[seen] if delight else None)
    skin = _skin_tone(colour, weight, pts, fit)
    weight[seen] *= _hair_free(colour[seen], skin, pts[seen], fit)
    colour[seen], lips = _neutral_mouth(colour[seen], weight[seen], px[seen], fit)
    fill = _skin_fill(colour, weight, skin, (th, tw))
    out = weight[:, None] * colour + (1 - weight[:, None]) * fill
    image = _linear_to_srgb8(out).reshape(th, tw, 3)
    corner_uv = uv[fit.faces].astype(np.float32)
    hair, note = hair_colour(photo, fit.image_points)
    app = Appearance(uv=corner_uv, image=image, source=source, hair=hair)
    return BakedTexture(app, weight.reshape(th, tw), _linear_to_srgb8(skin),
                        None if lips is None else _linear_to_srgb8(lips), hair, note)


def _lerp_axis(values: np.ndarray, at: np.ndarray, to: np.ndarray, axis: int) -> np.ndarray:
    """``values`` sampled at the increasing coordinates ``at`` along ``axis``, interpolated
    (linearly, extrapolated beyond the ends) to the coordinates ``to``."""
    i = np.clip(np.searchsorted(at, to) - 1, 0, len(at) - 2)
    f = (to - at[i]) / (at[i + 1] - at[i])
    shape = [1] * values.ndim
    shape[axis] = len(to)
    f = f.reshape(shape)
    return (np.take(values, i, axis=axis) * (1 - f) + np.take(values, i + 1, axis=axis) * f)


def _photo_colour(photo: np.ndarray, px: np.ndarray, normals: np.ndarray | None) -> np.ndarray:
    """Linear colours (n, 3) of the photo at image points ``px`` (n, 2) px (bilinear); with
    ``normals`` (n, 3), divided by the renderer's light there (the module's docstring)."""
    h, w = photo.shape[:2]
    x = np.clip(px[:, 0] - 0.5, 0.0, w - 1.0)
    y = np.clip(px[:, 1] - 0.5, 0.0, h - 1.0)
    x0 = np.minimum(x.astype(int), max(w - 2, 0))
    y0 = np.minimum(y.astype(int), max(h - 2, 0))
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    rgb = np.asarray(photo)[..., :3]

    def at(dy, dx):
        return _SRGB_TO_LINEAR[rgb[y0 + dy, x0 + dx]]

    colour = ((1 - fy) * ((1 - fx) * at(0, 0) + fx * at(0, 1))
              + fy * ((1 - fx) * at(1, 0) + fx * at(1, 1)))
    if normals is None:
        return colour
    diffuse, spec = _renderer_light(normals)
    return np.clip((colour - spec[:, None]) / np.maximum(diffuse, MIN_LIGHT)[:, None], 0.0, 1.0)


#: share of the mouth's width around the photo's outer lip line that is repainted (the lips'
#: edge, the smile's folds at the corners)
MOUTH_MARGIN = 0.12
#: the blend from the repainted mouth to the photo, a share of the mouth's width
MOUTH_FEATHER = 0.06


def _polygon_depth(poly: np.ndarray, px: np.ndarray) -> np.ndarray:
    """Signed distance (px) of image points ``px`` (n, 2) to the outline of the polygon
    (k, 2) px: positive inside, negative outside."""
    from matplotlib.path import Path as Polygon

    px = np.asarray(px, float)
    poly = np.asarray(poly, float)
    nearest = np.full(len(px), np.inf)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        ab = b - a
        t = np.clip((px - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        nearest = np.minimum(nearest, np.hypot(*(px - a - t[:, None] * ab).T))
    return np.where(Polygon(poly).contains_points(px), nearest, -nearest)


def _neutral_mouth(colour: np.ndarray, weight: np.ndarray, px: np.ndarray,
                   fit: PhotoFit) -> tuple[np.ndarray, np.ndarray | None]:
    """The texels' colours (n, 3) linear with the photo's mouth repainted, and the lip colour.

    Texels that look up the photo within :data:`MOUTH_MARGIN` of its outer lip line (iBUG
    48-59) are repainted: inside the fitted, closed lips
    (the fitted face's outer lip line, iBUG 48-59, seen through the photo's camera)
    with the photo's lip colour (the median of the reddest half of the texels on the photo's
    lips, between its outer and inner lip lines: teeth and the dark mouth are not), elsewhere
    with the skin round the mouth (the median of a ring outside the repainted area).
    """
    pts = np.asarray(fit.image_points, float)
    width = float(np.linalg.norm(pts[54] - pts[48]))
    margin, feather = MOUTH_MARGIN * width, max(MOUTH_FEATHER * width, 1.0)
    outer = _polygon_depth(pts[48:60], px)
    near = np.flatnonzero(outer > -(margin + 3 * feather))  # the rest keeps the photo
    inner, closed = np.full(len(px), -np.inf), np.full(len(px), -np.inf)
    inner[near] = _polygon_depth(pts[60:68], px[near])
    closed[near] = _polygon_depth(fit.camera.project(fit.ibug[48:60]), px[near])
    on_lips = (outer > 1.0) & (inner < -1.0) & (weight > 0.5)
    lips = None
    if on_lips.sum() >= 20:
        c = colour[on_lips]
        red = (c[:, 0] - c[:, 1]) / np.maximum(c.sum(axis=1), 1e-6)
        lips = np.median(c[red >= np.median(red)], axis=0)
    ring = (outer < -(margin + feather)) & (outer > -(margin + 3 * feather)) & (weight > 0.5)
    if ring.sum() < 20 or lips is None:
        return colour, lips
    around = np.median(colour[ring], axis=0)
    t = np.clip((outer + margin + feather) / feather, 0.0, 1.0)
    repaint = t * t * (3 - 2 * t)
    s = np.clip(closed / max(0.02 * width, 0.75) + 0.5, 0.0, 1.0)
    paint = s[:, None] * lips + (1 - s[:, None]) * around
    return (1 - repaint[:, None]) * colour + repaint[:, None] * paint, lips


def _hair_free(colour: np.ndarray, skin: np.ndarray, pts: np.ndarray,
               fit: PhotoFit) -> np.ndarray:
    """Weights (n,) in [0, 1] that let the skin tone replace hair over the forehead: above the
    brows (iBUG 17-26), texels much darker than the skin (luma under half of its) or far from
    its hue get weight 0, with a soft step between."""
    brow = float(fit.ibug[17:27, 1].max())
    luma = colour @ np.array([0.2126, 0.7152, 0.0722])
    skin_luma = float(skin @ np.array([0.2126, 0.7152, 0.0722]))
    dark = np.clip((luma / max(skin_luma, 1e-6) - 0.45) / 0.2, 0.0, 1.0)
    hue = colour / np.maximum(colour.sum(axis=1, keepdims=True), 1e-6) - skin / max(
        float(skin.sum()), 1e-6)
    off_hue = np.clip(1.5 - np.linalg.norm(hue, axis=1) / 0.08, 0.0, 1.0)
    above = pts[:, 1] > brow + 0.004
    return np.where(above, np.minimum(dark, off_hue), 1.0)


def _skin_fill(colour: np.ndarray, weight: np.ndarray, skin: np.ndarray,
                size: tuple[int, int]) -> np.ndarray:
    """What the texels (n, 3) linear the photo does not see are painted with: the photo's own
    skin carried outward (its Gaussian mean over :data:`FILL_SIGMA` texels, weighted by how
    much of each texel is the photo), fading into the skin tone ``skin`` (3,) where few seen
    texels are near (:data:`FILL_FADE`), so that the texture meets the head's one colour
    without a seam. The means are taken on texels grouped 8 x 8 and interpolated back (the
    Gaussian is wide)."""
    from scipy.ndimage import gaussian_filter, zoom

    th, tw = size
    k = 8
    hk, wk = th // k, tw // k
    w = weight.reshape(th, tw)[:hk * k, :wk * k].reshape(hk, k, wk, k).mean(axis=(1, 3))
    cw = (colour * weight[:, None]).reshape(th, tw, 3)[:hk * k, :wk * k].reshape(
        hk, k, wk, k, 3).mean(axis=(1, 3))
    sigma = FILL_SIGMA / k
    near = gaussian_filter(w, sigma, mode="nearest")
    mean = np.stack([gaussian_filter(cw[..., c], sigma, mode="nearest") for c in range(3)],
                    axis=-1)
    local = mean / np.maximum(near, 1e-6)[..., None]
    t = np.clip(near / FILL_FADE, 0.0, 1.0)[..., None]
    t = t * t * (3 - 2 * t)
    small = t * local + (1 - t) * skin
    full = np.stack([zoom(small[..., c], (th / hk, tw / wk), order=1, mode="nearest",
                          grid_mode=True) for c in range(3)], axis=-1)
    return full.reshape(-1, 3)


def _outline_weight(points: np.ndarray, size: tuple[int, int], px: np.ndarray,
                    top: float) -> np.ndarray:
    """How far (0..1) image points ``px`` (n, 2) lie inside the face's outline in the photo.

    The outline: the jaw line (iBUG 0-16), closed over the forehead by half a super-ellipse
    (exponent 4, a rounded box) from its ends up to a tenth of the jaw's width over the image
    row ``top`` (the fitted face's hairline, px); 1 from
    :data:`FEATHER` of the jaw's width inside it, 0 outside. The photo's background never
    paints the skin.
    """
    from matplotlib.path import Path as Polygon
    from scipy.ndimage import distance_transform_edt, map_coordinates

    h, w = size
    jaw = np.asarray(points[:17], float)
    centre = 0.5 * (jaw[0] + jaw[-1])
    half = 0.5 * (jaw[-1, 0] - jaw[0, 0])
    rise = max(centre[1] - top, 1.0) + 0.2 * half
    a = np.linspace(0.0, np.pi, 33)[1:-1]
    c, s = np.cos(a), np.sin(a)  # a super-ellipse of exponent 4: a rounded box
    cap = np.column_stack([centre[0] + half * np.sign(c) * np.sqrt(np.abs(c)),
                           centre[1] - rise * np.sqrt(s)])
    poly = np.concatenate([jaw, cap])
    lo = np.floor(np.clip(poly.min(axis=0) - 2, 0, None)).astype(int)
    hi = np.ceil(np.minimum(poly.max(axis=0) + 2, [w, h])).astype(int)
    yy, xx = np.mgrid[lo[1]:hi[1], lo[0]:hi[0]]
    inside = Polygon(poly).contains_points(np.column_stack([xx.ravel() + 0.5,
                                                            yy.ravel() + 0.5])).reshape(xx.shape)
    depth = distance_transform_edt(inside)
    feather = max(FEATHER * float(np.ptp(jaw[:, 0])), 1.0)
    d = map_coordinates(depth, [px[:, 1] - 0.5 - lo[1], px[:, 0] - 0.5 - lo[0]], order=1,
                        mode="constant")
    t = np.clip(d / feather, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _grid_shape(uv: np.ndarray) -> tuple[int, int]:
    """(rows, cols) of the generic grid the fitted face keeps (:data:`PHOTO_RESOLUTION`)."""
    from ..geometry.photo_fit import PHOTO_RESOLUTION

    rows, cols = PHOTO_RESOLUTION
    cols += 1 - cols % 2
    if rows * cols != len(uv):
        raise ValueError(f"{len(uv)} nodes is not the generic grid's {rows} x {cols}")
    return rows, cols


def _skin_tone(colour: np.ndarray, weight: np.ndarray, pts: np.ndarray,
               fit: PhotoFit) -> np.ndarray:
    """The photo's skin (linear RGB, (3,)): the median of the cheeks it sees face on.

    The cheeks: under the eyes, over the mouth corners, outside the nose (10 mm from the
    midline) and inside the cheek landmarks.
    """
    lm = fit.landmarks
    eye_y = 0.5 * (lm["eye_left"][1] + lm["eye_right"][1])
    mouth_y = 0.5 * (lm["mouth_corner_left"][1] + lm["mouth_corner_right"][1])
    half = 0.5 * abs(lm["cheek_left"][0] - lm["cheek_right"][0])
    ax = np.abs(pts[:, 0] - 0.5 * (lm["cheek_left"][0] + lm["cheek_right"][0]))
    cheek = ((pts[:, 1] < eye_y - 0.012) & (pts[:, 1] > mouth_y) & (ax > 0.018) & (ax < half)
             & (weight > 0.99))
    if cheek.sum() < 50:
        cheek = weight > 0.99
    if not cheek.any():
        return np.array([0.62, 0.39, 0.27])  # the renderer's skin tone (textures.SKIN), linear
    return np.median(colour[cheek], axis=0)


def _renderer_light(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Diffuse light and highlight (n,) of the renderer at unit normals seen from the front."""
    from .raster import GROUND, LIGHTS, SKY, WRAP, vertex_light

    lights = np.concatenate([LIGHTS[:, :3] / np.linalg.norm(LIGHTS[:, :3], axis=1,
                                                            keepdims=True), LIGHTS[:, 3:]],
                            axis=1)
    gloss = np.tile(np.array(SKIN_GLOSS), (len(normals), 1))
    light = vertex_light(normals.astype(np.float64), gloss, lights, SKY, GROUND, WRAP)
    return light[:, 0].astype(float), light[:, 1].astype(float)


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB in [0, 1] to linear light (IEC 61966-2-1)."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


#: linear light of each sRGB level 0-255
_SRGB_TO_LINEAR = _srgb_to_linear(np.arange(256) / 255.0)
#: the linear light at which the nearest sRGB level goes from k - 1 to k (k = 1..255)
_SRGB_STEPS = _srgb_to_linear((np.arange(1, 256) - 0.5) / 255.0)


def _linear_to_srgb8(c: np.ndarray) -> np.ndarray:
    """Linear light to the nearest sRGB level, uint8 (as ``round(255 * sRGB(c))``)."""
    return np.searchsorted(_SRGB_STEPS, np.asarray(c, float), side="right").astype(np.uint8)
