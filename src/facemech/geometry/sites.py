"""Sites on the face: generic frontal positions carried onto a face and snapped to its nodes.

Landmarks, virtual markers and muscle attachments are placed on the generic face
(:mod:`anatomy`, frontal ``(x, y)`` mm, origin at the nasion); :class:`SurfaceSites` carries
them onto a face by the landmark warp (:mod:`warp`) and snaps them to epidermal nodes, on the
right side of the lip line near the mouth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from . import anatomy, generic
from .mouth import LOWER_LIP, UPPER_LIP, MouthCut
from .warp import LandmarkWarp, generic_landmarks, landmark_warp

#: candidates :meth:`SurfaceSites.snap` looks through for a node on the wanted side of the lips
SNAP_CANDIDATES = 12
#: generic mm: markers farther than this from the midline are not held to a side of the lips
MARKER_LIP_HALF_WIDTH = 27.0


def generic_point(xy: tuple[float, float]) -> np.ndarray:
    """The generic face's surface point (3,), metres, at frontal ``xy`` (mm)."""
    return generic.surface_point(np.array(xy[0]), np.array(xy[1])) * 1e-3


@dataclass(frozen=True)
class SurfaceSites:
    """What sites are placed on: a cut surface and the warp from the generic face.

    Parameters
    ----------
    mouth : the cut epidermal surface (its lip line and the side of every node)
    warp : generic landmarks -> this face's landmarks (metres)
    tree : k-d tree of ``mouth.vertices``
    """

    mouth: MouthCut
    warp: LandmarkWarp
    tree: cKDTree

    def place(self, xy: tuple[float, float]) -> np.ndarray:
        """The point (3,), metres, of the generic frontal site ``xy`` (mm) on this face."""
        return self.warp(generic_point(xy)[None])[0]

    def snap(self, point: np.ndarray, want_side: int | None = None) -> int:
        """The epidermal node nearest ``point`` (m), on ``want_side`` of the lip line if given.

        Looks through the :data:`SNAP_CANDIDATES` nearest; the nearest of all if none fits.
        """
        _, cand = self.tree.query(point, k=min(SNAP_CANDIDATES, self.mouth.n_surface))
        for c in np.atleast_1d(cand):
            if want_side is None or self.mouth.side[c] == want_side:
                return int(c)
        return int(np.atleast_1d(cand)[0])


def surface_sites(mouth: MouthCut, landmarks: dict[str, np.ndarray]) -> SurfaceSites:
    """The :class:`SurfaceSites` of a cut surface with its landmarks (metres)."""
    return SurfaceSites(mouth=mouth, warp=landmark_warp(generic_landmarks(), landmarks),
                        tree=cKDTree(mouth.vertices))


def landmark_nodes(sites: SurfaceSites, landmarks: dict[str, np.ndarray]) -> dict[str, int]:
    """The epidermal node of every landmark (the mouth corners are the cut's corners)."""
    mouth = sites.mouth
    lip_side = {"upper_lip_center": UPPER_LIP, "lower_lip_center": LOWER_LIP}
    out: dict[str, int] = {}
    for name, p in landmarks.items():
        if name.startswith("mouth_corner"):
            out[name] = mouth.corner_left if name.endswith("left") else mouth.corner_right
        else:
            out[name] = sites.snap(p, lip_side.get(name, mouth.line.side_of(p)))
    return out


def marker_nodes(sites: SurfaceSites) -> dict[str, int]:
    """The epidermal node of every virtual marker of :mod:`anatomy` (right ones first)."""
    out: dict[str, int] = {}
    for name, xy in {**anatomy.RIGHT_MARKERS, **anatomy.LEFT_MARKERS}.items():
        side = (None if abs(xy[0]) > MARKER_LIP_HALF_WIDTH
                else (UPPER_LIP if xy[1] >= generic.Y_STOMION else LOWER_LIP))
        out[name] = sites.snap(sites.place(xy), side)
    return out


def marker_aliases(landmarks: dict[str, int], markers: dict[str, int]) -> dict[str, str]:
    """Virtual markers on a landmark's node, as ``marker -> landmark``: one point of the face
    with two names (on the default face R07 and L06 are the mouth corners, the cut's corners).
    Both names stay (results and scripts use either); the landmark's is the point's name."""
    by_node = {int(v): k for k, v in landmarks.items()}
    return {m: by_node[int(v)] for m, v in markers.items() if int(v) in by_node}


def shared_points(names, nodes, aliases: dict[str, str] | None = None) -> list[str]:
    """Lines naming the markers of ``names`` that sit on one node (``nodes``, same order),
    e.g. ``R07 = mouth_corner_right (node 1187)``; ``aliases`` (marker -> landmark) say which
    name is the point's own."""
    aliases = aliases or {}
    groups: dict[int, list[str]] = {}
    for n, v in zip(names, nodes, strict=True):
        groups.setdefault(int(v), []).append(str(n))
    out = []
    for node, group in groups.items():
        if len(group) > 1:
            group.sort(key=lambda g: (g in aliases, g))
            out.append(f"{' = '.join(group[1:])} = {group[0]} (node {node})")
    return out
