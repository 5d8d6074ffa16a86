"""The mandible as a planar rigid body: coupled glide, two-marker drive, results, CLI."""

import json

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import activity
from conftest import run_cli as cli
from facemech.errors import InputError
from facemech.geometry.teeth import lower_incisor_point
from facemech.io.results import read_results, to_dataset, write_results
from facemech.params import GLIDE_RATE, GLIDE_SLOPE, Parameters, preset, read_preset, write_preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.solvers.jaw import (
    condyle_glide,
    jaw_poses,
    jaw_poses_from_points,
    move_points,
)
from facemech.solvers.mandible import JawBundle, place_jaw

DEG = np.pi / 180


def place(face, points, pose, rate=(0.0, 0.0, 0.0)):
    """The face's jaw skull nodes and extra mandible ``points`` (weight 1) placed in ``pose`` by
    the stepper's kernel: (positions of all nodes + points, velocities)."""
    pos = np.concatenate([face.rest_positions, points])
    vel = np.zeros_like(pos)
    extra = np.arange(len(face.rest_positions), len(pos))
    nodes = np.concatenate([face.jaw_nodes, extra]).astype(np.int64)
    weights = np.concatenate([face.jaw_weight, np.ones(len(extra))])
    none = np.zeros((0, 3))
    jaw = JawBundle(hinge_point=np.asarray(face.hinge_point, float),
                    hinge_axis=np.asarray(face.hinge_axis, float), nodes=nodes, weights=weights,
                    rest_from_hinge=pos[nodes] - face.hinge_point, anchor_weights=np.zeros(0),
                    anchor_rest=none, anchor_normal=none)
    jaw_pos, jaw_vel, _ = place_jaw(jaw, np.asarray(pose, float), np.asarray(rate, float))
    pos[nodes] = jaw_pos
    vel[nodes] = jaw_vel
    return pos, vel


def open_until_incisor_drops(face, params, drop):
    """(incisor displacement, mid-mandible displacement) (y, z) m when the jaw opens, under the
    preset's kinematics, until the lower incisor tip has dropped ``drop`` m."""
    inc = lower_incisor_point(face)
    mid = 0.5 * (inc + face.hinge_point)
    pts = np.stack([inc, mid])

    def moved(th):
        pos, _ = place(face, pts, jaw_poses(th, params))
        return pos[-2:] - pts

    th = brentq(lambda t: moved(t)[0, 1] + drop, 0.0, 0.6)
    d = moved(th)
    return d[0, 1:], d[1, 1:]


def test_glide_keeps_the_incisor_over_its_rest_and_drops_the_mandible_body(face):
    glide = preset("anatomical")
    assert glide.jaw_kinematics == "glide"
    inc, mid = open_until_incisor_drops(face, glide, 0.020)
    assert inc[0] == pytest.approx(-0.020, abs=1e-9)
    assert abs(inc[1]) <= 0.005  # fore-aft: measured 3.1 mm back
    assert mid[0] / inc[0] >= 0.55  # measured 0.61
    hinge = glide.with_(jaw_kinematics="hinge")
    inc_h, mid_h = open_until_incisor_drops(face, hinge, 0.020)
    assert abs(inc_h[1]) > 0.010  # 13 mm back
    assert mid_h[0] / inc_h[0] < 0.55  # exactly 0.5: the test can fail


def test_condyle_glide_formula_and_the_seeds_keep_their_hinge():
    sy, sz = condyle_glide(0.2)
    assert sy == pytest.approx(-GLIDE_RATE * 0.2 * np.sin(GLIDE_SLOPE))
    assert sz == pytest.approx(GLIDE_RATE * 0.2 * np.cos(GLIDE_SLOPE))
    assert condyle_glide(-0.1) == (0.0, 0.0)
    np.testing.assert_allclose(np.column_stack(condyle_glide(np.array([-0.1, 0.0, 0.1]), 0.01,
                                                             0.0)),
                               [[0, 0], [0, 0], [0, 0.001]], atol=1e-15)
    for name in ("lucero1999", "pitermann2001", "calibrated"):
        p = preset(name)
        assert p.jaw_kinematics == "hinge"
        np.testing.assert_array_equal(jaw_poses(np.array([0.1, 0.2]), p)[:, 1:], 0.0)


