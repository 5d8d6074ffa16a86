"""The last remedy for a real scan whose skin folds: smooth the skin where no tissue fits.

Where the skin itself folds over or turns sharper than the thinnest tissue (a crease behind the
jaw, a scan's ragged edge, an ear's rim) no offset or depth keeps a prism's volume
(:mod:`thinning`). There the skin is smoothed: Taubin's lambda-mu smoothing (Taubin 1995, "A
signal processing approach to fair surface design"; lambda 0.5, mu -0.53, no shrinking) of the
nodes of the folded prisms and two rings of nodes round them, with more steps and then a wider
region (:data:`TRIES`) until the tissue fits. The slit's twins move together. A note says
where, over how many nodes and by how much the skin moved.
"""

from __future__ import annotations

import numpy as np

#: Taubin's weights (a shrinking step, then an inflating one)
LAMBDA, MU = 0.5, -0.53
#: (rings of nodes round the folded prisms, lambda-mu pairs, the border smoothed as a curve)
#: tried in turn; the menpo3d head scan (tests/data/scans) folds at its border, which only
#: smoothing it with the surface mends
TRIES = tuple((r, k, c) for c in (True, False) for r, k in ((2, 10), (2, 40), (4, 40),
                                                          (4, 160)))
STEPS = 10


def _neighbours(faces: np.ndarray, n: int, border_as_curve: bool = True):
    """The node-adjacency matrix (n, n), sparse, of the triangles' edges; with
    ``border_as_curve`` a node on the surface's border has only its two neighbours along the
    border (the border is smoothed as a curve and does not shrink inward)."""
    from scipy.sparse import coo_matrix

    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    e, count = np.unique(e, axis=0, return_counts=True)
    border = np.zeros(n, bool)
    border[e[count == 1].ravel()] = True
    rows, cols = np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]]
    on_border = np.r_[count, count] == 1
    keep = ~border[rows] | on_border | (not border_as_curve)
    a = coo_matrix((np.ones(int(keep.sum())), (rows[keep], cols[keep])), shape=(n, n)).tocsr()
    a.data[:] = 1.0
    return a


def grow(adjacency, region: np.ndarray, rings: int) -> np.ndarray:
    """The boolean node set ``region`` (n,) grown by ``rings`` rings of neighbours."""
    out = region.copy()
    for _ in range(rings):
        out = out | (adjacency @ out.astype(float) > 0)
    return out


#: a smoothing that shortens an edge to less than this share of its length is not taken
SHORTEST = 0.25


def smooth_region(vertices: np.ndarray, faces: np.ndarray, region: np.ndarray,
                  twins: np.ndarray | None = None, steps: int = STEPS,
                  border_as_curve: bool = True) -> np.ndarray | None:
    """The vertices (n, 3) m with the nodes of ``region`` (n,) bool smoothed (Taubin's
    lambda-mu, ``steps`` pairs); the others stay. ``twins`` (q, 2): node pairs that move as
    one (the mouth slit's). None where an edge would shrink under :data:`SHORTEST` of its
    length (a triangle collapsing)."""
    adj = _neighbours(faces, len(vertices), border_as_curve)
    deg = np.maximum(np.asarray(adj.sum(axis=1)).ravel(), 1.0)
    v = np.array(vertices, float)
    for _ in range(steps):
        for w in (LAMBDA, MU):
            lap = (adj @ v) / deg[:, None] - v
            v[region] += w * lap[region]
            if twins is not None and len(twins):
                v[twins[:, 1]] = v[twins[:, 0]]
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    before = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    after = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    if np.any(after < SHORTEST * before):
        return None
    return v


def note(vertices0: np.ndarray, vertices: np.ndarray, generic_xy: np.ndarray) -> str:
    """The note of a smoothing: where (the region of the node moved most, from its generic
    frontal coordinates (n, 2) mm), over how many nodes, by how much (mm)."""
    from .thinning import region_name

    moved = np.linalg.norm(vertices - vertices0, axis=1)
    k = int(np.argmax(moved))
    at = vertices0[k] * 1e3
    where = region_name(*generic_xy[k])
    return (f"the skin folds where no tissue fits at {where} near ({at[0]:.0f}, {at[1]:.0f}, "
            f"{at[2]:.0f}) mm: smoothed there over {int((moved > 1e-7).sum())} nodes, moved by "
            f"up to {moved.max() * 1e3:.1f} mm (mean {moved[moved > 1e-7].mean() * 1e3:.2f} "
            "mm)")
