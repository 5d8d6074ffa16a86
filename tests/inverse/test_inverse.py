"""Dynamic inversion (Pitermann & Munhall 2001): statistics, twin experiments, bad input."""

import json
import sys

import numpy as np
import pytest

from facemech import InputError, MarkerSet, read_results, simulate, write_markers
from facemech.inverse.experiments import synthetic_data, triangle_sequence
from facemech.inverse.frame import FrameProblem
from facemech.inverse.invert import control_matrix, invert
from facemech.inverse.methods import LeastSquares
from facemech.kinematics import stats
from facemech.params import MUSCLE_GROUPS, Parameters
from facemech.physics.model import model as face_model
from facemech.solvers.state import State
from facemech.solvers.step import Stepper

SEEDS = Parameters()  # lucero1999: most of these are the seeds' inversion's tests


def held(ms, **kw):
    """The jaw held at rest (these twins keep it closed) and the receding horizon these tests
    were measured with (window 3, no smoothing, 1-um stopping rule)."""
    return {"jaw_angle": np.zeros(ms.n_frames), "window": 3, "smooth": 0.0, "tol": 1e-3, **kw}


def test_3d_statistics_as_published_and_unbiased():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(20, 3))
    n = len(v)
    assert stats.corr3d(v, v) == 1.0  # one normalisation (tests/kinematics/test_error_stats.py)
    assert stats.corr3d(v, v, published=False) == 1.0
    assert stats.corr3d(v, 2 * v + 1, published=False) == pytest.approx(1.0)
    assert stats.corr3d(v, -v, published=False) == pytest.approx(-1.0)
    d = v - v.mean(axis=0)
    assert stats.std3d(v) == pytest.approx(np.sqrt(np.sum(d * d) / (n - 1)))
    two = np.stack([v, 3 * v], axis=1)
    s = np.array([stats.std3d(v), stats.std3d(3 * v)])
    assert stats.movement(two) == pytest.approx(2 * np.sqrt(np.mean(s**2)))
    err = stats.frame_errors(two + np.array([0.0, 0.0, 1.0]), two)
    np.testing.assert_allclose(err, 1.0)
    assert stats.summary5(np.arange(5.0)) == {"min": 0, "q1": 1, "median": 2, "q3": 3, "max": 4}
    ax = stats.axis_correlations(v, v)
    assert ax["displacement"]["x"] == pytest.approx(1.0)
    assert ax["acceleration"]["z"] == pytest.approx(1.0)
    assert "acceleration" not in stats.axis_correlations(v[:4], v[:4])


def test_acceleration_and_cross_correlation_analytic():
    t = np.arange(60) / 60.0
    # a cubic Savitzky-Golay filter differentiates a parabola exactly: (3 t^2)'' = 6
    np.testing.assert_allclose(stats.acceleration(3 * t**2, 60.0), 6.0, atol=1e-9)
    w = 2 * np.pi * 2.0
    acc = stats.acceleration(np.sin(w * t), 60.0)
    # a 7-sample cubic window attenuates a 2-Hz sine at 60 Hz by about 3.5 %
    np.testing.assert_allclose(acc[5:-5], -w**2 * np.sin(w * t[5:-5]), atol=0.05 * w**2)
    assert np.all(stats.acceleration(t[:3], 60.0) == 0)  # too short for a cubic fit
    a = np.sin(w * t)
    assert stats.cross_correlation(a, 2 * a + 1) == pytest.approx(1.0)
    assert stats.cross_correlation(a, -a) == pytest.approx(-1.0)
    assert np.isnan(stats.cross_correlation(a, np.ones_like(a)))


def test_triangle_sequence():
    t = triangle_sequence()
    assert len(t) == 36 and t[6] == 1.0 and t[1] == pytest.approx(1 / 6) and t[11] == t[1]


