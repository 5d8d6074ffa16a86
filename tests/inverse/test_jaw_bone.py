"""The jaw from bone points (lower incisor, molar) with its protrusion, articulography roles,
and the controls picked when the markers cannot determine the default set (issue 27, parts 3
and 5)."""

import numpy as np
import pytest

from conftest import run_cli as cli
from facemech import MUSCLE_GROUPS
from facemech.errors import InputError
from facemech.geometry.teeth import lower_incisor_point
from facemech.inverse.control_pick import MIN_NEW_MOTION_MM, pick_controls
from facemech.inverse.invert import SPEECH_CONTROLS
from facemech.inverse.workflow import _at_frame_rate, _bone_gaps_filled
from facemech.io.markers import write_markers
from facemech.io.results import read_results
from facemech.kinematics.roles import bone_points, marker_roles, on_sites
from facemech.markerset import MarkerSet
from facemech.params import preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.solvers.jaw import angles_from_chin, glide_of, move_points
from facemech.solvers.jaw_bone import (
    MAX_BONE_STRETCH,
    eminence_direction,
    jaw_poses_from_bone,
    jaw_poses_from_incisor,
    poses_with_protrusion,
    protrusion_of,
)
from facemech.workflows import simulate as wsim
from facemech.workflows.invert import invert_markers

DEG = np.pi / 180
MOLAR_FROM_INCISOR = np.array([0.0, 0.008, -0.035])  # m: a molar pellet behind the incisors


def speech_jaw(params, frames):
    """A jaw that opens 12 degrees and closes, coming 2.5 mm forward as it closes (the read
    sentence of issue 27) after 1 mm of retraction: (angles rad, protrusions m, poses)."""
    t = np.linspace(0.0, 1.0, frames)
    angle = 12 * DEG * np.sin(np.pi * t) ** 2
    protrusion = -0.001 * np.sin(np.pi * t) + 0.0025 * t ** 2
    return angle, protrusion, poses_with_protrusion(angle, protrusion, params)


def carried(face, point, poses):
    """(frames, 3) m: a mandible point moved through the poses by the stepper's kernel."""
    return np.stack([move_points(point, q, face.hinge_point, face.hinge_axis)[0] for q in poses])


@pytest.mark.parametrize("name", ["anatomical", "lucero1999"])
def test_incisor_gives_angle_glide_and_protrusion_exactly(face, name):
    prm = preset(name)
    angle, protrusion, poses = speech_jaw(prm, 25)
    tip = lower_incisor_point(face)
    inc = carried(face, tip, poses) + [0.001, 0.02, -0.05]  # in the articulograph's own origin
    got = jaw_poses_from_incisor(inc, face, prm)
    np.testing.assert_allclose(got, poses, atol=1e-12)
    np.testing.assert_allclose(protrusion_of(got, prm), protrusion, atol=1e-12)
    # the shift is the coupled glide plus the protrusion, along the eminence (35 degrees down)
    e = eminence_direction(prm)
    assert np.degrees(np.arctan2(-e[0], e[1])) == pytest.approx(np.degrees(prm.glide_slope))
    rate = prm.glide_rate if prm.jaw_kinematics == "glide" else 0.0
    np.testing.assert_allclose(got[:, 1:], np.outer(rate * angle + protrusion, e), atol=1e-15)
    # the kernel carries the model's incisor onto the sensor's displacement
    back = carried(face, tip, got)
    np.testing.assert_allclose(back - back[0], inc - inc[0], atol=1e-12)
    # the angle alone (a chin-style drive from the same point's drop) cannot follow it front
    # to back: the protrusion is lost
    alone = angles_from_chin(inc[:, 1], tip, face.hinge_point, face.hinge_axis, lead=0,
                             glide=glide_of(prm))
    hinge_only = carried(face, tip, poses_with_protrusion(alone, 0.0, prm))
    np.testing.assert_allclose(hinge_only[:, 1] - inc[:, 1], -inc[0, 1] + tip[1], atol=1e-9)
    assert np.abs((hinge_only[:, 2] - tip[2]) - (inc[:, 2] - inc[0, 2])).max() > 0.0015
    # a lead moves the poses earlier, the last held; a bite block holds the first
    led = jaw_poses_from_incisor(inc, face, prm, lead=2)
    np.testing.assert_allclose(led[:-2], got[2:])
    held = jaw_poses_from_incisor(inc, face, prm, bite_block=True)
    np.testing.assert_array_equal(held, np.zeros_like(held))


