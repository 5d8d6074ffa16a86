"""Forward simulation of the seeds' model (lucero1999) on the built-in face: muscle actions,
jaw, lips, integrators, blow-up. The anatomical preset has its own tests (test_realism.py)."""

import numpy as np
import pytest

from conftest import activity
from facemech import SimulationBlowUp, Stepper, simulate
from facemech.errors import InputError
from facemech.params import MUSCLE_GROUPS, Parameters
from facemech.physics.model import model as face_model
from facemech.solvers.explicit import ExplicitEuler
from facemech.solvers.implicit import LinearImplicitEuler, Rosenbrock2
from facemech.solvers.jaw import angle_for_drop, angles_from_chin, rotate_about
from facemech.solvers.state import Controls, State

FRAMES = 25
SEEDS = Parameters()  # lucero1999


def moved(face, frames=FRAMES, jaw=None, integrator="euler", **levels):
    sim = simulate(face_model(face, SEEDS), activity(frames, **levels), jaw, integrator=integrator)
    d = sim.positions[-1] - sim.positions[0]
    return sim, {k: d[v] for k, v in face.landmarks.items()}


def test_rest_is_an_equilibrium(seeds_face):
    face = seeds_face
    sim, d = moved(face, frames=10)
    assert np.abs(sim.positions - sim.positions[0]).max() < 1e-12


def test_zygomatic_major_lifts_the_mouth_corner_up_and_out(seeds_face):
    face = seeds_face
    _, d = moved(face, ZYG=1.0)
    assert d["mouth_corner_right"][1] > 0.02e-3 and d["mouth_corner_right"][0] < -0.01e-3
    assert d["mouth_corner_left"][1] > 0.02e-3 and d["mouth_corner_left"][0] > 0.01e-3


def test_depressor_anguli_oris_pulls_the_corner_down(seeds_face):
    face = seeds_face
    _, d = moved(face, DAO=1.0)
    assert d["mouth_corner_right"][1] < -0.05e-3 and d["mouth_corner_left"][1] < -0.05e-3


def test_levator_labii_lifts_the_upper_lip(seeds_face):
    face = seeds_face
    _, d = moved(face, LLS=1.0)
    assert d["upper_lip_center"][1] > 0.08e-3
    assert abs(d["lower_lip_center"][1]) < 0.3 * d["upper_lip_center"][1]


def test_depressor_labii_lowers_the_lower_lip(seeds_face):
    face = seeds_face
    _, d = moved(face, DLI=1.0)
    assert d["lower_lip_center"][1] < -0.08e-3
    assert abs(d["upper_lip_center"][1]) < 0.3 * abs(d["lower_lip_center"][1])


def test_orbicularis_oris_narrows_the_mouth(seeds_face):
    face = seeds_face
    sim, d = moved(face, OOS=1.0, OOI=1.0)
    lm = face.landmarks
    width = np.linalg.norm(sim.positions[:, lm["mouth_corner_left"]]
                           - sim.positions[:, lm["mouth_corner_right"]], axis=1)
    assert width[-1] < width[0] - 1.0e-3
    # left and right act alike: the face stays symmetric
    assert d["mouth_corner_left"][0] == pytest.approx(-d["mouth_corner_right"][0], rel=1e-3)


def test_frontalis_raises_the_brows(seeds_face):
    face = seeds_face
    _, d = moved(face, FRM=1.0, FRL=1.0, FRI=1.0)
    assert d["brow_left"][1] > 0.0 and d["brow_right"][1] > 0.0


def lip_gaps(face, sim):
    up, lo = face.lip_pairs.T
    return np.einsum("tqa,qa->tq", sim.positions[:, up[up < face.n_surface]]
                     - sim.positions[:, lo[lo < face.n_surface]],
                     face.lip_normals[up < face.n_surface])


def test_jaw_opening_lowers_lower_lip_and_chin_without_interpenetration(seeds_face):
    face = seeds_face
    chin = face.rest_positions[face.landmarks["chin"] + 2 * face.n_surface]
    theta = angle_for_drop(chin, face.hinge_point, face.hinge_axis, -8e-3)
    jaw = np.concatenate([np.linspace(0, theta, 15), np.full(15, theta)])
    sim, d = moved(face, frames=30, jaw=jaw)
    assert d["chin"][1] < -6e-3
    assert d["lower_lip_center"][1] < -4e-3
    assert abs(d["upper_lip_center"][1]) < 1e-3
    assert lip_gaps(face, sim).min() > -1e-5
    # and closing again with the lips pressed together by the sphincter keeps them apart
    back = np.concatenate([jaw, np.linspace(theta, 0, 15), np.zeros(15)])
    act = np.zeros((60, len(MUSCLE_GROUPS)))
    act[30:, 6:8] = 1.0  # OOS and OOI
    sim2 = simulate(face_model(face, SEEDS), act, back)
    assert lip_gaps(face, sim2).min() > -0.15e-3


