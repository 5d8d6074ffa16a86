"""The interactive viewer: its data block decodes back to the results, the CLI refuses bad input,
and headless Chromium draws the face, its motion and the plot (``make test`` installs Chromium)."""

from __future__ import annotations

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
from facemech.viz.viewer import (
    DATA_ID,
    decode,
    read_data_block,
    resample_measured,
    viewer_data,
    write_viewer,
)

FRAMES = 24
BACKGROUND = np.array([22, 24, 29])  # the face canvas's clear colour (viewer_template.html)


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """A short lip-spreading gesture with the jaw opening to 12 degrees, on the coarse face."""
    import facemech as fm

    ramp = np.linspace(0.0, 1.0, FRAMES)[:, None]
    act = activity(FRAMES, ZYG=0.8, RIS=0.8) * ramp
    sim = fm.simulate(fm.default_face("default-coarse"), act, np.radians(12.0) * ramp[:, 0])
    path = tmp_path_factory.mktemp("viewer") / "gesture.nc"
    fm.write_results(path, sim)
    return path


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
    np.testing.assert_allclose(decode(d["activity"], "f4", (FRAMES, 16)), ds["activity"].values,
                               rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(decode(d["jawDeg"], "f4"), np.degrees(ds["jaw_angle"].values),
                               rtol=1e-6, atol=1e-6)
    assert d["jawDeg"] and abs(decode(d["jawDeg"], "f4")[-1] - 12.0) < 1e-4
    assert d["measured"] is None


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
        ((result, "-o", result), "must end in .html"),
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


def _chromium(tmp_path, url: str, *args: str) -> subprocess.CompletedProcess:
    home = tmp_path / "home"
    home.mkdir(exist_ok=True)
    env = {**os.environ, "HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config"),
           "XDG_CACHE_HOME": str(home / ".cache")}
    cmd = [_browser(), "--headless=new", "--no-sandbox", "--disable-gpu",
           "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-first-run",
           f"--user-data-dir={tmp_path / 'profile'}", "--window-size=900,900",
           "--virtual-time-budget=5000", *args, url]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done


def _screenshot(tmp_path, page, frame: int) -> np.ndarray:
    from PIL import Image

    png = tmp_path / f"frame{frame}.png"
    _chromium(tmp_path, f"{page.resolve().as_uri()}#frame={frame}", f"--screenshot={png}")
    return np.asarray(Image.open(png).convert("RGB")).astype(int)


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


def test_viewer_hooks_in_headless_chromium(page, tmp_path):
    dom = _chromium(tmp_path, f"{page.resolve().as_uri()}#t=0.2", "--dump-dom").stdout
    assert re.search(r'<html[^>]*data-ready="1"', dom), "the first frame was not drawn"
    assert re.search(r'<html[^>]*data-frame="12"', dom)  # t = 0.2 s at 60 Hz, paused there


def _page_text(path) -> str:
    return path.read_text(encoding="utf-8")
