"""Recordings as they come: empty ends dropped with a note, ``markers trim``, the fill-gaps
hint only where fill-gaps helps, roles kept through CSV, sensor names matched as meant, and
every marker command on articulography (MOCHA's real file and twins, .txy with empty ends)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.io.markers import read_markers, write_markers
from facemech.kinematics.trim import drop_empty_ends, empty_ends, trim
from facemech.markerset import MarkerSet, match_name, shared_names
from test_articulography import XRMB_STEP_S, XRMB_UM, write_mocha

_ROOT = Path(__file__).resolve().parents[2]
#: MOCHA-TIMIT fsew0_001 (the real recording): shipped in the repository, or beside it
MOCHA = next((p for p in (_ROOT / "data" / "mocha" / "fsew0_001.ema",
                          _ROOT.parent / "shared" / "data" / "mocha" / "fsew0_001.ema")
              if p.is_file()),
             _ROOT / "data" / "mocha" / "fsew0_001.ema")
needs_mocha = pytest.mark.skipif(not MOCHA.is_file(), reason="the MOCHA recording is absent")
LEAD, TRAIL, N = 6, 3, 60
TIP_RISE = 0.5  #: the tongue tip (T1) rises by this share of the jaw's drop


def write_txy_empty_ends(path, *, lead=LEAD, trail=TRAIL, n=N, hole=None):
    """An X-ray microbeam .txy whose first ``lead`` and last ``trail`` frames have every
    pellet lost (1000000), as recordings often come; ``hole``: (frame, pellet) lost inside.
    The lower lip and incisor drop 3 mm together (micrometres), the tongue tip (T1) rises
    1.5 mm."""
    drop = 3000 * (1 - np.cos(np.pi * np.arange(n) / (n - 1))) / 2
    rows = []
    for k in range(n):
        cells = [f"{k * XRMB_STEP_S * 1e3:.10g}"]
        for p, (x, y) in XRMB_UM.items():
            lost = k < lead or k >= n - trail or (hole is not None and hole == (k, p))
            dy = -drop[k] if p in ("LL", "MNI") else (TIP_RISE * drop[k] if p == "T1" else 0)
            cells += (["1000000", "1000000"] if lost else [str(x), f"{y + dy:.0f}"])
        rows.append("\t".join(cells))
    path.write_text("\n".join(rows) + "\n")
    return path


def _snapshot(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())
            if p.is_file()}


# ---- empty ends -----------------------------------------------------------------------------
def test_txy_with_empty_ends_reads_without_them(tmp_path):
    ms = read_markers(write_txy_empty_ends(tmp_path / "tp.txy"))
    assert ms.n_frames == N - LEAD - TRAIL
    assert ms.valid.all()
    assert ms.time[0] == pytest.approx(LEAD * XRMB_STEP_S, abs=1e-9)  # the file's times kept
    assert ms.rate == pytest.approx(145.6, rel=1e-6)
    assert ms.meta["dropped_frames"] == [LEAD, TRAIL]
    note = [n for n in ms.meta["notes"] if n.startswith("dropped")]
    assert note and "6 leading" in note[0] and "3 trailing" in note[0], ms.meta["notes"]


def test_markers_info_says_what_was_dropped(monkeypatch, capsys, tmp_path):
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info",
                             write_txy_empty_ends(tmp_path / "tp.txy"))
    assert code == 0, err
    assert "note: dropped 6 leading" in out and "axes: model z (forward) = +file x" in out


def test_est_break_frames_at_both_ends_are_dropped(tmp_path):
    present = np.ones(40)
    present[:4] = 0
    present[-2:] = 0
    ms = read_markers(write_mocha(tmp_path / "b.ema", present=present))
    assert ms.n_frames == 34 and ms.time[0] == pytest.approx(4 / 500.0)
    assert ms.meta["dropped_frames"] == [4, 2]


def test_interior_empty_frames_stay(tmp_path):
    present = np.ones(40)
    present[10:13] = 0
    ms = read_markers(write_mocha(tmp_path / "i.ema", present=present))
    assert ms.n_frames == 40 and int((~ms.valid.any(axis=1)).sum()) == 3


def test_empty_ends_api():
    pos = np.zeros((10, 2, 3))
    pos[:2] = np.nan
    pos[-3:, 0] = np.nan
    pos[-1:] = np.nan
    ms = MarkerSet(pos, ("a", "b"), 100.0)
    assert empty_ends(ms) == (2, 1)
    out, note = drop_empty_ends(ms)
    assert out.n_frames == 7 and out.time[0] == pytest.approx(0.02)
    assert "2 leading" in note and "1 trailing" in note
    same, none = drop_empty_ends(out)
    assert same is out and none is None
    with pytest.raises(InputError):
        drop_empty_ends(MarkerSet(np.full((5, 1, 3), np.nan), ("a",), 10.0))


# ---- trim -----------------------------------------------------------------------------------
def _line(n=100, rate=100.0):
    pos = np.zeros((n, 1, 3))
    pos[:, 0, 1] = np.arange(n) * 1e-3
    return MarkerSet(pos, ("m",), rate)


def test_trim_by_time_and_by_frames():
    ms = _line()
    a = trim(ms, start=0.2, stop=0.5)
    assert a.n_frames == 31 and a.time[0] == pytest.approx(0.2) and a.time[-1] == pytest.approx(0.5)
    assert a.marker("m")[0, 1] == pytest.approx(0.020)
    b = trim(ms, first=10, last=19)
    assert b.n_frames == 10 and b.meta["trimmed"] == [10, 19]
    assert trim(ms, start=0.9).n_frames == 10 and trim(ms, last=4).n_frames == 5


@pytest.mark.parametrize("kw, field", [({"start": 0.1, "first": 2}, "start"),
                                       ({"first": 200}, "first"), ({"last": -1}, "last"),
                                       ({"start": 5.0}, "start"), ({"stop": -1.0}, "stop"),
                                       ({"start": 0.5, "stop": 0.5}, "stop"),
                                       ({"start": float("nan")}, "start")])
def test_trim_refuses_what_keeps_no_recording(kw, field):
    with pytest.raises(InputError) as err:
        trim(_line(), **kw)
    assert err.value.field == field


def test_markers_trim_command(monkeypatch, capsys, tmp_path):
    src = write_txy_empty_ends(tmp_path / "tp.txy")
    before = src.read_bytes()
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", src, "-o",
                             tmp_path / "cut.csv", "--start", "0.1", "--stop", "0.3")
    assert code == 0, err
    cut = read_markers(tmp_path / "cut.csv")
    assert cut.time[0] >= 0.1 - 1e-9 and cut.time[-1] <= 0.3 + 1e-9
    assert cut.n_frames == int(np.sum((np.arange(N) * XRMB_STEP_S >= 0.1 - 1e-9)
                                      & (np.arange(N) * XRMB_STEP_S <= 0.3 + 1e-9)))
    # the CSV keeps the sensors' roles and planarity: invert and compare read it as the .txy
    src_ms = read_markers(src)
    assert cut.meta["roles"] == src_ms.meta["roles"] and cut.meta["midsagittal"] is True
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", src, "-o",
                             tmp_path / "f.csv", "--first", "2", "--last", "11")
    assert code == 0 and "kept frames 2-11" in out, err
    assert read_markers(tmp_path / "f.csv").n_frames == 10
    snap = _snapshot(tmp_path)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", src, "-o", src)
    assert code == 2 and "refusing to overwrite an input" in err
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", src, "-o",
                             tmp_path / "x.csv", "--first", "3", "--start", "0.1")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert _snapshot(tmp_path) == snap and src.read_bytes() == before


def test_markers_trim_without_bounds_drops_empty_ends_of_any_format(monkeypatch, capsys,
                                                                    tmp_path):
    pos = np.zeros((20, 2, 3))
    pos[:, 1, 0] = 0.03
    pos[:3] = np.nan
    pos[-2:] = np.nan
    write_markers(tmp_path / "m.csv", MarkerSet(pos, ("a", "b"), 60.0), units="mm")
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", tmp_path / "m.csv",
                             "-o", tmp_path / "t.csv")
    assert code == 0, err
    assert "3 leading" in out and "2 trailing" in out
    assert read_markers(tmp_path / "t.csv").valid.all()


# ---- the fill-gaps hint ----------------------------------------------------------------------
def test_fill_gaps_says_trim_for_gaps_at_an_end(monkeypatch, capsys, tmp_path):
    pos = np.zeros((30, 2, 3))
    pos[:, 1, 0] = 0.03
    pos[:4, 0] = np.nan  # marker a starts late: an end gap, not fillable
    pos[10:12, 1] = np.nan  # marker b: an interior gap
    write_markers(tmp_path / "m.csv", MarkerSet(pos, ("a", "b"), 60.0), units="mm")
    code, out, err = run_cli(monkeypatch, capsys, "markers", "fill-gaps", tmp_path / "m.csv",
                             "-o", tmp_path / "f.csv")
    assert code == 0 and "filled 1 gaps" in out
    assert "facemech markers trim" in err and "a: frames 0-3 (4) at an end" in err


def test_gap_hint_where_fill_gaps_helps():
    from facemech.workflows.markers import gap_hint

    pos = np.zeros((10, 1, 3))
    pos[0] = np.nan
    pos[5] = np.nan
    ms = MarkerSet(pos, ("a",), 10.0)
    assert "trim" in gap_hint(ms, 0) and "fill-gaps)" not in gap_hint(ms, 0)
    assert "fill-gaps" in gap_hint(ms, 5)


# ---- names as the user means them ---------------------------------------------------------------
def test_names_match_ignoring_case_where_unambiguous():
    assert match_name("ul", ("UL", "LL")) == "UL"
    assert match_name("UL", ("UL", "ul")) == "UL"
    with pytest.raises(InputError) as err:
        match_name("Ul", ("UL", "ul"))
    assert "differ only in case" in str(err.value)
    with pytest.raises(InputError):
        match_name("zz", ("UL",))
    assert shared_names(("ul", "ll", "li"), ("UL", "LL", "MNI")) == [("ul", "UL"), ("ll", "LL")]
    with pytest.raises(InputError):
        shared_names(("ul",), ("UL", "Ul"))
    ms = MarkerSet(np.zeros((3, 2, 3)), ("UL", "LL"), 10.0, meta={"roles": {"UL": "upper_lip"}})
    assert ms.select(["ll", "ul"]).names == ("LL", "UL")
    assert ms.renamed(["ul", "ll"]).meta["roles"] == {"ul": "upper_lip"}


# ---- marker commands on articulography ---------------------------------------------------------
@needs_mocha
def test_compare_across_rates_resamples_as_invert_does(monkeypatch, capsys, tmp_path):
    """The MOCHA file (500 Hz) against its own 60-Hz resampling (a CSV written by facemech):
    the 500-Hz side is put on the 60-Hz frames by the same low-pass and spline, so the two agree
    to the rounding of the CSV's times (1 us), and the note says how."""
    from facemech.kinematics.resample import resample

    ms = read_markers(MOCHA)
    write_markers(tmp_path / "m60.csv", resample(ms, 60.0), units="mm")
    code, out, err = run_cli(monkeypatch, capsys, "compare", MOCHA, tmp_path / "m60.csv",
                             "--markers", "UL,LL,li", "--json")
    assert code == 0, err
    res = json.loads(out)
    assert res["frames"] == 116
    assert res["error"]["median_mm"] < 1e-4  # the CSV's times have 6 decimals: 2e-6 mm
    assert "resampled onto 116 frames at 60 Hz (low-passed, cubic spline)" in " ".join(
        err.split())


