"""Rendering for perception experiments: the mouth interior, eyes, texture, views, stills."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from conftest import activity, run_cli
from facemech.geometry.appearance import Appearance
from facemech.io.results import read_results, to_dataset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.viz.camera import parse_size
from facemech.viz.raster import srgb_to_linear
from facemech.viz.render import Renderer
from facemech.viz.scene import build_scene, look_from_dataset, look_from_model
from facemech.viz.video import RenderOptions, jaw_poses_of, render_results, still
from facemech.workflows.demo import run_demo

GREEN = "#00ff00"  # a background no part of the face has


@pytest.fixture(scope="module")
def open_mouth(face):
    """0.5 s: the jaw opens to 14 degrees while DLI lowers the lower lip (in memory)."""
    n = 31
    jaw = np.radians(14.0) * np.clip(np.linspace(0, 1.6, n), 0, 1)
    sim = simulate(face_model(face), activity(n, DLI=0.6), jaw)
    return to_dataset(sim)


@pytest.fixture(scope="module")
def demo_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    run_demo(out, video=False)
    return read_results(out / "result.nc")


def enclosed_background(img: np.ndarray, rgb) -> int:
    """Pixels of exactly the background colour that do not connect to the frame's border."""
    bg = np.all(img[..., :3] == np.asarray(rgb, np.uint8), axis=-1)
    lab, n = ndimage.label(bg)
    border = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    return int(np.isin(lab, np.setdiff1d(np.arange(1, n + 1), border)).sum())


def _bg(renderer) -> np.ndarray:
    from facemech.viz.render import resolve_background

    return resolve_background(renderer.background)[:3]


def test_open_mouth_shows_the_mouth_interior_not_the_background(open_mouth):
    scene = build_scene(look_from_dataset(open_mouth))
    rend = Renderer(scene, "mouth", (360, 480), background=GREEN)
    k = len(open_mouth.time) - 1
    img = rend(open_mouth.positions.values[k], jaw_poses_of(open_mouth)[k])
    cam = rend.cameras[0]
    nodes = __import__("json").loads(open_mouth.attrs["marker_nodes"])
    pos = open_mouth.positions.values[k]
    # the lips are apart: the lip centres are at least 8 mm apart
    gap = pos[nodes["upper_lip_center"], 1] - pos[nodes["lower_lip_center"], 1]
    assert gap > 0.024
    # inside the lip contour (the polygon of the lip centres and the corners) nothing shows
    # the background, and what shows there is dark cavity, teeth or tongue, not skin
    from matplotlib.path import Path as Poly

    poly = cam.project(pos[[nodes[n] for n in ("mouth_corner_right", "upper_lip_center",
                                               "mouth_corner_left", "lower_lip_center")]])
    yy, xx = np.mgrid[0:360, 0:480]
    inside = Poly(poly[:, :2]).contains_points(np.column_stack([xx.ravel() + 0.5,
                                                                yy.ravel() + 0.5]))
    inside = inside.reshape(360, 480)
    assert inside.sum() > 2000
    pix = img[inside][:, :3]
    assert not np.any(np.all(pix == _bg(rend), axis=1))
    assert enclosed_background(img, _bg(rend)) == 0
    # a dark oral cavity fills much of the opening, and the teeth show: bright pixels of low
    # saturation inside the mouth
    rgbf = pix.astype(float) / 255
    assert (rgbf.max(axis=1) < 0.25).mean() > 0.2
    teeth = (rgbf.min(axis=1) > 0.55) & (rgbf.max(axis=1) - rgbf.min(axis=1) < 0.2)
    assert teeth.sum() > 50


@pytest.mark.slow
def test_no_background_enclosed_by_the_face_in_any_demo_frame(demo_results):
    ds = demo_results
    scene = build_scene(look_from_dataset(ds))
    rend = Renderer(scene, "frontal+profile", (360, 1280), background=GREEN, supersample=1)
    pos, jaw = ds.positions.values, jaw_poses_of(ds)  # the teeth follow angle and shift
    bg = _bg(rend)
    worst = max(enclosed_background(rend(pos[k], jaw[k]), bg) for k in range(len(pos)))
    assert worst == 0
    assert np.degrees(jaw[:, 0].max()) > 5  # the demo does open the mouth


