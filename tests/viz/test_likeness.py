"""The built-in head as a person: Farkas' proportions on the drawn mesh, nostrils and lashes in
the frontal 720p render (per-part pixel counts), a sclera that is not white and is redder at
the corners, ears in relief, and folds that deepen with a smile; the simulated skin is never
moved by any of it."""

from __future__ import annotations

import numpy as np
import pytest

from facemech.viz.camera import Camera, view_camera, view_rotation
from facemech.viz.proportions import FARKAS, head_measures
from facemech.viz.render import class_pixels, parse_background, part_labels, render_panel
from facemech.viz.scene import build_scene, look_from_model


@pytest.fixture(scope="module")
def scene(face):
    return build_scene(look_from_model(face))


def _frontal(scene, size=(720, 1280)):
    """The frontal frame at rest: rgb (h, w, 3) float 0-255, part labels (h, w), names."""
    look = scene.look
    verts, norms = scene.frame(look.rest)
    cam = view_camera("frontal", scene.framing, size)
    img = render_panel(scene, verts, norms, cam, background=parse_background("#ffffff"),
                       supersample=1)[..., :3].astype(float)
    return img, part_labels(scene, verts, cam), [p.name for p in scene.parts] + ["inside"]


def test_head_proportions_within_one_sd_of_farkas(scene):
    """Head length, face height, nose and mouth width of the drawn head within one SD of
    Farkas' adult male norms (measured 196.5, 120.2, 34.0, 53.6 mm; the simulated skin's
    own mouth is 50.5 mm wide, widened on the render side)."""
    m = head_measures(scene)
    assert set(m) == set(FARKAS)
    for k, (mean, sd) in FARKAS.items():
        assert abs(m[k] - mean) <= sd, (k, m[k], mean, sd)


def test_nostrils_and_lashes_show_in_the_frontal_render(scene):
    """At 720p, frontal, at rest: dark nostril pixels (the nasal base's openings, under 0.4
    of the skin's median luminance; measured 124) and lash pixels on each eye (measured 128,
    123, the lashes foreshortened over the margin); from below (55 degrees) the nostrils are
    larger (measured 490 at 360 px over 60 mm)."""
    img, labels, names = _frontal(scene)
    lum = img.mean(axis=-1)
    skin = np.median(lum[labels == names.index("skin")])
    nostril = (labels == names.index("nostrils")) & (lum < 0.4 * skin)
    assert nostril.sum() > 60
    counts = class_pixels(scene, scene.look.rest)
    assert counts["lashes_left"] > 100 and counts["lashes_right"] > 100, counts
    verts, norms = scene.frame(scene.look.rest)
    below = Camera(view_rotation(0.0, -55.0), np.array([0.0, -0.05, 0.0]), 0.03, (360, 360),
                   1.2)
    img = render_panel(scene, verts, norms, below, background=parse_background("#ffffff"),
                       supersample=1)[..., :3].astype(float)
    lab = part_labels(scene, verts, below)
    assert ((lab == names.index("nostrils")) & (img.mean(axis=-1) < 0.4 * skin)).sum() > 300


def test_the_sclera_is_not_white_and_redder_at_the_corners(scene):
    """The white of the left eye, frontal (24 mm over 240 px, outside the iris): no channel
    over 235 on average, red > green > blue, and red over green larger towards the canthi
    than beside the iris (measured 198/187/177 there, 202/179/170 at the corners)."""
    look = scene.look
    e = look.landmarks["eye_left"]
    verts, norms = scene.frame(look.rest)
    cam = Camera(view_rotation(0.0, 0.0), e, 0.012, (240, 320), 1.2)
    img = render_panel(scene, verts, norms, cam, background=parse_background("#00ff00"),
                       supersample=1)[..., :3].astype(float)
    names = [p.name for p in scene.parts]
    eye = part_labels(scene, verts, cam) == names.index("eye_left")
    c = cam.project(e[None])[0]
    yy, xx = np.mgrid[0:240, 0:320]
    pixel = 2 * 0.012 / 240
    dx = (xx + 0.5 - c[0]) * pixel
    sclera = eye & (np.hypot(dx, (yy + 0.5 - c[1]) * pixel) > 0.0065)
    middle, corner = sclera & (np.abs(dx) < 0.009), sclera & (np.abs(dx) > 0.010)
    assert middle.sum() > 1000 and corner.sum() > 1000
    m, k = img[middle].mean(axis=0), img[corner].mean(axis=0)
    assert m.max() < 235 and m[0] > m[1] > m[2], m
    assert k[0] - k[1] > (m[0] - m[1]) + 5, (m, k)


def test_the_ears_are_in_relief(scene):
    """Over each ear's front (past the root), the normals turn: median 26, 90th percentile
    47 degrees from their mean (a flat flap: a few degrees); the ears show in the frontal
    render (measured 3019 and 2563 px at 720p)."""
    from facemech.geometry.builder import vertex_normals
    from facemech.viz.ears import N_S, N_T

    for side in ("left", "right"):
        p = next(q for q in scene.parts if q.name == "ear_" + side)
        n = vertex_normals(p.rest, p.faces).reshape(N_S + 1, N_T, 3)[2:].reshape(-1, 3)
        mean = n.mean(axis=0) / np.linalg.norm(n.mean(axis=0))
        angle = np.degrees(np.arccos(np.clip(n @ mean, -1.0, 1.0)))
        assert np.percentile(angle, 50) > 15 and np.percentile(angle, 90) > 35
    counts = class_pixels(scene, scene.look.rest)
    assert counts["ear_left"] > 1000 and counts["ear_right"] > 1000


def test_folds_deepen_when_the_skin_is_compressed_and_the_physics_is_untouched(scene):
    """A smile-like frame (each mouth corner's neighbourhood moved 8 mm up and out towards the
    cheek): the nasolabial folds' drawn nodes sink deeper than at rest; the skin handed to the
    scene is not changed."""
    look = scene.look
    rest = look.rest.copy()
    folds = scene.shape.folds
    lm = look.landmarks
    moved = rest.copy()
    for k, side in (("mouth_corner_left", 1), ("mouth_corner_right", -1)):
        w = np.exp(-0.5 * (np.linalg.norm(rest[:, :2] - lm[k][:2], axis=1) / 0.012) ** 2)
        moved += w[:, None] * np.array([side * 0.005, 0.006, 0.0])
    before = moved.copy()
    at_rest, smiling = folds.depth(rest), folds.depth(moved)
    nasolabial = folds.line > 0.5
    assert smiling[nasolabial].min() < at_rest[nasolabial].min() - 0.0005
    scene.frame(moved)
    assert np.array_equal(moved, before)
