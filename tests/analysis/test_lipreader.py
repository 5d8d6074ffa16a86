"""Issue 29, "a machine lip-reader sees it": standard face trackers on the rendered frontal movie.

The sentence is spoken by :func:`facemech.workflows.speak.speak` on the built-in face
``default`` (blinks, gaze and head motion off) and its frontal frames are rendered at 300x360
pixels: the frontal camera frames the head by the frame's height, so these are the 640x360
movie's frames with the background at the sides cropped (the face about 190 px across, found
by the detector without upsampling). The whole file takes about 40 s on two cores.

Two trackers read it. MediaPipe's face mesh (468 points, run with LiteRT as MediaPipe tracks a
video: :mod:`facemech.io.face_mesh`) meets the issue's r >= 0.9 on this sentence (0.939; 0.905-
0.972 over six Harvard sentences at 640x360, docs/lipreader.md). dlib's 68-point predictor meets it
on this sentence too since the built-in head's drawn shape (its mouth as wide as Farkas' norm and
the folds, :mod:`facemech.viz.shape`; 0.850 without it): 0.918 at 300x360, 0.916 at 640x360,
a margin of 0.02 (0.57-0.92 over the six before it). dlib is also held to the face in every
frame, the points on the mouth, an r near the measured one.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from facemech.analysis.lipreader import (
    compare,
    frontal_frames,
    inner_lip_distance,
    model_aperture,
    read_lips,
)
from facemech.errors import InputError

#: a Harvard sentence (IEEE 1969, list 1), about 2 s at eSpeak's default rate
TEXT = "Rice is often served in round bowls."
#: the issue's least Pearson r between the tracker's inner-lip distance and the model's aperture
R_ISSUE = 0.9
#: r measured on this sentence at 300x360 as ``speak`` plans it by default (0.918 since the
#: built-in head's drawn shape, :mod:`facemech.viz.shape`; 0.815 under the
#: measured muscle laws, 2026-11-29; 0.849 since /ɪ/ is
#: a lax vowel of its own, not /i/, 2026-11-28: its lips spread half as much; 0.707 with the
#: /i/ target's ZYG and RIS at 0.6, not 1.0; 0.632 before, after the labiodental's retune;
#: 0.669 before that; benchmarks/lipreader.py at 640x360: docs/lipreader.md)
R_MEASURED = 0.92
#: the least r this test holds the tracker to: the measured r less 0.13, about 1.5 times the most
#: a change of frame size moved r on the sentences tried (0.09)
R_FLOOR = 0.79
#: the least share of frames in which the face is found (measured: every frame)
FOUND_MIN = 0.95
#: r of the face mesh on this sentence at 300x360 (measured 0.939, 2026-11-29; 0.929 with the
#: region from the detector's box in every frame instead of from the previous frame's points;
#: 0.936-0.940 with LiteRT's other kernels, which another CPU may pick)
R_MESH_MEASURED = 0.939


@pytest.fixture(scope="module")
def detector():
    pytest.importorskip("dlib")
    pytest.importorskip("face_recognition_models")
    from facemech.io.photo import DlibDetector

    return DlibDetector()


@pytest.fixture(scope="module")
def spoken(tmp_path_factory):
    """(the sentence's frontal frames, the model's aperture m, its results file)."""
    from facemech.speech.alive import Liveliness
    from facemech.workflows.speak import speak

    folder = tmp_path_factory.mktemp("lipreader")
    ds = speak(folder, TEXT, face="default", video=False, alive=Liveliness.off()).dataset
    aperture = model_aperture(ds)
    assert len(aperture) == ds.sizes["time"]
    return list(frontal_frames(ds, size=(360, 300))), aperture, folder / "result.nc"


@pytest.fixture(scope="module")
def read(spoken, detector):
    """(dlib's lip reading, the model's aperture m, their agreement) of the sentence."""
    frames, aperture, _ = spoken
    reading = read_lips(frames, detector=detector)
    return reading, aperture, compare(reading.distance, aperture)


@pytest.fixture(scope="module")
def mesh_read(spoken, detector):
    """(the face mesh's lip reading, the model's aperture m, their agreement)."""
    pytest.importorskip("ai_edge_litert")
    frames, aperture, _ = spoken
    reading = read_lips(frames, tracker="mesh")
    return reading, aperture, compare(reading.distance, aperture)


@pytest.mark.slow
def test_the_tracker_finds_the_face_and_sees_the_mouth_open(read):
    reading, aperture, agreement = read
    assert agreement.frames == len(aperture) == len(reading.distance)
    assert agreement.found_fraction >= FOUND_MIN, agreement
    # the mouth opens in the sentence (about a centimetre), and wider open reads wider
    assert aperture.max() > 5e-3
    assert agreement.slope > 0
    assert agreement.r >= R_FLOOR, agreement
    # the points sit on the mouth: the inner lips' corners (60, 64) within the outer lips'
    # (48, 54), the inner lips between the nose's base (33) and the chin (8)
    pts = reading.points[reading.found]
    assert np.all(pts[:, 60, 0] > pts[:, 48, 0] - 2) and np.all(pts[:, 64, 0] < pts[:, 54, 0] + 2)
    assert np.all(pts[:, 62, 1] > pts[:, 33, 1]) and np.all(pts[:, 66, 1] < pts[:, 8, 1])


@pytest.mark.slow
def test_the_face_mesh_reads_the_aperture_as_the_issue_asks(mesh_read):
    """The issue's r >= 0.9 with MediaPipe's face mesh (measured :data:`R_MESH_MEASURED`), the
    face in every frame, wider open read wider, and the inner-lip points between the outer
    lips' (mesh points 0 and 17, the outer midline) in every frame."""
    reading, aperture, agreement = mesh_read
    assert agreement.found_fraction >= FOUND_MIN, agreement
    assert agreement.slope > 0
    assert agreement.r >= R_ISSUE, agreement
    pts = reading.points[reading.found]
    assert reading.points.shape[1:] == (468, 2)
    assert np.all(pts[:, 13, 1] >= pts[:, 0, 1] - 1) and np.all(pts[:, 14, 1] <= pts[:, 17, 1] + 1)


