"""Creases in the skin: how much the angle between neighbouring triangles grows.

A crease is a line along which the skin folds sharply: the normals of the two triangles on
either side of an edge turn away from each other. :func:`fold_increase` gives, for every interior
edge of the epidermal surface, the angle between the two normals in a deformed state minus the
same angle at rest (degrees). Realistic skin bends smoothly, so no edge outside the lips should
gain much (the bound: 20 degrees for a 10-degree jaw opening).
"""

from __future__ import annotations

import numpy as np


def _edge_triangles(faces: np.ndarray) -> np.ndarray:
    """(e, 2) pairs of triangles that share an edge (interior edges only)."""
    f = np.asarray(faces, np.int64)
    tri = np.repeat(np.arange(len(f)), 3)
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]).reshape(3, -1, 2)
                .transpose(1, 0, 2).reshape(-1, 2), axis=1)
    key = e[:, 0] * (f.max() + 1) + e[:, 1]
    order = np.argsort(key, kind="stable")
    ks = key[order]
    same = np.nonzero(ks[1:] == ks[:-1])[0]
    return np.column_stack([tri[order[same]], tri[order[same + 1]]])


def triangle_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit normals (f, 3) of the triangles."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def fold_increase(rest: np.ndarray, deformed: np.ndarray, faces: np.ndarray):
    """Growth (degrees) of the angle between the normals across each interior edge.

    Parameters
    ----------
    rest, deformed : (n, 3) epidermal node positions (any length unit)
    faces : (f, 3) triangles

    Returns
    -------
    increase : (e,) degrees, deformed angle minus rest angle
    pairs : (e, 2) the two triangles of each edge
    """
    pairs = _edge_triangles(faces)

    def angles(v):
        nrm = triangle_normals(v, faces)
        cos = np.einsum("ea,ea->e", nrm[pairs[:, 0]], nrm[pairs[:, 1]])
        return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))

    return angles(deformed) - angles(rest), pairs


def largest_fold_increase(model, deformed: np.ndarray, *, exclude_lips: bool = True) -> float:
    """The largest growth (degrees) of a fold angle of a face outside its lips.

    ``deformed`` (n_surface, 3) m; the lips are the model's lip region (``model.lip_region``)
    and the two triangles of an edge must both lie outside it.
    """
    n = model.n_surface
    inc, pairs = fold_increase(model.rest_positions[:n], deformed, model.faces)
    if exclude_lips and model.lip_region is not None:
        lips = np.asarray(model.lip_region)[model.faces].any(axis=1)
        keep = ~(lips[pairs[:, 0]] | lips[pairs[:, 1]])
        inc = inc[keep]
    return float(inc.max()) if len(inc) else 0.0
