"""Build the three-layer face model from a surface and landmarks (Lucero & Munhall 1999, I.A).

The epidermal surface is copied inwards along its normals to make the fascia and skull layers.
Each surface triangle with its copies below makes prism elements. The mouth slit is cut along
the lip line so that upper and lower lips are separate sheets that touch at rest.

Two tissue geometries (``BuildOptions.tissue``):

``uniform`` (the seeds')
    fascia 1.5 mm and skull 4 mm below the skin everywhere. Springs join the epidermis within
    itself, epidermis to fascia (dermal-fatty), the fascia within itself, and fascia to skull
    (muscle layer) where the fascia is tied; a prism joins epidermis and fascia everywhere and
    fascia and skull where the fascia is tied. The fascia is free (untied) in an ellipse around
    the mouth and a disc in each cheek.
``anatomical``
    the skull layer lies at the soft-tissue depth of :mod:`tissue` (3 mm on the nasal bridge to
    16 mm in the upper lip and over the buccal teeth), along normals smoothed over about a
    centimetre so that the thick layers do not fold in concave places; the fascia (the plane of
    the mimetic muscles) lies at ``fascia_fraction`` of that depth. Two prism layers everywhere,
    with springs on every prism edge, the diagonals of the side faces included (they carry the
    tissue's shear). Under the lips and the chin pad the skull layer is the deep surface of the
    tissue (labial mucosa, chin fat), which moves and slides on the teeth and bone
    (``FaceModel.sliding``); the jaw turns the deep surface with a weight that blends from the
    mandible to the fixed skull across a band lateral to the mouth corners.

Other choices the paper leaves open (SPEC section 6), each a field of :class:`BuildOptions`:
- the jaw: skull nodes below the lip line and below the line from each mouth corner to the jaw
  angle; the hinge axis is parallel to x, at the height of the nasal base (halfway between nose
  tip and subnasale) and 25 mm behind the skin jaw-angle landmarks (the condyles lie about
  10-12 mm in front of the tragus, near its height);
- linear muscles pull the fascia nodes within ``insertion_radius`` of the insertion site: the
  seeds' tissue shares the force equally among the nearest ``max_insertion_nodes``; the
  anatomical tissue spreads it over the insertion area (weights: each node's share of the skin
  area times a smooth bump of the distance), so the spread does not depend on the mesh;
- lip contact: the upper lip margin and its twin on the lower one never pass each other.
"""

from __future__ import annotations

import heapq
from collections import OrderedDict
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import cKDTree

from ..errors import InputError
from ..params import MUSCLE_GROUPS
from . import anatomy, generic, tissue
from .appearance import Appearance
from .model import (  # noqa: F401  (re-exported: the model's names live beside its builder)
    EPIDERMIS,
    FASCIA,
    LAYER_NAMES,
    LINEAR,
    SKULL,
    SPHINCTER,
    SPRING_KINDS,
    TISSUES,
    FaceModel,
    Muscles,
)
from .surface_io import REQUIRED_LANDMARKS, check_manifold


@dataclass(frozen=True)
class BuildOptions:
    """Geometric choices of the model builder (lengths in metres).

    ``tissue_options(name)`` gives the options of each tissue geometry.
    """

    tissue: str = "uniform"  # "uniform" (the seeds') or "anatomical"
    depth_fascia: float = 1.5e-3  # uniform: epidermis -> fascia
    depth_skull: float = 2.5e-3  # uniform: fascia -> skull
    fascia_fraction: float = 0.4  # anatomical: depth of the muscle plane / soft-tissue depth
    normal_smoothing: float = 6e-3  # anatomical: m, Gaussian width of the offset directions
    lip_region_half_width: float = 1.25  # x semi-axis of the free lip ellipse, in mouth half-widths
    lip_region_up: float = 1.0  # upward semi-axis, in subnasale-stomion heights
    lip_region_down: float = 0.9  # downward semi-axis, in the same unit
    cheek_radius: float = 14e-3  # m, radius of each free cheek disc (uniform)
    insertion_radius: float = 3.5e-3  # m
    max_insertion_nodes: int = 6  # uniform: nearest nodes sharing a muscle's force
    hinge_behind_jaw_angle: float = 25e-3  # m, condyle behind the (skin) jaw angle landmark
    jaw_band: float = 30e-3  # anatomical: m, width of the jaw-weight blend lateral to the mouth
    jaw_taper: float = 30e-3  # anatomical: m, over which the blend widens from the corner
    sphincter_spacing: float = 6e-3  # anatomical: m, between the beads of orbicularis oris
    sphincter_offset: float = 3.5e-3  # anatomical: m, bead centres from the lip line into the lip
    sphincter_radius: float = 4.5e-3  # anatomical: m, radius of each bead's patch
    #: anatomical: share of each bead's force on the skin, the muscle plane and the deep surface
    sphincter_depth_weights: tuple = (0.0, 0.0, 1.0)
    modiolus: float = 5e-3  # anatomical: m, the first bead lateral to the mouth corner
    modiolus_depth_weights: tuple = (1.0, 1.0, 0.0)  # anatomical: the first bead's layers


