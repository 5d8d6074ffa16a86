"""Is the talker still the person in the photo? dlib's face-recognition distance between a
real portrait and renders of the talker made from it, at rest and in every frame of a sentence.

For each portrait of tests/data/portraits: the talker is made (``face_from_photo_file``, timed),
speaks :data:`SENTENCE` (eSpeak NG, no video), and is rendered at rest and at every frame from
the front and at three-quarters. dlib's ResNet face descriptor (the model file ships in
``face-recognition-models``; 128 numbers, Euclidean distance, under 0.6 the same person by dlib's
own threshold) of each render is compared with the photo's. Prints one JSON line per portrait:
the build time (s), the distance at rest and the largest over the frames in each view, and the
distance of the built-in face's render to the same photo (a different person's face, the
baseline). With ``--sheets DIR`` it writes a sheet per portrait: the photo; the talker at rest,
on the open vowel (the frame of the widest jaw) and on the rounded vowel (the narrowest mouth)
from the front; at rest at three-quarters and in profile.

``python benchmarks/photo_identity.py [--sheets docs/img] [--only obama]``  (needs the
``photo`` extra and eSpeak NG; about a minute a portrait)
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

PORTRAITS = Path(__file__).resolve().parents[1] / "tests" / "data" / "portraits"
SENTENCE = "Pa saw two blue boats."
SIZE = (480, 400)  #: (height, width) of each render, px


class Identity:
    """dlib's face detector, 68-point predictor and ResNet descriptor."""

    def __init__(self):
        import dlib
        import face_recognition_models as m

        self.detector = dlib.get_frontal_face_detector()
        self.shape = dlib.shape_predictor(m.pose_predictor_model_location())
        self.net = dlib.face_recognition_model_v1(m.face_recognition_model_location())

    def descriptor(self, image: np.ndarray) -> np.ndarray | None:
        """(128,) the descriptor of the largest face of an RGB image, or None (no face)."""
        image = np.ascontiguousarray(image[..., :3])
        rects = self.detector(image, 1)
        if not rects:
            return None
        r = max(rects, key=lambda r: r.width())
        return np.array(self.net.compute_face_descriptor(image, self.shape(image, r), 1))


def distance(a, b) -> float:
    return float("nan") if a is None or b is None else float(np.linalg.norm(a - b))


def one(path: Path, ident: Identity, sheets: Path | None) -> dict:
    from facemech.geometry.builder import default_face
    from facemech.io.photo import read_photo
    from facemech.viz.look import look_from_model
    from facemech.viz.render import Renderer
    from facemech.viz.scene import build_scene
    from facemech.workflows.photo import face_from_photo_file
    from facemech.workflows.speak import speak

    photo = read_photo(path)
    ref = ident.descriptor(photo)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        made = face_from_photo_file(path, Path(tmp) / "talker.npz")
        build_s = time.perf_counter() - t0
        spoken = speak(Path(tmp) / "said", SENTENCE, face=Path(tmp) / "talker.npz", video=False)
    model = made.data.model
    look = look_from_model(model)
    scene = build_scene(look)
    views = {v: Renderer(scene, v, SIZE, background="#8a9099")
             for v in ("frontal", "three-quarter", "profile")}
    ds = spoken.dataset
    pos, jaw = ds["positions"].values, ds["jaw_angle"].values
    out = {"portrait": path.name, "build_s": round(build_s, 2), "note": made.data.fit.note()}
    for v in ("frontal", "three-quarter"):
        rest = distance(ref, ident.descriptor(views[v](look.rest)))
        frames = [distance(ref, ident.descriptor(views[v](p, j))) for p, j in zip(pos, jaw,
                                                                                  strict=True)]
        out[v] = {"rest": round(rest, 3), "frames_max": round(float(np.nanmax(frames)), 3),
                  "frames_mean": round(float(np.nanmean(frames)), 3),
                  "frames_missed": int(np.isnan(frames).sum()), "frames": len(frames)}
    builtin = look_from_model(default_face())
    out["built_in_frontal"] = round(distance(ref, ident.descriptor(
        Renderer(build_scene(builtin), "frontal", SIZE, background="#8a9099")(builtin.rest))), 3)
    if sheets is not None:
        _sheet(path, photo, look, views, pos, jaw, model, sheets)
    return out


def _sheet(path, photo, look, views, pos, jaw, model, folder: Path) -> None:
    from PIL import Image

    lm = model.landmarks
    width = np.linalg.norm(pos[:, lm["mouth_corner_left"]] - pos[:, lm["mouth_corner_right"]],
                           axis=1)
    k_open, k_round = int(np.argmax(jaw)), int(np.argmin(width))
    h, w = SIZE
    scale = h / photo.shape[0]
    tiles = [Image.fromarray(photo).resize((int(photo.shape[1] * scale), h), Image.LANCZOS)]
    for view, p, j in (("frontal", look.rest, 0.0), ("frontal", pos[k_open], jaw[k_open]),
                       ("frontal", pos[k_round], jaw[k_round]),
                       ("three-quarter", look.rest, 0.0), ("profile", look.rest, 0.0)):
        tiles.append(Image.fromarray(np.ascontiguousarray(views[view](p, j)[..., :3])))
    sheet = Image.new("RGB", (sum(t.width for t in tiles), h), (255, 255, 255))
    x = 0
    for t in tiles:
        sheet.paste(t, (x, 0))
        x += t.width
    sheet.save(folder / f"photo-talker-{path.stem}.jpg", quality=85)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sheets", type=Path)
    ap.add_argument("--only")
    args = ap.parse_args(argv)
    ident = Identity()
    for path in sorted(PORTRAITS.glob("*.jpg")):
        if args.only and args.only != path.stem:
            continue
        try:
            print(json.dumps(one(path, ident, args.sheets)), flush=True)
        except Exception as exc:  # a portrait that fails is reported, the others go on
            print(json.dumps({"portrait": path.name, "error": str(exc)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
