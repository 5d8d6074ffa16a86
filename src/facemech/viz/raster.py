"""Headless software rasteriser (numba, one core, no display, no GPU).

A visibility-buffer renderer: a first pass scan-converts the triangles into a supersampled
z-buffer that keeps, per sample, the nearest triangle and two barycentric weights; a second pass
shades the samples in linear light and box-filters them to pixels (anti-aliasing), shading a
pixel once where all its samples see one triangle (as multisampling does), blends them over the
background and converts to sRGB. Light is computed per vertex (wrapped diffuse key, fill and
rim lights under a sky/ground ambient, and a Blinn-Phong highlight of the key light) and
interpolated (Gouraud); the albedo comes per pixel from the texture or per vertex. Texture
lookups are bilinear in a single RGBA atlas; a texel with alpha below one half discards the
sample (the eye fissures are cut this way).

The projection (:class:`facemech.viz.camera.Camera`) has already taken the vertices to image
sample coordinates: ``x`` right, ``y`` down, ``z`` towards the viewer (larger is nearer).
"""

from __future__ import annotations

import numba as nb
import numpy as np

#: light directions in camera space (x right, y up, z towards the viewer) and intensities
LIGHTS = np.array([
    [-0.45, 0.55, 0.70, 0.80],   # key: above, to the viewer's left
    [0.65, 0.05, 0.75, 0.32],    # fill: the other side, lower and softer
    [0.00, 0.60, -0.80, 0.22],   # rim: from behind and above
])  # fmt: skip
SKY, GROUND = 0.26, 0.14  #: hemisphere ambient (linear) from above and from below
WRAP = 0.35  #: diffuse wrap: light bleeds past the terminator as in translucent skin
EDGE_EPS = 1e-6  #: barycentric slack: a sample on an edge shared by two triangles is never lost
INSIDE = (0.012, 0.004, 0.004)  #: linear colour of the skin's inner side (inside the mouth)


def srgb_to_linear(c):
    """sRGB in [0, 1] to linear light (IEC 61966-2-1)."""
    c = np.asarray(c, np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


_LUT = np.clip(
    np.where((g := np.linspace(0.0, 1.0, 4096)) <= 0.0031308, 12.92 * g,
             1.055 * g ** (1 / 2.4) - 0.055), 0.0, 1.0) * 255.0
LINEAR_TO_SRGB_LUT = (_LUT + 0.5).astype(np.uint8)


@nb.njit(cache=True)
def _atlas_alpha(atlas, u, v):
    h, w = atlas.shape[0], atlas.shape[1]
    iu = min(max(int(u), 0), w - 1)
    iv = min(max(int(v), 0), h - 1)
    return atlas[iv, iu, 3]


@nb.njit(cache=True)
def rasterise(px, py, pz, tris, uv, tex, alpha_test, two_sided, atlas, zbuf, tid, bary):
    """Scan-convert triangles into a visibility buffer (in place).

    Back faces are skipped, except those of ``two_sided`` triangles, which are recorded as
    triangle ``f + len(tris)`` (the inside of the skin, seen through the lips or the lids).

    Parameters
    ----------
    px, py, pz : (n,) float32 sample-space coordinates (x right, y down, z nearer is larger)
    tris : (f, 3) int32 vertex indices, counter-clockwise seen from the front
    uv : (f, 3, 2) float32 atlas texel coordinates per corner
    tex : (f,) int8, 1 where the triangle is textured
    alpha_test : (f,) bool, texels with alpha < 0.5 discard the sample
    two_sided : (f,) bool, draw the back face too
    atlas : (H, W, 4) float32 linear RGBA
    zbuf : (h, w) float32, -inf where empty
    tid : (h, w) int32 triangle index, -1 where empty
    bary : (h, w, 2) float32 weights of the first two corners
    """
    h, w = zbuf.shape
    nt = tris.shape[0]
    for f in range(nt):
        i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
        x0, y0, x1, y1, x2, y2 = px[i0], py[i0], px[i1], py[i1], px[i2], py[i2]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        # y points down: front faces have negative area
        if abs(area) < 1e-9 or (area > 0 and not two_sided[f]):
            continue
        label = f if area < 0 else f + nt
        xmin = max(int(np.floor(min(x0, min(x1, x2)))), 0)
        xmax = min(int(np.ceil(max(x0, max(x1, x2)))), w - 1)
        ymin = max(int(np.floor(min(y0, min(y1, y2)))), 0)
        ymax = min(int(np.ceil(max(y0, max(y1, y2)))), h - 1)
        if xmin > xmax or ymin > ymax:
            continue
        inv = 1.0 / area
        z0, z1, z2 = pz[i0], pz[i1], pz[i2]
        test = alpha_test[f] and area < 0  # a cut-out shows the inside of its rim
        # barycentric weights are affine in x: on each row, solve for the span where all three
        # are >= 0 and step them along it
        a0 = (y1 - y2) * inv
        a1 = (y2 - y0) * inv
        a2 = -a0 - a1
        for yy in range(ymin, ymax + 1):
            fy = yy + 0.5
            fx = xmin + 0.5
            w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) * inv
            w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) * inv
            lo, hi = xmin, xmax
            empty = False
            for wk, ak in ((w0, a0), (w1, a1), (1.0 - w0 - w1, a2)):
                if ak > 1e-12:
                    lo = max(lo, xmin + int(np.ceil((-EDGE_EPS - wk) / ak - 1e-6)))
                elif ak < -1e-12:
                    hi = min(hi, xmin + int(np.floor((-EDGE_EPS - wk) / ak + 1e-6)))
                elif wk < -EDGE_EPS:
                    empty = True
            if empty or lo > hi:
                continue
            w0 += a0 * (lo - xmin)
            w1 += a1 * (lo - xmin)
            for xx in range(lo, hi + 1):
                w2 = 1.0 - w0 - w1
                if w0 >= -EDGE_EPS and w1 >= -EDGE_EPS and w2 >= -EDGE_EPS:
                    z = w0 * z0 + w1 * z1 + w2 * z2
                    if z > zbuf[yy, xx]:
                        keep = True
                        if test:
                            u = w0 * uv[f, 0, 0] + w1 * uv[f, 1, 0] + w2 * uv[f, 2, 0]
                            v = w0 * uv[f, 0, 1] + w1 * uv[f, 1, 1] + w2 * uv[f, 2, 1]
                            keep = _atlas_alpha(atlas, u, v) >= 0.5
                        if keep:
                            zbuf[yy, xx] = z
                            tid[yy, xx] = label
                            bary[yy, xx, 0] = w0
                            bary[yy, xx, 1] = w1
                w0 += a0
                w1 += a1