def tissue_options(name: str) -> BuildOptions:
    """The build options of a tissue geometry: ``uniform`` (seeds) or ``anatomical``."""
    if name == "uniform":
        return BuildOptions()
    if name == "anatomical":
        return BuildOptions(tissue="anatomical", insertion_radius=7e-3)
    raise InputError(f"unknown tissue geometry {name!r} (expected {', '.join(TISSUES)})",
                     field="tissue")


# ------------------------------------------------------------------------------------------------
def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3) of a triangle mesh."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    fn = np.cross(b - a, c - a)
    vn = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(vn, faces[:, k], fn)
    norm = np.linalg.norm(vn, axis=1, keepdims=True)
    return vn / np.where(norm > 0, norm, 1.0)


def _edges(faces: np.ndarray) -> np.ndarray:
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def _boundary_nodes(faces: np.ndarray) -> np.ndarray:
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    u, c = np.unique(e, axis=0, return_counts=True)
    return np.unique(u[c == 1])


def _lip_line_path(vertices, faces, start, goal, line_y) -> list[int]:
    """Shortest edge path from ``start`` to ``goal`` that hugs the lip line ``y = line_y(x)``."""
    edges = _edges(faces)
    n = len(vertices)
    adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for a, b in edges:
        length = np.linalg.norm(vertices[a] - vertices[b])
        off = 0.5 * (abs(vertices[a, 1] - line_y(vertices[a, 0]))
                     + abs(vertices[b, 1] - line_y(vertices[b, 0])))
        w = length * (1.0 + (off / 0.5e-3) ** 2)  # strongly prefer nodes on the lip line
        adj[a].append((b, w))
        adj[b].append((a, w))
    dist = np.full(n, np.inf)
    prev = np.full(n, -1)
    dist[start] = 0.0
    heap = [(0.0, start)]
    while heap:
        d, u = heapq.heappop(heap)
        if u == goal:
            break
        if d > dist[u]:
            continue
        for v, w in adj[u]:
            if d + w < dist[v]:
                dist[v] = d + w
                prev[v] = u
                heapq.heappush(heap, (d + w, v))
    if not np.isfinite(dist[goal]):
        raise InputError("the mouth corners are not connected by the surface", field="mouth")
    path = [goal]
    while path[-1] != start:
        path.append(int(prev[path[-1]]))
    return path[::-1]


def _cut_mouth(vertices, faces, corner_r, corner_l, line_y):
    """Duplicate the interior lip-line nodes; faces below the line take the copies.

    Returns the new vertices and faces, and the (upper, lower) node pairs of the cut. The
    copies are appended after the vertices, in the order of the pairs; every triangle keeps its
    row and the order of its corners (what carries a texture through the cut).
    """
    path = _lip_line_path(vertices, faces, corner_r, corner_l, line_y)
    interior = path[1:-1]
    if not interior:
        raise InputError("mouth corners are adjacent: the mesh is too coarse at the lips",
                         field="mouth")
    n = len(vertices)
    twin = {v: n + k for k, v in enumerate(interior)}
    new_vertices = np.concatenate([vertices, vertices[interior]])
    faces = faces.copy()
    on_path = np.isin(faces, interior)
    rows = np.nonzero(on_path.any(axis=1))[0]
    centroid = vertices[faces[rows]].mean(axis=1)
    below = centroid[:, 1] < np.array([line_y(x) for x in centroid[:, 0]])
    for r, is_below in zip(rows, below, strict=True):
        if is_below:
            faces[r] = [twin.get(int(v), int(v)) for v in faces[r]]
    pairs = np.array([(v, twin[v]) for v in interior], dtype=np.int64)
    return new_vertices, faces, pairs, np.asarray(path)


def _tps_warp(source: dict, target: dict):
    """Thin-plate-spline map from the generic landmarks to a face's landmarks (metres)."""
    names = [n for n in source if n in target]
    src = np.array([source[n] for n in names])
    dst = np.array([target[n] for n in names])
    if np.allclose(src, dst, atol=1e-9):
        return lambda p: np.asarray(p, float)
    rbf = RBFInterpolator(src, dst - src, kernel="thin_plate_spline", degree=1)
    return lambda p: np.asarray(p, float) + rbf(np.atleast_2d(p)).reshape(np.shape(p))


