"""Scans as they come: loose fragments dropped, closed heads refused, bad triangles named.

A scanner's mesh holds more than the face: specks of hair or background floating near it, a
closed head, slivers where the reconstruction folded. The builder needs one open sheet of
reasonable triangles; these steps make it one, or say in one line where it is not. (Texture
seams, where one position has two texture coordinates, are merged when the surface is read:
:mod:`surface_io`.)
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import InputError
from .appearance import Appearance
from .mesh import surface_edges

#: a connected piece of the surface holding less than this share of its area is a fragment
FRAGMENT_AREA_SHARE = 0.10
#: triangle quality (4 sqrt(3) area / sum of squared edges: 1 equilateral, 0 degenerate)
#: below which a triangle is refused
MIN_TRIANGLE_QUALITY = 0.02
#: m, the shortest edge accepted (its spring would be stiffer than the time step allows)
MIN_EDGE_M = 1e-4


def triangle_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of every triangle, (f,) in the unit of ``vertices`` squared."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def surface_pieces(n_vertices: int, faces: np.ndarray) -> np.ndarray:
    """The connected piece of every triangle, (f,) ints (triangles sharing a vertex connect)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    e = surface_edges(faces)
    graph = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n_vertices, n_vertices))
    _, label = connected_components(graph, directed=False)
    return label[faces[:, 0]]


def drop_fragments(vertices: np.ndarray, faces: np.ndarray, appearance: Appearance | None = None,
                   *, source: str | None = None,
                   max_share: float = FRAGMENT_AREA_SHARE):
    """The largest connected piece of a surface; the small others dropped.

    Parameters
    ----------
    vertices : (n, 3) metres
    faces : (f, 3) int triangles
    appearance : its texture (per corner of ``faces``) or vertex colours, kept with what is kept
    source : the surface file, for the message
    max_share : a piece with less than this share of the area is a fragment

    Returns
    -------
    vertices, faces, appearance : the kept piece, its vertices renumbered (unused ones dropped)
    note : a line saying what was dropped ("" when nothing was)

    Raises
    ------
    InputError
        Field ``faces``: a second piece holding at least ``max_share`` of the area (two faces, or
        a face cut in two: its parts must be joined).
    """
    piece = surface_pieces(len(vertices), faces)
    area = triangle_areas(vertices, faces)
    total = float(area.sum())
    by_piece = np.bincount(piece, weights=area)
    order = np.argsort(by_piece)[::-1]
    main = int(order[0])
    n_pieces = int(np.sum(np.bincount(piece) > 0))
    if n_pieces > 1 and by_piece[order[1]] >= max_share * total:
        raise InputError(f"the surface is in {n_pieces} pieces and the second holds "
                         f"{100 * by_piece[order[1]] / total:.0f} % of its area: join them into "
                         "one sheet (the mouth corners must be connected by the surface)",
                         source=source, field="faces")
    keep = piece == main
    note = ""
    if n_pieces > 1:
        dropped = total - float(by_piece[main])
        note = (f"dropped {n_pieces - 1} loose fragment{'s' if n_pieces > 2 else ''} "
                f"({int(np.sum(~keep))} triangles, {100 * dropped / total:.2g} % of the area)")
    return (*keep_triangles(vertices, faces, appearance, keep), note)


def keep_triangles(vertices: np.ndarray, faces: np.ndarray, appearance: Appearance | None,
                   keep: np.ndarray):
    """The triangles ``keep`` (bool mask) with their vertices renumbered (unused ones dropped)
    and their texture coordinates or vertex colours. Returns (vertices, faces, appearance)."""
    if not np.any(keep):
        raise InputError("no triangle is left", field="faces")
    used = np.zeros(len(vertices), bool)
    used[faces[keep].ravel()] = True
    if keep.all() and used.all():
        return vertices, faces, appearance
    new = np.cumsum(used) - 1
    if appearance is not None:
        appearance = replace(
            appearance, uv=None if appearance.uv is None else appearance.uv[keep],
            vertex_colours=(None if appearance.vertex_colours is None
                            else appearance.vertex_colours[used]))
    return vertices[used], new[faces[keep]], appearance


#: m, the face a scan is cropped to: above the higher brow, under the menton, behind the
#: jaw angles (the built-in face reaches 65, 14 and 35 mm)
CROP_ABOVE_BROWS, CROP_BELOW_MENTON, CROP_BEHIND_JAW_ANGLES = 0.075, 0.025, 0.045


