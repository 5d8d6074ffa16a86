"""The interactive viewer: its data block decodes back to the results and the movie renderer's
scene, the CLI refuses bad input, and headless Chromium draws the head (skin, eyes, teeth, oral
cavity), its motion and the plot (``make test`` installs Chromium)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from conftest import activity
from conftest import run_cli as cli
from facemech import MUSCLE_GROUPS, read_results
from facemech.io.markers import write_markers
from facemech.markerset import MarkerSet
from facemech.physics.model import model as face_model
from facemech.viz.scene import build_scene, look_from_dataset
from facemech.viz.viewer import (
    DATA_ID,
    atlas_block,
    decode,
    decode_atlas,
    decode_scene,
    linear_to_srgb8,
    read_data_block,
    resample_measured,
    viewer_data,
    write_viewer,
)

FRAMES = 24
BACKGROUND = np.array([22, 24, 29])  # the face canvas's clear colour (viewer_template.html)
OPEN_FRAMES = 12


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """A short lip-spreading gesture with the jaw opening to 12 degrees, on the coarse face."""
    import facemech as fm

    ramp = np.linspace(0.0, 1.0, FRAMES)[:, None]
    act = activity(FRAMES, ZYG=0.8, RIS=0.8) * ramp
    sim = fm.simulate(face_model(fm.default_face("default-coarse")), act,
                      np.radians(12.0) * ramp[:, 0])
    path = tmp_path_factory.mktemp("viewer") / "gesture.nc"
    fm.write_results(path, sim)
    return path


@pytest.fixture(scope="module")
def open_mouth(tmp_path_factory):
    """The jaw opening to 14 degrees (held over the last quarter) with the open vowel's lower
    lip (DLI 0.3, speech/visemes.py), on the coarse face. (The jaw alone showed 28 pixels of
    teeth since the contacts are stepped on their own: the lower lip rides the jaw less and
    covers the lower incisors, docs/model.md.)"""
    import facemech as fm
    from facemech.io.results import to_dataset

    ramp = np.clip(np.linspace(0.0, 1.35, OPEN_FRAMES), 0.0, 1.0)
    act = np.zeros((OPEN_FRAMES, len(MUSCLE_GROUPS)))
    act[:, MUSCLE_GROUPS.index("DLI")] = 0.3 * ramp
    sim = fm.simulate(face_model(fm.default_face("default-coarse")), act, np.radians(14.0) * ramp)
    return write_viewer(to_dataset(sim), tmp_path_factory.mktemp("open") / "open.html")


@pytest.fixture(scope="module")
def measured_csv(result):
    """Measured markers: the model's left cheek, 4 mm in front of it, plus an unknown marker."""
    ds = read_results(result)
    cheek = ds["markers"].sel(marker="cheek_left").values + [0.0, 0.0, 0.004]
    ms = MarkerSet(np.stack([cheek, cheek + 0.05], axis=1), ("cheek_left", "elsewhere"), 60.0,
                   source_units="mm")
    path = result.parent / "measured.csv"
    write_markers(path, ms, units="mm")
    return path


@pytest.fixture(scope="module")
def page(result, measured_csv, tmp_path_factory):
    from facemech.viz.viewer import view_file

    return view_file(result, tmp_path_factory.mktemp("page") / "view.html",
                     markers=measured_csv, units="mm")