def smoothed_normals(vertices: np.ndarray, faces: np.ndarray, sigma: float) -> np.ndarray:
    """Unit normals (n, 3) averaged over the surface with a Gaussian of width ``sigma`` (m).

    Area-weighted triangle normals within 2.5 sigma of each vertex. The offset direction of a
    thick tissue layer must change slowly, or the layer folds where the skin is concave (the
    mentolabial sulcus, the sides of the nose); averaging over a fixed distance rather than a
    number of neighbours gives the same directions on every mesh resolution.
    """
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    fn = np.cross(b - a, c - a)  # twice the area times the unit normal
    centroid = (a + b + c) / 3.0
    tree = cKDTree(centroid)
    out = np.zeros_like(vertices)
    for i, near in enumerate(tree.query_ball_point(vertices, 2.5 * sigma)):
        if not near:
            continue
        near = np.asarray(near)
        d2 = np.sum((centroid[near] - vertices[i]) ** 2, axis=1)
        out[i] = (np.exp(-0.5 * d2 / sigma**2)[:, None] * fn[near]).sum(axis=0)
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return out / np.where(norm > 0, norm, 1.0)


def vertex_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each vertex's share of the surface area (a third of its triangles'), m^2."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    out = np.zeros(len(vertices))
    for k in range(3):
        np.add.at(out, faces[:, k], area / 3.0)
    return out


