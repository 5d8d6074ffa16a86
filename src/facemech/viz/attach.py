"""Render-only meshes carried by the moving skin (alae, nostrils): each vertex bound to a skin
triangle.

A vertex p at rest is bound to its nearest skin triangle (a, b, c): the barycentric weights
(w0, w1, w2) of its foot point and its offset in the triangle's frame (e1 along b - a, n the
weights' blend of the vertex normals, e2 = n x e1). In a frame the vertex is
``sum w_i x_i + o1 e1 + o2 e2 + o3 n``: it moves, turns and stretches with the skin under it,
and the physics never sees it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Attachment:
    """Vertices bound to a skin surface (indices into its nodes, weights, offsets in m)."""

    corners: np.ndarray  # (m, 3) int, the skin triangle of each vertex
    weights: np.ndarray  # (m, 3) barycentric weights of the foot point
    offset: np.ndarray  # (m, 3) m, along (e1, e2, n) of the triangle's frame
    blend: np.ndarray | None = None  # (m,) 1: the mesh's own normal .. 0: the skin's

    def with_blend(self, blend: np.ndarray) -> Attachment:
        """The same binding whose normals turn to the skin's where ``blend`` (m,) is 0."""
        return Attachment(self.corners, self.weights, self.offset, np.asarray(blend, float))

    def shade_normals(self, own: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """(m, 3) unit normals: the mesh's ``own`` (m, 3), turned to the skin's (its unit
        vertex ``normals`` (n, 3) blended at the foot points) by :attr:`blend`, so that a
        patch that lies flat on the skin meets it without a seam of shading."""
        if self.blend is None:
            return own
        under = np.einsum("mk,mkj->mj", self.weights, normals[self.corners])
        b = self.blend[:, None]
        n = b * own + (1.0 - b) * under
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)

    def place(self, skin: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """(m, 3) m: the vertices on skin nodes ``skin`` (n, 3) with unit ``normals`` (n, 3)."""
        x = skin[self.corners]  # (m, 3, 3)
        foot = np.einsum("mk,mkj->mj", self.weights, x)
        e1, e2, n = _frame(x, np.einsum("mk,mkj->mj", self.weights, normals[self.corners]))
        o = self.offset
        return foot + o[:, :1] * e1 + o[:, 1:2] * e2 + o[:, 2:] * n


def _frame(x: np.ndarray, n: np.ndarray):
    """Unit (e1, e2, n) of triangles x (m, 3, 3) with blended normals n (m, 3)."""
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    e1 = x[:, 1] - x[:, 0]
    e1 -= np.einsum("ij,ij->i", e1, n)[:, None] * n
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(n, e1), n


def closest_on_skin(points: np.ndarray, skin: np.ndarray, triangles: np.ndarray,
                    candidates: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Nearest skin triangle (m,) and barycentric weights (m, 3) of each point (m, 3) m, among
    the ``candidates`` triangles whose centroids lie nearest it."""
    from scipy.spatial import cKDTree

    x = skin[triangles]
    k = min(candidates, len(triangles))
    _, near = cKDTree(x.mean(axis=1)).query(points, k=k)
    near = near.reshape(len(points), k)
    best_d = np.full(len(points), np.inf)
    best_t = np.zeros(len(points), int)
    best_w = np.zeros((len(points), 3))
    for j in range(k):
        t = near[:, j]
        w = _barycentric_clamped(points, x[t])
        d = np.linalg.norm(np.einsum("mk,mkj->mj", w, x[t]) - points, axis=1)
        better = d < best_d
        best_d[better], best_t[better], best_w[better] = d[better], t[better], w[better]
    return best_t, best_w


def _barycentric_clamped(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Weights (m, 3) of the points p (m, 3) projected on triangles x (m, 3, 3), clamped into
    the triangle (negative weights cut to 0, renormalised: near enough for a foot point)."""
    a, b, c = x[:, 0], x[:, 1], x[:, 2]
    v0, v1, v2 = b - a, c - a, p - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-30)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    lam = np.clip(np.stack([1.0 - v - w, v, w], -1), 0.0, None)
    return lam / np.maximum(lam.sum(axis=1, keepdims=True), 1e-12)


def attach(points: np.ndarray, skin: np.ndarray, triangles: np.ndarray,
           normals: np.ndarray) -> Attachment:
    """Bind points (m, 3) m to the skin at rest (nodes (n, 3) m, triangles (f, 3), unit vertex
    normals (n, 3)): :class:`Attachment`."""
    t, w = closest_on_skin(points, skin, triangles)
    corners = np.asarray(triangles)[t]
    x = skin[corners]
    foot = np.einsum("mk,mkj->mj", w, x)
    e1, e2, n = _frame(x, np.einsum("mk,mkj->mj", w, normals[corners]))
    d = points - foot
    off = np.stack([np.einsum("ij,ij->i", d, e) for e in (e1, e2, n)], -1)
    return Attachment(corners, w, off)


def on_skin(points: np.ndarray, skin: np.ndarray, triangles: np.ndarray,
            normals: np.ndarray, lift: float) -> Attachment:
    """Bind points (m, 3) m to their foot points on the skin, ``lift`` m out along the normal:
    a decal that lies on the skin (a nostril's opening)."""
    t, w = closest_on_skin(points, skin, triangles)
    off = np.zeros((len(points), 3))
    off[:, 2] = lift
    return Attachment(np.asarray(triangles)[t], w, off)
