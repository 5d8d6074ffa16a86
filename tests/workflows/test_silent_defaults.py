"""The defaults a command takes are said (issue 54, item 6): EMG scaled without a calibration
recording, a simulation's jaw held at rest, and the model's points that have two names."""

import numpy as np

from conftest import run_cli
from facemech.emg import process_emg
from facemech.geometry.sites import marker_aliases, shared_points
from facemech.workflows import simulate as wsim


def _emg(rng, burst=1.0, frames=2500):
    x = rng.standard_normal((frames, 2)) * 0.02
    x[frames // 3: frames // 2] *= 50 * burst
    return x


def test_emg_without_calibration_says_each_channel_is_scaled_to_its_own_maximum():
    rng = np.random.default_rng(2)
    plain = process_emg(_emg(rng), 2500.0, ("LAO", "MEN"))
    assert len(plain.notes) == 1 and "without a calibration recording" in plain.notes[0]
    np.testing.assert_allclose(plain.activity.max(axis=0), 1.0)  # what the note warns of
    cal = process_emg(_emg(rng), 2500.0, ("LAO", "MEN"), calibration=_emg(rng, 3.0))
    assert cal.notes == () and cal.activity.max() < 0.6


def test_emg_process_prints_the_note(monkeypatch, capsys, tmp_path):
    rng = np.random.default_rng(3)
    x = _emg(rng)
    path = tmp_path / "emg.csv"
    path.write_text("time,LAO,MEN\n" + "".join(f"{k / 2500},{float(a)!r},{float(b)!r}\n"
                                               for k, (a, b) in enumerate(x)))
    code, _, err = run_cli(monkeypatch, capsys, "emg", "process", path, "-o", tmp_path / "a.csv")
    assert code == 0, err
    assert "note: EMG scaled without a calibration recording" in " ".join(err.split())


def test_simulate_notes_a_jaw_held_at_rest_and_uncalibrated_emg(tmp_path):
    emg = wsim.Controls(emg=tmp_path / "emg.csv")
    notes = wsim.input_notes(emg, wsim.JawSource())
    assert len(notes) == 2 and notes[1] == wsim.JAW_AT_REST_NOTE
    assert "without a calibration recording" in notes[0]
    given = wsim.input_notes(wsim.Controls(activity=tmp_path / "a.csv"),
                             wsim.JawSource(angles=tmp_path / "jaw.csv"))
    assert given == ()
    run = wsim.SimulationRun(None, tmp_path / "r.nc", notes=notes)
    assert run.warnings.count("facemech: note: ") == 2


def test_the_mouth_corner_markers_are_aliases_of_the_corners(face):
    aliases = marker_aliases(face.landmarks, face.markers)
    assert aliases == {"R07": "mouth_corner_right", "L06": "mouth_corner_left"}
    names = ["R05", "R07", "mouth_corner_right", "L06"]
    nodes = [face.markers["R05"], face.markers["R07"], face.landmarks["mouth_corner_right"],
             face.markers["L06"]]
    line, = shared_points(names, nodes, aliases)
    assert line == f"R07 = mouth_corner_right (node {face.markers['R07']})"
    assert shared_points(["a", "b"], [1, 2]) == []


def test_shared_points_without_aliases_name_the_point_by_its_first_name_in_order():
    assert shared_points(["y", "x"], [7, 7]) == ["y = x (node 7)"]
