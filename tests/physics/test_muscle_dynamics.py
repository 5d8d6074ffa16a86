"""The muscle's speed laws beyond the seeds' constants (issue 27, part 2): eq. (4)'s filter with
a measured damping ratio, and eq. (6)'s velocity scale from an intrinsic speed in fibre lengths
per second and each muscle's fibre length. The seeds' presets keep their constants to the bit."""

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.io.activity import write_activity
from facemech.params import FACIAL_VMAX, MUSCLE_GROUPS, Parameters, preset, read_preset
from facemech.physics import muscle
from facemech.physics.assembly import Physics

#: the lips' force response to a stimulus pulse: 6.1 Hz, damping ratio 0.7 (orbicularis oris
#: superior and inferior, eight subjects; Ito, Murano & Gomi 2004, J Appl Physiol 96:2318)
ITO_TAU = 1.0 / (2.0 * np.pi * 6.1)
ITO_ZETA = 0.7


def test_the_damped_filter_is_exact_and_the_seeds_filter_unchanged():
    """Stepped exactly, the underdamped filter follows its closed-form step response at every
    step, overshoots by exp(-pi zeta / sqrt(1 - zeta^2)) (4.6 % at 0.7), and at zeta = 1 it is
    the seeds' critically damped step to the bit."""
    m, r = 0.0, 0.0
    t = np.arange(1, 201) * 1e-3
    got = []
    for _ in t:
        m, r = muscle.activation_exact_damped(m, r, 2.0, ITO_TAU, ITO_ZETA, 1e-3)
        got.append(m)
    want = muscle.activation_response(t, 2.0, ITO_TAU, ITO_ZETA)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)
    overshoot = max(got) / 2.0 - 1.0
    assert overshoot == pytest.approx(np.exp(-np.pi * ITO_ZETA / np.sqrt(1 - ITO_ZETA**2)),
                                      rel=1e-3)
    for state in [(0.0, 0.0), (0.7, -3.0), (1.3, 40.0)]:
        assert (muscle.activation_exact_damped(*state, 1.0, 0.015, 1.0, 4e-3)
                == muscle.activation_exact(*state, 1.0, 0.015, 4e-3))


def _rise_10_90(tau, zeta):
    """10-90 % rise time (s) of eq. (4)'s step response, from its closed form."""
    t = np.linspace(0.0, 0.4, 400_001)
    y = np.maximum.accumulate(muscle.activation_response(t, 1.0, tau, zeta))
    return np.interp(0.9, y, t) - np.interp(0.1, y, t)


def test_the_lip_filter_rises_as_the_lips_measured_response():
    """The anatomical preset's critically damped filter (params.LIP_ACTIVATION_TAU, 16.5 ms) has the
    10-90 % rise of the lips' measured response (6.1 Hz, damping 0.7: 55.5 ms), 10 % slower
    than the seeds' 15 ms (50.4 ms)."""
    from facemech.params import ITO_ACTIVATION, LIP_ACTIVATION_TAU

    ito = _rise_10_90(ITO_ACTIVATION["tau_activation"], ITO_ACTIVATION["activation_damping"])
    assert ito == pytest.approx(55.5e-3, abs=0.1e-3)
    assert _rise_10_90(LIP_ACTIVATION_TAU, 1.0) == pytest.approx(ito, rel=0.005)
    assert _rise_10_90(0.015, 1.0) == pytest.approx(50.4e-3, abs=0.1e-3)


def test_the_damped_filter_by_euler_converges_at_first_order():
    """The explicit Euler step of the damped filter converges to the exact response with the
    error halving as the step halves."""
    errs = []
    for dt in (1e-4, 5e-5, 2.5e-5):
        m, r = 0.0, 0.0
        for _ in range(int(round(0.05 / dt))):
            m, r = muscle.activation_euler(m, r, 1.0, ITO_TAU, dt, ITO_ZETA)
        errs.append(abs(m - muscle.activation_response(0.05, 1.0, ITO_TAU, ITO_ZETA)))
    assert errs[0] < 1e-3
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.1)
    assert errs[1] / errs[2] == pytest.approx(2.0, rel=0.1)


def test_the_seeds_f4_halves_the_force_at_57_mm_per_s():
    """With the seeds' f1-f3, eq. (6)'s factor halves where its arctan's argument is
    half_force_argument: f4 = 20 s/m puts that at 57 mm/s of shortening (the issue's figure)."""
    p = Parameters()
    x = muscle.half_force_argument(p.f1, p.f2, p.f3)
    iso = p.f1 + p.f2 * np.arctan(p.f3)
    assert p.f1 + p.f2 * np.arctan(x) == pytest.approx(iso / 2, rel=1e-12)
    assert (p.f3 - x) / p.f4 * 1e3 == pytest.approx(57.0, abs=0.1)


@pytest.mark.parametrize("curvature", [0.25, 0.4])
def test_hill_half_speed_is_where_the_hyperbola_halves(curvature):
    """Hill's hyperbola (1 - v/Vmax) / (1 + v/(a Vmax)) is 1/2 at hill_half_speed(a) Vmax
    (1/6 of Vmax at a = 0.25)."""
    x = muscle.hill_half_speed(curvature)
    assert (1 - x) / (1 + x / curvature) == pytest.approx(0.5, rel=1e-12)
    if curvature == 0.25:
        assert x == pytest.approx(1 / 6)