@needs_mocha
def test_compare_refuses_recordings_without_a_common_span(monkeypatch, capsys, tmp_path):
    ms = read_markers(MOCHA)
    later = MarkerSet(ms.positions[:100], ms.names, ms.rate, time=ms.time[:100] + 10.0,
                      source_units="mm")
    write_markers(tmp_path / "late.csv", later, units="mm")
    code, _, err = run_cli(monkeypatch, capsys, "compare", MOCHA, tmp_path / "late.csv")
    assert code == 2 and "share no time span" in err and "Traceback" not in err


@pytest.fixture(scope="module")
def inverted(tmp_path_factory):
    """MOCHA's real recording and a .txy twin with empty ends, each inverted once on the coarse
    face (the results the marker commands are tried on)."""
    from facemech.workflows.invert import invert

    folder = tmp_path_factory.mktemp("inverted")
    txy = write_txy_empty_ends(folder / "tp.txy")
    out = {}
    for name, path in (("mocha", MOCHA), ("txy", txy)):
        if not path.is_file():
            pytest.skip("the MOCHA recording is absent")
        invert(path, folder / f"{name}.nc", face="default-coarse")
        out[name] = (path, folder / f"{name}.nc")
    return out


@pytest.mark.parametrize("which", ["mocha", "txy"])
def test_compare_recording_with_its_inversion(monkeypatch, capsys, which, inverted):
    """compare reproduces the inversion's own per-frame error: the recording on the results'
    frames, its lips laid on the results' data as invert lays them."""
    from facemech import read_results

    src, nc = inverted[which]
    code, out, err = run_cli(monkeypatch, capsys, "compare", src, nc, "--json")
    assert code == 0, err
    res = json.loads(out)
    rms = read_results(nc)["rms_error"].values * 1e3
    assert res["frames"] == len(rms)
    assert res["error"]["median_mm"] == pytest.approx(float(np.nanmedian(rms)), abs=1e-6)
    assert res["error"]["max_mm"] == pytest.approx(float(np.nanmax(rms)), abs=1e-6)
    assert any("laid on the results' marker data" in n for n in res["notes"])
    if which == "txy":  # the empty ends, said by the inversion and by compare
        assert "tp.txy: dropped 6 leading" in read_results(nc).attrs["notes"]
        assert any("dropped 6 leading" in n for n in res["notes"])


