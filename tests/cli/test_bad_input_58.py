"""Bad input, the rows of issue 58 outside the articulography readers: a voice variant eSpeak NG
does not have, a design row refused before any manifest, a lip coil given as a bone point."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.physics.model import model as face_model
from test_bad_input_31 import refused


# ---- a voice variant eSpeak NG does not have -----------------------------------------------
def test_the_variants_are_espeaks_own():
    from facemech.speech.tts import variants

    have = variants()
    assert {"f1", "f3", "m1", "m3", "klatt"} <= set(have) and "nonexistent" not in have
    assert len(have) > 50


@pytest.mark.parametrize("voice", ["en-us+nonexistent", "en-us+", "en-us+F3", "en-us+10",
                                   "en-us+3x", "en-us+../lang/gmw/en", "+f3",
                                   "en-us+f3+m1"])
@pytest.mark.parametrize("isolated", [True, False])
def test_a_voice_variant_espeak_does_not_have_is_refused(voice, isolated):
    from facemech.speech.tts import synthesize

    with pytest.raises(InputError) as err:
        synthesize("ba", voice=voice, isolated=isolated)
    assert err.value.field == "voice" and "--voice" in str(err.value)
    if voice.startswith("en-us+"):
        assert "f3, f4" in str(err.value) and "m1" in str(err.value)  # the variants it has


def test_a_variant_it_has_is_that_variant():
    """``+f3`` speaks higher than the plain voice; eSpeak's numeric shorthand ``+13`` is f3."""
    from facemech.speech.tts import synthesize

    plain = synthesize("ba", voice="en-us")
    f3, thirteen = synthesize("ba", voice="en-us+f3"), synthesize("ba", voice="en-us+13")
    assert f3.alignment.meta["voice"] == "en-us+f3"
    assert np.array_equal(f3.audio, thirteen.audio)
    assert not (len(f3.audio) == len(plain.audio) and np.array_equal(f3.audio, plain.audio))


def test_speak_refuses_an_unknown_variant_and_writes_nothing(monkeypatch, capsys, tmp_path):
    line = refused(monkeypatch, capsys, tmp_path, "speak", "ba", "-o", "{t}/out", "--voice",
                   "en-us+nonexistent", "--no-video",
                   words=("--voice", "'en-us+nonexistent'", "field 'voice'", "f3"))
    assert "nonexistent'; it has" in line
    assert not (tmp_path / "out").exists()


# ---- a design row that cannot be made: refused before any manifest -----------------------------
@pytest.fixture(scope="module")
def item(face, tmp_path_factory):
    """A 24-frame lips-and-jaw movement (results) and its sound, outside the tests' folders."""
    from conftest import activity
    from facemech import simulate
    from facemech.io.results import to_dataset, write_dataset
    from facemech.speech.wav import write_wav

    folder = tmp_path_factory.mktemp("item")
    a = activity(24)
    bump = np.sin(np.linspace(0, np.pi, 24))
    a[:, 2] = 0.5 * bump
    write_dataset(folder / "a.nc", to_dataset(simulate(face_model(face), a,
                                                       np.radians(5.0) * bump)))
    write_wav(folder / "a.wav", np.sin(np.arange(6400) / 5.0), 16000)
    return folder


def _table(path, rows):
    cols = list(dict.fromkeys(c for r in rows for c in r))
    path.write_text("\n".join([",".join(cols)] + [
        ",".join(str(r.get(c, "")) for c in cols) for r in rows]) + "\n")
    return path


@pytest.mark.parametrize("cells, words", [
    ({"freeze_region": "lips", "freeze_at": "9999"}, ("column 'freeze_at'", "frame 9999",
                                                      "0 to 23")),
    ({"freeze_region": "lips", "freeze_at": "-1"}, ("column 'freeze_at'", "frame -1")),
    ({"freeze_region": "lips", "freeze_at": "99s"}, ("column 'freeze_at'", "99 s is outside")),
    ({"freeze_region": "lips", "freeze_at": "50", "time_scale": "2"},
     ("column 'freeze_at'", "frame 50", "0 to 47")),
    ({"freeze_at": "3"}, ("column 'freeze_at'", "without a freeze_region")),
    ({"freeze_region": "face"}, ("column 'freeze_region'", "leaves no motion")),
    ({"results": "{t}/garbage.nc"}, ("column 'results'", "not a readable NetCDF")),
])
def test_a_design_row_that_cannot_be_made_is_refused_before_any_manifest(
        monkeypatch, capsys, tmp_path, item, cells, words):
    """The second row fails; the first would be made: the whole table is refused, and neither
    out/manifest.csv nor out/manifest.json (nor out/) is written."""
    (tmp_path / "garbage.nc").write_bytes(b"not a results file")
    good = {"id": "one", "results": item / "a.nc", "audio": item / "a.wav"}
    bad = {**good, "id": "two", **{k: v.format(t=tmp_path) for k, v in cells.items()}}
    _table(tmp_path / "d.csv", [good, bad])
    refused(monkeypatch, capsys, tmp_path, "stimuli", "{t}/d.csv", "-o", "{t}/out",
            "--no-video", words=("{t}/d.csv", "row 2", *words), seconds=60)
    assert not (tmp_path / "out").exists()