def test_incisor_and_molar_give_the_whole_planar_pose(face):
    prm = preset("anatomical")
    _, _, poses = speech_jaw(prm, 12)
    poses = poses + np.column_stack([np.zeros(12), np.linspace(0, -0.001, 12), np.zeros(12)])
    tip = lower_incisor_point(face)
    inc = carried(face, tip, poses)
    mol = carried(face, tip + MOLAR_FROM_INCISOR, poses)
    off = np.array([0.0, 0.03, -0.09])
    got = jaw_poses_from_bone(inc + off, face, prm, molar=mol + off, names=("LI", "MM"))
    np.testing.assert_allclose(got, poses, atol=1e-9)
    # the incisor alone cannot see the extra vertical shift: its own track is still exact
    one = jaw_poses_from_bone(inc + off, face, prm)
    np.testing.assert_allclose(carried(face, tip, one), inc, atol=1e-12)
    assert np.abs(one - poses).max() > 1e-4
    # two points that are not on one bone
    slid = mol.copy()
    slid[5:, 2] -= MAX_BONE_STRETCH * 2  # 6 mm further back
    with pytest.raises(InputError) as exc:
        jaw_poses_from_bone(inc, face, prm, molar=slid, names=("LI", "MM"))
    assert exc.value.field == "MM" and "change their distance by 5.9 mm" in exc.value.message


def test_bad_bone_points_name_the_field(face):
    prm = preset("anatomical")
    tip = lower_incisor_point(face)
    inc = np.repeat(tip[None], 5, axis=0)
    gap = inc.copy()
    gap[3, 2] = np.nan
    with pytest.raises(InputError) as exc:
        jaw_poses_from_incisor(gap, face, prm, name="LI", source="s.csv")
    assert exc.value.field == "LI" and "gap at sample 3" in exc.value.message
    far = inc.copy()
    far[2, 1] -= 0.045  # 45 mm of drop: about 40 degrees
    with pytest.raises(InputError) as exc:
        jaw_poses_from_incisor(far, face, prm, name="LI")
    assert exc.value.field == "LI" and "beyond the jaw's range" in exc.value.message
    up = inc.copy()
    up[2, 1] += 0.2  # no rotation reaches it
    with pytest.raises(InputError) as exc:
        jaw_poses_from_incisor(up, face, prm, name="LI")
    assert exc.value.field == "LI" and "no jaw pose" in exc.value.message


def ema_set(positions, roles, **meta):
    """A MarkerSet as an articulography reader returns it (60 Hz, roles, midsagittal)."""
    return MarkerSet(np.array(positions), tuple(roles), 60.0,
                     meta={"roles": roles, "midsagittal": True, "source": "s.ema", **meta})


