"""A machine lip-reader on the frontal movie of spoken Harvard sentences (issue 29).

Each sentence is spoken by :func:`facemech.workflows.speak.speak` (eSpeak NG, the built-in face,
no movie file, blinks, gaze and head motion off), its frontal frames are rendered in memory
(:func:`facemech.analysis.lipreader.frontal_frames`), a face tracker reads the inner-lip
distance off each (:func:`~facemech.analysis.lipreader.read_lips`) and that is correlated with
the model's lip aperture (:func:`~facemech.analysis.lipreader.compare`). ``--tracker dlib``
(default): dlib's 68-point predictor; ``--tracker mesh``: MediaPipe's face mesh, tracked as
MediaPipe tracks a video (:mod:`facemech.io.face_mesh`).

Prints JSON: per sentence Pearson's r, the frames with a face out of all, the fitted line (px
per mm of aperture, px at zero), the aperture's largest value (mm), and the wall time of
speaking (synthesis and simulation), rendering and tracking (s). ``r_with_shape`` is a
diagnosis, not the issue's measure: the multiple correlation of the inner-lip distance with
the aperture, the lips' protrusion and the mouth's width change together
(:func:`facemech.speech.mouth.mouth_measures`), i.e. how much of what the tracker reads the
lips' shape explains besides their opening. ``--picture FILE.jpg``: three frames of the sentence
with the lowest r, the 68 points drawn on them (the inner lips' six in red), side by side: the
widest aperture, and the frames the tracker reads most below and most above its fitted line.

``--boxes``: each point the median of the predictor's from 45 boxes around the detector's, as
``face from-photo`` reads a photo (the default: one box per frame, as dlib's examples track).

``python benchmarks/lipreader.py [--tracker dlib|mesh] [--face default] [--size 640x360]
[--aa 2] [--upsample 0] [--sentences N] [--picture docs/img/lipreader.jpg] [--boxes]``
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from sentences import HARVARD  # noqa: E402  (benchmarks/sentences.py: lists 1 and 2)

#: the sentences measured by default: the first six of list 1
DEFAULT_SENTENCES = 6


def measure(text: str, *, face: str, size: tuple[int, int], aa: int, upsample: int,
            detector, boxes: bool = False, tracker: str = "dlib") -> tuple[dict, tuple]:
    """The sentence's row of the report, and what :func:`draw` needs to draw it."""
    from facemech.analysis.lipreader import compare, frontal_frames, model_aperture, read_lips
    from facemech.speech.alive import Liveliness
    from facemech.speech.mouth import mouth_measures
    from facemech.workflows.speak import speak

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        spoken = speak(tmp, text, face=face, video=False, alive=Liveliness.off())
    t1 = time.perf_counter()
    ds = spoken.dataset
    frames = list(frontal_frames(ds, size=size, supersample=aa))
    t2 = time.perf_counter()
    reading = read_lips(frames, detector=detector, upsample=upsample, boxes=boxes,
                        tracker=tracker)
    t3 = time.perf_counter()
    aperture = model_aperture(ds)
    agreement = compare(reading.distance, aperture)
    shape = mouth_measures(spoken.simulation.model, spoken.simulation.positions)
    ok = reading.found
    x = np.column_stack([aperture, shape["lips_forward"], shape["width_change"],
                         np.ones(len(aperture))])[ok]
    fit = x @ np.linalg.lstsq(x, reading.distance[ok], rcond=None)[0]
    r_shape = float(np.corrcoef(fit, reading.distance[ok])[0, 1])
    miss = reading.distance - (agreement.intercept + agreement.slope * aperture)
    which = (int(np.argmax(aperture)), int(np.nanargmin(miss)), int(np.nanargmax(miss)))
    keep = (frames, reading.points, aperture, which)
    return {"text": text, **{k: round(v, 4) if isinstance(v, float) else v
                             for k, v in agreement.to_dict().items()},
            "r_with_shape": round(r_shape, 4),
            "aperture_max_mm": round(float(aperture.max()) * 1e3, 2),
            "speak_s": round(t1 - t0, 1), "render_s": round(t2 - t1, 1),
            "track_s": round(t3 - t2, 1)}, keep


def draw(path: str, frames, points, aperture, which: tuple[int, ...]) -> None:
    """Frames ``which`` with their points, cropped to the face, side by side."""
    from PIL import Image, ImageDraw

    from facemech.analysis import lipreader
    from facemech.io import face_mesh

    inner_lip_distance = lipreader.inner_lip_distance
    # the inner lips' points of the tracker that drew them (68 iBUG points or the 468 of the mesh)
    own = lipreader if points.shape[1] == 68 else face_mesh
    tiles = []
    for k in which:
        im = Image.fromarray(frames[k])
        h, w = frames[k].shape[:2]
        x0 = max(w // 2 - h * 5 // 12, 0)
        box = (x0, 0, min(x0 + h * 5 // 6, w), h)
        zoom = 2
        im = im.crop(box).resize(((box[2] - box[0]) * zoom, h * zoom), Image.LANCZOS)
        pen = ImageDraw.Draw(im)
        inner = set(own.UPPER_INNER) | set(own.LOWER_INNER)
        radius = 2.5 if points.shape[1] == 68 else 1.2
        for i, (x, y) in enumerate(points[k]):
            if np.isfinite(x):
                x, y = (x - box[0]) * zoom, y * zoom
                colour = (230, 30, 30) if i in inner else (40, 230, 60)
                r = 2.5 if i in inner else radius
                pen.ellipse((x - r, y - r, x + r, y + r), fill=colour)
        pen.text((8, 8), f"model aperture {aperture[k] * 1e3:.1f} mm, tracker's inner-lip "
                  f"distance {inner_lip_distance(points[k]):.1f} px", fill=(255, 255, 255))
        tiles.append(im)
    sheet = Image.new("RGB", (sum(t.width for t in tiles), tiles[0].height))
    for i, t in enumerate(tiles):
        sheet.paste(t, (i * tiles[0].width, 0))
    sheet.save(path, quality=80, optimize=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--face", default="default")
    ap.add_argument("--size", default="640x360", help="WIDTHxHEIGHT pixels")
    ap.add_argument("--aa", type=int, default=2, help="anti-aliasing samples per axis")
    ap.add_argument("--upsample", type=int, default=0, help="detector upsampling (0 or 1)")
    ap.add_argument("--sentences", type=int, default=DEFAULT_SENTENCES)
    ap.add_argument("--picture", help="JPEG of three frames with their points (module doc)")
    ap.add_argument("--tracker", choices=("dlib", "mesh"), default="dlib")
    ap.add_argument("--boxes", action="store_true",
                    help="each point the median over 45 predictor boxes (as face from-photo)")
    args = ap.parse_args(argv)
    from facemech.io.photo import DlibDetector

    w, h = (int(v) for v in args.size.lower().split("x"))
    detector = DlibDetector()
    rows, worst = [], None
    for text in HARVARD[: args.sentences]:
        row, keep = measure(text, face=args.face, size=(h, w), aa=args.aa,
                            upsample=args.upsample, detector=detector, boxes=args.boxes,
                            tracker=args.tracker)
        if worst is None or row["r"] < worst[0]:
            worst = (row["r"], keep)
        rows.append(row)
    if args.picture:
        draw(args.picture, *worst[1])
    rs = [row["r"] for row in rows]
    print(json.dumps({"tracker": args.tracker, "face": args.face, "size": args.size,
                      "aa": args.aa,
                      "upsample": args.upsample, "boxes": args.boxes, "r_min": min(rs),
                      "r_mean": sum(rs) / len(rs),
                      "sentences": rows}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
