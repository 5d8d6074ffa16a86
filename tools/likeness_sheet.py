"""The built-in head's sheet for docs/rendering.md: rest, the open vowel and a smile, frontal,
three-quarter and profile.

    PYTHONPATH=src python tools/likeness_sheet.py DEMO.nc SMILE.nc OUT.jpg

DEMO.nc: ``facemech demo``'s results (the open vowel: its frame of the widest jaw angle);
SMILE.nc: ``facemech simulate --activity smile.csv`` with ZYG 0.9 and RIS 0.5 held (its last
frame). Run with another checkout's src first on the path for its sheet.
"""

from __future__ import annotations

import sys

import numpy as np


def main(argv: list[str]) -> None:
    from PIL import Image

    from facemech.io.results import read_results
    from facemech.viz.scene import build_scene, look_from_dataset
    from facemech.viz.sheet import Block, contact_sheet
    from facemech.viz.video import jaw_poses_of

    demo, smile = read_results(argv[0]), read_results(argv[1])
    scene = build_scene(look_from_dataset(demo))
    jaw = jaw_poses_of(demo)
    if jaw is None:
        k = len(demo.time) // 2
    else:
        a = np.asarray(jaw, float)
        k = int(np.argmax(a if a.ndim == 1 else a[:, 0]))
    s_jaw = jaw_poses_of(smile)
    frames = [(demo.positions.values[0], jaw[0] if jaw is not None else 0.0),
              (demo.positions.values[k], jaw[k] if jaw is not None else 0.0),
              (smile.positions.values[-1], s_jaw[-1] if s_jaw is not None else 0.0)]
    t = float(demo.time.values[k])
    labels = ["rest", f"open vowel (t = {t:.2f} s)", "smile (ZYG 0.9, RIS 0.5)"]
    img = contact_sheet([Block(scene, frames, labels, "built-in head (facemech)")])
    Image.fromarray(img).save(argv[2], quality=88)


if __name__ == "__main__":
    main(sys.argv[1:])