@nb.njit(cache=True, fastmath=True)
def _bilinear(atlas, u, v, out):
    h, w = atlas.shape[0], atlas.shape[1]
    u = min(max(u - 0.5, 0.0), w - 1.001)
    v = min(max(v - 0.5, 0.0), h - 1.001)
    iu, iv = int(u), int(v)
    fu, fv = u - iu, v - iv
    for c in range(3):
        out[c] = ((1 - fu) * (1 - fv) * atlas[iv, iu, c] + fu * (1 - fv) * atlas[iv, iu + 1, c]
                  + (1 - fu) * fv * atlas[iv + 1, iu, c] + fu * fv * atlas[iv + 1, iu + 1, c])


def vertex_light(normals: np.ndarray, gloss: np.ndarray, lights: np.ndarray, sky: float,
                 ground: float, wrap: float) -> np.ndarray:
    """Diffuse light and specular highlight at each vertex, (n, 2) float32 (Gouraud shading).

    ``normals`` (n, 3) are unit camera-space normals (the viewer along +z), ``gloss`` (n, 2)
    the specular strength and Blinn-Phong exponent, ``lights`` (k, 4) unit directions and
    intensities. Diffuse: a sky/ground hemisphere plus each light wrapped by ``wrap``;
    highlights of the first (key) light only.
    """
    n = normals
    t = 0.5 * (n[:, 1] + 1.0)
    diff = sky * t + ground * (1.0 - t)
    for lx, ly, lz, li in lights:
        d = n[:, 0] * lx + n[:, 1] * ly + n[:, 2] * lz
        diff = diff + li * np.clip((d + wrap) / (1.0 + wrap), 0.0, None)
    key = lights[0]
    half = key[:3] + np.array([0.0, 0.0, 1.0])
    half = half / np.linalg.norm(half)
    c = np.clip(n @ half, 0.0, 1.0)
    facing = (n @ key[:3]) > 0
    spec = np.where(facing, key[3] * gloss[:, 0] * c ** gloss[:, 1], 0.0)
    return np.stack([diff, spec], axis=1).astype(np.float32)