def twin(face, frames=10):
    """Markers from known activity of three groups (the well-posed case)."""
    names, g = control_matrix(["DLI", "OOS", "LLS"])
    t = np.arange(frames) / 60
    c = np.stack([0.5 + 0.4 * np.sin(2 * np.pi * 2 * t), 0.3 + 0.2 * np.cos(2 * np.pi * t),
                  0.2 + 0.2 * np.sin(2 * np.pi * 1.5 * t)], axis=1)
    sim = simulate(face_model(face, SEEDS), c @ g.T, integrator="euler", dt=1e-3)
    mk = list(face.markers)
    ms = MarkerSet(sim.positions[:, [face.markers[n] for n in mk]], tuple(mk), 60.0)
    mapping = {n: face.markers[n] for n in mk if n.startswith("R")}
    return ms, mapping, c


def test_twin_experiment_recovers_known_activity(seeds_face):
    face = seeds_face
    ms, mapping, truth = twin(face)
    res = invert(face_model(face, SEEDS), ms, mapping, controls=["DLI", "OOS", "LLS"], **held(ms))
    # the activity of the last two frames shows mostly after the recording ends
    np.testing.assert_allclose(res.controls[:-3], truth[:-3], atol=0.05)
    np.testing.assert_allclose(res.controls[-3:-1], truth[-3:-1], atol=0.1)
    assert np.median(res.rms_error[1:]) < 1e-6
    assert np.all(np.isfinite(res.condition[1:])) and np.nanmax(res.condition) < 1e4
    # the re-animation is the forward simulation of the recovered activity
    again = simulate(face_model(face, SEEDS), np.clip(res.activity, 0, 1), integrator="euler",
                     dt=1e-3)
    np.testing.assert_allclose(again.positions, res.positions, atol=1e-12)


def frame_problem(face, frames, horizon, settle=None):
    """One frame's problem on the twin markers, from rest or after holding ``settle``
    activity for six frames."""
    ms, mapping, truth = twin(face, frames=frames)
    names, g = control_matrix(["DLI", "OOS", "LLS"])
    st = Stepper(face_model(face, Parameters()), integrator="euler", dt=1e-3)
    s0 = State.at_rest(face.rest_positions, st.physics.n_muscles)
    for _ in range(0 if settle is None else 6):
        s0 = st.advance(s0, g @ settle, 0.0)
    nodes = np.array(list(mapping.values()))
    data = ms.select(list(mapping)).positions
    return FrameProblem(st, s0, g, nodes, data, np.zeros(frames), 0, horizon)


def test_jacobian_matches_central_differences(seeds_face):
    face = seeds_face
    fp = frame_problem(face, 3, 1)
    c = np.array([0.4, 0.3, 0.2])
    x = fp.lsq(c, None, LeastSquares(window=1, max_evaluations=40, smooth=0.0)).x
    pos0 = fp.roll(x)[0]
    fwd = fp.jacobian(fp.lag_responses(x, pos0))
    cen = np.empty_like(fwd)
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1e-4
        cen[:, j] = (fp.marker_residual(x[0] + e) - fp.marker_residual(x[0] - e)) / 2e-4
    # column by column (the skull and lip contacts switch, so single entries may jump)
    rel = np.linalg.norm(fwd - cen, axis=0) / np.linalg.norm(cen, axis=0)
    assert np.all(rel < 0.1), rel