def crop_to_face(vertices: np.ndarray, faces: np.ndarray, landmarks: dict,
                 appearance: Appearance | None = None):
    """Crop a head scan (in facemech's axes) to the face: from the hairline (75 mm above the
    brows) to under the chin (25 mm below the menton), and to the ears (45 mm behind the jaw
    angles); of what is left, the largest connected piece. A capped or whole head becomes an
    open face sheet. Returns (vertices, faces, appearance, note); note "" when nothing was
    cropped."""
    top = max(landmarks["brow_left"][1], landmarks["brow_right"][1]) + CROP_ABOVE_BROWS
    bottom = landmarks["menton"][1] - CROP_BELOW_MENTON
    back = min(landmarks["jaw_angle_left"][2], landmarks["jaw_angle_right"][2]) \
        - CROP_BEHIND_JAW_ANGLES
    c = vertices[faces].mean(axis=1)
    keep = (c[:, 1] <= top) & (c[:, 1] >= bottom) & (c[:, 2] >= back)
    if keep.all():
        return vertices, faces, appearance, ""
    if not keep.any():
        return vertices, faces, appearance, ""
    piece = surface_pieces(len(vertices), faces[keep])
    main = np.argmax(np.bincount(piece))
    inner = np.flatnonzero(keep)[piece == main]
    keep = np.zeros(len(faces), bool)
    keep[inner] = True
    area = triangle_areas(vertices, faces)
    share = 100 * float(area[~keep].sum() / area.sum())
    v, f, look = keep_triangles(vertices, faces, appearance, keep)
    v, f, look, fins = trim_fins(v, f, look)
    return v, f, look, (f"cropped to the face (75 mm above the brows, 25 mm under the menton, "
                        f"45 mm behind the jaw angles): {int(np.sum(~keep))} triangles, "
                        f"{share:.0f} % of the area, dropped"
                        + (f"; {fins} triangles on the cut's ragged border (spikes and flaps "
                           "folded back) trimmed" if fins else ""))


#: a border triangle whose normal lies more than 90 degrees from a neighbour's is a flap folded
#: back; rounds of trimming at most
FIN_ROUNDS = 10
#: a triangle with two edges on the border meeting at under this angle is a spike (a grid's
#: corner, 90 degrees, is not)
SPIKE_DEG = 45.0


def _spikes(vertices: np.ndarray, faces: np.ndarray, on_border: np.ndarray) -> np.ndarray:
    """(f,) bool: triangles with three edges on the border, or two meeting at under
    :data:`SPIKE_DEG` (``on_border`` (f, 3): edge k runs from corner k to corner k + 1)."""
    two = on_border.sum(axis=1) == 2
    out = on_border.sum(axis=1) == 3
    for k in range(3):  # the corner between border edges k - 1 and k is corner k
        both = two & on_border[:, k] & on_border[:, k - 1]
        if not both.any():
            continue
        f = faces[both]
        p, a, b = vertices[f[:, k]], vertices[f[:, (k + 1) % 3]], vertices[f[:, k - 1]]
        u, w = a - p, b - p
        cos = np.einsum("ij,ij->i", u, w) / np.maximum(
            np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-30)
        out[np.flatnonzero(both)[cos > np.cos(np.radians(SPIKE_DEG))]] = True
    return out


def trim_fins(vertices: np.ndarray, faces: np.ndarray, appearance: Appearance | None = None):
    """Trim a cut surface's ragged border: spikes (:func:`_spikes`) and border triangles
    folded back against a neighbour (their normals more than 90 degrees apart), round by
    round; of what is left, the largest piece. Returns (vertices, faces, appearance, the
    number of triangles trimmed)."""
    trimmed = 0
    for _ in range(FIN_ROUNDS):
        e = np.sort(np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1),
                    axis=2).reshape(-1, 2)
        key = e[:, 0].astype(np.int64) * len(vertices) + e[:, 1]
        _, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
        on_border = (count[inverse] == 1).reshape(-1, 3)
        a, b, c = (vertices[faces[:, k]] for k in range(3))
        normal = np.cross(b - a, c - a)
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-30)
        # each interior edge's two triangles: sorted by edge, the pairs lie side by side
        order = np.argsort(inverse, kind="stable")
        starts = np.searchsorted(inverse[order], np.flatnonzero(count == 2))
        t1, t2 = order[starts] // 3, order[starts + 1] // 3
        back = np.einsum("ij,ij->i", normal[t1], normal[t2]) < 0
        folded = np.zeros(len(faces), bool)
        folded[t1[back]] = True
        folded[t2[back]] = True
        drop = _spikes(vertices, faces, on_border) | (folded & on_border.any(axis=1))
        if not drop.any():
            break
        trimmed += int(drop.sum())
        vertices, faces, appearance = keep_triangles(vertices, faces, appearance, ~drop)
    if trimmed:
        piece = surface_pieces(len(vertices), faces)
        keep = piece == np.argmax(np.bincount(piece))
        trimmed += int((~keep).sum())
        vertices, faces, appearance = keep_triangles(vertices, faces, appearance, keep)
    return vertices, faces, appearance, trimmed


