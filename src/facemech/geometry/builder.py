"""Build the three-layer face model from a surface and landmarks (Lucero & Munhall 1999, I.A).

The epidermal surface is copied inwards along its normals to make the fascia (1.5 mm) and skull
(4 mm) layers. Springs join the epidermis within itself, epidermis to fascia (dermal-fatty), the
fascia within itself, and fascia to skull (muscle layer) where the fascia is tied. Each surface
triangle with its copies below makes prism elements for the volume term. The mouth slit is cut
along the lip line so that upper and lower lips are separate sheets that touch at rest.

Choices the paper leaves open (SPEC section 6), each a field of :class:`BuildOptions`:
- free fascia: an ellipse around the mouth (lips from subnasale to the labiomental fold) and one
  disc per cheek between the cheek landmark and the mouth corner;
- the jaw: skull nodes below the lip line and below the line from each mouth corner to the jaw
  angle; the hinge axis is parallel to x, at the height of the nasal base (halfway between nose
  tip and subnasale) and 25 mm behind the skin jaw-angle landmarks (the condyles lie about
  10-12 mm in front of the tragus, near its height);
- linear muscles pull all fascia nodes within ``insertion_radius`` of the insertion site, the
  force shared equally;
- lip contact: a penalty between each node of the upper lip margin and its twin on the lower one.
"""

from __future__ import annotations

import heapq
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import cKDTree

from ..errors import InputError
from ..params import MUSCLE_GROUPS
from . import anatomy, generic
from .surface_io import REQUIRED_LANDMARKS, check_manifold

EPIDERMIS, FASCIA, SKULL = 0, 1, 2
LAYER_NAMES = ("epidermis", "fascia", "skull")
SPRING_KINDS = ("epidermis", "dermal_fatty", "fascia", "muscle_layer")
LINEAR, SPHINCTER = 0, 1


@dataclass(frozen=True)
class BuildOptions:
    """Geometric choices of the model builder (lengths in metres)."""

    depth_fascia: float = 1.5e-3
    depth_skull: float = 2.5e-3
    lip_region_half_width: float = 1.25  # x semi-axis of the free lip ellipse, in mouth half-widths
    lip_region_up: float = 1.0  # upward semi-axis, in subnasale-stomion heights
    lip_region_down: float = 0.9  # downward semi-axis, in the same unit
    cheek_radius: float = 14e-3  # m, radius of each free cheek disc
    insertion_radius: float = 3.5e-3  # m
    max_insertion_nodes: int = 6
    hinge_behind_jaw_angle: float = 25e-3  # m, condyle behind the (skin) jaw angle landmark


@dataclass(frozen=True)
class Muscles:
    """Muscle instances of a face (left and right are separate instances).

    Node lists are in CSR form: the insertion (or path) nodes of muscle ``m`` are
    ``nodes[ptr[m]:ptr[m + 1]]`` with weights ``weights[ptr[m]:ptr[m + 1]]``.
    """

    names: tuple[str, ...]
    group: np.ndarray  # (m,) index into MUSCLE_GROUPS
    kind: np.ndarray  # (m,) LINEAR or SPHINCTER
    origin: np.ndarray  # (m,) skull node (-1 for sphincters)
    ptr: np.ndarray  # (m + 1,)
    nodes: np.ndarray  # insertion fascia nodes, or the sphincter path in order
    weights: np.ndarray  # share of the force per insertion node (1 on sphincter paths)
    rest_length: np.ndarray  # (m,) metres

    def __len__(self) -> int:
        return len(self.names)


