"""Element kernels against hand-computed values: eqs. (1)-(7) and (9) of Lucero & Munhall 1999."""

import math

import numpy as np
import pytest

from facemech.params import Parameters, preset
from facemech.physics import muscle, springs, volume
from facemech.stepping import StepOptions


def test_presets_are_si_conversions_of_the_paper():
    p = preset("lucero1999")
    assert p.node_mass == pytest.approx(2.3e-4)
    assert p.damping == pytest.approx(0.030)
    assert p.k_epidermis == pytest.approx(1.2)
    assert p.k_force == pytest.approx(250.0)
    assert p.f4 == pytest.approx(20.0)
    assert p.k_volume == pytest.approx(1.0e4)
    assert p.passive_stiffness("OOS") == pytest.approx(17.3 * 0.6)
    assert StepOptions().steps_per_frame(p.frame_rate) == 50
    assert preset("pitermann2001").damping == pytest.approx(0.050)


def test_rest_length_scaling_of_stiffness():
    # a 2.5-mm spring is 4 times as stiff as the 1-cm reference
    assert springs.scaled_stiffness(0.6, 2.5e-3) == pytest.approx(2.4)


def test_eq1_linear_and_biphasic_elongation():
    l0, k1, k2 = 0.01, 0.6, 6.0
    # 10 % strain: below the knee, k1 dl
    assert springs.spring_force(0.011, l0, k1, k2, biphasic=True) == pytest.approx(0.6 * 0.001)
    # 30 % strain: 0.2 k1 l0 + k2 (dl - 0.2 l0) = 0.2*0.6*0.01 + 6*(0.003 - 0.002)
    assert springs.spring_force(0.013, l0, k1, k2, biphasic=True) == pytest.approx(
        0.0012 + 0.006)
    # the same spring without the biphasic law stays linear
    assert springs.spring_force(0.013, l0, k1, k2, biphasic=False) == pytest.approx(0.6 * 0.003)


def test_eq2_compression():
    l0, k = 0.01, 1.2
    # 10 % compression: k l0 tan(pi sigma dl / (2 l0)) with dl = -0.001
    want = k * l0 * math.tan(math.pi * 0.98 * -0.001 / (2 * l0))
    assert springs.spring_force(0.009, l0, k) == pytest.approx(want)
    # slope at rest: pi sigma k / 2, and unbounded growth towards zero length
    tiny = springs.spring_force(l0 - 1e-9, l0, k) / -1e-9
    assert tiny == pytest.approx(math.pi * 0.98 * k / 2, rel=1e-5)
    assert springs.spring_force(1e-6, l0, k) < -30 * k * l0


def test_eq3_steady_force():
    # k_f S E = 250 N/m^2 * 0.1e-4 m^2 * 0.5
    assert muscle.steady_force(250.0, 0.1e-4, 0.5) == pytest.approx(1.25e-3)


def test_eq5_force_length():
    assert muscle.force_length(0.03, 0.03) == pytest.approx(1.0)
    r = 1.2
    want = math.exp(-abs((r**2.3 - 1) / 1.26) ** 1.62)
    assert muscle.force_length(1.2 * 0.03, 0.03) == pytest.approx(want)
    assert want == pytest.approx(0.7873, abs=1e-4)  # by hand: 1.2^2.3 = 1.5210
    assert muscle.force_length(0.7 * 0.03, 0.03) < 1.0


def test_eq6_eq7_hill_force():
    p = Parameters()
    m = 0.01
    # isometric at rest length: M (f1 + f2 atan f3), no passive force
    iso = muscle.hill_force(m, 0.03, 0.03, 0.0, 10.0, p.f1, p.f2, p.f3, p.f4)
    assert iso == pytest.approx(m * (0.82 + 0.5 * math.atan(0.43)))
    # shortening at 5 cm/s lowers the force: atan(0.43 + 20 * -0.05)
    sh = muscle.hill_force(m, 0.03, 0.03, -0.05, 10.0, p.f1, p.f2, p.f3, p.f4)
    assert sh == pytest.approx(m * (0.82 + 0.5 * math.atan(0.43 - 1.0)))
    # stretched 10 %: active part scaled by eq. 5, plus [k_m dl]^+
    st = muscle.hill_force(m, 0.033, 0.03, 0.0, 10.0, p.f1, p.f2, p.f3, p.f4)
    fl = math.exp(-abs((1.1**2.3 - 1) / 1.26) ** 1.62)
    assert st == pytest.approx(m * fl * (0.82 + 0.5 * math.atan(0.43)) + 10.0 * 0.003)
    # shorter than rest: no passive force ([x]^+ of eq. 7)
    sl = muscle.hill_force(0.0, 0.027, 0.03, 0.0, 10.0, p.f1, p.f2, p.f3, p.f4)
    assert sl == 0.0


def test_eq4_activation_filter_exact_and_euler():
    tau, target = 0.015, 2.0
    t = np.linspace(0, 0.1, 11)
    want = muscle.activation_response(t, target, tau)
    m, r = 0.0, 0.0
    got = [0.0]
    for _ in range(10):
        m, r = muscle.activation_exact(m, r, target, tau, 0.01)
        got.append(m)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    # explicit Euler at the paper's step converges to the same response (first order)
    errs = []
    for dt in (1e-3, 0.5e-3):
        m, r = 0.0, 0.0
        for _ in range(round(0.03 / dt)):
            m, r = muscle.activation_euler(m, r, target, tau, dt)
        errs.append(abs(m - muscle.activation_response(0.03, target, tau)))
    assert errs[1] < errs[0] and errs[0] / errs[1] == pytest.approx(2.0, rel=0.15)


