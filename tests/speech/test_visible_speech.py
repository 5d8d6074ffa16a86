"""Visible speech per phone (issue 29): the measures on hand-made motion whose answers are known,
and spoken Harvard sentences held to the issue's criteria."""

from __future__ import annotations

import json

import numpy as np
import pytest

from facemech.speech.alignment import Alignment, Segment
from facemech.speech.mouth import midline_lip_pair
from facemech.speech.planning import PLAN_ITERATIONS as DEFAULT_PLAN_ITERATIONS
from facemech.speech.visible_speech import (
    CONTACT_MM,
    REAL_JAW_PEAK_MM_S,
    PhoneMeasure,
    incisor_speed,
    lower_lip_top,
    measure_phones,
    peak_lower_lip_speed,
    summarize,
    upper_incisor_edge,
)

RATE = 100.0  # Hz of the hand-made frames


def alignment(labels, durations, voice="en-us"):
    edges = np.concatenate([[0.1], 0.1 + np.cumsum(durations)])
    phones = tuple(Segment(lab, float(a), float(b))
                   for lab, a, b in zip(labels, edges[:-1], edges[1:], strict=True))
    return Alignment(words=(), phones=phones, notation="espeak", duration=float(edges[-1]) + 0.1,
                     meta={"voice": voice})


def frames(face, al):
    """Time (s) and the epidermis at rest in every frame (frames, n_surface, 3)."""
    t = np.arange(int(round(al.duration * RATE)) + 1) / RATE
    rest = face.rest_positions[: face.n_surface]
    return t, np.repeat(rest[None], len(t), axis=0)


def bump(t, a, b):
    """0 outside [a, b], rising to 1 at its middle (a sine arch)."""
    return np.where((t >= a) & (t <= b), np.sin(np.pi * np.clip((t - a) / (b - a), 0, 1)), 0.0)


def test_lip_gap_aperture_stress_and_bilabial_context(face):
    al = alignment(["m", "'A:", "b", "@", "t"], [0.1, 0.2, 0.1, 0.1, 0.1])
    t, p = frames(face, al)
    _, lo, normal = midline_lip_pair(face)
    gap = 0.2e-3 + 9e-3 * bump(t, 0.2, 0.4)  # 0.2 mm at the bilabials, 9.2 mm in the vowel
    p[:, lo] -= gap[:, None] * normal
    m, a, b, schwa, t_ = measure_phones(al, face, t, p)
    assert [x.group for x in (m, a, b, schwa, t_)] == ["bilabial", "open", "bilabial", None,
                                                     None]
    assert m.lip_gap_mid == pytest.approx(0.2e-3, abs=1e-9)
    assert a.aperture_max == pytest.approx(9.2e-3, abs=1e-6)
    assert a.stress == "primary" and m.stress is None
    assert a.between_bilabials and not schwa.between_bilabials  # "@" lies between b and t
    assert schwa.aperture_max is None and a.forward_max is None
    # the en-gb "0" is rounded, not open; en-us's is open
    assert measure_phones(alignment(["'0"], [0.1], "en-gb"), face, *frames(
        face, alignment(["'0"], [0.1])))[0].group is None
    assert measure_phones(alignment(["'0"], [0.1]), face, *frames(
        face, alignment(["'0"], [0.1])))[0].group == "open"


def test_rounding_takes_the_lip_that_moves_less(face):
    al = alignment(["w", "'u:", "t"], [0.1, 0.2, 0.1])
    t, p = frames(face, al)
    lm = face.landmarks
    p[:, lm["upper_lip_center"], 2] += 3e-3 * bump(t, 0.2, 0.4)
    p[:, lm["lower_lip_center"], 2] += 2.5e-3 * bump(t, 0.2, 0.4)
    w, u, t_ = measure_phones(al, face, t, p)
    assert (w.group, u.group, t_.group) == ("rounded", "rounded", None)
    assert u.forward_max == pytest.approx(2.5e-3, abs=1e-9)
    assert u.upper_forward == pytest.approx(3e-3, abs=1e-9)
    assert u.lower_forward == pytest.approx(2.5e-3, abs=1e-9)
    assert w.forward_max < 2.5e-3  # w ends where the bump starts: less forward


