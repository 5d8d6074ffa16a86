"""Issue 30 (part 2): a talker from photos (``facemech face from-photo``).

The photos are facemech's own renders of faces of known shape: the built-in face, and a
variant with a wider mouth, a longer lower face and a nose 6 mm longer, each with its
procedural skin. The fit is checked twice: from the exact iBUG points (the renders' own
projections: the fit's geometry alone) and from dlib's (the whole route a user's photo takes).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import run_cli
from facemech.geometry import generic
from facemech.geometry.ibug import generic_ibug68
from photo_render import rerender

pytest.importorskip("dlib")
pytest.importorskip("face_recognition_models")

SIZE = (720, 540)  #: (height, width) of the test photos
DISTANCE = 1.2  #: m, the renderer's camera distance


def _variant(p: np.ndarray) -> np.ndarray:
    """The variant face's points (..., 3) m from the generic face's: the mouth 8 % wider, the
    face below the subnasale 7 % longer, a nose tip 6 mm further forward."""
    p = np.array(p, float)
    x, y = p[..., 0].copy(), p[..., 1].copy()
    p[..., 0] = x * (1.0 + 0.08 * np.exp(-0.5 * ((y + 0.073) / 0.018) ** 2))
    p[..., 1] = np.where(y < -0.052, y + 0.07 * (y + 0.052), y)
    p[..., 2] += 0.006 * np.exp(-0.5 * (x / 0.010) ** 2) * np.exp(-0.5 * ((y + 0.040) / 0.012)
                                                                   ** 2)
    return p


class Subject:
    """A face of known shape and its photos."""

    def __init__(self, model, landmarks: dict, ibug: np.ndarray):
        from facemech.viz.look import look_from_model
        from facemech.viz.render import Renderer
        from facemech.viz.scene import build_scene

        self.model, self.landmarks, self.ibug = model, landmarks, ibug
        look = look_from_model(model)
        scene = build_scene(look)
        front = Renderer(scene, "frontal", SIZE, background="#8a9099", distance=DISTANCE)
        side = Renderer(scene, "profile", SIZE, background="#8a9099", distance=DISTANCE)
        self.front = np.ascontiguousarray(front(look.rest)[..., :3])
        self.profile = np.ascontiguousarray(side(look.rest)[..., :3])
        cam = front.cameras[0]
        self.camera = cam
        self.points = cam.project(ibug)[:, :2].astype(float)  # pixel edges at integers
        er, el = ibug[36:42].mean(axis=0), ibug[42:48].mean(axis=0)
        self.ipd = float(np.linalg.norm(el - er))
        # the fit's camera distance is to the eyes; the renderer's to the framing's centre
        self.distance = DISTANCE - float(ibug[36:48, 2].mean() - cam.target[2])

    def errors(self, landmarks: dict) -> dict[str, np.ndarray]:
        """Each landmark's error vector (3,) mm, the mean offset between the faces removed (a
        photo does not say where the face is)."""
        names = list(self.landmarks)
        a = np.array([landmarks[n] for n in names])
        b = np.array([self.landmarks[n] for n in names])
        d = (a - b) - (a - b).mean(axis=0)
        return {n: d[i] * 1e3 for i, n in enumerate(names)}


@pytest.fixture(scope="module")
def built_in():
    from facemech.geometry.builder import default_face

    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    return Subject(default_face(), lm, generic_ibug68())


@pytest.fixture(scope="module")
def variant():
    from facemech.geometry.builder import build_face, default_surface, tissue_options

    v, f, lm = default_surface()
    lm = {k: _variant(x) for k, x in lm.items()}
    model = build_face(_variant(v), f, lm, name="variant", options=tissue_options("uniform"))
    return Subject(model, lm, _variant(generic_ibug68()))


@pytest.fixture(scope="module")
def detector():
    from facemech.io.photo import DlibDetector

    return DlibDetector()


def _fit(subject, points, *, offsets="dlib", profile=False, ipd="known"):
    from facemech.workflows.photo import face_from_photo

    return face_from_photo(subject.front, profile=subject.profile if profile else None,
                           points=points, ipd=subject.ipd if ipd == "known" else ipd,
                           distance=subject.distance, offsets=offsets)


def _rerender(made, size=SIZE) -> np.ndarray:
    """The fitted face rendered through the photo's fitted camera (frontal), (h, w, 3)."""
    return rerender(made, size)


