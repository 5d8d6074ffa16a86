"""Thick tissue layers kept from folding where a real head curves sharply.

The anatomical skull layer lies up to 18 mm under the skin (:mod:`tissue`) along smoothed
normals. Where a real head curves more sharply (the jaw angle, under the chin, the neck, the
ears, the nostrils) a prism between two layers loses its volume: *sheared* (a triangle's normal
more than 60 degrees, :data:`SHEAR_COS`, from its nodes' offsets) or *squeezed* (the skin bends
round a radius smaller than the depth). A prism keeping less than :data:`FOLDING` of a flat
slab's volume is folded. :func:`relieve_folds` mends such places until each prism keeps
:data:`MIN_QUALITY`, and changes nothing else: (1) a sheared node's offset turns towards the
middle direction of its triangles' normals; (2) prisms still short thin by steps down to
:data:`MIN_DEPTH` (3 mm), tapering into the tissue around by at most :data:`MAX_SLOPE` mm per
mm of skin; (3) those still folding thin on to :data:`LAST_DEPTH`. Notes come back per
connected patch (region, point mm, thinning mm, turn degrees, nodes); a face with no folding
prism (the built-in faces) comes back unchanged to the bit.
"""

from __future__ import annotations

import numpy as np

from .tissue import DEPTH_RANGE_MM

#: a prism that keeps less than this share of a flat slab's volume (area times thickness) is
#: as good as folded: on the tests' scan-like head one left at 0.05 made the simulation blow up
#: in its second frame. The built-in faces' worst prisms keep 0.28 (fine) to 0.32 and the tests'
#: scan-like face's 0.17, so that nothing changes on them.
FOLDING = 0.15
#: a prism near a fold is mended until it keeps this share
MIN_QUALITY = 0.3
#: below this cosine between a triangle's normal and a node's offset the prism counts as sheared
SHEAR_COS = 0.5
#: thinning tapers: the thinning falls off by at most this many metres per metre of skin
MAX_SLOPE = 0.5
#: m, the tissue thins first down to the thinnest of the anatomical map (the nasal bridge,
#: :data:`tissue.DEPTH_RANGE_MM`): no thinner, and so no stiffer, than the built-in face has
MIN_DEPTH = DEPTH_RANGE_MM[0] * 1e-3
#: m, where a prism still folds at that floor (a rim sharper than 3 mm), the tissue there thins
#: on to this
LAST_DEPTH = 1.5e-3
#: a thinning step keeps this share of the depth; a turning step goes this share of the way
THIN_STEP, TURN_STEP = 0.85, 0.5
#: rounds of each remedy at most
MAX_ROUNDS = 80
#: an offset within about 2.5 degrees of its triangles' middle direction has turned enough
TURNED_COS = 0.999


def prism_quality(vertices: np.ndarray, faces: np.ndarray, offset: np.ndarray,
                  depth: np.ndarray, fascia_fraction: float) -> np.ndarray:
    """Each triangle's worse prism (f,): its volume over the skin triangle's area times the
    prism's mean thickness (1 for a flat slab; 0 or less for a folded one).

    Parameters
    ----------
    vertices : (n, 3) epidermal nodes, metres
    faces : (f, 3) triangles
    offset : (n, 3) unit directions out of the face along which the layers lie
    depth : (n,) skull-layer depth, metres; the fascia lies at ``fascia_fraction`` of it
    """
    from .prism import rest_geometry

    n = len(vertices)
    rest = layer_positions(vertices, offset, depth, fascia_fraction)
    tri = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    out = np.full(len(faces), np.inf)
    for layer, share in ((0, fascia_fraction), (1, 1.0 - fascia_fraction)):
        prisms = np.concatenate([faces + layer * n, faces + (layer + 1) * n], axis=1)
        vol, _ = rest_geometry(rest, prisms)
        thick = share * depth[faces].mean(axis=1)
        out = np.minimum(out, vol / np.maximum(area * thick, 1e-30))
    return out


def layer_positions(vertices: np.ndarray, offset: np.ndarray, depth: np.ndarray,
                    fascia_fraction: float) -> np.ndarray:
    """Epidermis, fascia and skull nodes (3 n, 3), metres."""
    return np.concatenate([vertices, vertices - (fascia_fraction * depth)[:, None] * offset,
                           vertices - depth[:, None] * offset])


