"""The mouth: the lip line, the slit cut along it, the lips' sides and their contact pairs.

The input surface has a closed mouth (the lips fused along the lip line). The cut runs along
the mesh's edges from one mouth corner to the other, hugging the lip line (corner - stomion -
corner, piecewise linear), and duplicates its interior nodes: the triangles below the line take
the copies, so that the upper and lower lips are separate sheets that touch at rest. The twins
are the lip contact pairs: the upper lip margin and its twin on the lower one never pass each
other (Lucero & Munhall 1999 leave lip contact open; SPEC section 6).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from .appearance import Appearance
from .kinds import EPIDERMIS, FASCIA, SKULL, layer_nodes
from .mesh import boundary_nodes, surface_edges, vertex_normals
from .options import BuildOptions

UPPER_LIP, LOWER_LIP = 1, -1  # the side of the lip line a node lies on
#: metres: the lip-line path's edges cost (1 + (offset / this)^2) times their length
LIP_LINE_TOLERANCE = 0.5e-3


@dataclass(frozen=True)
class LipLine:
    """The lip line at rest: corner - stomion - corner, piecewise linear in the frontal plane.

    Parameters
    ----------
    corner_right, stomion, corner_left : (3,) arrays, metres
    """

    corner_right: np.ndarray
    stomion: np.ndarray
    corner_left: np.ndarray

    def y(self, x: float) -> float:
        """Height (m) of the lip line at ``x`` (m); level beyond the corners."""
        cr, st, cl = self.corner_right, self.stomion, self.corner_left
        if x <= st[0]:
            t = (x - cr[0]) / max(st[0] - cr[0], 1e-9)
            return float(cr[1] + np.clip(t, 0, 1) * (st[1] - cr[1]))
        t = (x - st[0]) / max(cl[0] - st[0], 1e-9)
        return float(st[1] + np.clip(t, 0, 1) * (cl[1] - st[1]))

    def heights(self, x: np.ndarray) -> np.ndarray:
        """:meth:`y` at every ``x``, (k,) metres."""
        return np.array([self.y(v) for v in x])

    @property
    def half_width(self) -> float:
        """Half the distance between the mouth corners, m."""
        return 0.5 * np.linalg.norm(self.corner_left - self.corner_right)

    def side_of(self, point: np.ndarray) -> int | None:
        """:data:`UPPER_LIP` or :data:`LOWER_LIP` near the mouth; None beyond 1.1 half widths."""
        if abs(point[0] - self.stomion[0]) > 1.1 * self.half_width:
            return None
        return UPPER_LIP if point[1] >= self.y(point[0]) else LOWER_LIP


@dataclass(frozen=True)
class MouthCut:
    """The surface with its mouth slit cut (metres).

    Parameters
    ----------
    vertices : (n, 3) array
        The surface's vertices, then one copy of every interior lip-line node.
    faces : (f, 3) int array
        Same rows and corner order as the input; those below the line use the copies.
    pairs : (q, 2) int array
        (upper, lower) node pairs of the cut, corner to corner.
    path : (q + 2,) int array
        The lip-line nodes from the right corner to the left one.
    corner_right, corner_left : int
        The mouth corners' nodes.
    line : LipLine
    side : (n,) int array
        :data:`UPPER_LIP` or :data:`LOWER_LIP`, every node; the pairs' by construction.
    normals : (n, 3) array
        Unit vertex normals; a pair's two nodes share the lip line's.
    """

    vertices: np.ndarray
    faces: np.ndarray
    pairs: np.ndarray
    path: np.ndarray
    corner_right: int
    corner_left: int
    line: LipLine
    side: np.ndarray
    normals: np.ndarray

    @property
    def n_surface(self) -> int:
        return len(self.vertices)

    def midline_index(self) -> int:
        """Position in :attr:`path` of the node nearest the stomion's x."""
        return int(np.argmin(np.abs(self.vertices[self.path, 0] - self.line.stomion[0])))

    def lower_twin(self) -> dict[int, int]:
        """Upper-lip node -> its lower-lip copy."""
        return dict(zip(self.pairs[:, 0].tolist(), self.pairs[:, 1].tolist(), strict=True))


def stomion(landmarks: dict[str, np.ndarray]) -> np.ndarray:
    """The ``stomion`` landmark, or midway between the lip centres, (3,) metres."""
    return landmarks.get("stomion",
                         0.5 * (landmarks["upper_lip_center"] + landmarks["lower_lip_center"]))


def distance_to_corner_line(points: np.ndarray, landmarks: dict[str, np.ndarray]) -> np.ndarray:
    """Distance (m) of ``points`` (..., 3) to the segment between the mouth-corner landmarks."""
    p, q = landmarks["mouth_corner_right"], landmarks["mouth_corner_left"]
    pts = np.asarray(points, float)
    s = np.clip((pts - p) @ (q - p) / max(float((q - p) @ (q - p)), 1e-12), 0.0, 1.0)
    return np.linalg.norm(pts - (p + s[..., None] * (q - p)), axis=-1)


def mouth_corners(vertices: np.ndarray, faces: np.ndarray, landmarks: dict[str, np.ndarray],
                  source: str | None = None) -> tuple[int, int]:
    """The (right, left) mouth-corner nodes: nearest the landmarks, off the mesh's holes."""
    tree = cKDTree(vertices)
    corner_r = int(tree.query(landmarks["mouth_corner_right"])[1])
    corner_l = int(tree.query(landmarks["mouth_corner_left"])[1])
    boundary = boundary_nodes(faces)
    if corner_r in boundary or corner_l in boundary:
        raise InputError("the mouth corners lie on a hole of the mesh: facemech needs a closed "
                         "mouth (lips fused along the lip line)", source=source, field="mouth")
    return corner_r, corner_l


