"""The control pick completed for sign (issue 27, part 5): activity only pulls, so each marker
coordinate the candidates move both ways must be moved both ways by a kept control; and a twin
of two midsagittal lip pellets (X-ray microbeam .txy, the jaw from the incisor pellet) whose lips
close (OOSM, MEN) and open (DLI, LLS) is re-animated through ``facemech invert``."""

import numpy as np
import pytest

from conftest import run_cli as cli
from facemech import MUSCLE_GROUPS
from facemech.geometry.teeth import lower_incisor_point
from facemech.inverse.combinations import from_json
from facemech.inverse.control_pick import (
    MIN_NEW_MOTION_MM,
    cover_signs,
    pick_controls,
    signed_motion,
)
from facemech.inverse.sensor_fit import fit_from_json
from facemech.inverse.workflow import pick_candidates
from facemech.io.results import read_results
from facemech.params import preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.solvers.jaw import move_points
from facemech.solvers.jaw_bone import poses_with_protrusion

#: synthetic step responses (mm per unit) of two midsagittal markers (rows: m1 x y z, m2 x y z)
#: for seven controls: A raises m1, B lowers m2, C and D move both forward and back (the rank's
#: four); E lowers m1, F raises m2 and G does both at 1.2 mm per unit (each a combination of
#: the four with a negative weight: rank holds them)
NAMES = ("LLS", "DLI", "OOS", "OOI", "DAO", "MEN", "OOSM")  # A..G (any groups: only the names)
S = np.zeros((6, 7))
S[1, 0] = 6.0                    # A: m1 up
S[4, 1] = -8.0                   # B: m2 down
S[2, 2], S[5, 2] = 4.0, 1.5      # C: both forward
S[2, 3], S[5, 3] = -0.5, -3.0    # D: both back, m1 by less than 1 mm per unit
S[1, 4] = -2.0                   # E: m1 down
S[4, 5], S[5, 5] = 1.5, 0.2      # F: m2 up
S[1, 6], S[4, 6] = -1.2, 1.2     # G: m1 down and m2 up


def _pick(face, names=NAMES, s=S):
    return pick_controls(None, [0, 1], list(names), estimate_jaw=False,
                         axes=(1, 2), responses=s, labels=["UL", "LL"])


def test_signed_motion_splits_each_coordinate_and_the_jaw_moves_both_ways():
    s = np.array([[2.0, -3.0], [-1.0, 0.5]])
    m = signed_motion(s, two_way=[1])
    np.testing.assert_array_equal(m, [[2.0, 3.0], [0.0, 3.0], [0.0, 0.5], [1.0, 0.5]])


def test_the_sign_step_covers_each_two_way_coordinate_with_the_fewest_controls(face):
    pick = _pick(face)
    # rank: the four independent controls, strongest first; sign: G alone covers m1 down and
    # m2 up (E and F each cover one of them)
    assert pick.order == ("DLI", "LLS", "OOS", "OOI", "OOSM")
    assert pick.for_sign == (("OOSM", ("UL y-", "LL y+"), (1.2, 1.2)),)
    assert set(pick.held) == {"DAO", "MEN"}
    # m1 z: C moves it forward 4, nothing back by 1 mm per unit (D by 0.5): one way
    assert pick.one_way == (("UL z-", "OOI", 0.5),)
    note = pick.note(2, midsagittal=True)
    assert "OOSM (UL y- 1.2, LL y+ 1.2)" in note and "UL z- (OOI 0.5)" in note
    assert "kept 5: the 4 that move them in the most independent ways" in note
    assert "the markers determine 4 combinations of the kept" in note
    # without G: E and F, each covering one; the larger motion first (E 2.0, F 1.5)
    pick = _pick(face, NAMES[:6], S[:, :6])
    assert [c for c, _, _ in pick.for_sign] == ["DAO", "MEN"]
    assert pick.for_sign[0][1] == ("UL y-",) and pick.for_sign[1][1] == ("LL y+",)
    # without E, F, G: nothing moves m1 down or m2 up: those are one way, nothing is added
    pick = _pick(face, NAMES[:4], S[:, :4])
    assert pick.for_sign == () and {d for d, _, _ in pick.one_way} == {"UL y-", "LL y+", "UL z-"}


