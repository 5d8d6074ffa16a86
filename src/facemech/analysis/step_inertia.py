"""The inertia that the implicit step's shared matrix adds to a motion, part by part.

The linearly implicit step solves ``A dv = h f(x + h v, v)`` with one matrix
``A = M + h C + h^2 K`` shared by x, y and z. Stiffness or damping in A beyond the forces' own
along a motion acts as mass: a velocity field v meets ``v^T (M + h C_m + h^2 K_m) v`` in place
of ``v^T (M + h C_t + h^2 K_t) v`` (m: the matrix's, t: the forces' tangent at rest). The parts,
each measured as a multiple of ``v^T M v``: ``springs_shared`` (``k I``) against
``springs_along`` (``k e e^T``); ``volume_gram`` (``(g_a . g_b) I``) against
``volume_rank_one`` (``g g^T``); ``dashpots_shared`` (``b I``) against ``dashpots_along``
(``b e e^T``). The rank-one form never exceeds 3 times the Gram form (``tr(X)^2 <= 3 |X|_F^2``
for ``X = sum_a v_a g_a^T``). The ``along`` and ``rank_one`` parts resist no rigid motion; the
shared ones resist a turn. Docs: docs/model.md.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..geometry.prism import volume_gradients
from ..physics.assembly import Physics

#: the parts of the step's matrix (see the module doc): name -> (power of h, stiffness or damping)
PARTS = {"springs_shared": 2, "springs_along": 2, "volume_gram": 2, "volume_rank_one": 2,
         "dashpots_shared": 1, "dashpots_along": 1}


def _spring_blocks(i: np.ndarray, j: np.ndarray, blocks: np.ndarray, n: int) -> sp.csr_matrix:
    """The (3n, 3n) matrix of 3 x 3 blocks (s, 3, 3) on the springs i-j (a graph Laplacian of
    blocks: +B on both diagonals, -B off them)."""
    a = np.arange(3)
    ra, ca = np.repeat(a, 3), np.tile(a, 3)
    flat = blocks.reshape(-1, 9)
    rows, cols, vals = [], [], []
    for p, q, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
        rows.append((3 * p[:, None] + ra).ravel())
        cols.append((3 * q[:, None] + ca).ravel())
        vals.append((sign * flat).ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(3 * n, 3 * n))


def _prism_blocks(nodes: np.ndarray, blocks: np.ndarray, n: int) -> sp.csr_matrix:
    """The (3n, 3n) matrix of each prism's (18, 18) block (p, 18, 18) on its six nodes."""
    idx = (3 * nodes[:, :, None] + np.arange(3)).reshape(-1, 18)
    rows = np.broadcast_to(idx[:, :, None], blocks.shape).ravel()
    cols = np.broadcast_to(idx[:, None, :], blocks.shape).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(3 * n, 3 * n))


def step_parts(physics: Physics) -> dict[str, sp.csr_matrix]:
    """Each part of the step's matrix at the rest shape, over all nodes, at a share of 1.

    Returns
    -------
    dict name -> (3 n, 3 n) sparse, node-major (x, y, z of node 0, then node 1, ...): N/m for
    the stiffness parts, N s/m for the damping parts (:data:`PARTS`)
    """
    springs, prisms = physics.forces.springs, physics.forces.prisms
    rest = physics.model.rest_positions
    n = physics.model.n_nodes
    e = rest[springs.j] - rest[springs.i]
    e /= np.linalg.norm(e, axis=1)[:, None]
    ee = e[:, :, None] * e[:, None, :]
    eye = np.broadcast_to(np.eye(3), ee.shape)
    g = volume_gradients(rest[prisms.nodes])  # (p, 6, 3) m^2
    gram = np.einsum("pac,pbc->pab", g, g)
    gram18 = np.einsum("pab,cd->pacbd", gram, np.eye(3)).reshape(-1, 18, 18)
    g18 = g.reshape(-1, 18)
    bulk = prisms.bulk[:, None, None]
    k, b = springs.k_high[:, None, None], springs.damping[:, None, None]
    return {
        "springs_shared": _spring_blocks(springs.i, springs.j, k * eye, n),
        "springs_along": _spring_blocks(springs.i, springs.j, k * ee, n),
        "volume_gram": _prism_blocks(prisms.nodes, bulk * gram18, n),
        "volume_rank_one": _prism_blocks(prisms.nodes, bulk * g18[:, :, None] * g18[:, None, :],
                                         n),
        "dashpots_shared": _spring_blocks(springs.i, springs.j, b * eye, n),
        "dashpots_along": _spring_blocks(springs.i, springs.j, b * ee, n),
    }


def rigid_turn(physics: Physics, centre: np.ndarray, axis: np.ndarray, radius: float):
    """The velocity field (n, 3) m/s of a turn at 1 rad/s about ``axis`` through ``centre`` (m)
    of the moving nodes within ``radius`` (m) of the centre; every other node still."""
    rest = physics.model.rest_positions
    w = np.asarray(axis, float) / np.linalg.norm(axis)
    v = np.cross(w, rest - np.asarray(centre, float))
    moving = np.zeros(len(rest), bool)
    moving[physics.dynamic] = True
    v[~moving | (np.linalg.norm(rest - centre, axis=1) > radius)] = 0.0
    return v


def added_inertia(physics: Physics, parts: dict, velocity: np.ndarray, h: float) -> dict:
    """Each part's ``h^p v^T X v / v^T M v`` for the velocity field (n, 3) and the step h (s):
    the inertia the part adds to that motion at a share of 1, in multiples of the motion's own
    (p = 2 for stiffness, 1 for damping)."""
    mass = np.zeros(physics.model.n_nodes)
    mass[physics.dynamic] = 1.0 / physics.inv_mass[physics.dynamic]
    v = np.asarray(velocity, float)
    own = float(np.sum(mass[:, None] * v * v))
    flat = v.reshape(-1)
    return {name: float(h ** PARTS[name] * flat @ (x @ flat)) / own
            for name, x in parts.items()}