def test_jaw_velocities_are_the_pose_rates(face):
    inc = lower_incisor_point(face)
    pose = np.array([0.2, -0.003, 0.004])
    rate = np.array([1.5, -0.02, 0.03])
    pos, vel = place(face, inc[None], pose, rate)
    h = 1e-6
    ahead, _ = place(face, inc[None], pose + h * rate, rate)
    moving = np.concatenate([face.jaw_nodes, [len(pos) - 1]])
    np.testing.assert_allclose(vel[moving], (ahead[moving] - pos[moving]) / h, atol=1e-6)
    # the stepper's kernel and the helper for single points agree
    np.testing.assert_allclose(pos[-1], move_points(inc, pose, face.hinge_point,
                                                    face.hinge_axis)[0], atol=1e-15)


def synthetic_path(face, frames=10):
    """A rigid planar mandible path unlike the coupled glide: poses (frames, 3) and two mandible
    points (incisor and a molar) moved by it."""
    s = np.sin(np.linspace(0, np.pi / 2, frames))
    poses = np.column_stack([12 * DEG * s, -0.002 * s, 0.0015 * s ** 2])
    inc = lower_incisor_point(face)
    molar = inc + np.array([0.0, 0.006, -0.035])
    p1 = np.stack([move_points(inc, q, face.hinge_point, face.hinge_axis)[0] for q in poses])
    p2 = np.stack([move_points(molar, q, face.hinge_point, face.hinge_axis)[0] for q in poses])
    return poses, p1, p2


@pytest.fixture(scope="module")
def two_marker_run(face):
    poses, p1, p2 = synthetic_path(face)
    got = jaw_poses_from_points(p1, p2, hinge_point=face.hinge_point, lead=0)
    sim = simulate(face_model(face), activity(len(poses)), got, integrator="implicit")
    return poses, p1, p2, got, sim


def test_two_marker_drive_reproduces_a_rigid_planar_path(face, two_marker_run):
    poses, p1, p2, got, sim = two_marker_run
    np.testing.assert_allclose(got, poses, atol=1e-9)
    # the two points carried by the recovered poses follow the synthetic path
    for k in range(len(poses)):
        for p in (p1, p2):
            back = move_points(p[0], got[k], face.hinge_point, face.hinge_axis)[0]
            assert np.linalg.norm(back - p[k]) < 2e-4
    # the simulation moved the mandible (skull nodes of weight 1) along the synthetic path
    np.testing.assert_allclose(sim.jaw_pose, got, atol=1e-15)
    full = sim.model.jaw_nodes[sim.model.jaw_weight == 1.0]
    want = move_points(sim.model.rest_positions[full], poses[-1], face.hinge_point,
                       face.hinge_axis)
    assert np.abs(sim.final_state.positions[full] - want).max() < 2e-4
    np.testing.assert_allclose(sim.final_state.jaw_shift, poses[-1, 1:], atol=1e-9)
    # lead: the poses come two samples early, the last held
    led = jaw_poses_from_points(p1, p2, hinge_point=face.hinge_point)
    np.testing.assert_allclose(led[:-2], got[2:])
    np.testing.assert_allclose(led[-2:], got[[-1, -1]])