def test_a_motion_under_the_threshold_covers_nothing_and_the_limit_holds():
    yz = S[[1, 2, 4, 5]]  # m1 y, m1 z, m2 y, m2 z; signed rows 2 i (up) and 2 i + 1 (down)
    s = yz[:, [0, 1, 2, 3, 5, 6]].copy()  # without E; columns F = 4, G = 5
    s[0, 5] = -0.99 * MIN_NEW_MOTION_MM  # G's m1 down falls under 1 mm per unit
    added, covers, one_way = cover_signs(s, [0, 1, 2, 3])
    assert added == [4] and covers == [[4]]  # F for m2 up (1.5 against G's 1.2)
    assert one_way == [1, 3]  # m1 down and m1 back: no candidate moves them 1 mm per unit
    # no more columns than the limit, whatever is open
    assert cover_signs(yz, [0, 1, 2, 3], limit=4)[0] == []
    assert cover_signs(yz[:, :6], [0, 1, 2, 3], limit=5)[0] == [4]  # E, not F as well


@pytest.fixture(scope="module")
def lips_twin(face):
    """A twin of the lips on the jaw: 24 frames at 60 Hz, the lips closing with the marginal
    orbicularis and mentalis on a jaw open 3 degrees, then opening with DLI and LLS as it
    drops to 8 (frames, groups activity; poses; the lips' and the incisor's positions, m)."""
    prm = preset("anatomical")
    frames = 24
    t = np.arange(frames) / (frames - 1)
    bump = np.clip(np.sin(np.pi * 2 * t), 0.0, None)  # the first half
    late = np.clip(-np.sin(np.pi * 2 * t), 0.0, None)  # the second half
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    for group, level, when in (("OOSM", 0.25, bump), ("MEN", 0.2, bump),
                               ("DLI", 0.15, late), ("LLS", 0.2, late)):
        act[:, MUSCLE_GROUPS.index(group)] = level * when
    angle = np.radians(3.0) * bump + np.radians(8.0) * late
    poses = poses_with_protrusion(angle, np.zeros(frames), prm)
    sim = simulate(face_model(face), act, poses)
    lm = face.landmarks
    lips = sim.positions[:, [lm["upper_lip_center"], lm["lower_lip_center"]]]
    tip = lower_incisor_point(face)
    inc = np.stack([move_points(tip, q, face.hinge_point, face.hinge_axis)[0] for q in poses])
    return act, poses, lips, inc


def _write_txy(path, lips, inc):
    """X-ray microbeam pellets (um, x forward, y up, origin at the upper incisors); the tongue
    pellets still, the molar lost throughout."""
    origin = np.array([0.0, -0.07, -0.01])  # the model point at the microbeam's origin
    rows = []
    for k in range(len(lips)):
        cells = [f"{k / 60.0 * 1e3:.10g}"]
        for p in ("UL", "LL", "T1", "T2", "T3", "T4", "MNI", "MNM"):
            if p == "MNM":
                cells += ["1000000", "1000000"]
                continue
            moving = {"UL": lips[k, 0], "LL": lips[k, 1], "MNI": inc[k]}
            q = moving[p] if p in moving else np.array([0.0, -0.075, -0.025 - 0.006 * int(p[1])])
            rel = (q - origin) * 1e6
            cells += [f"{rel[2]:.4f}", f"{rel[1]:.4f}"]
        rows.append(" ".join(cells))
    path.write_text("\n".join(rows) + "\n")
    return path