def test_labiodental_contact_is_the_lower_lips_top_at_the_upper_incisors(face):
    edge = upper_incisor_edge(face)
    rest = face.rest_positions
    st = rest[face.landmarks["stomion"]]
    assert edge[1] < st[1] and edge[2] < st[2]  # below the lip line, behind the lips
    _, lo, _ = midline_lip_pair(face)
    front, back = lower_lip_top(face, rest[: face.n_surface])
    np.testing.assert_allclose(front, rest[lo])
    np.testing.assert_allclose(back, rest[lo + 2 * face.n_surface])  # the deep twin
    al = alignment(["f", "'i:", "v"], [0.1, 0.1, 0.1])
    t, p = frames(face, al)
    # during /v/ only: the lip's edge 2 mm in front of and 0.3 mm above the incisors' edge
    inside = (t >= 0.3) & (t <= 0.4)
    p[inside, lo] = edge + np.array([0.0, 0.3e-3, 2e-3])
    f, i, v = measure_phones(al, face, t, p)

    def brute(a):  # the nearest of many points along the lip's top
        s = np.linspace(0.0, 1.0, 200001)[:, None]
        top = a + s * (rest[lo + 2 * face.n_surface] - rest[lo])
        return np.linalg.norm(top - edge, axis=1).min()

    assert v.incisor_distance == pytest.approx(brute(edge + [0.0, 0.3e-3, 2e-3]), abs=1e-8)
    assert v.incisor_distance < 1e-3 * CONTACT_MM
    assert f.incisor_distance == pytest.approx(brute(rest[lo]), abs=1e-8)
    assert f.incisor_distance > 2e-3  # at rest the lip's top lies well above the edge
    assert i.incisor_distance is None


def test_peak_lower_lip_speed(face):
    t = np.arange(61) / 60.0
    p = np.repeat(face.rest_positions[None, : face.n_surface], len(t), axis=0)
    k = face.landmarks["lower_lip_center"]
    # down 0.12 m/s for 10 frames, then back up at 0.06 m/s
    y = np.interp(t, [0.0, 0.2, 0.35, 0.55, 1.0], [0.0, 0.0, -0.018, -0.006, -0.006])
    p[:, k, 1] += y
    assert peak_lower_lip_speed(t, p, face) == pytest.approx(0.12, rel=1e-9)


def row(group, stress="primary", **values):
    base = dict(label="x", start=0.0, end=0.1, classes=("open",), stress=stress, group=group,
                between_bilabials=False, lip_gap_mid=0.0, lips_forward_mid=0.0)
    return PhoneMeasure(**{**base, **values})


def test_the_incisors_speed_on_a_hinge_and_with_the_glide(face):
    """:func:`incisor_speed`: the jaw turning at 60 degrees/s about its hinge moves the lower
    incisor tip at 60 degrees/s times its distance from the hinge axis; a glide of the condyles
    adds its own speed, and a still jaw gives 0."""
    from facemech.geometry.teeth import lower_incisor_point

    t = np.arange(31) / 60.0
    poses = np.column_stack([np.radians(60.0) * t, np.zeros(31), np.zeros(31)])
    tip = lower_incisor_point(face)
    axis = face.hinge_axis / np.linalg.norm(face.hinge_axis)
    r = tip - face.hinge_point
    radius = np.linalg.norm(r - np.dot(r, axis) * axis)
    v = incisor_speed(t, poses, face)
    assert 0.05 < radius < 0.12  # the lower incisor, 5-12 cm from the hinge
    np.testing.assert_allclose(v, np.radians(60.0) * radius, rtol=1e-3)
    # a glide straight forward at 30 mm/s on a still angle: the tip moves at 30 mm/s
    glide = np.column_stack([np.zeros(31), np.zeros(31), 0.03 * t])
    np.testing.assert_allclose(incisor_speed(t, glide, face), 0.03, rtol=1e-6)
    assert incisor_speed(t, np.zeros((31, 3)), face).max() < 1e-12
    assert REAL_JAW_PEAK_MM_S == 186.0  # issue 27's recordings: 58-186 mm/s