def test_pose_series_round_trips_through_the_results_file(tmp_path, two_marker_run):
    _, _, _, got, sim = two_marker_run
    path = write_results(tmp_path / "r.nc", sim)
    ds = read_results(path)
    np.testing.assert_array_equal(ds["jaw_angle"].values, got[:, 0])
    np.testing.assert_array_equal(ds["jaw_shift"].sel(shift_axis="y").values, got[:, 1])
    np.testing.assert_array_equal(ds["jaw_shift"].sel(shift_axis="z").values, got[:, 2])
    assert ds["jaw_shift"].attrs["units"] == "m"
    from facemech.viz.video import jaw_poses_of

    np.testing.assert_array_equal(jaw_poses_of(ds), got)
    # a file written before the jaw's shift existed reads with zeros
    old = to_dataset(sim).drop_vars(["jaw_shift", "shift_axis"])
    old.to_netcdf(tmp_path / "old.nc", engine="h5netcdf")
    ds_old = read_results(tmp_path / "old.nc")
    np.testing.assert_array_equal(ds_old["jaw_shift"].values, np.zeros((len(got), 2)))
    np.testing.assert_array_equal(ds_old["jaw_angle"].values, got[:, 0])


def test_angles_alone_follow_the_presets_kinematics(face, seeds_face):
    angles = np.radians(np.linspace(0.0, 6.0, 5))
    sim = simulate(face_model(face), activity(5), angles, integrator="implicit")
    np.testing.assert_allclose(sim.jaw_shift, np.column_stack(condyle_glide(angles)))
    ds = to_dataset(sim)
    np.testing.assert_allclose(ds["jaw_shift"].values, sim.jaw_shift)
    seeds = simulate(face_model(seeds_face, preset("lucero1999")), activity(3),
                     np.radians([0.0, 2.0, 4.0]))
    np.testing.assert_array_equal(seeds.jaw_shift, 0.0)
    assert seeds.attrs["jaw_kinematics"] == "hinge"


def test_bad_jaw_inputs_name_the_field(face, tmp_path):
    poses, p1, p2 = synthetic_path(face)
    hp = face.hinge_point
    gap = p2.copy()
    gap[3, 1] = np.nan
    with pytest.raises(InputError) as exc:
        jaw_poses_from_points(p1, gap, hinge_point=hp, names=("LI", "MM"))
    assert exc.value.field == "MM" and "sample 3" in exc.value.message
    with pytest.raises(InputError) as exc:
        jaw_poses_from_points(p1, p1 + [0, 0.004, 0.004], hinge_point=hp, names=("LI", "MM"))
    assert exc.value.field == "MM" and "5.7 mm apart" in exc.value.message
    wide = np.array([0.0, 40 * DEG])
    q1 = np.stack([move_points(p1[0], (a, 0, 0), hp, face.hinge_axis)[0] for a in wide])
    q2 = np.stack([move_points(p2[0], (a, 0, 0), hp, face.hinge_axis)[0] for a in wide])
    with pytest.raises(InputError) as exc:
        jaw_poses_from_points(q1, q2, hinge_point=hp)
    assert exc.value.field == "jaw" and "40.0 degrees" in exc.value.message
    far = np.array([0.0, 0.025, 0.0])
    with pytest.raises(InputError) as exc:
        jaw_poses_from_points(np.stack([p1[0], p1[0] + far]), np.stack([p2[0], p2[0] + far]),
                              hinge_point=hp)
    assert exc.value.field == "jaw" and "25.0 mm" in exc.value.message
    with pytest.raises(InputError) as exc:
        Parameters(jaw_kinematics="slide")
    assert exc.value.field == "jaw_kinematics"
    with pytest.raises(InputError) as exc:
        preset("anatomical").with_(glide_rate=-0.01)
    assert exc.value.field == "glide_rate"
    with pytest.raises(InputError) as exc:
        simulate(face_model(face), activity(4), np.zeros((4, 2)))
    assert exc.value.field == "jaw_angle"
    # preset files: the jaw block round-trips and is checked
    write_preset(tmp_path / "p.json", "mine", {"force": 0.9}, jaw_kinematics="hinge",
                 glide_rate=0.02, glide_slope=30 * DEG)
    back = read_preset(tmp_path / "p.json")
    assert (back.jaw_kinematics, back.glide_rate) == ("hinge", pytest.approx(0.02))
    assert back.glide_slope == pytest.approx(30 * DEG)
    assert read_preset(tmp_path / "p.json").k_force == preset("anatomical").k_force * 0.9
    data = json.loads((tmp_path / "p.json").read_text())
    for key, value in (("kinematics", "slide"), ("glide_rate_mm_per_rad", "fast"),
                       ("glide_slope_deg", 120.0)):
        bad = {**data, "jaw": {**data["jaw"], key: value}}
        (tmp_path / "bad.json").write_text(json.dumps(bad))
        with pytest.raises(InputError) as exc:
            read_preset(tmp_path / "bad.json")
        assert exc.value.field == "jaw." + key and exc.value.source.endswith("bad.json")
    old = {k: v for k, v in data.items() if k != "jaw"}  # files without the block: the base's
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert read_preset(tmp_path / "old.json").jaw_kinematics == "glide"