def test_data_block_decodes_to_the_results(result):
    ds = read_results(result)
    html = _page_text(write_viewer(ds, result.parent / "plain.html"))
    d = read_data_block(html)
    n = d["nNodes"]
    pos = ds["positions"].values
    assert d["format"] == "facemech-viewer/1" and n == pos.shape[1]
    assert d["frameRate"] == 60.0 and len(d["time"]) == FRAMES
    np.testing.assert_allclose(d["time"], ds["time"].values, rtol=0, atol=1e-12)
    rest = decode(d["rest"], "f4", (n, 3))
    steps = decode(d["positions"], "i2", (FRAMES, n, 3))
    back = rest.astype(float) + d["positions"]["scale"] * steps
    scale = d["positions"]["scale"]
    assert scale < 1e-6                              # sub-micrometre steps for a 12-degree jaw
    err = np.abs(back - pos).max()
    assert err <= scale / 2 + 1e-7                   # rounding plus float32 rest (0.1 m * 2^-24)
    assert np.abs(back[-1] - back[0]).max() > 5e-3   # the jaw moved the skin by millimetres
    np.testing.assert_array_equal(decode(d["triangles"], d["triangles"]["dtype"], (-1, 3)),
                                  ds["triangles"].values)
    np.testing.assert_allclose(decode(d["markers"], "f4", (FRAMES, -1, 3)), ds["markers"].values,
                               rtol=1e-6, atol=1e-8)
    assert d["markers"]["names"] == [str(m) for m in ds["marker"].values]
    assert d["activity"]["names"] == list(MUSCLE_GROUPS)
    np.testing.assert_allclose(decode(d["activity"], "f4", (FRAMES, len(MUSCLE_GROUPS))),
                               ds["activity"].values, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(decode(d["jawDeg"], "f4"), np.degrees(ds["jaw_angle"].values),
                               rtol=1e-6, atol=1e-6)
    assert d["jawDeg"] and abs(decode(d["jawDeg"], "f4")[-1] - 12.0) < 1e-4
    assert d["measured"] is None


@pytest.mark.slow
def test_scene_block_decodes_to_the_scene(result):
    ds = read_results(result)
    d = viewer_data(ds)
    scene = build_scene(look_from_dataset(ds))
    got = decode_scene(d["scene"])
    names = [p["name"] for p in d["scene"]["parts"]]
    assert {"skin", "eye_left", "eye_right", "cavity", "upper_teeth", "lower_teeth", "tongue",
            "head", "ear_left", "ear_right"} <= set(names)
    assert names == [p.name for p in scene.parts]
    assert [p["motion"] for p in d["scene"]["parts"]] == [p.motion for p in scene.parts]
    assert [p["inward"] for p in d["scene"]["parts"]] == [p.inward for p in scene.parts]
    np.testing.assert_array_equal(got["offsets"], scene.offsets)
    np.testing.assert_array_equal(got["tris"], scene.tris)
    np.testing.assert_array_equal(got["tex"], scene.tex > 0)
    np.testing.assert_array_equal(got["alpha_test"], scene.alpha_test)
    np.testing.assert_array_equal(got["two_sided"], scene.two_sided)
    assert got["alpha_test"].any() and got["two_sided"].any() and got["tex"].any()
    rest = np.concatenate([p.rest for p in scene.parts])
    np.testing.assert_allclose(got["rest"], rest, rtol=0, atol=1e-7)   # float32
    np.testing.assert_array_equal(got["rest"][:d["nNodes"]], decode(d["rest"], "f4", (-1, 3)))
    h, w = scene.atlas.shape[:2]
    assert (d["scene"]["atlas"]["height"], d["scene"]["atlas"]["width"]) == (h, w)
    tex = scene.tex > 0                                # untextured triangles keep no uv
    np.testing.assert_allclose(got["uv"][tex], scene.uv[tex], rtol=0, atol=max(h, w) / 65535)
    assert not got["uv"][~tex].any()
    # 8-bit sRGB: the same bytes as the sRGB of the scene's linear colours
    np.testing.assert_array_equal(decode(d["scene"]["albedo"], "u1", (-1, 3)),
                                  linear_to_srgb8(scene.albedo))
    np.testing.assert_allclose(got["albedo"], scene.albedo, rtol=0, atol=5e-3)
    np.testing.assert_allclose(got["atlas"], scene.atlas, rtol=0, atol=5e-3)   # PNG: lossless
    np.testing.assert_array_equal(got["atlas"][..., 3] < 0.5, scene.atlas[..., 3] < 0.5)
    np.testing.assert_allclose(got["gloss"], scene.gloss, rtol=1e-7)        # float32
    hinge = d["scene"]["hinge"]
    np.testing.assert_allclose(hinge["point"], scene.look.hinge_point, atol=1e-12)
    np.testing.assert_allclose(hinge["axis"], scene.look.hinge_axis, atol=1e-12)
    assert d["scene"]["frameY"] == [pytest.approx(scene.framing["points"][:, 1].min()),
                                    pytest.approx(scene.framing["points"][:, 1].max())]


def test_atlas_scaled_to_4096_and_jpeg_past_the_budget(monkeypatch):
    import facemech.viz.viewer as V

    atlas = np.ones((4100, 6, 4), np.float32)
    atlas[..., :3] = 0.5
    atlas[:2050, :, 3] = 0.0                          # the top half transparent
    png = atlas_block(atlas)
    assert (png["height"], png["width"]) == (4096, 6)
    assert png["color"].startswith("data:image/png;base64,")
    got = decode_atlas(png)
    assert got.shape == (4096, 6, 4)
    assert np.all(got[..., :3] == got[0, 0, 0])
    assert abs(got[0, 0, 0] - 0.5) < 5e-3 and (got[:2040, :, 3] == 0).all()
    assert (got[2056:, :, 3] == 1).all()
    monkeypatch.setattr(V, "PNG_BUDGET", 100)
    jpeg = atlas_block(atlas[..., :8, :])
    assert jpeg["color"].startswith("data:image/jpeg;base64,")
    assert jpeg["alpha"].startswith("data:image/png;base64,")
    atlas[..., 3] = 1.0
    assert atlas_block(atlas)["alpha"] is None          # opaque: no alpha image


def test_measured_markers_resampled_onto_the_results_times():
    # measured at 30 Hz from 0.1 s to 0.3 s, linear in time, one missing sample at 0.2 s
    t = 0.1 + np.arange(7) / 30.0
    p = np.stack([t, 2 * t, -t], axis=1)[:, None, :]
    p[3] = np.nan
    ms = MarkerSet(p, ("A",), 30.0, time=t)
    times = np.arange(FRAMES) / 60.0
    out, coverage = resample_measured(ms, ["A"], times)
    inside = (times >= t[0] - 1e-12) & (times <= t[-1] + 1e-12)
    gap = (times > t[2]) & (times < t[4])
    keep = inside & ~gap
    np.testing.assert_allclose(out[keep, 0, 0], times[keep], atol=1e-12)
    np.testing.assert_allclose(out[keep, 0, 1], 2 * times[keep], atol=1e-12)
    assert np.all(np.isnan(out[~keep]))              # nothing extrapolated, gaps not bridged
    assert coverage == [pytest.approx(times[keep][0]), pytest.approx(times[keep][-1])]


@pytest.mark.slow
def test_measured_markers_matched_by_name(result, measured_csv):
    from facemech.io.markers import read_markers

    d = viewer_data(read_results(result), measured=read_markers(measured_csv))
    m = d["measured"]
    assert m["names"] == ["cheek_left"]              # "elsewhere" has no model marker
    got = decode(m, "f4", (FRAMES, 1, 3))
    want = read_results(result)["markers"].sel(marker="cheek_left").values + [0, 0, 0.004]
    np.testing.assert_allclose(got[:, 0], want, atol=1e-6)   # CSV in mm, 6 decimals of a second
    assert m["coverage"] == [0.0, pytest.approx((FRAMES - 1) / 60.0)]
    assert "1 of 2 measured markers" in m["note"]


def test_view_cli(result, measured_csv, tmp_path, monkeypatch, capsys):
    out = tmp_path / "v.html"
    code, stdout, _ = cli(monkeypatch, capsys, "view", result, "-o", out, "--markers",
                          measured_csv)
    assert code == 0 and out.is_file()
    assert str(out) in stdout and "MB" in stdout
    assert read_data_block(_page_text(out))["measured"]["names"] == ["cheek_left"]

    bad = tmp_path / "bad.nc"
    bad.write_text("not netcdf")
    nomatch = tmp_path / "nomatch.csv"
    write_markers(nomatch, MarkerSet(np.zeros((3, 1, 3)), ("X9",), 60.0))
    cases = [
        ((tmp_path / "missing.nc", "-o", tmp_path / "a.html"), "file not found"),
        ((bad, "-o", tmp_path / "b.html"), "not a readable NetCDF"),
        ((result, "-o", tmp_path / "c.html", "--markers", nomatch), "no marker name in common"),
        ((result, "-o", tmp_path / "d.html", "--markers", tmp_path / "none.csv"),
         "file not found"),
        ((result, "-o", result), "refusing to overwrite an input"),  # checked first
        ((result, "-o", tmp_path / "e.nc"), "must end in .html"),
    ]
    for args, message in cases:
        code, _, err = cli(monkeypatch, capsys, "view", *args)
        assert code == 2, args
        assert err.count("\n") == 1 and message in err and "Traceback" not in err, err
    assert not any(tmp_path.glob("[abcd].html")) and not any(tmp_path.glob(".*.html*"))
    assert read_results(result)["positions"].shape[0] == FRAMES   # the input is untouched


def test_page_is_self_contained(page):
    html = _page_text(page)
    start = html.index(f'<script id="{DATA_ID}"')
    outside = html[:start] + html[html.index("</script>", start):]
    refs = re.findall(r"""(?:src|href)\s*=\s*["']?([^"'\s>]*)""", html, flags=re.I)
    assert not [r for r in refs if "http" in r.lower() or "//" in r]
    assert "://" not in outside and "http:" not in outside and "https:" not in outside
    assert "default-src 'none'" in outside           # the page's CSP forbids any fetch


# ---- the page in headless Chromium ----------------------------------------------------------
def _browser() -> str:
    exe = (os.environ.get("FACEMECH_CHROMIUM") or shutil.which("chromium")
           or shutil.which("chromium-browser"))
    if not exe:
        pytest.fail("chromium is not installed: run `make test`, which installs it "
                    "(apt-get install chromium), or set FACEMECH_CHROMIUM", pytrace=False)
    return exe


def _chromium(tmp_path, url: str, *args: str, window=(900, 900)) -> subprocess.CompletedProcess:
    home = tmp_path / "home"
    home.mkdir(exist_ok=True)
    env = {**os.environ, "HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config"),
           "XDG_CACHE_HOME": str(home / ".cache")}
    cmd = [_browser(), "--headless=new", "--no-sandbox", "--disable-gpu",
           "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-first-run",
           f"--user-data-dir={tmp_path / 'profile'}", f"--window-size={window[0]},{window[1]}",
           "--virtual-time-budget=5000", *args, url]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done