def test_window_jacobian_from_lag_responses(seeds_face):
    face = seeds_face
    """Within a window the response to a later frame's activity is the first frame's, shifted:
    the block-Toeplitz Jacobian is checked against differences of each frame's activity."""
    fp = frame_problem(face, 5, 3, settle=np.array([0.4, 0.3, 0.2]))
    x = np.array([[0.42, 0.31, 0.2], [0.44, 0.32, 0.2], [0.46, 0.33, 0.2]])
    r0 = fp.marker_residual(x)
    jm = fp.jacobian(fp.lag_responses(x, fp.roll(x)[0]))
    assert jm.shape == (3 * 33, 9)
    assert np.all(jm[:33, 3:] == 0)  # a frame does not see later activity
    full = np.empty_like(jm)
    for col in range(9):
        xe = x.copy().reshape(-1)
        xe[col] += 1e-3
        full[:, col] = (fp.marker_residual(xe) - r0) / 1e-3
    rel = np.linalg.norm(jm - full) / np.linalg.norm(full)
    assert rel < 0.05, rel
    # the regularisation rows: second differences vanish for activity at a steady rate
    a_reg, b_reg = fp.regularisation(np.zeros(3), LeastSquares(bend=1.0, smooth=0.0), None,
                                     None)
    assert a_reg.shape == (3, 9)
    np.testing.assert_allclose(a_reg @ x.reshape(-1) + b_reg, 0.0, atol=1e-12)
    bent = x.copy()
    bent[1] += 0.1
    np.testing.assert_allclose(a_reg @ bent.reshape(-1) + b_reg, -0.2, atol=1e-12)


def test_powell_baseline_with_the_positive_constraint(seeds_face):
    face = seeds_face
    ms, mapping, truth = twin(face, frames=4)
    res = invert(face_model(face, SEEDS), ms, mapping, method="powell",
                 controls=["DLI", "OOS", "LLS"],
                 max_evaluations=150, jaw_angle=np.zeros(ms.n_frames))
    assert np.all(res.controls >= 0)
    assert np.median(res.rms_error[1:]) < 0.02e-3
    assert res.evaluations[1:].min() > 10


def test_experiment1_synthetic_data(seeds_face):
    face = seeds_face
    data, truth = synthetic_data(face_model(face, SEEDS))
    assert data.n_frames == 36 and len(data.names) == 19
    assert truth[:, :8].max() == 1.0 and truth[:, 8:].max() == 0.0


def test_inversion_bad_input(seeds_face):
    face = seeds_face
    ms, mapping, _ = twin(face, frames=4)
    with pytest.raises(InputError, match="resample first"):
        invert(face_model(face, SEEDS), MarkerSet(ms.positions, ms.names, 120.0), mapping)
    with pytest.raises(InputError, match="coordinates for 17 controls"):
        invert(face_model(face, SEEDS), ms, {"R03": mapping["R03"], "R05": mapping["R05"]},
               controls="all")
    gap = ms.positions.copy()
    gap[2, ms.index("R05")] = np.nan
    res = invert(face_model(face, SEEDS), ms.with_positions(gap), mapping,
                 controls=["DLI", "OOS", "LLS"], **held(ms))
    assert res.markers_used[2] == 10 and any("missing" in n for n in res.notes)
    few = ms.positions.copy()
    few[2, [ms.index(n) for n in mapping][1:]] = np.nan
    with pytest.raises(InputError, match="frame 2: 1 usable markers for 4 controls"):
        invert(face_model(face, SEEDS), ms.with_positions(few), mapping,
               controls=["DLI", "OOS", "LLS", "MEN"], **held(ms))


def test_invert_and_compare_commands(seeds_face, tmp_path, monkeypatch, capsys):
    face = seeds_face
    from facemech.cli import main

    ms, mapping, _ = twin(face, frames=6)
    write_markers(tmp_path / "m.csv", ms.select(list(mapping)), units="mm")
    monkeypatch.setattr(sys, "argv", ["facemech", "invert", "--markers", str(tmp_path / "m.csv"),
                                      "--controls", "DLI,OOS,LLS", "-o", str(tmp_path / "r.nc"),
                                      "--figure", str(tmp_path / "act.png"),
                                      "--preset", "lucero1999", "--window", "3",
                                      "--smooth", "0", "--tol", "0.001"])
    with pytest.raises(SystemExit) as info:
        main()
    assert info.value.code in (0, None), capsys.readouterr().err
    ds = read_results(tmp_path / "r.nc")
    assert "rms_error" in ds and ds["rms_error"].values[1:].max() < 1e-5
    assert ds.attrs["inversion_method"] == "lsq"
    assert (tmp_path / "act.png").stat().st_size > 10_000
    capsys.readouterr()
    monkeypatch.setattr(sys, "argv", ["facemech", "compare", str(tmp_path / "r.nc"),
                                      str(tmp_path / "m.csv"), "--json"])
    with pytest.raises(SystemExit) as info:
        main()
    res = json.loads(capsys.readouterr().out)
    assert res["frame_error_mm"]["max"] < 0.01
    assert res["markers"]["R05"]["corr3d_unbiased"] > 0.99


