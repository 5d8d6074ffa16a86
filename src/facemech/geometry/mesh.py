"""Triangle-mesh primitives of the epidermal surface: edges, boundary, normals, areas.

Pure functions of ``vertices`` ((n, 3) array, metres) and ``faces`` ((f, 3) int array).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def _corner_pairs(faces: np.ndarray) -> np.ndarray:
    """The three edges of every triangle, (3 f, 2), in triangle-corner order."""
    return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])


def surface_edges(faces: np.ndarray) -> np.ndarray:
    """The mesh's unique edges, (e, 2) int array, each sorted (low node first), sorted rows."""
    return np.unique(np.sort(_corner_pairs(faces), axis=1), axis=0)


def boundary_edges(faces: np.ndarray) -> np.ndarray:
    """The edges only one triangle has (the mesh's holes and rim), (b, 2), each sorted."""
    u, c = np.unique(np.sort(_corner_pairs(faces), axis=1), axis=0, return_counts=True)
    return u[c == 1]


def boundary_nodes(faces: np.ndarray) -> np.ndarray:
    """Sorted nodes on an edge that only one triangle has (the mesh's holes and rim)."""
    return np.unique(boundary_edges(faces))


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3) of a triangle mesh."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    fn = np.cross(b - a, c - a)
    vn = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(vn, faces[:, k], fn)
    norm = np.linalg.norm(vn, axis=1, keepdims=True)
    return vn / np.where(norm > 0, norm, 1.0)


def smoothed_normals(vertices: np.ndarray, faces: np.ndarray, sigma: float) -> np.ndarray:
    """Unit normals (n, 3) averaged over the surface with a Gaussian of width ``sigma`` (m).

    Area-weighted triangle normals within 2.5 sigma of each vertex. The offset direction of a
    thick tissue layer must change slowly, or the layer folds where the skin is concave (the
    mentolabial sulcus, the sides of the nose); averaging over a fixed distance rather than a
    number of neighbours gives the same directions on every mesh resolution.
    """
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    fn = np.cross(b - a, c - a)  # twice the area times the unit normal
    centroid = (a + b + c) / 3.0
    tree = cKDTree(centroid)
    out = np.zeros_like(vertices)
    for i, near in enumerate(tree.query_ball_point(vertices, 2.5 * sigma)):
        if not near:
            continue
        near = np.asarray(near)
        d2 = np.sum((centroid[near] - vertices[i]) ** 2, axis=1)
        out[i] = (np.exp(-0.5 * d2 / sigma**2)[:, None] * fn[near]).sum(axis=0)
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return out / np.where(norm > 0, norm, 1.0)


def vertex_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each vertex's share of the surface area (a third of its triangles'), (n,) m^2."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    out = np.zeros(len(vertices))
    for k in range(3):
        np.add.at(out, faces[:, k], area / 3.0)
    return out
