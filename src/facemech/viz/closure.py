"""The head surface that closes the skin: one mesh from the crown to the neck.

The physics carries the face as an open sheet whose outer edge runs over the forehead under the
hair, down in front of the ears and under the chin. The closure is a second sheet that shares
that edge: its first ring of vertices *is* the skin's edge nodes, so skin and closure together
are one closed surface (the mouth slit aside), and the closure's vertices near the edge move
with the edge nodes (the jaw opening drags the throat).

Construction. Directions from the head's centre are written in polar coordinates about the back
of the head (``theta`` from -z, ``phi`` round it). Seen from there the skin's edge is a closed
curve round the pole that meets each ``phi`` once (checked: :func:`outer_loop` returns None
otherwise). Ring k of the closure lies on the rays ``theta = theta_i (1 - k/K)`` of each edge
node i, down to one vertex at the pole. Along its ray a vertex lies at the radius of the
adult head and neck (:class:`.cranium.Cranium`), blended over 35 degrees with the skin's edge
radius continued at the skin's own slope, so that surface and slope are continuous across the
edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cranium import Cranium

RAY_ORIGIN = np.array([0.0, -0.045, 0.0])  #: m, the rays' origin from the head's centre:
#: lower than the centre, so that the rays down the neck do not graze its sides
RINGS = 26  #: rings from the skin's edge to the back of the head
BLEND_DEG = 35.0  #: degrees over which the closure relaxes from the skin's edge to the cranium
SMOOTHING_STEPS = 10  #: Taubin iterations over the closure (away from the skin's edge)
MAX_SLOPE = 0.03  #: m/rad, the edge slope continued into the closure is clipped to this
#: rad: the largest step back in ``phi`` along the edge that is allowed (and flattened in the
#: rings). A scan's edge where it turns sharply (the corners of a neck cut straight across)
#: goes back by a fraction of a degree between neighbours (0.9 degrees at most on the
#: scan-like head of tests/scans.py built as it comes)
PHI_REVERSAL = np.radians(2.0)


@dataclass(frozen=True)
class Closure:
    """The closing sheet.

    Attributes
    ----------
    rest : (m, 3) m, vertices at rest; the first ``len(loop)`` are the skin's edge nodes
    faces : (f, 3) int, counter-clockwise seen from outside (consistent with the skin)
    loop : (e,) int, the skin's edge nodes in order
    nodes : (m,) int, the skin node each vertex follows
    weights : (m,) float in [0, 1], how much of that node's displacement it takes (1 on the
        edge)
    theta, phi : (m,) rad, polar coordinates of each vertex about the back of the head
    inner : (m,) int, the skin node one step inside the skin from ``nodes``
    reach : (m,) float, how far (in steps from ``inner`` to ``nodes``) the skin's motion
        across its edge is carried on past it (0 on the edge, fading within 20 degrees): the
        closure near the edge turns with the skin, so that the slope stays continuous as
        the jaw opens
    """

    rest: np.ndarray
    faces: np.ndarray
    loop: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    inner: np.ndarray
    reach: np.ndarray

    def place(self, skin: np.ndarray, skin_rest: np.ndarray) -> np.ndarray:
        """Vertices (m, 3) for skin node positions ``skin`` (n, 3); the edge ring exactly."""
        d = skin[self.nodes] - skin_rest[self.nodes]
        d_in = skin[self.inner] - skin_rest[self.inner]
        return self.rest + self.weights[:, None] * d + self.reach[:, None] * (d - d_in)

    def joint_faces(self, n_skin: int) -> np.ndarray:
        """The closure's faces indexing ``[skin nodes (n_skin), closure vertices]``: the edge
        ring refers to the skin's own nodes, the others to ``n_skin + vertex``."""
        e = len(self.loop)
        local = np.arange(len(self.rest))
        idx = np.where(local < e, self.loop[np.minimum(local, e - 1)], n_skin + local)
        return idx[self.faces]


def boundary_loops(triangles: np.ndarray) -> list[np.ndarray]:
    """Closed boundary loops of a triangle mesh, each in the direction of its triangles'
    edges (a -> b as a triangle lists them), longest first."""
    f = np.asarray(triangles, np.int64)
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    _, inv, cnt = np.unique(np.sort(directed, axis=1), axis=0, return_inverse=True,
                            return_counts=True)
    edges = directed[cnt[inv.ravel()] == 1]
    nxt = {int(a): int(b) for a, b in edges}
    seen, loops = set(), []
    for start in nxt:
        if start in seen:
            continue
        loop, x = [], start
        while x not in seen and x in nxt:
            seen.add(x)
            loop.append(x)
            x = nxt[x]
        if x == start:
            loops.append(np.array(loop, np.int64))
    return sorted(loops, key=len, reverse=True)


