"""Prism geometry: the volume of a prism element and its nodes about its centre.

A prism is a surface triangle (a, b, c) and its copy (d, e, f) in the layer below, wound alike.
The volumes here are what the builder checks (no inverted prism) and what the physics keeps
(:mod:`facemech.physics.volume`, Lucero & Munhall 1999, eq. 9): :func:`prism_volume` over the
closed surface :data:`PRISM_TRIANGLES`, or :func:`symmetric_volume` under the bilinear patches
of the sides (the continuum's). The kernels work on a (6, 3) array of the prism's node positions
(m) and write no temporaries, so the force kernels inline them.
"""

from __future__ import annotations

import numba as nb
import numpy as np

# outward-oriented triangles of the prism's closed surface, as indices into its 6 nodes
PRISM_TRIANGLES = np.array(
    [[0, 1, 2], [3, 5, 4], [0, 3, 4], [0, 4, 1], [1, 4, 5], [1, 5, 2], [2, 5, 3], [2, 3, 0]],
    dtype=np.int64,
)
# the same surface with each quadrilateral side split along its other diagonal; the mean of the
# two is the volume under the sides' bilinear patches, which does not depend on the node order
# (a mirrored prism gets the same volume)
PRISM_TRIANGLES_ALT = np.array(
    [[0, 1, 2], [3, 5, 4], [0, 3, 1], [1, 3, 4], [1, 4, 2], [2, 4, 5], [2, 5, 0], [0, 5, 3]],
    dtype=np.int64,
)


@nb.njit(cache=True, inline="always")
def prism_volume(p):
    """Volume (m^3) of a (possibly warped) prism, p of shape (6, 3), by the divergence theorem.

    The quadrilateral sides are split into two triangles each; the result is exact for planar
    sides and independent of the origin (it is computed about the element's centre).
    :func:`_volume_about_node0` gives the same volume to rounding with half the work, but a
    different rounding moves the seeds' Experiment 1 (docs/inversion.md), so it is not used.
    """
    cx, cy, cz = _centre(p)
    v = 0.0
    for t in range(8):
        _, _, _, ax, ay, az, bx, by, bz, qx, qy, qz = _triangle_about(p, t, cx, cy, cz)
        v += ax * (by * qz - bz * qy) - ay * (bx * qz - bz * qx) + az * (bx * qy - by * qx)
    return v / 6.0


@nb.njit(cache=True, inline="always")
def _triple(ax, ay, az, bx, by, bz, cx, cy, cz):
    """a . (b x c)."""
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)


@nb.njit(cache=True, inline="always")
def _volume_about_node0(r):
    """Volume (m^3) of the closed surface :data:`PRISM_TRIANGLES` from ``r`` (5, 3), nodes 1-5
    relative to node 0 (m): the triangles (3, 5, 4), (1, 4, 5), (1, 5, 2), (2, 5, 3); the other
    four pass through node 0."""
    v = _triple(r[2, 0], r[2, 1], r[2, 2], r[4, 0], r[4, 1], r[4, 2], r[3, 0], r[3, 1], r[3, 2])
    v += _triple(r[0, 0], r[0, 1], r[0, 2], r[3, 0], r[3, 1], r[3, 2], r[4, 0], r[4, 1], r[4, 2])
    v += _triple(r[0, 0], r[0, 1], r[0, 2], r[4, 0], r[4, 1], r[4, 2], r[1, 0], r[1, 1], r[1, 2])
    v += _triple(r[1, 0], r[1, 1], r[1, 2], r[4, 0], r[4, 1], r[4, 2], r[2, 0], r[2, 1], r[2, 2])
    return v / 6.0


@nb.njit(cache=True, inline="always")
def _centre(p):
    """Mean of a prism's six nodes (m)."""
    return ((p[0, 0] + p[1, 0] + p[2, 0] + p[3, 0] + p[4, 0] + p[5, 0]) / 6.0,
            (p[0, 1] + p[1, 1] + p[2, 1] + p[3, 1] + p[4, 1] + p[5, 1]) / 6.0,
            (p[0, 2] + p[1, 2] + p[2, 2] + p[3, 2] + p[4, 2] + p[5, 2]) / 6.0)


@nb.njit(cache=True, inline="always")
def _triangle_about(p, t, cx, cy, cz):
    """Node indices of triangle t of :data:`PRISM_TRIANGLES` and its corners about (cx, cy, cz)."""
    a = PRISM_TRIANGLES[t, 0]
    b = PRISM_TRIANGLES[t, 1]
    c = PRISM_TRIANGLES[t, 2]
    return (a, b, c, p[a, 0] - cx, p[a, 1] - cy, p[a, 2] - cz, p[b, 0] - cx, p[b, 1] - cy,
            p[b, 2] - cz, p[c, 0] - cx, p[c, 1] - cy, p[c, 2] - cz)


# the quadrilateral sides of a prism, each (a, b, c, d) in order around it, outward
PRISM_QUADS = np.array([[0, 3, 4, 1], [1, 4, 5, 2], [2, 5, 3, 0]], dtype=np.int64)