def test_roles_choose_the_bone_points_and_are_checked(face):
    pos = np.zeros((3, 5, 3))
    pos[:, :, 1:] = np.arange(10).reshape(5, 2) * 0.01
    roles = {"UL": "upper_lip", "LL": "lower_lip", "LI": "lower_incisor", "MM": "molar",
             "TT": "tongue"}
    ms = ema_set(pos, roles)
    assert marker_roles(ms) == roles
    assert bone_points(ms) == ("LI", "MM", True)
    assert bone_points(ms, skin_jaw="UL") == (None, None, False)  # a skin marker asked for
    assert bone_points(ms, incisor="LI", molar="MM") == ("LI", "MM", False)
    for given, option, role in (({"incisor": "LL"}, "jaw-incisor", "lower_lip"),
                                ({"incisor": "MM"}, "jaw-incisor", "molar"),
                                ({"incisor": "LI", "molar": "TT"}, "jaw-molar", "tongue")):
        with pytest.raises(InputError) as exc:  # a sensor whose role is not that bone point
            bone_points(ms, **given)
        assert exc.value.field == option and f"role is {role}" in exc.value.message
    some = {"UL": "upper_lip", "LL": "other"}  # the others have none: taken as named
    unroled = MarkerSet(pos, tuple(roles), 60.0, meta={"roles": some})
    assert bone_points(unroled, incisor="LL", molar="TT") == ("LL", "TT", False)
    with pytest.raises(InputError) as exc:
        bone_points(ms, molar="MM")
    assert exc.value.field == "jaw-molar"
    with pytest.raises(InputError) as exc:
        bone_points(ms, incisor="LI", skin_jaw="UL")
    assert exc.value.field == "jaw-incisor"
    with pytest.raises(InputError) as exc:
        bone_points(ms, incisor="XX")
    assert exc.value.field == "XX"
    with pytest.raises(InputError) as exc:
        marker_roles(ema_set(pos, {**roles, "TT": "teeth"}))
    assert exc.value.field == "TT" and exc.value.source == "s.ema"
    with pytest.raises(InputError) as exc:
        bone_points(ema_set(pos, {**roles, "TT": "lower_incisor"}))
    assert exc.value.field == "TT"
    # a bone point's short gaps are filled (a file written to fill them would lose the roles)
    moving = pos + np.linspace(0, 0.001, 3)[:, None, None]
    long = np.concatenate([moving] * 6)  # 18 frames
    holed = long.copy()
    holed[5:8, 2] = np.nan  # LI: 3 frames, 50 ms
    got, note = _bone_gaps_filled(ema_set(holed, roles), ("LI", "MM"), True)
    assert got.valid.all() and got.filled[5:8, 2].all() and not got.filled[:, 3].any()
    assert note == ["filled 1 gaps of the jaw's bone points (3 frames, each at most 0.1 s) by "
                    "a cubic spline"]
    holed[5:13, 2] = np.nan  # 8 frames, 133 ms: left for the drive to refuse
    assert not _bone_gaps_filled(ema_set(holed, roles), ("LI", "MM"), True)[0].valid.all()
    # a lip that starts in a gap is laid on its site by its first present sample
    late = long.copy()
    late[:2, 0] = np.nan
    on = on_sites(ema_set(late, roles), face, {"UL": 7})
    np.testing.assert_allclose(on.positions[2:, 0] - on.positions[2, 0], late[2:, 0] - late[2, 0])
    np.testing.assert_allclose(on.positions[2, 0], face.rest_positions[7])
    with pytest.raises(InputError) as exc:
        on_sites(ema_set(np.full_like(late, np.nan), roles), face, {"UL": 7})
    assert exc.value.field == "UL"
    # articulography comes at its own rate (here 200 Hz) and is resampled to the model's
    fast = MarkerSet(np.zeros((41, 5, 3)), tuple(roles), 200.0, meta={"roles": roles})
    at60, note = _at_frame_rate(fast, 60.0)
    assert at60.rate == 60.0 and at60.n_frames == 13 and marker_roles(at60) == roles
    assert note == ["articulography at 200 Hz resampled to 60 Hz (low-passed, cubic spline)"]
    plain = MarkerSet(np.zeros((41, 5, 3)), tuple(roles), 200.0)
    assert _at_frame_rate(plain, 60.0) == (plain, [])  # other data must come at the rate
    with pytest.raises(InputError):
        wsim.JawSource(markers="m.csv", chin_marker="R01", incisor="LI")
    with pytest.raises(InputError) as exc:
        wsim.JawSource(markers="m.csv", molar="MM")
    assert exc.value.field == "jaw-molar"
    with pytest.raises(InputError) as exc:
        wsim.JawSource(incisor="LI")
    assert exc.value.field == "jaw-incisor"


def write_csv(path, header, rows):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        fh.writelines(",".join(f"{v:.9g}" for v in r) + "\n" for r in rows)


def test_simulate_cli_drives_the_jaw_from_the_incisor(face, tmp_path, monkeypatch, capsys):
    prm = preset("anatomical")
    frames = 10
    _, _, poses = speech_jaw(prm, frames)
    tip = lower_incisor_point(face)
    off = np.array([0.002, 0.03, -0.09])  # the articulograph's origin is not the model's
    inc = carried(face, tip, poses) + off
    mol = carried(face, tip + MOLAR_FROM_INCISOR, poses) + off
    write_csv(tmp_path / "act.csv", "time,OOS", [(k / 60, 0.0) for k in range(frames)])
    t = np.arange(frames) / 60
    ms = MarkerSet(np.stack([inc, mol], axis=1), ("LI", "MM"), 60.0)
    write_csv(tmp_path / "ema.csv", "# units: mm\ntime,LI_x,LI_y,LI_z,MM_x,MM_y,MM_z",
              [(t[k], *(inc[k] * 1e3), *(mol[k] * 1e3)) for k in range(frames)])
    base = ["simulate", "--activity", tmp_path / "act.csv", "--jaw-chin", tmp_path / "ema.csv"]
    for extra, out in ((("--jaw-incisor", "LI"), "one.nc"),
                       (("--jaw-incisor", "LI", "--jaw-molar", "MM"), "two.nc")):
        code, _, err = cli(monkeypatch, capsys, *base, *extra, "-o", tmp_path / out)
        assert code == 0, err
        ds = read_results(tmp_path / out)
        got = np.column_stack([ds["jaw_angle"].values, ds["jaw_shift"].values])
        np.testing.assert_allclose(got, poses, atol=1e-7)  # no lead: the sensor is on the bone
        np.testing.assert_allclose(ds["time"].values, t)
    # articulography roles: the lower incisor is found without naming it
    roled = ms.with_positions(ms.positions, meta={"roles": {"LI": "lower_incisor",
                                                            "MM": "molar"}})
    monkeypatch.setattr("facemech.io.markers.read_markers", lambda *a, **k: roled)
    jaw, _ = wsim.jaw_series(wsim.JawSource(markers=tmp_path / "ema.csv"), face_model(face, prm), t)
    np.testing.assert_allclose(jaw, poses, atol=1e-12)
    monkeypatch.undo()
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-incisor", "LI", "--chin-marker", "R01",
                       "-o", tmp_path / "x.nc")
    assert code == 2 and "jaw-incisor" in err and len(err.strip().splitlines()) == 1
    code, _, err = cli(monkeypatch, capsys, *base, "--jaw-incisor", "XX", "-o", tmp_path / "x.nc")
    assert code == 2 and "'XX'" in err
    assert not (tmp_path / "x.nc").exists()


