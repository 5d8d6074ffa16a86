"""One per-frame error (RMS over the markers used, mm; median and maximum, with warnings) and
the 3-D correlation (Pitermann & Munhall 2001, eq. 7) in both forms, through ``compare``."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from conftest import activity
from conftest import run_cli as cli
from facemech import simulate
from facemech.io.results import write_results
from facemech.kinematics import stats
from facemech.params import preset
from facemech.physics.model import model as face_model


def test_corr3d_is_one_for_itself_in_both_forms():
    rng = np.random.default_rng(0)
    for n in (3, 20, 60, 157):
        v = rng.normal(scale=1e-3, size=(n, 3)) + [0.03, 0.05, 0.09]
        assert stats.corr3d(v, v) == 1.0
        assert stats.corr3d(v, v, published=False) == 1.0
    assert stats.corr3d(v, 2 * v + 1) == pytest.approx(1.0, abs=1e-12)
    assert stats.corr3d(v, -v) == -1.0
    # a marker still to 0.05 um at 10 cm: the raw-moment form gave self-correlations off 1
    # (the "1.0025" of issue 15); about the centroid it is exactly 1
    still = np.array([0.03, 0.05, 0.09]) + rng.normal(scale=5e-8, size=(60, 3))
    n = len(still)
    raw = (np.sum(still * still) / n - still.mean(0) @ still.mean(0)) * n / (n - 1)
    assert abs(raw / stats.std3d(still) ** 2 - 1) > 1e-4  # what the old form computed
    assert stats.corr3d(still, still) == 1.0
    # per marker at once, (frames, markers, 3)
    two = np.stack([v, v[::-1]], axis=1)
    np.testing.assert_array_equal(stats.corr3d(two, two), [1.0, 1.0])


def test_corr3d_by_hand_for_a_small_case():
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 2.0]])
    w = np.array([[0.0, 1.0, 0.0], [1.0, 1.0, 1.0], [1.0, 2.0, 0.0], [4.0, 2.0, 1.0]])
    # centroids (1.5, 0.5, 0.5) and (1.5, 1.5, 0.5); sum of centred dot products 6 (x) + 1 (y)
    # + 1 (z) = 8;
    # sum |v - mu_v|^2 = 5 + 1 + 3 = 9, sum |w - mu_w|^2 = 9 + 1 + 1 = 11
    hand = 8.0 / np.sqrt(9.0 * 11.0)
    n = len(v)
    # the published form, 1/n throughout, and the unbiased, 1/(n - 1) throughout
    pub = (8.0 / n) / (np.sqrt(9.0 / n) * np.sqrt(11.0 / n))
    unb = (8.0 / (n - 1)) / (np.sqrt(9.0 / (n - 1)) * np.sqrt(11.0 / (n - 1)))
    assert stats.corr3d(v, w) == pytest.approx(hand, rel=1e-14)
    assert stats.corr3d(v, w) == pytest.approx(pub, rel=1e-14)
    assert stats.corr3d(v, w, published=False) == pytest.approx(unb, rel=1e-14)
    # eq. 7 as printed (1/n over the (n - 1) sigmas of eq. 6) is (n - 1)/n of it
    printed = (8.0 / n) / (stats.std3d(v) * stats.std3d(w))
    assert printed == pytest.approx(hand * (n - 1) / n)


def test_corr3d_of_no_motion_is_nan_and_gaps_are_left_out():
    v = np.tile([0.03, 0.05, 0.09], (30, 1))
    w = v + np.random.default_rng(1).normal(scale=1e-3, size=v.shape)
    assert np.isnan(stats.corr3d(v, w)) and np.isnan(stats.corr3d(w, v))
    assert np.isnan(stats.corr3d(v, v, published=False))
    gap = w.copy()
    gap[5] = np.nan
    keep = np.ones(len(w), bool)
    keep[5] = False
    assert stats.corr3d(gap, w) == 1.0
    assert stats.corr3d(gap, 2 * w) == pytest.approx(stats.corr3d(w[keep], 2 * w[keep]))


def test_frame_errors_are_the_rms_over_the_markers_used():
    rng = np.random.default_rng(2)
    data = rng.normal(scale=0.01, size=(10, 4, 3))
    model = data.copy()
    model[:, 0] += [0.003, 0.0, 0.0]  # 3 mm on one marker of four
    model[:, 1] += [0.0, 0.0, -0.004]  # 4 mm on another
    err = stats.frame_errors(model, data)
    np.testing.assert_allclose(err, np.sqrt((0.003**2 + 0.004**2) / 4), rtol=1e-12)
    data[2, 3] = np.nan  # a marker missing at frame 2: the RMS over the other three
    data[4] = np.nan  # no marker at frame 4
    err = stats.frame_errors(model, data)
    assert err[2] == pytest.approx(np.sqrt((0.003**2 + 0.004**2) / 3), rel=1e-12)
    assert np.isnan(err[4])
    s = stats.error_summary(err, 60.0)
    assert s["frames"] == 9 and s["max_frame"] == 2
    assert s["max_mm"] == pytest.approx(np.sqrt(25 / 3), rel=1e-12)
    assert s["median_mm"] == pytest.approx(2.5, rel=1e-12)
    assert s["summary_mm"]["median"] == s["median_mm"]
    assert any("1 frames have no marker" in w for w in s["warnings"])


def test_error_summary_warnings():
    e = np.full(200, 0.1e-3)  # 0.1 mm everywhere
    assert stats.error_summary(e, 60.0)["warnings"] == []
    e[74] = 0.8e-3  # below 1 mm but 8 x the median
    w = stats.error_summary(e, 60.0)["warnings"]
    assert w == ["maximum per-frame error 0.8 mm at 1.23 s is more than 5 x the median "
                 "(0.1 mm)"]
    e[74] = 8.6e-3
    s = stats.error_summary(e, 60.0)
    assert s["warnings"][0] == "maximum per-frame error 8.6 mm at 1.23 s is more than 1 mm"
    assert len(s["warnings"]) == 2 and s["max_time_s"] == pytest.approx(74 / 60)
    flat = np.full(10, 2e-3)  # 2 mm everywhere: over 1 mm, not over 5 x the median
    assert stats.error_summary(flat, 100.0)["warnings"] == [
        "maximum per-frame error 2 mm at 0.00 s is more than 1 mm"]
    times = np.arange(10) / 100.0 + 5.0
    assert stats.error_summary(flat, time_s=times)["max_time_s"] == 5.0
    assert stats.error_summary(np.full(3, np.nan))["frames"] == 0


@pytest.fixture(scope="module")
def results_pair(seeds_face, tmp_path_factory):
    """A short simulation's results and a copy with one marker still to 0.05 um, and a copy
    with every marker moved 2 mm along x."""
    d = tmp_path_factory.mktemp("compare")
    sim = simulate(face_model(seeds_face, preset("lucero1999")), activity(30, OOS=0.5, ZYG=0.3),
                   integrator="implicit")
    markers = sim.markers.copy()
    markers[:, 0] = markers[0, 0] + np.random.default_rng(3).normal(scale=5e-8,
                                                                     size=markers[:, 0].shape)
    a = write_results(d / "a.nc", dataclasses.replace(sim, markers=markers))
    shifted = markers + np.array([0.002, 0.0, 0.0])
    b = write_results(d / "b.nc", dataclasses.replace(sim, markers=shifted))
    return a, b, sim


def test_compare_a_with_itself_through_the_cli(results_pair, monkeypatch, capsys):
    a, _, sim = results_pair
    code, out, err = cli(monkeypatch, capsys, "compare", a, a, "--json")
    assert code == 0 and err == ""
    res = json.loads(out)
    assert len(res["markers"]) == len(sim.marker_names)
    for name, v in res["markers"].items():
        assert v["corr3d_published"] == 1.0, name
        assert v["corr3d_unbiased"] == 1.0, name
    assert res["error"]["median_mm"] == 0.0 and res["error"]["max_mm"] == 0.0
    assert res["error"]["warnings"] == []


def test_compare_known_offset_and_warning(results_pair, monkeypatch, capsys):
    a, b, _ = results_pair
    code, out, err = cli(monkeypatch, capsys, "compare", b, a, "--json")
    assert code == 0
    res = json.loads(out)
    assert res["error"]["median_mm"] == pytest.approx(2.0, rel=1e-9)
    assert res["error"]["max_mm"] == pytest.approx(2.0, rel=1e-9)
    assert res["frame_error_mm"]["min"] == pytest.approx(2.0, rel=1e-9)
    lines = err.strip().splitlines()  # every frame is 2 mm off: one warning, not the 5 x one
    assert len(lines) == 1 and lines[0].startswith("facemech: warning: maximum per-frame error "
                                                   "2 mm at ")
    assert lines[0].endswith(" s is more than 1 mm")
    assert res["error"]["warnings"] == [err.strip().removeprefix("facemech: warning: ")]
    for v in res["markers"].values():  # a translation keeps every 3-D correlation at 1
        assert v["corr3d_published"] == pytest.approx(1.0, abs=1e-9)
    code, out, err = cli(monkeypatch, capsys, "compare", b, a)
    assert code == 0 and "median 2.000, max 2.000 at" in out
    assert "more than 1 mm" in err