@pytest.mark.parametrize("which", ["mocha", "txy"])
def test_plot_measured_and_regions_on_inverted_articulography(monkeypatch, capsys, tmp_path,
                                                              which, inverted):
    src, nc = inverted[which]
    lips = "ul,ll" if which == "mocha" else "UL,LL"
    code, _, err = run_cli(monkeypatch, capsys, "plot", nc, "-o", tmp_path / "p.png",
                           "--measured", src, "--markers", lips.upper())
    assert code == 0, err
    assert (tmp_path / "p.png").stat().st_size > 10_000
    code, out, err = run_cli(monkeypatch, capsys, "regions", nc, "-o", tmp_path / "reg")
    assert code == 0, err
    assert "no eigenregion or orthogonal-region maps: 2 markers" in out
    summary = json.loads((tmp_path / "reg" / "summary.json").read_text())
    assert summary["markers"] == 2 and set(summary["figures"]) == {"r_values"}
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".reg")]


def test_regions_on_results_whose_names_differ_in_case(monkeypatch, capsys, tmp_path, inverted):
    """MOCHA's ul/ll and X-ray microbeam's UL/LL are the same lips."""
    code, out, err = run_cli(monkeypatch, capsys, "regions", inverted["mocha"][1],
                             inverted["txy"][1], "-o", tmp_path / "both")
    assert code == 0, err
    summary = json.loads((tmp_path / "both" / "summary.json").read_text())
    assert summary["utterances"] == 2