@pytest.fixture(scope="module")
def talking(face):
    """A forward run of the default face with lip muscles and a protruding jaw: (poses,
    activity, simulation), 10 frames."""
    prm = preset("anatomical")
    frames = 10
    _, _, poses = speech_jaw(prm, frames)
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    ramp = np.sin(np.linspace(0, np.pi, frames))
    for group, level in (("OOS", 0.3), ("DLI", 0.2), ("LLS", 0.2)):
        act[:, MUSCLE_GROUPS.index(group)] = level * ramp
    return poses, act, simulate(face_model(face), act, poses)


def test_invert_cli_with_an_incisor_keeps_it_out_of_the_skin(face, talking, tmp_path,
                                                            monkeypatch, capsys):
    poses, _, sim = talking
    skin = ["R03", "R05", "R07", "L03", "L05"]
    inc = carried(face, lower_incisor_point(face), poses) + [0.0, 0.004, -0.002]
    pos = np.concatenate([sim.positions[:, [face.markers[n] for n in skin]], inc[:, None]], 1)
    write_markers(tmp_path / "m.csv", MarkerSet(pos, (*skin, "LI"), 60.0), units="mm")
    code, out, err = cli(monkeypatch, capsys, "invert", "--markers", tmp_path / "m.csv",
                         "--jaw-incisor", "LI", "-o", tmp_path / "r.nc")
    assert code == 0, err
    err = " ".join(err.split())  # the notes as one text, whatever the console's width
    assert "bone point LI (lower incisor)" in err and "0-frame lead" in err
    assert "controls:" not in err  # 15 coordinates determine the 9 default controls
    ds = read_results(tmp_path / "r.nc")
    got = np.column_stack([ds["jaw_angle"].values, ds["jaw_shift"].values])
    np.testing.assert_allclose(got, poses, atol=1e-9)
    np.testing.assert_array_equal(ds["markers_used"].values, 5)  # the incisor is not skin
    assert np.median(ds["rms_error"].values) < 1e-4  # measured 0.02 mm
    # explicit controls the markers cannot determine are still refused
    code, _, err = cli(monkeypatch, capsys, "invert", "--markers", tmp_path / "m.csv",
                       "--map", _map(tmp_path, {"R03": "R03"}), "--controls", "speech",
                       "--jaw-incisor", "LI", "-o", tmp_path / "x.nc")
    assert code == 2 and "1 markers give 3 coordinates for 9 controls" in err
    assert not (tmp_path / "x.nc").exists()


def _map(tmp_path, pairs):
    path = tmp_path / "map.csv"
    path.write_text("marker,node\n" + "".join(f"{a},{b}\n" for a, b in pairs.items()))
    return path


def test_three_markers_invert_the_controls_they_determine(face, talking, tmp_path,
                                                         monkeypatch, capsys):
    _, _, sim = talking
    skin = ["R03", "R05", "R07"]
    ms = MarkerSet(sim.positions[:6, [face.markers[n] for n in skin]], tuple(skin), 60.0)
    write_markers(tmp_path / "m.csv", ms, units="mm")
    args = ("invert", "--markers", tmp_path / "m.csv")
    code, _, err = cli(monkeypatch, capsys, *args, "--controls", "speech", "-o", tmp_path / "x.nc")
    assert code == 2 and "3 markers give 9 coordinates for 10 controls" in err
    code, _, err = cli(monkeypatch, capsys, *args, "-o", tmp_path / "r.nc")
    assert code == 0, err
    err = " ".join(err.split())
    assert err.count("note: controls:") == 1
    note = err.split("note: controls:")[1].split("facemech:")[0]
    kept = read_results(tmp_path / "r.nc").attrs["controls"].split(",")
    assert ("3 markers give 9 coordinates for the 12 candidate controls (the default set, and "
            f"orbicularis oris's marginal part where the face has it); kept {len(kept)}: the ") \
        in note
    assert "jaw" in kept and note.split("mm per unit): ")[1].startswith("jaw ")  # taken first
    held = note.split("held at rest: ")[1]
    assert len(kept) <= 9
    assert all(f"{c} " in held for c in {*SPEECH_CONTROLS, "OOSM", "OOIM", "jaw"} - set(kept))
    assert not any(f"{c} " in held for c in kept)


