"""Slabs of the mesh for thread-parallel force assembly without locks or per-thread copies.

The springs and prisms are sorted into ``2 P`` slabs across the face (by their rest centroid
along one axis, with equal work in each) for a pool of ``P`` threads. Slabs of one parity
(0, 2, 4, ... or 1, 3, 5, ...) share no node, which is checked: the threads take the even
slabs together, each adding its forces straight into the one array of forces, then the odd
slabs. Each node's forces are then added in an order fixed by the mesh (its even slab's
elements, then its odd slab's, each in the slab's order), whatever the thread count: the
forces on 2, 3 or more threads are the same to the bit, and differ from one thread's (the
elements in their own order) only by the rounding of the additions' order (about 1e-16
relative). Each thread works on a band of the face, whose nodes stay in its core's cache.

The axis is the one along which the mesh numbers its nodes (:func:`slab_axis`): slabs across
it hold long runs of consecutive nodes, so the two threads write to separate stretches of the
forces. Across the other axis every row of nodes is cut into pieces and the threads' pieces
alternate in memory, where each core's prefetchers fetch the other's lines ahead. The built-in
face numbers its nodes row by row from the hairline down: across y the two threads' nodes
change places 10 times in memory, across x 575 times, and two slabs across x took 21-37 %
longer side by side than alone (133-153 µs against 110-112 µs a slab), across y 2 % (114
against 112 µs).
"""

from __future__ import annotations

import numpy as np

from .bundles import PrismBundle, SlabBundle, SpringBundle

#: relative cost of a prism and a spring in the force kernel (measured in
#: benchmarks/forward.py: the seeds' eq. (9) prism costs more than the continuum's pressure)
PRISM_COST = {"seeds": 6.0, "continuum": 3.0}


def _element_slabs(centre: np.ndarray, cost: np.ndarray, n_slabs: int) -> np.ndarray:
    """Slab (0 to n_slabs - 1) of each element: cuts at equal shares of the summed cost, in
    the order of the centroids along the axis (``centre``)."""
    order = np.argsort(centre, kind="stable")
    share = np.cumsum(cost[order]) / cost.sum()
    slab = np.empty(len(centre), np.int64)
    slab[order] = np.minimum((share * n_slabs - 1e-9).astype(np.int64), n_slabs - 1)
    return slab


#: the axes a face may be cut across: x (the subject's left) and y (down the face)
AXES = {"x": (0, 1.0), "y": (1, -1.0)}


def slab_axis(springs: SpringBundle, prisms: PrismBundle, rest: np.ndarray) -> str:
    """The axis to cut slabs across: of x and y, the one where two threads' slabs interleave
    least in memory (:func:`interleaving`; ties: y).

    Parameters
    ----------
    springs, prisms : the mesh's
    rest : (nodes, 3) m -- rest positions

    Returns
    -------
    str -- ``"x"`` or ``"y"``
    """
    changes = {name: interleaving(springs, prisms, rest, name) for name in ("y", "x")}
    return min(changes, key=changes.get)


def interleaving(springs: SpringBundle, prisms: PrismBundle, rest: np.ndarray,
                 axis: str) -> int:
    """How often, in the nodes' order, two threads' slabs across ``axis`` change from one
    thread's nodes to the other's: slabs 0 and 2 side by side, then 1 and 3 (4 slabs, both
    phases summed). A few per layer where the mesh numbers its nodes along ``axis``; hundreds
    where it numbers them across it, thousands where in no order.
    """
    slab = _element_slabs(_centres(springs, prisms, rest, axis), _costs(springs, prisms), 4)
    nodes = [np.unique(n) for n in _slab_nodes(springs, prisms, slab, 4)]
    changes = 0
    for a in (0, 1):  # slabs a and a + 2 run side by side
        owner = np.concatenate([np.zeros(len(nodes[a]), int), np.ones(len(nodes[a + 2]), int)])
        owner = owner[np.argsort(np.concatenate([nodes[a], nodes[a + 2]]), kind="stable")]
        changes += int(np.count_nonzero(np.diff(owner)))
    return changes


def _centres(springs: SpringBundle, prisms: PrismBundle, rest: np.ndarray,
             axis: str) -> np.ndarray:
    """Each spring's and then each prism's rest centroid along ``axis`` (ascending: left to
    right across x, top to bottom across y)."""
    col, sign = AXES[axis]
    c = sign * rest[:, col]
    return np.concatenate([(c[springs.i] + c[springs.j]) / 2, c[prisms.nodes].mean(axis=1)])


def _costs(springs: SpringBundle, prisms: PrismBundle) -> np.ndarray:
    """The relative cost of each spring and then each prism (:data:`PRISM_COST`)."""
    kind = "seeds" if prisms.k_volume != 0.0 or prisms.k_shape != 0.0 else "continuum"
    return np.concatenate([np.ones(len(springs.i)),
                           np.full(len(prisms.nodes), PRISM_COST[kind])])


def _slab_nodes(springs: SpringBundle, prisms: PrismBundle, slab: np.ndarray,
                n_slabs: int) -> list[np.ndarray]:
    """The nodes of each slab's elements (with repeats)."""
    n_s = len(springs.i)
    s_slab, p_slab = slab[:n_s], slab[n_s:]
    return [np.concatenate([springs.i[s_slab == k], springs.j[s_slab == k],
                            prisms.nodes[p_slab == k].ravel()]) for k in range(n_slabs)]


def _disjoint_by_parity(slab_nodes: list[np.ndarray]) -> bool:
    """Whether slabs of one parity share no node."""
    for parity in (0, 1):
        seen = np.concatenate([np.unique(n) for n in slab_nodes[parity::2]])
        if len(np.unique(seen)) != len(seen):
            return False
    return True