def _face_region(points: np.ndarray, size=SIZE) -> np.ndarray:
    """(h, w) bool: inside the jaw line and the brows (the iBUG outline)."""
    from matplotlib.path import Path as Polygon

    h, w = size
    outline = np.concatenate([points[0:17], points[26:16:-1]])
    yy, xx = np.mgrid[0:h, 0:w]
    return Polygon(outline).contains_points(
        np.column_stack([xx.ravel() + 0.5, yy.ravel() + 0.5])).reshape(h, w)


# ---- SSIM ------------------------------------------------------------------------------------
def test_ssim_of_an_image_with_itself_is_one_and_symmetric():
    from facemech.similarity import ssim

    rng = np.random.default_rng(0)
    a = rng.integers(0, 256, (40, 50, 3)).astype(np.uint8)
    b = np.clip(a + rng.normal(0, 20, a.shape), 0, 255)
    assert ssim(a, a) == pytest.approx(1.0, abs=1e-12)
    assert ssim(a, b) == pytest.approx(ssim(b, a), abs=1e-12)
    noisier = [ssim(a, np.clip(a + rng.normal(0, s, a.shape), 0, 255)) for s in (10, 40, 160)]
    assert 1.0 > noisier[0] > noisier[1] > noisier[2] > 0.0


def test_ssim_of_flat_images_is_the_luminance_term():
    """No variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1), C1 = (0.01 * 255)^2."""
    from facemech.similarity import ssim

    a, b = 100.0, 140.0
    c1 = (0.01 * 255) ** 2
    got = ssim(np.full((20, 20), a), np.full((20, 20), b))
    assert got == pytest.approx((2 * a * b + c1) / (a * a + b * b + c1), rel=1e-9)


def test_ssim_map_is_wang_2004_at_a_pixel():
    """At one pixel, the map is the formula with an 11 x 11 Gaussian window (sigma 1.5)
    summed by hand."""
    from facemech.similarity import ssim_map

    rng = np.random.default_rng(1)
    x = rng.uniform(0, 255, (30, 30))
    y = 0.7 * x + rng.normal(0, 15, x.shape) + 20
    k = np.arange(-5, 6)
    w = np.exp(-0.5 * (k[:, None] ** 2 + k[None, :] ** 2) / 1.5 ** 2)
    w /= w.sum()
    px, py = x[10:21, 12:23], y[10:21, 12:23]  # centred on (15, 17)
    mx, my = (w * px).sum(), (w * py).sum()
    sx = (w * px * px).sum() - mx * mx
    sy = (w * py * py).sum() - my * my
    sxy = (w * px * py).sum() - mx * my
    c1, c2 = (0.01 * 255) ** 2, (0.03 * 255) ** 2
    want = (2 * mx * my + c1) * (2 * sxy + c2) / ((mx * mx + my * my + c1) * (sx + sy + c2))
    assert ssim_map(x, y)[15, 17] == pytest.approx(want, rel=1e-9)


# ---- the fit's geometry, from exact points ---------------------------------------------------
#: mm. From the exact points the built-in face comes back to 0.61 mm (the derived jaw angles;
#: the others under 0.45 mm): the surface is resampled to nodes and the derived landmarks put
#: back on it
EXACT_MM = 1.0


def test_the_built_in_face_comes_back_from_its_own_points(built_in):
    made = _fit(built_in, built_in.points, offsets=None)
    err = {n: np.linalg.norm(e) for n, e in built_in.errors(made.fit.landmarks).items()}
    assert max(err.values()) < EXACT_MM, err
    assert made.fit.size_factor == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("degrees", [10.0, -15.0])
def test_a_tilted_photo_fits_the_same(degrees):
    """The exact points of a frontal pinhole view turned in the image plane: the roll comes
    back and the landmarks as without it (0.60 mm at most)."""
    from facemech.geometry.photo_fit import fit_frontal
    from facemech.viz.camera import Camera

    g = generic_ibug68()
    cam = Camera(np.eye(3), np.array([0.0, -0.02, -0.082]), 0.142, SIZE, DISTANCE)
    level = cam.project(g)[:, :2].astype(float)
    truth = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    ipd = float(np.linalg.norm(g[42:48].mean(axis=0) - g[36:42].mean(axis=0)))
    dist = DISTANCE - float(g[36:48, 2].mean() + 0.082)
    r = np.radians(degrees)
    turn = np.array([[np.cos(r), np.sin(r)], [-np.sin(r), np.cos(r)]])  # y down: anticlockwise
    centre = np.array([SIZE[1] / 2, SIZE[0] / 2])
    fits = [fit_frontal(p, SIZE, ipd=ipd, distance=dist, offsets=None)
            for p in (level, (level - centre) @ turn.T + centre)]
    assert np.degrees(fits[1].camera.roll) == pytest.approx(degrees, abs=1e-6)
    for n in truth:
        assert np.linalg.norm(fits[1].landmarks[n] - fits[0].landmarks[n]) < 1e-6
    names = list(truth)
    d = np.array([fits[1].landmarks[n] - truth[n] for n in names])
    assert np.linalg.norm(d - d.mean(axis=0), axis=1).max() < EXACT_MM