@needs_mocha
def test_regions_on_midsagittal_articulography_draws_maps_in_z_and_y(monkeypatch, capsys,
                                                                     tmp_path):
    code, out, err = run_cli(monkeypatch, capsys, "regions", MOCHA, "-o", tmp_path / "r")
    assert code == 0, err
    assert {"eigenregions.png", "orthogonal_regions.png"} <= {
        p.name for p in (tmp_path / "r").iterdir()}


@needs_mocha
def test_regions_leaves_no_folder_when_it_fails(monkeypatch, capsys, tmp_path):
    from facemech.workflows import regions as wr

    def broken(*a, **k):
        raise InputError("drawing failed", field="figure")

    monkeypatch.setattr(wr, "write", broken)
    code, _, err = run_cli(monkeypatch, capsys, "regions", MOCHA, "-o", tmp_path / "r")
    assert code == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@needs_mocha
def test_markers_convert_keeps_roles(monkeypatch, capsys, tmp_path):
    code, _, err = run_cli(monkeypatch, capsys, "markers", "convert", MOCHA, tmp_path / "m.csv")
    assert code == 0, err
    back, src = read_markers(tmp_path / "m.csv"), read_markers(MOCHA)
    assert back.meta["roles"] == src.meta["roles"] and back.meta["midsagittal"] is True
    assert np.allclose(back.positions, src.positions, atol=1e-9)


def test_region_maps_need_three_markers_off_one_line():
    from facemech.workflows.regions import _plane

    face = np.array([[-30.0, 0, 0], [30, 0, 0], [0, 20, 10], [0, -20, 12]])
    xy, axes, why = _plane(face)
    assert axes == [0, 1] and why is None
    sagittal = np.array([[0.0, 8, 10], [0, -14, 11], [0, -10, -12], [0, -4, -30]])
    xy, axes, why = _plane(sagittal)
    assert axes == [2, 1] and why is None  # z across, y up
    line = np.array([[0.0, 0, 0], [0, 1, 1], [0, 2, 2]])
    assert "one line" in _plane(line)[2]
    assert "2 markers" in _plane(face[:2])[2]


def test_the_tongue_tip_coil_drives_the_rendered_tongue(inverted):
    """The .txy twin's T1 rises 1.5 mm while the lower incisor drops 3 mm: in the mandible's
    frame the tip rises 4.5 mm (from the first kept frame), and does not move forward."""
    from facemech import read_results
    from facemech.io.results import results_tongue

    ds = read_results(inverted["txy"][1])
    pose = results_tongue(ds)
    t = np.arange(N) * XRMB_STEP_S
    drop = 3.0 * (1 - np.cos(np.pi * np.arange(N) / (N - 1))) / 2
    rise = (1 + TIP_RISE) * (drop - drop[LEAD])  # mm, from the first kept frame
    want = np.interp(t[LEAD] + ds["time"].values, t, rise)
    assert pose[:, 1] * 1e3 == pytest.approx(want, abs=0.15)
    assert np.abs(pose[:, 0]).max() < 1e-6
    assert "the rendered tongue tip follows the coil T1" in ds.attrs["notes"]
    mocha = results_tongue(read_results(inverted["mocha"][1]))
    assert mocha is not None and np.ptp(mocha[:, 1]) > 0.005  # MOCHA's tt moves > 5 mm