def relieve_folds(vertices: np.ndarray, faces: np.ndarray, offset: np.ndarray,
                  depth: np.ndarray, fascia_fraction: float, *, generic_xy: np.ndarray,
                  twins: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Offsets and depths with no folded prism, changed only near the places that fold.

    Parameters
    ----------
    vertices : (n, 3) epidermal nodes, metres
    faces : (f, 3) triangles, wound so that their normals point out of the face
    offset : (n, 3) unit offset directions of the layers
    depth : (n,) skull-layer depth, metres
    fascia_fraction : the fascia's share of the depth
    generic_xy : (n, 2) generic frontal coordinates, mm (:func:`~.warp.generic_frontal_mm`),
        which name the regions in the notes
    twins : (q, 2) node pairs that must keep one offset and depth (the mouth slit's)

    Returns
    -------
    offset : (n, 3) unit directions, ``offset`` itself where nothing folds
    depth : (n,) metres, ``depth`` itself where nothing folds
    notes : one line per mended place (empty when nothing folds)
    """
    quality = prism_quality(vertices, faces, offset, depth, fascia_fraction)
    if np.all(quality >= FOLDING):
        return offset, depth, []
    n = len(vertices)
    o, d = offset.copy(), depth.copy()
    near = np.zeros(n, bool)
    near[faces[quality < FOLDING]] = True
    tri_normal = _triangle_normals(vertices, faces)
    edges = _edges(faces)
    edge_len = np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)

    def bad_prisms(q):
        out = (q < MIN_QUALITY) & near[faces].any(axis=1) | (q < FOLDING)
        near[faces[out]] = True
        return out

    def settle(o, d):
        if twins is not None and len(twins):  # a changed twin takes its partner along
            moved = (d != depth) | np.any(o != offset, axis=1)
            t = twins[moved[twins[:, 0]] | moved[twins[:, 1]]]
            d[t[:, 0]] = d[t[:, 1]] = np.minimum(d[t[:, 0]], d[t[:, 1]])
            o[t[:, 1]] = o[t[:, 0]]
        return prism_quality(vertices, faces, o, d, fascia_fraction)

    # 1. sheared nodes turn towards the middle of their triangles' normals
    for _ in range(MAX_ROUNDS):
        bad = bad_prisms(quality)
        cos = np.einsum("fkc,fc->fk", o[faces[bad]], tri_normal[bad])
        nodes = np.unique(faces[bad][cos < SHEAR_COS])
        if not len(nodes):
            break
        centre = _fan_centres(tri_normal, faces, nodes)
        still = np.einsum("ic,ic->i", centre, o[nodes]) < TURNED_COS
        if not still.any():
            break
        c = nodes[still]
        o[c] = _unit(o[c] + TURN_STEP * (centre[still] - o[c]))
        quality = settle(o, d)
    # 2. the tissue of the prisms still short of a slab's share thins, down to the floor;
    # 3. of those still folding, on to the last floor
    for floor, worse_than in ((np.minimum(depth, MIN_DEPTH), MIN_QUALITY),
                              (np.minimum(depth, LAST_DEPTH), FOLDING)):
        for _ in range(MAX_ROUNDS):
            bad = bad_prisms(quality) & (quality < worse_than)
            thin = np.zeros(n, bool)
            thin[faces[bad]] = True
            thin &= d > floor * (1 + 1e-9)
            if not thin.any():
                break
            d[thin] = np.maximum(d[thin] * THIN_STEP, floor[thin])
            d = _taper(d, depth, edges, edge_len)
            quality = settle(o, d)
    if np.any(quality <= 0):
        return o, d, []  # still folded: the caller's check names the place
    notes = fold_notes(vertices, faces, offset, depth, o, d, generic_xy)
    return o, d, notes + _still_flat(vertices, faces, quality, generic_xy)


def _still_flat(vertices, faces, quality, generic_xy) -> list[str]:
    """A note on the prisms that keep under :data:`FOLDING` after the mending (none: [])."""
    flat = np.nonzero(quality < FOLDING)[0]
    if not len(flat):
        return []
    k = flat[np.argmin(quality[flat])]
    at = vertices[faces[k, 0]] * 1e3
    return [f"{len(flat)} prisms at {region_name(*generic_xy[faces[k, 0]])} near "
            f"({at[0]:.0f}, {at[1]:.0f}, {at[2]:.0f}) mm keep under "
            f"{FOLDING * 100:.0f} % of a flat slab's volume even so (down to "
            f"{quality[k] * 100:.0f} %): a simulation may blow up there; smooth the "
            "scan there if it does"]


def _taper(d: np.ndarray, depth: np.ndarray, edges: np.ndarray,
           length: np.ndarray) -> np.ndarray:
    """``d`` (m) thinned further round each thinned node, so that the thinning ``depth - d``
    falls off by at most :data:`MAX_SLOPE` per metre along the edges."""
    t = depth - d
    a, b = edges[:, 0], edges[:, 1]
    for _ in range(500):
        need = np.zeros(len(d))
        np.maximum.at(need, a, t[b] - MAX_SLOPE * length)
        np.maximum.at(need, b, t[a] - MAX_SLOPE * length)
        more = need > t + 1e-12
        if not more.any():
            break
        t[more] = need[more]
    spread = depth - np.minimum(t, depth - np.minimum(depth, MIN_DEPTH))
    return np.minimum(d, spread)  # the taper itself thins nothing below the floor


def fold_notes(vertices: np.ndarray, faces: np.ndarray, offset0: np.ndarray,
               depth0: np.ndarray, offset: np.ndarray, depth: np.ndarray,
               generic_xy: np.ndarray) -> list[str]:
    """One line per connected patch of changed nodes: the region, a point (mm), how much the
    tissue thinned (mm, from what to what) and how far its offset turned (degrees)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    thinned = depth0 - depth
    turned = np.any(offset != offset0, axis=1)
    angle = np.where(turned, np.degrees(np.arccos(np.clip(
        np.einsum("ic,ic->i", offset0, offset), -1.0, 1.0))), 0.0)
    changed = (thinned > 1e-7) | turned  # a tenth of a micrometre: rounding, not thinning
    edges = _edges(faces)
    keep = changed[edges[:, 0]] & changed[edges[:, 1]]
    n = len(vertices)
    graph = coo_matrix((np.ones(int(keep.sum())), (edges[keep, 0], edges[keep, 1])),
                       shape=(n, n))
    _, label = connected_components(graph, directed=False)
    notes = []
    patches = sorted(np.unique(label[changed]),
                     key=lambda p: -max(thinned[label == p].max(), 0.0))
    for p in patches:
        nodes = np.nonzero(changed & (label == p))[0]
        k = nodes[np.argmax(thinned[nodes] + 1e-6 * angle[nodes])]
        at = vertices[k] * 1e3
        parts = []
        if thinned[nodes].max() > 1e-7:
            parts.append(f"thinned by up to {thinned[k] * 1e3:.1f} mm "
                         f"({depth0[k] * 1e3:.1f} -> {depth[k] * 1e3:.1f} mm)")
        if turned[nodes].any():
            parts.append(f"its offset direction turned by up to "
                         f"{angle[nodes].max():.0f} degrees")
        where = region_name(*generic_xy[k])
        notes.append(f"the tissue layers would fold at {where} near ({at[0]:.0f}, "
                     f"{at[1]:.0f}, {at[2]:.0f}) mm (the skin curves more sharply than the "
                     f"tissue is deep): {' and '.join(parts)}, over {len(nodes)} nodes")
    return notes


def region_name(x: float, y: float) -> str:
    """The part of the face at generic frontal (x, y) mm (:mod:`generic`: nasion at the origin,
    menton at y = -122, the jaw angles at (+-50, -100), +x the subject's left)."""
    side = "left" if x > 0 else "right"
    ax = abs(x)
    if y < -138:
        return "the neck"
    if y < -124:
        return "the throat under the chin" if ax < 35 else f"the underside of the {side} jaw"
    if ax > 62 and y > -85:
        return f"the {side} ear"
    if ax > 42 and y < -80:
        return f"the {side} jaw angle"
    if ax < 20 and -58 < y < -38:
        return "the nostrils"
    if ax < 15 and -38 <= y < 2:
        return "the nose"
    if ax < 35 and -98 < y <= -58:
        return "the lips"
    if ax < 35 and y <= -98:
        return "the chin"
    if 12 < ax < 52 and -14 < y < 8:
        return f"the {side} eye"
    if y >= 8:
        return "the forehead" if ax < 35 else f"the {side} temple"
    return f"the {side} cheek"


def _fans(faces: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(owner, triangle): each of ``nodes``' triangles, ``owner`` its index into ``nodes``."""
    corner_node = faces.T.reshape(-1)
    corner_tri = np.tile(np.arange(len(faces)), 3)
    slot = np.full(int(faces.max()) + 1, -1)
    slot[nodes] = np.arange(len(nodes))
    keep = slot[corner_node] >= 0
    return slot[corner_node[keep]], corner_tri[keep]


def _fan_centres(normals: np.ndarray, faces: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """For each of ``nodes``, the unit direction (len(nodes), 3) as near as it can be to all
    its triangles' ``normals`` (the largest smallest cosine), by subgradient steps from their
    mean: the offset that shears none of them, where the skin does not fold over itself."""
    owner, tri = _fans(faces, nodes)
    centre = np.zeros((len(nodes), 3))
    np.add.at(centre, owner, normals[tri])
    centre = _unit(centre)
    for it in range(40):
        cos = np.einsum("ic,ic->i", centre[owner], normals[tri])
        order = np.lexsort((cos, owner))  # by node, then the worst triangle first
        first = np.ones(len(order), bool)
        first[1:] = owner[order][1:] != owner[order][:-1]
        worst = tri[order][first]
        centre = _unit(centre + 0.3 / (1.0 + 0.3 * it) * normals[worst])
    return centre


def _edges(faces: np.ndarray) -> np.ndarray:
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def _triangle_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return _unit(np.cross(b - a, c - a))


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0)
