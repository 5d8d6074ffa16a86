"""Stimuli for perception experiments: manipulations, their measured parameters, design tables."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import activity, run_cli
from facemech import simulate
from facemech.analysis.describe import describe, marker_nodes
from facemech.errors import InputError
from facemech.io.results import read_results, to_dataset, write_dataset
from facemech.physics.model import model as face_model
from facemech.speech import stimuli as st
from facemech.speech.audio import Audio, onset, read_wav, shift, write_wav
from facemech.workflows.stimuli import run_design

RATE = 16000
FRAMES = 24


def clicks(period_s: float, seconds: float, first_s: float = 0.05) -> Audio:
    """A click train: single full-scale-half samples every period_s from first_s."""
    x = np.zeros((int(round(seconds * RATE)), 1), np.int16)
    x[np.arange(int(first_s * RATE), len(x), int(round(period_s * RATE))), 0] = 16000
    return Audio(x, RATE)


@pytest.fixture(scope="module")
def item(face, tmp_path_factory):
    """A short utterance-like movement (lips and jaw) as results file plus click-train WAV."""
    folder = tmp_path_factory.mktemp("item")
    a = activity(FRAMES)
    bump = np.sin(np.linspace(0, np.pi, FRAMES))
    a[:, 2] = 0.5 * bump  # OOS: the lips
    sim = simulate(face_model(face), a, np.radians(5.0) * bump)
    write_dataset(folder / "a.nc", to_dataset(sim))
    write_wav(folder / "a.wav", clicks(0.05, FRAMES / 60))
    write_wav(folder / "b.wav", clicks(0.08, FRAMES / 60, first_s=0.1))
    return folder


@pytest.fixture(scope="module")
def ds(item):
    return read_results(item / "a.nc")


def lag_ms(a: Audio, b: Audio) -> float:
    """How much later b is than a (ms), from the peak of their cross-correlation."""
    from scipy.signal import correlate

    x, y = a.mono(), b.mono()
    c = correlate(y, x, mode="full")
    return 1e3 * (int(np.argmax(c)) - (len(x) - 1)) / a.rate


def lip_nodes(ds):
    n = marker_nodes(ds)
    return [n["upper_lip_center"], n["lower_lip_center"]]


def test_amplitude_half_moves_lips_half(ds):
    d1 = describe(ds)
    d2 = describe(st.scale_amplitude(ds, 0.5, "lips"))
    for k in ("upper_lip_center", "lower_lip_center"):
        ratio = d2.landmarks[k].peak_displacement / d1.landmarks[k].peak_displacement
        assert abs(ratio - 0.5) < 0.05 * 0.5
        # mm: the lips do move (measured: upper lip 0.90 mm, since the contacts are stepped on
        # their own, issue 32; 1.1 before)
        assert d1.landmarks[k].peak_displacement > 0.5
    # frame by frame, the whole face at 0.5: every displacement halves, the jaw angle too
    half = st.scale_amplitude(ds, 0.5)
    rest = ds["rest_positions"].values
    np.testing.assert_allclose(half["positions"].values - rest,
                               0.5 * (ds["positions"].values - rest), atol=1e-12)
    np.testing.assert_allclose(half["jaw_angle"].values, 0.5 * ds["jaw_angle"].values)
    assert json.loads(half.attrs["stimulus"])[-1]["factor"] == 0.5


def test_region_scaling_leaves_other_regions(ds):
    part = st.region_partition(ds)
    np.testing.assert_allclose(part["lips"] + part["jaw"] + part["upper_face"], 1.0)
    nodes = marker_nodes(ds)
    assert part["lips"][lip_nodes(ds)].min() == 1.0
    assert part["jaw"][nodes["chin"]] == 1.0 and part["upper_face"][nodes["nasion"]] == 1.0
    pos = ds["positions"].values
    for region, other in (("lips", "lips"), ("upper_face", "upper_face"), ("jaw", "jaw")):
        out = st.scale_amplitude(ds, 0.2, region)
        untouched = part[other] == 0.0
        assert untouched.sum() > 100
        np.testing.assert_array_equal(out["positions"].values[:, untouched], pos[:, untouched])
        moved = part[other] == 1.0
        assert not np.allclose(out["positions"].values[:, moved], pos[:, moved])
        same_jaw = np.array_equal(out["jaw_angle"].values, ds["jaw_angle"].values)
        assert same_jaw == (region != "jaw")
    # markers follow their nodes
    out = st.scale_amplitude(ds, 0.2, "lips,jaw")
    names = [str(m) for m in ds["marker"].values]
    i = names.index("chin")
    np.testing.assert_array_equal(out["markers"].values[:, i],
                                  out["positions"].values[:, nodes["chin"]])


@pytest.mark.parametrize("ms", [40.0, -40.0])
def test_av_offset_moves_audio(ds, item, ms):
    audio = read_wav(item / "a.wav")
    out, moved = st.offset_audio(ds, audio, ms)
    assert len(moved.samples) == len(audio.samples)
    assert abs(lag_ms(audio, moved) - ms) < 1.0
    assert abs(onset(moved) - onset(audio) - ms / 1e3) < 1e-3
    assert out.attrs["audio_offset_ms"] == pytest.approx(ms)
    assert describe(out).audio_offset_ms == pytest.approx(ms)
    k = int(round(ms * RATE / 1e3))
    if k > 0:
        np.testing.assert_array_equal(moved.samples[k:], audio.samples[:-k])
    else:
        np.testing.assert_array_equal(moved.samples[:k], audio.samples[-k:])


def test_dub_takes_b_audio_and_a_face(ds, item):
    a, b = read_wav(item / "a.wav"), read_wav(item / "b.wav")
    out, audio = st.dub(ds, a, b, align="onset")
    np.testing.assert_array_equal(out["positions"].values, ds["positions"].values)
    assert len(audio.samples) == len(a.samples)
    assert onset(audio) == pytest.approx(onset(a), abs=1.0 / RATE)
    k = int(round((onset(a) - onset(b)) * RATE))  # b's clicks moved 50 ms earlier
    assert k == -800
    np.testing.assert_array_equal(audio.samples[:len(b.samples) + k], b.samples[-k:])
    out, audio = st.dub(ds, a, b, align="start")
    np.testing.assert_array_equal(audio.samples, b.samples)
    assert json.loads(out.attrs["stimulus"])[-1]["manipulation"] == "dub"


def test_freeze_holds_region(ds):
    part = st.region_partition(ds)
    pos, rest = ds["positions"].values, ds["rest_positions"].values
    lips = part["lips"] == 1.0
    out = st.freeze(ds, "lips")
    np.testing.assert_allclose(out["positions"].values[:, lips], np.broadcast_to(
        rest[lips], pos[:, lips].shape), atol=1e-15)
    free = part["lips"] == 0.0
    np.testing.assert_array_equal(out["positions"].values[:, free], pos[:, free])
    assert describe(out).lip_aperture.max == pytest.approx(0.0, abs=1e-9)
    held = st.freeze(ds, "jaw", at=12)
    jaw = part["jaw"] == 1.0
    np.testing.assert_allclose(held["positions"].values[:, jaw],
                               np.broadcast_to(pos[12, jaw], pos[:, jaw].shape), atol=1e-15)
    np.testing.assert_array_equal(held["jaw_angle"].values, ds["jaw_angle"].values[12])


def test_time_scale_doubles_duration(ds, item):
    audio = read_wav(item / "a.wav")
    out, stretched = st.time_scale_with_audio(ds, audio, 2.0)
    d1, d2 = describe(ds), describe(out)
    assert out.sizes["time"] == 2 * FRAMES and d2.duration_s == pytest.approx(2 * d1.duration_s)
    np.testing.assert_allclose(out["positions"].values[::2], ds["positions"].values, atol=1e-12)
    for k in ("upper_lip_center", "lower_lip_center"):
        assert d2.landmarks[k].peak_displacement == pytest.approx(
            d1.landmarks[k].peak_displacement, rel=0.01)
        assert d2.landmarks[k].peak_speed == pytest.approx(
            0.5 * d1.landmarks[k].peak_speed, rel=0.1)
    assert len(stretched.samples) == 2 * len(audio.samples)
    assert out.attrs["frame_rate_hz"] == 60.0


def test_describe_analytic_motion(ds):
    f, amp = 2.0, 3e-3  # Hz, m
    n = 60
    t = np.arange(n) / 60.0
    rest = ds["rest_positions"].values
    pos = np.repeat(rest[None], n, axis=0)
    pos[:, :, 1] += amp * np.sin(2 * np.pi * f * t)[:, None]
    syn = ds.isel(time=[0] * n).assign_coords(time=t)
    syn["positions"] = (("time", "node", "axis"), pos)
    syn["jaw_angle"] = (("time",), np.radians(4.0) * np.sin(2 * np.pi * f * t))
    d = describe(syn, audio_offset_s=0.025)
    for k in ("upper_lip_center", "lower_lip_center", "chin", "mouth_corner_left"):
        m = d.landmarks[k]
        assert m.peak_displacement == pytest.approx(3.0, rel=0.02)
        assert m.rms_displacement == pytest.approx(3.0 / np.sqrt(2), rel=0.02)
        assert m.peak_speed == pytest.approx(2 * np.pi * f * 3.0, rel=0.02)
    assert d.jaw_angle.peak_displacement == pytest.approx(4.0, rel=0.02)
    assert d.jaw_angle.peak_speed == pytest.approx(2 * np.pi * f * 4.0, rel=0.02)
    assert d.lip_aperture.max == pytest.approx(d.lip_aperture.rest, abs=1e-9)
    assert d.mouth_width.mean == pytest.approx(50.0, abs=3.0)  # the default face: 50 mm
    assert d.audio_offset_ms == pytest.approx(25.0)
    assert json.loads(json.dumps(d.to_dict()))["landmarks"]["chin"]["peak_displacement"] > 2


def test_lip_aperture_opens_with_the_jaw(ds):
    d = describe(ds)
    assert d.lip_aperture.rest == pytest.approx(0.0, abs=1e-9)  # the twins coincide at rest
    assert d.lip_aperture.max > 2.0


def _design(path, rows):
    cols = sorted({c for r in rows for c in r}, key=lambda c: (c != "id", c))
    lines = [",".join(cols)] + [",".join(str(r.get(c, "")) for c in cols) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _failing_hook(row):
    from facemech.errors import FacemechError

    raise FacemechError("no face here")


_failing_hook.version = "fails"


@pytest.mark.slow
def test_design_bad_row_rerun_and_manifest(item, tmp_path):
    from facemech.viz.render import RenderOptions

    table = _design(tmp_path / "design.csv", [
        {"id": "half", "results": item / "a.nc", "audio": item / "a.wav", "amplitude": 0.5,
         "amplitude_region": "lips"},
        {"id": "bad", "results": tmp_path / "bad.nc", "audio": item / "a.wav"},
        {"id": "spoken", "text": "hello"},  # fails late: its hook cannot make it
        {"id": "mcgurk", "results": item / "a.nc", "audio": item / "a.wav",
         "dub_audio": item / "b.wav", "dub_align": "onset", "av_offset_ms": 40},
    ])
    (tmp_path / "bad.nc").write_bytes(b"not a results file")
    out = tmp_path / "out"
    opts = RenderOptions(view="frontal", size=(120, 160), supersample=1)
    # a row that cannot be made refuses the table before anything is written
    with pytest.raises(InputError, match=r"row 2, column 'results'"):
        run_design(table, out, options=opts, make_item=_failing_hook)
    assert not out.exists()
    (tmp_path / "bad.nc").unlink()
    table.write_text("\n".join(ln for ln in table.read_text().splitlines()
                               if not ln.startswith("bad,")) + "\n")
    # a row that fails while the table runs (here its hook) is recorded; the others are made
    rep = run_design(table, out, options=opts, make_item=_failing_hook)
    assert rep.made == ["half", "mcgurk"] and rep.skipped == []
    assert [(e.row, e.column) for e in rep.failed] == [(2, "text")]
    assert "row 2, column 'text'" in rep.failed[0].one_line()
    for sid in ("half", "mcgurk"):
        assert (out / f"{sid}.mp4").stat().st_size > 1000
    assert not (out / "spoken.nc").exists()
    man = json.loads((out / "manifest.json").read_text())
    by = {e["id"]: e for e in man["stimuli"]}
    assert by["spoken"]["status"] == "failed"
    assert by["half"]["settings"]["amplitude"] == 0.5
    assert by["half"]["inputs"]["source"]["results"]
    lips = by["half"]["description"]["landmarks"]["upper_lip_center"]["peak_displacement"]
    full = describe(read_results(item / "a.nc")).landmarks["upper_lip_center"]
    assert lips == pytest.approx(0.5 * full.peak_displacement, rel=0.05)
    assert by["mcgurk"]["description"]["audio_offset_ms"] == pytest.approx(40.0)
    wav = read_wav(out / "mcgurk.wav")
    b = read_wav(item / "b.wav")
    dubbed, _ = shift(b, onset(read_wav(item / "a.wav")) - onset(b))
    assert abs(lag_ms(dubbed, wav) - 40.0) < 1.0
    csv_text = (out / "manifest.csv").read_text().splitlines()
    assert len(csv_text) == 4 and "upper_lip_center_peak_displacement_mm" in csv_text[0]
    # a rerun makes nothing new; a changed setting remakes that stimulus only
    stamp = (out / "half.mp4").stat().st_mtime_ns
    rep = run_design(table, out, options=opts, make_item=_failing_hook)
    assert rep.made == [] and sorted(rep.skipped) == ["half", "mcgurk"]
    assert (out / "half.mp4").stat().st_mtime_ns == stamp
    text = table.read_text().replace("0.5,", "0.25,")
    table.write_text(text)
    rep = run_design(table, out, options=opts, make_item=_failing_hook)
    assert rep.made == ["half"] and rep.skipped == ["mcgurk"]


def test_toml_design_dub_from_and_freeze(item, tmp_path):
    (tmp_path / "d.toml").write_text(f"""