def test_mouth_seal_closes_the_slit_from_inside(face, open_mouth):
    from facemech.viz.face_parts import mouth_seal

    look = look_from_model(face)
    seal = mouth_seal(look)
    epi = face.lip_pairs[face.lip_pairs[:, 0] < face.n_surface]  # (upper, lower) skin twins
    corners = {face.landmarks["mouth_corner_right"], face.landmarks["mouth_corner_left"]}
    # a quad per edge of the lip line: two triangles per twin pair (the corners are shared)
    assert len(seal.faces) == 2 * len(epi)
    assert set(seal.faces.ravel()) == set(epi.ravel()) | corners
    assert seal.motion == "skin"

    def areas(pos):
        a, b, c = (pos[seal.faces[:, i]] for i in range(3))
        return 0.5 * np.cross(b - a, c - a)

    assert np.abs(areas(look.rest)).max() == 0.0  # at rest the twins coincide: no area
    pos = open_mouth.positions.values[-1]
    n = areas(pos)
    assert np.all(n[:, 2] < 0)  # every triangle faces back, into the mouth: culled from outside
    # the strip tiles the opening: its frontal area is the lip contour's (shoelace), exactly
    upper = epi[np.argsort(pos[epi[:, 0], 0]), 0]
    lower = epi[np.argsort(pos[epi[:, 1], 0]), 1]
    ring = pos[[face.landmarks["mouth_corner_right"], *upper,
                face.landmarks["mouth_corner_left"], *lower[::-1]], :2]
    x, y = ring[:, 0], ring[:, 1]
    contour = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert contour > 2e-4  # the lips are well apart (> 2 cm^2)
    assert -n[:, 2].sum() == pytest.approx(contour, rel=1e-9)


@pytest.mark.slow
def test_mouth_interior_is_dark_from_oblique_views(demo_results):
    """Close-ups of the mouth from the side, above and below: no background shows through the
    lips in any fourth frame of the demo (lips a hair apart, apart, the jaw open)."""
    from facemech.viz.camera import Camera, view_rotation
    from facemech.viz.render import parse_background, render_panel

    ds = demo_results
    scene = build_scene(look_from_dataset(ds))
    pos, jaw = ds.positions.values, jaw_poses_of(ds)
    bg = parse_background(GREEN)
    target = scene.framing["mouth"] + np.array([0.0, 0.0, -0.01])
    cams = [Camera(view_rotation(az, el), target, 0.03, (160, 160), 1.2)
            for az, el in ((35, 0), (-35, 0), (35, -25), (-20, 25), (90, 0), (-90, 0))]
    worst = 0
    for k in range(0, len(pos), 4):
        verts, norms = scene.frame(pos[k], jaw[k])
        for cam in cams:
            img = render_panel(scene, verts, norms, cam, background=bg, supersample=1)
            worst = max(worst, enclosed_background(img, np.array([0, 255, 0], np.uint8)))
    assert worst == 0


def test_eyes_differ_from_skin_and_sit_under_the_lids(face):
    look = look_from_model(face)
    rend = Renderer(build_scene(look), "frontal", (720, 720))
    img = rend(look.rest).astype(float)[..., :3] / 255
    cam = rend.cameras[0]

    def patch(p, r=4):
        x, y, _ = cam.project(p[None])[0]
        return img[int(y) - r:int(y) + r, int(x) - r:int(x) + r].reshape(-1, 3)

    skin = patch(look.landmarks["cheek_left"], 8).mean(axis=0)
    for eye in ("eye_left", "eye_right"):
        centre = patch(look.landmarks[eye], 3).mean(axis=0)  # the pupil and iris
        assert np.linalg.norm(centre - skin) > 0.35
        assert centre.mean() < 0.35
    # the sclera: near-white pixels beside the iris, none on the cheek
    e = look.landmarks["eye_left"]
    white = patch(e + np.array([0.0085, 0.0, 0.0]), 2).mean(axis=0)
    assert white.min() > 0.6 and white.max() - white.min() < 0.15
    # the skin's lips are vermilion: redder than the cheek
    lip = patch(0.5 * (look.landmarks["upper_lip_center"] + look.landmarks["stomion"]),
                3).mean(axis=0)
    assert lip[0] - lip[1] > skin[0] - skin[1] + 0.05


