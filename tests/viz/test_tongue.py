"""Issue 29 item 2: the tongue tip between the teeth for /θ ð/ and up behind them for
/l t d n s/ (:mod:`facemech.speech.tongue`), in the rendered frames, the results, the viewer and
the exports."""

from __future__ import annotations

import json

import numpy as np
import pytest

import facemech as fm
from conftest import seen_triangles
from facemech.errors import InputError
from facemech.io.results import read_results, results_tongue, to_dataset, with_tongue, write_dataset
from facemech.physics.model import model as face_model
from facemech.speech.alignment import Alignment, Segment
from facemech.speech.coarticulation import controls_from_alignment
from facemech.speech.tongue import FREE, REST_TIP_BEHIND_INCISORS, TARGETS, target_of, tongue_tip
from facemech.viz.camera import view_camera
from facemech.viz.scene import build_scene, look_from_dataset

RATE = 60.0
THETA = (("_", "T", "i:", "_"), (0.0, 0.3, 0.42, 0.7, 1.0))  # eSpeak: T is θ
TA = (("_", "t", "a", "_"), (0.0, 0.3, 0.38, 0.7, 1.0))


def _alignment(labels, edges) -> Alignment:
    phones = tuple(Segment(lab, a, b) for lab, a, b in zip(labels, edges[:-1], edges[1:],
                                                           strict=True))
    return Alignment((), phones, "espeak", edges[-1])


def _frame(t: float) -> int:
    return int(round(t * RATE))


def test_targets_per_class():
    """/θ ð/: the tip past the upper incisors' labial face by 0-5 mm and raised; t d n s z and l:
    raised 8 mm or more, hardly forward; postalveolar: raised, further back; the rest: rest."""
    dental = TARGETS["dental"]
    assert 0.0 < dental.protrusion - REST_TIP_BEHIND_INCISORS <= 0.005
    assert dental.elevation > 0.005
    for cls in ("alveolar", "l"):
        assert TARGETS[cls].elevation >= 0.008 and abs(TARGETS[cls].protrusion) <= 0.002
    assert TARGETS["postalveolar"].protrusion < TARGETS["alveolar"].protrusion
    assert TARGETS["postalveolar"].elevation >= 0.008
    for cls in ("bilabial", "labiodental", "velar", "open", "close_front_spread", "pause"):
        t = target_of(cls)
        assert t.protrusion == 0.0 and t.elevation == 0.0, cls
    assert target_of("open") is FREE


def test_the_dental_puts_the_tip_past_the_incisors_and_the_pauses_rest():
    al = _alignment(*THETA)
    time = np.arange(_frame(1.0) + 1) / RATE
    pose = tongue_tip(al, time)
    assert pose.shape == (len(time), 2)
    mid = pose[_frame(0.36)]
    assert mid[0] > REST_TIP_BEHIND_INCISORS  # past the upper incisors' labial face
    assert mid[1] > 0.005
    for t in (0.15, 0.85):  # the pauses' middles
        assert np.abs(pose[_frame(t)]).max() < 5e-4, t
    np.testing.assert_array_equal(pose[[0, -1]], 0.0)  # tapered to rest at both ends
    # scaled with the articulation's strength; none: rest
    np.testing.assert_allclose(tongue_tip(al, time, strength=0.5), 0.5 * pose, atol=1e-15)
    assert not tongue_tip(al, time, strength=0.0).any()


def test_the_alveolar_raises_the_tip():
    al = _alignment(*TA)
    time = np.arange(_frame(1.0) + 1) / RATE
    pose = tongue_tip(al, time)
    at_t, at_a = pose[_frame(0.34)], pose[_frame(0.54)]
    assert at_t[1] > 0.008 and abs(at_t[0]) < 0.002
    assert at_a[1] < at_t[1]  # the open vowel leaves it, less than /t/ raised it


def test_bad_input_names_the_field():
    al = _alignment(*TA)
    with pytest.raises(InputError) as e:
        tongue_tip(al, np.arange(5.0), strength=-1.0)
    assert e.value.field == "strength"
    with pytest.raises(InputError) as e:
        tongue_tip(al, np.array([0.0, np.nan]))
    assert e.value.field == "time"


