"""Draw a scan talker's sheet: at rest, on the open vowel (the widest jaw) and on the rounded
vowel (the narrowest mouth) from the front; at rest at three-quarters and in profile.

Usage::

    facemech face build tests/data/scans/james.obj tests/data/scans/james.ljson --units auto \\
        -o james.npz
    facemech speak "Pa saw two blue boats." --face james.npz --no-video --no-plan -o said
    PYTHONPATH=src python tools/scan_sheet.py james.npz said/result.nc scan-talker-james.jpg
"""

from __future__ import annotations

import sys

import numpy as np
from PIL import Image


def main(face: str, results: str, out: str) -> None:
    from facemech.geometry.model import FaceModel
    from facemech.io.results import read_results
    from facemech.viz.look import look_from_model
    from facemech.viz.render import Renderer
    from facemech.viz.scene import build_scene

    model = FaceModel.load(face)
    ds = read_results(results)
    pos, jaw = ds["positions"].values, ds["jaw_angle"].values
    lm = model.landmarks
    width = np.linalg.norm(pos[:, lm["mouth_corner_left"]] - pos[:, lm["mouth_corner_right"]],
                           axis=1)
    k_open, k_round = int(np.argmax(jaw)), int(np.argmin(width))
    look = look_from_model(model)
    scene = build_scene(look)
    tiles = []
    for view, p, j in (("frontal", look.rest, 0.0), ("frontal", pos[k_open], jaw[k_open]),
                       ("frontal", pos[k_round], jaw[k_round]),
                       ("three-quarter", look.rest, 0.0), ("profile", look.rest, 0.0)):
        r = Renderer(scene, view, (480, 400), background="#8a9099")
        tiles.append(np.ascontiguousarray(r(p, j)[..., :3]))
    Image.fromarray(np.concatenate(tiles, axis=1)).save(out, quality=85)


if __name__ == "__main__":
    main(*sys.argv[1:])