def test_a_profile_corrects_the_depth_the_front_cannot_see(variant):
    """The variant's nose is 6 mm longer than the generic face's: the front alone leaves the
    nose tip 5.4 mm short; the profile brings every landmark within 2 mm (measured on the one
    head, hair, ears and neck in the outline: 1.0-1.2 mm at the subnasale, the nose tip 0.6-0.8
    mm)."""
    front_only = variant.errors(_fit(variant, variant.points, offsets=None).fit.landmarks)
    both = variant.errors(_fit(variant, variant.points, offsets=None, profile=True)
                          .fit.landmarks)
    assert front_only["nose_tip"][2] < -4.0
    assert abs(both["nose_tip"][2]) < 1.5
    assert max(np.linalg.norm(e) for e in both.values()) < 2.0, both


def test_a_jaw_line_off_on_one_side_is_taken_loosely(built_in):
    """The built-in face's exact points with the jaw line on its right (iBUG 0-7) 4 mm further
    out, as a detector puts it on a face lit from one side: interpolated, the jaw angle on that
    side moves by 4.9 mm; made symmetric and followed loosely (a detector's jaw line), every
    landmark stays within 0.6 mm (measured 0.55; 0.46 without the shift). The same jaw line 4 mm
    lower (a longer lower face) takes the menton down with it: the chin's heights are
    interpolated."""
    mm_per_px = 2e3 * built_in.camera.half_height / SIZE[0]
    shifted = built_in.points.copy()
    shifted[0:8, 0] -= 4.0 / mm_per_px  # the subject's right is the image's left
    from facemech.geometry.photo_fit import fit_frontal

    strict, loose = (fit_frontal(shifted, SIZE, ipd=built_in.ipd, distance=built_in.distance,
                                 offsets=None, loose_jaw=lj) for lj in (False, True))
    err = {n: np.linalg.norm(e) for n, e in built_in.errors(strict.landmarks).items()}
    assert err["jaw_angle_right"] > 4.0
    err = {n: np.linalg.norm(e) for n, e in built_in.errors(loose.landmarks).items()}
    assert max(err.values()) < 0.6, err
    lower = built_in.points.copy()
    lower[0:17, 1] += 4.0 / mm_per_px
    longer = fit_frontal(lower, SIZE, ipd=built_in.ipd, distance=built_in.distance,
                         offsets=None, loose_jaw=True)
    assert (longer.landmarks["menton"] - loose.landmarks["menton"])[1] * 1e3 < -3.5


def test_the_jaw_line_is_made_mirror_symmetric_about_its_middle():
    from facemech.geometry.photo_fit import MIRROR, symmetric_jaw

    g = generic_ibug68()
    moved = g + [0.003, 0.001, 0.0]  # the face 3 mm to its left, 1 mm up
    np.testing.assert_allclose(symmetric_jaw(moved), moved, atol=1e-9)  # symmetric: kept
    lop = moved.copy()
    lop[0:8, 0] -= 0.004  # the jaw line 4 mm out on the right
    lop[12, 1] += 0.002
    out = symmetric_jaw(lop)
    np.testing.assert_array_equal(out[17:], lop[17:])
    np.testing.assert_array_equal(out[:, 2], lop[:, 2])
    jaw = np.arange(17)
    mid = lop[jaw, 0].mean()
    assert out[jaw, 0].mean() == pytest.approx(mid, abs=1e-12)  # where it lies stays
    np.testing.assert_allclose(out[jaw, 0] - mid, -(out[MIRROR[jaw], 0] - mid), atol=1e-12)
    np.testing.assert_allclose(out[jaw, 1], out[MIRROR[jaw], 1], atol=1e-12)
    # the shape takes half the one-sided 4 mm: each side 2 mm wider than the face's own
    wider = np.abs(out[jaw, 0] - mid) - np.abs(moved[jaw, 0] - 0.003)
    np.testing.assert_allclose(np.delete(wider, 8), 0.002, atol=1e-12)