def build_face(
    vertices: np.ndarray,
    faces: np.ndarray,
    landmarks: dict[str, np.ndarray],
    *,
    options: BuildOptions | None = None,
    name: str = "face",
    source: str | None = None,
    appearance: Appearance | None = None,
) -> FaceModel:
    """Build the layered face model from an epidermal surface (metres) and its landmarks.

    Parameters
    ----------
    vertices : (n, 3) array, metres; +x subject's left, +y up, +z forward
    faces : (f, 3) int array; a closed mouth (the lips fused along the lip line)
    landmarks : dict name -> (3,) metres; at least :data:`REQUIRED_LANDMARKS`
    options : geometric choices (default: the seeds' uniform tissue, :class:`BuildOptions`)
    source : name of the input, for error messages
    appearance : the surface's texture (UVs per corner of ``faces``) or vertex colours (per
        row of ``vertices``), carried onto the model: the nodes the mouth cut adds take their
        twins' colours, and the triangles keep their corners' texture coordinates
    """
    opt = options or BuildOptions()
    if opt.tissue not in TISSUES:
        raise InputError(f"unknown tissue geometry {opt.tissue!r}", source=source, field="tissue")
    missing = [n for n in REQUIRED_LANDMARKS if n not in landmarks]
    if missing:
        raise InputError(f"missing landmarks: {', '.join(missing)}", source=source,
                         field=missing[0])
    vertices = np.asarray(vertices, float)
    faces = np.asarray(faces, np.int64)
    if len(vertices) < 200 or len(faces) < 300:
        raise InputError(f"surface too coarse ({len(vertices)} vertices)", source=source,
                         field="vertices")
    check_manifold(faces, source=source)
    if appearance is not None:
        appearance.check_surface(len(vertices), len(faces), source=source)
    normals = vertex_normals(vertices, faces)
    if normals[:, 2].mean() < 0:  # faces must be wound so normals point out of the face
        faces = faces[:, ::-1].copy()
        normals = -normals
        if appearance is not None and appearance.uv is not None:
            appearance = replace(appearance, uv=appearance.uv[:, ::-1])
    surface = {"vertices": vertices.copy(), "faces": faces.copy(),
               "landmarks": {k: np.asarray(v, float).copy() for k, v in landmarks.items()}}

    lm = {k: np.asarray(v, float) for k, v in landmarks.items()}
    tree0 = cKDTree(vertices)
    corner_r = int(tree0.query(lm["mouth_corner_right"])[1])
    corner_l = int(tree0.query(lm["mouth_corner_left"])[1])
    boundary = _boundary_nodes(faces)
    if corner_r in boundary or corner_l in boundary:
        raise InputError("the mouth corners lie on a hole of the mesh: facemech needs a closed "
                         "mouth (lips fused along the lip line)", source=source, field="mouth")
    stomion = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    cr, cl = vertices[corner_r], vertices[corner_l]

    def line_y(x: float) -> float:
        """Height of the lip line at x: corner - stomion - corner, piecewise linear."""
        if x <= stomion[0]:
            t = (x - cr[0]) / max(stomion[0] - cr[0], 1e-9)
            return float(cr[1] + np.clip(t, 0, 1) * (stomion[1] - cr[1]))
        t = (x - stomion[0]) / max(cl[0] - stomion[0], 1e-9)
        return float(stomion[1] + np.clip(t, 0, 1) * (cl[1] - stomion[1]))

    vertices, faces, cut_pairs, path = _cut_mouth(vertices, faces, corner_r, corner_l, line_y)
    n = len(vertices)
    if appearance is not None:  # the cut rewires triangles in place: same rows, same corners
        if appearance.vertex_colours is not None:
            vc = appearance.vertex_colours
            appearance = replace(appearance, vertex_colours=np.concatenate(
                [vc, vc[cut_pairs[:, 0]]]))
    normals = vertex_normals(vertices, faces)
    # the two copies of a cut node share one normal (the lip line's)
    avg = 0.5 * (normals[cut_pairs[:, 0]] + normals[cut_pairs[:, 1]])
    avg /= np.linalg.norm(avg, axis=1, keepdims=True)
    normals[cut_pairs[:, 0]] = avg
    normals[cut_pairs[:, 1]] = avg

    # side of the lip line for every epidermal node: +1 upper, -1 lower
    side = np.where(vertices[:, 1] >= np.array([line_y(x) for x in vertices[:, 0]]), 1, -1)
    side[cut_pairs[:, 0]] = 1
    side[cut_pairs[:, 1]] = -1

    gen_lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    half_w = 0.5 * np.linalg.norm(cl - cr)
    anatomical = opt.tissue == "anatomical"
    if anatomical:
        # generic frontal coordinates (mm) of every node, for the fields of :mod:`tissue`
        gxy = _tps_warp(lm, gen_lm)(vertices)[:, :2] * 1e3
        depth = tissue.tissue_depth_mm(gxy[:, 0], gxy[:, 1]) * 1e-3
        offset = smoothed_normals(vertices, faces, opt.normal_smoothing)
        offset[cut_pairs[:, 1]] = offset[cut_pairs[:, 0]]
        fascia = vertices - (opt.fascia_fraction * depth)[:, None] * offset
        skull = vertices - depth[:, None] * offset
        skull_normals = np.concatenate([offset, offset, offset])
        lip_region = tissue.lip_ellipse(gxy[:, 0], gxy[:, 1])
        slides = tissue.sliding_region(gxy[:, 0], gxy[:, 1])
        free = slides
    else:
        fascia = vertices - opt.depth_fascia * normals
        skull = vertices - (opt.depth_fascia + opt.depth_skull) * normals
        skull_normals = np.concatenate([normals, normals, normals])
        # free fascia: lips and cheeks
        up = max(lm["subnasale"][1] - stomion[1], 5e-3)
        dx = (vertices[:, 0] - stomion[0]) / (opt.lip_region_half_width * half_w)
        dy = vertices[:, 1] - stomion[1]
        dy = np.where(dy > 0, dy / (opt.lip_region_up * up), -dy / (opt.lip_region_down * up))
        lip_region = dx**2 + dy**2 < 1.0
        free = lip_region.copy()
        for s in ("left", "right"):
            centre = 0.5 * (lm[f"cheek_{s}"] + lm[f"mouth_corner_{s}"])
            free |= np.linalg.norm(vertices - centre, axis=1) < opt.cheek_radius
        slides = np.zeros(n, bool)
    rest = np.concatenate([vertices, fascia, skull])
    tied = np.nonzero(~free)[0]
    tied_fascia = tied + n

    edges = _edges(faces)
    if anatomical:
        spring_i, spring_j, spring_kind, prism_nodes = _anatomical_topology(edges, faces, n,
                                                                            slides)
        _check_prisms(rest, prism_nodes, source)
    else:
        spring_i, spring_j, spring_kind, prism_nodes = _uniform_topology(edges, faces, n, free,
                                                                         tied)

    # ---- jaw -----------------------------------------------------------------------------
    ga = {s: lm[f"jaw_angle_{s}"] for s in ("left", "right")}

    def jaw_line(x: float) -> float:
        if cr[0] <= x <= cl[0]:
            return line_y(x)
        c, g = (cl, ga["left"]) if x > cl[0] else (cr, ga["right"])
        t = np.clip((x - c[0]) / (g[0] - c[0]) if g[0] != c[0] else 1.0, 0.0, 1.0)
        return float(c[1] + t * (g[1] - c[1]))

    if anatomical:
        weight = tissue.jaw_weight(gxy[:, 0], gxy[:, 1], side < 0, band_mm=opt.jaw_band * 1e3,
                                   taper_mm=opt.jaw_taper * 1e3)
        on_jaw = np.nonzero((weight > 1e-6) & ~slides)[0]  # sliding nodes are not kinematic
        jaw_nodes = on_jaw + 2 * n
        jaw_weights = weight[on_jaw]
    else:
        below_line = vertices[:, 1] < np.array([jaw_line(x) for x in vertices[:, 0]])
        below_line[cut_pairs[:, 1]] = True
        below_line[cut_pairs[:, 0]] = False
        jaw_nodes = np.nonzero(below_line)[0] + 2 * n
        jaw_weights = np.ones(len(jaw_nodes))
        weight = below_line.astype(float)
    ga_mean = 0.5 * (ga["left"] + ga["right"])
    hinge_y = 0.5 * (lm["nose_tip"][1] + lm["subnasale"][1])  # condyles: about the nasal base
    hinge_point = np.array([0.0, hinge_y, ga_mean[2] - opt.hinge_behind_jaw_angle])
    hinge_axis = np.array([1.0, 0.0, 0.0])

    # ---- lip contact pairs: the cut twins, in every moving layer --------------------------
    layers = [cut_pairs, cut_pairs + n] + ([cut_pairs + 2 * n] if anatomical else [])
    lip_pairs = np.concatenate(layers).astype(np.int64)
    lip_normals = np.tile(np.array([0.0, 1.0, 0.0]), (len(lip_pairs), 1))

    # ---- sites: landmarks, markers, muscles ----------------------------------------------
    tree = cKDTree(vertices)
    warp = _tps_warp(gen_lm, lm)

    def generic_point(xy):
        return generic.surface_point(np.array(xy[0]), np.array(xy[1])) * 1e-3

    def snap(p, want_side=None):
        """Nearest epidermal node to p, on the given side of the lip line near the mouth."""
        k = min(12, n)
        _, cand = tree.query(p, k=k)
        for c in np.atleast_1d(cand):
            if want_side is None or side[c] == want_side:
                return int(c)
        return int(np.atleast_1d(cand)[0])

    def side_of(p) -> int | None:
        if abs(p[0] - stomion[0]) > 1.1 * half_w:
            return None
        return 1 if p[1] >= line_y(p[0]) else -1

    landmark_nodes: dict[str, int] = {}
    for nm, p in lm.items():
        want = {"upper_lip_center": 1, "lower_lip_center": -1}.get(nm, side_of(p))
        if nm.startswith("mouth_corner"):
            landmark_nodes[nm] = corner_l if nm.endswith("left") else corner_r
        else:
            landmark_nodes[nm] = snap(p, want)

    markers: dict[str, int] = {}
    for nm, xy in {**anatomy.RIGHT_MARKERS, **anatomy.LEFT_MARKERS}.items():
        gp = generic_point(xy)
        p = warp(gp[None])[0]
        gen_side = None if abs(xy[0]) > 27 else (1 if xy[1] >= generic.Y_STOMION else -1)
        markers[nm] = snap(p, gen_side)

    area = vertex_areas(vertices, faces)
    fixed_skull = ~slides
    names, group, kind, origin, ptr, nodes, weights, rest_length = [], [], [], [], [0], [], [], []
    offsets = []
    sites = anatomy.LINEAR_MUSCLES + (anatomy.INCISIVE_MUSCLES if anatomical else ())
    for site in sites:
        for sgn, suffix in ((-1.0, "R"), (1.0, "L")):
            o_xy = (sgn * abs(site.origin[0]), site.origin[1])
            i_xy = (sgn * abs(site.insertion[0]), site.insertion[1])
            o_p = warp(generic_point(o_xy)[None])[0]
            i_p = warp(generic_point(i_xy)[None])[0]
            if anatomical:
                # the origin is on bone that does not slide: on the mandible (full jaw weight)
                # or on the fixed skull (none)
                ok = fixed_skull & ((weight > 0.999) if site.on_mandible else (weight < 1e-3))
                cand = np.nonzero(ok)[0]
                o_node = int(cand[np.argmin(np.linalg.norm(vertices[cand] - o_p, axis=1))]) + 2 * n
                if site.origin_in_fascia:  # a fixed point at the depth of the muscle plane
                    offset = rest[o_node - n] - rest[o_node]
            else:
                o_node = snap(o_p, side_of(o_p)) + 2 * n
                if site.on_mandible and o_node not in set(jaw_nodes.tolist()):
                    jd = np.linalg.norm(rest[jaw_nodes] - rest[o_node], axis=1)
                    o_node = int(jaw_nodes[np.argmin(jd)])
            if not (anatomical and site.origin_in_fascia):
                offset = np.zeros(3)
            want = side_of(i_p)
            near = tree.query_ball_point(i_p, opt.insertion_radius)
            near = [c for c in near if want is None or side[c] == want]
            near = sorted(near, key=lambda c: np.linalg.norm(vertices[c] - i_p))
            if anatomical:
                near = near or [snap(i_p, want)]
                dist = np.linalg.norm(vertices[near] - i_p, axis=1) / opt.insertion_radius
                w = area[near] * np.clip(1.0 - dist**2, 0.05, None) ** 2
                w = w / w.sum()
            else:
                near = near[: opt.max_insertion_nodes] or [snap(i_p, want)]
                w = np.full(len(near), 1.0 / len(near))
            ins = np.asarray(near) + n
            names.append(f"{site.name or site.group}_{suffix}")
            group.append(MUSCLE_GROUPS.index(site.group))
            kind.append(LINEAR)
            origin.append(o_node)
            nodes.extend(ins.tolist())
            weights.extend(w.tolist())
            ptr.append(len(nodes))
            centre = (w[:, None] * rest[ins]).sum(axis=0) if anatomical else rest[ins].mean(axis=0)
            rest_length.append(np.linalg.norm(centre - rest[o_node] - offset))
            offsets.append(offset)
    # sphincters: half paths from each corner to the midline of the lip line
    mid = int(np.argmin(np.abs(vertices[path, 0] - stomion[0])))
    twin_of = dict(zip(cut_pairs[:, 0].tolist(), cut_pairs[:, 1].tolist(), strict=True))
    bead = [0] * len(nodes)
    for grp, lower_lip in (("OOS", False), ("OOI", True)):
        for suffix, seg in (("R", path[: mid + 1]), ("L", path[mid:][::-1])):
            seq = [twin_of.get(int(v), int(v)) if lower_lip else int(v) for v in seg]
            if anatomical:
                seq_nodes, w, b = _sphincter_beads(vertices, area, side, seq,
                                                   -1 if lower_lip else 1, opt, n, slides)
                chain_rest = np.array([(w[b == k, None] * rest[seq_nodes[b == k]]).sum(axis=0)
                                       for k in range(b.max() + 1)])
            else:
                seq_nodes = np.asarray(seq) + n
                w = np.ones(len(seq))
                b = np.arange(len(seq))
                chain_rest = rest[seq_nodes]
            names.append(f"{grp}_{suffix}")
            group.append(MUSCLE_GROUPS.index(grp))
            kind.append(SPHINCTER)
            origin.append(-1)
            offsets.append(np.zeros(3))
            nodes.extend(seq_nodes.tolist())
            weights.extend(np.asarray(w, float).tolist())
            bead.extend(np.asarray(b).tolist())
            ptr.append(len(nodes))
            rest_length.append(np.sum(np.linalg.norm(np.diff(chain_rest, axis=0), axis=1)))
    muscles = Muscles(
        names=tuple(names), group=np.asarray(group, np.int64), kind=np.asarray(kind, np.int64),
        origin=np.asarray(origin, np.int64), ptr=np.asarray(ptr, np.int64),
        nodes=np.asarray(nodes, np.int64), weights=np.asarray(weights, float),
        rest_length=np.asarray(rest_length, float), bead=np.asarray(bead, np.int64),
        origin_offset=np.asarray(offsets, float).reshape(-1, 3),
    )
    return FaceModel(
        rest_positions=rest, faces=faces, n_surface=n, spring_i=spring_i, spring_j=spring_j,
        spring_kind=spring_kind, prism_nodes=prism_nodes, tied_fascia=tied_fascia,
        skull_normals=skull_normals, jaw_nodes=jaw_nodes, hinge_point=hinge_point,
        hinge_axis=hinge_axis, lip_pairs=lip_pairs, lip_normals=lip_normals, muscles=muscles,
        landmarks=landmark_nodes, markers=markers, name=name, tissue=opt.tissue,
        jaw_weights=jaw_weights, sliding=np.nonzero(slides)[0] + 2 * n,
        sliding_weights=weight[slides] if anatomical else None,
        sliding_tether=(tissue.tether_weight(gxy[slides, 0], gxy[slides, 1]) if anatomical
                        else None),
        lip_region=lip_region, surface=surface, appearance=appearance,
    )