@nb.njit(cache=True, inline="always")
def _bilinear_volume_gradient(p, out):
    """Write 12 x the gradient of the prism's volume under the bilinear patches of its sides
    into ``out`` (6, 3) and return 12 x the volume.

    A side (a, b, c, d) contributes ``(a + b + c + d) . ((c - a) x (d - b)) / 24``, the mean of
    its two splits into triangles; its gradient at a is ``(n + s x (d - b)) / 24``, at c
    ``(n - s x (d - b)) / 24``, at b ``(n - s x (c - a)) / 24``, at d ``(n + s x (c - a)) / 24``
    with ``n = (c - a) x (d - b)``, ``s = a + b + c + d``. The end triangles (a, b, c)
    contribute ``a . (b x c) / 6``. Evaluated about the prism's centre.
    """
    cx, cy, cz = _centre(p)
    for k in range(6):
        out[k, 0] = 0.0
        out[k, 1] = 0.0
        out[k, 2] = 0.0
    v12 = 0.0
    for t in range(2):  # the end triangles: (0, 1, 2) and (3, 5, 4)
        a, b, c, ax, ay, az, bx, by, bz, qx, qy, qz = _triangle_about(p, t, cx, cy, cz)
        bcx, bcy, bcz = by * qz - bz * qy, bz * qx - bx * qz, bx * qy - by * qx
        v12 += 2.0 * (ax * bcx + ay * bcy + az * bcz)
        out[a, 0] += 2.0 * bcx
        out[a, 1] += 2.0 * bcy
        out[a, 2] += 2.0 * bcz
        out[b, 0] += 2.0 * (qy * az - qz * ay)
        out[b, 1] += 2.0 * (qz * ax - qx * az)
        out[b, 2] += 2.0 * (qx * ay - qy * ax)
        out[c, 0] += 2.0 * (ay * bz - az * by)
        out[c, 1] += 2.0 * (az * bx - ax * bz)
        out[c, 2] += 2.0 * (ax * by - ay * bx)
    for q in range(3):
        ia = PRISM_QUADS[q, 0]
        ib = PRISM_QUADS[q, 1]
        ic = PRISM_QUADS[q, 2]
        idd = PRISM_QUADS[q, 3]
        ax, ay, az = p[ia, 0] - cx, p[ia, 1] - cy, p[ia, 2] - cz
        bx, by, bz = p[ib, 0] - cx, p[ib, 1] - cy, p[ib, 2] - cz
        qx, qy, qz = p[ic, 0] - cx, p[ic, 1] - cy, p[ic, 2] - cz
        dx, dy, dz = p[idd, 0] - cx, p[idd, 1] - cy, p[idd, 2] - cz
        ux, uy, uz = qx - ax, qy - ay, qz - az  # c - a
        wx, wy, wz = dx - bx, dy - by, dz - bz  # d - b
        nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
        # halves: 12 x (1/24)
        nx, ny, nz = 0.5 * nx, 0.5 * ny, 0.5 * nz
        sx, sy, sz = ax + bx + qx + dx, ay + by + qy + dy, az + bz + qz + dz
        v12 += sx * nx + sy * ny + sz * nz
        # s x (d - b) and s x (c - a), halved
        tx, ty, tz = 0.5 * (sy * wz - sz * wy), 0.5 * (sz * wx - sx * wz), 0.5 * (sx * wy - sy * wx)
        rx, ry, rz = 0.5 * (sy * uz - sz * uy), 0.5 * (sz * ux - sx * uz), 0.5 * (sx * uy - sy * ux)
        out[ia, 0] += nx + tx
        out[ia, 1] += ny + ty
        out[ia, 2] += nz + tz
        out[ic, 0] += nx - tx
        out[ic, 1] += ny - ty
        out[ic, 2] += nz - tz
        out[ib, 0] += nx - rx
        out[ib, 1] += ny - ry
        out[ib, 2] += nz - rz
        out[idd, 0] += nx + rx
        out[idd, 1] += ny + ry
        out[idd, 2] += nz + rz
    return v12


@nb.njit(cache=True, inline="always")
def symmetric_volume(p):
    """Volume (m^3) of a prism (6, 3) under the bilinear patches of its sides: the mean of the
    two splits of every side, independent of the order of the nodes."""
    g = np.empty((6, 3))
    return _bilinear_volume_gradient(p, g) / 12.0


@nb.njit(cache=True)
def volume_gradients(prisms):
    """Gradients (k, 6, 3) of the volumes of prisms (k, 6, 3) under the bilinear patches of their
    sides (m^2), as :func:`symmetric_volume` measures them."""
    out = np.empty_like(prisms)
    for e in range(prisms.shape[0]):
        _bilinear_volume_gradient(prisms[e], out[e])
        for k in range(6):
            for a in range(3):
                out[e, k, a] /= 12.0
    return out


def rest_geometry(positions: np.ndarray, prism_nodes: np.ndarray, *, symmetric: bool = False):
    """Rest volumes (p,) and rest node offsets from the centre (p, 6, 3) of all prisms.

    ``symmetric``: the order-independent :func:`symmetric_volume` (the continuum's) instead of
    eq. (9)'s :func:`prism_volume`.
    """
    p = positions[prism_nodes]  # (p, 6, 3)
    rel = p - p.mean(axis=1, keepdims=True)
    return _volumes(np.ascontiguousarray(p), symmetric), rel


@nb.njit(cache=True)
def _volumes(p, symmetric):
    out = np.empty(p.shape[0])
    for e in range(p.shape[0]):
        out[e] = symmetric_volume(p[e]) if symmetric else prism_volume(p[e])
    return out