def test_the_profile_nasion_is_the_notch_under_the_outline_hull():
    """An outline (front, px, by row) that recedes into hair above a sloping forehead and into
    the neck below the chin: the nasion is the notch between brow and nose, not the
    furthest-back row above the tip."""
    from facemech.geometry.photo_fit import ProfileSilhouette

    rows = np.arange(400.0)
    front = -0.6 * np.abs(rows - 250.0)  # forehead and chin recede from the nose tip (row 250)
    front[:120] -= 2.0 * (120 - rows[:120])  # the crown: the hair
    front -= 25.0 * np.exp(-0.5 * ((rows - 200.0) / 8.0) ** 2)  # the notch: the nasion
    front[330:] -= 3.0 * (rows[330:] - 330)  # under the chin, the neck
    nasion, tip = ProfileSilhouette(rows, front).nasion_and_tip()
    assert tip == 250
    assert abs(nasion - 200) <= 2
    # the forehead 100 rows up lies deeper than the notch: a window of rows would take it
    assert front[150] < front[200]


def test_a_profile_facing_either_way_reads_the_same(variant):
    from facemech.geometry.photo_fit import profile_silhouette

    right = profile_silhouette(variant.profile)
    left = profile_silhouette(variant.profile[:, ::-1])
    np.testing.assert_array_equal(right.rows, left.rows)
    np.testing.assert_allclose(right.front - right.front.max(), left.front - left.front.max())


# ---- the whole route: dlib's landmarks -------------------------------------------------------
#: mm, the issue's criterion: the fitted face's landmarks from dlib's points within 2 mm of the
#: truth. Measured (2026-11-29, the points the median over the predictor's boxes, the spline of
#: the linear kernel): the built-in face 0.96 mm at most (a mouth corner; median 0.56; 1.30, a
#: jaw angle, with the thin-plate spline and its affine part); the variant 1.19 mm from the front
#: alone (the right cheek; the nose's depth apart), 1.72 mm with the profile (the subnasale's
#: depth; 2.57 and 2.60 with the thin-plate spline, the jaw angles 2.0-2.4 mm too wide). The jaw
#: line taken strictly gave 3.70 and 4.3 mm (the jaw angles): dlib puts the jaw line of these
#: renders 3-5 mm further out on the subject's right than where it puts it on the left
DLIB_MM = 2.0
#: the re-rendered face against the photo, inside the iBUG outline: measured 0.887 (0.917 from
#: the detector's box alone: the outline moves with the points)
MIN_SSIM = 0.85


@pytest.mark.parametrize("degrees", [-20.0, -8.0, 0.0, 5.0, 15.0])
def test_the_turn_is_read_from_the_generic_faces_points(degrees):
    """The generic face's points turned about the vertical and seen from far (a similarity of
    the turned points, with the image's y down) give their angle back."""
    from facemech.geometry.photo_fit import estimate_yaw, turn_about_vertical

    g = generic_ibug68()
    pivot = 0.5 * (g[36:42].mean(axis=0) + g[42:48].mean(axis=0))
    t = turn_about_vertical(g, np.radians(degrees), pivot)
    r = np.radians(7.0)  # a roll and an offset change nothing
    xy = np.column_stack([t[:, 0], -t[:, 1]]) @ np.array([[np.cos(r), -np.sin(r)],
                                                         [np.sin(r), np.cos(r)]]) * 4e3
    assert np.degrees(estimate_yaw(xy + [300.0, 400.0], g)) == pytest.approx(degrees, abs=0.1)


def test_a_turned_camera_sees_the_face_turned():
    """``PhotoCamera.yaw`` turns the face about the vertical through its eyes before the view:
    a point on that vertical projects where it did, any other as the turned point does, and
    the camera is seen from the turned-back direction."""
    from dataclasses import replace

    from facemech.geometry.photo_fit import PhotoCamera, turn_about_vertical

    cam = PhotoCamera(np.array([270.0, 300.0]), np.array([0.0, 0.01]), 0.02, 2e-4, 1.0, 0.1,
                      (720, 540))
    turned = replace(cam, yaw=np.radians(12.0))
    p = np.array([[0.03, -0.04, 0.05], [0.0, 0.02, 0.02], [-0.05, 0.0, -0.01]])
    assert np.allclose(turned.project(p), cam.project(turn_about_vertical(
        p, np.radians(12.0), cam.pivot)))
    assert np.allclose(turned.project(p[1:2]), cam.project(p[1:2]))
    d = turned.view_direction(cam.pivot[None])[0]
    assert d == pytest.approx([-np.sin(np.radians(12.0)), 0.0, np.cos(np.radians(12.0))])
    with pytest.raises(ValueError):
        turned.back_project(np.array([[270.0, 300.0]]), np.array([0.02]))