def _sphincter_beads(vertices, area, side, seq, lip_side, opt, n, moving_skull):
    """Beads of one half of an anatomical orbicularis oris, from the mouth corner to the midline.

    ``seq`` is the lip-line path (epidermal nodes, corner first). Beads lie every
    ``sphincter_spacing`` along it, each centred ``sphincter_offset`` into the lip (the middle
    of the muscle's band) and gather the nodes of that lip within ``sphincter_radius`` through
    the lip's thickness: skin, muscle plane and the deep (teeth-side) surface, weighted by
    ``sphincter_depth_weights`` (the peripheral part of the muscle lies near the teeth), by skin
    area and by a smooth bump of the distance. The first bead is the modiolus, ``modiolus``
    lateral to the corner, and takes nodes of both lips. Returns the nodes (global indices),
    their weights and the bead of each.
    """
    pts = vertices[np.asarray(seq)]
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    count = max(3, int(round(arc[-1] / opt.sphincter_spacing)) + 1)
    tree = cKDTree(vertices)
    lateral = np.sign(pts[0, 0] - pts[-1, 0])
    out_nodes, out_w, out_b = [], [], []
    for k, s_k in enumerate(np.linspace(0.0, arc[-1], count)):
        centre = np.array([np.interp(s_k, arc, pts[:, a]) for a in range(3)])
        if k > 0:
            centre = centre + np.array([0.0, lip_side * opt.sphincter_offset, 0.0])
        else:
            centre = centre + np.array([lateral * opt.modiolus, 0.0, 0.0])
        near = np.asarray(tree.query_ball_point(centre, opt.sphincter_radius), np.int64)
        if k > 0:
            near = near[side[near] == lip_side]
        if len(near) == 0:
            near = np.array([int(tree.query(centre)[1])])
        dist = np.linalg.norm(vertices[near] - centre, axis=1) / opt.sphincter_radius
        w = area[near] * np.clip(1.0 - dist**2, 0.05, None) ** 2
        shares = opt.sphincter_depth_weights if k > 0 else opt.modiolus_depth_weights
        for layer, share in enumerate(shares):
            nodes = near + layer * n
            ok = np.ones(len(near), bool) if layer < 2 else moving_skull[near]
            if share <= 0 or not ok.any():
                continue
            out_nodes.extend(nodes[ok].tolist())
            out_w.extend((share * w[ok]).tolist())
            out_b.extend([k] * int(ok.sum()))
    out_w = np.asarray(out_w)
    out_b = np.asarray(out_b, np.int64)
    for k in range(count):
        out_w[out_b == k] /= out_w[out_b == k].sum()
    return np.asarray(out_nodes, np.int64), out_w, out_b


