"""The built-in head: one surface from the crown to the neck, with no visible edge where the
physics face meets the rest of the head, in any view, at rest and with the jaw open."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from conftest import activity
from facemech.solvers.forward import simulate
from facemech.viz.camera import view_camera
from facemech.viz.closure import closed_surface
from facemech.viz.raster import rasterise
from facemech.viz.render import parse_background, render_panel
from facemech.viz.scene import build_scene, look_from_model

VIEWS = ("frontal", "three-quarter", "profile")


@pytest.fixture(scope="module")
def head(face):
    """The scene of the built-in face, its skin at rest and with the jaw opened to 15 deg."""
    n = 6
    jaw = np.radians(15.0) * np.linspace(0, 1, n)
    sim = simulate(face, activity(n), jaw)
    look = look_from_model(face)
    return build_scene(look), [(look.rest, 0.0), (sim.positions[-1], float(jaw[-1]))]


def _labels(scene, verts, cam):
    """Per pixel: the part index seen (-1 none; inner sides -2) and the camera depth (m)."""
    h, w = cam.size
    p = cam.project(verts, 1)
    z = np.full((h, w), -np.inf, np.float32)
    tid = np.full((h, w), -1, np.int32)
    bary = np.empty((h, w, 2), np.float32)
    rasterise(p[:, 0], p[:, 1], p[:, 2], scene.tris, scene.uv, scene.tex, scene.alpha_test,
              scene.two_sided, scene.atlas, z, tid, bary)
    nt = len(scene.tris)
    face_part = np.repeat(np.arange(len(scene.parts)),
                          [len(q.faces) for q in scene.parts])
    part = np.where(tid < 0, -1, np.where(tid >= nt, -2, face_part[np.minimum(tid, nt - 1)]))
    return part, np.where(np.isfinite(z), z, -1e3)


def _neighbour_steps(img, part, z, a, b, region=None):
    """Largest colour step (max over RGB, 0-255) between 4-neighbours labelled ``a`` and
    ``b`` that lie within 2 mm of each other in depth (a surface, not an occluding contour),
    and how many such pairs there are; ``region`` limits both pixels to a mask."""
    img = img[..., :3].astype(int)
    steps, count = [0], 0
    for sl0, sl1 in (((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
                     ((slice(None, -1), slice(None)), (slice(1, None), slice(None)))):
        p0, p1 = part[sl0], part[sl1]
        ok = (((p0 == a) & (p1 == b)) | ((p0 == b) & (p1 == a)))
        ok &= np.abs(z[sl0] - z[sl1]) < 0.002
        if region is not None:
            ok &= region[sl0] & region[sl1]
        d = np.abs(img[sl0] - img[sl1]).max(axis=-1)[ok]
        steps.append(int(d.max()) if d.size else 0)
        count += int(ok.sum())
    return max(steps), count


@pytest.mark.parametrize("view", VIEWS)
def test_no_edge_where_the_face_meets_the_head(head, view):
    """Across the old mask boundary (skin pixels next to head pixels on the same surface) no
    step in colour is larger than the largest step between neighbouring pixels of the cheek."""
    scene, frames = head
    names = [p.name for p in scene.parts]
    skin, head_part = names.index("skin"), names.index("head")
    lm = scene.look.landmarks
    for pos, jaw in frames:
        verts, norms = scene.frame(pos, jaw)
        cam = view_camera(view, scene.framing, (480, 400))
        img = render_panel(scene, verts, norms, cam, background=parse_background("#2a2c33"),
                           supersample=1)
        part, z = _labels(scene, verts, cam)
        seam, n_seam = _neighbour_steps(img, part, z, skin, head_part)
        # the cheek: skin pixels within 15 mm of the cheek landmark that faces the camera
        side = "cheek_right" if view != "frontal" else "cheek_left"
        c = cam.project(lm[side][None])[0]
        yy, xx = np.mgrid[0:480, 0:400]
        px_per_m = 0.5 * 480 / cam.half_height
        near = np.hypot(xx + 0.5 - c[0], yy + 0.5 - c[1]) < 0.015 * px_per_m
        cheek, n_cheek = _neighbour_steps(img, part, z, skin, skin, near)
        assert n_seam > 30 and n_cheek > 500, (view, n_seam, n_cheek)  # both are seen
        assert seam <= cheek, (view, np.degrees(jaw), seam, cheek)


def test_head_and_skin_are_one_closed_surface(head):
    """The closure's edge ring is the skin's edge; skin and closure (the mouth cut closed as
    the lips are at rest) make one watertight, consistently wound surface enclosing the head's
    volume, at rest and with the jaw open."""
    scene, frames = head
    closure = next(p.follow for p in scene.parts if p.motion == "follow")
    look = scene.look
    for pos, jaw in frames:
        verts, _ = scene.frame(pos, jaw)
        cv = verts[scene.offsets[[p.name for p in scene.parts].index("head")]:][
            :len(closure.rest)]
        e = len(closure.loop)
        assert np.array_equal(cv[:e], pos[closure.loop])  # shared, not copied nearby
        v, f = closed_surface(pos, closure, look.triangles, look.rest)
        mesh = trimesh.Trimesh(v, f, process=False)
        assert mesh.is_watertight and mesh.is_winding_consistent
        assert mesh.euler_number == 2  # a sphere's topology: no handle, no second shell
        # an adult head and neck: 4 to 8 litres (the neck cut 300 mm under the head's centre)
        assert 0.004 < mesh.volume < 0.008, mesh.volume
