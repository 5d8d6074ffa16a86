"""Issue 29, part 3, in design tables: a row's ``blinks``, ``gaze``, ``head_motion`` and ``seed``
(off by default), drawn on the finished stimulus, shown in its movie and recorded in the
manifest with their times."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from conftest import activity, run_cli
from facemech.io.results import read_results, to_dataset, write_dataset
from facemech.physics.model import model as face_model
from facemech.speech import stimuli as st
from facemech.speech.design import check_design
from facemech.speech.wav import Audio, write_audio
from facemech.workflows.stimuli import run_design

RATE = 16000
SECONDS = 3.2  # long enough for a blink: the first comes within 60 / 26 = 2.3 s


def _voice(seconds: float, f0: float = 120.0) -> Audio:
    """A voice-like tone (five harmonics) gliding up 30 %, after 0.2 s of silence."""
    t = np.arange(int(seconds * RATE)) / RATE
    phase = 2 * np.pi * np.cumsum(f0 * (1 + 0.3 * t / seconds)) / RATE
    x = sum(0.3 / k * np.sin(k * phase) for k in range(1, 6)) * (t > 0.2)
    return Audio((x[:, None] * 32000).astype(np.int16), RATE)


@pytest.fixture(scope="module")
def item(tmp_path_factory):
    """A 3.2-s face item on the coarse face (24 simulated frames time-scaled to 192) and its
    voice, and a second voice to dub on."""
    from facemech import simulate
    from facemech.geometry.builder import load_face

    folder = tmp_path_factory.mktemp("alive-item")
    a = activity(24)
    a[:, 2] = 0.5 * np.sin(np.linspace(0, np.pi, 24))
    ds = to_dataset(simulate(face_model(load_face("default-coarse")), a, np.radians(5.0) * a[:, 2]))
    ds = st.time_scale(ds, SECONDS / 0.4)
    ds.attrs.pop("stimulus", None)
    write_dataset(folder / "a.nc", ds)
    write_audio(folder / "a.wav", _voice(SECONDS))
    write_audio(folder / "b.wav", _voice(SECONDS, f0=200.0))
    return folder


def _design(path, rows):
    cols = []
    for r in rows:
        cols += [c for c in r if c not in cols]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    return path


def _row(item, sid, **cells):
    return {"id": sid, "results": item / "a.nc", "audio": item / "a.wav", **cells}


def test_rows_turn_them_on_seeded_and_the_movie_shows_them(item, tmp_path, monkeypatch):
    import facemech.viz.video as video

    drawn = {}

    def fake_render(ds, path, *, source=None, motion=None, **kw):  # what the movie is drawn from
        drawn[source] = motion
        path.write_bytes(b"movie")

    monkeypatch.setattr(video, "render_results", fake_render)
    table = _design(tmp_path / "design.csv", [
        _row(item, "still"),
        _row(item, "alive", blinks="yes", gaze="true", head_motion="1", seed=3),
        _row(item, "again", blinks="on", gaze="yes", head_motion="TRUE", seed=3),
        _row(item, "other", blinks="yes", gaze="yes", head_motion="yes", seed=4),
        _row(item, "blinks_only", blinks="yes", gaze="no", head_motion="0", seed=3),
        _row(item, "off", blinks="no", gaze="false", head_motion="off", seed=3)])
    rep = run_design(table, tmp_path / "out")
    assert not rep.failed and len(rep.made) == 6
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    by = {e["id"]: e for e in man["stimuli"]}
    frames = read_results(item / "a.nc").sizes["time"]

    # off (by default, or said): no events, the head still, the movie drawn without them
    for sid in ("still", "off"):
        rec = by[sid]["alive"]
        assert rec["blinks"] == [] and rec["gaze_shifts"] == []
        assert not np.any(rec["head"]["series_rad"]["pitch"]) and rec["head"]["on"] is False
        assert drawn[sid] is None
    assert by["still"]["settings"]["blinks"] is False and by["still"]["settings"]["seed"] == 0

    # on: blink events and gaze shifts with their times, the head moving, the movie showing them
    rec = by["alive"]["alive"]
    assert rec["laws"]["settings"] == {"blinks": True, "gaze": True, "head": True, "seed": 3,
                                       "blink_rate_per_min": 26.0}
    assert rec["blinks"] and rec["gaze_shifts"]
    assert all(0 <= b["onset_s"] < SECONDS and b["duration_s"] == pytest.approx(0.27)
               for b in rec["blinks"])
    pitch = np.array(rec["head"]["series_rad"]["pitch"])
    assert len(pitch) == frames and np.abs(pitch).max() > np.radians(0.3)
    motion = drawn["alive"]
    assert motion is not None and motion.blink.max() > 0.99 and np.abs(motion.gaze).max() > 0
    t0 = rec["blinks"][0]["onset_s"]
    k = int(round((t0 + 0.09) * 60))  # the lid shut
    assert motion.blink[k] > 0.9 and np.abs(motion.head).max() > 0

    # the seed: the same events again; another seed, others; a part off leaves the rest
    assert by["again"]["alive"]["blinks"] == rec["blinks"]
    assert by["again"]["alive"]["gaze_shifts"] == rec["gaze_shifts"]
    assert by["again"]["alive"]["head"] == rec["head"]
    assert by["other"]["alive"]["blinks"] != rec["blinks"]
    assert by["blinks_only"]["alive"]["blinks"] == rec["blinks"]
    assert by["blinks_only"]["alive"]["gaze_shifts"] == []
    assert np.array_equal(drawn["blinks_only"].blink, motion.blink)
    assert not np.any(drawn["blinks_only"].head)

    # the results stay in the head's frame: the same with and without them
    a, b = read_results(tmp_path / "out" / "still.nc"), read_results(tmp_path / "out" /
                                                                     "alive.nc")
    assert np.array_equal(a["positions"].values, b["positions"].values)
    assert by["still"]["flat"] == by["alive"]["flat"]

    # manifest.csv: the switches, the seed and the onsets
    with open(tmp_path / "out" / "manifest.csv", newline="") as fh:
        rows = {r["id"]: r for r in csv.DictReader(fh)}
    assert rows["alive"]["blinks"] == "True" and rows["alive"]["seed"] == "3"
    onsets = [float(v) for v in rows["alive"]["blink_onsets_s"].split(";")]
    assert onsets == pytest.approx([e["onset_s"] for e in rec["blinks"]], abs=1e-4)
    assert rows["still"]["blink_onsets_s"] == "" and rows["still"]["blinks"] == "False"

    # a changed switch remakes that row only
    lines = table.read_text().splitlines()
    lines[5] = lines[5].replace(",yes,", ",no,")  # blinks_only's blinks
    table.write_text("\n".join(lines) + "\n")
    rep = run_design(table, tmp_path / "out")
    assert rep.made == ["blinks_only"] and len(rep.skipped) == 5


def test_the_head_follows_the_faces_own_voice(item, tmp_path):
    """Dubbed or offset sound leaves the head as the face's own voice drives it; a time scale
    stretches it with the face."""
    on = {"head_motion": "yes", "seed": 5}
    table = _design(tmp_path / "design.csv", [
        _row(item, "own", **on),
        _row(item, "dubbed", dub_audio=item / "b.wav", dub_align="start", **on),
        _row(item, "late", av_offset_ms=120, **on),
        _row(item, "slow", time_scale=1.5, time_scale_audio="none", **on)])
    rep = run_design(table, tmp_path / "out", video=False)
    assert not rep.failed
    by = {e["id"]: e["alive"]["head"]
          for e in json.loads((tmp_path / "out" / "manifest.json").read_text())["stimuli"]}
    for sid in ("dubbed", "late"):
        assert by[sid] == by["own"]
    assert by["own"]["f0_median_hz"] == pytest.approx(138, rel=0.05)  # 120 Hz gliding to 156
    assert by["slow"]["f0_median_hz"] == pytest.approx(138, rel=0.05)  # stretched, pitch kept
    assert len(by["slow"]["series_rad"]["pitch"]) == int(round(1.5 * len(
        by["own"]["series_rad"]["pitch"])))


def test_toml_defaults_and_a_text_row(item, tmp_path):
    """TOML booleans and integers, a [defaults] table turning them on for every row, a row
    turning one off; a text row's hook never sees these columns."""
    seen = []

    def make_item(row):
        seen.append(dict(row))
        return read_results(item / "a.nc"), item / "a.wav"

    (tmp_path / "d.toml").write_text(f"""
[defaults]
blinks = true
seed = 11
[[stimulus]]
id = "file"
results = "{item / 'a.nc'}"
audio = "{item / 'a.wav'}"
gaze = 1
[[stimulus]]
id = "said"
text = "ba"
blinks = false
""")
    specs = {s.id: s.settings for s in check_design(tmp_path / "d.toml", make_item)}
    assert specs["file"]["blinks"] and specs["file"]["gaze"] and specs["file"]["seed"] == 11
    assert not specs["said"]["blinks"] and not specs["said"]["head_motion"]
    rep = run_design(tmp_path / "d.toml", tmp_path / "o", make_item, video=False)
    assert not rep.failed and seen == [{"text": "ba"}]
    man = json.loads((tmp_path / "o" / "manifest.json").read_text())
    by = {e["id"]: e["alive"] for e in man["stimuli"]}
    assert by["file"]["blinks"] and by["file"]["laws"]["settings"]["seed"] == 11
    assert by["said"]["blinks"] == [] and by["said"]["gaze_shifts"] == []


@pytest.mark.parametrize("column,value", [
    ("blinks", "maybe"), ("gaze", "2"), ("head_motion", "yes please"), ("seed", "1.5"),
    ("seed", "-1"), ("seed", "abc"), ("seed", str(2 ** 32))])
def test_a_bad_cell_refuses_the_table(item, tmp_path, monkeypatch, capsys, column, value):
    table = _design(tmp_path / "design.csv", [
        _row(item, "ok", blinks="yes"), _row(item, "bad", **{column: value})])
    code, _, err = run_cli(monkeypatch, capsys, "stimuli", table, "-o", tmp_path / "o",
                           "--no-video")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "design.csv" in err and f"row 2, column '{column}'" in err and value in err
    assert not (tmp_path / "o").exists()


def test_a_bad_toml_value_is_refused(item, tmp_path):
    from facemech.errors import InputError

    (tmp_path / "d.toml").write_text(f"""
[[stimulus]]
id = "x"
results = "{item / 'a.nc'}"
audio = "{item / 'a.wav'}"
seed = 1.5
""")
    with pytest.raises(InputError, match=r"d\.toml.*row 1, column 'seed'.*1\.5"):
        check_design(tmp_path / "d.toml")
