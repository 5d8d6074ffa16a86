"""EMG processing, activity and marker files, results files."""

import numpy as np
import pytest

from facemech import (
    InputError,
    MarkerSet,
    process_emg,
    read_activity,
    read_marker_csv,
    read_results,
    seven_channel_control,
    simulate,
    write_activity,
    write_marker_csv,
    write_results,
)
from facemech.emg import integrate, trapezoid_kernel
from facemech.params import MUSCLE_GROUPS
from facemech.physics.model import model as face_model


def burst_emg(rate=2500.0, duration=3.0, seed=0):
    """Two channels: noise at rest and a burst (DLI 1.0-1.5 s, OOS 2.0-2.2 s)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * rate)) / rate
    amp = np.stack([0.05 + 1.0 * ((t >= 1.0) & (t < 1.5)),
                    0.05 + 0.5 * ((t >= 2.0) & (t < 2.2))], axis=1)
    return t, 0.3 + amp * rng.standard_normal(amp.shape)  # 0.3 V DC offset


def test_trapezoid_window_has_unit_area_and_17ms_width():
    k = trapezoid_kernel(2500.0)
    assert k.sum() == pytest.approx(1.0)
    assert len(k) == pytest.approx(0.017 * 2500, abs=1)
    assert k[len(k) // 2] == k.max() and k[0] < k[len(k) // 4 + 2]


def test_integration_of_a_constant_rectified_signal():
    x = np.full((2500, 1), 2.0)
    x[::2] = -2.0  # rectified, a constant 2 after removing the (zero) median
    t, env = integrate(x, 2500.0)
    assert len(t) == 60  # 0 ... 59/60 s within one second of data
    np.testing.assert_allclose(env[3:-3], 2.0, rtol=1e-9)


def test_emg_pipeline_on_a_synthetic_burst():
    t, x = burst_emg()
    res = process_emg(x, 2500.0, ["dli", "OOS"])
    assert res.channels == ("DLI", "OOS")
    assert len(res.time) == int(3.0 * 60)
    assert res.activity.min() >= 0 and res.activity.max() <= 1
    act = res.activity
    tt = res.time
    quiet = (tt > 0.2) & (tt < 0.8)
    burst = (tt > 1.1) & (tt < 1.4)
    assert act[quiet, 0].mean() < 0.05
    assert act[burst, 0].mean() > 0.6
    # onset within a frame of 1.0 s: first frame above half the burst level
    onset = tt[np.argmax(act[:, 0] > 0.5 * act[burst, 0].mean())]
    assert onset == pytest.approx(1.0, abs=1.5 / 60)
    # the second channel has its own normalisation
    assert act[(tt > 2.05) & (tt < 2.15), 1].mean() > 0.6
    # an explicit baseline interval gives the same zero level
    res2 = process_emg(x, 2500.0, ["DLI", "OOS"], baseline=(0.1, 0.9))
    assert res2.activity[quiet, 0].mean() < 0.05


def test_calibration_recording_sets_the_maximum():
    t, x = burst_emg()
    cal = x.copy()
    cal[:, 0] *= 2.0  # maximal gestures twice as strong
    res = process_emg(x, 2500.0, ["DLI", "OOS"], calibration=cal, calibration_rate=2500.0)
    burst = (res.time > 1.1) & (res.time < 1.4)
    assert 0.3 < res.activity[burst, 0].mean() < 0.6


def test_emg_bad_input():
    t, x = burst_emg(duration=1.0)
    bad = x.copy()
    bad[100, 1] = np.nan
    with pytest.raises(InputError, match="field 'OOS'.*non-finite sample at 100"):
        process_emg(bad, 2500.0, ["DLI", "OOS"], source="emg.csv")
    with pytest.raises(InputError, match="field 'BICEPS'"):
        process_emg(x, 2500.0, ["DLI", "BICEPS"], source="emg.csv")


def test_seven_channel_control_drives_zygomatic_with_levator_anguli():
    ch = {g: np.full(5, 0.1 * (k + 1)) for k, g in
          enumerate(("LLS", "LAO", "DAO", "DLI", "MEN", "OOS", "OOI"))}
    act = seven_channel_control(ch)
    assert act.shape == (5, len(MUSCLE_GROUPS))
    np.testing.assert_allclose(act[:, MUSCLE_GROUPS.index("ZYG")], 0.2)
    np.testing.assert_allclose(act[:, MUSCLE_GROUPS.index("LAO")], 0.2)
    assert np.all(act[:, MUSCLE_GROUPS.index("FRM")] == 0)


def test_activity_csv_round_trip_and_resampling(tmp_path):
    t = np.arange(30) / 60
    a = np.zeros((30, len(MUSCLE_GROUPS)))
    a[:, 0] = np.linspace(0, 1, 30)
    write_activity(tmp_path / "a.csv", t, a)
    t2, a2 = read_activity(tmp_path / "a.csv")
    np.testing.assert_allclose(a2, a, atol=1e-6)
    # 120-Hz input is brought to 60 Hz
    (tmp_path / "b.csv").write_text("time,dao\n" + "".join(f"{k / 120},{k / 240}\n"
                                                          for k in range(121)))
    t3, a3 = read_activity(tmp_path / "b.csv")
    assert len(t3) == 61 and a3[-1, 0] == pytest.approx(0.5)


@pytest.mark.parametrize("text, field", [
    ("time,DAO\n0,0.1\n0.0167,1.5\n", "DAO"),
    ("time,XYZ\n0,0.1\n0.0167,0.5\n", "XYZ"),
    ("time,DAO\n0,0.1\n0.0167,\n", "DAO"),
    ("DAO\n0.1\n0.2\n", "time"),
    ("time,DAO\n0,0.1\n0,0.2\n", "time"),
])
def test_activity_bad_input(tmp_path, text, field):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputError) as info:
        read_activity(p)
    assert info.value.field == field and info.value.source == str(p)


def test_marker_csv_round_trip_with_units_and_gaps(tmp_path):
    pos = np.random.default_rng(1).normal(size=(5, 2, 3)) * 0.01
    pos[2, 1] = np.nan
    table = MarkerSet(pos, ("chin", "lip"), 60.0)
    write_marker_csv(tmp_path / "m.csv", table, units="mm")
    back = read_marker_csv(tmp_path / "m.csv")
    assert back.names == table.names
    np.testing.assert_allclose(back.positions, pos, atol=1e-9)
    assert np.isnan(back.positions[2, 1]).all()
    (tmp_path / "n.csv").write_text("time,a_x,a_y,a_z\n0,1,2,3\n1,1,2,3\n")
    with pytest.raises(InputError, match="no length unit"):
        read_marker_csv(tmp_path / "n.csv")
    assert read_marker_csv(tmp_path / "n.csv", units="cm").positions[0, 0, 1] == 0.02


def test_results_round_trip(face, tmp_path):
    act = np.zeros((6, len(MUSCLE_GROUPS)))
    act[:, 0] = 0.5
    sim = simulate(face_model(face), act, np.linspace(0, 0.05, 6))
    path = write_results(tmp_path / "r.nc", sim, inputs={"activity": "abc"})
    ds = read_results(path)
    np.testing.assert_array_equal(ds["positions"].values, sim.positions)
    np.testing.assert_array_equal(ds["markers"].sel(marker="R03").values, sim.marker("R03"))
    np.testing.assert_array_equal(ds["activity"].values, act)
    np.testing.assert_array_equal(ds["jaw_angle"].values, sim.jaw_angle)
    assert ds["positions"].attrs["units"] == "m"
    assert ds.attrs["integrator"] == "implicit" and ds.attrs["preset"] == "anatomical"
    assert ds.attrs["dt_s"] == pytest.approx(1 / 240)
    assert "facemech_version" in ds.attrs and '"activity": "abc"' in ds.attrs["inputs"]
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left


def test_results_name_the_numerical_environment(face, tmp_path):
    """The libraries and the CPU target that made the numbers (issue 32): their last bits
    depend on them (docs/reproducibility.md)."""
    import json
    from importlib import metadata

    import numba

    sim = simulate(face_model(face), np.zeros((3, len(MUSCLE_GROUPS))))
    ds = read_results(write_results(tmp_path / "r.nc", sim))
    for lib in ("numpy", "scipy", "numba", "llvmlite"):
        assert ds.attrs[f"{lib}_version"] == metadata.version(lib), lib
    assert ds.attrs["numba_cpu"] == (numba.config.CPU_NAME
                                     or numba.core.codegen.ll.get_host_cpu_name())
    blas = json.loads(ds.attrs["blas"])
    assert blas and all(b["version"] and b["architecture"] for b in blas), blas
    assert ds.attrs["blas_core"] == ",".join(sorted({b["architecture"] for b in blas}))
    assert ds.attrs["cpu_model"] and ds.attrs["machine"]


def test_results_refuse_non_finite(face, tmp_path):
    sim = simulate(face_model(face), np.zeros((3, len(MUSCLE_GROUPS))))
    sim.positions[1, 0, 0] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        write_results(tmp_path / "r.nc", sim)
    assert list(tmp_path.iterdir()) == []


def test_emg_from_c3d_analog_channels(tmp_path):
    ezc3d = pytest.importorskip("ezc3d")
    from facemech import read_emg

    t, x = burst_emg(duration=2.0)
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c["parameters"]["POINT"]["LABELS"]["value"] = ("chin",)
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c["data"]["points"] = np.ones((4, 1, 200))
    c["parameters"]["ANALOG"]["RATE"]["value"] = [2500.0]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = ("DLI", "OOS")
    c["data"]["analogs"] = x.T[None]
    c.write(str(tmp_path / "emg.c3d"))
    sig, rate, names = read_emg(tmp_path / "emg.c3d")
    assert rate == 2500.0 and names == ("DLI", "OOS")
    np.testing.assert_allclose(sig, x, atol=1e-5)
    res = process_emg(sig, rate, names)
    assert res.activity[(res.time > 1.1) & (res.time < 1.4), 0].mean() > 0.6