def write_csv(path, header, rows):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        fh.writelines(",".join(f"{v:.9g}" for v in r) + "\n" for r in rows)


def test_cli_jaw_kinematics_and_two_marker_drive(face, tmp_path, monkeypatch, capsys):
    frames = 8
    write_csv(tmp_path / "act.csv", "time,OOS", [(k / 60, 0.0) for k in range(frames)])
    angles = np.radians(np.linspace(0, 8, frames))
    write_csv(tmp_path / "jaw.csv", "time,jaw_angle", zip(np.arange(frames) / 60, angles,
                                                          strict=True))
    base = ["simulate", "--activity", tmp_path / "act.csv"]
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-angle", tmp_path / "jaw.csv",
                       "--jaw-kinematics", "hinge", "-o", tmp_path / "h.nc")
    assert code == 0, err
    ds = read_results(tmp_path / "h.nc")
    np.testing.assert_allclose(ds["jaw_angle"].values, angles, atol=1e-9)
    np.testing.assert_array_equal(ds["jaw_shift"].values, 0.0)
    assert ds.attrs["jaw_kinematics"] == "hinge"
    # two markers (mm) on the mandible: the chin marker R01 and a molar-like point
    poses, _, _ = synthetic_path(face, frames)
    chin = face.rest_positions[face.markers["R01"]]
    molar = chin + np.array([0.0, 0.02, -0.045])
    c = np.stack([move_points(chin, q, face.hinge_point, face.hinge_axis)[0] for q in poses])
    m = np.stack([move_points(molar, q, face.hinge_point, face.hinge_axis)[0] for q in poses])
    offset = np.array([1.0, 2.0, 3.0])  # the recording's origin is not the model's
    rows = [(k / 60, *((c[k] + offset) * 1e3), *((m[k] + offset) * 1e3)) for k in range(frames)]
    write_csv(tmp_path / "jawm.csv", "# units: mm\ntime,R01_x,R01_y,R01_z,MM_x,MM_y,MM_z", rows)
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-chin", tmp_path / "jawm.csv",
                       "--chin-marker", "R01", "--jaw-second-marker", "MM",
                       "-o", tmp_path / "two.nc")
    assert code == 0, err
    ds = read_results(tmp_path / "two.nc")
    got = np.column_stack([ds["jaw_angle"].values, ds["jaw_shift"].values])
    np.testing.assert_allclose(got[:-2], poses[2:], atol=1e-7)  # 33 ms early
    # bad: an unknown kinematics, a second marker without the file
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-kinematics", "slide",
                       "-o", tmp_path / "x.nc")
    assert code == 2 and "jaw_kinematics" in err and "Traceback" not in err
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-second-marker", "MM",
                       "-o", tmp_path / "x.nc")
    assert code == 2 and "jaw-second-marker" in err
    assert not (tmp_path / "x.nc").exists()