def lip_line_path(vertices: np.ndarray, faces: np.ndarray, start: int, goal: int,
                  line: LipLine) -> list[int]:
    """Shortest edge path from ``start`` to ``goal`` that hugs the lip line (Dijkstra)."""
    edges = surface_edges(faces)
    n = len(vertices)
    adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for a, b in edges:
        length = np.linalg.norm(vertices[a] - vertices[b])
        off = 0.5 * (abs(vertices[a, 1] - line.y(vertices[a, 0]))
                     + abs(vertices[b, 1] - line.y(vertices[b, 0])))
        w = length * (1.0 + (off / LIP_LINE_TOLERANCE) ** 2)  # strongly prefer the lip line
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


def split_along(vertices: np.ndarray, faces: np.ndarray, path: list[int], line: LipLine):
    """Duplicate the interior nodes of ``path``; faces below the line take the copies.

    Returns the new vertices and faces, and the (upper, lower) node pairs of the cut. The
    copies are appended after the vertices, in the order of the pairs; every triangle keeps its
    row and the order of its corners (what carries a texture through the cut).
    """
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
    below = centroid[:, 1] < line.heights(centroid[:, 0])
    for r, is_below in zip(rows, below, strict=True):
        if is_below:
            faces[r] = [twin.get(int(v), int(v)) for v in faces[r]]
    pairs = np.array([(v, twin[v]) for v in interior], dtype=np.int64)
    return new_vertices, faces, pairs


def cut_normals(vertices: np.ndarray, faces: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Unit vertex normals (n, 3) of the cut surface; a pair's two copies share the lip line's."""
    normals = vertex_normals(vertices, faces)
    avg = 0.5 * (normals[pairs[:, 0]] + normals[pairs[:, 1]])
    avg /= np.linalg.norm(avg, axis=1, keepdims=True)
    normals[pairs[:, 0]] = avg
    normals[pairs[:, 1]] = avg
    return normals


def lip_sides(vertices: np.ndarray, line: LipLine, pairs: np.ndarray) -> np.ndarray:
    """The side of the lip line of every node, (n,) int: :data:`UPPER_LIP` or :data:`LOWER_LIP`."""
    side = np.where(vertices[:, 1] >= line.heights(vertices[:, 0]), UPPER_LIP, LOWER_LIP)
    side[pairs[:, 0]] = UPPER_LIP
    side[pairs[:, 1]] = LOWER_LIP
    return side


def cut_mouth(vertices: np.ndarray, faces: np.ndarray, landmarks: dict[str, np.ndarray],
              source: str | None = None) -> MouthCut:
    """Cut the mouth slit of a closed-mouth surface (metres; landmarks name -> (3,) metres)."""
    corner_r, corner_l = mouth_corners(vertices, faces, landmarks, source)
    line = LipLine(vertices[corner_r], stomion(landmarks), vertices[corner_l])
    path = lip_line_path(vertices, faces, corner_r, corner_l, line)
    cut_vertices, cut_faces, pairs = split_along(vertices, faces, path, line)
    return MouthCut(vertices=cut_vertices, faces=cut_faces, pairs=pairs, path=np.asarray(path),
                    corner_right=corner_r, corner_left=corner_l, line=line,
                    side=lip_sides(cut_vertices, line, pairs),
                    normals=cut_normals(cut_vertices, cut_faces, pairs))


def appearance_after_cut(appearance: Appearance | None, pairs: np.ndarray) -> Appearance | None:
    """The surface's look on the cut surface: the copies take their twins' vertex colours.

    The cut rewires triangles in place (same rows, same corners), so texture coordinates stay.
    """
    if appearance is None or appearance.vertex_colours is None:
        return appearance
    vc = appearance.vertex_colours
    return replace(appearance, vertex_colours=np.concatenate([vc, vc[pairs[:, 0]]]))


def lip_contact(pairs: np.ndarray, n_surface: int, *, deep: bool) -> tuple[np.ndarray,
                                                                          np.ndarray]:
    """The lip contact pairs: the cut's twins in every moving layer.

    Parameters
    ----------
    pairs : (q, 2) int array, the cut's (upper, lower) epidermal pairs
    n_surface : nodes per layer
    deep : whether the skull layer of the lips moves (the anatomical tissue's deep surface)

    Returns
    -------
    lip_pairs : (2 q or 3 q, 2) int64 array, (upper, lower) nodes
    lip_normals : (len(lip_pairs), 3) array, the rest direction from the lower to the upper lip
    """
    layers = (EPIDERMIS, FASCIA, SKULL) if deep else (EPIDERMIS, FASCIA)
    lip_pairs = np.concatenate([layer_nodes(pairs, layer, n_surface)
                                for layer in layers]).astype(np.int64)
    lip_normals = np.tile(np.array([0.0, 1.0, 0.0]), (len(lip_pairs), 1))
    return lip_pairs, lip_normals


def uniform_lip_region(vertices: np.ndarray, line: LipLine, landmarks: dict[str, np.ndarray],
                       opt: BuildOptions) -> np.ndarray:
    """The seeds' free lip region, (n,) bool: an ellipse about the stomion.

    Semi-axes: ``lip_region_half_width`` mouth half widths across, and ``lip_region_up`` /
    ``lip_region_down`` subnasale-stomion heights (at least 5 mm) up and down.
    """
    st = line.stomion
    up = max(landmarks["subnasale"][1] - st[1], 5e-3)
    dx = (vertices[:, 0] - st[0]) / (opt.lip_region_half_width * line.half_width)
    dy = vertices[:, 1] - st[1]
    dy = np.where(dy > 0, dy / (opt.lip_region_up * up), -dy / (opt.lip_region_down * up))
    return dx**2 + dy**2 < 1.0
