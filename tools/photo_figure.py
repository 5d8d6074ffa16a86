"""Draw docs/img/photo-talker.jpg: a talker from photos of a face of known shape.

The test face of tests/viz/test_photo.py (the built-in face with a wider mouth, a longer lower face
and a nose 6 mm longer), rendered from the front and in profile; the talker made from both
photos (dlib's landmarks, the IPD given) rendered through the front photo's fitted camera and
at three-quarters. The panels, left to right: the front photo with dlib's 68 points, the
profile, the re-rendered talker, the talker at three-quarters.

Usage::

    PYTHONPATH=src:tests:tests/viz python tools/photo_figure.py [docs/img/photo-talker.jpg]
"""

from __future__ import annotations

import sys

import numpy as np
from PIL import Image, ImageDraw

import test_photo as T  # tests/viz/test_photo.py: the test faces and the re-render
from facemech.geometry.builder import build_face, default_surface, tissue_options
from facemech.geometry.ibug import generic_ibug68
from facemech.io.photo import DlibDetector, frontal_landmarks
from facemech.viz.look import look_from_model
from facemech.viz.render import Renderer
from facemech.viz.scene import build_scene


def main(path: str = "docs/img/photo-talker.jpg") -> None:
    v, f, lm = default_surface()
    lm = {k: T._variant(x) for k, x in lm.items()}
    model = build_face(T._variant(v), f, lm, name="variant", options=tissue_options("uniform"))
    subject = T.Subject(model, lm, T._variant(generic_ibug68()))
    found = frontal_landmarks(subject.front, source="front", detector=DlibDetector())
    made = T._fit(subject, found.points, profile=True)
    marked = Image.fromarray(subject.front.copy())
    draw = ImageDraw.Draw(marked)
    for x, y in found.points:
        draw.ellipse([x - 3, y - 3, x + 3, y + 3], fill=(40, 230, 90))
    look = look_from_model(made.model)
    turned = Renderer(build_scene(look), "three-quarter", T.SIZE,
                      background="#8a9099")(look.rest)[..., :3]
    tiles = [marked, Image.fromarray(subject.profile), Image.fromarray(T._rerender(made)),
             Image.fromarray(np.ascontiguousarray(turned))]
    sheet = Image.new("RGB", (sum(t.width for t in tiles), T.SIZE[0]), (255, 255, 255))
    x = 0
    for t in tiles:
        sheet.paste(t, (x, 0))
        x += t.width
    sheet.resize((sheet.width // 2, sheet.height // 2), Image.LANCZOS).save(path, quality=85)
    print(f"{made.fit.note()} -> {path}")


if __name__ == "__main__":
    main(*sys.argv[1:])
