"""The commands' workflows called from Python (facemech.workflows): jaw sources and the bite
block, EMG input and its calibration, trajectories from marker and results files, face info."""

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech import InputError, preset, write_marker_csv
from facemech.markerset import MarkerSet
from facemech.physics.model import model as face_model
from facemech.solvers.jaw_drive import jaw_angles_from_marker
from facemech.workflows import emg as wemg
from facemech.workflows import markers as wmarkers
from facemech.workflows import simulate as wsim
from facemech.workflows.faces import face_info


def chin_file(path, face, frames=30, drop_mm=6.0):
    """A chin marker (R01) that drops ``drop_mm`` over the first half, in mm, at 60 Hz."""
    chin = face.rest_positions[face.markers["R01"]] * 1e3
    t = np.arange(frames) / 60
    y = chin[1] - drop_mm * np.minimum(t / t[frames // 2], 1.0)
    pos = np.column_stack([np.full(frames, chin[0]), y, np.full(frames, chin[2])])
    write_marker_csv(path, MarkerSet(pos[:, None] * 1e-3, ("R01",), 60.0, source_units="mm"))
    return t


def test_bite_block_gives_the_same_jaw_through_a_chin_marker_and_a_jaw_csv(tmp_path,
                                                                             seeds_face):
    prm = preset("lucero1999")  # the seeds' thin tissue: angles from the bone under the marker
    t = chin_file(tmp_path / "chin.csv", seeds_face)
    free, inputs = wsim.jaw_series(wsim.JawSource(markers=tmp_path / "chin.csv"),
                                   face_model(seeds_face, prm), t)
    assert set(inputs) == {"jaw_chin"} and free.max() > np.radians(3)
    node = seeds_face.markers["R01"]
    y = seeds_face.rest_positions[node, 1] - 6e-3 * np.minimum(t / t[15], 1.0)
    np.testing.assert_allclose(free, jaw_angles_from_marker(face_model(seeds_face, prm), node, y),
                               atol=1e-6)  # the file holds mm to a few decimals
    with open(tmp_path / "jaw.csv", "w") as fh:
        fh.write("time,jaw_angle\n" + "".join(f"{a},{float(b)!r}\n" for a, b in zip(t, free,
                                                                           strict=True)))
    held = [wsim.jaw_series(wsim.JawSource(**src, bite_block=True), face_model(seeds_face, prm),
                            t)[0]
            for src in ({"markers": tmp_path / "chin.csv"}, {"angles": tmp_path / "jaw.csv"})]
    np.testing.assert_allclose(held[0], np.full(len(t), free[0]), atol=0)
    np.testing.assert_allclose(held[1], held[0], atol=1e-12)
    # and as the solver's own bite block had it
    np.testing.assert_allclose(held[0], jaw_angles_from_marker(face_model(seeds_face, prm), node, y,
                                                               bite_block=True), atol=1e-6)
    assert wsim.bite_block(np.arange(6.0).reshape(2, 3)).tolist() == [[0, 1, 2], [0, 1, 2]]


def test_jaw_source_and_controls_are_checked():
    with pytest.raises(InputError) as e:
        wsim.JawSource(angles="a.csv", markers="m.csv")
    assert e.value.field == "jaw"
    with pytest.raises(InputError) as e:
        wsim.JawSource(second_marker="M2")
    assert e.value.field == "jaw-second-marker"
    with pytest.raises(InputError) as e:
        wsim.Controls()
    assert e.value.field == "activity"


def write_emg(path, channels, rng, burst=1.0):
    with open(path, "w") as fh:
        fh.write("time," + ",".join(channels) + "\n")
        for k in range(2500):
            level = burst if 1000 <= k < 1800 else 0.05
            fh.write(f"{k / 2500}," + ",".join(f"{level * rng.standard_normal()}"
                                               for _ in channels) + "\n")


def test_simulate_with_emg_keeps_the_calibration_channel_names(tmp_path):
    rng = np.random.default_rng(1)
    write_emg(tmp_path / "emg.csv", ["LAO", "MEN"], rng)
    write_emg(tmp_path / "cal.csv", ["LAO", "MEN"], rng, burst=3.0)
    write_emg(tmp_path / "swapped.csv", ["MEN", "LAO"], rng, burst=3.0)
    controls = wsim.Controls(emg=tmp_path / "emg.csv", emg_calibration=tmp_path / "swapped.csv")
    with pytest.raises(InputError) as e:  # before: simulate dropped the names unchecked
        wsim.simulate_files(tmp_path / "r.nc", controls)
    assert e.value.field == "header" and e.value.source.endswith("swapped.csv")
    assert not (tmp_path / "r.nc").exists()
    ok = wsim.Controls(emg=tmp_path / "emg.csv", emg_calibration=tmp_path / "cal.csv")
    t, act, inputs = wsim.read_controls(ok, 60.0)
    assert set(inputs) == {"emg", "emg_calibration"} and len(t) == 60
    _, plain, _ = wsim.read_controls(wsim.Controls(emg=tmp_path / "emg.csv"), 60.0)
    lao = 2  # the LAO column of the 16 groups
    # a calibration three times stronger lowers the recording's peak activity to about a third
    assert plain[:, lao].max() == pytest.approx(1.0)
    assert 0.2 < act[:, lao].max() < 0.5
    res = wemg.emg_activity(tmp_path / "emg.csv", rate=60.0, calibration=tmp_path / "cal.csv")
    np.testing.assert_allclose(act[:, lao], res.activity[:, 0], atol=1e-12)


def test_intervals_from_text_or_pairs():
    assert wemg.as_interval("0.1, 0.5", "baseline") == (0.1, 0.5)
    assert wemg.as_interval((0, 2), "baseline") == (0.0, 2.0)
    assert wemg.as_interval(None, "baseline") is None
    for bad in ("0.1", "a,b", "0.5,0.1"):
        with pytest.raises(InputError) as e:
            wemg.as_interval(bad, "emg-baseline")
        assert e.value.field == "emg-baseline"


def test_trajectories_from_a_marker_file_onto_a_time_grid(tmp_path):
    t = np.arange(11) / 10
    pos = np.zeros((11, 2, 3))
    pos[:, 0, 1] = 2.0 * t  # m: A rises 2 m/s
    pos[:, 1] = [0.1, 0.2, 0.3]
    write_marker_csv(tmp_path / "m.csv", MarkerSet(pos, ("A", "B"), 10.0, source_units="m"))
    grid = np.array([0.05, 0.5, 0.95])
    time, tr = wmarkers.trajectories(tmp_path / "m.csv", "A, NOPE, B", times=grid,
                                     missing="skip")
    assert list(tr) == ["A", "B"]
    np.testing.assert_array_equal(time, grid)
    np.testing.assert_allclose(tr["A"][:, 1], 2.0 * grid, atol=1e-9)
    np.testing.assert_allclose(tr["B"], np.tile([0.1, 0.2, 0.3], (3, 1)), atol=1e-9)
    with pytest.raises(InputError) as e:
        wmarkers.trajectories(tmp_path / "m.csv", ["NOPE"])
    assert e.value.field == "NOPE"
    with pytest.raises(InputError) as e:
        wmarkers.trajectories(tmp_path / "m.csv", ["A"], times=[0.0, 1.5], cover="the markers")
    assert e.value.field == "time"
    assert "the markers does not cover" in str(e.value)


def test_face_info_json_and_text(monkeypatch, capsys):
    info = face_info("default-coarse", tissue="uniform")
    assert json.loads(info.text(as_json=True)) == info.summary
    code, out, _ = run_cli(monkeypatch, capsys, "face", "info", "default-coarse", "--tissue",
                           "uniform")
    assert code == 0 and out.startswith("name: generic-adult-coarse\n")
    n = info.summary["nodes_per_layer"]["epidermis"]
    assert f"nodes per layer: epidermis {n}, fascia {n}, skull {n}" in out
    with pytest.raises(json.JSONDecodeError):  # --json changes the output
        json.loads(out)
    code, out, _ = run_cli(monkeypatch, capsys, "face", "info", "default-coarse", "--tissue",
                           "uniform", "--json")
    assert code == 0 and json.loads(out) == info.summary