@pytest.mark.parametrize("rest_length", [0.02, 0.048])
def test_a_fibre_f4_halves_the_hill_force_at_the_hyperbolas_half_speed(rest_length):
    """Eq. (6) with the fibre f4 of a muscle of ``rest_length`` gives half its isometric force at
    hill_half_speed x Vmax x l0 of shortening: a 48-mm zygomaticus at 20 l0/s, 160 mm/s; a
    20-mm muscle at 67 mm/s. The force then scales with the fibre length, not in m/s."""
    p = Parameters()
    f4 = muscle.fibre_f4(rest_length, 20.0, 0.25, p.f1, p.f2, p.f3)
    v_half = 20.0 * rest_length / 6.0
    iso = muscle.hill_force(1.0, rest_length, rest_length, 0.0, 0.0, p.f1, p.f2, p.f3, f4)
    half = muscle.hill_force(1.0, rest_length, rest_length, -v_half, 0.0, p.f1, p.f2, p.f3, f4)
    assert half == pytest.approx(iso / 2, rel=1e-12)


def test_each_muscle_gets_its_own_f4_and_the_seeds_keep_theirs(face, seeds_face):
    """Under an intrinsic speed, each instance's f4 is (f3 - x_half) / (v_half l0) with its own
    rest length (the short mentalis slower in m/s than the long zygomaticus); the seeds' presets
    give every muscle f4 = 20 s/m."""
    seeds = Physics.build(seeds_face, preset("lucero1999")).forces.muscles
    assert np.all(seeds.f4 == 20.0)
    ph = Physics.build(face, preset("anatomical").with_(fv_vmax=20.0))
    f4 = ph.forces.muscles.f4
    names = ph.model.muscles.names
    p = ph.params
    x = muscle.half_force_argument(p.f1, p.f2, p.f3)
    np.testing.assert_allclose(f4, (p.f3 - x) / (20.0 / 6.0 * ph.forces.muscles.rest_length),
                               rtol=1e-12)
    assert f4[names.index("MEN_R")] > f4[names.index("ZYG_R")]
    # at the facial muscles' 11 fibre lengths per second (params.FACIAL_VMAX) zygomaticus
    # halves its force at 88 mm/s of shortening, mentalis at 39 (docs/model.md)
    v_half = 1e3 * FACIAL_VMAX / 6.0 * ph.forces.muscles.rest_length
    assert v_half[names.index("ZYG_R")] == pytest.approx(88.0, abs=1.5)
    assert v_half[names.index("MEN_R")] == pytest.approx(39.0, abs=1.5)
    # the default anatomical preset: those speeds, and eq. (4) with the rise of the lips'
    # measured response; none of the seeds' constants
    a = preset("anatomical")
    assert (a.fv_vmax, a.tau_activation, a.activation_damping) == (FACIAL_VMAX, 16.5e-3, 1.0)
    np.testing.assert_allclose(Physics.build(face, a).forces.muscles.f4,
                               (p.f3 - x) / (v_half * 1e-3), rtol=1e-12)


@pytest.mark.parametrize("field,value", [("activation_damping", 1.5),
                                         ("activation_damping", 0.0),
                                         ("fv_vmax", -1.0), ("fv_curvature", 0.0),
                                         ("tau_activation", float("nan"))])
def test_out_of_range_dynamics_are_refused_naming_the_field(field, value):
    with pytest.raises(InputError) as info:
        Parameters(**{field: value})
    assert info.value.field == field


def test_a_preset_file_sets_the_muscle_dynamics(tmp_path, monkeypatch, capsys):
    """A preset file's ``muscle`` block sets the intrinsic speed and the filter in the file's
    units (ms for tau); a bad value is one line naming the file and the entry, exit 2, nothing
    written; through ``facemech simulate --preset`` the activation follows the damped filter."""
    good = {"format": "facemech-preset", "version": 1, "name": "fast", "base": "anatomical",
            "scales": {"force": 1.0},
            "muscle": {"fv_vmax_fibre_lengths_per_s": 20, "activation_tau_ms": 26.1,
                       "activation_damping": 0.7}}
    path = tmp_path / "fast.json"
    path.write_text(json.dumps(good))
    p = read_preset(path)
    assert (p.fv_vmax, p.tau_activation, p.activation_damping) == (20.0, 0.0261, 0.7)
    act = tmp_path / "act.csv"
    level = np.zeros((7, len(MUSCLE_GROUPS)))
    level[:, MUSCLE_GROUPS.index("ZYG")] = 1.0
    write_activity(act, np.arange(7) / 60.0, level)
    out = tmp_path / "r.nc"
    code, _, err = run_cli(monkeypatch, capsys, "simulate", "--face", "default-coarse",
                           "--activity", act, "--preset", path, "-o", out)
    assert code == 0, err
    from facemech import read_results

    res = read_results(out)
    names = [str(n) for n in res["muscle_instance"].values]
    zyg = res["muscle_activation"].values[:, names.index("ZYG_R")]
    t = np.arange(7) / 60.0
    np.testing.assert_allclose(zyg / zyg.max(), (muscle.activation_response(t, 1, 0.0261, 0.7)
                                                 / muscle.activation_response(
                                                     t[-1], 1, 0.0261, 0.7)), rtol=1e-9,
                               atol=1e-12)
    for key, value in [("activation_damping", 2.0), ("fv_vmax_fibre_lengths_per_s", "fast"),
                       ("stiffness", 1.0)]:
        bad = {**good, "muscle": {key: value}}
        path.write_text(json.dumps(bad))
        out2 = tmp_path / "r2.nc"
        code, _, err = run_cli(monkeypatch, capsys, "simulate", "--face", "default-coarse",
                               "--activity", act, "--preset", path, "-o", out2)
        lines = [ln for ln in err.strip().splitlines() if "still working" not in ln]
        assert code == 2 and len(lines) == 1 and "muscle." + key in lines[0], err
        assert str(path.name) in lines[0] and not out2.exists()
