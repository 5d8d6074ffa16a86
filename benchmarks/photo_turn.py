"""A talker from a photo of a turned face: the fit with the turn taken out and without it.

The built-in face (procedural skin, the whole head) is rendered at 720 x 540 from a pinhole 1.2 m
away, turned by each ``--degrees`` about the vertical (the renderer's view azimuth: positive
looks from the subject's right, so the face appears turned to its left by a negative amount),
dlib finds its 68 points, and :func:`facemech.geometry.photo_fit.fit_frontal` fits the generic
face to them twice: as it does by default (the turn read by ``estimate_yaw`` and taken out from
3 degrees on) and with ``yaw=0`` (fitted as frontal, as before 2026-11-28). Each fit's 18
landmarks are compared with the face's own in x and y (a frontal photo cannot see depth), the
mean offset removed.

Prints JSON: per angle the turn read (degrees), and for each fit the worst landmark (its name
and error, mm) and the median error (mm). ``--face variant``: the variant face of
tests/viz/test_photo.py (a wider mouth, a longer lower face, a nose 6 mm longer) instead. Needs the
``photo`` extra (dlib); about 20 s.

``python benchmarks/photo_turn.py [--degrees -15 -10 -5 0 5 10 15] [--face variant]``
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

SIZE = (720, 540)  #: (height, width) of the photos, px
DISTANCE = 1.2  #: m, the renderer's camera distance


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--degrees", type=float, nargs="+",
                    default=[-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 15.0])
    ap.add_argument("--face", choices=("built-in", "variant"), default="built-in")
    args = ap.parse_args(argv)
    from facemech.geometry.photo_fit import fit_frontal
    from facemech.io.photo import DlibDetector
    from facemech.viz.camera import Camera, view_camera, view_rotation
    from facemech.viz.look import look_from_model
    from facemech.viz.render import parse_background, render_panel
    from facemech.viz.scene import build_scene
    from photo_sizes import faces  # benchmarks/photo_sizes.py: the two test faces

    _, model, truth, ibug = next(f for f in faces() if f[0] == args.face)
    names = list(truth)
    ipd = float(np.linalg.norm(ibug[42:48].mean(axis=0) - ibug[36:42].mean(axis=0)))
    look = look_from_model(model)
    scene = build_scene(look)
    frontal = view_camera("frontal", scene.framing, SIZE, DISTANCE)
    # the fit's camera distance is to the eyes; the renderer's to the framing's centre
    distance = DISTANCE - float(ibug[36:48, 2].mean() - frontal.target[2])
    verts, norms = scene.frame(look.rest, 0.0)
    detector = DlibDetector()

    def errors(fit) -> dict:
        d = np.array([fit.landmarks[n] - truth[n] for n in names])
        d = d - d.mean(axis=0)
        e = 1e3 * np.hypot(d[:, 0], d[:, 1])
        k = int(np.argmax(e))
        return {"worst_mm": round(float(e[k]), 2), "worst": names[k],
                "median_mm": round(float(np.median(e)), 2)}

    rows = []
    for deg in args.degrees:
        cam = Camera(view_rotation(deg, 0.0), frontal.target, frontal.half_height, SIZE,
                     DISTANCE)
        photo = np.ascontiguousarray(render_panel(scene, verts, norms, cam, background=(
            parse_background("#8a9099")))[..., :3])
        found = detector.faces(photo)
        if len(found) != 1:
            rows.append({"view_degrees": deg, "faces_found": len(found)})
            continue
        pts = found[0].points
        turned = fit_frontal(pts, SIZE, ipd=ipd, distance=distance)
        flat = fit_frontal(pts, SIZE, ipd=ipd, distance=distance, yaw=0.0)
        rows.append({"view_degrees": deg,
                     "turn_read_degrees": round(float(np.degrees(turned.camera.yaw)), 2),
                     "turned_back": errors(turned), "as_frontal": errors(flat)})
    print(json.dumps({"face": args.face, "size": list(SIZE), "distance_m": DISTANCE,
                      "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
