"""The anatomical (default) preset against what real faces do: gesture amplitudes through the
command line, no crease when the jaw opens (built-in face and a scan-like face), the three
mesh resolutions, the response to a pulse, and the chin marker driving the jaw."""


import numpy as np
import pytest

from conftest import run_cli
from facemech import default_face, read_results
from facemech.analysis.folds import largest_fold_increase
from facemech.analysis.gestures import (
    MAX_DISPLACEMENT_MM,
    TARGETS,
    check_targets,
    gesture_activity,
    measure,
    run_gesture,
)
from facemech.io.activity import write_activity
from facemech.params import MUSCLE_GROUPS, preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate


@pytest.mark.slow
def test_gesture_amplitudes_reach_real_faces_through_the_cli(tmp_path, monkeypatch, capsys):
    """Each muscle group pair at full activity (ramped 0.2 s, held 0.5 s), simulated with
    ``facemech simulate`` as a user calls it, moves the named landmark at least as far as the
    issue's table asks, and no landmark more than 20 mm."""
    face = default_face()
    table = {}
    for groups in sorted({t[0] for t in TARGETS}):
        act = gesture_activity(groups)
        path = tmp_path / f"{'_'.join(groups)}.csv"
        write_activity(path, np.arange(len(act)) / 60.0, act)
        res = tmp_path / f"{'_'.join(groups)}.nc"
        code, _, err = run_cli(monkeypatch, capsys, "simulate", "--activity", path, "-o", res)
        assert code == 0, err
        pos = read_results(res)["positions"].values
        table["+".join(groups)] = measure(face, pos[-1] - pos[0], pos[0])
    assert check_targets(table) == []
    assert max(row["largest"] for row in table.values()) <= MAX_DISPLACEMENT_MM


@pytest.mark.parametrize("which", ["built-in", "scan"])
def test_opening_the_jaw_draws_no_crease(which):
    """Opening the jaw 10 degrees raises no angle between neighbouring triangles outside the
    lips by more than 20 degrees over its value at rest, on the built-in face and on a face
    built from an irregular scan-like mesh."""
    if which == "built-in":
        face = default_face()
    else:
        from facemech.geometry.builder import build_face, tissue_options
        from scans import scan_face

        v, f, lm = scan_face()
        face = build_face(v, f, lm, name="scan", options=tissue_options("anatomical"))
    jaw = np.radians(10.0) * np.clip(np.arange(40) / 15, 0, 1)
    sim = simulate(face_model(face), np.zeros((40, len(MUSCLE_GROUPS))), jaw)
    assert np.degrees(sim.jaw_angle[-1]) == pytest.approx(10.0)
    assert largest_fold_increase(sim.model, sim.positions[-1]) < 20.0
    # the seeds' tissue on the same face creases (the issue's complaint)
    seeds = simulate(face_model(face, preset("lucero1999")), np.zeros((40, len(MUSCLE_GROUPS))),
                     jaw)
    assert largest_fold_increase(seeds.model, seeds.positions[-1]) > 25.0


RESOLUTION_MEASURES = [("ZYG", "corner_up"), ("LAO", "corner_up"), ("DAO", "corner_up"),
                       ("RIS", "corner_out"), ("LLS", "upper_lip_up"), ("DLI", "lower_lip_down"),
                       ("OOS+OOI", "mouth_narrower"), ("OOS+OOI", "lips_forward")]
#: measures the issue names whose coarse face is off by more than 15 % (docs/model.md)
RESOLUTION_MISSES = [("ZYG", "corner_out"), ("MEN", "chin_up")]


@pytest.mark.slow
def test_three_resolutions_give_the_same_gestures():
    """Coarse (about 2.6 mm at the lips), default (2 mm) and fine (1.5 mm) built-in faces move
    alike within 15 %: constants per volume, masses from density, forces over areas."""
    got = {}
    for name in ("default-coarse", "default", "default-fine"):
        face = default_face(name)
        for groups in {g for g, _ in RESOLUTION_MEASURES}:
            m = run_gesture(face_model(face), tuple(groups.split("+"))).measures
            for g, key in RESOLUTION_MEASURES:
                if g == groups:
                    got.setdefault((g, key), []).append(m[key])
    for (g, key), v in got.items():
        v = np.abs(np.array(v))
        assert (v.max() - v.min()) / v[1] < 0.15, (g, key, v)


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="issue 11, not met: ZYG's outward motion (16.0 %) and mentalis's chin "
                   "(23.4 %) differ by more than 15 % between the three faces")
