"""Refinement of a coarse scan around the mouth, so that the lips get the builder's spacing.

A scan decimated to 4 mm gives the lips a dozen node pairs: each muscle then pulls on one or two
nodes and the motion is lopsided. :func:`refine_perioral` splits every triangle near the mouth
into four at its edges' midpoints (red refinement), and each neighbour that shares one split edge
into two (green closure), so that the mesh stays conforming: no node hangs on another triangle's
edge. A scan whose lip-line nodes lie more than 3.5 mm apart gets up to two such rounds, the second
on a smaller region, so that no green triangle is split again. Texture coordinates
(per triangle corner) and vertex colours are carried to the new nodes by the same midpoints.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["refine_perioral", "split_faces"]

#: m, the lips' spacing a scan is refined to
LIP_SPACING = 0.0025
#: m, a scan whose lip-line nodes lie farther apart than this on average is refined (the
#: built-in faces: 2.4, 3.1 and 4.2 mm for default-fine, default and default-coarse)
LIP_TRIGGER = 0.0035
#: m, the perioral region: triangles whose centroid lies within this of the segment between the
#: mouth corners (the second round: half of it)
PERIORAL_RADIUS = 0.018


def _edge_key(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    return lo * (1 << 32) + hi


def split_faces(vertices: np.ndarray, faces: np.ndarray, red: np.ndarray, appearance=None):
    """Split the triangles ``red`` (bool mask) into four, their neighbours into two or four.

    A neighbour with two or three split edges is split into four as well (repeated until none
    has two), one with a single split edge into two. Returns (vertices, faces, appearance,
    number of triangles split)."""
    v, f = np.asarray(vertices, float), np.asarray(faces, np.int64)
    keys = np.stack([_edge_key(f[:, 0], f[:, 1]), _edge_key(f[:, 1], f[:, 2]),
                     _edge_key(f[:, 2], f[:, 0])], axis=1)  # edge k: corner k -> k+1
    red = np.asarray(red, bool).copy()
    while True:
        split = np.isin(keys, np.unique(keys[red]))
        more = (split.sum(axis=1) >= 2) & ~red
        if not more.any():
            break
        red |= more
    split = np.isin(keys, np.unique(keys[red]))
    new_keys = np.unique(keys[split])
    index = {int(k): len(v) + i for i, k in enumerate(new_keys)}
    a, b = new_keys // (1 << 32), new_keys % (1 << 32)
    mids = 0.5 * (v[a] + v[b])
    out_f, corner_uv = [], []
    uv = None if appearance is None else appearance.uv
    for t in range(len(f)):
        c = f[t]
        n_split = int(split[t].sum())
        if n_split == 0:
            out_f.append(c)
            if uv is not None:
                corner_uv.append(uv[t])
            continue
        m = [index.get(int(keys[t, k]), -1) for k in range(3)]
        tuv = None if uv is None else np.vstack([uv[t], 0.5 * (uv[t] + np.roll(uv[t], -1, 0))])
        # tuv rows: corners 0, 1, 2, then midpoints of edges 0-1, 1-2, 2-0
        if n_split == 3:
            pieces = [(0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)]
        else:  # one split edge k: the opposite corner to its midpoint
            k = int(np.argmax(split[t]))
            pieces = [(k, 3 + k, (k + 2) % 3), (3 + k, (k + 1) % 3, (k + 2) % 3)]
        nodes = [*c, m[0], m[1], m[2]]
        for p in pieces:
            out_f.append([nodes[i] for i in p])
            if tuv is not None:
                corner_uv.append(tuv[list(p)])
    look = appearance
    if appearance is not None:
        colours = appearance.vertex_colours
        if colours is not None:
            mid_colours = (0.5 * (colours[a].astype(float) + colours[b])).round().astype(np.uint8)
            colours = np.concatenate([colours, mid_colours])
        look = replace(appearance, vertex_colours=colours,
                       uv=None if uv is None else np.asarray(corner_uv, uv.dtype))
    return (np.concatenate([v, mids]), np.asarray(out_f, np.int64), look,
            int(split.any(axis=1).sum()))


def _near_mouth(vertices, faces, landmarks, radius):
    from .mouth import distance_to_corner_line

    return distance_to_corner_line(vertices[faces].mean(axis=1), landmarks) <= radius


def lip_spacing(vertices: np.ndarray, faces: np.ndarray, landmarks: dict) -> float:
    """Mean distance (m) between the nodes of the lip line, corner to corner."""
    from .mouth import LipLine, lip_line_path, mouth_corners, stomion

    right, left = mouth_corners(vertices, faces, landmarks)
    line = LipLine(vertices[right], stomion(landmarks), vertices[left])
    path = np.asarray(lip_line_path(vertices, faces, right, left, line))
    return float(np.linalg.norm(np.diff(vertices[path], axis=0), axis=1).mean())


def refine_perioral(vertices: np.ndarray, faces: np.ndarray, landmarks: dict, appearance=None,
                    *, max_edge: float = LIP_SPACING, trigger: float = LIP_TRIGGER,
                    radius: float = PERIORAL_RADIUS):
    """Refine the mouth region of a scan whose lip line is coarser than ``trigger``.

    While the lip line's nodes lie more than ``trigger`` apart on average (two rounds at
    most), the triangles near the mouth whose longest edge exceeds ``max_edge`` are split.

    Parameters
    ----------
    vertices : (n, 3) metres; ``faces`` (f, 3); ``landmarks`` with both mouth corners
    appearance : :class:`~facemech.geometry.appearance.Appearance` or None, carried along
    max_edge : m, the lips' target spacing
    trigger : m, the mean lip-line spacing above which the scan is refined
    radius : m, the region: within this of the segment between the mouth corners

    Returns
    -------
    (vertices, faces, appearance, note) : note is "" when nothing was refined
    """
    v, f, look, done = np.asarray(vertices, float), np.asarray(faces, np.int64), appearance, 0
    before, spacing = len(v), lip_spacing(v, f, landmarks)
    first = spacing
    for r in (radius, 0.5 * radius):
        if spacing <= trigger:
            break
        e = np.linalg.norm(v[f] - v[np.roll(f, -1, axis=1)], axis=2).max(axis=1)
        red = _near_mouth(v, f, landmarks, r) & (e > max_edge)
        if not red.any():
            break
        v, f, look, n = split_faces(v, f, red, look)
        done, spacing = done + n, lip_spacing(v, f, landmarks)
    if not done:
        return v, f, look, ""
    return v, f, look, (f"the mouth region refined: the lip line's nodes {first * 1e3:.1f} mm "
                        f"apart, now {spacing * 1e3:.1f} mm ({done} triangles split, "
                        f"{len(v) - before} nodes added)")