@dataclass(frozen=True)
class FaceModel:
    """A three-layer face: geometry and topology, no material constants.

    Node ``i`` of the epidermis has copies ``i + n_surface`` (fascia) and ``i + 2 n_surface``
    (skull). All positions in metres, +x the subject's left, +y up, +z forward.
    """

    rest_positions: np.ndarray  # (3 n_surface, 3)
    faces: np.ndarray  # (f, 3) epidermal triangles
    n_surface: int
    spring_i: np.ndarray
    spring_j: np.ndarray
    spring_kind: np.ndarray  # index into SPRING_KINDS
    prism_nodes: np.ndarray  # (p, 6): top triangle then the one below
    tied_fascia: np.ndarray  # fascia nodes tied to the skull
    skull_normals: np.ndarray  # (3 n_surface, 3) outward normals of the skull layer at rest
    jaw_nodes: np.ndarray  # skull nodes that rotate with the mandible
    hinge_point: np.ndarray  # (3,) a point on the hinge axis
    hinge_axis: np.ndarray  # (3,) unit axis (+x): positive angles open the mouth
    lip_pairs: np.ndarray  # (q, 2) upper-lip node, lower-lip twin (epidermis and fascia)
    lip_normals: np.ndarray  # (q, 3) rest direction from the lower to the upper lip
    muscles: Muscles
    landmarks: dict = field(default_factory=dict)  # name -> epidermal node
    markers: dict = field(default_factory=dict)  # virtual marker name -> epidermal node
    name: str = "face"

    # ---- derived views -------------------------------------------------------------------
    @property
    def n_nodes(self) -> int:
        return self.rest_positions.shape[0]

    @property
    def layer(self) -> np.ndarray:
        return np.repeat(np.arange(3, dtype=np.int8), self.n_surface)

    @property
    def free_fascia(self) -> np.ndarray:
        """Fascia nodes not tied to the skull (lips and cheeks)."""
        fascia = np.arange(self.n_surface, 2 * self.n_surface)
        return np.setdiff1d(fascia, self.tied_fascia)

    def landmark_positions(self) -> dict[str, np.ndarray]:
        return {k: self.rest_positions[v] for k, v in self.landmarks.items()}

    def summary(self) -> dict:
        """Counts a user checks a model by (``facemech face info``)."""
        kinds = {k: int(np.sum(self.spring_kind == i)) for i, k in enumerate(SPRING_KINDS)}
        return {
            "name": self.name,
            "nodes_per_layer": {k: self.n_surface for k in LAYER_NAMES},
            "nodes": self.n_nodes,
            "triangles": int(len(self.faces)),
            "springs": int(len(self.spring_i)),
            "springs_by_kind": kinds,
            "prisms": int(len(self.prism_nodes)),
            "muscles": int(len(self.muscles)),
            "muscle_groups": sorted({MUSCLE_GROUPS[g] for g in self.muscles.group}),
            "free_fascia_nodes": int(len(self.free_fascia)),
            "tied_fascia_nodes": int(len(self.tied_fascia)),
            "jaw_nodes": int(len(self.jaw_nodes)),
            "lip_contact_pairs": int(len(self.lip_pairs)),
            "landmarks": sorted(self.landmarks),
            "markers": list(self.markers),
            "extent_mm": (np.ptp(self.rest_positions[: self.n_surface], axis=0) * 1e3)
            .round(1)
            .tolist(),
        }

    # ---- persistence ---------------------------------------------------------------------
    def save(self, path: str | Path) -> None:
        """Write the model to a ``.npz`` file, atomically."""
        from ..io.atomic import atomic_path

        arrays = {
            k: getattr(self, k)
            for k in ("rest_positions", "faces", "spring_i", "spring_j", "spring_kind",
                      "prism_nodes", "tied_fascia", "skull_normals", "jaw_nodes", "hinge_point",
                      "hinge_axis", "lip_pairs", "lip_normals")
        }
        m = self.muscles
        arrays.update({f"muscle_{k}": getattr(m, k)
                       for k in ("group", "kind", "origin", "ptr", "nodes", "weights",
                                 "rest_length")})
        meta = {"format": "facemech-face", "version": 1, "name": self.name,
                "n_surface": self.n_surface, "muscle_names": list(m.names),
                "landmarks": {k: int(v) for k, v in self.landmarks.items()},
                "markers": {k: int(v) for k, v in self.markers.items()}}
        arrays["meta"] = np.array(json.dumps(meta))
        with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    @classmethod
    def load(cls, path: str | Path) -> FaceModel:
        """Read a model written by :meth:`save`."""
        path = Path(path)
        if not path.is_file():
            raise InputError("file not found", source=str(path))
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
            meta = json.loads(str(data.pop("meta")))
        except Exception as exc:
            raise InputError(f"not a facemech face file ({type(exc).__name__})",
                             source=str(path)) from None
        if meta.get("format") != "facemech-face":
            raise InputError("not a facemech face file", source=str(path), field="format")
        muscles = Muscles(names=tuple(meta["muscle_names"]),
                          **{k: data.pop(f"muscle_{k}")
                             for k in ("group", "kind", "origin", "ptr", "nodes", "weights",
                                       "rest_length")})
        return cls(muscles=muscles, n_surface=int(meta["n_surface"]), name=meta["name"],
                   landmarks=meta["landmarks"], markers=meta["markers"], **data)


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

    Returns the new vertices and faces, and the (upper, lower) node pairs of the cut.
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