def test_three_resolutions_agree_on_every_named_measure():
    """The issue's other two measures, ZYG corner outward and MEN chin up, within 15 % too."""
    got = {}
    for name in ("default-coarse", "default", "default-fine"):
        face = default_face(name)
        for g, key in RESOLUTION_MISSES:
            got.setdefault((g, key), []).append(run_gesture(face_model(face), (g,)).measures[key])
    for (g, key), v in got.items():
        v = np.abs(np.array(v))
        assert (v.max() - v.min()) / v[1] < 0.15, (g, key, v)


def rise_time(face, group, landmark, axis, level=1.0, frames=61):
    """10-90 % rise time (s) of a landmark's displacement along ``axis`` after a step of
    activity, against its value after ``frames`` frames."""
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    act[:, MUSCLE_GROUPS.index(group)] = level
    sim = simulate(face_model(face), act)
    y = np.abs(sim.positions[:, face.landmarks[landmark], axis]
               - sim.positions[0, face.landmarks[landmark], axis])
    t = np.arange(frames) / 60.0
    mono = np.maximum.accumulate(y)
    return np.interp(0.9 * y[-1], mono, t) - np.interp(0.1 * y[-1], mono, t)


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="issue 11, not met: a full zygomaticus step rises in about 190 ms "
                   "(activation filter, Hill force-velocity, the step's numerical drag; "
                   "docs/model.md, Dynamics)")
def test_a_step_rises_as_fast_as_real_lips(face):
    """The 10-90 % rise time of a step of activity is between 30 and 150 ms."""
    assert 0.030 <= rise_time(face, "ZYG", "mouth_corner_right", 1) <= 0.150


def _speed_benchmark():
    """benchmarks/speed.py, the measures of issue 27's speed table."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    import speed

    return speed


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="issue 27, not met: full DLI moves the lower lip at 67 mm/s at most "
                   "under the preset's step (126 mm/s with the fast-lips step, 0.6 x real "
                   "time; docs/model.md, The correction on a region about the mouth)")
def test_the_lower_lip_moves_as_fast_as_real_lips(face):
    """Issue 27: a step of full activity moves the lower lip at 120 mm/s or more (real lower
    lips: 115-233 mm/s)."""
    got = _speed_benchmark().measure(face, preset("anatomical"), ("DLI",), "lower_lip_center",
                                     1, 1.0)
    assert got["peak_speed_mm_s"] >= 120.0


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="issue 27, not met: full OOSM lowers the upper lip at 23 mm/s with "
                   "the jaw open 10 degrees under the preset's step (59 mm/s with the fast-lips "
                   "step; docs/model.md, The correction on a region about the mouth)")
def test_the_upper_lip_lowers_as_fast_as_real_lips(face):
    """Issue 27: the marginal orbicularis lowers the upper lip at 60 mm/s or more (real upper
    lips: up to 58 mm/s), measured with the jaw open 10 degrees as before a bilabial."""
    got = _speed_benchmark().measure_open_jaw(face, preset("anatomical"), ("OOSM",),
                                              "upper_lip_center", 1, 1.0)
    assert got["peak_speed_mm_s"] >= 60.0


@pytest.mark.parametrize("group,landmark,axis", [("ZYG", "mouth_corner_right", 1),
                                                 ("DLI", "lower_lip_center", 1),
                                                 ("OOS", "upper_lip_center", 2)])
def test_a_full_pulse_returns_to_rest_without_ringing(face, group, landmark, axis):
    """After a 100-ms full pulse the landmark does not overshoot rest by more than 10 % of its
    peak: the tissue is at least critically damped."""
    act = np.zeros((60, len(MUSCLE_GROUPS)))
    act[:6, MUSCLE_GROUPS.index(group)] = 1.0
    if group == "OOS":
        act[:6, MUSCLE_GROUPS.index("OOI")] = 1.0
    sim = simulate(face_model(face), act)
    x = sim.positions[:, face.landmarks[landmark], axis] - sim.positions[0, face.landmarks[
        landmark], axis]
    sign = np.sign(x[np.argmax(np.abs(x))])
    x = sign * x
    peak = x.max()
    assert peak > 1e-3
    after = x[np.argmax(x):]
    assert -after.min() < 0.1 * peak
    assert np.all(np.diff(x[:4]) >= 0)  # it moves the way the muscle pulls from the start


def test_a_chin_marker_drives_the_jaw_in_the_tissue(face):
    """A chin marker on the skin that drops 6 mm gives the model's chin marker a 6 mm drop once
    the tissue has settled: the jaw angle comes from the skin's own response."""
    from facemech.solvers.jaw_drive import jaw_angles_from_marker

    p = preset("anatomical")
    node = face.markers["R01"]
    y = face.rest_positions[node, 1] - np.concatenate([np.linspace(0, 6e-3, 12),
                                                       np.full(48, 6e-3)])
    jaw = jaw_angles_from_marker(face_model(face, p), node, y, lead=0)
    sim = simulate(face_model(face, p), np.zeros((60, len(MUSCLE_GROUPS))), jaw)
    drop = sim.positions[-1, node, 1] - sim.positions[0, node, 1]
    assert drop * 1e3 == pytest.approx(-6.0, abs=0.4)


