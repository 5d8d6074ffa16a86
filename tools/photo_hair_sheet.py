"""Draw docs/img/photo-hair.jpg: the real portraits beside their talkers, for the hair's colour.

For each portrait of tests/data/portraits (astronaut, obama, obama2, biden): the photo's head
(cropped round the face, 320 px high), the talker at rest from the front (320 px high), and a
swatch of the hair colour measured on the photo (:func:`facemech.viz.photo_hair.hair_colour`).

Usage::

    PYTHONPATH=src python tools/photo_hair_sheet.py [docs/img/photo-hair.jpg]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from facemech.io.photo import DlibDetector, frontal_landmarks, read_photo
from facemech.viz.look import look_from_model
from facemech.viz.render import Renderer
from facemech.viz.scene import build_scene
from facemech.workflows.photo import face_from_photo

PORTRAITS = Path(__file__).parents[1] / "tests" / "data" / "portraits"
NAMES = ("astronaut", "obama", "obama2", "biden")
HEIGHT = 320


def _head(photo: np.ndarray, points: np.ndarray) -> Image.Image:
    """The photo cropped round the head (the jaw's width 1.6 times across), HEIGHT px high."""
    w = float(np.linalg.norm(points[16] - points[0]))
    cx, cy = points[:, 0].mean(), points[:, 1].mean() - 0.35 * w
    box = (cx - 0.8 * w, cy - 1.0 * w, cx + 0.8 * w, cy + 1.0 * w)
    im = Image.fromarray(photo).crop(tuple(int(round(c)) for c in box))
    return im.resize((int(HEIGHT * 0.8), HEIGHT), Image.LANCZOS)


def main(path: str = "docs/img/photo-hair.jpg") -> None:
    detector = DlibDetector()
    rows = []
    for name in NAMES:
        photo = read_photo(PORTRAITS / f"{name}.jpg")
        points = frontal_landmarks(photo, source=name, detector=detector).points
        made = face_from_photo(photo, points=points, source=name)
        look = look_from_model(made.model)
        talker = Renderer(build_scene(look), "frontal", (HEIGHT, int(HEIGHT * 0.8)),
                          background="#8a9099")(look.rest)[..., :3]
        swatch = np.zeros((HEIGHT, 40, 3), np.uint8)
        swatch[:] = 255 if made.texture.hair is None else made.texture.hair
        print(f"{name}: {made.texture.note}")
        rows.append(np.concatenate([np.asarray(_head(photo, points)), talker, swatch], axis=1))
    Image.fromarray(np.concatenate(rows, axis=1)).save(path, quality=88)


if __name__ == "__main__":
    main(*sys.argv[1:])
