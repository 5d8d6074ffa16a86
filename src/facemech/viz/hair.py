"""Scalp hair with volume and a soft, irregular hairline.

The hair is one layer over the head (skin and closure, :mod:`.closure`), lifted off the scalp
by the hair's thickness: 0.2 mm up to the top of the fringe (below), growing over 25 mm above
it to 9 mm on the
crown and the back (a short haircut's volume, which moves the silhouette out as real hair
does). Its texture over (longitude, latitude) about the head's centre is made of strands that
run from the crown down the meridians. Towards the hairline the strands thin out: a strand
is kept where its own random threshold lies under the hair's density, which ramps from 0
3 mm under the hairline to 1 3 mm above it, so the hairline breaks into strand tips over
skin rather than a painted band's edge; the hairline itself wanders by up to 2 mm
(low-frequency noise) round :func:`.head.hairline`. The strands' cut-outs are alpha-tested,
only in that band, over a skin-coloured strip half way to the scalp (so that at the head's
silhouette the gaps show skin, not the background). The strands' colour is the built-in
:data:`.textures.HAIR`, or a colour measured on a photo (:func:`strand_base`).
"""

from __future__ import annotations

import numpy as np

from . import textures as T
from .mesh import Part
from .raster import rasterise

STEP_DEG = 2.5  #: grid step of the hair layer, degrees of longitude and latitude
TEXELS_PER_DEGREE = 4  #: of the strand texture
THICKNESS = 0.009  #: m, the hair's thickness on the crown and the back
LIFT = 0.0002  #: m, the hair's thickness at the hairline
RAMP = 0.025  #: m above the hairline over which the thickness grows
FRINGE = 0.006  #: m across the hairline over which the strands' density grows from 0 to 1
WANDER = 0.002  #: m, the hairline's low-frequency wander
HAIR_GLOSS = (0.06, 12.0)  #: specular strength and exponent of hair
SKIN_GLOSS = (0.10, 16.0)  #: of the strip under the fringe (the skin's)
UNDER_GAP = 0.00003  #: m, the strip under the fringe lies this far under the strands
#: a strand's shade: the base colour times SHADE[0] + SHADE[1] rank + SHADE[2] lock, with its
#: rank uniform in 0..1 and its lock's in -1..1 (median 0.87)
SHADE = (0.62, 0.5, 0.18)
#: the hair's normal a frontal view sees most, (3,): forward and up
SEEN_NORMAL = np.array([0.0, 0.5, 0.866])


def strand_base(colour: np.ndarray) -> np.ndarray:
    """The strands' base colour (3,) sRGB in [0, 1] that renders as ``colour`` ((3,) uint8
    sRGB, as a photo shows the hair) in a frontal view: the colour in linear light divided by
    the renderer's diffuse light on :data:`SEEN_NORMAL`, back to sRGB, over the median
    shade."""
    from .raster import GROUND, LIGHTS, SKY, WRAP, srgb_to_linear, vertex_light

    lights = np.concatenate([LIGHTS[:, :3] / np.linalg.norm(LIGHTS[:, :3], axis=1,
                                                            keepdims=True), LIGHTS[:, 3:]],
                            axis=1)
    light = vertex_light(SEEN_NORMAL[None].astype(np.float64), np.array([HAIR_GLOSS]),
                         lights, SKY, GROUND, WRAP)[0].astype(float)
    lin = srgb_to_linear(np.asarray(colour, float) / 255.0).astype(float)
    seen = np.clip(lin / light[0], 0.0, 1.0)
    srgb = np.where(seen <= 0.0031308, 12.92 * seen, 1.055 * seen ** (1 / 2.4) - 0.055)
    return np.clip(srgb / (SHADE[0] + 0.5 * SHADE[1]), 0.0, 1.0)