def slab_bundles(springs: SpringBundle, prisms: PrismBundle, rest: np.ndarray,
                 threads: int, dynamic: np.ndarray | None = None,
                 axis: str | None = None) -> SlabBundle:
    """The springs and prisms sorted into ``2 threads`` slabs (fewer where elements are too
    wide for that many), or :meth:`SlabBundle.empty` where even two threads' slabs would
    share nodes.

    Parameters
    ----------
    springs, prisms : the mesh's, as :class:`~facemech.physics.assembly.Physics` builds them
    rest : (nodes, 3) m -- rest positions
    threads : int -- the most threads the slabs are for
    dynamic : (d,) int, optional -- the nodes that move under forces (default: all)
    axis : ``"x"`` or ``"y"``, optional -- the axis to cut across (default: :func:`slab_axis`)

    Returns
    -------
    SlabBundle -- the elements regrouped slab by slab (each slab's in the mesh's order), with
        ``spring_ptr`` and ``prism_ptr`` (slabs + 1,) the start of each slab, the nodes each
        pair's thread zeroes, and the dynamic nodes in bands, one for each pair of slabs (cut
        at the odd slabs' far ends)
    """
    n_s, n_p = len(springs.i), len(prisms.nodes)
    if threads < 2 or n_s + n_p == 0:
        return SlabBundle.empty()
    axis = slab_axis(springs, prisms, rest) if axis is None else axis
    if axis not in AXES:
        raise ValueError(f"axis must be one of {sorted(AXES)} (got {axis!r})")
    centre = _centres(springs, prisms, rest, axis)
    col, sign = AXES[axis]
    cost = _costs(springs, prisms)
    for t in range(threads, 1, -1):
        n_slabs = 2 * t
        slab = _element_slabs(centre, cost, n_slabs)
        slab_nodes = _slab_nodes(springs, prisms, slab, n_slabs)
        if _disjoint_by_parity(slab_nodes):
            coord = sign * rest[:, col]
            cuts = [coord[n].max() for n in slab_nodes[1:-1:2]]  # the odd slabs' far ends
            return SlabBundle(**_regroup(springs, prisms, slab[:n_s], slab[n_s:], n_slabs),
                              **_bands(coord, cuts, dynamic),
                              **_zeroing(slab_nodes, len(rest)))
    return SlabBundle.empty()


def _zeroing(slab_nodes: list[np.ndarray], n_nodes: int) -> dict:
    """The nodes whose forces the thread of each pair of slabs zeroes before it takes its even
    slab: the even slab's nodes, and the odd slab's that no even slab has (the nodes of no
    slab with the first pair). No thread zeroes a node that another adds to meanwhile, and
    every node is zeroed once."""
    even = np.zeros(n_nodes, bool)
    for n in slab_nodes[0::2]:
        even[n] = True
    lists = []
    for q in range(len(slab_nodes) // 2):
        odd = np.unique(slab_nodes[2 * q + 1])
        lists.append(np.union1d(slab_nodes[2 * q], odd[~even[odd]]))
    touched = np.zeros(n_nodes, bool)
    for n in lists:
        touched[n] = True
    lists[0] = np.union1d(lists[0], np.flatnonzero(~touched))
    return {"zero": np.concatenate(lists).astype(np.int64),
            "zero_ptr": np.cumsum([0] + [len(n) for n in lists]).astype(np.int64)}


def _bands(x: np.ndarray, cuts: list[float], dynamic: np.ndarray | None) -> dict:
    """The dynamic nodes in bands of ``x`` (nodes,) m between ``cuts`` (m, ascending), each
    band in the nodes' order."""
    band = np.searchsorted(np.asarray(cuts), x, side="left")
    n_bands = len(cuts) + 1
    dynamic = np.arange(len(x)) if dynamic is None else np.asarray(dynamic, np.int64)
    dynamic = dynamic[np.argsort(band[dynamic], kind="stable")].astype(np.int64)
    return {"dynamic": dynamic,
            "dynamic_ptr": np.searchsorted(band[dynamic],
                                           np.arange(n_bands + 1)).astype(np.int64)}


def _regroup(springs: SpringBundle, prisms: PrismBundle, s_slab: np.ndarray,
             p_slab: np.ndarray, n_slabs: int) -> dict:
    """The springs and prisms slab by slab, and where each slab starts."""
    # slab by slab, each slab's elements in the mesh's order (which reads the nodes in memory
    # order where the mesh numbers its elements as its nodes; as fast as sorting the springs
    # by their lower node, and the prisms by node are slower: measured)
    s_order = np.argsort(s_slab, kind="stable")
    p_order = np.argsort(p_slab, kind="stable")
    s_ptr = np.searchsorted(s_slab[s_order], np.arange(n_slabs + 1)).astype(np.int64)
    p_ptr = np.searchsorted(p_slab[p_order], np.arange(n_slabs + 1)).astype(np.int64)
    sp = springs._replace(**{f: getattr(springs, f)[s_order]
                             for f in ("i", "j", "rest_length", "k_low", "k_high", "biphasic",
                                       "damping", "knee_length")})
    pr = prisms._replace(nodes=prisms.nodes[p_order], rest_volume=prisms.rest_volume[p_order],
                         rest_rel=prisms.rest_rel[p_order], bulk=prisms.bulk[p_order])
    return {"springs": sp, "prisms": pr, "spring_ptr": s_ptr, "prism_ptr": p_ptr}


__all__ = ["slab_bundles", "slab_axis", "interleaving", "PRISM_COST", "AXES"]
