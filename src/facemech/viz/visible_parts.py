"""What shows of each part of a scene: pixels per part through one camera.

The renderer's visibility buffer (:func:`.raster.rasterise_grid`) holds, per sample, the
triangle seen there; each triangle belongs to one part (the scene's parts are packed in
order, :mod:`.scene`). Counting the samples per part, divided by the samples per pixel, gives
each part's visible area in pixels: how much of the teeth, the tongue or the mouth's lining
a frame shows.
"""

from __future__ import annotations

import numpy as np

from .raster import rasterise_grid
from .render import Renderer


def part_pixels(renderer: Renderer, skin: np.ndarray, jaw_angle=0.0, tongue=None,
                panel: int = 0) -> dict[str, float]:
    """Visible pixels per part of one frame (blinks, gaze and head at rest).

    Parameters
    ----------
    renderer : the :class:`~.render.Renderer` (its scene, cameras and supersampling)
    skin : (n, 3) m, the skin's node positions
    jaw_angle : rad, or the jaw's pose (3,) (angle rad, shift_y m, shift_z m)
    tongue : None, or the tongue tip's pose (2,) m
    panel : which of the view's panels

    Returns
    -------
    dict part name -> pixels (float: samples / supersample**2); parts not seen are left out
    """
    scene = renderer.scene
    verts, _ = scene.frame(skin, jaw_angle, 0.0, (0.0, 0.0), None, tongue)
    cam = renderer.cameras[panel]
    s = renderer.supersample
    h, w = cam.size
    p = cam.project(verts, s)
    buffers = (np.full((h * s, w * s), -np.inf, np.float32),
               np.full((h * s, w * s), -1, np.int32), np.empty((h * s, w * s, 2), np.float32))
    rasterise_grid(p[:, 0], p[:, 1], p[:, 2], scene.tris, scene.uv, scene.tex, scene.alpha_test,
                   scene.two_sided, scene.atlas, buffers, s)
    tid = buffers[1]
    f = len(scene.tris)
    seen = tid[tid >= 0]
    seen = np.where(seen >= f, seen - f, seen)  # a two-sided triangle's inner side
    ends = np.cumsum([len(part.faces) for part in scene.parts])
    which = np.searchsorted(ends, seen, side="right")
    counts = np.bincount(which, minlength=len(scene.parts))
    return {part.name: float(c) / (s * s) for part, c in zip(scene.parts, counts, strict=True)
            if c}