def unit_prism(h=1.0):
    return np.array([[0, 0, h], [1, 0, h], [0, 1, h], [0, 0, 0], [1, 0, 0], [0, 1, 0]], float)


def test_prism_volume():
    assert volume.prism_volume(unit_prism()) == pytest.approx(0.5)
    assert volume.prism_volume(unit_prism(0.004)) == pytest.approx(0.002)
    rot = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    if np.linalg.det(rot) < 0:
        rot[:, 0] *= -1
    p = unit_prism() @ rot.T + np.array([3.0, -2.0, 5.0])
    assert volume.prism_volume(p) == pytest.approx(0.5)


def test_eq9_prism_forces():
    p0 = unit_prism(0.004) * 0.002
    v0, rel0 = volume.rest_geometry(p0, np.arange(6)[None])
    out = np.empty((6, 3))
    volume.prism_forces(p0, v0[0], rel0[0], 1e4, 2.0, out)
    np.testing.assert_allclose(out, 0.0, atol=1e-18)
    # squash the top face down: the volume term pushes the top up and the bottom down
    p = p0.copy()
    p[:3, 2] -= 0.2 * p0[0, 2]
    volume.prism_forces(p, v0[0], rel0[0], 1e4, 0.0, out)
    assert np.all(out[:3, 2] > 0) and np.all(out[3:, 2] < 0)
    expected = -1e4 * (volume.prism_volume(p) - v0[0])
    assert out[0, 2] == pytest.approx(expected)
    # the shape term alone: -k_e2 (p_i - p~_i), and it sums to zero over the element
    volume.prism_forces(p, v0[0], rel0[0], 0.0, 2.0, out)
    np.testing.assert_allclose(out.sum(axis=0), 0.0, atol=1e-15)
    rel = p - p.mean(axis=0)
    np.testing.assert_allclose(out, -2.0 * (rel - rel0[0]), atol=1e-15)


def _assembled(face, params):
    """The bundles of a face through the public assembly (what every solver uses)."""
    from facemech.physics.assembly import Physics, rest_anchors

    ph = Physics.build(face, params)
    return ph, ph.forces, rest_anchors(ph)


def test_springs_bundle_gives_eqs_1_2_on_a_perturbed_face(seeds_face):
    """The springs alone (the other bundles emptied by name) give the sum over springs of the
    vectorised law of eqs. (1)-(2) along each spring, biphasic on the dermal-fatty ones."""
    from facemech.physics.assembly import accumulate_forces
    from facemech.physics.bundles import (
        ContactBundle,
        MuscleBundle,
        PrismBundle,
        RestorationBundle,
    )
    from facemech.physics.kinds import SpringKind

    p = preset("lucero1999")
    ph, bundles, anchors = _assembled(seeds_face, p)
    springs_only = bundles._replace(prisms=PrismBundle.empty(), muscles=MuscleBundle.empty(),
                                    restoration=RestorationBundle.empty(),
                                    contact=ContactBundle.empty())
    rng = np.random.default_rng(5)
    pos = ph.model.rest_positions + rng.normal(0, 3e-4, ph.model.rest_positions.shape)
    out = np.empty_like(pos)
    no_anchors = anchors._replace(rest=np.zeros((0, 3)), normal=np.zeros((0, 3)))
    accumulate_forces(springs_only, pos, np.zeros_like(pos), np.zeros(0), no_anchors, out)
    s = bundles.springs
    d = pos[s.j] - pos[s.i]
    length = np.linalg.norm(d, axis=1)
    dermal = ph.model.spring_kind == SpringKind.DERMAL_FATTY
    assert dermal.any() and np.array_equal(s.biphasic, dermal)
    t = np.where(dermal,
                 springs.spring_force(length, s.rest_length, s.k_low, s.k_high, biphasic=True,
                                      knee=p.biphasic_knee, sigma=p.sigma),
                 springs.spring_force(length, s.rest_length, s.k_low, s.k_high, biphasic=False,
                                      knee=p.biphasic_knee, sigma=p.sigma))
    f = (t / length)[:, None] * d
    want = np.zeros_like(pos)
    np.add.at(want, s.i, f)
    np.add.at(want, s.j, -f)
    np.testing.assert_allclose(out, want, rtol=1e-9, atol=1e-12 * np.abs(want).max())


def test_assembled_forces_at_rest_are_the_dashpots_alone(face):
    """At rest positions every elastic term of the anatomical preset vanishes (springs at rest
    length, prisms at rest volume, tethers at their anchors, no muscle force), so the net force
    is the springs' dashpots on the velocities: r (v_j - v_i) on node i, its opposite on j."""
    from facemech.physics.assembly import accumulate_forces

    ph, bundles, anchors = _assembled(face, preset("anatomical"))
    pos = ph.model.rest_positions.copy()
    vel = np.random.default_rng(6).normal(0, 0.01, pos.shape)
    out = np.empty_like(pos)
    accumulate_forces(bundles, pos, vel, np.zeros(ph.n_muscles), anchors, out)
    s = bundles.springs
    f = s.damping[:, None] * (vel[s.j] - vel[s.i])
    want = np.zeros_like(pos)
    np.add.at(want, s.i, f)
    np.add.at(want, s.j, -f)
    assert np.abs(want).max() > 1e-4  # the dashpots do act
    np.testing.assert_allclose(out, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
