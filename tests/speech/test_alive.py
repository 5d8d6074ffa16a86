"""Issue 29, part 3: a face that is alive. Blinks, gaze shifts and head motion driven by the
voice (facemech.speech.alive), in the movie (the renderer) and in speak's manifest; the
stimulus parameters stay relative to the head."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.speech import alive as A
from facemech.speech.pitch import track_f0

RATE = 16000


def _tone(f0, seconds: float) -> np.ndarray:
    """A voice-like tone (five harmonics) of F0 ``f0`` (Hz, a number or a function of t)."""
    t = np.arange(int(seconds * RATE)) / RATE
    f = np.broadcast_to(f0(t) if callable(f0) else f0, t.shape)
    phase = 2 * np.pi * np.cumsum(f) / RATE
    return sum(0.3 / k * np.sin(k * phase) for k in range(1, 6))


def test_the_f0_tracker_finds_a_tone_and_no_voice_in_silence():
    x = np.concatenate([np.zeros(RATE // 2), _tone(120.0, 1.0)])
    frames = np.arange(0, 1.5, 1 / 60)
    tr = track_f0(x, RATE, frames)
    tone = frames > 0.55
    assert tr.voiced[tone].all() and not tr.voiced[frames < 0.45].any()
    assert np.abs(tr.f0[tone] / 120.0 - 1).max() < 0.02
    with pytest.raises(InputError) as exc:
        track_f0(np.zeros((2, 3)), RATE, frames)
    assert exc.value.field == "audio"


def test_blinks_come_at_the_conversational_rate_with_their_designed_shape():
    """Over an hour, 26/min within 5 % (Bentivoglio et al. 1997: 26 in conversation, 17 at
    rest), no interval under the minimum, and each blink closes fully and lasts 270 ms."""
    rng = np.random.default_rng(1)
    onsets = A.blink_schedule(3600.0, rng)
    rate = len(onsets) / 60.0
    assert rate == pytest.approx(A.BLINK_RATE_PER_MIN, rel=0.05)
    assert np.diff(onsets).min() >= A.BLINK_MIN_INTERVAL_S
    t = np.arange(0, 2.0, 1e-4)
    b = A.blink_closure(t, [0.5])
    shut = t[b > 0]
    length = A.BLINK_CLOSE_S + A.BLINK_HOLD_S + A.BLINK_OPEN_S
    assert shut[0] == pytest.approx(0.5, abs=2e-4)
    assert shut[-1] - shut[0] == pytest.approx(length, abs=3e-4)
    assert b.max() == pytest.approx(1.0)
    # closing faster than opening: half shut sooner after the onset than before the end
    half = t[b >= 0.5]
    assert half[0] - 0.5 < 0.5 + length - half[-1]
    fewer = A.blink_schedule(3600.0, np.random.default_rng(1), rate_per_min=17.0)
    assert len(fewer) / 60 == pytest.approx(17.0, rel=0.05)


def test_gaze_shifts_are_small_and_quick():
    onsets, targets = A.gaze_schedule(600.0, np.random.default_rng(2))
    assert np.diff(onsets).mean() == pytest.approx(A.GAZE_MEAN_INTERVAL_S, rel=0.1)
    assert np.abs(targets).max() <= A.GAZE_MAX_RAD
    # the main sequence: a 5-degree saccade takes 32 ms (21 ms + 2.2 ms/deg)
    assert float(A.saccade_duration(np.radians(5.0))) == pytest.approx(0.032)


def test_the_series_are_deterministic_given_the_seed():
    frames = np.arange(0, 8.0, 1 / 60)
    voice = _tone(110.0, 8.0)
    one = A.liveliness(frames, voice, RATE, A.Liveliness(seed=7))
    two = A.liveliness(frames, voice, RATE, A.Liveliness(seed=7))
    other = A.liveliness(frames, voice, RATE, A.Liveliness(seed=8))
    for name in ("blink", "gaze", "head", "blinks", "gaze_shifts"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    assert not np.array_equal(one.gaze, other.gaze)
    assert json.dumps(one.record()) == json.dumps(two.record())


def test_head_pitch_follows_f0_at_the_designed_lead():
    """A glide (110 Hz +- 4 semitones at 0.6 Hz): the head's pitch correlates with F0 best
    when it leads F0 by HEAD_LEAD_S (one frame either way), r > 0.95."""
    seconds = 5.0  # three whole periods: the median F0 is 110 Hz

    def f0(t):
        return 110.0 * 2 ** (4 / 12 * np.sin(2 * np.pi * 0.6 * t))

    frames = np.arange(0, seconds, 1 / 60)
    got = A.liveliness(frames, _tone(f0, seconds), RATE, A.Liveliness(blinks=False, gaze=False))
    pitch = got.head[:, 0]
    st = 12 * np.log2(f0(frames) / 110.0)
    inner = slice(60, len(frames) - 60)

    def r(lag):  # pitch at t against F0 at t + lag frames
        return np.corrcoef(pitch[inner], np.roll(st, -lag)[inner])[0, 1]

    lags = np.arange(-20, 21)
    best = lags[np.argmax([r(k) for k in lags])]
    assert abs(best - A.HEAD_LEAD_S * 60) <= 1
    assert r(best) > 0.95
    assert got.head_summary["pitch_f0_correlation"] > 0.95
    # 4 semitones above the median: 1.6 degrees up (less 5 % smoothing)
    assert np.degrees(pitch.max()) == pytest.approx(4 * np.degrees(
        A.HEAD_PITCH_PER_SEMITONE_RAD), rel=0.15)
    # yaw and roll wander while the voice sounds, a degree or two
    assert 0.5 < np.degrees(got.head[:, 1].std()) < 3.0


def test_head_motion_spans_the_few_degrees_of_read_speech():
    """A sentence-like voice (F0 falling from 130 to 95 Hz with three accents): the head
    turns over a few degrees, as read speech's head does (Yehia et al. 2002, Munhall et al.
    2004): pitch over 2.5-8 degrees peak to peak, yaw over at least one, none past the
    bound."""
    seconds = 2.5

    def f0(t):
        return 130.0 * 2 ** (-5 / 12 * t / seconds) * 2 ** (
            2.5 / 12 * np.maximum(np.sin(2 * np.pi * 1.2 * t), 0.0))

    frames = np.arange(0, seconds, 1 / 60)
    got = A.liveliness(frames, _tone(f0, seconds), RATE, A.Liveliness(blinks=False, gaze=False))
    span = np.degrees(np.ptp(got.head, axis=0))
    assert 2.5 <= span[0] <= 8.0, span
    assert span[1] >= 1.0, span
    assert np.abs(got.head).max() <= A.HEAD_MAX_RAD


def test_each_item_has_its_own_seed_unless_one_is_given():
    """By default the seed is derived from the item's audio: two items blink and look at
    different times, the same item again at the same; a given seed is used as it is; the
    record says which."""
    frames = np.arange(0, 6.0, 1 / 60)
    a, b = _tone(110.0, 6.0), _tone(118.0, 6.0)
    one, again, other = (A.liveliness(frames, v, RATE) for v in (a, a, b))
    assert one.settings.seed == again.settings.seed == A.item_seed(a, RATE)
    assert one.settings.seed != other.settings.seed
    np.testing.assert_array_equal(one.blinks, again.blinks)
    assert not np.array_equal(one.blinks, other.blinks)
    assert not np.array_equal(one.gaze_shifts, other.gaze_shifts)
    assert one.record()["seed"] == {"value": one.settings.seed,
                                    "source": "derived from the item's audio"}
    fixed = [A.liveliness(frames, v, RATE, A.Liveliness(seed=3)) for v in (a, b)]
    np.testing.assert_array_equal(fixed[0].blinks, fixed[1].blinks)
    assert fixed[0].record()["seed"] == {"value": 3, "source": "given"}


def test_each_switch_turns_its_part_off():
    frames = np.arange(0, 10.0, 1 / 60)
    voice = _tone(120.0, 10.0)
    on = A.liveliness(frames, voice, RATE)
    assert len(on.blinks) and len(on.gaze_shifts) and np.abs(on.head).max() > 0
    for flag, series in (("blinks", "blink"), ("gaze", "gaze"), ("head", "head")):
        off = A.liveliness(frames, voice, RATE, A.Liveliness(**{flag: False}))
        assert not np.any(getattr(off, series)), flag
        assert off.record()["laws"]["settings"][flag] is False
        for other in {"blink", "gaze", "head"} - {series}:  # the others as they were
            np.testing.assert_array_equal(getattr(off, other), getattr(on, other))
    nothing = A.liveliness(frames, voice, RATE, A.Liveliness.off())
    assert nothing.record()["blinks"] == [] and nothing.record()["gaze_shifts"] == []


@pytest.mark.parametrize("field, value", [("blink_rate_per_min", -1.0), ("seed", -3),
                                          ("seed", 1.5)])
def test_bad_settings_name_their_field(field, value):
    with pytest.raises(InputError) as exc:
        A.Liveliness(**{field: value})
    assert exc.value.field == field


@pytest.fixture(scope="module")
def small_renderer(face):
    from facemech.viz.render import RenderOptions
    from facemech.viz.scene import build_scene, look_from_model

    scene = build_scene(look_from_model(face), head=False)
    return RenderOptions(view="frontal", size=(160, 160), supersample=1).renderer(scene)


def test_a_blink_shows_in_the_eyes_and_nowhere_else(small_renderer):
    rend = small_renderer
    scene = rend.scene
    rest = scene.look.rest
    still = rend(rest, 0.0)
    mid = rend(rest, 0.0, 1.0)
    changed = np.argwhere(np.any(mid != still, axis=2))
    assert len(changed) > 20  # the lids cover the eyes
    cam = rend.cameras[0]
    eyes = np.concatenate([cam.project(p.rest) for p in scene.parts
                           if p.motion in ("eye", "lid")])
    margin = 2
    assert changed[:, 1].min() >= eyes[:, 0].min() - margin
    assert changed[:, 1].max() <= eyes[:, 0].max() + margin
    assert changed[:, 0].min() >= eyes[:, 1].min() - margin
    assert changed[:, 0].max() <= eyes[:, 1].max() + margin


def test_head_motion_turns_the_whole_head(small_renderer, tmp_path):
    """A nod moves the chin and the brow in the picture; the movie's frames carry it."""
    from facemech.viz.movie import write_frames
    from facemech.viz.render import FrameMotion, RenderOptions

    rend = small_renderer
    rest = rend.scene.look.rest
    level = rend(rest, 0.0)
    nod = rend(rest, 0.0, 0.0, (0.0, 0.0), (np.radians(4.0), 0.0, 0.0))
    rows = np.flatnonzero(np.any(level != nod, axis=(1, 2)))
    assert rows.max() - rows.min() > 80  # the whole face, top to bottom
    motion = FrameMotion(np.array([0.0, 1.0]), np.zeros((2, 2)),
                         np.array([[0.0, 0.0, 0.0], [0.05, 0.02, 0.0]]))
    frames = write_frames(tmp_path / "f", rend.scene, np.stack([rest, rest]),
                          options=RenderOptions(view="frontal", size=(64, 64), supersample=1),
                          motion=motion)
    import matplotlib.image as mpimg

    a, b = (mpimg.imread(frames / f"frame_0000{k}.png") for k in (0, 1))
    assert not np.array_equal(a, b)
    with pytest.raises(InputError) as exc:
        write_frames(tmp_path / "g", rend.scene, np.stack([rest] * 3), motion=motion)
    assert exc.value.field == "motion"