def _uniform_topology(edges, faces, n, free, tied):
    """The seeds' springs and prisms (Lucero & Munhall 1999, I.A)."""
    idx = np.arange(n)
    si = [edges[:, 0], edges[:, 0] + n, idx, tied + n]
    sj = [edges[:, 1], edges[:, 1] + n, idx + n, tied + 2 * n]
    sk = [np.full(len(edges), 0), np.full(len(edges), 2), np.full(n, 1), np.full(len(tied), 3)]
    spring_i = np.concatenate(si).astype(np.int64)
    spring_j = np.concatenate(sj).astype(np.int64)
    spring_kind = np.concatenate(sk).astype(np.int8)
    # prisms: dermal-fatty everywhere, muscle layer where the fascia is tied
    upper = np.concatenate([faces, faces + n], axis=1)
    tied_tri = ~free[faces].any(axis=1)
    lower = np.concatenate([faces[tied_tri] + n, faces[tied_tri] + 2 * n], axis=1)
    prism_nodes = np.concatenate([upper, lower]).astype(np.int64)
    return spring_i, spring_j, spring_kind, prism_nodes


def _anatomical_topology(edges, faces, n, slides):
    """Two prism layers everywhere and a spring on every prism edge, diagonals included.

    Edges between two kinematic skull nodes carry no force and are left out.
    """
    idx = np.arange(n)
    a, b = edges[:, 0], edges[:, 1]
    skull_edge = slides[a] & slides[b]  # the fold of the vestibule gives the mucosa slack
    deep_vertical = np.ones(n, bool)
    pairs = [
        (a, b, 0), (a + n, b + n, 2), (a[skull_edge] + 2 * n, b[skull_edge] + 2 * n, 4),
        (idx, idx + n, 1), (idx[deep_vertical] + n, idx[deep_vertical] + 2 * n, 3),
        (a, b + n, 5), (b, a + n, 5),
        (a + n, b + 2 * n, 6), (b + n, a + 2 * n, 6),
    ]
    spring_i = np.concatenate([p[0] for p in pairs]).astype(np.int64)
    spring_j = np.concatenate([p[1] for p in pairs]).astype(np.int64)
    spring_kind = np.concatenate([np.full(len(p[0]), p[2]) for p in pairs]).astype(np.int8)
    upper = np.concatenate([faces, faces + n], axis=1)
    lower = np.concatenate([faces + n, faces + 2 * n], axis=1)
    prism_nodes = np.concatenate([upper, lower]).astype(np.int64)
    return spring_i, spring_j, spring_kind, prism_nodes


