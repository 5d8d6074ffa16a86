"""What the renderer shows of each part (facemech.viz.visible_parts): the mouth's inside at an
open mouth, nothing of it behind closed lips."""

from __future__ import annotations

import numpy as np
import pytest

from facemech.speech.mouth import midline_lip_pair


@pytest.fixture(scope="module")
def mouth_renderer(face):
    from facemech.viz.render import Renderer
    from facemech.viz.video import scene_of

    return Renderer(scene_of(face), "mouth", (120, 160))


def test_closed_lips_hide_the_inside_and_an_open_mouth_shows_teeth_and_tongue(face,
                                                                             mouth_renderer):
    from facemech.viz.visible_parts import part_pixels

    rest = face.rest_positions[: face.n_surface]
    shut = part_pixels(mouth_renderer, rest)
    for name in ("upper_teeth", "lower_teeth", "tongue", "cavity"):
        assert shut.get(name, 0.0) < 2.0, (name, shut)
    assert shut["skin"] > 1000
    # the lower lip and the skin under it 12 mm down over the middle 30 mm (less further
    # down), the jaw 10 degrees open
    up, lo = face.lip_pairs.T
    st = rest[face.landmarks["stomion"]]
    below = rest[:, 1] < st[1] - 1e-5
    below[lo[lo < face.n_surface]] = True
    below[up[up < face.n_surface]] = False
    x = np.abs(rest[:, 0] - st[0])
    drop = 12e-3 * np.clip((15e-3 - x) / 8e-3, 0.0, 1.0) * np.exp(
        -0.5 * ((st[1] - rest[:, 1]) / 0.02) ** 2)
    p = rest.copy()
    p[below, 1] -= drop[below]
    _, mid, _ = midline_lip_pair(face)
    assert p[mid, 1] == pytest.approx(rest[mid, 1] - 12e-3)
    open_ = part_pixels(mouth_renderer, p, np.radians(10.0))
    assert open_["upper_teeth"] > 50 and open_["tongue"] > 50, open_
    assert sum(open_.values()) == pytest.approx(120 * 160, rel=0.01)  # every pixel once


def test_the_gum_stays_behind_a_chin_pressed_in(face, mouth_renderer):
    """The mentalis presses the skin under the lower lip in (2.5 mm here, over the middle 30
    mm): the lower gum stays behind it (its fold into the lip once showed through as pink
    specks)."""
    from facemech.viz.visible_parts import part_pixels

    rest = face.rest_positions[: face.n_surface]
    st = rest[face.landmarks["stomion"]]
    depth = st[1] - rest[:, 1]
    x = np.abs(rest[:, 0] - st[0])
    push = 2.5e-3 * np.clip((15e-3 - x) / 8e-3, 0.0, 1.0) * np.clip((depth - 0.006) / 0.004,
                                                                      0.0, 1.0) \
        * np.clip((0.035 - depth) / 0.01, 0.0, 1.0)
    p = rest.copy()
    p[:, 2] -= push
    assert part_pixels(mouth_renderer, p).get("lower_gum", 0.0) == 0.0