def surface_radius(verts: np.ndarray, faces: np.ndarray, centre: np.ndarray, lat: np.ndarray,
                   lon: np.ndarray) -> np.ndarray:
    """Distance (len(lat), len(lon)) m from ``centre`` to the outermost crossing of a closed
    surface along each (latitude, longitude) ray, degrees, longitude 0 forward (+z), 90 to
    the subject's left (+x). Rays no triangle covers take the nearest covered ray's value."""
    from scipy import ndimage

    rel = verts - centre
    dist = np.linalg.norm(rel, axis=1)
    vlat = np.degrees(np.arcsin(np.clip(rel[:, 1] / dist, -1, 1)))
    vlon = np.degrees(np.arctan2(rel[:, 0], rel[:, 2]))
    step_lat = lat[1] - lat[0]
    step_lon = lon[1] - lon[0]
    px = ((vlon - lon[0]) / step_lon + 0.5).astype(np.float32)
    py = ((vlat - lat[0]) / step_lat + 0.5).astype(np.float32)
    tris = np.asarray(faces, np.int32)
    tris = tris[np.ptp(vlon[tris], axis=1) < 180.0]  # not across longitude 180
    both = np.concatenate([tris, tris[:, ::-1]]).astype(np.int32)
    shape = (len(lat), len(lon))
    z = np.full(shape, -np.inf, np.float32)
    tid = np.full(shape, -1, np.int32)
    bary = np.zeros((*shape, 2), np.float32)
    rasterise(px, py, dist.astype(np.float32), both, np.zeros((len(both), 3, 2), np.float32),
              np.zeros(len(both), np.int8), np.zeros(len(both), bool),
              np.zeros(len(both), bool), np.ones((1, 1, 4), np.float32), z, tid, bary)
    covered = tid >= 0
    idx = ndimage.distance_transform_edt(~covered, return_distances=False,
                                         return_indices=True)
    return z[idx[0], idx[1]].astype(float)


def hair_parts(verts: np.ndarray, faces: np.ndarray, centre: np.ndarray,
               hairline, colour: np.ndarray | None = None) -> list[Part]:
    """The hair layer over a closed head, and the skin-coloured strip under its fringe.

    Parameters
    ----------
    verts, faces : the head's closed surface at rest (skin and closure), m
    centre : (3,) m, the head's centre
    hairline : function (longitude deg, 0 forward) -> height (m) of the hairline
    colour : (3,) uint8 sRGB, the hair's colour as a photo shows it, or None (the built-in)
    """
    lat = np.arange(-60.0, 90.0 + 1e-9, STEP_DEG)
    lon = np.arange(-180.0, 180.0 + 1e-9, STEP_DEG)
    r = surface_radius(verts, faces, centre, lat, lon)
    LA, LO = np.meshgrid(np.radians(lat), np.radians(lon), indexing="ij")
    d = np.stack([np.cos(LA) * np.sin(LO), np.sin(LA), np.cos(LA) * np.cos(LO)], -1)
    y = centre[1] + r * d[..., 1]
    line = hairline(lon)[None, :] + _wander(lon)[None, :]
    above = y - line
    # the layer lifts off only above the fringe: where its strands are cut out it lies on the
    # scalp, so that what shows between them is skin, also at the head's silhouette
    s = np.clip((above - 0.5 * FRINGE) / RAMP, 0.0, 1.0)
    thick = LIFT + (THICKNESS - LIFT) * s * s * (3 - 2 * s) * _clumps(len(lat), len(lon))
    pts = centre + d * (r + thick)[..., None]
    n_lat, n_lon = len(lat), len(lon)
    from .mesh import grid_faces

    f = grid_faces(n_lat, n_lon)  # columns run towards +x from the front: outward
    keep = (above.ravel()[f] > -FRINGE).any(axis=1)
    f = f[keep]
    base = T.HAIR if colour is None else strand_base(colour)
    tex, _ = _strand_texture(lat, lon, above, base)
    tpd = TEXELS_PER_DEGREE
    u = (np.broadcast_to(lon[None, :], (n_lat, n_lon)) - lon[0]) * tpd
    v = (lat[-1] - np.broadcast_to(lat[:, None], (n_lat, n_lon))) * tpd
    uv = np.stack([u.ravel(), v.ravel()], -1)[f]
    # the texture folded in two (the subject's right half above the left), so that the atlas
    # it joins stays narrow; no triangle crosses longitude 0, a column of the grid
    th, tw = tex.shape[:2]
    half = (tw - 1) // 2
    left = (lon[f % n_lon] >= 0).all(axis=1)
    uv[left, :, 0] -= half
    uv[left, :, 1] += th + 2
    tex = np.concatenate([tex[:, :half + 1], np.repeat(tex[-1:, :half + 1], 2, axis=0),
                          tex[:, half:]])
    albedo = np.tile(base, (n_lat * n_lon, 1))
    hair = Part("hair", pts.reshape(-1, 3), f, albedo, HAIR_GLOSS, "skull", uv, tex,
                alpha_test=True)
    # under the fringe, just under the strands, a skin-coloured strip: between the strands one
    # sees skin, also where the fringe stands against the background at the head's silhouette
    # (a line of sight grazing the layer passes between them and the strip over a chord of
    # 2 sqrt(2 r gap): the gap is kept small)
    fringe = f[(above.ravel()[f] < 0.5 * FRINGE + 0.002).any(axis=1)]
    under = centre + d * (r + thick - UNDER_GAP)[..., None]
    strip = Part("hair_under", under.reshape(-1, 3), fringe, np.tile(T.SKIN, (n_lat * n_lon, 1)),
                 SKIN_GLOSS, "skull")
    return [hair, strip]