@pytest.mark.parametrize("degrees", [-12.0, 9.0])
def test_a_turned_face_is_turned_back_before_the_fit(degrees):
    """The exact points of the built-in face turned about its eyes' vertical and seen by a
    pinhole at 1.2 m: the turn is read within a tenth of a degree and the landmarks come back as
    from a frontal view (within EXACT_MM, the mean offset removed), where the points fitted
    as frontal put them several millimetres off."""
    from facemech.geometry.photo_fit import YAW_MIN, fit_frontal, turn_about_vertical
    from facemech.viz.camera import Camera

    g = generic_ibug68()
    pivot = 0.5 * (g[36:42].mean(axis=0) + g[42:48].mean(axis=0))
    cam = Camera(np.eye(3), np.array([0.0, -0.02, -0.082]), 0.142, SIZE, DISTANCE)
    pts = cam.project(turn_about_vertical(g, np.radians(degrees), pivot))[:, :2].astype(float)
    truth = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    ipd = float(np.linalg.norm(g[42:48].mean(axis=0) - g[36:42].mean(axis=0)))
    dist = DISTANCE - float(g[36:48, 2].mean() + 0.082)
    names = list(truth)

    def worst(fit):
        d = np.array([fit.landmarks[n] - truth[n] for n in names])
        return 1e3 * float(np.linalg.norm(d - d.mean(axis=0), axis=1).max())

    fit = fit_frontal(pts, SIZE, ipd=ipd, distance=dist, offsets=None)
    flat = fit_frontal(pts, SIZE, ipd=ipd, distance=dist, offsets=None, yaw=0.0)
    assert abs(degrees) > np.degrees(YAW_MIN)
    assert np.degrees(fit.camera.yaw) == pytest.approx(degrees, abs=0.1)
    assert worst(fit) < EXACT_MM < 3.0 < worst(flat)
    # the fitted face seen through the fitted camera lands on the photo's points
    assert np.abs(fit.camera.project(fit.ibug) - pts).max() < 3.0  # px, of a 139-px IPD
    assert "turned" in fit.note() and "turned" not in flat.note()


#: mm, the worst landmark (x and y) of a photo turned 15 or 10 degrees, the turn taken out.
#: Measured (2026-11-29, dlib's points the median over its boxes, the spline of the linear
#: kernel): 3.73 mm at -15 degrees (the left brow) and 1.63 mm at +10 (4.11 and 2.26 with the
#: thin-plate spline; from the detector's box alone 3.53 and 6.53 mm)
TURNED_MM = 4.5


def _render_view(subject, degrees: float, size=SIZE, distance=DISTANCE) -> np.ndarray:
    """The subject rendered from a camera turned ``degrees`` about the vertical (negative: the
    face seen turned to its left), (h, w, 3) uint8."""
    from facemech.viz.camera import Camera, view_camera, view_rotation
    from facemech.viz.look import look_from_model
    from facemech.viz.render import parse_background, render_panel
    from facemech.viz.scene import build_scene

    look = look_from_model(subject.model)
    scene = build_scene(look)
    frontal = view_camera("frontal", scene.framing, size, distance)
    cam = Camera(view_rotation(degrees, 0.0), frontal.target, frontal.half_height, size,
                 distance)
    verts, norms = scene.frame(look.rest, 0.0)
    return np.ascontiguousarray(render_panel(scene, verts, norms, cam, background=(
        parse_background("#8a9099")))[..., :3])


@pytest.mark.parametrize("degrees", [-15.0, 10.0])
def test_a_turned_photo_through_dlib_is_turned_back(built_in, detector, degrees):
    """A render of the built-in face from a camera turned about the vertical, through dlib:
    the turn taken out leaves the worst landmark (x and y) under :data:`TURNED_MM` and below
    that of the points fitted as frontal, and lowers the median by a fifth at least (measured:
    by 29 and 65 %; docs/photo.md)."""
    from facemech.geometry.photo_fit import fit_frontal
    from facemech.io.photo import frontal_landmarks

    pts = frontal_landmarks(_render_view(built_in, degrees), source="turned.png",
                            detector=detector).points

    def xy(fit):
        e = built_in.errors(fit.landmarks)
        return np.array([np.hypot(v[0], v[1]) for v in e.values()])

    fit = fit_frontal(pts, SIZE, ipd=built_in.ipd, distance=built_in.distance)
    flat = fit_frontal(pts, SIZE, ipd=built_in.ipd, distance=built_in.distance, yaw=0.0)
    # the face seen turned to its left (a negative view) is turned to its left (positive)
    assert 0.5 * abs(degrees) < -np.sign(degrees) * np.degrees(fit.camera.yaw) < 1.5 * abs(
        degrees)
    assert xy(fit).max() < min(TURNED_MM, xy(flat).max())
    assert np.median(xy(fit)) < 0.8 * np.median(xy(flat))