def test_second_talker_adaptation_by_scaling_and_warp(seeds_face):
    face = seeds_face
    from facemech import scale_adapt, warp_face
    from facemech.inverse.experiments import CROSS_EXTRA, second_talker

    other = second_talker()
    names = [*other.markers, *CROSS_EXTRA]
    rest_other = np.array([other.rest_positions[other.markers.get(n, other.landmarks.get(n))]
                           for n in names])
    ms = MarkerSet(rest_other[None].repeat(2, axis=0), tuple(names), 60.0)
    mapping = {n: face.markers.get(n, face.landmarks.get(n)) for n in names}
    rest_face = face.rest_positions[[mapping[n] for n in names]]
    assert np.abs(rest_other - rest_face).max() > 3e-3  # a different talker
    sc = scale_adapt(ms, face, mapping, ("R02", "L07"))
    np.testing.assert_allclose(sc.markers.positions[0], rest_face, atol=1e-12)
    warped = warp_face(face, ms, mapping)
    np.testing.assert_allclose(warped.rest_positions[[mapping[n] for n in names]], rest_other,
                               atol=1e-9)
    # the warped face is a working model: a short simulation stays finite and moves
    act = np.zeros((6, len(MUSCLE_GROUPS)))
    act[:, 6:8] = 0.5
    sim = simulate(face_model(warped, SEEDS), act)
    assert np.isfinite(sim.positions).all() and np.ptp(sim.positions[:, :, 0], axis=0).max() > 0


def test_crosstalker_experiment_runs(seeds_face):
    face = seeds_face
    from facemech.inverse.experiments import run_crosstalker

    res = run_crosstalker(face_model(face, SEEDS), frames=10)
    assert set(res.runs) == {"lsq, positive, scaling", "lsq, positive, warp"}
    for r in res.runs.values():
        assert len(r.corr3d) == 22
        assert np.isfinite(r.frame_error_mm["median"])


def test_experiment1_command_prints_the_tables(tmp_path, monkeypatch, capsys):
    from facemech.cli import main

    monkeypatch.setattr(sys, "argv", ["facemech", "experiment", "pitermann2001-synthetic",
                                      "--preset", "lucero1999", "-o", str(tmp_path / "figs")])
    with pytest.raises(SystemExit) as info:
        main()
    assert info.value.code in (0, None)
    out = capsys.readouterr().out
    assert "Table I" in out and "Table III" in out and "| 0.293" in out
    res = json.loads((tmp_path / "figs" / "summary.json").read_text())
    run = res["runs"]["lsq, positive"]
    assert run["table3_frame_error_mm"]["median"] <= 0.10
    assert run["corr3d_above_0.8"] >= 17
    for run in res["runs"].values():
        ctrl, true = np.array(run["controls"]), np.array(run["true_controls"])
        assert ctrl.shape == true.shape == (36, 7)
        # the fast method recovers the triangle: activity within 0.1 on average
        assert np.abs(ctrl[:-1] - true[:-1]).mean() < 0.1
    figs = sorted(p.name for p in (tmp_path / "figs").glob("*.png"))
    assert figs == ["experiment1_lsq_no-constraint.png", "experiment1_lsq_positive.png"]