def test_jaw_angle_from_chin_marker():
    point, axis = np.array([0.0, -0.046, -0.073]), np.array([1.0, 0.0, 0.0])
    chin = np.array([0.0, -0.112, 0.0])
    drops = np.array([0.0, -1e-3, -4e-3, -8e-3, -8e-3, -2e-3])
    y = chin[1] + drops
    angles = angles_from_chin(y, chin, point, axis, lead=0)
    for a, dy in zip(angles, drops, strict=True):
        assert rotate_about(chin, point, axis, a)[1] - chin[1] == pytest.approx(dy, abs=1e-12)
    assert np.all(angles[1:4] > 0)  # opening angles are positive
    led = angles_from_chin(y, chin, point, axis)  # 33 ms (2 samples) early
    np.testing.assert_allclose(led[:4], angles[2:6])
    np.testing.assert_allclose(led[4:], angles[5])
    bite = angles_from_chin(y, chin, point, axis, bite_block=True)
    np.testing.assert_allclose(bite, led[0])


def test_fast_integrators_follow_the_paper_integrator(seeds_face):
    face = seeds_face
    act = activity(30, OOS=0.8, OOI=0.8, ZYG=0.5, DLI=0.6)
    jaw = np.radians(4.0) * np.sin(np.linspace(0, np.pi, 30)) ** 2
    ref = simulate(face_model(face, SEEDS), act, jaw, integrator="euler")
    for integ in ("rosenbrock", "implicit"):
        sim = simulate(face_model(face, SEEDS), act, jaw, integrator=integ, substeps=8)
        dev = np.linalg.norm(sim.markers - ref.markers, axis=2).max()
        amp = np.linalg.norm(ref.markers - ref.markers[0], axis=2).max()
        assert dev < 0.1 * amp, (integ, dev, amp)


def test_state_restart_is_exact(seeds_face):
    face = seeds_face
    """Advancing 10 frames, or 5 then 5 from the saved state, gives the same state."""
    m = face_model(face, Parameters())
    ph = m.physics
    st = Stepper(m, integrator="euler")
    a = activity(1, DAO=0.7, LLS=0.4)[0]
    s0 = State.at_rest(face.rest_positions, ph.n_muscles)
    s = s0
    for _ in range(10):
        s = st.advance(s, a, 0.02)
    mid = s0
    for _ in range(5):
        mid = st.advance(mid, a, 0.02)
    again = mid
    for _ in range(5):
        again = st.advance(again, a, 0.02)
    np.testing.assert_array_equal(again.positions, s.positions)
    np.testing.assert_array_equal(again.muscle_force, s.muscle_force)
    assert not s.positions.flags.writeable  # states are immutable
    assert s.time == pytest.approx(10 / 60)


def test_solver_objects_step_without_hidden_state(seeds_face):
    """Each integrator's name stands for one solver object; ``step`` of the object gives the
    stepper's state, the same state every time it is called on the same arguments (in any
    order), and leaves its arguments and the solver state as they were."""
    m = face_model(seeds_face, SEEDS)
    ph = m.physics
    a = activity(1, ZYG=0.6, OOS=0.3)[0]
    s0 = State.at_rest(ph.model.rest_positions, ph.n_muscles)
    opened = np.array([0.05, 0.0, 0.0])
    controls = Controls(a, s0.jaw_pose, opened)
    for name, solver, kw in (("euler", ExplicitEuler(m.steps.dt), {}),
                             ("implicit", LinearImplicitEuler(4), {"substeps": 4}),
                             ("rosenbrock", Rosenbrock2(2), {"substeps": 2})):
        stepper = Stepper(m, integrator=name, **kw)
        assert stepper.solver == solver and stepper.integrator == name
        ss = solver.init(ph)
        jaw_before = [np.array(x) for x in ss.jaw]
        s1 = solver.step(ss, s0, controls)
        s2 = solver.step(ss, s1, Controls(a, opened, opened))
        again = solver.step(ss, s0, controls)
        np.testing.assert_array_equal(again.positions, s1.positions)
        np.testing.assert_array_equal(again.muscle_force, s1.muscle_force)
        np.testing.assert_array_equal(stepper.advance(s0, a, 0.05).positions, s1.positions)
        assert s1.jaw_angle == 0.05 and s1.time == pytest.approx(1 / 60)
        assert s2.time == pytest.approx(2 / 60)
        assert np.abs(s1.positions - s0.positions).max() > 1e-5  # the jaw and muscles moved it
        np.testing.assert_array_equal(s0.positions, ph.model.rest_positions)
        for before, after in zip(jaw_before, ss.jaw, strict=True):
            np.testing.assert_array_equal(before, after)