def test_the_pick_follows_the_rank_of_the_responses(face):
    # a synthetic response: the third control repeats the first; the fourth barely moves
    s = np.zeros((2, 3, 4))
    s[0, 1] = [5.0, 0.0, 5.0, 0.0]
    s[1, 2] = [0.0, 3.0, 0.0, 0.5]
    s[1, 1] = [0.0, 1.0, 0.0, 0.2]
    pick = pick_controls(None, [0, 1], ["LLS", "DLI", "OOS", "OOI"],
                         estimate_jaw=False, axes=(1, 2), responses=s.reshape(6, 4))
    assert pick.coordinates == 4
    assert set(pick.order) == {"LLS", "DLI"} and pick.held == ("OOS", "OOI")
    assert pick.new_motion["OOS"] == pytest.approx(0.0, abs=1e-12)
    assert pick.new_motion["OOI"] < MIN_NEW_MOTION_MM
    assert "adds less than 1 mm per unit" in pick.note(2, midsagittal=True)
    with pytest.raises(InputError):
        pick_controls(None, [0, 1], ["OOI"], estimate_jaw=False,
                      responses=np.full((6, 1), 0.1))


def test_midsagittal_articulography_fits_the_lips_with_the_jaw_from_the_incisor(face):
    prm = preset("anatomical")
    frames = 14
    lm = face.landmarks
    nodes = [lm["upper_lip_center"], lm["lower_lip_center"]]
    _, _, poses = speech_jaw(prm, frames)
    from facemech.inverse.workflow import pick_candidates

    pick = pick_controls(face_model(face, prm), nodes, pick_candidates(face), estimate_jaw=False,
                         axes=(1, 2))
    # rank keeps 4 (one per coordinate); the sign step adds what lifts the lower lip
    assert 4 < len(pick.order) <= 6 and not pick.jaw
    assert any("y+" in " ".join(dirs) for _, dirs, _ in pick.for_sign)
    # a twin the picked controls can make: each at a different level, rising and falling
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    ramp = np.sin(np.linspace(0, np.pi, frames))
    for j, group in enumerate(pick.muscles):
        act[:, MUSCLE_GROUPS.index(group)] = (0.1 + 0.05 * j) * ramp
    sim = simulate(face_model(face), act, poses)
    lips = sim.positions[:, nodes]
    inc = carried(face, lower_incisor_point(face), poses)
    ema = np.concatenate([lips, inc[:, None], inc[:, None] + [0, 0.01, -0.05]], axis=1)
    ema = ema + [0.0, 0.04, -0.08]  # the articulograph's origin
    ema[:, :, 0] = 0.0  # midsagittal: x = 0
    roles = {"UL": "upper_lip", "LL": "lower_lip", "LI": "lower_incisor", "TD": "tongue"}
    res = invert_markers(ema_set(ema, roles), options={"tol": 0.01})
    assert res.marker_names == ("UL", "LL")
    np.testing.assert_allclose(res.jaw_pose, poses, atol=1e-9)
    assert set(res.control_names) == set(pick.muscles)
    # two coils: the pick is paced (smooth 1 mm per unit, 22 per second), which costs a twin
    # that needs none: 0.107, 0.206 mm (0.017, 0.044 unpaced)
    assert np.median(res.rms_error) < 1.5e-4 and res.rms_error.max() < 3e-4
    # the model's midline points stay on the midline: x adds nothing to the cost
    assert np.abs(res.markers[:, :, 0] - face.rest_positions[nodes, 0]).max() < 1e-9
    text = "\n".join(res.notes)
    assert "UL (upper_lip) -> node" in text and "(upper_lip_center)" in text
    assert "TD (tongue)" in text and "midsagittal" in text
    assert "2 markers give 4 coordinates (y and z: midsagittal) for the 11 candidate" in text
    assert sum("controls:" in n for n in res.notes) == 1