#: mm, the issue's 2 mm, on the built-in face's photos at 640 x 480 from 1.2 m and 720 x 540
#: from 1.5 m through dlib (x and y). Measured (2026-11-29): 1.67 and 1.20 mm with the points the
#: median over the predictor's boxes and the spline of the linear kernel (2.00 and 1.69 mm with
#: the thin-plate spline), 3.74 and 5.19 mm from the detector's box alone (the eye centres 3-5 %
#: closer than on the tests' photo, and the whole face that much larger; ``python
#: benchmarks/photo_sizes.py``: over its six photos of each face at most 1.67 and 2.15 mm)
SIZES_MM = 2.0


@pytest.mark.parametrize(("size", "distance"), [((640, 480), 1.2), ((720, 540), 1.5)])
def test_photos_of_other_sizes_fit_as_well(built_in, detector, size, distance):
    """dlib's detector box moves on the face with the image's size (an image pyramid), and the
    predictor's points with it; from the median over boxes around it the fit stays within
    :data:`SIZES_MM` on photos where one box put it 3.7-5.2 mm off."""
    from facemech.geometry.photo_fit import fit_frontal
    from facemech.io.photo import frontal_landmarks
    from facemech.viz.look import look_from_model
    from facemech.viz.render import Renderer
    from facemech.viz.scene import build_scene

    look = look_from_model(built_in.model)
    render = Renderer(build_scene(look), "frontal", size, background="#8a9099",
                      distance=distance)
    ibug = built_in.ibug
    eyes = distance - float(ibug[36:48, 2].mean() - render.cameras[0].target[2])
    photo = np.ascontiguousarray(render(look.rest)[..., :3])
    pts = frontal_landmarks(photo, source="photo.png", detector=detector).points
    fit = fit_frontal(pts, size, ipd=built_in.ipd, distance=eyes)
    e = built_in.errors(fit.landmarks)
    worst = max(np.hypot(v[0], v[1]) for v in e.values())
    assert worst < SIZES_MM


def test_a_frontal_photo_is_not_turned(built_in, from_dlib):
    """The frontal render's turn reads under YAW_MIN: its fit is the frontal one, unchanged."""
    _, made = from_dlib
    assert made.fit.camera.yaw == 0.0


@pytest.fixture(scope="module")
def from_dlib(built_in, detector):
    from facemech.io.photo import frontal_landmarks

    found = frontal_landmarks(built_in.front, source="built-in.png", detector=detector)
    return found, _fit(built_in, found.points)


def test_dlib_finds_the_landmarks_and_the_fit_places_them(built_in, from_dlib):
    found, made = from_dlib
    err = {n: float(np.linalg.norm(e)) for n, e in built_in.errors(made.fit.landmarks).items()}
    assert max(err.values()) < DLIB_MM, err
    assert np.median(list(err.values())) < 1.2


@pytest.fixture(scope="module")
def variant_from_dlib(variant, detector):
    from facemech.geometry.photo_fit import fit_frontal, profile_silhouette
    from facemech.io.photo import frontal_landmarks

    found = frontal_landmarks(variant.front, source="variant.png", detector=detector)
    return [fit_frontal(found.points, SIZE, ipd=variant.ipd, distance=variant.distance,
                        profile=p) for p in (None, profile_silhouette(variant.profile))]


def _variant_errors(variant, variant_from_dlib):
    front_only, both = (variant.errors(f.landmarks) for f in variant_from_dlib)
    assert front_only["nose_tip"][2] < -4.0  # a frontal photo cannot see the longer nose
    for n in ("nose_tip", "subnasale"):
        front_only[n] = front_only[n][:2]
    return [{n: float(np.linalg.norm(e)) for n, e in err.items()} for err in (front_only, both)]