def test_summary_applies_the_issues_criteria():
    bil = [row("bilabial", lip_gap_mid=0.1e-3)] * 19 + [row("bilabial", lip_gap_mid=0.8e-3)]
    s = summarize(bil)["bilabial"]
    assert (s["n"], s["share_passing"], s["met"], s["worst"]["value_mm"]) == (20, 0.95, True, 0.8)
    s = summarize(bil[1:] + [row("bilabial", lip_gap_mid=1.2e-3)])["bilabial"]
    assert not s["met"]  # 95 % pass, but one is above 1 mm
    opn = [row("open", aperture_max=v * 1e-3) for v in (12, 11, 10.5, 9, 7)]
    s = summarize(opn + [row("open", stress=None, aperture_max=1e-3)])["open"]
    assert (s["n"], s["share_passing"], s["median_mm"], s["met"]) == (5, 0.8, 10.5, False)
    s = summarize([row("rounded", forward_max=2.1e-3, upper_forward=3e-3,
                       lower_forward=2.1e-3)] * 9 +
                  [row("rounded", forward_max=1e-3, upper_forward=1e-3, lower_forward=2e-3)])
    assert s["rounded"]["met"] and s["rounded"]["share_passing"] == 0.9
    s = summarize([row("labiodental", incisor_distance=0.5e-3)], [0.09, 0.2])
    assert s["labiodental"]["met"] and not s["speed"]["met"]
    assert s["speed"]["min_mm_s"] == 90.0 and s["speed"]["share_passing"] == 0.5


# ---- spoken sentences ---------------------------------------------------------------------

#: three Harvard sentences (IEEE 1969, list 1) with every group of the issue
SENTENCES = ("The juice of lemons makes fine punch.",
             "Glue the sheet to the dark blue background.",
             "Four hours of steady work faced us.")
#: two words with an open vowel between bilabials, in benchmarks/sentences.py's carrier phrase
BETWEEN = ("Say pop again.", "Say map again.")
#: the face ``speak`` uses, the one the issue's criteria are claimed on (the coarse face until
#: 2026-12-07: its shares are within a few points of the default face's on the 20 sentences of
#: benchmarks/sentences.py, but with the planner's present gains the /m/ of "map" stays 0.55 mm
#: apart there at 8 iterations; the fixture takes about 25 s on the default face)
SENTENCE_FACE = "default"
#: the planner's iterations here: speak's default (8; 4 until 2026-12-07: on the coarse face the
#: /a/ of "map" was a knife's edge between its aperture and its /m/, 8.3 to 10.6 mm open with
#: the /m/ 0.3 to 1.4 mm apart as the planner's gains moved)
PLAN_ITERATIONS = DEFAULT_PLAN_ITERATIONS


@pytest.fixture(scope="module")
def spoken_summary(tmp_path_factory):
    """The sentences said as ``facemech speak`` says them (eSpeak en-us at its default 175
    words per minute, planned with :data:`PLAN_ITERATIONS`, no movie, no liveliness), as
    benchmarks/sentences.py does."""
    from facemech.speech.alive import Liveliness
    from facemech.workflows.speak import speak

    phones, speeds, between = [], [], []
    for k, text in enumerate(SENTENCES + BETWEEN):
        sp = speak(tmp_path_factory.mktemp(f"s{k}"), text, rate_wpm=175, face=SENTENCE_FACE,
                   plan=PLAN_ITERATIONS, video=False, alive=Liveliness.off())
        sim = sp.simulation
        ph = measure_phones(sp.alignment, sim.model, sim.time, sim.positions,
                            jaw_pose=sim.jaw_pose)
        if text in BETWEEN:
            between += ph
            continue
        phones += ph
        speeds.append(peak_lower_lip_speed(sim.time, sim.positions, sim.model))
    out = summarize(phones, speeds)
    out["between_bilabials"] = summarize(between)["open"]["between_bilabials"]
    # the bilabials of the same words: the open vowel between them must not open them
    out["their_bilabials"] = summarize([p for p in between if p.group == "bilabial"])["bilabial"]
    print(json.dumps(out))  # the numbers the marks below quote (pytest -s shows them)
    return out