@pytest.mark.slow
def test_lipread_on_the_command_line_gives_the_same_reading(spoken, mesh_read, tmp_path,
                                                            monkeypatch, capsys):
    """``facemech lipread RESULT`` draws the same frames and reads the same r as the Python
    API; ``-o`` writes the series per frame; a bad tracker is one line, exit 2, nothing
    written."""
    import json

    from conftest import run_cli

    _, aperture, result = spoken
    reading, _, agreement = mesh_read
    table = tmp_path / "lips.csv"
    code, out, err = run_cli(monkeypatch, capsys, "lipread", result, "--size", "300x360",
                             "-o", table, "--json")
    assert code == 0, err
    got = json.loads(out)
    assert got["tracker"] == "mesh" and got["frames"] == len(aperture)
    assert got["r"] == pytest.approx(agreement.r, abs=1e-9) and got["r"] >= R_ISSUE
    rows = np.loadtxt(table, delimiter=",", skiprows=1)
    assert rows.shape == (len(aperture), 3)
    np.testing.assert_allclose(rows[:, 1], aperture * 1e3, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(rows[:, 2], reading.distance, rtol=1e-5, atol=1e-4)
    code, out, err = run_cli(monkeypatch, capsys, "lipread", result, "--tracker", "openface",
                             "-o", tmp_path / "no.csv")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--tracker" in err
    assert not (tmp_path / "no.csv").exists()


@pytest.mark.slow
def test_dlibs_inner_lip_distance_correlates_with_the_aperture_as_the_issue_asks(read):
    assert read[2].r >= R_ISSUE, read[2]


def test_compare_gives_pearson_r_over_the_frames_with_a_face():
    # the frames without a face (2 and 5) hold apertures that would spoil the correlation
    aperture = np.array([1.0, 2.0, 9.0, 3.0, 4.0, 9.0, 5.0]) * 1e-3
    distance = np.array([2.0, 1.0, np.nan, 4.0, 3.0, np.nan, 5.0])
    # over the others: deviations (-2, -1, 0, 1, 2) mm against (-1, -2, 1, 0, 2) px; their
    # products sum to 8, the squares to 10 and 10: r = 0.8, slope 0.8 px/mm, 3 - 0.8 * 3 px at 0
    got = compare(distance, aperture)
    assert got.found == 5 and got.frames == 7
    assert got.found_fraction == pytest.approx(5 / 7)
    assert got.r == pytest.approx(0.8, abs=1e-12)
    assert got.slope == pytest.approx(800.0) and got.intercept == pytest.approx(0.6)
    # a line: r = 1, its slope (px per m) and intercept (px) recovered
    line = compare(4.0 + 2500.0 * aperture, aperture)
    assert line.r == pytest.approx(1.0)
    assert line.slope == pytest.approx(2500.0) and line.intercept == pytest.approx(4.0)
    assert line.to_dict()["slope_px_per_mm"] == pytest.approx(2.5)
    # anticorrelated
    assert compare(-aperture, aperture).r == pytest.approx(-1.0)
    with pytest.raises(InputError, match="two"):
        compare(distance[:-1], aperture)


def test_inner_lip_distance_pairs_the_inner_lip_points():
    pts = np.zeros((2, 68, 2))
    pts[:, [61, 62, 63], 1] = 100.0
    pts[0, [67, 66, 65], 1] = [104.0, 106.0, 105.0]  # lower lip below (y down)
    pts[1, [67, 66, 65], 1] = 100.0
    pts[1, 0, 1] = 500.0  # a point off the lips changes nothing
    assert inner_lip_distance(pts) == pytest.approx([5.0, 0.0])
    with pytest.raises(InputError, match="68, 2"):
        inner_lip_distance(np.zeros((67, 2)))
    # the face mesh's: points 82, 13, 312 above 87, 14, 317
    mesh = np.zeros((468, 2))
    mesh[[82, 13, 312], 1] = 50.0
    mesh[[87, 14, 317], 1] = [53.0, 54.0, 55.0]
    mesh[0, 1] = -400.0  # the outer lip changes nothing
    assert inner_lip_distance(mesh) == pytest.approx(4.0)


def test_no_face_gives_nan(detector):
    frames = [np.full((360, 300, 3), 40, np.uint8), np.zeros((360, 300, 4), np.uint8)]
    reading = read_lips(frames, detector=detector)
    assert reading.distance.shape == (2,) and np.all(np.isnan(reading.distance))
    assert np.all(np.isnan(reading.points)) and not reading.found.any()
    got = compare(reading.distance, np.array([0.0, 1e-3]))
    assert got.found == 0 and got.frames == 2 and np.isnan(got.r)
    with pytest.raises(InputError, match="uint8 RGB"):
        read_lips([np.zeros((360, 300), np.uint8)], detector=detector)


def test_without_dlib_the_error_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "dlib", None)  # import dlib raises ImportError
    with pytest.raises(InputError, match=r"facemech\[photo\]"):
        read_lips([np.zeros((64, 64, 3), np.uint8)])


