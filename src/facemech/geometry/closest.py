"""The closest point of a triangle mesh to a few query points (landmarks, markers).

Exact point-to-triangle distances over candidate triangles near each query, so that a point on
a coarse mesh (4-mm triangles) is not reported millimetres off the surface as the nearest
vertex would report it.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray,
                         c: np.ndarray) -> np.ndarray:
    """The closest point of each triangle ``(a, b, c)`` to ``p``.

    Parameters
    ----------
    p : (3,) or (k, 3) query point(s)
    a, b, c : (k, 3) corners of k triangles (any unit)

    Returns
    -------
    (k, 3) closest points, in the unit of the input
    """
    p = np.broadcast_to(np.asarray(p, float), a.shape)
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = np.einsum("ij,ij->i", n, n)
    # the projection onto the plane, and its barycentric coordinates
    ap = p - a
    v = np.einsum("ij,ij->i", np.cross(ap, ac), n) / np.where(nn > 0, nn, 1.0)
    w = np.einsum("ij,ij->i", np.cross(ab, ap), n) / np.where(nn > 0, nn, 1.0)
    inside = (v >= 0) & (w >= 0) & (v + w <= 1) & (nn > 0)
    best = a + v[:, None] * ab + w[:, None] * ac
    best = np.where(inside[:, None], best, np.inf)
    # otherwise the closest point lies on one of the three edges
    for s, e in ((a, b), (b, c), (c, a)):
        d = e - s
        dd = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.einsum("ij,ij->i", p - s, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
        q = s + t[:, None] * d
        closer = ~inside & (np.linalg.norm(q - p, axis=1) < np.linalg.norm(best - p, axis=1))
        best = np.where(closer[:, None], q, best)
    return best


def closest_points(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, *,
                   candidates: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """The closest surface point of a triangle mesh to each query point.

    Parameters
    ----------
    points : (k, 3) query points, metres
    vertices : (n, 3) mesh vertices, metres
    faces : (f, 3) int triangles
    candidates : the triangles around this many nearest vertices are searched

    Returns
    -------
    closest : (k, 3) metres
    distance : (k,) metres
    """
    points = np.atleast_2d(np.asarray(points, float))
    vertices = np.asarray(vertices, float)
    faces = np.asarray(faces, np.int64)
    # triangles of each vertex (CSR)
    order = np.argsort(faces.ravel(), kind="stable")
    owner = order // 3
    ptr = np.searchsorted(faces.ravel()[order], np.arange(len(vertices) + 1))
    _, near = cKDTree(vertices).query(points, k=min(candidates, len(vertices)))
    near = np.asarray(near).reshape(len(points), -1)
    out = np.empty_like(points)
    for i, p in enumerate(points):
        tris = np.unique(np.concatenate([owner[ptr[v]:ptr[v + 1]] for v in near[i]]))
        if len(tris) == 0:
            out[i] = vertices[near[i, 0]]
            continue
        q = closest_on_triangles(p, *(vertices[faces[tris, k]] for k in range(3)))
        out[i] = q[np.argmin(np.linalg.norm(q - p, axis=1))]
    return out, np.linalg.norm(out - points, axis=1)
