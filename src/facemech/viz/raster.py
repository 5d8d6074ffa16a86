"""Headless software rendering of a shaded triangle mesh (no display, no GPU).

A z-buffered scan-converter written in numba with Gouraud-interpolated Lambert + Blinn-Phong
shading. Orthographic views are enough for face movies and need no camera set-up.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..geometry.builder import vertex_normals

SKIN_RGB = np.array([0.87, 0.68, 0.58])
BACKGROUND_RGB = np.array([0.16, 0.17, 0.20])


def view_rotation(azimuth_deg: float, elevation_deg: float = 0.0) -> np.ndarray:
    """Rotation taking model coordinates to camera coordinates (camera looks along -z).

    ``azimuth_deg = 0`` is the frontal view; ``90`` looks at the subject's right profile.
    """
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    ry = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
    return rx @ ry


@nb.njit(cache=True)
def _rasterise(px, py, pz, shade, faces, zbuf, img, colour):
    h, w = zbuf.shape
    for f in range(faces.shape[0]):
        i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
        x0, y0, x1, y1, x2, y2 = px[i0], py[i0], px[i1], py[i1], px[i2], py[i2]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if abs(area) < 1e-12:
            continue
        xmin = max(int(np.floor(min(x0, min(x1, x2)))), 0)
        xmax = min(int(np.ceil(max(x0, max(x1, x2)))), w - 1)
        ymin = max(int(np.floor(min(y0, min(y1, y2)))), 0)
        ymax = min(int(np.ceil(max(y0, max(y1, y2)))), h - 1)
        inv = 1.0 / area
        for yy in range(ymin, ymax + 1):
            fy = yy + 0.5
            for xx in range(xmin, xmax + 1):
                fx = xx + 0.5
                w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) * inv
                w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) * inv
                w2 = 1.0 - w0 - w1
                if w0 < 0 or w1 < 0 or w2 < 0:
                    continue
                z = w0 * pz[i0] + w1 * pz[i1] + w2 * pz[i2]
                if z <= zbuf[yy, xx]:
                    continue
                zbuf[yy, xx] = z
                s = w0 * shade[i0] + w1 * shade[i1] + w2 * shade[i2]
                for ch in range(3):
                    c = (w0 * colour[i0, ch] + w1 * colour[i1, ch] + w2 * colour[i2, ch])
                    v = c * s[0] + s[1]
                    img[yy, xx, ch] = min(max(v, 0.0), 1.0)


def render(
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    rotation: np.ndarray,
    size: tuple[int, int] = (480, 360),
    extent: float | None = None,
    centre: np.ndarray | None = None,
    colour: np.ndarray = SKIN_RGB,
) -> np.ndarray:
    """Render a mesh to an RGB image.

    Parameters
    ----------
    vertices : (n, 3) array
        Positions in any length unit (the view is scaled to ``extent``).
    faces : (f, 3) int array
    rotation : (3, 3) array
        Model-to-camera rotation (see :func:`view_rotation`).
    size : (height, width)
    extent : float, optional
        Half-height of the view in the vertices' unit; defaults to fit the mesh.
    centre : (3,) array, optional
        Model point at the image centre; defaults to the bounding-box centre.
    colour : (3,) RGB in [0, 1] for the whole surface, or (n, 3) per vertex

    Returns
    -------
    (height, width, 3) uint8 array
    """
    h, w = size
    v = np.asarray(vertices, float)
    if centre is None:
        centre = 0.5 * (v.min(axis=0) + v.max(axis=0))
    cam = (v - centre) @ rotation.T
    if extent is None:
        extent = 0.55 * max(np.ptp(cam[:, 1]), np.ptp(cam[:, 0]) * h / w)
    scale = 0.5 * h / extent
    px = w / 2 + cam[:, 0] * scale
    py = h / 2 - cam[:, 1] * scale
    pz = cam[:, 2]
    normals = vertex_normals(v, faces) @ rotation.T
    light = np.array([0.35, 0.45, 0.82])
    light /= np.linalg.norm(light)
    half = light + np.array([0.0, 0.0, 1.0])
    half /= np.linalg.norm(half)
    diffuse = np.clip(normals @ light, 0.0, 1.0)
    spec = np.clip(normals @ half, 0.0, 1.0) ** 40
    shade = np.stack([0.25 + 0.75 * diffuse, 0.18 * spec], axis=1)
    zbuf = np.full((h, w), -np.inf)
    img = np.empty((h, w, 3))
    img[:] = BACKGROUND_RGB
    colours = np.asarray(colour, float)
    if colours.ndim == 1:
        colours = np.broadcast_to(colours, (len(v), 3))
    _rasterise(px, py, pz, shade, np.ascontiguousarray(faces, dtype=np.int64), zbuf, img,
               np.ascontiguousarray(colours))
    return (img * 255 + 0.5).astype(np.uint8)