def test_a_freeze_inside_the_stimulus_is_made(monkeypatch, capsys, tmp_path, item):
    from facemech.io.results import read_results

    _table(tmp_path / "d.csv", [{"id": "one", "results": item / "a.nc", "audio": item / "a.wav",
                                 "freeze_region": "lips", "freeze_at": "47",
                                 "time_scale": "2"}])
    code, _, err = run_cli(monkeypatch, capsys, "stimuli", tmp_path / "d.csv", "-o",
                           tmp_path / "out", "--no-video")
    assert code == 0, err
    made = read_results(tmp_path / "out" / "one.nc")
    assert made.sizes["time"] == 48
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert [e["status"] for e in man["stimuli"]] == ["made"]


def test_a_text_row_with_an_unknown_voice_variant_is_refused_first(monkeypatch, capsys,
                                                                   tmp_path):
    (tmp_path / "d.toml").write_text('[[stimulus]]\nid = "a"\ntext = "ba"\n'
                                     'voice = "en-us+nonexistent"\n')
    refused(monkeypatch, capsys, tmp_path, "stimuli", "{t}/d.toml", "-o", "{t}/out",
            words=("{t}/d.toml", "row 1, column 'voice'", "nonexistent", "f3"))


# ---- a lip coil given as a bone point ----------------------------------------------------------
#: the MOCHA-TIMIT sentence, beside the repository (../shared/data/mocha)
MOCHA = str(__import__("pathlib").Path(__file__).resolve().parents[3] / "shared" / "data"
            / "mocha" / "fsew0_001.ema")


@pytest.fixture
def ema(tmp_path):
    import shutil
    from pathlib import Path

    if not Path(MOCHA).is_file():
        pytest.skip("the MOCHA-TIMIT sample is not here")
    (tmp_path / "act.csv").write_text("time,OOS\n0,0\n0.1,0\n")
    return shutil.copy(MOCHA, tmp_path / "s.ema")


@pytest.mark.parametrize("command, options, option, role", [
    ("invert", ("--jaw-incisor", "ul"), "--jaw-incisor", "upper_lip"),
    ("invert", ("--jaw-incisor", "li", "--jaw-molar", "ll"), "--jaw-molar", "lower_lip"),
    ("invert", ("--jaw-incisor", "tt"), "--jaw-incisor", "tongue"),
    ("simulate", ("--jaw-incisor", "ul"), "--jaw-incisor", "upper_lip"),
    ("simulate", ("--jaw-incisor", "li", "--jaw-molar", "v"), "--jaw-molar", "velum"),
])
def test_a_bone_point_option_refuses_a_sensor_of_another_role(monkeypatch, capsys, tmp_path,
                                                              ema, command, options, option,
                                                              role):
    """MOCHA-TIMIT's upper-lip coil ``ul`` is not the lower incisor: refused naming the option
    and the coil's role, before the face is built, nothing written."""
    where = ("--markers", "{t}/s.ema") if command == "invert" else (
        "--activity", "{t}/act.csv", "--jaw-chin", "{t}/s.ema")
    line = refused(monkeypatch, capsys, tmp_path, command, *where, *options, "-o",
                   "{t}/r.nc", words=("{t}/s.ema", option, f"role is {role}"), seconds=30)
    assert "not a point on the jaw bone" in line


def test_a_batch_items_bone_point_of_another_role_fails_that_item(tmp_path, ema):
    """The manifest keys ``jaw-incisor`` and ``jaw-molar`` reach the same check: the item
    fails with the one line, nothing of it is written, the batch goes on."""
    pytest.importorskip("distributed")
    from facemech.workflows.batch import run_batch

    (tmp_path / "m.csv").write_text("id,job,markers,jaw-incisor\ninv,invert,s.ema,ul\n")
    rep = run_batch(tmp_path / "m.csv", tmp_path / "out", workers=1, processes=False)
    (outcome,) = rep.outcomes
    assert outcome.status == "failed" and rep.exit_code == 1
    assert "jaw-incisor" in outcome.error and "role is upper_lip" in outcome.error
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["summary.csv"]


def test_the_speak_api_refuses_an_unknown_variant_before_writing(tmp_path):
    from facemech.workflows.speak import speak

    with pytest.raises(InputError) as err:
        speak(tmp_path / "out", "ba", voice="en-us+nonexistent", video=False)
    assert err.value.field == "voice" and "f3" in str(err.value)
    assert not (tmp_path / "out").exists()