@nb.njit(cache=True, inline="always", fastmath=True)
def _shade_sample(f, w0, w1, tris, light, albedo, uv, tex, atlas, col):
    """Linear RGB of one sample of triangle ``f`` at barycentric weights (w0, w1), into col."""
    if f >= tris.shape[0]:  # the inside of a two-sided surface: unlit, dark
        for c in range(3):
            col[c] = INSIDE[c]
        return
    w2 = 1.0 - w0 - w1
    i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
    diff = w0 * light[i0, 0] + w1 * light[i1, 0] + w2 * light[i2, 0]
    spec = w0 * light[i0, 1] + w1 * light[i1, 1] + w2 * light[i2, 1]
    if tex[f]:
        u = w0 * uv[f, 0, 0] + w1 * uv[f, 1, 0] + w2 * uv[f, 2, 0]
        v = w0 * uv[f, 0, 1] + w1 * uv[f, 1, 1] + w2 * uv[f, 2, 1]
        _bilinear(atlas, u, v, col)
        for c in range(3):
            col[c] = col[c] * diff + spec
    else:
        for c in range(3):
            col[c] = (w0 * albedo[i0, c] + w1 * albedo[i1, c] + w2 * albedo[i2, c]) * diff + spec


@nb.njit(cache=True, fastmath=True)
def shade_resolve(tid, bary, s, tris, light, albedo, uv, tex, atlas, background, lut, rgba):
    """Shade the samples and box-filter s x s of them per pixel into sRGB uint8 RGBA.

    A pixel whose samples all show one triangle is shaded once, at the mean of their weights
    (as multisampling does); edge pixels are shaded per sample. ``light`` (n, 2) is
    :func:`vertex_light`'s, ``albedo`` (n, 3) linear RGB. ``background`` is (4,) linear RGB
    and alpha; alpha 0 gives a transparent background with the coverage in the alpha channel.
    """
    h, w = rgba.shape[0], rgba.shape[1]
    col = np.empty(3, np.float32)
    ns = s * s
    m = lut.shape[0] - 1
    for yy in range(h):
        for xx in range(w):
            t0 = tid[yy * s, xx * s]
            same = True
            for j in range(s):
                for i in range(s):
                    if tid[yy * s + j, xx * s + i] != t0:
                        same = False
            r = g = b = 0.0
            cov = 0.0
            if same and t0 >= 0:
                a0 = a1 = 0.0
                for j in range(s):
                    for i in range(s):
                        a0 += bary[yy * s + j, xx * s + i, 0]
                        a1 += bary[yy * s + j, xx * s + i, 1]
                _shade_sample(t0, a0 / ns, a1 / ns, tris, light, albedo, uv, tex, atlas, col)
                r, g, b, cov = col[0] * ns, col[1] * ns, col[2] * ns, float(ns)
            elif not same:
                for j in range(s):
                    for i in range(s):
                        f = tid[yy * s + j, xx * s + i]
                        if f >= 0:
                            _shade_sample(f, bary[yy * s + j, xx * s + i, 0],
                                          bary[yy * s + j, xx * s + i, 1], tris, light,
                                          albedo, uv, tex, atlas, col)
                            r += col[0]
                            g += col[1]
                            b += col[2]
                            cov += 1.0
            a_bg = background[3]
            if cov > 0:
                if a_bg > 0:
                    rem = ns - cov
                    r = (r + rem * background[0]) / ns
                    g = (g + rem * background[1]) / ns
                    b = (b + rem * background[2]) / ns
                    alpha = 1.0
                else:
                    r, g, b = r / cov, g / cov, b / cov
                    alpha = cov / ns
            else:
                r, g, b, alpha = background[0], background[1], background[2], a_bg
            rgba[yy, xx, 0] = lut[min(int(min(max(r, 0.0), 1.0) * m + 0.5), m)]
            rgba[yy, xx, 1] = lut[min(int(min(max(g, 0.0), 1.0) * m + 0.5), m)]
            rgba[yy, xx, 2] = lut[min(int(min(max(b, 0.0), 1.0) * m + 0.5), m)]
            rgba[yy, xx, 3] = int(alpha * 255 + 0.5)