def back_polar(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(theta, phi) rad of unit directions (n, 3): theta from -z, phi = atan2(y, x)."""
    return np.arccos(np.clip(-d[:, 2], -1.0, 1.0)), np.arctan2(d[:, 1], d[:, 0])


def from_back_polar(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit directions (n, 3) of :func:`back_polar` coordinates."""
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), -np.cos(theta)], -1)


def outer_loop(rest: np.ndarray, triangles: np.ndarray, centre: np.ndarray):
    """The skin's outer edge as ordered nodes (e,), or None where no closure can be built.

    The outer edge is the longest boundary loop; it must go once round the back of the head
    seen from ``centre`` (its ``phi`` monotonic but for steps back of at most
    :data:`PHI_REVERSAL`, one turn in all) and stay in front of the back pole.
    """
    loops = boundary_loops(triangles)
    if not loops:
        return None
    loop = loops[0]
    rel = rest[loop] - centre
    d = rel / np.linalg.norm(rel, axis=1, keepdims=True)
    theta, phi = back_polar(d)
    step = np.diff(np.unwrap(np.append(phi, phi[0])))
    turn = step.sum()
    if theta.min() < np.radians(30) or abs(abs(turn) - 2 * np.pi) > 1e-6:
        return None
    if np.any(np.sign(turn) * step < -PHI_REVERSAL):
        return None
    return loop


def monotone_phi(phi: np.ndarray) -> np.ndarray:
    """The edge's ``phi`` (e,) rad made strictly monotonic in its direction of turn: each step
    back (at most :data:`PHI_REVERSAL`) is taken out and the run it ends is spread evenly
    between the angles on either side; unchanged where it already is."""
    u = np.unwrap(phi)
    sign = 1.0 if u[-1] > u[0] else -1.0  # the edge's net turn (nearly a whole one)
    v = sign * u
    if np.all(np.diff(v) > 0):
        return phi
    env = np.maximum.accumulate(v)
    out = env.copy()
    k = 0
    n = len(v)
    while k < n:
        j = k
        while j + 1 < n and env[j + 1] <= env[k]:
            j += 1
        if j > k:  # a flat run k..j: spread it up to the next angle (a turn on at the end)
            nxt = env[j + 1] if j + 1 < n else v[0] + 2 * np.pi
            out[k:j + 1] = env[k] + (nxt - env[k]) * np.arange(j - k + 1) / (j - k + 1)
        k = j + 1
    return sign * out


def _edge_slope(rest, triangles, loop, centre, theta_loop):
    """dr/dalpha (e,) m/rad of the skin at its edge nodes: the radius's change per radian of
    angle away from the face, from the edge's neighbours inside the skin; and for each edge
    node its neighbour furthest inside (e,) and that neighbour's angle from it (e,) rad (the
    edge node itself and 0 where it has none)."""
    f = np.asarray(triangles, np.int64)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    on_edge = np.zeros(len(rest), bool)
    on_edge[loop] = True
    rel = rest - centre
    r = np.linalg.norm(rel, axis=1)
    theta, _ = back_polar(rel / r[:, None])
    pos = {int(n): i for i, n in enumerate(loop)}
    inner = np.array(loop, np.int64)
    beta = np.zeros(len(loop))
    keep = on_edge[edges[:, 0]] & ~on_edge[edges[:, 1]]
    sums = np.zeros(len(loop))
    wsum = np.zeros(len(loop))
    for a, b in edges[keep]:
        i = pos[int(a)]
        dth = theta[b] - theta_loop[i]
        if dth > np.radians(0.5):
            w = dth
            sums[i] += w * (r[a] - r[b]) / dth
            wsum[i] += w
            if dth > beta[i]:
                inner[i], beta[i] = b, dth
    slope = np.where(wsum > 0, sums / np.maximum(wsum, 1e-12), 0.0)
    return np.clip(slope, -MAX_SLOPE, MAX_SLOPE), inner, beta


def _smooth_loop(x: np.ndarray, sigma: float) -> np.ndarray:
    from scipy.ndimage import gaussian_filter1d

    return gaussian_filter1d(x, sigma, mode="wrap") if sigma > 0 else x