# ---- the face mesh's region of interest and its model ----------------------------------------
def test_a_region_maps_the_networks_pixels_to_the_frame():
    """The input square's corners and centre land on the region's, turned by its angle; the
    crop the tracker feeds the network samples the frame there (a dot found where mapped)."""
    from facemech.io.face_mesh import INPUT_SIZE, Region, crop

    reg = Region(np.array([150.0, 120.0]), 96.0, np.radians(30.0))
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    got = reg.to_image(np.array([[96.0, 96.0], [192.0, 96.0], [96.0, 192.0]]))
    np.testing.assert_allclose(got[0], [150.0, 120.0])
    np.testing.assert_allclose(got[1] - got[0], [48.0 * c, 48.0 * s])  # along the turned x
    np.testing.assert_allclose(got[2] - got[0], [-48.0 * s, 48.0 * c])
    # a dot in the frame where the input's pixel (60, 140) maps is found there in the crop
    frame = np.zeros((300, 300, 3), np.uint8)
    x, y = reg.to_image(np.array([[60.5, 140.5]]))[0]
    frame[int(y) - 1:int(y) + 2, int(x) - 1:int(x) + 2] = 255
    patch = crop(frame, reg)[..., 0].astype(float)
    assert patch.shape == (INPUT_SIZE, INPUT_SIZE)
    vv, uu = np.mgrid[0:INPUT_SIZE, 0:INPUT_SIZE]
    u, v = (patch * uu).sum() / patch.sum(), (patch * vv).sum() / patch.sum()
    # the dot's centre (the middle pixel's centre) mapped back into the input: its pixel index
    # there is that less a half (bilinear resampling keeps a dot's centroid; measured 0.001 px)
    back = np.linalg.solve(reg.axes(), np.array([int(x) + 0.5, int(y) + 0.5]) - reg.centre)
    want = back / reg.side * INPUT_SIZE + 0.5 * INPUT_SIZE - 0.5
    np.testing.assert_allclose([u, v], want, atol=0.02)


def test_a_region_follows_the_points_turned_and_scaled():
    """The region of a set of points turned by 12 degrees (the eyes' outer corners on a line
    turned so) has that angle, their centre, and 1.5 times their extent along its axes."""
    from facemech.io.face_mesh import EYE_CORNERS, ROI_SCALE, region_of_box, region_of_points

    rng = np.random.default_rng(3)
    local = rng.uniform(-40.0, 40.0, (468, 2)) * [1.0, 1.25]
    local[EYE_CORNERS[0]] = (-30.0, -10.0)
    local[EYE_CORNERS[1]] = (30.0, -10.0)
    a = np.radians(12.0)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    centre = np.array([200.0, 180.0])
    reg = region_of_points(local @ rot.T + centre)
    assert reg.angle == pytest.approx(a)
    lo, hi = local.min(axis=0), local.max(axis=0)
    np.testing.assert_allclose(reg.centre, centre + rot @ (0.5 * (lo + hi)), atol=1e-9)
    assert reg.side == pytest.approx(ROI_SCALE * float(np.max(hi - lo)))
    box = region_of_box(10.0, 20.0, 110.0, 140.0)
    np.testing.assert_allclose(box.centre, [60.0, 80.0])
    assert box.side == pytest.approx(180.0) and box.angle == 0.0


def test_the_mesh_model_missing_or_a_tracker_unknown_is_one_line(monkeypatch, tmp_path):
    from facemech.io import face_mesh

    monkeypatch.setenv(face_mesh.MODEL_ENV, str(tmp_path / "none.tflite"))
    with pytest.raises(InputError, match="no such model file"):
        face_mesh.model_path()
    given = tmp_path / "m.tflite"
    given.write_bytes(b"x")
    monkeypatch.setenv(face_mesh.MODEL_ENV, str(given))
    assert face_mesh.model_path() == given
    with pytest.raises(InputError, match="no tracker 'openface'"):
        read_lips([np.zeros((64, 64, 3), np.uint8)], tracker="openface")
