"""Prism elements: volume and shape preservation (Lucero & Munhall 1999, eq. 9).

A prism is a surface triangle (a, b, c) and its copy (d, e, f) in the layer below, wound alike.
The kernels work on a (6, 3) array of the prism's node positions and write no temporaries, so
the assembly can call them for every element in the hot loop.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..geometry.prism import (  # noqa: F401  (re-exported: the prism's geometry)
    PRISM_QUADS,
    PRISM_TRIANGLES,
    PRISM_TRIANGLES_ALT,
    _bilinear_volume_gradient,
    _centre,
    _triangle_about,
    _triple,
    _volume_about_node0,
    _volumes,
    prism_volume,
    rest_geometry,
    symmetric_volume,
    volume_gradients,
)


@nb.njit(cache=True, inline="always")
def _unit_normal(p, i, j, k):
    ux, uy, uz = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1], p[j, 2] - p[i, 2]
    wx, wy, wz = p[k, 0] - p[i, 0], p[k, 1] - p[i, 1], p[k, 2] - p[i, 2]
    nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    s = np.sqrt(nx * nx + ny * ny + nz * nz) + 1e-300
    return nx / s, ny / s, nz / s


@nb.njit(cache=True, inline="always")
def prism_forces(p, rest_volume, rest_rel, k_volume, k_shape, out):
    """Forces (N) of eq. (9) on the 6 nodes of a prism, written into ``out`` (6, 3).

    ``q_i = k_e1 (V - V~) n_i + k_e2 (p_i - p~_i)`` is a left-hand-side term of eq. (8), so the
    force on node i is ``-q_i``. ``n_i`` is the unit normal pointing out of the element at node i:
    the epidermal-side normal on the top face and its opposite on the bottom face (our reading of
    "the epidermal normal"; it makes the term restore the volume). ``p_i`` is the node relative to
    the element's centre of mass; as published this term is not rotation-invariant.

    Returns the current volume (m^3).
    """
    v = prism_volume(p)
    tx, ty, tz = _unit_normal(p, 0, 1, 2)
    bx, by, bz = _unit_normal(p, 3, 4, 5)
    cx = (p[0, 0] + p[1, 0] + p[2, 0] + p[3, 0] + p[4, 0] + p[5, 0]) / 6.0
    cy = (p[0, 1] + p[1, 1] + p[2, 1] + p[3, 1] + p[4, 1] + p[5, 1]) / 6.0
    cz = (p[0, 2] + p[1, 2] + p[2, 2] + p[3, 2] + p[4, 2] + p[5, 2]) / 6.0
    dv = k_volume * (v - rest_volume)
    for k in range(6):
        if k < 3:
            nx, ny, nz = tx, ty, tz
        else:
            nx, ny, nz = -bx, -by, -bz
        out[k, 0] = -dv * nx - k_shape * ((p[k, 0] - cx) - rest_rel[k, 0])
        out[k, 1] = -dv * ny - k_shape * ((p[k, 1] - cy) - rest_rel[k, 1])
        out[k, 2] = -dv * nz - k_shape * ((p[k, 2] - cz) - rest_rel[k, 2])
    return v


@nb.njit(cache=True, inline="always")
def prism_pressure(p, rest_volume, bulk_per_volume, out):
    """Volume-preserving pressure on the 6 nodes of a prism, written into ``out`` (6, 3).

    The force is minus the gradient of ``K (V - V0)^2 / (2 V0)`` with ``bulk_per_volume`` =
    ``K / V0``: ``-K / V0 (V - V0) dV/dp_i``. V is :func:`symmetric_volume`; the gradient of a
    closed surface's volume at node i is a sixth of the sum, over its triangles at i, of the
    cross product of the triangle's two other corners (taken in order), here averaged over the
    two splits of the sides in closed form (:func:`_bilinear_volume_gradient`). Returns V.
    """
    vol = _bilinear_volume_gradient(p, out) / 12.0
    s = -bulk_per_volume * (vol - rest_volume) / 12.0
    for k in range(6):
        out[k, 0] *= s
        out[k, 1] *= s
        out[k, 2] *= s
    return vol


@nb.njit(cache=True, inline="always")
def _unit_cross(ux, uy, uz, wx, wy, wz):
    """(u x w) / |u x w| (the 1e-300 keeps a degenerate triangle finite)."""
    nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    s = np.sqrt(nx * nx + ny * ny + nz * nz) + 1e-300
    return nx / s, ny / s, nz / s


@nb.njit(cache=True, inline="always")
def _add_shape_volume(out, u, p, c, rel, e, k, dv, n, k_shape):
    """Add eq. (9)'s force on node k (global node u, at p = (x, y, z)) of prism e, centre c,
    face normal n, to ``out``."""
    out[u, 0] += -dv * n[0] - k_shape * ((p[0] - c[0]) - rel[e, k, 0])
    out[u, 1] += -dv * n[1] - k_shape * ((p[1] - c[1]) - rel[e, k, 1])
    out[u, 2] += -dv * n[2] - k_shape * ((p[2] - c[2]) - rel[e, k, 2])


@nb.njit(cache=True, inline="always")
def add_prism_forces(pos, nodes, e, rest_volume, rest_rel, k_volume, k_shape, out):
    """Add the forces (N) of eq. (9) of prism ``e`` to ``out`` (nodes, 3): :func:`prism_forces`
    unrolled, reading the six nodes from ``pos`` (nodes, 3) m through ``nodes`` (p, 6) and
    ``rest_rel`` (p, 6, 3) m, and writing no temporaries (the same numbers to the last bit)."""
    u0, u1, u2, u3, u4, u5 = nodes[e, 0], nodes[e, 1], nodes[e, 2], nodes[e, 3], nodes[e, 4], \
        nodes[e, 5]
    x0, y0, z0 = pos[u0, 0], pos[u0, 1], pos[u0, 2]
    x1, y1, z1 = pos[u1, 0], pos[u1, 1], pos[u1, 2]
    x2, y2, z2 = pos[u2, 0], pos[u2, 1], pos[u2, 2]
    x3, y3, z3 = pos[u3, 0], pos[u3, 1], pos[u3, 2]
    x4, y4, z4 = pos[u4, 0], pos[u4, 1], pos[u4, 2]
    x5, y5, z5 = pos[u5, 0], pos[u5, 1], pos[u5, 2]
    cx = (x0 + x1 + x2 + x3 + x4 + x5) / 6.0
    cy = (y0 + y1 + y2 + y3 + y4 + y5) / 6.0
    cz = (z0 + z1 + z2 + z3 + z4 + z5) / 6.0
    # prism_volume's eight triangles about the centre, in its order (the same rounding)
    a0, b0, c0 = x0 - cx, y0 - cy, z0 - cz
    a1, b1, c1 = x1 - cx, y1 - cy, z1 - cz
    a2, b2, c2 = x2 - cx, y2 - cy, z2 - cz
    a3, b3, c3 = x3 - cx, y3 - cy, z3 - cz
    a4, b4, c4 = x4 - cx, y4 - cy, z4 - cz
    a5, b5, c5 = x5 - cx, y5 - cy, z5 - cz
    v = _triple(a0, b0, c0, a1, b1, c1, a2, b2, c2)
    v += _triple(a3, b3, c3, a5, b5, c5, a4, b4, c4)
    v += _triple(a0, b0, c0, a3, b3, c3, a4, b4, c4)
    v += _triple(a0, b0, c0, a4, b4, c4, a1, b1, c1)
    v += _triple(a1, b1, c1, a4, b4, c4, a5, b5, c5)
    v += _triple(a1, b1, c1, a5, b5, c5, a2, b2, c2)
    v += _triple(a2, b2, c2, a5, b5, c5, a3, b3, c3)
    v += _triple(a2, b2, c2, a3, b3, c3, a0, b0, c0)
    v = v / 6.0
    tx, ty, tz = _unit_cross(x1 - x0, y1 - y0, z1 - z0, x2 - x0, y2 - y0, z2 - z0)
    bx, by, bz = _unit_cross(x4 - x3, y4 - y3, z4 - z3, x5 - x3, y5 - y3, z5 - z3)
    bx, by, bz = -bx, -by, -bz
    dv = k_volume * (v - rest_volume)
    c, t, b = (cx, cy, cz), (tx, ty, tz), (bx, by, bz)
    _add_shape_volume(out, u0, (x0, y0, z0), c, rest_rel, e, 0, dv, t, k_shape)
    _add_shape_volume(out, u1, (x1, y1, z1), c, rest_rel, e, 1, dv, t, k_shape)
    _add_shape_volume(out, u2, (x2, y2, z2), c, rest_rel, e, 2, dv, t, k_shape)
    _add_shape_volume(out, u3, (x3, y3, z3), c, rest_rel, e, 3, dv, b, k_shape)
    _add_shape_volume(out, u4, (x4, y4, z4), c, rest_rel, e, 4, dv, b, k_shape)
    _add_shape_volume(out, u5, (x5, y5, z5), c, rest_rel, e, 5, dv, b, k_shape)


@nb.njit(cache=True, inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@nb.njit(cache=True, inline="always")
def _quad_terms(ax, ay, az, bx, by, bz, qx, qy, qz, dx, dy, dz):
    """12 x the volume of side (a, b, c, d) about the centre and the halved n, s x (d - b),
    s x (c - a) of :func:`_bilinear_volume_gradient` (the same operations in the same order)."""
    ux, uy, uz = qx - ax, qy - ay, qz - az
    wx, wy, wz = dx - bx, dy - by, dz - bz
    nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    nx, ny, nz = 0.5 * nx, 0.5 * ny, 0.5 * nz
    sx, sy, sz = ax + bx + qx + dx, ay + by + qy + dy, az + bz + qz + dz
    v = sx * nx + sy * ny + sz * nz
    tx, ty, tz = 0.5 * (sy * wz - sz * wy), 0.5 * (sz * wx - sx * wz), 0.5 * (sx * wy - sy * wx)
    rx, ry, rz = 0.5 * (sy * uz - sz * uy), 0.5 * (sz * ux - sx * uz), 0.5 * (sx * uy - sy * ux)
    return v, nx, ny, nz, tx, ty, tz, rx, ry, rz


@nb.njit(cache=True, inline="always")
def pressure_terms(xyz, rest_volume, bulk_per_volume):
    """The volume-preserving pressure of one prism from its six nodes' coordinates ``xyz`` (a
    tuple of 18, m: node 0's x, y, z, then node 1's, ...): :func:`prism_pressure` unrolled
    over the two end triangles and three sides of :func:`_bilinear_volume_gradient`, in
    registers (the same numbers to the last bit).

    Returns the 18 force components (N, in the same order) and the volume (m^3). A prism with
    ``bulk_per_volume`` 0 has no pressure: its forces are exactly 0.
    """
    x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3, x4, y4, z4, x5, y5, z5 = xyz
    cx = (x0 + x1 + x2 + x3 + x4 + x5) / 6.0
    cy = (y0 + y1 + y2 + y3 + y4 + y5) / 6.0
    cz = (z0 + z1 + z2 + z3 + z4 + z5) / 6.0
    x0, y0, z0 = x0 - cx, y0 - cy, z0 - cz
    x1, y1, z1 = x1 - cx, y1 - cy, z1 - cz
    x2, y2, z2 = x2 - cx, y2 - cy, z2 - cz
    x3, y3, z3 = x3 - cx, y3 - cy, z3 - cz
    x4, y4, z4 = x4 - cx, y4 - cy, z4 - cz
    x5, y5, z5 = x5 - cx, y5 - cy, z5 - cz
    # end triangle (0, 1, 2): a . (b x c) and its gradient, doubled
    px, py, pz = _cross(x1, y1, z1, x2, y2, z2)
    v12 = 2.0 * (x0 * px + y0 * py + z0 * pz)
    g0x, g0y, g0z = 2.0 * px, 2.0 * py, 2.0 * pz
    g1x, g1y, g1z = 2.0 * (y2 * z0 - z2 * y0), 2.0 * (z2 * x0 - x2 * z0), 2.0 * (x2 * y0 - y2 * x0)
    g2x, g2y, g2z = 2.0 * (y0 * z1 - z0 * y1), 2.0 * (z0 * x1 - x0 * z1), 2.0 * (x0 * y1 - y0 * x1)
    # end triangle (3, 5, 4)
    px, py, pz = _cross(x5, y5, z5, x4, y4, z4)
    v12 += 2.0 * (x3 * px + y3 * py + z3 * pz)
    g3x, g3y, g3z = 2.0 * px, 2.0 * py, 2.0 * pz
    g5x, g5y, g5z = 2.0 * (y4 * z3 - z4 * y3), 2.0 * (z4 * x3 - x4 * z3), 2.0 * (x4 * y3 - y4 * x3)
    g4x, g4y, g4z = 2.0 * (y3 * z5 - z3 * y5), 2.0 * (z3 * x5 - x3 * z5), 2.0 * (x3 * y5 - y3 * x5)
    # side (0, 3, 4, 1): a = 0, c = 4 get n -/+ t, b = 3, d = 1 get n -/+ r
    v, nx, ny, nz, tx, ty, tz, rx, ry, rz = _quad_terms(x0, y0, z0, x3, y3, z3, x4, y4, z4,
                                                        x1, y1, z1)
    v12 += v
    g0x, g0y, g0z = g0x + (nx + tx), g0y + (ny + ty), g0z + (nz + tz)
    g4x, g4y, g4z = g4x + (nx - tx), g4y + (ny - ty), g4z + (nz - tz)
    g3x, g3y, g3z = g3x + (nx - rx), g3y + (ny - ry), g3z + (nz - rz)
    g1x, g1y, g1z = g1x + (nx + rx), g1y + (ny + ry), g1z + (nz + rz)
    # side (1, 4, 5, 2)
    v, nx, ny, nz, tx, ty, tz, rx, ry, rz = _quad_terms(x1, y1, z1, x4, y4, z4, x5, y5, z5,
                                                        x2, y2, z2)
    v12 += v
    g1x, g1y, g1z = g1x + (nx + tx), g1y + (ny + ty), g1z + (nz + tz)
    g5x, g5y, g5z = g5x + (nx - tx), g5y + (ny - ty), g5z + (nz - tz)
    g4x, g4y, g4z = g4x + (nx - rx), g4y + (ny - ry), g4z + (nz - rz)
    g2x, g2y, g2z = g2x + (nx + rx), g2y + (ny + ry), g2z + (nz + rz)
    # side (2, 5, 3, 0)
    v, nx, ny, nz, tx, ty, tz, rx, ry, rz = _quad_terms(x2, y2, z2, x5, y5, z5, x3, y3, z3,
                                                        x0, y0, z0)
    v12 += v
    g2x, g2y, g2z = g2x + (nx + tx), g2y + (ny + ty), g2z + (nz + tz)
    g3x, g3y, g3z = g3x + (nx - tx), g3y + (ny - ty), g3z + (nz - tz)
    g5x, g5y, g5z = g5x + (nx - rx), g5y + (ny - ry), g5z + (nz - rz)
    g0x, g0y, g0z = g0x + (nx + rx), g0y + (ny + ry), g0z + (nz + rz)
    vol = v12 / 12.0
    s = -bulk_per_volume * (vol - rest_volume) / 12.0
    s = 0.0 if bulk_per_volume == 0.0 else s  # a select: no pressure, whatever the volume
    return (g0x * s, g0y * s, g0z * s, g1x * s, g1y * s, g1z * s, g2x * s, g2y * s, g2z * s,
            g3x * s, g3y * s, g3z * s, g4x * s, g4y * s, g4z * s, g5x * s, g5y * s, g5z * s,
            vol)


@nb.njit(cache=True, inline="always")
def add_prism_pressure(pos, nodes, e, rest_volume, bulk_per_volume, out):
    """Add the volume-preserving pressure (N) of prism ``e`` to ``out`` (nodes, 3), reading its
    six nodes from ``pos`` (nodes, 3) m through ``nodes`` (p, 6): :func:`pressure_terms`.
    Returns the volume (m^3).
    """
    u = nodes[e]
    f = pressure_terms((pos[u[0], 0], pos[u[0], 1], pos[u[0], 2],
                        pos[u[1], 0], pos[u[1], 1], pos[u[1], 2],
                        pos[u[2], 0], pos[u[2], 1], pos[u[2], 2],
                        pos[u[3], 0], pos[u[3], 1], pos[u[3], 2],
                        pos[u[4], 0], pos[u[4], 1], pos[u[4], 2],
                        pos[u[5], 0], pos[u[5], 1], pos[u[5], 2]), rest_volume, bulk_per_volume)
    for c in range(6):
        out[u[c], 0] += f[3 * c]
        out[u[c], 1] += f[3 * c + 1]
        out[u[c], 2] += f[3 * c + 2]
    return f[18]


#: prisms per block of :func:`add_pressure_blocks`: its scratch (2 x 18 x 64 doubles, 18 KiB)
#: stays in the first-level cache
PRESSURE_BLOCK = 64


@nb.njit(cache=True, inline="always")
def add_pressure_blocks(pos, nodes, rest_volume, bulk, e0, e1, coords, forces, out):
    """Add the pressure (N) of prisms ``e0:e1`` to ``out`` (nodes, 3), a block at a time.

    The same numbers as :func:`add_prism_pressure` over the prisms in order, to the last bit,
    about twice as fast: each block's node coordinates are gathered into ``coords`` (18,
    PRESSURE_BLOCK), the pressure of the whole block is computed from them in one loop without
    branches, which the compiler turns into vector instructions, and the forces (``forces``,
    the same shape) are added to the nodes in the prisms' order.

    Parameters
    ----------
    pos : (nodes, 3) m
    nodes : (p, 6) int64
    rest_volume : (p,) m^3
    bulk : (p,) N/m^5 -- K / V0 of each prism, 0 for none
    e0, e1 : int -- the range of prisms
    coords, forces : (18, PRESSURE_BLOCK) float64 -- scratch
    out : (nodes, 3) N -- the forces are added to it
    """
    for b0 in range(e0, e1, PRESSURE_BLOCK):
        n = min(PRESSURE_BLOCK, e1 - b0)
        for q in range(n):
            for c in range(6):
                u = nodes[b0 + q, c]
                coords[3 * c, q] = pos[u, 0]
                coords[3 * c + 1, q] = pos[u, 1]
                coords[3 * c + 2, q] = pos[u, 2]
        for q in range(n):
            c = coords
            f = pressure_terms((c[0, q], c[1, q], c[2, q], c[3, q], c[4, q], c[5, q],
                                c[6, q], c[7, q], c[8, q], c[9, q], c[10, q], c[11, q],
                                c[12, q], c[13, q], c[14, q], c[15, q], c[16, q], c[17, q]),
                               rest_volume[b0 + q], bulk[b0 + q])
            forces[0, q], forces[1, q], forces[2, q] = f[0], f[1], f[2]
            forces[3, q], forces[4, q], forces[5, q] = f[3], f[4], f[5]
            forces[6, q], forces[7, q], forces[8, q] = f[6], f[7], f[8]
            forces[9, q], forces[10, q], forces[11, q] = f[9], f[10], f[11]
            forces[12, q], forces[13, q], forces[14, q] = f[12], f[13], f[14]
            forces[15, q], forces[16, q], forces[17, q] = f[15], f[16], f[17]
        for q in range(n):
            for c in range(6):
                u = nodes[b0 + q, c]
                out[u, 0] += forces[3 * c, q]
                out[u, 1] += forces[3 * c + 1, q]
                out[u, 2] += forces[3 * c + 2, q]
