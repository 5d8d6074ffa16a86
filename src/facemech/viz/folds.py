"""Nasolabial and mentolabial folds, render-only, deepening as the skin round them is
compressed (a smile, a pucker).

Each fold is a curve on the frontal plane drawn from the landmarks: the nasolabial from the
alar groove (16.5 mm off the midline, 5 mm over the subnasale) down and out to 8 mm lateral of
and 8 mm under each cheilion, bowed outwards; the mentolabial an arc 12 mm under the lower
lip's centre, 28 mm wide. Per frame the drawn skin node i moves along its rest normal by

    d_i = -w_i (D0 + G c_i) + b_i G c_i / 2,   c_i = clip(1 - L_s / L_s^rest, 0, C_MAX),

where L_s is the skin's width across the fold at its station s nearest the node (the distance
between two points carried by the skin 6 mm either side of it), w_i a Gaussian (sigma 4.5 mm)
of the node's distance to the fold and b_i one on the cheek's side of the nasolabial fold
(the cheek piling over it). The physics' nodes are not changed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .look import FaceLook

REST_DEPTH = 0.0004  #: m, D0: an adult's folds at rest
GAIN = 0.03  #: m per unit of compression across the fold, G
MAX_COMPRESSION = 0.15  #: C_MAX
SIGMA = 0.0045  #: m, the fold's half-width
PROBE = 0.006  #: m, the points either side of a fold whose distance is its width


@dataclass(frozen=True)
class Folds:
    """Fold weights of the skin's nodes and what their compression is measured against."""

    nodes: np.ndarray  # (k,) the skin nodes the folds move
    line: np.ndarray  # (k,) weight of the fold's furrow
    cheek: np.ndarray  # (k,) weight of the bulge beside it
    normals: np.ndarray  # (k, 3) rest unit normals
    station: np.ndarray  # (k,) the station of each node
    probes: tuple  # two (s, 3) node indices and (s, 3) weights: the points either side
    rest_width: np.ndarray  # (s,) m, the widths across the folds at rest

    def compression(self, skin: np.ndarray) -> np.ndarray:
        """(s,) the compression across the folds at their stations, 0 .. C_MAX."""
        (ia, wa), (ib, wb) = self.probes
        a = np.einsum("sk,skj->sj", wa, skin[ia])
        b = np.einsum("sk,skj->sj", wb, skin[ib])
        width = np.linalg.norm(a - b, axis=1)
        return np.clip(1.0 - width / self.rest_width, 0.0, MAX_COMPRESSION)

    def depth(self, skin: np.ndarray) -> np.ndarray:
        """(k,) m, the outward displacement of :attr:`nodes` for skin nodes (n, 3) m."""
        c = self.compression(skin)[self.station]
        return -self.line * (REST_DEPTH + GAIN * c) + self.cheek * 0.5 * GAIN * c



def fold_curves(landmarks: dict) -> list[np.ndarray]:
    """The folds' curves, each (m, 2) m on the frontal plane (x, y): two nasolabial, one
    mentolabial; [] without the landmarks they are drawn from."""
    need = ("subnasale", "mouth_corner_left", "lower_lip_center")
    if not all(k in landmarks for k in need):
        return []
    sn = np.asarray(landmarks["subnasale"], float)
    ch = np.asarray(landmarks["mouth_corner_left"], float)
    li = np.asarray(landmarks["lower_lip_center"], float)
    s = np.linspace(0.0, 1.0, 40)[:, None]
    curves = []
    for side in (1, -1):
        p0 = np.array([side * 0.0165, sn[1] + 0.005])
        p2 = np.array([side * (abs(ch[0]) + 0.008), ch[1] - 0.008])
        p1 = np.array([side * (abs(ch[0]) + 0.006), sn[1] - 0.004])  # bowed outwards
        curves.append((1 - s) ** 2 * p0 + 2 * s * (1 - s) * p1 + s ** 2 * p2)
    x = np.linspace(-0.014, 0.014, 29)
    curves.append(np.stack([x, li[1] - 0.012 + 0.003 * (x / 0.014) ** 2], -1))
    return curves


def build_folds(look: FaceLook) -> Folds | None:
    """The folds of an untextured face with the landmarks they are drawn from, else None."""
    from ..geometry.builder import vertex_normals
    from .attach import closest_on_skin
    from .mesh import skin_depth

    curves = fold_curves(look.landmarks)
    if not curves or look.textured:
        return None
    r = look.rest
    line = np.zeros(len(r))
    cheek = np.zeros(len(r))
    near = np.full(len(r), np.inf)
    station = np.zeros(len(r), int)
    sides = []
    start = 0
    for k, c in enumerate(curves):
        d = np.linalg.norm(r[:, None, :2] - c[None], axis=2)
        j = np.argmin(d, axis=1)
        dj = d[np.arange(len(r)), j]
        line = np.maximum(line, np.exp(-(dj / SIGMA) ** 2))
        closer = dj < near
        near[closer], station[closer] = dj[closer], start + j[closer]
        if k < 2:  # the cheek's side of a nasolabial fold: further from the midline
            off = c + np.array([np.sign(c[-1, 0]) * 0.007, 0.003])
            db = np.linalg.norm(r[:, None, :2] - off[None], axis=2).min(axis=1)
            cheek = np.maximum(cheek, np.exp(-(db / SIGMA) ** 2))
        t = np.gradient(c, axis=0)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        across = np.stack([-t[:, 1], t[:, 0]], -1) * PROBE
        sides.append((c + across, c - across))
        start += len(c)
    front = r[:, 2] > np.percentile(r[:, 2], 30)
    nodes = np.flatnonzero(front & ((line > 0.02) | (cheek > 0.02)))
    depth = skin_depth(look)
    probes = []
    for i in (0, 1):
        xy = np.concatenate([s[i] for s in sides])
        p = np.column_stack([xy, depth(xy[:, 0], xy[:, 1])])
        p[:, 2] = np.where(np.isfinite(p[:, 2]), p[:, 2], 0.0)
        t, w = closest_on_skin(p, r, look.triangles)
        probes.append((np.asarray(look.triangles)[t], w))
    normals = vertex_normals(r, look.triangles)[nodes]
    folds = Folds(nodes, line[nodes], cheek[nodes], normals, station[nodes], tuple(probes),
                  np.ones(len(probes[0][0])))
    (ia, wa), (ib, wb) = probes
    width = np.linalg.norm(np.einsum("sk,skj->sj", wa, r[ia])
                           - np.einsum("sk,skj->sj", wb, r[ib]), axis=1)
    object.__setattr__(folds, "rest_width", width)
    return folds