def test_tolerance_stops_early_without_losing_the_fit(seeds_face):
    face = seeds_face
    ms, mapping, truth = twin(face, frames=8)
    kw = dict(controls=["DLI", "OOS", "LLS"])
    tight = invert(face_model(face, SEEDS), ms, mapping, **held(ms, tol=0.0), **kw)
    loose = invert(face_model(face, SEEDS), ms, mapping, **held(ms), **kw)
    assert loose.evaluations.sum() < tight.evaluations.sum()
    # 1 um of RMS improvement is the stopping rule: the fit stays within a few micrometres
    assert np.median(loose.rms_error[1:]) < 3e-6
    np.testing.assert_allclose(loose.controls[:-3], truth[:-3], atol=0.05)
    with pytest.raises(InputError, match="tol"):
        invert(face_model(face, SEEDS), ms, mapping, tol=-1.0, **kw)
    with pytest.raises(InputError, match="window"):
        invert(face_model(face, SEEDS), ms, mapping, window=0, **kw)


def test_noisy_experiment_is_also_scored_against_the_true_motion(seeds_face):
    face = seeds_face
    from facemech.inverse.experiments import run_synthetic

    res = run_synthetic(face_model(face, SEEDS), noise=0.5e-3)
    for run in res.runs.values():
        noisy = run.frame_error_mm["median"]
        true = run.vs_noise_free.frame_error_mm["median"]
        # the fit cannot beat the noise in the data, yet stays far closer to the true motion
        assert 0.7 < noisy < 1.0
        assert true < 0.6 * noisy
        assert set(run.vs_noise_free.corr3d) == set(res.markers_used + res.held_out)


def test_regularisation_pulls_activity_as_documented(seeds_face):
    face = seeds_face
    ms, mapping, truth = twin(face, frames=6)
    kw = dict(controls=["DLI", "OOS", "LLS"])
    kw.update(held(ms))
    free = invert(face_model(face, SEEDS), ms, mapping, **kw)
    # a strong prior (e.g. processed EMG) wins over the markers
    prior = np.clip(truth + 0.2, 0, 1)
    led = invert(face_model(face, SEEDS), ms, mapping, prior=prior, prior_weight=100.0, **kw)
    np.testing.assert_allclose(led.controls[:-1], prior[:-1], atol=0.01)
    # a strong effort term drives activity towards zero, at a cost in marker error
    lazy = invert(face_model(face, SEEDS), ms, mapping, effort=100.0, **kw)
    assert np.abs(lazy.controls[:-1]).max() < 0.02 < np.abs(free.controls[:-1]).max()
    assert np.median(lazy.rms_error[1:]) > 10 * np.median(free.rms_error[1:])
    # a strong smoothness term holds activity near the previous frame's (zero at the start)
    still = invert(face_model(face, SEEDS), ms, mapping, **{**kw, "smooth": 100.0})
    assert np.abs(np.diff(still.controls[:-1], axis=0)).max() < 0.02
    with pytest.raises(InputError, match="bend"):
        invert(face_model(face, SEEDS), ms, mapping, bend=-1.0, **kw)



def test_anatomical_twin_experiment_recovers_known_activity(face):
    """The default preset's inversion (implicit steps, muscles through beads) recovers the
    activity that made its own markers."""
    names, g = control_matrix(["DLI", "OOS", "LLS"])
    t = np.arange(8) / 60
    c = np.stack([0.4 + 0.3 * np.sin(2 * np.pi * 2 * t), 0.3 + 0.2 * np.cos(2 * np.pi * t),
                  0.2 + 0.15 * np.sin(2 * np.pi * 1.5 * t)], axis=1)
    sim = simulate(face_model(face), c @ g.T)
    mk = [n for n in face.markers if n.startswith("R")]
    ms = MarkerSet(sim.positions[:, [face.markers[n] for n in mk]], tuple(mk), 60.0)
    res = invert(face_model(face), ms, {n: face.markers[n] for n in mk},
                 controls=["DLI", "OOS", "LLS"],
                 **held(ms))
    np.testing.assert_allclose(res.controls[:-3], c[:-3], atol=0.05)
    assert np.median(res.rms_error[1:]) < 1e-5