def _clumps(n_lat: int, n_lon: int) -> np.ndarray:
    """(n_lat, n_lon) factor 0.8-1.2 of the hair's thickness: locks about 10 degrees across,
    longer down the meridians, so that the silhouette is lumpy, not a shell's."""
    from scipy import ndimage

    rng = np.random.default_rng(23)
    n = ndimage.gaussian_filter(rng.standard_normal((n_lat, n_lon)), (3.0, 1.5),
                                mode=("nearest", "wrap"))
    n[:, -1] = n[:, 0]  # longitude -180 and 180 are one meridian
    return 1.0 + 0.2 * np.tanh(n / (n.std() + 1e-12))


def _wander(lon: np.ndarray) -> np.ndarray:
    """Low-frequency wander (m) of the hairline round its mean, periodic in longitude."""
    rng = np.random.default_rng(5)
    k = np.arange(3, 9)
    amp = rng.normal(0, 1, len(k)) / k
    phase = rng.uniform(0, 2 * np.pi, len(k))
    w = (amp[:, None] * np.sin(k[:, None] * np.radians(lon)[None, :] + phase[:, None])).sum(0)
    return WANDER * w / np.abs(w).max()


def _strand_texture(lat: np.ndarray, lon: np.ndarray, above: np.ndarray,
                    base: np.ndarray = T.HAIR):
    """RGBA strands of ``base`` colour (sRGB) over the hair layer's (lon, lat) grid, row 0 at
    the top latitude, and the density (texels) of the fringe."""
    from scipy import ndimage

    tpd = TEXELS_PER_DEGREE
    th = int(round((lat[-1] - lat[0]) * tpd)) + 1
    tw = int(round((lon[-1] - lon[0]) * tpd)) + 1
    rng = np.random.default_rng(17)
    # strands: noise stretched along the meridians (rows), thin across them
    noise = ndimage.gaussian_filter(rng.standard_normal((th, tw)), (3.0, 0.5),
                                    mode=("nearest", "wrap"))
    noise = (noise - noise.mean()) / noise.std()
    rank = 0.5 * (1.0 + np.tanh(noise / np.sqrt(2)))  # roughly uniform in 0..1
    # height above the hairline at each texel (bilinear in the layer's grid)
    gy = (lat[-1] - lat[0]) - np.arange(th) / tpd  # rows from the top, in grid degrees
    gx = np.arange(tw) / tpd
    GY, GX = np.meshgrid(gy / (lat[1] - lat[0]), gx / (lon[1] - lon[0]), indexing="ij")
    h = ndimage.map_coordinates(above, [GY, GX], order=1, mode="nearest")
    density = np.clip(h / FRINGE + 0.5, 0.0, 1.0)  # one half on the hairline
    alpha = (rank < density).astype(float)
    # strands light and dark, in locks a few degrees across
    lock = ndimage.gaussian_filter(rng.standard_normal((th, tw)), (12.0, 4.0),
                                   mode=("nearest", "wrap"))
    lock = np.tanh(lock / (lock.std() + 1e-12))
    shade = SHADE[0] + SHADE[1] * rank[..., None] + SHADE[2] * lock[..., None]
    rgb = np.clip(base * shade, 0, 1)
    return np.concatenate([rgb, alpha[..., None]], axis=-1), density