def _shot(tmp_path, url: str, png) -> np.ndarray:
    """A screenshot of the page once it is drawn with its textures, (h, w, 3) int.

    The DOM is dumped in the same run just before the screenshot; it says whether the page was
    ready (its texture images decode asynchronously, which a loaded machine may not finish
    within the virtual time): if not, the run is repeated.
    """
    from PIL import Image

    for _ in range(4):
        dom = _chromium(tmp_path, url, "--dump-dom", f"--screenshot={png}").stdout
        if re.search(r'<html[^>]*data-ready="1"', dom):
            return np.asarray(Image.open(png).convert("RGB")).astype(int)
    pytest.fail(f"the page was never ready: {url}")


def _screenshot(tmp_path, page, frame: int) -> np.ndarray:
    return _shot(tmp_path, f"{page.resolve().as_uri()}#frame={frame}",
                 tmp_path / f"frame{frame}.png")


def test_viewer_draws_in_headless_chromium(page, tmp_path):
    first, last = _screenshot(tmp_path, page, 0), _screenshot(tmp_path, page, FRAMES - 1)
    assert first.shape == (900, 900, 3)
    face = (slice(90, 520), slice(220, 680))         # the middle of the face canvas
    for img in (first, last):
        px = img[face].reshape(-1, 3)
        r, g, b = px.T
        skin = (r > 90) & (r > g) & (g > b) & (r - b > 40)
        assert skin.mean() > 0.3, f"face not drawn: {skin.mean():.0%} skin-coloured pixels"
        assert (np.abs(px - BACKGROUND).sum(axis=1) > 30).mean() > 0.3
    moved = np.abs(first[face] - last[face]).sum(axis=2) > 30
    assert moved.sum() > 300, f"frames 0 and {FRAMES - 1} look alike ({moved.sum()} pixels)"
    # the measured left cheek (orange) lies on the viewer's right: the view is not mirrored
    r, g, b = (first[face][..., k] for k in range(3))
    orange = (r > 200) & (g > 110) & (g < 190) & (b < 80)
    cols = np.nonzero(orange)[1] + face[1].start
    assert orange.sum() > 10 and cols.mean() > 450 + 40
    # the plot under the face: coloured activity traces and the jaw angle
    plot = first[700:890, 40:740].reshape(-1, 3)
    coloured = (plot.max(axis=1) - plot.min(axis=1)) > 60
    assert coloured.sum() > 300, "muscle activity plot not drawn"
    assert (plot.min(axis=1) > 180).sum() > 100, "jaw angle trace not drawn"


