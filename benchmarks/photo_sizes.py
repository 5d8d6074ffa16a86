"""A talker from photos of other sizes: how far the fit's landmarks move with the image size and
the camera distance, with dlib's points from one box and from the median over many.

The built-in face and the variant face of tests/viz/test_photo.py (a wider mouth, a longer lower
face, a nose 6 mm longer; procedural skin, the whole head) are rendered from the front at each
size and camera distance of :data:`GRID`; dlib finds the 68 points twice, from its detector's box
alone and as :meth:`facemech.io.photo.DlibDetector.faces` does by default (the median over the
boxes of ``BOX_SCALES`` and ``BOX_SHIFTS`` around it), and
:func:`facemech.geometry.photo_fit.fit_frontal` fits the front alone (the IPD given). Each fit's
18 landmarks are compared with the face's own in x and y (a frontal photo cannot see the nose's
depth), the mean offset removed.

Prints JSON: per photo the worst landmark (its name and error, mm) and the median (mm) of each
way, and over the photos the largest and the mean of the worst. Needs the ``photo`` extra
(dlib); about 30 s.

``python benchmarks/photo_sizes.py``
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

TESTS = Path(__file__).resolve().parents[1] / "tests"
sys.path[:0] = [str(TESTS), str(TESTS / "viz")]  # test_photo and the conftest it imports

#: ((height, width) px, camera distance m) of the photos; the first is the tests'
GRID = (((720, 540), 1.2), ((800, 600), 1.2), ((640, 480), 1.2), ((720, 540), 1.0),
        ((720, 540), 1.5), ((900, 700), 0.8))


def faces():
    """(name, model, landmarks m, iBUG points (68, 3) m) of the two test faces."""
    import test_photo as T  # tests/viz/test_photo.py: the variant face's shape
    from facemech.geometry import generic
    from facemech.geometry.builder import build_face, default_face, default_surface, tissue_options
    from facemech.geometry.ibug import generic_ibug68

    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    yield "built-in", default_face(), lm, generic_ibug68()
    v, f, lmv = default_surface()
    lmv = {k: T._variant(x) for k, x in lmv.items()}
    yield ("variant", build_face(T._variant(v), f, lmv, name="variant",
                                 options=tissue_options("uniform")), lmv,
           T._variant(generic_ibug68()))


def main() -> int:
    from facemech.geometry.photo_fit import fit_frontal
    from facemech.io.photo import DlibDetector
    from facemech.viz.look import look_from_model
    from facemech.viz.render import Renderer
    from facemech.viz.scene import build_scene

    detector = DlibDetector()
    rows = []
    for name, model, truth, ibug in faces():
        names = list(truth)
        ipd = float(np.linalg.norm(ibug[42:48].mean(axis=0) - ibug[36:42].mean(axis=0)))
        look = look_from_model(model)
        scene = build_scene(look)
        for size, dist in GRID:
            render = Renderer(scene, "frontal", size, background="#8a9099", distance=dist)
            cam = render.cameras[0]
            photo = np.ascontiguousarray(render(look.rest)[..., :3])
            # the fit's camera distance is to the eyes; the renderer's to the framing's centre
            eyes = dist - float(ibug[36:48, 2].mean() - cam.target[2])
            row = {"face": name, "size": list(size), "distance_m": dist}
            for way, boxes in (("one_box", False), ("median_of_boxes", True)):
                found = detector.faces(photo, boxes=boxes)
                if len(found) != 1:
                    row[way] = {"faces_found": len(found)}
                    continue
                fit = fit_frontal(found[0].points, size, ipd=ipd, distance=eyes)
                d = np.array([fit.landmarks[n] - truth[n] for n in names])
                d -= d.mean(axis=0)
                e = 1e3 * np.hypot(d[:, 0], d[:, 1])
                k = int(np.argmax(e))
                row[way] = {"worst_mm": round(float(e[k]), 2), "worst": names[k],
                            "median_mm": round(float(np.median(e)), 2)}
            rows.append(row)
            print(f"{name} {size[1]}x{size[0]} {dist} m: one box "
                  f"{row['one_box'].get('worst_mm')} mm, median of boxes "
                  f"{row['median_of_boxes'].get('worst_mm')} mm", file=sys.stderr, flush=True)
    summary = {}
    for way in ("one_box", "median_of_boxes"):
        worst = [r[way]["worst_mm"] for r in rows if "worst_mm" in r[way]]
        summary[way] = {"largest_worst_mm": max(worst), "mean_worst_mm": round(
            float(np.mean(worst)), 2), "photos_within_2_mm": sum(w <= 2.0 for w in worst),
            "photos": len(worst)}
    print(json.dumps({"rows": rows, "summary": summary}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