def test_speak_records_them_and_describe_stays_relative_to_the_head(tmp_path, monkeypatch,
                                                                    capsys):
    """The flags turn each off (the manifest says so); the results and describe's numbers are
    identical with and without blinks, gaze and head motion."""
    from facemech import read_results
    from facemech.workflows.speak import speak

    text = "Bob"
    lively = speak(tmp_path / "on", text, video=False, alive=A.Liveliness(seed=4),
                   plan=False)
    man = lively.manifest["alive"]
    assert man["laws"]["settings"] == {"blinks": True, "gaze": True, "head": True, "seed": 4,
                                       "blink_rate_per_min": A.BLINK_RATE_PER_MIN}
    assert man["head"]["on"] and man["head"]["pitch_peak_rad"] > 0
    assert len(man["head"]["series_rad"]["pitch"]) == lively.manifest["frames"]
    for b in man["blinks"]:
        assert 0 <= b["onset_s"] < lively.alignment.duration and b["duration_s"] == \
            pytest.approx(0.27)
    written = json.loads((tmp_path / "on" / "manifest.json").read_text())
    assert written["alive"]["gaze_shifts"] == man["gaze_shifts"]
    code, _, err = run_cli(monkeypatch, capsys, "speak", text, "-o", tmp_path / "off",
                           "--no-video", "--no-blinks", "--no-gaze", "--no-head-motion",
                           "--no-plan")
    assert code == 0, err
    still = json.loads((tmp_path / "off" / "manifest.json").read_text())
    settings = still["alive"]["laws"]["settings"]
    assert settings == {"blinks": False, "gaze": False, "head": False,
                        "seed": settings["seed"], "blink_rate_per_min": A.BLINK_RATE_PER_MIN}
    assert still["alive"]["seed"]["source"] == "derived from the item's audio"
    assert still["alive"]["blinks"] == [] and still["alive"]["gaze_shifts"] == []
    assert not any(still["alive"]["head"]["series_rad"]["pitch"])
    assert still["stimulus"] == written["stimulus"]
    a, b = (read_results(tmp_path / k / "result.nc") for k in ("on", "off"))
    np.testing.assert_array_equal(a["positions"].values, b["positions"].values)


def test_the_head_pose_turns_as_its_docstring_says():
    """Pitch > 0 raises the face (its forward axis tilts up), yaw > 0 turns it to the subject's
    left (+x), roll > 0 tilts its top to the left; a rotation, applied about the pivot."""
    from facemech.viz.scene import head_rotation

    ahead, up = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    a = np.radians(5.0)
    assert (head_rotation((a, 0, 0)) @ ahead)[1] == pytest.approx(np.sin(a))
    assert (head_rotation((0, a, 0)) @ ahead)[0] == pytest.approx(np.sin(a))
    assert (head_rotation((0, 0, a)) @ up)[0] == pytest.approx(np.sin(a))
    r = head_rotation((0.1, -0.2, 0.05))
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