@pytest.fixture(scope="module")
def theta():
    """"_ T i: _" on the coarse face: the results dataset with its tongue series, and the
    frame at the /θ/'s middle."""
    al = _alignment(*THETA)
    _, act, jaw = controls_from_alignment(al, frame_rate=RATE)
    sim = fm.simulate(face_model(fm.default_face("default-coarse")), act, jaw)
    ds = with_tongue(to_dataset(sim), tongue_tip(al, sim.time))
    return ds, _frame(0.36)


@pytest.fixture(scope="module")
def scene(theta):
    return build_scene(look_from_dataset(theta[0]))


def _tongue_pixels(scene, verts, cam) -> int:
    """Pixels where the tongue is the nearest surface."""
    z, tid = seen_triangles(scene, verts, cam)
    starts = np.cumsum([0] + [len(q.faces) for q in scene.parts])
    i = [q.name for q in scene.parts].index("tongue")
    return int(((tid >= starts[i]) & (tid < starts[i + 1])).sum())


def test_the_dental_shows_the_tongue_between_the_lips(theta, scene):
    """At the /θ/'s middle the tongue shows in the mouth close-up; the same frame with the
    tongue at rest shows at most its dome's top behind the teeth (the lit mouth's inside)."""
    ds, k = theta
    cam = view_camera("mouth", scene.framing, (160, 160))
    from facemech.viz.video import jaw_poses_of

    skin = ds["positions"].values[k]
    jaw = jaw_poses_of(ds)[k]
    bent, _ = scene.frame(skin, jaw, tongue=results_tongue(ds)[k])
    rest, _ = scene.frame(skin, jaw)
    at_rest = _tongue_pixels(scene, rest, cam)
    assert at_rest < 40
    assert _tongue_pixels(scene, bent, cam) > at_rest + 20


@pytest.mark.slow
def test_results_round_trip_and_files_without_the_series(theta, tmp_path):
    ds, k = theta
    path = write_dataset(tmp_path / "r.nc", ds)
    back = read_results(path)
    np.testing.assert_array_equal(results_tongue(back), results_tongue(ds))
    assert back["tongue_tip"].attrs["units"] == "m"
    assert [str(a) for a in back["tongue_axis"].values] == ["protrusion", "elevation"]
    # a file without it (every command but speak) reads as the tongue at rest, and its still
    # is the one drawn with a resting tongue
    from facemech.viz.video import RenderOptions, motion_with_tongue, still

    old = back.drop_vars(["tongue_tip", "tongue_axis"])
    assert results_tongue(old) is None and motion_with_tongue(None, old) is None
    opt = RenderOptions(view="mouth", size=(96, 96), supersample=1)
    zero = with_tongue(old.copy(), np.zeros((old.sizes["time"], 2)))
    t = float(ds["time"].values[k])
    import matplotlib.image as mpimg

    imgs = {}
    for name, d in (("old", old), ("zero", zero), ("tongue", back)):
        still(d, tmp_path / f"{name}.png", time=t, options=opt)
        imgs[name] = mpimg.imread(tmp_path / f"{name}.png")
    np.testing.assert_array_equal(imgs["old"], imgs["zero"])
    assert np.abs(imgs["tongue"] - imgs["old"]).max() > 0.1


def test_the_viewer_carries_the_series_and_bends_as_the_renderer(theta, scene):
    from facemech.viz.viewer import decode, viewer_data

    ds, k = theta
    data = viewer_data(ds)
    series = decode(data["tongueTip"], "f4", (-1, 2))
    np.testing.assert_allclose(series, results_tongue(ds), atol=1e-7)
    part = next(p for p in data["scene"]["parts"] if p["name"] == "tongue")
    modes = decode(part["modes"], "f4", (part["count"], 2, 3))
    verts, _ = scene.frame(ds["positions"].values[k], 0.0, tongue=series[k])
    rest = scene.parts[[p.name for p in scene.parts].index("tongue")].rest
    np.testing.assert_allclose(rest + series[k] @ modes,
                               verts[part["start"]:part["start"] + part["count"]], atol=1e-6)
    zeros = decode(viewer_data(ds.drop_vars(["tongue_tip", "tongue_axis"]))["tongueTip"], "f4")
    assert not zeros.any()