def test_the_variant_through_dlib_is_within_2_mm(variant, variant_from_dlib):
    """The variant (a wider mouth, a longer lower face, a longer nose) from dlib's points: every
    landmark within the issue's :data:`DLIB_MM` with the profile, and without it but for the
    depth of the nose tip and the subnasale, which a frontal photo cannot see (the generic
    face's: 5.4 mm short); the median within 1.2 mm. Its photo had shown the renderer's
    incisors and gums through the closed lips until 2026-11-29 (``geometry.teeth.teeth_depth``);
    on the clean photo the thin-plate spline's affine part had put its jaw angles 2.0-2.4 mm
    too wide (2.60 mm)."""
    for norms in _variant_errors(variant, variant_from_dlib):
        assert max(norms.values()) < DLIB_MM, norms
        assert np.median(list(norms.values())) < 1.2


def test_the_rerendered_talker_matches_the_photo(built_in, from_dlib):
    from facemech.similarity import ssim

    found, made = from_dlib
    image = _rerender(made)
    assert ssim(built_in.front, image, mask=_face_region(found.points)) >= MIN_SSIM
    # the photo paints the face; the sides it sees edge-on are the photo's skin tone
    assert made.texture.coverage.max() == 1.0
    assert 0.3 < made.texture.coverage.mean() < 0.9


def test_the_photo_talker_blinks_and_its_iris_is_the_photos(built_in, from_dlib):
    """The photo's eyes are cut from its texture and drawn (:mod:`facemech.viz.fissures`): the
    talker's iris takes the photo's (the built-in face's ``IRIS``; measured within 0.01), the
    lids its skin; open, the eye shows its white (measured: 25 % of a 16 x 50 px box round
    each eye above 200 in every channel); in a blink, none of it (0 %)."""
    from facemech.viz import textures as T
    from facemech.viz.face_parts import textured_fissures
    from facemech.viz.look import look_from_model
    from facemech.viz.render import Renderer
    from facemech.viz.scene import build_scene

    found, made = from_dlib
    look = look_from_model(made.model)
    cut = textured_fissures(look)
    for name in ("eye_left", "eye_right"):
        np.testing.assert_allclose(cut.colours[name].iris, T.IRIS, atol=0.03)
        assert np.abs(cut.colours[name].lid - T.SKIN).max() < 0.08
    render = Renderer(build_scene(look), "frontal", SIZE, background="#8a9099",
                      distance=built_in.distance)
    cam = render.cameras[0]
    for name in ("eye_left", "eye_right"):
        x, y = cam.project(look.landmarks[name][None])[0, :2]
        box = np.s_[int(y) - 8:int(y) + 8, int(x) - 25:int(x) + 25]
        white = [np.mean(np.all(render(look.rest, blink=b)[box][..., :3] > 200, axis=-1))
                 for b in (0.0, 1.0)]
        assert white[0] > 0.08 and white[1] < 0.005, (name, white)


def test_the_scale_is_the_adult_norm_when_not_given(built_in, from_dlib):
    found, _ = from_dlib
    made = _fit(built_in, found.points, ipd=None)
    assert made.fit.ipd == pytest.approx(0.0634)
    assert "63.4 mm (adult norm, Dodgson 2004)" in made.fit.note()
    # the built-in face's 64.0 mm against the norm's 63.4: its size within 1 %
    assert made.fit.size_factor == pytest.approx(0.0634 / built_in.ipd, rel=1e-6)


# ---- the command -----------------------------------------------------------------------------
def _save(image: np.ndarray, path) -> None:
    from PIL import Image

    Image.fromarray(np.ascontiguousarray(image)).save(path)


@pytest.mark.slow
def test_from_photo_then_speak(built_in, tmp_path, monkeypatch, capsys):
    import json

    from facemech.geometry.model import FaceModel

    photo = tmp_path / "front.png"
    _save(built_in.front, photo)
    talker = tmp_path / "talker.npz"
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", photo, "-o", talker,
                             "--ipd", "64", "--distance", f"{built_in.distance:.4f}")
    assert code == 0, err
    assert "facemech: note: scale: interpupillary distance 64.0 mm (given)" in " ".join(
        err.split())
    model = FaceModel.load(talker)
    assert model.appearance is not None and model.appearance.textured
    spoken = tmp_path / "spoken"
    code, out, err = run_cli(monkeypatch, capsys, "speak", "Bob bought a puppy", "--face",
                             talker, "-o", spoken, "--no-video")
    assert code == 0, err
    man = json.loads((spoken / "manifest.json").read_text())
    assert man["stimulus"]["jaw_angle"]["peak_displacement"] > 3.0  # degrees: it spoke


def _no_face(subject):
    y = np.linspace(0, 1, SIZE[0])[:, None, None]
    return np.broadcast_to(80 + 120 * y, (*SIZE, 3)).astype(np.uint8)


def _two_faces(subject):
    return np.concatenate([subject.front, subject.front], axis=1)