def _probe(tmp_path, url: str) -> dict:
    """The page's ``data-probe`` (markers in CSS pixels) at the screenshots' 900 x 900 viewport.

    ``--dump-dom`` lays the page out in a viewport shorter than the window by the browser's
    frame, ``--screenshot`` in one of the window's size: the window is grown to match.
    """
    def run(pad):
        dom = _chromium(tmp_path, url, "--dump-dom", window=(900, 900 + pad)).stdout
        m = re.search(r'<html[^>]*\sdata-probe="([^"]*)"', dom)
        assert m, "the page wrote no probe"
        return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))

    got = run(_FRAME_PAD.get("pad", 0))
    if got["size"] != [900, 900]:
        _FRAME_PAD["pad"] = _FRAME_PAD.get("pad", 0) + 900 - got["size"][1]
        got = run(_FRAME_PAD["pad"])
    assert got["size"] == [900, 900], got
    return got


_FRAME_PAD: dict = {}  # the browser frame's height, once known


def _region(img, probe, x0, x1, y0, y1):
    """Pixels (n, 3) of img[y0:y1, x0:x1] (page pixels) off the drawn marker dots."""
    x0, x1, y0, y1 = (int(round(v)) for v in (x0, x1, y0, y1))
    yy, xx = np.mgrid[y0:y1, x0:x1]
    keep = np.ones(yy.shape, bool)
    for mx, my in probe["markers"].values():  # dots of 7 pixels with a dark rim
        keep &= np.hypot(xx - mx, yy - my) > 6.0
    return img[y0:y1, x0:x1][keep]


