"""Where dlib's 68-point predictor puts the iBUG points on the generic face (prints the table).

facemech places the generic face's iBUG points by its own reading of the convention
(:func:`facemech.geometry.ibug.generic_ibug68`); the predictor, trained on the 300-W
annotations, puts some of them elsewhere: the jaw line on the face's visible outline, the eye
corners where the rendered fissure ends. This script renders the built-in face from the front
at four image sizes and camera distances, finds its landmarks with dlib, and prints the mean
offset of each point from the generic one (mm on the face, x to the subject's left, y up),
made mirror-symmetric, and the largest standard deviation over the renders: the table
:data:`facemech.geometry.photo_fit.DLIB_OFFSETS_MM`. It also prints how far the jaw line's mean
offsets depart from mirror symmetry (half the difference between a point's offset and its
mirror partner's, mirrored), the one-sided error that
:func:`facemech.geometry.photo_fit.symmetric_jaw` takes out of a detector's jaw line.

Usage::

    PYTHONPATH=src python tools/photo_detector_offsets.py
"""

from __future__ import annotations

import numpy as np

from facemech.geometry.builder import default_face
from facemech.geometry.ibug import generic_ibug68
from facemech.geometry.photo_fit import MIRROR
from facemech.io.photo import DlibDetector
from facemech.viz.look import look_from_model
from facemech.viz.render import Renderer
from facemech.viz.scene import build_scene

#: (height, width) px and camera distance m of the renders
RENDERS = (((720, 540), 1.2), ((1080, 810), 0.7), ((560, 420), 2.5), ((900, 900), 1.0))


def measure() -> tuple[np.ndarray, float, np.ndarray]:
    """The symmetric table (68, 2) mm, the largest standard deviation over the renders (mm),
    and the jaw line's departure from symmetry (17, 2) mm."""
    look = look_from_model(default_face())
    scene = build_scene(look)
    g = generic_ibug68()
    det = DlibDetector()
    offsets = []
    for (h, w), dist in RENDERS:
        r = Renderer(scene, "frontal", (h, w), background="#8a9099", distance=dist)
        cam = r.cameras[0]
        found = det.faces(r(look.rest)[..., :3])
        if len(found) != 1:
            raise SystemExit(f"{len(found)} faces found in the {w}x{h} render")
        p = cam.project(g)[:, :2].astype(float)
        k = dist / (dist - (g[:, 2] - cam.target[2]))
        mm_per_px = 2e3 * cam.half_height / h / k
        offsets.append((found[0].points - p) * mm_per_px[:, None] * [1.0, -1.0])
    offsets = np.array(offsets)
    mean = offsets.mean(axis=0)
    sym = 0.5 * (mean + mean[MIRROR] * [-1.0, 1.0])
    return sym, float(offsets.std(axis=0).max()), (mean - sym)[:17]


if __name__ == "__main__":
    table, spread, lopsided = measure()
    print(f"# largest standard deviation over the renders: {spread:.2f} mm")
    worst = int(np.argmax(np.linalg.norm(lopsided, axis=1)))
    print(f"# the jaw line's largest departure from symmetry: {np.linalg.norm(lopsided[worst]):.2f}"
          f" mm (iBUG {worst}: x {lopsided[worst, 0]:+.1f}, y {lopsided[worst, 1]:+.1f})")
    rows = ", ".join(f"({x:.1f}, {y:.1f})" for x, y in table)
    print(f"DLIB_OFFSETS_MM = np.array([{rows}])")