[defaults]
results = "{item / 'a.nc'}"
[[stimulus]]
id = "ga"
audio = "{item / 'a.wav'}"
[[stimulus]]
id = "ba"
audio = "{item / 'b.wav'}"
[[stimulus]]
id = "ba_on_ga"
audio = "{item / 'a.wav'}"
dub_from = "ba"
dub_align = "start"
freeze_region = "upper_face"
time_scale = 1.5
""")
    rep = run_design(tmp_path / "d.toml", tmp_path / "o", video=False)
    assert rep.made == ["ga", "ba", "ba_on_ga"] and not rep.failed
    out = read_results(tmp_path / "o" / "ba_on_ga.nc")
    assert out.sizes["time"] == 36
    steps = [s["manipulation"] for s in json.loads(out.attrs["stimulus"])]
    assert steps == ["dub", "time_scale", "freeze"]
    wav = read_wav(tmp_path / "o" / "ba_on_ga.wav")
    assert len(wav.samples) == int(1.5 * len(read_wav(item / "b.wav").samples))


def test_cli_describe_and_bad_tables(item, tmp_path, monkeypatch, capsys):
    code, out, _ = run_cli(monkeypatch, capsys, "describe", item / "a.nc", "--json")
    assert code == 0 and json.loads(out)["frames"] == FRAMES
    code, out, _ = run_cli(monkeypatch, capsys, "describe", item / "a.nc")
    assert code == 0 and "lip aperture" in out
    (tmp_path / "noid.csv").write_text("name,amplitude\nx,1\n")
    code, _, err = run_cli(monkeypatch, capsys, "stimuli", tmp_path / "noid.csv", "-o",
                           tmp_path / "o")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "'id'" in err
    code, _, err = run_cli(monkeypatch, capsys, "stimuli", tmp_path / "none.csv", "-o",
                           tmp_path / "o")
    assert code == 2 and "not found" in err and "Traceback" not in err
    (tmp_path / "bad.toml").write_text("[[stimulus]\n")
    code, _, err = run_cli(monkeypatch, capsys, "stimuli", tmp_path / "bad.toml", "-o",
                           tmp_path / "o")
    assert code == 2 and len(err.strip().splitlines()) == 1
    table = _design(tmp_path / "rows.csv", [
        {"id": "ok", "results": item / "a.nc", "audio": item / "a.wav"},
        {"id": "typo", "results": item / "a.nc", "audio": item / "a.wav",
         "amplitude_region": "nose"}])
    code, out, err = run_cli(monkeypatch, capsys, "stimuli", table, "-o", tmp_path / "o2",
                             "--no-video")
    assert code == 2 and len(err.strip().splitlines()) == 1  # the whole table, before any row
    assert "row 2, column 'amplitude_region'" in err and "nose" in err
    assert not (tmp_path / "o2").exists()


def test_an_offset_or_freeze_that_leaves_nothing_is_an_error(ds, item):
    from facemech.errors import InputError
    from facemech.speech.stimuli import freeze, offset_audio

    a = read_wav(item / "a.wav")
    with pytest.raises(InputError, match=r"av_offset_ms.*-100000 ms moves the whole sound"):
        offset_audio(ds, a, -100000.0)
    assert np.any(offset_audio(ds, a, 0.5e3 * a.duration)[1].samples)  # half of it stays
    with pytest.raises(InputError, match=r"freeze_region.*leaves no motion"):
        freeze(ds, "face")
    assert np.ptp(freeze(ds, "upper_face")["positions"].values, axis=0).max() > 0