def build_closure(rest: np.ndarray, triangles: np.ndarray, cranium: Cranium,
                  rings: int = RINGS) -> Closure | None:
    """The closure of a skin (rest (n, 3) m, triangles (f, 3)) onto ``cranium``; None where
    the skin's edge does not go once round the back of the head (see :func:`outer_loop`)."""
    c = cranium.centre + RAY_ORIGIN
    loop = outer_loop(rest, triangles, c)
    if loop is None:
        return None
    e = len(loop)
    rel = rest[loop] - c
    r_edge = np.linalg.norm(rel, axis=1)
    th0, ph0 = back_polar(rel / r_edge[:, None])
    slope, inner, beta = _edge_slope(rest, triangles, loop, c, th0)
    delta = r_edge - cranium.radius(rel / r_edge[:, None], c)
    verts, nodes, weights, thetas, phis = [rest[loop]], [loop], [np.ones(e)], [th0], [ph0]
    ph_rings = monotone_phi(ph0)  # the rings turn one way even where the edge steps back
    inners, reach = [inner], [np.zeros(e)]
    a0 = np.radians(BLEND_DEG)
    for k in range(1, rings):
        th = th0 * (1.0 - k / rings)
        alpha = th0 - th
        d = from_back_polar(th, ph_rings)
        s = np.clip(alpha / a0, 0.0, 1.0)
        g = 1.0 - s * s * (3.0 - 2.0 * s)
        sigma = 1.0 + k
        # the edge's slope is continued over the first few degrees only (its tangent), the
        # radius's offset over the whole blend
        lean = alpha * np.exp(-alpha / np.radians(8.0))
        rad = cranium.radius(d, c) + g * _smooth_loop(delta, sigma) + _smooth_loop(
            slope, sigma) * lean
        verts.append(c + d * rad[:, None])
        nodes.append(loop)
        weights.append(g)
        inners.append(inner)
        reach.append(np.where(beta > 0, lean / np.maximum(beta, 1e-9), 0.0))
        thetas.append(th)
        phis.append(ph_rings)
    pole = np.array([[0.0, 0.0, -1.0]])
    verts.append(c + pole * cranium.radius(pole, c)[:, None])
    nodes.append(loop[:1])
    weights.append(np.zeros(1))
    inners.append(loop[:1])
    reach.append(np.zeros(1))
    thetas.append(np.zeros(1))
    phis.append(np.zeros(1))
    # faces: the skin's edge runs a -> b, so the closure's first strip has b -> a
    faces = []
    i = np.arange(e)
    j = (i + 1) % e
    for k in range(rings - 1):
        a, b = k * e + i, k * e + j
        a2, b2 = (k + 1) * e + i, (k + 1) * e + j
        faces += [np.stack([b, a, a2], 1), np.stack([b, a2, b2], 1)]
    p = rings * e
    faces.append(np.stack([(rings - 1) * e + j, (rings - 1) * e + i, np.full(e, p)], 1))
    faces = np.concatenate(faces).astype(np.int64)
    verts = _taubin(np.concatenate(verts), faces, fixed=e)
    return Closure(verts, faces, loop, np.concatenate(nodes), np.concatenate(weights),
                   np.concatenate(thetas), np.concatenate(phis), np.concatenate(inners),
                   np.concatenate(reach))


def _taubin(v: np.ndarray, faces: np.ndarray, fixed: int, steps: int = SMOOTHING_STEPS):
    """Taubin's smoothing (lambda 0.5, mu -0.53: no shrinkage) of vertices ``fixed:``; the
    first ``fixed`` (the skin's edge and the ring that carries its slope) stay."""
    from scipy.sparse import coo_matrix

    n = len(v)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = np.concatenate([e, e[:, ::-1]])
    a = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    a.data[:] = 1.0
    deg = np.asarray(a.sum(axis=1)).ravel()
    free = np.arange(n) >= fixed
    v = v.copy()
    for _ in range(steps):
        for k in (0.5, -0.53):
            lap = a @ v / deg[:, None] - v
            v[free] += k * lap[free]
    return v


def closed_surface(skin: np.ndarray, closure: Closure, triangles: np.ndarray,
                   skin_rest: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The head as one closed surface: skin and closure, with the mouth cut closed.

    "Closed" means: the skin's nodes and the closure's vertices (its edge ring being the skin's
    edge nodes), with the twin nodes of the mouth cut (the lips' edges, which coincide at rest)
    merged into one, as the lips are at rest. The palpebral fissures are cut out of the skin's
    texture, not its mesh, so they need nothing. The eyeballs, the mouth's interior, the ears
    and the hair are separate parts and not in it.

    Parameters
    ----------
    skin : (n, 3) m, the skin's node positions of a frame
    closure : the :class:`Closure` of the skin
    triangles : (f, 3) the skin's triangles
    skin_rest : (n, 3) m, the skin at rest (finds the twins)

    Returns
    -------
    vertices (n + m - e, 3) m and triangles (k, 3), counter-clockwise seen from outside
    """
    n = len(skin)
    q = np.round(skin_rest / 1e-7).astype(np.int64)
    _, first, group = np.unique(q, axis=0, return_index=True, return_inverse=True)
    merge = first[group.ravel()]  # each node -> the lowest node at its rest position
    e = len(closure.loop)
    verts = np.concatenate([skin, closure.place(skin, skin_rest)[e:]])
    faces = np.concatenate([triangles, closure.joint_faces(n) - np.where(
        closure.joint_faces(n) >= n, e, 0)])
    remap = np.concatenate([merge, np.arange(n, len(verts))])
    faces = remap[faces]
    used, inv = np.unique(faces, return_inverse=True)
    return verts[used], inv.reshape(-1, 3)