@pytest.mark.slow
def test_open_mouth_shows_cavity_teeth_and_eyes(open_mouth, tmp_path):
    """At 14 degrees of jaw the lips part: the mouth shows the dark cavity and the teeth, never
    the background; at rest it shows neither. The eyes show sclera and iris in their fissures."""
    def look(frame):
        url = f"{open_mouth.resolve().as_uri()}#frame={frame}&view=front&bg=00ff00&probe=1"
        return _shot(tmp_path, url, tmp_path / f"open{frame}.png"), _probe(tmp_path, url)

    def kinds(px):
        r, g, b = px.T
        return {"background": (g > 200) & (r < 60) & (b < 60),
                "dark": px.max(axis=1) < 70,
                "white": (px.min(axis=1) > 160) & (px.max(axis=1) - px.min(axis=1) < 60)}

    for frame in (OPEN_FRAMES - 1, 0):
        img, probe = look(frame)
        assert probe["frame"] == frame
        mk = probe["markers"]
        assert kinds(img[100:101, 5])["background"].all(), "the hash's background (#bg) unused"
        # inside the lip contour: from corner to corner, from the upper to the lower lip
        x0, x1 = mk["mouth_corner_right"][0], mk["mouth_corner_left"][0]
        y0, y1 = mk["upper_lip_center"][1], mk["lower_lip_center"][1]
        assert x1 - x0 > 60 and y1 - y0 > 20, (x0, x1, y0, y1)
        k = kinds(_region(img, probe, x0, x1, y0, y1))
        assert not k["background"].any(), f"frame {frame}: the background shows in the mouth"
        if frame:
            assert k["dark"].sum() > 300, f"no dark oral cavity ({k['dark'].sum()} pixels)"
            assert k["white"].sum() > 30, f"no teeth ({k['white'].sum()} pixels)"
        else:
            assert k["dark"].sum() < 10 and k["white"].sum() < 5, "the mouth is open at rest"
        # the eyes: white sclera and a dark iris in the fissure, unlike the cheek
        cx, cy = mk["cheek_left"]
        cheek = _region(img, probe, cx - 8, cx + 8, cy - 4, cy + 4).mean(axis=0)
        for eye in ("eye_left", "eye_right"):
            ex, ey = mk[eye]
            px = _region(img, probe, ex - 18, ex + 18, ey - 5, ey + 5)
            assert kinds(px)["white"].sum() > 15, f"{eye}: no sclera"
            assert (px.max(axis=1) < 110).sum() > 15, f"{eye}: no iris or pupil"
            assert np.abs(px - cheek).sum(axis=1).mean() > 60, f"{eye} looks like the cheek"


def test_viewer_hooks_in_headless_chromium(page, tmp_path):
    for _ in range(4):  # as in _shot: the textures may decode after the virtual time ran out
        dom = _chromium(tmp_path, f"{page.resolve().as_uri()}#t=0.2", "--dump-dom").stdout
        if re.search(r'<html[^>]*data-ready="1"', dom):
            break
    assert re.search(r'<html[^>]*data-ready="1"', dom), "the first frame was not drawn"
    assert re.search(r'<html[^>]*data-frame="12"', dom)  # t = 0.2 s at 60 Hz, paused there


def _page_text(path) -> str:
    return path.read_text(encoding="utf-8")