@pytest.mark.slow
def test_textured_face_renders_its_texture(face):
    look = look_from_model(face)
    # a texture of four flat quadrants, mapped frontally from the rest (x, y)
    img = np.zeros((64, 64, 3), np.uint8)
    img[:32, :32] = (200, 40, 40)
    img[:32, 32:] = (40, 200, 40)
    img[32:, :32] = (40, 40, 200)
    img[32:, 32:] = (220, 200, 60)
    xy = look.rest[:, :2]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    uvn = (xy - lo) / (hi - lo)
    uv = uvn[face.faces].astype(np.float32)
    app = Appearance(uv=uv, image=img, source="quadrants")
    from dataclasses import replace

    textured = replace(look, uv=app.uv, image=app.image)
    scene = build_scene(textured)
    rend = Renderer(scene, "frontal", (600, 600))
    out = rend(textured.rest).astype(float)[..., :3]
    cam = rend.cameras[0]
    # patches well inside each quadrant: upper left of the image is the subject's right (-x)
    for (fx, fy), colour in (((0.3, 0.7), (200, 40, 40)), ((0.7, 0.7), (40, 200, 40)),
                             ((0.3, 0.25), (40, 40, 200)), ((0.7, 0.25), (220, 200, 60))):
        p = np.array([lo[0] + fx * (hi[0] - lo[0]), lo[1] + fy * (hi[1] - lo[1]), 0.0])
        node = np.argmin(np.linalg.norm(xy - p[:2], axis=1) - 1e-3 * textured.rest[:, 2])
        x, y, _ = cam.project(textured.rest[node][None])[0]
        mean = out[int(y) - 3:int(y) + 3, int(x) - 3:int(x) + 3].reshape(-1, 3).mean(axis=0)
        # in linear light the pixel is the texel scaled by the diffuse light plus a white
        # highlight: pixel = a * texel + s; fit a and s, the fit must be exact to 2 %
        lin, c = srgb_to_linear(mean / 255), srgb_to_linear(np.asarray(colour) / 255)
        A = np.column_stack([c, np.ones(3)])
        (a, s_), res, *_ = np.linalg.lstsq(A, lin, rcond=None)
        assert a > 0.5 and -0.01 <= s_ < 0.12, (colour, mean, a, s_)
        assert np.abs(A @ [a, s_] - lin).max() < 0.02, (colour, mean)
    # a large scan texture is reduced for the atlas, and still maps the same colours
    from facemech.viz.scene import MAX_TEXTURE

    big = np.kron(img, np.ones((80, 80, 1), np.uint8))  # 5120 texels a side
    scene_big = build_scene(replace(look, uv=app.uv, image=big))
    skin = next(p for p in scene_big.parts if p.name == "skin")
    assert max(skin.texture.shape[:2]) <= MAX_TEXTURE
    out_big = Renderer(scene_big, "frontal", (600, 600))(textured.rest).astype(float)[..., :3]
    assert np.abs(out_big - out).mean() < 2.0
    # vertex colours too
    vc = np.zeros((len(look.rest), 3), np.uint8)
    vc[:] = (30, 90, 210)
    scene2 = build_scene(replace(look, vertex_colours=vc))
    out2 = Renderer(scene2, "frontal", (300, 300))(look.rest).astype(float)[..., :3]
    x, y, _ = Renderer(scene2, "frontal", (300, 300)).cameras[0].project(
        look.landmarks["cheek_left"][None])[0]
    m = out2[int(y) - 2:int(y) + 2, int(x) - 2:int(x) + 2].reshape(-1, 3).mean(axis=0)
    assert m[2] > m[1] > m[0]