@pytest.mark.slow
def test_sentences_cover_every_group(spoken_summary):
    for group in ("bilabial", "open", "rounded", "labiodental", "speed", "between_bilabials",
                  "their_bilabials"):
        assert spoken_summary[group]["n"] >= 2, group


@pytest.mark.parametrize("group", [
    "bilabial",  # 5 of 5 at <= 0.5 mm, the widest 0.05 mm (2026-12-07, the jaw at 180 mm/s)
    "open",  # 4 of 4, median 13.4 mm, the smallest 11.9
    # the open vowels of 'pop' and 'map': 8.06 and 6.45 mm since the jaw is held under the
    # fastest real jaw (180 mm/s) and the seals are planned for 70 ms (11.2 and 10.4 mm with
    # the jaw at 250 mm/s and no seal target): not met (docs/visible-speech.md)
    pytest.param("between_bilabials", marks=pytest.mark.xfail(
        strict=True, reason="the open vowel of 'map' 6.45 mm between its seals")),
    "rounded",  # 4 of 4 at >= 2 mm, median 3.2
    # the lower lip's visible edge within 1 mm of the upper incisors' edge (5 of 5, the
    # farthest 0.93 mm) with the lower incisors hidden (4 of 5): 80 %, not the 90 %
    pytest.param("labiodental_front", marks=pytest.mark.xfail(
        strict=True, reason="one /f v/ of five shows its lower incisors")),
    "closure",  # every bilabial sealed >= 50 ms (5 of 5, the shortest 97 ms)
    "speed",  # 113-188 mm/s
    # the /m/ of 'map' 1.4 mm apart at its middle (its seal off its middle); 0.45 mm before
    pytest.param("their_bilabials", marks=pytest.mark.xfail(
        strict=True, reason="the /m/ of 'map' 1.4 mm apart at its middle")),
    # rounded phones from the front: the lips part over their whole width (aspect 0.07-0.09
    # at the narrowed mouth's width); no held target of benchmarks/rounding.py is round with
    # the lips forward: the physics', not the plan's, to make
    pytest.param("round_opening", marks=pytest.mark.xfail(
        strict=True, reason="no round opening: a slot over the teeth")),
])
@pytest.mark.slow
def test_sentences_meet_the_issues_criteria(spoken_summary, group):
    assert spoken_summary[group]["met"], spoken_summary[group]


def test_a_bilabials_closure_is_how_long_its_lips_stay_sealed(face):
    """The seal's run about the most closed frame, its ends interpolated where the gap
    crosses 0.5 mm: a 1-mm gap everywhere but a sealed 80 ms about the /m/ gives 80 ms; a
    seal that never reaches 0.5 mm gives 0; summarize counts the share >= 50 ms."""
    from facemech.speech.visible_speech import CLOSURE_MIN_S, closure_duration

    t = np.arange(0, 0.6, 0.01)
    gap = np.full(len(t), 2e-3)
    gap[(t > 0.26 - 1e-9) & (t < 0.34 + 1e-9)] = 0.0  # sealed from 0.26 to 0.34 s
    gap[np.isclose(t, 0.25)] = gap[np.isclose(t, 0.35)] = 1e-3
    # crossings: halfway between 0.25 (1 mm) and 0.26 (0): 0.255; likewise 0.345
    assert closure_duration(t, gap, 0.27, 0.33) == pytest.approx(0.09, abs=1e-9)
    assert closure_duration(t, np.full(len(t), 0.6e-3), 0.27, 0.33) == 0.0
    al = alignment(["'a", "m", "'a"], [0.15, 0.08, 0.15])
    tt, p = frames(face, al)
    _, lo, normal = midline_lip_pair(face)
    mid = 0.1 + 0.15 + 0.04
    for held, expect in ((0.08, True), (0.03, False)):
        g = np.where(np.abs(tt - mid) <= held / 2 + 1e-9, 0.0, 3e-3)
        q = p.copy()
        q[:, lo] -= g[:, None] * normal
        ms = measure_phones(al, face, tt, q)
        bil = [m for m in ms if m.group == "bilabial"][0]
        n = int(np.sum(g == 0.0))  # sealed frames; each end crosses 0.5 mm 1/6 frame out
        assert bil.closure == pytest.approx((n - 1 + 2 / 6) / RATE, abs=1e-9)
        assert summarize(ms)["closure"]["met"] is expect
        assert (bil.closure >= CLOSURE_MIN_S) is expect