def test_the_exports_carry_the_series(theta, tmp_path):
    from facemech.io.export import gltf_document, write_mesh_sequence

    ds, k = theta
    doc, _ = gltf_document(ds)
    extra = doc["asset"]["extras"]["tongue_tip"]
    assert extra["units"] == "m" and extra["axes"] == ["protrusion", "elevation"]
    np.testing.assert_allclose(extra["values"], results_tongue(ds), atol=1e-9)
    write_mesh_sequence(ds, tmp_path / "seq", units="mm")
    index = json.loads((tmp_path / "seq" / "index.json").read_text())
    assert index["tongue_tip"]["units"] == "mm"
    np.testing.assert_allclose(index["frames"][k]["tongue_tip"], 1e3 * results_tongue(ds)[k],
                               atol=1e-6)
    old = ds.drop_vars(["tongue_tip", "tongue_axis"])
    assert "tongue_tip" not in gltf_document(old)[0]["asset"]["extras"]


def test_speak_writes_the_series(tmp_path):
    """A recording and its alignment through ``speak``: result.nc holds the tongue series."""
    from facemech.speech.alignment_io import write_textgrid
    from facemech.speech.wav import write_wav
    from facemech.workflows.speak import Recording, speak

    rate = 16000
    noise = 0.1 * np.random.default_rng(0).standard_normal(rate)
    write_wav(tmp_path / "v.wav", noise, rate)
    write_textgrid(tmp_path / "v.TextGrid", _alignment(*THETA))
    spoken = speak(tmp_path / "out", recording=Recording(tmp_path / "v.wav",
                                                         tmp_path / "v.TextGrid"),
                   face="default-coarse", video=False, plan=False)
    back = read_results(spoken.files["results"])
    pose = results_tongue(back)
    assert pose is not None and len(pose) == back.sizes["time"]
    assert pose[_frame(0.36), 0] > REST_TIP_BEHIND_INCISORS


def test_the_manipulations_carry_the_tongue_with_the_jaw(theta):
    """Scaled and frozen with the jaw's region, resampled with the motion (speech/stimuli.py)."""
    from facemech.speech.stimuli import freeze, scale_amplitude, time_scale

    ds, k = theta
    pose = results_tongue(ds)
    np.testing.assert_allclose(results_tongue(scale_amplitude(ds, 0.5, "jaw")), 0.5 * pose)
    np.testing.assert_array_equal(results_tongue(scale_amplitude(ds, 0.5, "lips")), pose)
    assert not results_tongue(freeze(ds, "jaw", "rest")).any()
    held = results_tongue(freeze(ds, "jaw", k))
    np.testing.assert_array_equal(held, np.broadcast_to(pose[k], pose.shape))
    slow = time_scale(ds, 2.0)
    np.testing.assert_allclose(results_tongue(slow)[::2][: len(pose)], pose, atol=1e-12)


@pytest.mark.slow
def test_the_viewer_page_bends_the_tongue_in_headless_chromium(theta, scene, tmp_path):
    """The page's tongue at the /θ/'s middle: its foremost vertex where the renderer puts it."""
    from facemech.viz.video import jaw_poses_of
    from facemech.viz.viewer import write_viewer
    from test_viewer import _probe

    ds, k = theta
    page = write_viewer(ds, tmp_path / "theta.html")
    got = _probe(tmp_path, f"{page.resolve().as_uri()}#frame={k}&probe=1")
    assert got["frame"] == k
    jaw = jaw_poses_of(ds)[k]  # the angle and the condyles' shift, as the page moves the jaw
    verts, _ = scene.frame(ds["positions"].values[k], jaw, tongue=results_tongue(ds)[k])
    i = [p.name for p in scene.parts].index("tongue")
    tongue = verts[scene.offsets[i]:scene.offsets[i + 1]]
    front = tongue[np.argmax(tongue[:, 2])]
    np.testing.assert_allclose(got["tongue"], front, atol=2e-6)
    rest, _ = scene.frame(ds["positions"].values[k], jaw)
    assert front[2] - rest[scene.offsets[i]:scene.offsets[i + 1], 2].max() > 0.008
