"""The drawn skin's shape where the simulated skin is too coarse or too plain: render-only.

The physics' nodes are never changed; each frame the renderer draws a copy of them moved by

* static offsets (m, model axes): the malar eminences (cheekbones), a bump of 2.5 mm along
  the rest normal (Gaussian, sigma 13 mm) 12 mm over and 2 mm lateral of each cheek landmark;
  the mouth's corners 1.6 mm further out each (Gaussian, sigma 11 mm, round each cheilion),
  so that the drawn mouth width ch-ch lies within Farkas' adult male norm (54.0 +- 3.3 mm)
  where the built-in face's own is 50.5 mm;
* the folds that deepen as the skin is compressed across them (:mod:`.folds`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .folds import Folds, build_folds
from .look import FaceLook

CHEEKBONE = (0.0025, 0.013, 0.012, 0.002)  #: m: height, sigma, above and lateral of 'cheek'
MOUTH_WIDENING = 0.0016  #: m, each corner moved out
MOUTH_SIGMA = 0.011  #: m


@dataclass(frozen=True)
class DrawnShape:
    """Static offsets (n, 3) m of the skin's nodes and the folds (or None)."""

    offset: np.ndarray
    folds: Folds | None

    def apply(self, skin: np.ndarray) -> np.ndarray:
        """The drawn skin (n, 3) m of simulated skin nodes (n, 3) m."""
        out = np.asarray(skin, float) + self.offset
        if self.folds is not None:  # their compression is the simulated skin's
            out[self.folds.nodes] += self.folds.depth(skin)[:, None] * self.folds.normals
        return out


def drawn_shape(look: FaceLook) -> DrawnShape | None:
    """The built-in (untextured) face's drawn shape; None for a scan's or a photo's, whose
    own shape is drawn as it is."""
    if look.textured:
        return None
    from ..geometry.builder import vertex_normals

    r = look.rest
    lm = look.landmarks
    offset = np.zeros_like(r)
    normals = vertex_normals(r, look.triangles)
    for side, cheek, corner in ((1, "cheek_left", "mouth_corner_left"),
                                (-1, "cheek_right", "mouth_corner_right")):
        if cheek in lm:
            h, sigma, up, out = CHEEKBONE
            p = np.asarray(lm[cheek], float)
            c = p[:2] + np.array([side * out, up])
            w = np.exp(-0.5 * (np.linalg.norm(r[:, :2] - c, axis=1) / sigma) ** 2)
            w *= r[:, 2] > p[2] - 0.03  # the face's side, not the head behind it
            offset += (h * w)[:, None] * normals
        if corner in lm:
            c = np.asarray(lm[corner], float)[:2]
            w = np.exp(-0.5 * (np.linalg.norm(r[:, :2] - c, axis=1) / MOUTH_SIGMA) ** 2)
            offset[:, 0] += side * MOUTH_WIDENING * w * (side * r[:, 0] > 0)
    # the skin's outer edge stays where the results have it (the closing head's ring is its
    # nodes; the folds are drawn far inside it)
    from .closure import boundary_loops

    offset[np.linalg.norm(offset, axis=1) < 1e-6] = 0.0
    offset[max(boundary_loops(look.triangles), key=len)] = 0.0
    return DrawnShape(offset, build_folds(look))