def test_an_explicit_step_is_refused_under_the_implicit_preset(tmp_path, monkeypatch, capsys):
    """``--dt`` sets the explicit Euler step: under the anatomical preset (implicit steps) a dt
    other than the implicit step is an error naming the field, never silently ignored."""
    act = tmp_path / "act.csv"
    write_activity(act, np.arange(3) / 60.0, np.zeros((3, len(MUSCLE_GROUPS))))
    out = tmp_path / "r.nc"
    code, _, err = run_cli(monkeypatch, capsys, "simulate", "--face", "default-coarse",
                           "--activity", act, "--dt", "0.001", "-o", out)
    assert code == 2 and "dt" in err and "substeps" in err and not out.exists()
    assert len(err.strip().splitlines()) == 1
    code, _, err = run_cli(monkeypatch, capsys, "simulate", "--face", "default-coarse",
                           "--activity", act, "--dt", str(1 / 240), "-o", out)
    assert code == 0, err


def test_speech_targets_span_the_ranges_of_real_speech(face):
    """The synthetic targets of the reachability check move as far as issue 27's recordings:
    upper lip 3.0 mm vertical (all of it down) and 3.0 mm front-back, lower lip 9.0 and 4.5 mm,
    6.0 mm of it relative to the lower incisor, the incisor 4.5 mm, the chin 4.5 mm; the lower
    lip at up to 118 mm/s."""
    from facemech.analysis.reachability import speech_targets

    ms = speech_targets(face)
    d = (ms.positions - ms.positions[0]) * 1e3

    def span(names, axis):
        v = d[:, [ms.names.index(n) for n in names], axis]
        return v.max() - v.min()

    assert span(("R05", "L04"), 1) == pytest.approx(3.0, abs=0.05)
    assert d[:, ms.names.index("R05"), 1].max() == pytest.approx(0.0, abs=1e-9)
    assert span(("R05", "L04"), 2) == pytest.approx(3.0, abs=0.05)
    assert span(("R03", "L02"), 1) == pytest.approx(9.0, abs=0.05)
    assert span(("R03", "L02"), 2) == pytest.approx(4.5, abs=0.05)
    rel = d[:, ms.names.index("R03"), 1] - d[:, ms.names.index("LI"), 1]
    assert rel.max() - rel.min() == pytest.approx(6.0, abs=0.05)
    assert span(("LI",), 1) == pytest.approx(4.5, abs=0.05)
    assert span(("R01",), 1) == pytest.approx(4.5, abs=0.05)
    speed = np.abs(np.diff(d[:, ms.names.index("R03"), 1])).max() * 60.0
    assert 100.0 <= speed <= 125.0
    # mirror-symmetric: left and right markers of a pair move alike, the corners mirrored
    r, l_ = ms.names.index("R07"), ms.names.index("L06")
    assert np.allclose(d[:, r, 0], -d[:, l_, 0]) and np.allclose(d[:, r, 1:], d[:, l_, 1:])


@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="issue 27, not met: the speech targets are fitted within 1.35 mm "
                   "RMS (1.17 at 12 steps per frame), not 0.5, with the jaw from the incisor "
                   "and the marginal orbicularis; "
                   "4 times slower still 1.14 mm: reach, not speed (the upper lip 3 mm down "
                   "in /p/ drags the lower lip; docs/model.md, Reachability)")
@pytest.mark.slow
def test_the_lip_positions_of_real_speech_are_reachable(face):
    """Synthetic lip targets with the ranges of real speech, inverted with the jaw driven from
    the lower incisor, fit within 0.5 mm RMS (the issue's target; strict: this test fails the
    suite the day it passes, so that the mark comes off)."""
    from facemech.analysis.reachability import reach

    assert reach(face_model(face)).rms < 0.5e-3