def _check_prisms(rest, prism_nodes, source):
    """Every prism of the thick tissue must have a positive volume (no folded layer)."""
    from ..physics.volume import rest_geometry

    vols, _ = rest_geometry(rest, prism_nodes)
    if np.any(vols <= 0):
        bad = int(np.argmin(vols))
        p = rest[prism_nodes[bad, 0]] * 1e3
        raise InputError("the tissue layers fold (a prism has no volume) near "
                         f"({p[0]:.0f}, {p[1]:.0f}, {p[2]:.0f}) mm: the surface is too concave "
                         "there for the tissue depth", source=source, field="tissue")


#: the built-in face at three mesh resolutions: (rows, columns) of :func:`generic.make_surface`
DEFAULT_RESOLUTIONS = {"default-coarse": (38, 31), "default": (48, 41),
                       "default-fine": (62, 53)}
_DEFAULT_CACHE: dict[tuple[str, str], FaceModel] = {}
_REBUILT: OrderedDict = OrderedDict()


def default_surface(resolution: str = "default"):
    """The generic face's surface and landmarks, in metres.

    ``resolution`` is one of :data:`DEFAULT_RESOLUTIONS`: ``default-coarse`` (about 2.6 mm
    between nodes at the lips), ``default`` (about 2 mm) or ``default-fine`` (about 1.5 mm).
    """
    if resolution not in DEFAULT_RESOLUTIONS:
        raise InputError(f"unknown built-in face {resolution!r} (expected "
                         f"{', '.join(DEFAULT_RESOLUTIONS)})", field="face")
    rows, cols = DEFAULT_RESOLUTIONS[resolution]
    surf = generic.make_surface(rows, cols)
    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    return surf.vertices * 1e-3, surf.faces, lm


