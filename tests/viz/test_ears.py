"""The ears seen from the front: a rounded helix rim, standing off the head most in the upper
third, the highest point of the ear not its most lateral (issue 30: they read as pointed)."""

from __future__ import annotations

import numpy as np
import pytest

from facemech.viz.ears import N_S, N_T, STAND_OFF, stand_off
from facemech.viz.scene import build_scene, look_from_model


def _resample(xy, step):
    seg = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.arange(0.0, s[-1], step)
    return np.stack([np.interp(t, s, xy[:, 0]), np.interp(t, s, xy[:, 1])], -1)


@pytest.fixture(scope="module")
def scene(face):
    return build_scene(look_from_model(face))


@pytest.mark.parametrize("side", ["left", "right"])
def test_the_helix_rim_is_round_from_the_front(scene, side):
    """The rim (the helix's edge) projected on the frontal plane (lateral, up), resampled
    every millimetre: no vertex turns it by more than 75 degrees (measured 61-62 at the
    top; before 128-157, a point), nor does any 3 mm of it turn by more than 100 degrees
    (measured 80; before 141-199), except where the lobe grows into the head; the top of the
    ear stands off less than its widest part (measured 9 of 17 mm; before the top was the
    widest)."""
    part = next(p for p in scene.parts if p.name == "ear_" + side)
    rim = part.rest.reshape(N_S + 1, N_T, 3)[-1]
    xy = _resample(np.stack([np.abs(rim[:, 0]), rim[:, 1]], -1) * 1e3, 1.0)
    d = np.diff(xy, axis=0)
    a = np.arctan2(d[:, 1], d[:, 0])
    turn = np.degrees(np.abs((np.diff(a) + np.pi) % (2 * np.pi) - np.pi))
    free = slice(0, int(0.85 * len(turn)))  # the lobe's front meets the head after this
    assert turn[free].max() < 75.0, turn[free].max()
    assert np.convolve(turn[free], np.ones(3), "valid").max() < 100.0
    top = np.argmax(xy[:, 1])
    root = xy[:, 0].min()
    assert xy[top, 0] - root < 0.6 * (xy[:, 0].max() - root)


def test_the_ear_stands_off_most_in_its_upper_third():
    """The rim's stand-off: largest (STAND_OFF, 17 mm) in the upper third, about half that at
    the top of the helix and less again at the lobe; within the 15-20 mm of adult ears'
    helix-to-mastoid distance at its largest."""
    from facemech.viz.ears import outline

    t = np.linspace(0.0, 1.0, 401)
    s = stand_off(t)
    _, y = outline(t)
    assert 15.0 <= STAND_OFF <= 20.0
    widest = y[np.argmax(s)]
    assert y.min() + 2 * np.ptp(y) / 3 - 5 <= widest <= y.max()
    top = np.argmax(y)
    assert 0.3 * STAND_OFF < s[top] < 0.7 * STAND_OFF
    assert s[-1] < 0.7 * STAND_OFF