def test_size_view_and_transparency_are_honoured(face, tmp_path):
    look = look_from_model(face)
    scene = build_scene(look)
    for view, size in (("frontal", (240, 320)), ("profile", (200, 200)),
                       ("three-quarter", (100, 180)), ("mouth", (90, 160)),
                       ("frontal+profile", (120, 400))):
        img = Renderer(scene, view, size)(look.rest)
        assert img.shape == (*size, 4)
    # profile: the nose points to the image's left, the ear side to the right
    rend = Renderer(scene, "profile", (400, 400))
    p = rend.cameras[0].project(np.stack([look.landmarks["nose_tip"],
                                          look.landmarks["jaw_angle_right"]]))
    assert p[0, 0] < p[1, 0] - 50
    # frontal: the subject's left (+x) appears on the image's right
    f = Renderer(scene, "frontal", (400, 400)).cameras[0].project(
        np.stack([look.landmarks["eye_left"], look.landmarks["eye_right"]]))
    assert f[0, 0] > f[1, 0] + 50
    # the mouth close-up centres the stomion and frames about 64 mm
    m = Renderer(scene, "mouth", (360, 480))
    q = m.cameras[0].project(np.stack([look.landmarks["stomion"],
                                       look.landmarks["mouth_corner_left"],
                                       look.landmarks["mouth_corner_right"]]))
    assert abs(q[0, 0] - 240) < 2 and abs(q[0, 1] - 180) < 2
    assert 220 < q[1, 0] - q[2, 0] < 320
    # transparent background: clear corners, opaque face
    t = Renderer(scene, "frontal", (200, 200), background="transparent")(look.rest)
    assert t[0, 0, 3] == 0 and t[100, 100, 3] == 255
    assert 0 < np.count_nonzero((t[..., 3] > 0) & (t[..., 3] < 255))  # anti-aliased edges
    assert parse_size("1920x1080") == (1080, 1920)


@pytest.mark.slow
def test_render_command_frames_and_stills(open_mouth, tmp_path, monkeypatch, capsys):
    from facemech.io.results import write_results  # noqa: F401  (the CLI reads files)

    res = tmp_path / "r.nc"
    open_mouth.to_netcdf(res, engine="h5netcdf")
    frames = tmp_path / "frames"
    code, out, err = run_cli(monkeypatch, capsys, "render", res, "-o", frames, "--view",
                             "mouth", "--size", "160x90", "--background", "transparent")
    assert code == 0, err
    files = sorted(frames.glob("frame_*.png"))
    assert len(files) == len(open_mouth.time)
    import matplotlib.image as mpimg

    first = mpimg.imread(files[0])
    assert first.shape == (90, 160, 4)
    # still at the jaw's peak, with markers, as PNG and PDF
    png = tmp_path / "s.png"
    code, out, err = run_cli(monkeypatch, capsys, "still", res, "-o", png, "--peak", "jaw",
                             "--markers", "--size", "400x400")
    assert code == 0, err
    assert f"frame {int(np.argmax(open_mouth.jaw_angle.values))} " in out
    img = mpimg.imread(png)
    assert img.shape[:2] == (400, 400)
    yellow = (img[..., 0] > 0.85) & (img[..., 1] > 0.7) & (img[..., 2] < 0.25)
    assert yellow.sum() > 20  # the marker dots
    code, out, err = run_cli(monkeypatch, capsys, "still", res, "-o", tmp_path / "s.pdf",
                             "--time", "0.2")
    assert code == 0, err
    assert (tmp_path / "s.pdf").read_bytes()[:4] == b"%PDF"
    assert "frame 12 " in out
    # bad input: one line, exit 2, nothing written
    for args, field in (((("--view", "side")), "view"), (("--size", "big"), "size"),
                        (("--background", "#12"), "background")):
        code, _, err = run_cli(monkeypatch, capsys, "render", res, "-o", tmp_path / "x.mp4",
                               *args)
        assert code == 2 and len(err.strip().splitlines()) == 1 and field in err, err
    code, _, err = run_cli(monkeypatch, capsys, "render", res, "-o", tmp_path / "x.mp4",
                           "--background", "transparent")
    assert code == 2 and "transparent" in err
    code, _, err = run_cli(monkeypatch, capsys, "still", res, "-o", tmp_path / "y.png",
                           "--time", "9")
    assert code == 2 and "time" in err
    code, _, err = run_cli(monkeypatch, capsys, "still", res, "-o", tmp_path / "y.png",
                           "--peak", "XYZ")
    assert code == 2 and "peak" in err
    assert not (tmp_path / "x.mp4").exists() and not (tmp_path / "y.png").exists()
    # a results file holding NaN (written by another tool) is refused, not drawn
    broken = open_mouth.copy(deep=True)
    broken["positions"].values[3, 5, 1] = np.nan
    bad = tmp_path / "nan.nc"
    broken.to_netcdf(bad, engine="h5netcdf")
    code, _, err = run_cli(monkeypatch, capsys, "render", bad, "-o", tmp_path / "z.mp4",
                           "--size", "160x90")
    assert code == 2 and "positions" in err and "frame 3" in err, err
    assert not (tmp_path / "z.mp4").exists()


