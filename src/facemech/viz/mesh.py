"""Meshes of the rendered scene: the :class:`Part` type and the small geometric helpers the
parts are built with (spheres, grids, the skin's depth map, ellipsoids fitted inside the skin)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .look import FaceLook


@dataclass(frozen=True)
class Part:
    """A mesh of the scene. ``motion``: 'skin' (the results' nodes), 'skull', 'jaw',
    'skirt' (from the skin's edge inwards), 'follow' (the head closing the skin, its edge
    ring the skin's edge nodes), 'eye' (turns with the gaze), 'lid' (closes with the blink)
    or 'attached' (carried by the skin: ``follow`` is an :class:`.attach.Attachment`)."""

    name: str
    rest: np.ndarray  # (n, 3) m
    faces: np.ndarray  # (f, 3)
    albedo: np.ndarray  # (n, 3) sRGB
    gloss: tuple[float, float] | np.ndarray  # specular strength, Blinn-Phong exponent; or
    # per vertex (n, 2)
    motion: str = "skull"
    uv: np.ndarray | None = None  # (f, 3, 2) texel coordinates in ``texture``
    texture: np.ndarray | None = None  # (h, w, 4) sRGB + alpha
    alpha_test: bool = False
    inward: bool = False  # normals point inward (an interior seen from inside)
    tex_mask: np.ndarray | None = None  # (f,) bool: which triangles use the texture
    two_sided: np.ndarray | None = None  # (f,) bool: also draw the inner side (dark)
    skirt_nodes: np.ndarray | None = None  # motion 'skirt': the skin's edge nodes
    follow: object | None = None  # motion 'follow': a :class:`.closure.Closure`
    pivot: np.ndarray | None = None  # motion 'eye' / 'lid': the eyeball's centre, m


class VertexNormals:
    """Area-weighted unit vertex normals of one triangle list, for many vertex positions.

    The same normals as :func:`facemech.geometry.mesh.vertex_normals` (up to the order of the
    sums), a frame in a fraction of the time: the vertex-triangle incidence is a sparse matrix
    built once, where ``np.add.at`` would scatter the triangle normals afresh every frame.
    """

    def __init__(self, faces: np.ndarray, n_vertices: int):
        from scipy import sparse

        f = np.asarray(faces, np.int64)
        self.faces = f
        rows = f.T.ravel()
        cols = np.tile(np.arange(len(f)), 3)
        self.incidence = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)),
                                           shape=(n_vertices, len(f)))

    def __call__(self, vertices: np.ndarray) -> np.ndarray:
        """(n, 3) unit normals of vertices (n, 3); zero-area fans give (0, 0, 0)."""
        v = np.asarray(vertices, float)
        a, b, c = v[self.faces[:, 0]], v[self.faces[:, 1]], v[self.faces[:, 2]]
        vn = self.incidence @ np.cross(b - a, c - a)
        norm = np.sqrt(np.einsum("ij,ij->i", vn, vn))[:, None]
        return vn / np.where(norm > 0, norm, 1.0)


def sphere(n_lat: int, n_lon: int):
    """Unit UV sphere: vertices (n, 3) and outward triangles."""
    lat = np.linspace(-np.pi / 2, np.pi / 2, n_lat)
    lon = np.linspace(-np.pi, np.pi, n_lon, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    v = np.stack([np.cos(la) * np.sin(lo), np.sin(la), np.cos(la) * np.cos(lo)], -1)
    return v.reshape(-1, 3), grid_faces(n_lat, n_lon, wrap=True)


def grid_faces(rows: int, cols: int, wrap: bool = False) -> np.ndarray:
    """Triangles of a (rows, cols) vertex grid, counter-clockwise seen from outside.

    Rows go up (increasing latitude), columns go round (increasing longitude = towards +x from
    the front), which makes (a, b, c) with a=(r,c), b=(r,c+1), c=(r+1,c) outward.
    """
    faces = []
    cmax = cols if wrap else cols - 1
    for r in range(rows - 1):
        for c in range(cmax):
            a = r * cols + c
            b = r * cols + (c + 1) % cols
            d = (r + 1) * cols + c
            e = (r + 1) * cols + (c + 1) % cols
            faces += [(a, b, e), (a, e, d)]
    return np.asarray(faces, np.int64)


def skin_depth(look: FaceLook):
    """z of the rest skin at frontal (x, y) (the frontal sheet only), m; NaN off the face.

    The interpolator (a Delaunay triangulation of the skin's nodes) is built once per look:
    the skin, eyes, mouth and skirt all ask for it.
    """
    cached = look.__dict__.get("_skin_depth")
    if cached is not None:
        return cached
    from scipy.interpolate import LinearNDInterpolator

    r = look.rest
    front = r[:, 2] > np.percentile(r[:, 2], 30)
    depth = LinearNDInterpolator(r[front, :2], r[front, 2])
    object.__setattr__(look, "_skin_depth", depth)  # a cache on a frozen look
    return depth


def fit_inside(centre, unit, radii, depth, margin: float) -> np.ndarray:
    """An ellipsoid's vertices, shrunk (x and z) until it lies ``margin`` m inside the skin.

    Only the inner far wall of these linings is drawn; a part of it outside the skin would
    show on the face.
    """
    radii = np.asarray(radii, float)
    for _ in range(40):
        v = centre + unit * radii
        zs = depth(v[:, 0], v[:, 1])
        if not np.any(np.isfinite(zs) & (v[:, 2] > zs - margin)):
            break
        radii = radii * np.array([0.95, 0.98, 0.95])
    return v
