"""Draw docs/img/alive-blink.jpg: the built-in face open, at a blink's middle, and with its
head and eyes turned (facemech.speech.alive's series, as the movie of ``speak`` draws them).

Panels, left to right: at rest (closure 0); the blink's middle (closure 1, the frame 90 ms after
its onset, :data:`facemech.speech.alive.BLINK_CLOSE_S` + half the hold); the head raised 3
degrees and turned 4 degrees to its left, the eyes 3 degrees to the left (the largest of
``speak``'s head motion and gaze shifts are of this size).

Usage::

    PYTHONPATH=src python tools/alive_figure.py [docs/img/alive-blink.jpg]
"""

from __future__ import annotations

import sys

import numpy as np
from PIL import Image, ImageDraw

from facemech import default_face
from facemech.speech import alive as A
from facemech.viz.render import RenderOptions
from facemech.viz.scene import build_scene, look_from_model


def main(path: str = "docs/img/alive-blink.jpg") -> None:
    scene = build_scene(look_from_model(default_face()))
    rend = RenderOptions(view="frontal", size=(400, 320), supersample=2).renderer(scene)
    rest = scene.look.rest
    mid = A.BLINK_CLOSE_S + A.BLINK_HOLD_S / 2  # s after the onset
    closure = float(A.blink_closure([mid], [0.0])[0])
    panels = [("open", rend(rest, 0.0)),
              (f"blink, {1000 * mid:.0f} ms in", rend(rest, 0.0, closure)),
              ("head 3 deg up, 4 deg left", rend(rest, 0.0, 0.0, np.radians((3.0, 0.0)),
                                                 np.radians((3.0, 4.0, 0.0))))]
    img = Image.fromarray(np.concatenate([p[1][..., :3] for p in panels], axis=1))
    draw = ImageDraw.Draw(img)
    for k, (label, _) in enumerate(panels):
        draw.text((k * 320 + 8, 6), label, fill=(235, 235, 235))
    img.save(path, quality=85)
    print(f"wrote {path}: blink closure {closure:.2f} at {1000 * mid:.0f} ms")


if __name__ == "__main__":
    main(*sys.argv[1:])
