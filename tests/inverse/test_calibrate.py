"""``facemech calibrate``: a subject's maximal gestures refit the anatomical preset's scales;
the preset file it writes is accepted by every --preset option."""

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech import default_face
from facemech.analysis.gestures import gesture_activity
from facemech.errors import InputError
from facemech.io.markers import write_markers
from facemech.markerset import MarkerSet
from facemech.params import anatomical, preset, read_preset, write_preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate

MARKERS = ("R03", "R05", "R07", "L06", "R01")



def recorded(tmp_path, name, groups, params):
    """A twin subject's recording of a maximal gesture: the model's markers (mm CSV)."""
    face = default_face()
    sim = simulate(face_model(face, params), gesture_activity(groups))
    pos = sim.positions[:, [face.markers[m] for m in MARKERS]]
    path = tmp_path / f"{name}.csv"
    write_markers(path, MarkerSet(pos, MARKERS, 60.0), units="mm")
    return path


@pytest.mark.slow
def test_calibrate_recovers_a_twin_subjects_force(tmp_path, monkeypatch, capsys):
    subject = anatomical({"force": 1.25})
    smile = recorded(tmp_path, "smile", ("ZYG", "LAO"), subject)
    pucker = recorded(tmp_path, "pucker", ("OOS", "OOI"), subject)
    out = tmp_path / "subject.json"
    code, text, err = run_cli(monkeypatch, capsys, "calibrate", f"{smile}:ZYG,LAO",
                              f"{pucker}:OOS,OOI", "--fit", "force", "--max-evaluations", "8",
                              "-o", out)
    assert code == 0, err
    data = json.loads(out.read_text())
    assert data["format"] == "facemech-preset" and data["base"] == "anatomical"
    assert data["scales"]["force"] == pytest.approx(1.25, rel=0.06)
    assert read_preset(out).k_force == pytest.approx(subject.k_force, rel=0.06)
    # the preset file works wherever a preset is named
    act = tmp_path / "a.csv"
    from facemech.io.activity import write_activity

    write_activity(act, np.arange(5) / 60.0, gesture_activity(("ZYG",))[:5])
    code, _, err = run_cli(monkeypatch, capsys, "simulate", "--activity", act, "--preset", out,
                           "-o", tmp_path / "r.nc")
    assert code == 0, err


def test_calibrate_bad_input(tmp_path, monkeypatch, capsys):
    smile = recorded(tmp_path, "smile", ("ZYG",), anatomical())
    for args, needle in (
        ([str(smile)], "FILE:GROUPS"),
        ([f"{smile}:BICEPS"], "BICEPS"),
        ([f"{smile}:ZYG", "--fit", "wobble"], "wobble"),
        ([f"{smile}:ZYG", "-o", tmp_path / "p.txt"], ".json"),
        ([], "--builtin"),
        ([f"{tmp_path / 'none.csv'}:ZYG"], "none.csv"),
    ):
        out = [] if "-o" in map(str, args) else ["-o", tmp_path / "p.json"]
        code, _, err = run_cli(monkeypatch, capsys, "calibrate", *args, *out)
        assert code == 2, (args, err)
        assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "p.json").exists()


def test_preset_files_round_trip_and_refuse_garbage(tmp_path):
    path = tmp_path / "mine.json"
    write_preset(path, "mine", {"force": 0.8, "lips": 1.5})
    p = preset(str(path))
    assert p.name == "mine"
    assert p.k_force == pytest.approx(0.8 * anatomical().k_force)
    assert p.lip_stiffness_factor == pytest.approx(1.5 * anatomical().lip_stiffness_factor)
    bad = tmp_path / "bad.json"
    for text, field in (("not json", None), ('{"format": "x"}', "format"),
                        ('{"format": "facemech-preset", "base": "lucero1999"}', "base"),
                        ('{"format": "facemech-preset", "base": "anatomical", '
                         '"scales": {"force": -1}}', "force"),
                        ('{"format": "facemech-preset", "base": "anatomical", '
                         '"scales": {"glue": 2}}', "scales")):
        bad.write_text(text)
        with pytest.raises(InputError) as info:
            preset(str(bad))
        assert info.value.source == str(bad)
        if field:
            assert info.value.field == field