def test_a_rounded_openings_shape_is_its_height_over_its_width(face):
    """The lower lip's twins moved down 6 mm within 6 mm of the midline, tapering to 0 at
    9 mm: the opening (> 0.5 mm apart) is 2 x 8.5 mm wide, 6 mm high at the middle; sealed
    lips have no opening; a narrowed mouth's opening is as narrow as the lips are now, and its
    width ratio is its corner distance over rest."""
    from facemech.speech.mouth import opening_width

    rest = face.rest_positions[: face.n_surface]
    up, lo = face.lip_pairs.T
    skin = np.nonzero(up < face.n_surface)[0]
    x0 = rest[face.landmarks["stomion"], 0]
    p = rest.copy()
    assert opening_width(face, p) == 0.0
    x = np.abs(rest[lo[skin], 0] - x0)
    depth = 6e-3 * np.clip((9e-3 - x) / 3e-3, 0.0, 1.0)
    normals = np.asarray(face.lip_normals)[skin]
    p[lo[skin]] -= depth[:, None] * normals
    w = opening_width(face, p)
    assert w == pytest.approx(2 * (9e-3 - 0.5e-3 / 6e-3 * 3e-3), abs=0.6e-3)
    al = alignment(["u:"], [0.2])
    t, q = frames(face, al)
    q[:] = p
    r = measure_phones(al, face, t, q)[0]
    assert r.opening_aspect == pytest.approx(6e-3 / w, rel=0.02)
    assert r.width_ratio == pytest.approx(1.0)
    # the same opening with the mouth drawn in to 60 % of its width (rounding): the opening
    # is measured where the lips are, 60 % as wide, so its shape is rounder
    narrow = p.copy()
    narrow[:, 0] = x0 + 0.6 * (p[:, 0] - x0)
    assert opening_width(face, narrow) == pytest.approx(0.6 * w, rel=1e-6)
    q[:] = narrow
    r = measure_phones(al, face, t, q)[0]
    assert r.opening_aspect == pytest.approx(6e-3 / (0.6 * w), rel=0.02)
    assert r.width_ratio == pytest.approx(0.6, abs=0.01)


def test_the_teeth_shown_between_the_lips_and_the_lips_edge_at_the_incisors(face):
    """Closed lips show no teeth and the lower lip's edge stands 3 mm above the upper incisors'
    edge (at the stomion); its edge moved down 3 mm shows 3 mm of the upper incisors, the lower
    ones still behind them; the jaw opened 3 degrees and the lip 6 mm down bares the lower
    incisors under the upper ones."""
    from facemech.speech.visible_speech import teeth_shown
    from facemech.viz.dentition import UPPER_EDGE_BELOW_STOMION

    rest = face.rest_positions[: face.n_surface].copy()
    assert teeth_shown(face, rest, np.zeros(3)) == (0.0, 0.0)
    _, lo, _ = midline_lip_pair(face)
    p = rest.copy()
    p[lo, 1] -= UPPER_EDGE_BELOW_STOMION
    up, low = teeth_shown(face, p, np.zeros(3))
    assert up == pytest.approx(UPPER_EDGE_BELOW_STOMION, abs=1e-9) and low == 0.0
    p[lo, 1] -= UPPER_EDGE_BELOW_STOMION
    up, low = teeth_shown(face, p, np.array([np.radians(3.0), 0.0, 0.0]))
    assert up == pytest.approx(UPPER_EDGE_BELOW_STOMION, abs=1e-9) and low > 1e-3
    al = alignment(["f"], [0.1])
    t, q = frames(face, al)
    m = measure_phones(al, face, t, q, jaw_pose=np.zeros((len(t), 3)))[0]
    assert m.lip_edge == pytest.approx(UPPER_EDGE_BELOW_STOMION, abs=1e-4)
    assert m.upper_teeth == 0.0 and m.lower_teeth == 0.0
    row = summarize([m])["labiodental_front"]
    assert row["share_passing"] == 0.0 and not row["met"]
