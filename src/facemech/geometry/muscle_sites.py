"""Where the muscles attach: origins, insertions and the sphincter's beads, as nodes.

Linear muscles (:data:`anatomy.LINEAR_MUSCLES`, and in the anatomical tissue the incisive
bundles) pull the fascia nodes within ``insertion_radius`` of the insertion site toward an
origin on the skull layer. The seeds' tissue shares the force equally among the nearest
``max_insertion_nodes``; the anatomical tissue spreads it over the insertion area (weights: each
node's share of the skin area times a smooth bump of the distance), so the spread does not
depend on the mesh. The sphincter (:data:`anatomy.SPHINCTERS`, orbicularis oris) runs in two
halves per lip, from each mouth corner to the midline along the lip line: through the fascia
nodes of the line (seeds) or through beads, patches of nodes through the lip's thickness
(anatomical).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import MUSCLE_GROUPS
from . import anatomy
from .jaw import JawAttachment
from .kinds import FASCIA, SKULL, Layer, MuscleKind, layer_nodes
from .layers import Layers
from .model import Muscles
from .mouth import LOWER_LIP, UPPER_LIP
from .options import BuildOptions
from .sites import SurfaceSites

#: the instances of every muscle site: (sign of x, name suffix), the subject's right first
SIDES = ((-1.0, "R"), (1.0, "L"))
#: jaw weights of bone that is all mandible, or all fixed skull (where linear origins may lie)
ON_MANDIBLE, OFF_MANDIBLE = 0.999, 1e-3
#: lowest value of the insertion area's bump, so that no node in the radius has no share
BUMP_FLOOR = 0.05


@dataclass(frozen=True)
class MuscleInstance:
    """One muscle of one side, as nodes.

    Parameters
    ----------
    name : e.g. ``ZYG_R``
    group : a muscle group of :data:`facemech.params.MUSCLE_GROUPS`
    kind : LINEAR or SPHINCTER
    origin : the origin node, -1 for a sphincter
    nodes : (k,) int array, insertion nodes or the sphincter's path, in order
    weights : (k,) array, each node's share of the force within its bead
    beads : (k,) int array, the bead of each node
    rest_length : metres
    origin_offset : (3,) array, metres, from the origin node to the origin point
    """

    name: str
    group: str
    kind: MuscleKind
    origin: int
    nodes: np.ndarray
    weights: np.ndarray
    beads: np.ndarray
    rest_length: float
    origin_offset: np.ndarray


def bump_weights(distance: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Unnormalised weights of nodes at ``distance`` (in radii) with skin ``area`` (m^2).

    Area times a smooth bump, ``(1 - d^2)^2``, floored at :data:`BUMP_FLOOR` squared.
    """
    return area * np.clip(1.0 - distance**2, BUMP_FLOOR, None) ** 2


def anatomical_origin(site: anatomy.LinearMuscleSite, point: np.ndarray, layers: Layers,
                      jaw: JawAttachment) -> tuple[int, np.ndarray]:
    """The anatomical origin of a linear muscle near ``point`` (m): its node and offset (3,) m.

    The nearest skull node on bone that does not slide: on the mandible (full jaw weight) or on
    the fixed skull (none). An origin in the fascia (``site.origin_in_fascia``) is the point at
    the depth of the muscle plane above that node, a fixed point in the soft tissue.
    """
    n = layers.n_surface
    weight = jaw.bone_weight
    on_bone = (weight > ON_MANDIBLE) if site.on_mandible else (weight < OFF_MANDIBLE)
    cand = np.nonzero(~layers.slides & on_bone)[0]
    node = int(cand[np.argmin(np.linalg.norm(layers.rest[cand] - point, axis=1))])
    skull = layer_nodes(node, SKULL, n)
    if not site.origin_in_fascia:
        return skull, np.zeros(3)
    return skull, layers.rest[layer_nodes(node, FASCIA, n)] - layers.rest[skull]


def seeds_origin(site: anatomy.LinearMuscleSite, point: np.ndarray, sites: SurfaceSites,
                 layers: Layers, jaw: JawAttachment) -> int:
    """The seeds' origin node: the skull node under the epidermal node nearest ``point`` (m).

    A muscle on the mandible takes the nearest jaw node if that one is not on the jaw.
    """
    node = layer_nodes(sites.snap(point, sites.mouth.line.side_of(point)), SKULL,
                       layers.n_surface)
    if site.on_mandible and node not in set(jaw.nodes.tolist()):
        jd = np.linalg.norm(layers.rest[jaw.nodes] - layers.rest[node], axis=1)
        node = int(jaw.nodes[np.argmin(jd)])
    return node