def _small(subject):
    """The photo reduced ten times (a face about 36 px across, under the 40 px measured in
    benchmarks/photo_small_faces.py), on a canvas of the photo's size and its corner's colour."""
    from PIL import Image

    h, w = SIZE
    small = np.asarray(Image.fromarray(subject.front).resize((w // 10, h // 10), Image.BOX))
    out = np.empty_like(subject.front)
    out[:] = subject.front[0, 0]
    out[h // 3:h // 3 + small.shape[0], w // 3:w // 3 + small.shape[1]] = small
    return out


def _turned(subject):
    """The face from a camera 30 degrees to its side (the frontal framing)."""
    from facemech.viz.camera import Camera, view_rotation
    from facemech.viz.look import look_from_model
    from facemech.viz.render import parse_background, render_panel
    from facemech.viz.scene import build_scene

    look = look_from_model(subject.model)
    scene = build_scene(look)
    frontal = _frontal_camera(scene)
    cam = Camera(view_rotation(30.0, 0.0), frontal.target, frontal.half_height, SIZE,
                 DISTANCE)
    verts, norms = scene.frame(look.rest, 0.0)
    return np.ascontiguousarray(render_panel(scene, verts, norms, cam, background=(
        parse_background("#8a9099")))[..., :3])


def _frontal_camera(scene):
    from facemech.viz.camera import view_camera

    return view_camera("frontal", scene.framing, SIZE, DISTANCE)


@pytest.mark.parametrize("degrees", [-30.0, -12.0, 0.0, 15.0, 40.0])
def test_the_yaw_of_a_turned_face_is_read_from_its_nose(degrees):
    """The generic face's iBUG points turned and seen from far give their angle back."""
    from facemech.io.photo import yaw_degrees

    g = generic_ibug68()
    r = np.radians(degrees)
    points = np.column_stack([g[:, 0] * np.cos(r) + g[:, 2] * np.sin(r), -g[:, 1]]) * 4e3
    assert yaw_degrees(points + [300.0, 400.0]) == pytest.approx(degrees, abs=0.3)


@pytest.mark.parametrize(("make", "message"), [
    (_no_face, "no face found"),
    (_turned, "degrees from the camera (at most 20)"),
    (_two_faces, "2 faces found; crop the photo to one face"),
    (_small, "px across, under the 40 px needed"),
    (lambda s: s.profile, "the face is in profile, not facing the camera"),
])
def test_a_bad_photo_is_refused_in_one_line(built_in, tmp_path, monkeypatch, capsys, make,
                                            message):
    photo = tmp_path / "bad.png"
    _save(make(built_in), photo)
    talker = tmp_path / "talker.npz"
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", photo, "-o", talker)
    assert code == 2
    assert err.startswith("facemech: error: ") and err.count("\n") == 1, err
    assert str(photo) in err and message in err and "Traceback" not in err
    assert not talker.exists() and list(tmp_path.iterdir()) == [photo]


def test_a_frontal_photo_given_as_the_profile_is_refused(built_in, tmp_path, monkeypatch,
                                                         capsys):
    front = tmp_path / "front.png"
    _save(built_in.front, front)
    before = front.read_bytes()
    talker = tmp_path / "talker.npz"
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", front, "--profile",
                             front, "-o", talker)
    assert code == 2 and err.count("\n") == 1, err
    assert "field '--profile': this is a frontal photo, not a profile" in err
    assert not talker.exists() and front.read_bytes() == before


def test_a_profile_without_a_subject_is_refused(built_in, tmp_path, monkeypatch, capsys):
    front, side = tmp_path / "front.png", tmp_path / "side.png"
    _save(built_in.front, front)
    _save(np.full((*SIZE, 3), 128, np.uint8), side)
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", front, "--profile",
                             side, "-o", tmp_path / "t.npz")
    assert code == 2 and err.count("\n") == 1, err
    assert f"{side}: field '--profile': no subject distinct from the background" in err
    assert not (tmp_path / "t.npz").exists()


def test_not_a_photo_and_not_a_face_file(tmp_path, monkeypatch, capsys):
    text = tmp_path / "front.jpg"
    text.write_text("not an image")
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", text, "-o",
                             tmp_path / "t.npz")
    assert code == 2 and "not an image that can be read" in err and err.count("\n") == 1
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", text, "-o",
                             tmp_path / "t.obj")
    assert code == 2 and "the talker is a .npz face file" in err
    code, out, err = run_cli(monkeypatch, capsys, "face", "from-photo", text, "-o", text)
    assert code == 2 and text.read_text() == "not an image"