def check_open(faces: np.ndarray, *, source: str | None = None) -> None:
    """Refuse a closed surface (no boundary edge): a whole or capped head, not a face sheet."""
    from .mesh import boundary_nodes

    if len(boundary_nodes(faces)) == 0:
        raise InputError("the surface is closed (a whole or capped head, with no open rim): "
                         "facemech needs the face as an open sheet, from ear to ear and hairline "
                         "to under the chin; cut away the back of the head and any caps",
                         source=source, field="faces")


def check_mouth_closed(vertices: np.ndarray, faces: np.ndarray, landmarks: dict, *,
                       source: str | None = None, reach: float = 0.012) -> None:
    """Refuse a hole between the lips: a boundary loop other than the rim whose centre lies
    within ``reach`` (m) of the segment between the mouth corners. The builder cuts the mouth
    along the lip line of a closed mouth; a mouth open in the middle has none there."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from .mesh import boundary_edges
    from .mouth import distance_to_corner_line

    edges = boundary_edges(faces)
    if len(edges) == 0 or not {"mouth_corner_left", "mouth_corner_right"} <= set(landmarks):
        return
    n = len(vertices)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    loops = label[edges[:, 0]]
    sizes = np.bincount(loops)
    for loop in np.unique(loops):
        if sizes[loop] == sizes.max():
            continue  # the rim
        pts = vertices[np.unique(edges[loops == loop])]
        if distance_to_corner_line(pts.mean(axis=0), landmarks) <= reach:
            w, h = np.ptp(pts[:, 0]) * 1e3, np.ptp(pts[:, 1]) * 1e3
            raise InputError(f"the mouth is open in the middle (a hole {w:.0f} mm wide and "
                             f"{h:.0f} mm high between the lips): the builder needs the lips "
                             "touching from corner to corner; close the mouth in the scan",
                             source=source, field="mouth")


def triangle_quality(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Quality of every triangle, (f,): 4 sqrt(3) area / sum of squared edges, 1 equilateral."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    squares = (np.sum((b - a) ** 2, axis=1) + np.sum((c - b) ** 2, axis=1)
               + np.sum((a - c) ** 2, axis=1))
    return 4.0 * np.sqrt(3.0) * triangle_areas(vertices, faces) / np.where(squares > 0, squares,
                                                                            1.0)


def check_triangles(vertices: np.ndarray, faces: np.ndarray, landmarks: dict[str, np.ndarray],
                    *, source: str | None = None, min_quality: float = MIN_TRIANGLE_QUALITY,
                    min_edge_m: float = MIN_EDGE_M) -> None:
    """Refuse slivers and very short edges, naming the landmark they are nearest.

    Parameters
    ----------
    vertices : (n, 3) metres; faces : (f, 3) int
    landmarks : name -> (3,) metres, to say where the bad triangles are
    source : the surface file
    min_quality, min_edge_m : the limits

    Raises
    ------
    InputError
        Field ``faces``: how many triangles are bad, the worst one's quality or edge, and the
        landmark nearest it.
    """
    q = triangle_quality(vertices, faces)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    shortest = np.min([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                       np.linalg.norm(a - c, axis=1)], axis=0)
    bad = (q < min_quality) | (shortest < min_edge_m)
    if not bad.any():
        return
    worst = int(np.argmin(np.where(bad, q, np.inf)))
    centre = (a[worst] + b[worst] + c[worst]) / 3.0
    names = list(landmarks)
    where = ""
    if names:
        d = [float(np.linalg.norm(landmarks[n] - centre)) for n in names]
        k = int(np.argmin(d))
        where = f" near {names[k]} ({d[k] * 1e3:.0f} mm from it)"
    raise InputError(f"{int(bad.sum())} degenerate triangle{'s' if bad.sum() > 1 else ''} "
                     f"(quality below {min_quality:g} or an edge under {min_edge_m * 1e3:g} mm; "
                     f"worst: quality {q[worst]:.3f}, edge {shortest[worst] * 1e3:.3f} mm)"
                     f"{where}: remesh or clean that region of the scan", source=source,
                     field="faces")