def default_face(resolution: str = "default", *, tissue: str | None = None) -> FaceModel:
    """The built-in generic adult face, built by :func:`build_face` (cached).

    ``resolution``: ``default-coarse``, ``default`` or ``default-fine``; ``tissue``: the tissue
    geometry, ``anatomical`` (the default preset's) or ``uniform`` (the seeds').
    """
    from ..params import DEFAULT_PRESET, preset

    tissue = tissue or preset(DEFAULT_PRESET).tissue
    key = (resolution, tissue)
    if key not in _DEFAULT_CACHE:
        v, f, lm = default_surface(resolution)
        name = "generic-adult" if resolution == "default" else f"generic-adult-{resolution[8:]}"
        _DEFAULT_CACHE[key] = build_face(v, f, lm, name=name, options=tissue_options(tissue))
    return _DEFAULT_CACHE[key]


def for_tissue(model: FaceModel, tissue: str) -> FaceModel:
    """``model`` with the tissue geometry ``tissue``, rebuilt from its surface if it differs.

    A preset names its tissue geometry (:attr:`facemech.params.Parameters.tissue`); a face
    built for another one is rebuilt from the surface and landmarks it remembers (cached).
    """
    if model.tissue == tissue:
        return model
    for (name, _), face in _DEFAULT_CACHE.items():
        if face is model:
            return default_face(name, tissue=tissue)
    key = (id(model), tissue)
    if key in _REBUILT and _REBUILT[key][0] is model:
        return _REBUILT[key][1]
    if model.surface is None:
        raise InputError(f"face {model.name!r} was built for the {model.tissue} tissue and does "
                         f"not keep its surface: rebuild it (facemech face build) to use the "
                         f"{tissue} tissue", field="face")
    s = model.surface
    rebuilt = build_face(s["vertices"], s["faces"], s["landmarks"], name=model.name,
                         options=tissue_options(tissue), appearance=surface_appearance(model))
    _REBUILT[key] = (model, rebuilt)
    while len(_REBUILT) > 8:
        _REBUILT.popitem(last=False)
    return rebuilt


def load_face(spec: str | Path | None, *, tissue: str | None = None) -> FaceModel:
    """A face from a built-in name or a ``.npz`` written by ``face build``.

    ``spec``: ``None``, ``default``, ``default-coarse``, ``default-fine`` or a path. With
    ``tissue``, the face comes with that tissue geometry (:func:`for_tissue`).
    """
    name = "default" if spec is None else str(spec)
    if name in DEFAULT_RESOLUTIONS:
        return default_face(name, tissue=tissue)
    model = FaceModel.load(spec)
    return model if tissue is None else for_tissue(model, tissue)


def with_options(model: FaceModel, **changes) -> FaceModel:
    """Rebuild ``model`` from its surface with some build options changed."""
    if model.surface is None:
        raise InputError("the face does not keep its surface", field="face")
    s = model.surface
    opt = replace(tissue_options(model.tissue), **changes)
    return build_face(s["vertices"], s["faces"], s["landmarks"], name=model.name, options=opt,
                      appearance=surface_appearance(model))


def surface_appearance(model: FaceModel) -> Appearance | None:
    """The appearance of the surface ``model`` remembers (before the mouth cut).

    The cut appends the lower-lip twins after the surface's vertices and keeps the triangles'
    rows and corners, so the surface's appearance is the model's without the twins' colours.
    """
    a = model.appearance
    if a is None or a.vertex_colours is None or model.surface is None:
        return a
    return replace(a, vertex_colours=a.vertex_colours[: len(model.surface["vertices"])])