def insertion(point: np.ndarray, sites: SurfaceSites, area: np.ndarray,
              opt: BuildOptions) -> tuple[np.ndarray, np.ndarray]:
    """The epidermal nodes (k,) of an insertion at ``point`` (m), and their weights (k,).

    The nodes within ``insertion_radius`` on the point's side of the lip line, nearest first:
    weighted by :func:`bump_weights` (anatomical) or the nearest ``max_insertion_nodes`` in equal
    shares (seeds); the nearest node on that side if none lies within the radius.
    """
    want = sites.mouth.line.side_of(point)
    vertices, side = sites.mouth.vertices, sites.mouth.side
    near = sites.tree.query_ball_point(point, opt.insertion_radius)
    near = [c for c in near if want is None or side[c] == want]
    near = sorted(near, key=lambda c: np.linalg.norm(vertices[c] - point))
    if opt.anatomical:
        near = near or [sites.snap(point, want)]
        dist = np.linalg.norm(vertices[near] - point, axis=1) / opt.insertion_radius
        w = bump_weights(dist, area[near])
        return np.asarray(near), w / w.sum()
    near = near[: opt.max_insertion_nodes] or [sites.snap(point, want)]
    return np.asarray(near), np.full(len(near), 1.0 / len(near))


@dataclass(frozen=True)
class Attachment:
    """What muscles attach to: the surface's sites and area, the layers and the jaw."""

    sites: SurfaceSites
    area: np.ndarray  # (n,) m^2, each epidermal node's share of the skin
    layers: Layers
    jaw: JawAttachment


def linear_muscle(site: anatomy.LinearMuscleSite, sign: float, suffix: str, at: Attachment,
                  opt: BuildOptions) -> MuscleInstance:
    """One side (``sign`` of x, name ``suffix``) of a linear muscle site."""
    n, rest = at.layers.n_surface, at.layers.rest
    origin_p = at.sites.place((sign * abs(site.origin[0]), site.origin[1]))
    insertion_p = at.sites.place((sign * abs(site.insertion[0]), site.insertion[1]))
    if opt.anatomical:
        origin, offset = anatomical_origin(site, origin_p, at.layers, at.jaw)
    else:
        origin = seeds_origin(site, origin_p, at.sites, at.layers, at.jaw)
        offset = np.zeros(3)
    near, w = insertion(insertion_p, at.sites, at.area, opt)
    nodes = layer_nodes(near, FASCIA, n)
    centre = (w[:, None] * rest[nodes]).sum(axis=0) if opt.anatomical else rest[nodes].mean(axis=0)
    return MuscleInstance(name=f"{site.name or site.group}_{suffix}", group=site.group,
                          kind=MuscleKind.LINEAR, origin=origin, nodes=nodes, weights=w,
                          beads=np.zeros(len(nodes), np.int64),
                          rest_length=np.linalg.norm(centre - rest[origin] - offset),
                          origin_offset=offset)