def test_lips_closing_and_opening_on_the_jaw_are_reanimated_from_a_txy(face, lips_twin, tmp_path,
                                                                      monkeypatch, capsys):
    act, poses, lips, inc = lips_twin
    # the pick keeps, for each lip, a control that lowers it and one that raises it
    prm = preset("anatomical")
    lm = face.landmarks
    nodes = [lm["upper_lip_center"], lm["lower_lip_center"]]
    pick = pick_controls(face_model(face, prm), nodes, pick_candidates(face), estimate_jaw=False,
                         axes=(1, 2), labels=["UL", "LL"])
    for coord in ("UL y", "LL y"):
        assert f"{coord}+" not in {d for d, _, _ in pick.one_way}
    assert {"LLS", "OOSM", "DLI", "MEN"} <= set(pick.muscles)  # the twin's muscles
    out = tmp_path / "r.nc"
    code, _, err = cli(monkeypatch, capsys, "invert", "--markers",
                       _write_txy(tmp_path / "tp.txy", lips, inc), "-o", out)
    assert code == 0, err
    text = " ".join(err.split())
    assert "driven by the bone point MNI" in text
    assert "MEN (LL y+ " in text  # the sign step's addition, in the note
    ds = read_results(out)
    assert set(ds.attrs["controls"].split(",")) == set(pick.muscles)
    # the pick and the identifiability agree: the combinations determined at the noise floor
    # are led by the controls the pick kept by rank, in its order; the rest is regularised
    rank = [c for c in pick.order if c not in {s for s, _, _ in pick.for_sign}]
    combos = from_json(ds.attrs["combinations"])
    assert [c.lead for c in combos if c.motion_mm >= MIN_NEW_MOTION_MM] == rank
    assert len(rank) == 4 and "not determined by these markers" not in text
    assert "determined by these markers: 4 combinations of the 5 controls" in text
    assert set(ds.attrs["regularised"].split(",")) == set(pick.muscles)  # none alone
    assert ds["combination_activity"].shape == (len(lips), 4)
    # the fit per sensor and axis: in the results, printed by describe, drawn by plot
    fit = {(f.sensor, f.axis): f for f in fit_from_json(ds.attrs["sensor_fit"])}
    assert set(fit) == {("UL", "y"), ("UL", "z"), ("LL", "y"), ("LL", "z")}
    assert all(f.rms_mm < 0.2 and f.corr > 0.9 for f in fit.values()), fit
    code, described, err = cli(monkeypatch, capsys, "describe", out)
    assert code == 0, err
    assert "fit per sensor and axis" in described and "LL: y RMS" in described
    assert "regularised (not determined by the markers alone)" in described
    code, _, err = cli(monkeypatch, capsys, "plot", out, "-o", tmp_path / "p.png")
    assert code == 0 and (tmp_path / "p.png").stat().st_size > 10_000, err
    np.testing.assert_allclose(np.column_stack([ds["jaw_angle"].values,
                                                ds["jaw_shift"].values]), poses, atol=1e-7)
    rms = ds["rms_error"].values
    # the picked fit is paced (smooth 1, inverse.workflow.PICK_PACE): measured median 0.12 mm,
    # max 0.18 mm (0.07 and 0.17 unpaced)
    assert np.median(rms) < 0.15e-3 and rms.max() < 0.25e-3, rms
    # the closing muscles act in the first half, the opening ones in the second
    got = ds["activity"].values
    assert "effort 0.1 mm per unit" in text
    # the activities: OOSM and LLS come back each in its half; MEN and DLI, an opposing pair
    # on the lower lip (5 controls for 4 coordinates), co-contract in the opening (measured,
    # paced: MEN up to 0.37 where it is 0, DLI 0.36 for 0.15; unpaced 0.32 and 0.47; without
    # the sign step's effort weight 0.66 and 0.59)
    half = len(act) // 2
    cols = [MUSCLE_GROUPS.index(g) for g in ("OOSM", "MEN", "DLI", "LLS")]
    err = np.abs(got[:, cols] - act[:, cols]).max(axis=0)
    early, late = got[:half, cols].max(axis=0), got[half:, cols].max(axis=0)
    seen = (np.round(err, 3).tolist(), np.round(early, 2).tolist(), np.round(late, 2).tolist())
    # paced (smooth 1): OOSM within 0.17, LLS 0.11; the pace lags the twin's 0.2-s bumps
    assert err[0] < 0.2 and err[3] < 0.15, seen
    assert early[0] > 0.15 > late[0] and early[1] > 0.15, seen  # closing: OOSM, MEN
    assert late[2] > 0.1 > early[2] and late[3] > 0.1 > early[3], seen  # opening: DLI, LLS
    assert late[1] < 0.5 and late[2] < 0.6, seen  # the co-contraction, drawn back