def test_an_option_a_solver_does_not_take_is_an_error(seeds_face):
    """``substeps`` with explicit Euler and a ``dt`` that is not the implicit step are errors
    naming the field; the presets' own defaults are not."""
    m = face_model(seeds_face, SEEDS)
    for kw, field in (({"integrator": "euler", "substeps": 4}, "substeps"),
                      ({"integrator": "implicit", "dt": 1e-3}, "dt"),
                      ({"integrator": "rosenbrock", "substeps": 0}, "substeps"),
                      ({"integrator": "euler", "dt": -1e-3}, "dt"),
                      ({"integrator": Rosenbrock2(2), "substeps": 2}, "substeps"),
                      ({"integrator": "midpoint"}, "integrator")):
        with pytest.raises(InputError) as info:
            Stepper(m, **kw)
        assert info.value.field == field, kw
    for bad in (lambda: ExplicitEuler(0.0), lambda: LinearImplicitEuler(2.5),
                lambda: Rosenbrock2(True)):
        with pytest.raises(InputError):
            bad()
    assert Stepper(m).n_steps == 50  # the preset's euler and 0.33 ms
    assert Stepper(m, integrator="implicit").n_steps == m.steps.substeps
    assert Stepper(m, integrator="implicit", dt=1 / 240).n_steps == 4  # dt repeats h


def test_blow_up_is_caught_with_the_frame(seeds_face):
    face = seeds_face
    with pytest.raises(SimulationBlowUp) as info:
        simulate(face_model(face, SEEDS), activity(20, OOS=1.0), integrator="euler", dt=4e-3)
    assert info.value.frame >= 1
    assert "time step" in str(info.value)


def test_collapse_within_a_frame_is_a_blow_up_with_its_frame(seeds_face):
    face = seeds_face
    from facemech.inverse.experiments import triangle_sequence
    from facemech.params import preset

    act = np.zeros((12, len(MUSCLE_GROUPS)))
    act[:, :8] = triangle_sequence(1)[:, None]
    # the seeds' second damping value is too much for 1-ms explicit steps: nodes meet
    with pytest.raises(SimulationBlowUp, match=r"frame \d+.*time step") as info:
        simulate(face_model(face, preset("pitermann2001")), act, dt=1e-3)
    assert 1 <= info.value.frame < 12


def test_calibrated_preset_moves_experiment1_as_published(seeds_face):
    face = seeds_face
    from facemech.inverse.experiments import synthetic_data
    from facemech.kinematics import stats
    from facemech.params import preset, preset_steps

    base, cal = preset("lucero1999"), preset("calibrated")
    assert cal.k_force == pytest.approx(16 * base.k_force)
    assert cal.with_(k_force=base.k_force) == base.with_(name="calibrated")
    # its fast paths keep the paper's step: 1-ms steps would overshoot by half
    steps, base_steps = preset_steps("calibrated"), preset_steps("lucero1999")
    assert steps.fast_dt == steps.dt and base_steps.fast_dt == 1e-3
    data, _ = synthetic_data(face_model(face, cal))
    right = [i for i, n in enumerate(data.names) if n.startswith("R")]
    # Pitermann & Munhall (2001), Table III: movement 2.024 mm
    assert stats.movement(data.positions[:, right]) * 1e3 == pytest.approx(2.02, rel=0.05)


def test_lucero1999_still_moves_experiment1_as_before(seeds_face):
    """The published constants give the seeds' Experiment 1 the same movement as before the
    anatomical preset existed: 0.22 mm (docs/model.md), at the paper's 0.33-ms step."""
    from facemech.inverse.experiments import synthetic_data
    from facemech.kinematics import stats
    from facemech.params import preset

    data, _ = synthetic_data(face_model(seeds_face, preset("lucero1999")), dt=1 / 3000)
    right = [i for i, n in enumerate(data.names) if n.startswith("R")]
    assert stats.movement(data.positions[:, right]) * 1e3 == pytest.approx(0.223, abs=0.005)
