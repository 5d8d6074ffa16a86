"""A contact sheet of talkers: each talker's frames in frontal, three-quarter and profile views.

The sheet of docs/rendering.md shows the built-in head at rest and mid-sentence; further
talkers (a photo's, a scan's) are further column blocks of the same sheet, labelled, side by
side, so one picture compares them view by view.

    python -m facemech.viz.sheet RESULT.nc OUT.jpg [--times 0 0.98 1.52]

draws the results' talker at the given times (s; default: rest, the /a/ of "ma" and the
/u/ of "wu" of the demo's utterance).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

VIEWS = ("frontal", "three-quarter", "profile")


@dataclass(frozen=True)
class Block:
    """One talker's columns: a scene, its frames and their labels.

    Attributes
    ----------
    scene : :class:`facemech.viz.scene.Scene`
    frames : [(skin (n, 3) m, jaw angle rad or (3,) pose), ...]
    labels : one caption per frame
    title : the talker's name, over its block
    """

    scene: object
    frames: list
    labels: list
    title: str


def contact_sheet(blocks: list[Block], panel: tuple[int, int] = (360, 300),
                  views: tuple[str, ...] = VIEWS, background: str = "#ffffff",
                  supersample: int = 3) -> np.ndarray:
    """(H, W, 3) uint8: a row per view, a column per frame, blocks side by side with their
    titles and captions (a 28-px band above each block)."""
    from PIL import Image, ImageDraw

    from .render import Renderer

    h, w = panel
    band = 28
    columns = []
    for b in blocks:
        rows = []
        for view in views:
            r = Renderer(b.scene, view, (h, w), background=background, supersample=supersample)
            rows.append(np.concatenate([r(skin, jaw)[..., :3] for skin, jaw in b.frames], 1))
        img = np.concatenate(rows, 0)
        head = Image.new("RGB", (img.shape[1], 2 * band), background)
        d = ImageDraw.Draw(head)
        d.text((6, 4), b.title, fill=(20, 20, 20))
        for k, lab in enumerate(b.labels):
            d.text((k * w + 6, band + 4), lab, fill=(60, 60, 60))
        columns.append(np.concatenate([np.asarray(head), img], 0))
        columns.append(np.full((columns[-1].shape[0], 8, 3), 255, np.uint8))
    return np.concatenate(columns[:-1], 1)


def _frame_at(ds, t: float):
    from .video import jaw_poses_of

    k = int(np.argmin(np.abs(ds.time.values - t)))
    jaw = jaw_poses_of(ds)
    return ds.positions.values[k], (0.0 if jaw is None else jaw[k]), float(ds.time.values[k])


def main(argv=None) -> None:
    from PIL import Image

    from ..io.results import read_results
    from .scene import build_scene, look_from_dataset

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results")
    ap.add_argument("output")
    ap.add_argument("--times", type=float, nargs="+", default=[0.0, 0.98, 1.52])
    ap.add_argument("--title", default="built-in head (facemech)")
    args = ap.parse_args(argv)
    ds = read_results(args.results)
    scene = build_scene(look_from_dataset(ds))
    frames, labels = [], []
    for t in args.times:
        skin, jaw, tk = _frame_at(ds, t)
        frames.append((skin, jaw))
        ang = float(np.degrees(np.atleast_1d(jaw)[0]))
        labels.append("rest" if tk == 0.0 else f"t = {tk:.2f} s, jaw {ang:.0f} deg")
    img = contact_sheet([Block(scene, frames, labels, args.title)])
    Image.fromarray(img).save(args.output, quality=88)


if __name__ == "__main__":
    main()
