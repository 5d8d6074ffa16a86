"""A textured face's eyes: its fissures cut from its own image, its lids and iris in its colours
(:mod:`facemech.viz.fissures`), so that a scan or a photo talker blinks and looks around."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from facemech.viz import textures as T

SKIN = np.array([0.80, 0.62, 0.52])  #: the lids' skin painted on the test image
IRIS = np.array([0.20, 0.35, 0.55])  #: a blue iris
WHITE = np.array([0.95, 0.95, 0.93])
LASH = np.array([0.10, 0.07, 0.06])


@pytest.fixture(scope="module")
def flat():
    return _flat()


def _flat():
    """The built-in face's look with a frontal texture map (u, v from the rest x, y), its image
    (h, w) and the map's texel centres in model x, y."""
    from facemech.geometry.builder import default_face
    from facemech.viz.look import look_from_model

    face = default_face()
    look = look_from_model(face)
    xy = look.rest[:, :2]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    uv = ((xy - lo) / (hi - lo))[face.faces]
    h, w = 1100, 900
    x = lo[0] + (np.arange(w) + 0.5) / w * (hi[0] - lo[0])
    y = lo[1] + (1.0 - (np.arange(h) + 0.5) / h) * (hi[1] - lo[1])
    X, Y = np.meshgrid(x, y)
    texel = float(max((hi - lo) / [w, h]))
    return look, uv, X, Y, texel


def _painted(look, X, Y, offset=(0.0, 0.0)):
    """An image (h, w, 3) in [0, 1]: skin; in each fissure (its centre ``offset`` (2,) m from
    the eye's landmark) white with an iris 5 mm across the eye's centre (a pupil 1.5 mm); a
    white band 0.6 mm past the fissure's margin (a photo's eye white beyond the drawn fissure)
    and a lash line 1.2-1.4 mm past it. Returns the image and per eye the depth (m) of every
    texel in the fissure (> 0 inside)."""
    img = np.broadcast_to(SKIN, X.shape + (3,)).copy()
    depth = {}
    for side, name in ((1, "eye_left"), (-1, "eye_right")):
        e = look.landmarks[name] + np.array([*offset, 0.0])
        m = T.eye_mask(X, Y, e, side)
        depth[name] = m
        r = np.hypot(X - e[0], Y - e[1])
        img[(m > -0.0006)] = WHITE
        img[(m > 0) & (r < 0.005)] = IRIS
        img[(m > 0) & (r < 0.0015)] = 0.02
        img[(m < -0.0012) & (m > -0.0014)] = LASH
    return img, depth


def _cut(look, uv, img):
    from facemech.viz.fissures import cut_fissures

    return cut_fissures(replace(look, uv=uv, image=(img * 255).astype(np.uint8)), img)


def _depths(cut, X, Y):
    """Per eye the fissure's depth (m) at every texel, about the centre the cut took."""
    return {name: T.eye_mask(X, Y, cut.eyes[name], side)
            for side, name in ((1, "eye_left"), (-1, "eye_right"))}


@pytest.mark.parametrize("offset_mm", [(0.0, 0.0), (1.5, -1.0), (-2.0, 2.5)])
def test_the_fissure_is_moved_onto_the_textures_eye(flat, offset_mm):
    """An eye painted up to 3 mm from its landmark (a fitted mesh's landmark on a node, a
    scan's annotated by hand) is found: the cut's centre within one step (0.5 mm) of it."""
    from facemech.viz.fissures import SHIFT_STEP

    look, uv, X, Y, texel = flat
    off = np.array([*offset_mm, 0.0]) * 1e-3
    cut = _cut(look, uv, _painted(look, X, Y, off[:2])[0])
    for name in ("eye_left", "eye_right"):
        miss = cut.eyes[name] - (look.landmarks[name] + off)
        assert np.abs(miss).max() <= SHIFT_STEP + 1e-9, (name, miss)