def test_movie_of_results(open_mouth, tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    import imageio_ffmpeg

    path = render_results(open_mouth, tmp_path / "m.mp4",
                          options=RenderOptions(view="three-quarter", size=(180, 320)))
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(path))
    assert frames == len(open_mouth.time)
    with pytest.raises(Exception, match="size"):
        RenderOptions(size=(5000, 5000))


def test_still_as_library_call(open_mouth, tmp_path):
    import facemech as fm

    assert fm.still is still and fm.render_results is render_results
    r = still(open_mouth, tmp_path / "a.png", peak="DLI",
              options=RenderOptions(view="frontal", size=(200, 200)))
    assert r["frame"] == int(np.argmax(open_mouth.activity.values[:, 7]
                                       if list(open_mouth.muscle.values).index("DLI") == 7
                                       else open_mouth.activity.sel(muscle="DLI").values))


def test_render_reports_progress_when_piped(open_mouth, tmp_path):
    import subprocess
    import sys

    res = tmp_path / "r.nc"
    open_mouth.to_netcdf(res, engine="h5netcdf")
    run = subprocess.run([sys.executable, "-m", "facemech.cli", "render", str(res), "-o",
                          str(tmp_path / "m.mp4"), "--size", "320x180"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    n = len(open_mouth.time)
    lines = [ln for ln in run.stderr.splitlines() if ln.startswith("facemech: render:")]
    assert lines and lines[-1].startswith(f"facemech: render: frame {n}/{n}, ")


def test_edge_fade_of_a_bounded_search_is_the_unbounded_distance(face):
    """The skin texture's edge fade stops its tree search at EDGE_FADE: the same weights, to
    the bit, as the full nearest distance to the skin's edge, on the texture's own grid."""
    from scipy.spatial import cKDTree

    from facemech.viz import textures as T
    from facemech.viz.closure import boundary_loops
    from facemech.viz.face_parts import EDGE_FADE, _edge_fade

    look = look_from_model(face)
    loop = boundary_loops(look.triangles)[0]
    a = look.rest[loop, :2]
    k = np.linspace(0.0, 1.0, 12, endpoint=False)[None, :, None]
    edge = (a[:, None] + k * (np.roll(a, -1, axis=0) - a)[:, None]).reshape(-1, 2)
    lo, hi = look.rest[:, :2].min(0), look.rest[:, :2].max(0)
    x, y = np.meshgrid(np.arange(lo[0], hi[0], 2 * T.SKIN_TEXEL),
                       np.arange(lo[1], hi[1], 2 * T.SKIN_TEXEL))
    d, _ = cKDTree(edge).query(np.stack([x.ravel(), y.ravel()], -1))
    want = np.clip(d / EDGE_FADE, 0.0, 1.0).reshape(x.shape)
    got = _edge_fade(look)(x, y)
    np.testing.assert_array_equal(got, want)
    assert 0.05 < np.mean(want < 1.0) < 0.95  # both sides of the fade are on the grid