def build_face(
    vertices: np.ndarray,
    faces: np.ndarray,
    landmarks: dict[str, np.ndarray],
    *,
    options: BuildOptions | None = None,
    name: str = "face",
    source: str | None = None,
) -> FaceModel:
    """Build the layered face model from an epidermal surface (metres) and its landmarks.

    Parameters
    ----------
    vertices : (n, 3) array, metres; +x subject's left, +y up, +z forward
    faces : (f, 3) int array; a closed mouth (the lips fused along the lip line)
    landmarks : dict name -> (3,) metres; at least :data:`REQUIRED_LANDMARKS`
    options : geometric choices (defaults: :class:`BuildOptions`)
    source : name of the input, for error messages
    """
    opt = options or BuildOptions()
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
    normals = vertex_normals(vertices, faces)
    if normals[:, 2].mean() < 0:  # faces must be wound so normals point out of the face
        faces = faces[:, ::-1].copy()
        normals = -normals

    lm = {k: np.asarray(v, float) for k, v in landmarks.items()}
    tree = tree0 = cKDTree(vertices)
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

    fascia = vertices - opt.depth_fascia * normals
    skull = vertices - (opt.depth_fascia + opt.depth_skull) * normals
    rest = np.concatenate([vertices, fascia, skull])
    skull_normals = np.concatenate([normals, normals, normals])

    # ---- free fascia: lips and cheeks ----------------------------------------------------
    half_w = 0.5 * np.linalg.norm(cl - cr)
    up = max(lm["subnasale"][1] - stomion[1], 5e-3)
    dx = (vertices[:, 0] - stomion[0]) / (opt.lip_region_half_width * half_w)
    dy = vertices[:, 1] - stomion[1]
    dy = np.where(dy > 0, dy / (opt.lip_region_up * up), -dy / (opt.lip_region_down * up))
    free = dx**2 + dy**2 < 1.0
    for s in ("left", "right"):
        centre = 0.5 * (lm[f"cheek_{s}"] + lm[f"mouth_corner_{s}"])
        free |= np.linalg.norm(vertices - centre, axis=1) < opt.cheek_radius
    tied = np.nonzero(~free)[0]
    tied_fascia = tied + n

    # ---- springs -------------------------------------------------------------------------
    edges = _edges(faces)
    idx = np.arange(n)
    si = [edges[:, 0], edges[:, 0] + n, idx, tied + n]
    sj = [edges[:, 1], edges[:, 1] + n, idx + n, tied + 2 * n]
    sk = [np.full(len(edges), 0), np.full(len(edges), 2), np.full(n, 1), np.full(len(tied), 3)]
    spring_i = np.concatenate(si).astype(np.int64)
    spring_j = np.concatenate(sj).astype(np.int64)
    spring_kind = np.concatenate(sk).astype(np.int8)

    # ---- prisms: dermal-fatty everywhere, muscle layer where the fascia is tied ----------
    upper = np.concatenate([faces, faces + n], axis=1)
    tied_tri = ~free[faces].any(axis=1)
    lower = np.concatenate([faces[tied_tri] + n, faces[tied_tri] + 2 * n], axis=1)
    prism_nodes = np.concatenate([upper, lower]).astype(np.int64)

    # ---- jaw -----------------------------------------------------------------------------
    ga = {s: lm[f"jaw_angle_{s}"] for s in ("left", "right")}

    def jaw_line(x: float) -> float:
        if cr[0] <= x <= cl[0]:
            return line_y(x)
        c, g = (cl, ga["left"]) if x > cl[0] else (cr, ga["right"])
        t = np.clip((x - c[0]) / (g[0] - c[0]) if g[0] != c[0] else 1.0, 0.0, 1.0)
        return float(c[1] + t * (g[1] - c[1]))

    below_line = vertices[:, 1] < np.array([jaw_line(x) for x in vertices[:, 0]])
    below_line[cut_pairs[:, 1]] = True
    below_line[cut_pairs[:, 0]] = False
    jaw_nodes = np.nonzero(below_line)[0] + 2 * n
    ga_mean = 0.5 * (ga["left"] + ga["right"])
    hinge_y = 0.5 * (lm["nose_tip"][1] + lm["subnasale"][1])  # condyles: about the nasal base
    hinge_point = np.array([0.0, hinge_y, ga_mean[2] - opt.hinge_behind_jaw_angle])
    hinge_axis = np.array([1.0, 0.0, 0.0])

    # ---- lip contact pairs: the cut twins, in the epidermis and the fascia ----------------
    lip_pairs = np.concatenate([cut_pairs, cut_pairs + n]).astype(np.int64)
    lip_normals = np.tile(np.array([0.0, 1.0, 0.0]), (len(lip_pairs), 1))

    # ---- sites: landmarks, markers, muscles ----------------------------------------------
    tree = cKDTree(vertices)
    gen_lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
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

    names, group, kind, origin, ptr, nodes, weights, rest_length = [], [], [], [], [0], [], [], []
    for site in anatomy.LINEAR_MUSCLES:
        for sgn, suffix in ((-1.0, "R"), (1.0, "L")):
            o_xy = (sgn * abs(site.origin[0]), site.origin[1])
            i_xy = (sgn * abs(site.insertion[0]), site.insertion[1])
            o_p = warp(generic_point(o_xy)[None])[0]
            i_p = warp(generic_point(i_xy)[None])[0]
            o_node = snap(o_p, side_of(o_p)) + 2 * n
            if site.on_mandible and o_node not in set(jaw_nodes.tolist()):
                jd = np.linalg.norm(rest[jaw_nodes] - rest[o_node], axis=1)
                o_node = int(jaw_nodes[np.argmin(jd)])
            want = side_of(i_p)
            near = tree.query_ball_point(i_p, opt.insertion_radius)
            near = [c for c in near if want is None or side[c] == want]
            near = sorted(near, key=lambda c: np.linalg.norm(vertices[c] - i_p))
            near = near[: opt.max_insertion_nodes] or [snap(i_p, want)]
            ins = np.asarray(near) + n
            names.append(f"{site.group}_{suffix}")
            group.append(MUSCLE_GROUPS.index(site.group))
            kind.append(LINEAR)
            origin.append(o_node)
            nodes.extend(ins.tolist())
            weights.extend([1.0 / len(ins)] * len(ins))
            ptr.append(len(nodes))
            rest_length.append(np.linalg.norm(rest[ins].mean(axis=0) - rest[o_node]))
    # sphincters: half paths from each corner to the midline node of the lip line
    mid = int(np.argmin(np.abs(vertices[path, 0] - stomion[0])))
    twin_of = dict(zip(cut_pairs[:, 0].tolist(), cut_pairs[:, 1].tolist(), strict=True))
    for grp, lower_lip in (("OOS", False), ("OOI", True)):
        for suffix, seg in (("R", path[: mid + 1]), ("L", path[mid:][::-1])):
            seq = [twin_of.get(int(v), int(v)) if lower_lip else int(v) for v in seg]
            seq = np.asarray(seq) + n
            names.append(f"{grp}_{suffix}")
            group.append(MUSCLE_GROUPS.index(grp))
            kind.append(SPHINCTER)
            origin.append(-1)
            nodes.extend(seq.tolist())
            weights.extend([1.0] * len(seq))
            ptr.append(len(nodes))
            rest_length.append(np.sum(np.linalg.norm(np.diff(rest[seq], axis=0), axis=1)))
    muscles = Muscles(
        names=tuple(names), group=np.asarray(group, np.int64), kind=np.asarray(kind, np.int64),
        origin=np.asarray(origin, np.int64), ptr=np.asarray(ptr, np.int64),
        nodes=np.asarray(nodes, np.int64), weights=np.asarray(weights, float),
        rest_length=np.asarray(rest_length, float),
    )
    return FaceModel(
        rest_positions=rest, faces=faces, n_surface=n, spring_i=spring_i, spring_j=spring_j,
        spring_kind=spring_kind, prism_nodes=prism_nodes, tied_fascia=tied_fascia,
        skull_normals=skull_normals, jaw_nodes=jaw_nodes, hinge_point=hinge_point,
        hinge_axis=hinge_axis, lip_pairs=lip_pairs, lip_normals=lip_normals, muscles=muscles,
        landmarks=landmark_nodes, markers=markers, name=name,
    )


def default_surface() -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The generic face's surface and landmarks, in metres."""
    surf = generic.make_surface()
    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    return surf.vertices * 1e-3, surf.faces, lm


_DEFAULT: FaceModel | None = None


def default_face() -> FaceModel:
    """The built-in generic adult face, built by :func:`build_face` (cached)."""
    global _DEFAULT
    if _DEFAULT is None:
        v, f, lm = default_surface()
        _DEFAULT = build_face(v, f, lm, name="generic-adult")
    return _DEFAULT


def load_face(spec: str | Path | None) -> FaceModel:
    """A face from ``None``/``"default"`` (built-in) or a ``.npz`` written by ``face build``."""
    if spec is None or str(spec) == "default":
        return default_face()
    return FaceModel.load(spec)