def test_the_cut_is_the_fissure_and_nothing_else(flat):
    """alpha < 1/2 exactly where the fissure's depth (about the centre found) is positive, but
    for the texels within one texel of its margin (the cut ramps over two texels); 1 everywhere
    away from the eyes."""
    look, uv, X, Y, texel = flat
    cut = _cut(look, uv, _painted(look, X, Y)[0])
    alpha = cut.alpha
    inside = np.zeros(X.shape, bool)
    sure = np.ones(X.shape, bool)
    for m in _depths(cut, X, Y).values():
        inside |= m > 0
        sure &= np.abs(m) > 1.01 * texel
    assert inside.sum() > 1000
    np.testing.assert_array_equal(alpha[sure] < 0.5, inside[sure])
    assert np.all(alpha[inside & sure] == 0.0)
    # the cheeks keep their skin
    for name in ("cheek_left", "cheek_right", "nose_tip"):
        c = look.landmarks[name]
        near = np.hypot(X - c[0], Y - c[1]) < 0.01
        assert np.all(alpha[near] == 1.0)


def test_the_lids_and_iris_take_the_images_colours_and_the_rim_its_skin(flat):
    from facemech.viz.fissures import RIM

    look, uv, X, Y, texel = flat
    img, _ = _painted(look, X, Y)
    cut = _cut(look, uv, img)
    depths = _depths(cut, X, Y)
    white = np.all(img == WHITE, axis=-1)
    for side, name in ((1, "eye_left"), (-1, "eye_right")):
        c = cut.colours[name]
        np.testing.assert_allclose(c.lid, SKIN, atol=0.01)
        np.testing.assert_allclose(c.iris, IRIS, atol=0.01)
        # the eye white past the cut's margin, within the rim, is painted with the lids' skin
        m = depths[name]
        s, _ = T.eye_frame(X, Y, cut.eyes[name], side)
        rim = white & (m < -1.5 * texel) & (m > -RIM[0]) & (np.abs(s) < 0.95)
        assert rim.sum() > 200
        np.testing.assert_allclose(cut.image[rim], np.broadcast_to(SKIN, (rim.sum(), 3)),
                                   atol=1e-9)
    # the lash lines (darker than the skin) stay, and beyond the rims nothing changes
    lash = np.all(img == LASH, axis=-1)
    assert lash.sum() > 100
    np.testing.assert_allclose(cut.image[lash], img[lash], atol=1e-12)
    far = np.logical_and.reduce([m < -RIM[1] - texel for m in depths.values()])
    np.testing.assert_allclose(cut.image[far], img[far], atol=1e-12)


def test_a_clipped_iris_takes_the_other_eyes_colour(flat):
    """A photo's texture can lose one iris's dark channels (the renderer's highlight taken out
    of it, :mod:`facemech.viz.photo_texture`): both eyes take the iris of the eye whose texels
    are not clipped."""
    look, uv, X, Y, texel = flat
    img, depth = _painted(look, X, Y)
    e = look.landmarks["eye_right"]
    spoilt = (depth["eye_right"] > 0) & (np.hypot(X - e[0], Y - e[1]) < 0.005)
    img[spoilt] = (0.30, 0.12, 0.0)
    cut = _cut(look, uv, img)
    for name in ("eye_left", "eye_right"):
        np.testing.assert_allclose(cut.colours[name].iris, IRIS, atol=0.01)


@pytest.mark.slow
def test_a_textured_face_gets_eyes_and_a_vertex_coloured_one_keeps_them_painted(flat):
    from facemech.viz.scene import build_scene

    look, uv, X, Y, texel = flat
    img, _ = _painted(look, X, Y)
    textured = replace(look, uv=uv, image=(img * 255).astype(np.uint8))
    names = [p.name for p in build_scene(textured).parts]
    for part in ("eye_left", "eye_right", "lid_left", "lid_right", "lower_lid_left"):
        assert part in names
    skin = build_scene(textured).parts[0]
    assert skin.alpha_test and skin.texture[..., 3].min() == 0.0
    # without eyes the image is drawn whole
    skin = build_scene(textured, eyes=False).parts[0]
    assert not skin.alpha_test and skin.texture[..., 3].min() == 1.0
    coloured = replace(look, vertex_colours=np.full((len(look.rest), 3), 200, np.uint8))
    assert not any(p.name.startswith(("eye", "lid")) for p in build_scene(coloured).parts)
    # the lids are drawn in the image's skin (the generic albedo scaled by it)
    lid = next(p for p in build_scene(textured).parts if p.name == "lid_left")
    generic = next(p for p in build_scene(look).parts if p.name == "lid_left")
    np.testing.assert_allclose(lid.albedo, np.clip(generic.albedo * SKIN / T.SKIN, 0, 1),
                               atol=0.01)
