"""Headless software rasteriser (numba, one core per call, no display, no GPU).

A visibility-buffer renderer: a first pass scan-converts the triangles into a supersampled
z-buffer that keeps, per sample, the nearest triangle and two barycentric weights; a second pass
shades the samples in linear light and box-filters them to pixels (anti-aliasing), shading a
pixel once where all its samples see one triangle (as multisampling does), blends them over the
background and converts to sRGB. Light is computed per vertex (wrapped diffuse key, fill and
rim lights under a sky/ground ambient, and a Blinn-Phong highlight of the key light) and
interpolated (Gouraud); the albedo comes per pixel from the texture or per vertex. Texture
lookups are bilinear in a single RGBA atlas; where the bilinear alpha is below one half the
sample is discarded (the eye fissures are cut this way).

The kernels release the GIL (``nogil``): a movie's frames are drawn on several threads at
once, each with its own buffers (:mod:`.frame_pool`).

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


@nb.njit(cache=True, nogil=True)
def _atlas_alpha(atlas, u, v):
    """The atlas's alpha at texel coordinates (u, v): the nearest texel's where it is 0 or 1,
    else bilinear (as the colour is). A cut-out whose alpha ramps over two texels across its
    edge (the eye fissures) has a smooth outline at its 0.5 contour, not the staircase of
    its texels; a texel of alpha 0 or 1 lies a texel or more from that contour, where the
    bilinear alpha is on the same side of one half, so a binary cut-out (the hairline's
    strands) and the plain texels cost one lookup."""
    h, w = atlas.shape[0], atlas.shape[1]
    a = atlas[min(max(int(v), 0), h - 1), min(max(int(u), 0), w - 1), 3]
    if a == 0.0 or a == 1.0:
        return a
    u = min(max(u - 0.5, 0.0), w - 1.001)
    v = min(max(v - 0.5, 0.0), h - 1.001)
    iu, iv = int(u), int(v)
    fu, fv = u - iu, v - iv
    return ((1 - fv) * ((1 - fu) * atlas[iv, iu, 3] + fu * atlas[iv, iu + 1, 3])
            + fv * ((1 - fu) * atlas[iv + 1, iu, 3] + fu * atlas[iv + 1, iu + 1, 3]))


TILE = 8  #: samples per side of the tiles whose nearest depth culls the inner sides


@nb.njit(cache=True, nogil=True)
def rasterise(px, py, pz, tris, uv, tex, alpha_test, two_sided, atlas, zbuf, tid, bary):
    """Scan-convert triangles into a visibility buffer (in place), one sample at the centre of
    each cell (:func:`rasterise_grid` with s = 1; its parameters)."""
    rasterise_grid(px, py, pz, tris, uv, tex, alpha_test, two_sided, atlas, (zbuf, tid, bary),
                   1)


@nb.njit(cache=True, nogil=True)
def rasterise_grid(px, py, pz, tris, uv, tex, alpha_test, two_sided, atlas, buffers, s):
    """Scan-convert triangles into a visibility buffer (in place).

    With ``s`` > 1 (the buffer holds s x s samples per pixel) the samples lie on a rotated
    grid (:func:`sample_offsets`): each of a pixel's s^2 samples has an x and a y of its own,
    so a near-horizontal or near-vertical edge (a lid's margin) passes s^2 + 1 coverage
    levels, not the s + 1 of an ordered grid.

    Back faces are skipped, except those of ``two_sided`` triangles, which are recorded as
    triangle ``f + len(tris)`` (the inside of the skin, seen through the lips or the lids).
    The inner sides are drawn after every front face, tile by tile (:data:`TILE` samples a
    side), skipping the tiles whose nearest depth so far lies in front of the triangle's
    nearest corner: from outside, a closed head's inner side shows only through its openings,
    and most of it (the back of the head, behind the face) need not be scanned at all. The
    depth test is the same either way; the result differs from drawing in index order only
    where two triangles share a sample's depth exactly.

    Parameters
    ----------
    px, py, pz : (n,) float32 sample-space coordinates (x right, y down, z nearer is larger)
    tris : (f, 3) int32 vertex indices, counter-clockwise seen from the front
    uv : (f, 3, 2) float32 atlas texel coordinates per corner
    tex : (f,) int8, 1 where the triangle is textured
    alpha_test : (f,) bool, texels with alpha < 0.5 discard the sample
    two_sided : (f,) bool, draw the back face too
    atlas : (H, W, 4) float32 linear RGBA
    buffers : (zbuf, tid, bary): (h, w) float32 depth, -inf where empty; (h, w) int32
        triangle index, -1 where empty; (h, w, 2) float32 weights of the first two corners
    s : samples per pixel along each axis (the buffer's supersampling)
    """
    zbuf, tid, bary = buffers
    h, w = zbuf.shape
    nt = tris.shape[0]
    inner = np.zeros(nt, np.bool_)
    n_inner = 0
    for f in range(nt):
        i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
        area = (px[i1] - px[i0]) * (py[i2] - py[i0]) - (px[i2] - px[i0]) * (py[i1] - py[i0])
        # y points down: front faces have negative area
        if abs(area) < 1e-9:
            continue
        if area > 0:
            if two_sided[f]:
                inner[f] = True
                n_inner += 1
            continue
        _scan(f, f, (px, py, pz), tris, uv, alpha_test[f], atlas, (zbuf, tid, bary),
              (0, w - 1, 0, h - 1), s)
    if n_inner == 0:
        return
    th, tw = (h + TILE - 1) // TILE, (w + TILE - 1) // TILE
    nearest = np.full((th, tw), np.inf, np.float32)  # the smallest depth so far in each tile
    for yy in range(h):
        ty = yy // TILE
        for xx in range(w):
            z = zbuf[yy, xx]
            if z < nearest[ty, xx // TILE]:
                nearest[ty, xx // TILE] = z
    for f in range(nt):
        if not inner[f]:
            continue
        i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
        z0, z1, z2 = pz[i0], pz[i1], pz[i2]
        # a sample's weights may undershoot by EDGE_EPS: a margin keeps the cull conservative
        top = max(z0, max(z1, z2)) + 1e-5 * (abs(z0) + abs(z1) + abs(z2)) + 1e-9
        xmin = max(int(np.floor(min(px[i0], min(px[i1], px[i2])))), 0)
        xmax = min(int(np.ceil(max(px[i0], max(px[i1], px[i2])))), w - 1)
        ymin = max(int(np.floor(min(py[i0], min(py[i1], py[i2])))), 0)
        ymax = min(int(np.ceil(max(py[i0], max(py[i1], py[i2])))), h - 1)
        for ty in range(ymin // TILE, ymax // TILE + 1):
            for tx in range(xmin // TILE, xmax // TILE + 1):
                if nearest[ty, tx] >= top:
                    continue
                _scan(f, f + nt, (px, py, pz), tris, uv, False, atlas, (zbuf, tid, bary),
                      (max(xmin, tx * TILE), min(xmax, tx * TILE + TILE - 1),
                       max(ymin, ty * TILE), min(ymax, ty * TILE + TILE - 1)), s)


@nb.njit(cache=True, nogil=True, inline="always")
def sample_offsets(index, s):
    """Offset (in samples) of a sample from its cell's centre, along the other axis: a
    sample in buffer row r lies at x + (s - 1 - r % s + 0.5) / s - 0.5 and one in column c at
    y + (c % s + 0.5) / s - 0.5 (``index`` = r or c). For s = 2 this is the rotated grid of
    4x multisampling hardware (offsets of +-1/8 pixel): four distinct x and four distinct y
    per pixel. s = 1: no offset."""
    if s <= 1:
        return 0.0, 0.0
    k = index & (s - 1) if s & (s - 1) == 0 else index % s  # a mask for s = 2, 4
    return (s - 1 - k + 0.5) / s - 0.5, (k + 0.5) / s - 0.5


@nb.njit(cache=True, nogil=True, inline="always")
def _scan(f, label, points, tris, uv, test, atlas, buffers, rect, s):
    """Scan-convert triangle ``f`` inside the sample rectangle ``rect`` = (cx0, cx1, cy0, cy1),
    recording ``label``; ``points`` = (px, py, pz) the projected vertices, ``buffers`` = (zbuf,
    tid, bary); ``test``: discard samples on texels of alpha < 0.5; ``s``: samples per pixel
    along each axis (their positions: :func:`sample_offsets`)."""
    px, py, pz = points
    zbuf, tid, bary = buffers
    cx0, cx1, cy0, cy1 = rect
    i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
    x0, y0, x1, y1, x2, y2 = px[i0], py[i0], px[i1], py[i1], px[i2], py[i2]
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    xmin = max(int(np.floor(min(x0, min(x1, x2)))), cx0)
    xmax = min(int(np.ceil(max(x0, max(x1, x2)))), cx1)
    ymin = max(int(np.floor(min(y0, min(y1, y2)))), cy0)
    ymax = min(int(np.ceil(max(y0, max(y1, y2)))), cy1)
    if xmin > xmax or ymin > ymax:
        return
    inv = 1.0 / area
    z0, z1, z2 = pz[i0], pz[i1], pz[i2]
    # barycentric weights are affine in x and y: on each row, solve for the span where all
    # three are >= 0 at any of the samples' y offsets (a conservative span), and step them
    # along it, testing each sample at its own y
    a0 = (y1 - y2) * inv
    a1 = (y2 - y0) * inv
    a2 = -a0 - a1
    b0 = (x2 - x1) * inv  # along y
    b1 = (x0 - x2) * inv
    b2 = -b0 - b1
    reach = 0.5 - 0.5 / s if s > 1 else 0.0  # the largest y offset
    for yy in range(ymin, ymax + 1):
        ox, _ = sample_offsets(yy, s)
        fy = yy + 0.5
        fx = xmin + 0.5 + ox
        w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) * inv
        w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) * inv
        lo, hi = xmin, xmax
        empty = False
        for wk, ak, bk in ((w0, a0, b0), (w1, a1, b1), (1.0 - w0 - w1, a2, b2)):
            wk += abs(bk) * reach
            if ak > 1e-12:
                lo = max(lo, xmin + int(np.ceil((-EDGE_EPS - wk) / ak - 1e-6)))
            elif ak < -1e-12:
                hi = min(hi, xmin + int(np.floor((-EDGE_EPS - wk) / ak + 1e-6)))
            elif wk < -EDGE_EPS:
                empty = True
        if empty or lo > hi:
            continue
        # one pass along the span: the first sample's weights at its own y, then a step of
        # one column and of 1/s in the y offset (back by (s - 1)/s when the column's class,
        # its index mod s, wraps to 0)
        k = lo & (s - 1) if s & (s - 1) == 0 else lo % s
        oy = (k + 0.5) / s - 0.5 if s > 1 else 0.0
        v0 = w0 + a0 * (lo - xmin) + b0 * oy
        v1 = w1 + a1 * (lo - xmin) + b1 * oy
        up0, up1 = a0 + b0 / s, a1 + b1 / s
        wrap0, wrap1 = a0 - b0 * (s - 1) / s, a1 - b1 * (s - 1) / s
        for xx in range(lo, hi + 1):
            v2 = 1.0 - v0 - v1
            if v0 >= -EDGE_EPS and v1 >= -EDGE_EPS and v2 >= -EDGE_EPS:
                z = v0 * z0 + v1 * z1 + v2 * z2
                if z > zbuf[yy, xx]:
                    keep = True
                    if test:
                        u = v0 * uv[f, 0, 0] + v1 * uv[f, 1, 0] + v2 * uv[f, 2, 0]
                        v = v0 * uv[f, 0, 1] + v1 * uv[f, 1, 1] + v2 * uv[f, 2, 1]
                        keep = _atlas_alpha(atlas, u, v) >= 0.5
                    if keep:
                        zbuf[yy, xx] = z
                        tid[yy, xx] = label
                        bary[yy, xx, 0] = v0
                        bary[yy, xx, 1] = v1
            if s == 1:  # an ordered grid: a plain step (the hot loop of the label buffers)
                v0 += a0
                v1 += a1
                continue
            k += 1
            if k == s:
                k = 0
                v0 += wrap0
                v1 += wrap1
            else:
                v0 += up0
                v1 += up1


def vertex_light(normals: np.ndarray, gloss: np.ndarray, lights: np.ndarray, sky: float,
                 ground: float, wrap: float) -> np.ndarray:
    """Diffuse light and specular highlight at each vertex, (n, 2) float32 (Gouraud shading).

    ``normals`` (n, 3) are unit camera-space normals (the viewer along +z), ``gloss`` (n, 2)
    the specular strength and Blinn-Phong exponent, ``lights`` (k, 4) unit directions and
    intensities. Diffuse: a sky/ground hemisphere plus each light wrapped by ``wrap``;
    highlights of the first (key) light only.
    """
    key = np.asarray(lights[0], float)
    half = key[:3] + np.array([0.0, 0.0, 1.0])
    half = half / np.linalg.norm(half)
    out = np.empty((len(normals), 2), np.float32)
    _vertex_light(np.ascontiguousarray(normals, np.float64),
                  np.ascontiguousarray(gloss, np.float64),
                  np.ascontiguousarray(lights, np.float64), half, float(sky), float(ground),
                  float(wrap), out)
    return out


@nb.njit(cache=True, nogil=True)
def _vertex_light(n, gloss, lights, half, sky, ground, wrap, out):
    for i in range(n.shape[0]):
        nx, ny, nz = n[i, 0], n[i, 1], n[i, 2]
        t = 0.5 * (ny + 1.0)
        diff = sky * t + ground * (1.0 - t)
        for k in range(lights.shape[0]):
            d = nx * lights[k, 0] + ny * lights[k, 1] + nz * lights[k, 2]
            diff += lights[k, 3] * max((d + wrap) / (1.0 + wrap), 0.0)
        spec = 0.0
        if nx * lights[0, 0] + ny * lights[0, 1] + nz * lights[0, 2] > 0:
            c = min(max(nx * half[0] + ny * half[1] + nz * half[2], 0.0), 1.0)
            spec = lights[0, 3] * gloss[i, 0] * c ** gloss[i, 1]
        out[i, 0] = diff
        out[i, 1] = spec


@nb.njit(cache=True, nogil=True, fastmath=True)
def _texel(atlas, u, v):
    """Bilinear linear (r, g, b) of the atlas at texel coordinates (u, v)."""
    h, w = atlas.shape[0], atlas.shape[1]
    u = min(max(u - 0.5, 0.0), w - 1.001)
    v = min(max(v - 0.5, 0.0), h - 1.001)
    iu, iv = int(u), int(v)
    fu, fv = u - iu, v - iv
    k00, k01 = (1 - fu) * (1 - fv), fu * (1 - fv)
    k10, k11 = (1 - fu) * fv, fu * fv
    r = (k00 * atlas[iv, iu, 0] + k01 * atlas[iv, iu + 1, 0] + k10 * atlas[iv + 1, iu, 0]
         + k11 * atlas[iv + 1, iu + 1, 0])
    g = (k00 * atlas[iv, iu, 1] + k01 * atlas[iv, iu + 1, 1] + k10 * atlas[iv + 1, iu, 1]
         + k11 * atlas[iv + 1, iu + 1, 1])
    b = (k00 * atlas[iv, iu, 2] + k01 * atlas[iv, iu + 1, 2] + k10 * atlas[iv + 1, iu, 2]
         + k11 * atlas[iv + 1, iu + 1, 2])
    return r, g, b


@nb.njit(cache=True, nogil=True, fastmath=True)
def shade_resolve(tid, bary, s, tris, light, albedo, uv, tex, atlas, background, lut, rgba):
    """Shade the samples and box-filter s x s of them per pixel into sRGB uint8 RGBA.

    Each triangle a pixel's samples show is shaded once, at the mean of those samples'
    weights, and weighted by their number (as multisampling does): a pixel inside a triangle
    is shaded once, one on an edge once per triangle. ``light`` (n, 2) is
    :func:`vertex_light`'s, ``albedo`` (n, 3) linear RGB. ``background`` is (4,) linear RGB
    and alpha; alpha 0 gives a transparent background with the coverage in the alpha channel.
    """
    h, w = rgba.shape[0], rgba.shape[1]
    ns = s * s
    nt = tris.shape[0]
    ids = np.empty(ns, np.int32)  # the pixel's triangles, their sample counts and weights
    cnt = np.empty(ns, np.float64)
    wa = np.empty(ns, np.float64)
    wb = np.empty(ns, np.float64)
    m = lut.shape[0] - 1
    for yy in range(h):
        for xx in range(w):
            t0 = tid[yy * s, xx * s]
            same = True
            for j in range(s):
                for i in range(s):
                    if tid[yy * s + j, xx * s + i] != t0:
                        same = False
            k = 0
            if same:
                if t0 >= 0:
                    a0 = a1 = 0.0
                    for j in range(s):
                        for i in range(s):
                            a0 += bary[yy * s + j, xx * s + i, 0]
                            a1 += bary[yy * s + j, xx * s + i, 1]
                    ids[0], cnt[0], wa[0], wb[0] = t0, ns, a0, a1
                    k = 1
            else:
                # shade each triangle the pixel's samples see once, at the mean of its
                # samples' weights, weighted by their number (as multisampling does)
                for j in range(s):
                    for i in range(s):
                        f = tid[yy * s + j, xx * s + i]
                        if f < 0:
                            continue
                        q = 0
                        while q < k and ids[q] != f:
                            q += 1
                        if q == k:
                            ids[k] = f
                            cnt[k] = 0.0
                            wa[k] = 0.0
                            wb[k] = 0.0
                            k += 1
                        cnt[q] += 1.0
                        wa[q] += bary[yy * s + j, xx * s + i, 0]
                        wb[q] += bary[yy * s + j, xx * s + i, 1]
            r = g = b = 0.0
            cov = 0.0
            for q in range(k):
                # one sample of triangle f at the mean weights (w0, w1): the albedo (bilinear
                # in the atlas, or per vertex) times the diffuse light, plus the highlight
                # (written out here: numba's inlining of a helper that returned a tuple from
                # several places made this resolve two to three times slower)
                f, c = ids[q], cnt[q]
                w0, w1 = wa[q] / c, wb[q] / c
                if f >= nt:  # the inside of a two-sided surface: unlit, dark
                    cr, cg, cb = INSIDE[0], INSIDE[1], INSIDE[2]
                else:
                    w2 = 1.0 - w0 - w1
                    i0, i1, i2 = tris[f, 0], tris[f, 1], tris[f, 2]
                    diff = w0 * light[i0, 0] + w1 * light[i1, 0] + w2 * light[i2, 0]
                    spec = w0 * light[i0, 1] + w1 * light[i1, 1] + w2 * light[i2, 1]
                    if tex[f]:
                        cr, cg, cb = _texel(atlas,
                                            w0 * uv[f, 0, 0] + w1 * uv[f, 1, 0] + w2 * uv[f, 2, 0],
                                            w0 * uv[f, 0, 1] + w1 * uv[f, 1, 1] + w2 * uv[f, 2, 1])
                    else:
                        cr = w0 * albedo[i0, 0] + w1 * albedo[i1, 0] + w2 * albedo[i2, 0]
                        cg = w0 * albedo[i0, 1] + w1 * albedo[i1, 1] + w2 * albedo[i2, 1]
                        cb = w0 * albedo[i0, 2] + w1 * albedo[i1, 2] + w2 * albedo[i2, 2]
                    cr, cg, cb = cr * diff + spec, cg * diff + spec, cb * diff + spec
                r += cr * c
                g += cg * c
                b += cb * c
                cov += c
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