def sphincter_beads(path: list[int], lip_side: int, at: Attachment, opt: BuildOptions,
                    marginal: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Beads of one half of an anatomical orbicularis oris, from the mouth corner to the midline.

    ``path`` is the lip-line path (epidermal nodes, corner first). Beads lie every
    ``sphincter_spacing`` along it, each centred ``sphincter_offset`` into the lip (the middle
    of the muscle's band) and gather the nodes of that lip within ``sphincter_radius`` through
    the lip's thickness: skin, muscle plane and the deep (teeth-side) surface, weighted by
    ``sphincter_depth_weights`` (the peripheral part of the muscle lies near the teeth), by skin
    area and by a smooth bump of the distance. The first bead is the modiolus, ``modiolus``
    lateral to the corner, and takes nodes of both lips. Returns the nodes (global indices),
    their weights and the bead of each.

    The marginal part (``marginal``) runs in the red lip near its free margin: its beads lie
    ``marginal_height x (1 - (1 - u)^2)`` from the lip line (u: 0 at the corner, 1 at the
    midline; an arch whose top is level at the midline), gather ``marginal_radius`` and take
    ``marginal_depth_weights``.
    """
    vertices, side, tree = at.sites.mouth.vertices, at.sites.mouth.side, at.sites.tree
    n = len(vertices)
    pts = vertices[np.asarray(path)]
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    count = max(3, int(round(arc[-1] / opt.sphincter_spacing)) + 1)
    lateral = np.sign(pts[0, 0] - pts[-1, 0])
    out_nodes, out_w, out_b = [], [], []
    radius = opt.marginal_radius if marginal else opt.sphincter_radius
    for k, s_k in enumerate(np.linspace(0.0, arc[-1], count)):
        centre = np.array([np.interp(s_k, arc, pts[:, a]) for a in range(3)])
        u = s_k / arc[-1]
        offset = (opt.marginal_height * (1.0 - (1.0 - u) ** 2) if marginal
                  else opt.sphincter_offset)
        if k > 0:
            centre = centre + np.array([0.0, lip_side * offset, 0.0])
        else:
            centre = centre + np.array([lateral * opt.modiolus, 0.0, 0.0])
        near = np.asarray(tree.query_ball_point(centre, radius), np.int64)
        if k > 0:
            near = near[side[near] == lip_side]
        if len(near) == 0:
            near = np.array([int(tree.query(centre)[1])])
        dist = np.linalg.norm(vertices[near] - centre, axis=1) / radius
        w = bump_weights(dist, at.area[near])
        shares = ((opt.marginal_depth_weights if marginal else opt.sphincter_depth_weights)
                  if k > 0 else opt.modiolus_depth_weights)
        for layer, share in zip(Layer, shares, strict=True):
            # the deep surface takes a share only where it moves
            ok = at.layers.slides[near] if layer == SKULL else np.ones(len(near), bool)
            if share <= 0 or not ok.any():
                continue
            out_nodes.extend(layer_nodes(near, layer, n)[ok].tolist())
            out_w.extend((share * w[ok]).tolist())
            out_b.extend([k] * int(ok.sum()))
    out_w = np.asarray(out_w)
    out_b = np.asarray(out_b, np.int64)
    for k in range(count):
        out_w[out_b == k] /= out_w[out_b == k].sum()
    return np.asarray(out_nodes, np.int64), out_w, out_b


def sphincter_half(group: str, lip_side: int, suffix: str, path: list[int], at: Attachment,
                   opt: BuildOptions) -> MuscleInstance:
    """Half a sphincter along ``path`` (epidermal lip-line nodes of ``lip_side``, corner first);
    a group of :data:`anatomy.MARGINAL` is the marginal part (anatomical tissue only)."""
    rest = at.layers.rest
    if opt.anatomical:
        nodes, w, beads = sphincter_beads(path, lip_side, at, opt,
                                          marginal=group in anatomy.MARGINAL)
        chain_rest = np.array([(w[beads == k, None] * rest[nodes[beads == k]]).sum(axis=0)
                               for k in range(beads.max() + 1)])
    else:
        nodes = layer_nodes(np.asarray(path), FASCIA, at.layers.n_surface)
        w = np.ones(len(path))
        beads = np.arange(len(path))
        chain_rest = rest[nodes]
    return MuscleInstance(name=f"{group}_{suffix}", group=group, kind=MuscleKind.SPHINCTER,
                          origin=-1, nodes=nodes, weights=np.asarray(w, float), beads=beads,
                          rest_length=np.sum(np.linalg.norm(np.diff(chain_rest, axis=0), axis=1)),
                          origin_offset=np.zeros(3))


def sphincter_paths(at: Attachment, marginal: bool = False
                    ) -> list[tuple[str, int, str, list[int]]]:
    """(group, lip side, suffix, path) of every sphincter half: each lip's line, corner first.

    The halves meet at the lip-line node nearest the stomion; the lower lip runs through the
    cut's lower twins. ``marginal`` adds the marginal part's halves (:data:`anatomy.MARGINAL`),
    along the same lines.
    """
    mouth = at.sites.mouth
    path, mid, twin = mouth.path, mouth.midline_index(), mouth.lower_twin()
    out = []
    groups = anatomy.SPHINCTERS + (anatomy.MARGINAL if marginal else ())
    for group, lip_side in zip(groups, (UPPER_LIP, LOWER_LIP) * (len(groups) // 2), strict=True):
        for suffix, seg in (("R", path[: mid + 1]), ("L", path[mid:][::-1])):
            seq = [twin.get(int(v), int(v)) if lip_side == LOWER_LIP else int(v) for v in seg]
            out.append((group, lip_side, suffix, seq))
    return out


def muscle_instances(at: Attachment, opt: BuildOptions) -> list[MuscleInstance]:
    """Every muscle of the face: the linear ones (right, then left), then the sphincter."""
    linear_sites = anatomy.LINEAR_MUSCLES + (anatomy.INCISIVE_MUSCLES if opt.anatomical else ())
    linear = [linear_muscle(site, sign, suffix, at, opt)
              for site in linear_sites for sign, suffix in SIDES]
    return linear + [sphincter_half(*half, at, opt)
                     for half in sphincter_paths(at, marginal=opt.anatomical)]


def assemble_muscles(instances: list[MuscleInstance]) -> Muscles:
    """The :class:`~.model.Muscles` (CSR node lists) of muscle instances, in their order."""
    sizes = [len(m.nodes) for m in instances]
    return Muscles(
        names=tuple(m.name for m in instances),
        group=np.asarray([MUSCLE_GROUPS.index(m.group) for m in instances], np.int64),
        kind=np.asarray([int(m.kind) for m in instances], np.int64),
        origin=np.asarray([m.origin for m in instances], np.int64),
        ptr=np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
        nodes=np.concatenate([m.nodes for m in instances]).astype(np.int64),
        weights=np.concatenate([m.weights for m in instances]).astype(float),
        rest_length=np.asarray([m.rest_length for m in instances], float),
        bead=np.concatenate([m.beads for m in instances]).astype(np.int64),
        origin_offset=np.asarray([m.origin_offset for m in instances], float).reshape(-1, 3),
    )
