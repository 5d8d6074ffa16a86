"""The built-in head: one surface from the crown to the neck, with no visible edge where the
physics face meets the rest of the head, in any view, at rest and with the jaw open."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy import ndimage

from conftest import activity, seen_triangles
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.viz.camera import view_camera
from facemech.viz.closure import closed_surface
from facemech.viz.raster import rasterise
from facemech.viz.render import parse_background, render_panel
from facemech.viz.scene import build_scene, look_from_model

VIEWS = ("frontal", "three-quarter", "profile")


@pytest.fixture(scope="module")
def head(face):
    """The scene of the built-in face, its skin at rest and with the jaw opened to 15 deg (in
    100 ms, held 100 ms: at the instant a jaw that fast stops, the skin under the chin creases
    for a moment, a colour step of 15 there against the cheek's 11, measured; 4 once held)."""
    n = 12
    jaw = np.radians(15.0) * np.minimum(np.arange(n) / 5, 1.0)
    sim = simulate(face_model(face), activity(n), jaw)
    look = look_from_model(face)
    return build_scene(look), [(look.rest, 0.0), (sim.positions[-1], float(jaw[-1]))]


def _labels(scene, verts, cam):
    """Per pixel: the part index seen (-1 none; inner sides -2) and the camera depth (m)."""
    z, tid = seen_triangles(scene, verts, cam)
    nt = len(scene.tris)
    face_part = np.repeat(np.arange(len(scene.parts)),
                          [len(q.faces) for q in scene.parts])
    part = np.where(tid < 0, -1, np.where(tid >= nt, -2, face_part[np.minimum(tid, nt - 1)]))
    return part, np.where(np.isfinite(z), z, -1e3)


def _neighbour_steps(img, part, z, a, b, pixel, region=None):
    """Largest colour step (max over RGB, 0-255) between 4-neighbours labelled ``a`` and
    ``b``, and how many such pairs there are, on surface seen at under 75 degrees from
    face-on: where the depth changes by less than tan(75 deg) pixel widths (``pixel``, m) per
    pixel round both pixels (a silhouette's grazing surface changes colour quickly whatever
    its mesh); ``region`` limits both pixels to a mask."""
    img = img[..., :3].astype(int)
    gy, gx = np.gradient(z)
    facing = np.hypot(gx, gy) < np.tan(np.radians(75.0)) * pixel
    facing &= ndimage.minimum_filter(facing, size=3)
    steps, count = [0], 0
    for sl0, sl1 in (((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
                     ((slice(None, -1), slice(None)), (slice(1, None), slice(None)))):
        p0, p1 = part[sl0], part[sl1]
        ok = (((p0 == a) & (p1 == b)) | ((p0 == b) & (p1 == a)))
        ok &= facing[sl0] & facing[sl1]
        if region is not None:
            ok &= region[sl0] & region[sl1]
        d = np.abs(img[sl0] - img[sl1]).max(axis=-1)[ok]
        steps.append(int(d.max()) if d.size else 0)
        count += int(ok.sum())
    return max(steps), count


@pytest.mark.parametrize("view", VIEWS)
def test_no_edge_where_the_face_meets_the_head(head, view):
    """Across the old mask boundary (skin pixels next to head pixels, on surface seen at under
    75 degrees from face-on) no step in colour is larger than the largest step between
    neighbouring pixels of the cheek (measured, 480 x 400 px, no anti-aliasing: boundary 4-9,
    cheek 11-13 out of 255)."""
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
        pixel = 2 * cam.half_height / 480  # m per pixel at the target's depth
        seam, n_seam = _neighbour_steps(img, part, z, skin, head_part, pixel)
        # the cheek: skin pixels within 15 mm of the cheek landmark that faces the camera
        side = "cheek_right" if view != "frontal" else "cheek_left"
        c = cam.project(lm[side][None])[0]
        yy, xx = np.mgrid[0:480, 0:400]
        near = np.hypot(xx + 0.5 - c[0], yy + 0.5 - c[1]) < 0.015 / pixel
        cheek, n_cheek = _neighbour_steps(img, part, z, skin, skin, pixel, near)
        # both are seen; in the frontal view the boundary runs down the sides of the head and
        # under the chin, seen edge-on: few or none of its pixels face the camera
        assert n_cheek > 500 and (view == "frontal" or n_seam > 200), (n_seam, n_cheek)
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


def _eye_crop(scene, look, blink=0.0, gaze=(0.0, 0.0)):
    """The left eye's fissure seen from the front: (rgb float (h, w, 3), metres per pixel)."""
    from facemech.viz.camera import Camera, view_rotation

    e = look.landmarks["eye_left"]
    verts, norms = scene.frame(look.rest, 0.0, blink, gaze)
    cam = Camera(view_rotation(0.0, 0.0), e, 0.012, (240, 360), None)
    img = render_panel(scene, verts, norms, cam, background=parse_background("#00ff00"))
    return img[..., :3].astype(float) / 255.0, 2 * 0.012 / 240


def test_blink_closes_the_lids_and_open_changes_nothing(head):
    scene, _ = head
    look = scene.look
    names = [p.name for p in scene.parts]
    assert {"lid_left", "lid_right"} <= set(names)
    # open and looking ahead, the lids have no area: the frame is that of the parts at rest
    verts, _ = scene.frame(look.rest, 0.0)
    for name in ("lid_left", "lid_right"):
        i = names.index(name)
        v = verts[scene.offsets[i]:scene.offsets[i + 1]]
        f = scene.parts[i].faces
        area = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                              axis=1).sum() / 2
        assert area < 1e-5  # m^2: under 10 mm^2, a 2-degree strip behind the skin
    open_, _ = _eye_crop(scene, look)
    shut, _ = _eye_crop(scene, look, blink=1.0)
    half, _ = _eye_crop(scene, look, blink=0.5)
    h, w = open_.shape[:2]
    centre = (slice(h // 2 - 6, h // 2 + 6), slice(w // 2 - 6, w // 2 + 6))
    # the pupil is dark when open and covered by skin-coloured lid when closed
    assert open_[centre].mean() < 0.2
    skin = open_[h // 2 + 60:h // 2 + 70, w // 2 - 20:w // 2 + 20].reshape(-1, 3).mean(axis=0)
    lid = shut[centre].mean(axis=(0, 1))  # the lower lid's skin, 6-7 mm under the eye
    assert np.abs(lid - skin).max() < 0.12
    # no sclera shows when shut: nothing as white as the sclera inside the fissure
    assert (shut.min(axis=-1) > 0.8).sum() < 0.002 * h * w, (shut.min(axis=-1) > 0.8).sum()
    # half closed: the pupil's upper half is covered, the lower still dark
    assert half[h // 2 + 8:h // 2 + 14, w // 2 - 4:w // 2 + 4].mean() < 0.3


def test_gaze_turns_the_eyes_and_the_lid_follows_down(head):
    scene, _ = head
    look = scene.look

    def pupil(img, m):
        """Centroid (m) of the pupil's dark pixels within 7 x 3.5 mm of the fissure's centre
        (the lash line and the fissure's corners lie outside)."""
        h, w = img.shape[:2]
        yy, xx = np.mgrid[0:h, 0:w]
        box = (np.abs(xx - w / 2) * m < 0.007) & (np.abs(yy - h / 2) * m < 0.0035)
        yy, xx = np.nonzero(box & (img.max(axis=-1) < 0.12))
        return np.array([xx.mean(), yy.mean()]) * m

    ahead, m = _eye_crop(scene, look)
    left, _ = _eye_crop(scene, look, gaze=(0.3, 0.0))
    up, _ = _eye_crop(scene, look, gaze=(0.0, 0.2))
    p0, p1, p2 = pupil(ahead, m), pupil(left, m), pupil(up, m)
    # the pupil moves 12 mm x sin(angle) (the eyeball's radius), within a third; towards
    # the image's right (the subject's left) for yaw > 0, and up (image rows decrease)
    assert 0.67 * 0.012 * np.sin(0.3) < p1[0] - p0[0] < 1.33 * 0.012 * np.sin(0.3)
    assert 0.67 * 0.012 * np.sin(0.2) < p0[1] - p2[1] < 1.33 * 0.012 * np.sin(0.2)
    # looking down, the upper lid comes down with the eye: its edge's elevation falls by
    # 0.8 of the pitch
    lid = next(p.follow for p in scene.parts if p.name == "lid_left")
    drop = lid.edge(0.0, 0.0) - lid.edge(0.0, -0.25)
    assert np.allclose(drop, 0.8 * 0.25)


def test_the_lower_lid_rises_looking_up_and_in_a_blink(head):
    """The lower lids: open and looking ahead they have no area; looking up 0.3 rad the
    fissure's lower edge rises at its middle by LOWER_FOLLOW x 0.3 rad on the eyeball (1.3
    mm measured; within 0.4 mm); looking down it stays (the cut fissure cannot open further,
    one pixel); half a blink lifts it too (0.7 mm measured)."""
    from facemech.viz.lids import LOWER_FOLLOW

    scene, _ = head
    look = scene.look
    names = [p.name for p in scene.parts]
    verts, _ = scene.frame(look.rest, 0.0)
    for name in ("lower_lid_left", "lower_lid_right"):
        i = names.index(name)
        v = verts[scene.offsets[i]:scene.offsets[i + 1]]
        f = scene.parts[i].faces
        area = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                              axis=1).sum() / 2
        assert area < 1e-5  # m^2: a 2-degree strip behind the skin
    ahead, m = _eye_crop(scene, look)
    h, w = ahead.shape[:2]
    skin = ahead[h // 2 + 60:h // 2 + 70, w // 2 - 20:w // 2 + 20].reshape(-1, 3).mean(axis=0)

    def lower_edge(img):
        """Image row (y down) of the first skin-coloured pixel under the fissure's middle."""
        column = img[:, w // 2 - 3:w // 2 + 4].mean(axis=1)
        eye = np.abs(column - skin).max(axis=-1) > 0.12
        assert eye[h // 2], "the fissure's middle is covered"
        return h // 2 + int(np.argmin(eye[h // 2:]))

    rows = {k: lower_edge(_eye_crop(scene, look, *k)[0])
            for k in ((0.0, (0.0, 0.0)), (0.0, (0.0, 0.3)), (0.0, (0.0, -0.3)),
                      (0.5, (0.0, 0.0)))}
    lid = next(p.follow for p in scene.parts if p.name == "lower_lid_left")
    want = LOWER_FOLLOW * 0.3 * lid.radii[1]  # m
    rise = (rows[0.0, (0.0, 0.0)] - rows[0.0, (0.0, 0.3)]) * m
    assert abs(rise - want) < 0.4e-3, (rise, want)
    assert abs(rows[0.0, (0.0, 0.0)] - rows[0.0, (0.0, -0.3)]) <= 1
    assert (rows[0.0, (0.0, 0.0)] - rows[0.5, (0.0, 0.0)]) * m > 0.4e-3


@pytest.mark.parametrize("view", VIEWS)
def test_culling_the_inner_sides_by_tiles_changes_no_sample(head, view):
    """The rasteriser draws the inner sides (the skin's and the head's) after the front faces
    and skips tiles whose nearest depth hides them: the visibility buffer is that of drawing
    every inner side as a front face of its own (the same triangles, wound the other way, in
    the same order after the front faces), at rest and with the jaw open (measured: no sample
    differs)."""
    scene, frames = head
    nt = len(scene.tris)
    two = np.flatnonzero(scene.two_sided)
    tris = np.concatenate([scene.tris, scene.tris[two][:, ::-1]])
    uv = np.concatenate([scene.uv, scene.uv[two]])
    tex = np.concatenate([scene.tex, np.zeros(len(two), scene.tex.dtype)])
    alpha = np.concatenate([scene.alpha_test, np.zeros(len(two), bool)])
    plain = np.zeros(len(tris), bool)
    for skin, jaw in frames:
        verts, _ = scene.frame(skin, jaw)
        cam = view_camera(view, scene.framing, (480, 400), 1.2)
        p = cam.project(verts, 2)
        out = []
        for args in ((scene.tris, scene.uv, scene.tex, scene.alpha_test, scene.two_sided),
                     (tris, uv, tex, alpha, plain)):
            z = np.full((960, 800), -np.inf, np.float32)
            tid = np.full((960, 800), -1, np.int32)
            bary = np.empty((960, 800, 2), np.float32)
            rasterise(p[:, 0], p[:, 1], p[:, 2], *args, scene.atlas, z, tid, bary)
            out.append((z, tid))
        (z0, t0), (z1, t1) = out
        # the copies' labels as the rasteriser's inner-side labels (f + nt)
        t1 = np.where(t1 >= nt, two[np.maximum(t1 - nt, 0)] + nt, t1)
        assert (t0 >= nt).sum() > 0 or jaw == 0.0  # inner sides do show with the jaw open
        # the same samples (the reversed winding rounds the depth in its last bits: a tie
        # between two surfaces may go either way; depths near 0 (the camera's target plane)
        # differ by rounding alone, below 1e-9)
        assert (t0 != t1).sum() <= 2
        np.testing.assert_allclose(z0, z1, rtol=1e-6, atol=1e-8)


def test_the_joint_normals_are_the_meshs_vertex_normals(head):
    """The scene's sparse operator gives the joint mesh's area-weighted vertex normals
    (geometry.mesh.vertex_normals) to rounding, with the jaw open."""
    from facemech.geometry.mesh import vertex_normals

    scene, frames = head
    skin, _ = frames[1]
    closure = next(p for p in scene.parts if p.motion == "follow")
    v = np.concatenate([skin, closure.follow.place(skin, scene.look.rest)])
    np.testing.assert_allclose(scene.joint_normals(v), vertex_normals(v, scene.joint_faces),
                               atol=1e-12)


def test_ears_have_relief():
    from facemech.viz.ears import relief

    s = np.linspace(0, 1, 201)
    mid = relief(s, np.full_like(s, 0.45))  # through the concha and the antihelix
    upper = relief(s, np.full_like(s, 0.3))  # through the scapha
    lobe = relief(s, np.full_like(s, 0.95))
    at = lambda x: int(round(x * 200))  # noqa: E731
    assert mid[at(0.25)] < 1.5  # the concha's floor, near the head
    assert mid[at(0.58)] - mid[at(0.45)] > 2.0  # the antihelix stands over the concha
    assert upper[at(0.76)] < upper[at(0.62)] - 0.5  # the scapha, a groove
    assert upper[at(0.93)] > upper[at(0.84)] + 1.0  # the helix rolls up at the rim
    assert np.all(np.diff(lobe[at(0.2):]) > 0)  # the lobe: no relief, only the flare
    assert 12.0 < upper[at(0.93)] < 20.0  # mm off the head at the rim


def test_hair_has_volume_and_a_soft_irregular_hairline(head):
    scene, _ = head
    names = [p.name for p in scene.parts]
    hair = scene.parts[names.index("hair")]
    # the hair stands 8 to 10 mm off the scalp on the crown
    top = hair.rest[np.argmax(hair.rest[:, 1])]
    scalp_top = max(scene.look.rest[:, 1].max(), scene.parts[names.index("head")].rest[:, 1].max())
    assert 0.007 < top[1] - scalp_top < 0.011
    # its strands are alpha-tested only near the hairline
    i = names.index("hair")
    tested = scene.alpha_test[sum(len(p.faces) for p in scene.parts[:i]):][:len(hair.faces)]
    assert 0.02 < tested.mean() < 0.4
    # the hairline over the forehead: going up each column of the strand texture, the hair
    # becomes opaque over several texels (not a step), at heights that differ column by column
    tex = hair.texture
    th = (tex.shape[0] - 2) // 2
    right = tex[:th]  # the subject's right half: longitude -180 .. 0
    cols = right[:, -80:, 3] >= 0.5  # the last 20 degrees before the midline; rows down
    rows = np.arange(len(cols))[:, None]
    tip = np.where(cols, rows, -1).max(axis=0)  # each column's lowest strand tip
    assert np.std(tip) > 1.5, np.std(tip)  # texels (0.25 degree): the tips are irregular
    cover = cols.mean(axis=1)  # the share of hair along each row
    soft = int(((cover > 0.05) & (cover < 0.95)).sum())
    assert soft >= 8, soft  # rows: the hair thins out over 2 degrees (3.5 mm) or more


def test_a_textured_face_is_closed_by_the_head_in_its_own_skin_colour(face):
    """A face with its own texture on the generic grid (a photo talker's) gets the same closing
    head as the built-in face, not a separate shell behind a mask: the closure's edge ring takes
    the colour of the skin's edge nodes in the texture and fades into their mean away from the
    edge."""
    from dataclasses import replace

    from facemech.viz.head import skin_colours

    look = look_from_model(face)
    rng = np.random.default_rng(3)
    image = rng.integers(80, 230, (64, 64, 3)).astype(np.uint8)
    xy = look.rest[:, :2]
    uv = (xy - xy.min(axis=0)) / np.ptp(xy, axis=0)
    scene = build_scene(replace(look, uv=uv[look.triangles], image=image))
    names = [p.name for p in scene.parts]
    assert "head" in names and "skirt" not in names and scene.joint_faces is not None
    head = next(p for p in scene.parts if p.name == "head")
    closure = head.follow
    edge = skin_colours(replace(look, uv=uv[look.triangles], image=image))
    e = len(closure.loop)
    np.testing.assert_allclose(head.albedo[:e], edge[closure.loop], atol=1e-12)
    far = closure.weights < 1e-6
    assert far.any()
    assert np.abs(head.albedo[far] - edge[closure.loop].mean(axis=0)).max() < 1e-5
    # the texel each skin node shows is the one its texture coordinate points at
    k = 100
    col = min(int(uv[k, 0] * 64), 63)
    row = min(int((1.0 - uv[k, 1]) * 64), 63)
    np.testing.assert_allclose(edge[k], image[row, col] / 255.0)


def test_the_rings_turn_one_way_where_the_edge_steps_back():
    """``monotone_phi``: an edge whose angle steps back a little keeps its order, the step
    spread between its neighbours; one already monotonic is returned as it is."""
    from facemech.viz.closure import monotone_phi

    phi = np.array([0.0, 0.1, 0.09, 0.2, 0.3])
    np.testing.assert_allclose(monotone_phi(phi), [0.0, 0.1, 0.15, 0.2, 0.3])
    down = -phi
    np.testing.assert_allclose(monotone_phi(down), -np.array([0.0, 0.1, 0.15, 0.2, 0.3]))
    ok = np.linspace(0.0, 6.0, 40)
    assert monotone_phi(ok) is ok


def test_a_scan_cut_at_the_neck_is_closed_into_one_head(tmp_path, monkeypatch, capsys):
    """The scan-like head (a neck cut straight across, ears, jaw angles), written as OBJ + LJSON
    v3 and built through ``facemech face build``: its edge steps back by up to 0.9 degrees at the
    neck's corners, seen from behind the head; it is closed all the same, into one watertight,
    consistently wound surface of a sphere's topology, without the renderer's ears beside its
    own."""
    from conftest import run_cli
    from facemech.geometry.model import FaceModel
    from facemech.viz.closure import PHI_REVERSAL, RAY_ORIGIN, back_polar, boundary_loops
    from facemech.viz.head import cranium_of
    from scans import write_head_scan

    obj, ljson = write_head_scan(tmp_path)
    code, _, err = run_cli(monkeypatch, capsys, "face", "build", obj, ljson, "-o",
                           tmp_path / "head.npz")
    assert code == 0, err
    look = look_from_model(FaceModel.load(tmp_path / "head.npz"))
    loop = boundary_loops(look.triangles)[0]
    rel = look.rest[loop] - (cranium_of(look).centre + RAY_ORIGIN)
    _, phi = back_polar(rel / np.linalg.norm(rel, axis=1, keepdims=True))
    step = np.diff(np.unwrap(np.append(phi, phi[0])))
    back = -np.sign(step.sum()) * step
    assert 0 < back.max() < PHI_REVERSAL  # the edge does step back, a little
    scene = build_scene(look)
    head = next(p for p in scene.parts if p.name == "head")
    # its skin goes on round its own ears (fins standing out of it): no second pair is added
    assert not any(p.name.startswith("ear") for p in scene.parts)
    verts, faces = closed_surface(look.rest, head.follow, look.triangles, look.rest)
    mesh = trimesh.Trimesh(verts, faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.euler_number == 2
