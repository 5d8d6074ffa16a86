"""Issue 30: shaped, separated teeth with gums, and a tongue that shows when the mouth opens
(:mod:`facemech.viz.dentition`), checked on rendered pixels and on the meshes."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import activity, seen_triangles
from facemech.geometry.teeth import lower_incisor_point
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.solvers.jaw import rotate_about
from facemech.viz import dentition as D
from facemech.viz.camera import Camera, view_camera
from facemech.viz.render import parse_background, render_panel
from facemech.viz.scene import _pack, build_scene, look_from_model

JAW = np.radians(15.0)


@pytest.fixture(scope="module")
def mouth(face):
    """The built-in face's scene, its skin at rest and 0.5 s after the jaw began to open to 15
    degrees, the lower lip lowered by DLI (as in speech: the lower incisors show)."""
    n = 31
    sim = simulate(face_model(face), activity(n, DLI=0.6),
                   JAW * np.clip(np.linspace(0, 1.6, n), 0, 1))
    look = look_from_model(face)
    return build_scene(look), look.rest, sim.positions[-1]


def _seen(scene, skin, jaw, cam):
    """The frame (h, w, 3) int and, per pixel, the triangle seen (-1: none)."""
    verts, norms = scene.frame(skin, jaw)
    z, tid = seen_triangles(scene, verts, cam)
    img = render_panel(scene, verts, norms, cam, background=parse_background("#00ff00"))
    return img[..., :3].astype(int), tid


def _part_of(scene, tid):
    """Per pixel, the name's index in scene.parts (-1: none or an inner side)."""
    starts = np.cumsum([0] + [len(p.faces) for p in scene.parts])
    ok = (tid >= 0) & (tid < starts[-1])
    return np.where(ok, np.searchsorted(starts, np.maximum(tid, 0), side="right") - 1, -1)


def _crown_of(look, upper: bool, tri: np.ndarray) -> np.ndarray:
    """The crown (index in :func:`dentition.crowns`) of each of an arch's triangles."""
    ends = np.cumsum([len(f) for _, _, f, _ in D.crowns(look, upper)])
    return np.searchsorted(ends, tri, side="right")


def test_the_crowns_are_separate_and_shaped(face):
    """14 crowns an arch, none touching its neighbour; each front crown is narrower or
    thinner at its edge (rounded corners, a chisel, a cusp) than halfway to its neck."""
    look = look_from_model(face)
    for upper in (True, False):
        each = D.crowns(look, upper)
        assert len(each) == 14
        # neighbours along the arch: the slots alternate the subject's left (even) and right
        order = [*range(13, 0, -2), *range(0, 14, 2)]
        gaps = [np.min(np.linalg.norm(each[a][1][:, None] - each[b][1][None], axis=-1))
                for a, b in zip(order[:-1], order[1:], strict=True)]
        assert min(gaps) > 0.2e-3, min(gaps)  # m: GAP 0.35 mm less the meshes' chords
        for tooth, v, _, _ in each[:6]:
            b = np.abs(v[:, 1] - (v[:, 1].min() if upper else v[:, 1].max())) / tooth.height
            edge, mid = v[b < 0.08], v[(b > 0.4) & (b < 0.6)]
            across = np.ptp(edge[:, [0, 2]], axis=0) / np.ptp(mid[:, [0, 2]], axis=0)
            assert across.min() < 0.9, (tooth, across)


def test_the_lower_incisors_stand_where_the_jaw_solver_puts_them(face):
    """The lower central incisors' edge and labial face: where solvers.jaw.lower_incisor_point
    says the renderer draws them (0.1 mm in height, 0.5 mm in depth: the edge is rounded)."""
    look = look_from_model(face)
    both = np.concatenate([v for _, v, _, _ in D.crowns(look, False)[:2]])
    want = lower_incisor_point(face)
    assert abs(both[:, 1].max() - want[1]) < 0.1e-3
    top = both[both[:, 1] > want[1] - 0.001]
    assert abs(top[:, 2].max() - want[2]) < 0.5e-3, (top[:, 2].max(), want)


@pytest.mark.slow
def test_the_lower_arch_and_tongue_move_with_the_mandible(mouth):
    scene, rest, _ = mouth
    look = scene.look
    moved, _ = scene.frame(rest, JAW)
    still, _ = scene.frame(rest, 0.0)
    names = [p.name for p in scene.parts]
    for name in ("lower_teeth", "lower_gum", "tongue", "upper_teeth", "upper_gum"):
        i = names.index(name)
        sl = slice(scene.offsets[i], scene.offsets[i + 1])
        want = (rotate_about(still[sl], look.hinge_point, look.hinge_axis, JAW)
                if name in ("lower_teeth", "lower_gum", "tongue") else still[sl])
        np.testing.assert_allclose(moved[sl], want, atol=1e-12)


@pytest.mark.slow
def test_open_mouth_shows_separate_crowns_and_the_tongue(mouth):
    """The mouth close-up (a frontal camera) with the jaw at 15 degrees: the lower incisors
    show as four crowns, and between neighbours the picture darkens (their rounded sides and
    the embrasure between their edges) by at least 15 levels of 255 below both crowns; the
    tongue shows, pink."""
    scene, _, open_skin = mouth
    cam = view_camera("mouth", scene.framing, (360, 480), 1.2)
    img, tid = _seen(scene, open_skin, JAW, cam)
    names = [p.name for p in scene.parts]
    part = _part_of(scene, tid)
    i = names.index("lower_teeth")
    start = int(np.cumsum([0] + [len(p.faces) for p in scene.parts])[i])
    crown = np.where(part == i, _crown_of(scene.look, False, tid - start), -1)
    lum = img.mean(axis=-1)
    # the four lower incisors, from the subject's right to left: slots 3, 1, 0, 2
    incisors = (3, 1, 0, 2)
    rows = [r for r in range(len(crown)) if all((crown[r] == k).sum() >= 3 for k in incisors)]
    assert len(rows) >= 5
    r = rows[len(rows) // 3]  # a third of the way down the crowns from their edges
    dips = []
    for a, b in zip(incisors[:-1], incisors[1:], strict=True):
        ca, cb = np.flatnonzero(crown[r] == a), np.flatnonzero(crown[r] == b)
        between = lum[r, ca.max() - 1:cb.min() + 2]
        dips.append(min(np.median(lum[r, ca]), np.median(lum[r, cb])) - between.min())
    assert min(dips) >= 15, dips
    tongue = part == names.index("tongue")
    assert tongue.sum() > 500
    rgb = img[tongue]
    assert np.median(rgb[:, 0] - rgb[:, 1]) > 40  # pink: red well over green


@pytest.mark.slow
@pytest.mark.parametrize("view", ["frontal", "three-quarter", "profile", "mouth"])
def test_nothing_of_the_mouth_shows_through_closed_lips(mouth, view):
    """At rest, lips closed: no pixel sees a tooth, the gums or the tongue; with the jaw at
    15 degrees the frontal views see teeth and tongue."""
    scene, rest, open_skin = mouth
    cam = view_camera(view, scene.framing, (360, 480), 1.2)
    names = [p.name for p in scene.parts]
    inner = [names.index(n) for n in ("upper_teeth", "lower_teeth", "upper_gum", "lower_gum",
                                      "tongue")]
    _, tid = _seen(scene, rest, 0.0, cam)
    assert not np.isin(_part_of(scene, tid), inner).any()
    if view in ("frontal", "mouth"):
        _, tid = _seen(scene, open_skin, JAW, cam)
        seen = _part_of(scene, tid)
        for n in ("lower_teeth", "tongue"):
            assert (seen == names.index(n)).sum() > 20, n


@pytest.mark.parametrize("view", ["frontal", "mouth"])
def test_the_seeds_thin_tissue_hides_the_mouth_too(view):
    """The seeds' uniform tissue is 4 mm deep under the upper lip; the incisors stand at least
    12 mm behind the lip's surface all the same (``teeth_depth``), so nothing of the mouth shows
    through its closed lips (at 4 mm the central incisors did, and the gums above and below)."""
    from facemech.geometry.builder import default_face
    from facemech.geometry.teeth import TEETH_DEPTH_DEFAULT, teeth_depth

    face = default_face(tissue="uniform")
    n = face.n_surface
    ul = face.landmarks["upper_lip_center"]
    assert np.linalg.norm(face.rest_positions[ul] - face.rest_positions[ul + 2 * n]) < 0.005
    assert teeth_depth(face) == TEETH_DEPTH_DEFAULT
    look = look_from_model(face)
    scene = build_scene(look)
    cam = view_camera(view, scene.framing, (360, 480), 1.2)
    names = [p.name for p in scene.parts]
    inner = [names.index(n) for n in ("upper_teeth", "lower_teeth", "upper_gum", "lower_gum",
                                      "tongue")]
    _, tid = _seen(scene, look.rest, 0.0, cam)
    assert not np.isin(_part_of(scene, tid), inner).any()


def test_the_gums_are_pink_above_the_upper_crowns(face):
    """The dentition alone, from the front: over the middle of each upper front crown the
    first pixels above it are gingiva (red well over green and blue), and between the crowns
    the gum comes further down (the papillae)."""
    look = look_from_model(face)
    upper, gum = D.arch(look, True)
    scene = _pack([upper, gum], look)
    st = look.landmarks["stomion"]
    cam = Camera(np.eye(3), st + np.array([0.0, 0.008, 0.0]), 0.016, (320, 480), 1.2)
    img, tid = _seen(scene, look.rest, 0.0, cam)
    part = _part_of(scene, tid)
    crown = np.where(part == 0, _crown_of(look, True, tid), -1)
    margins = {}
    for k in range(6):  # the incisors and canines of both sides
        c = int(np.median(np.flatnonzero((crown == k).any(axis=0))))
        rows = np.flatnonzero(crown[:, c] == k)
        top = rows.min()  # y down: the crown's highest pixel in this column
        above = img[max(top - 4, 0):top - 1, c]
        assert (part[max(top - 4, 0):top - 1, c] == 1).all(), k
        # pink: red over green and blue by 58 to 84 levels measured
        assert np.all(above[:, 0] - above[:, 1] > 40) and np.all(above[:, 0] - above[:, 2] > 40)
        margins[k] = top
    # between the central incisors the gum reaches lower than over their middles
    mid_col = int(np.round(cam.project(np.array([[0.0, st[1] + 0.008, st[2]]]))[0, 0]))
    gum_rows = np.flatnonzero(part[:, mid_col] == 1)
    assert gum_rows.max() > min(margins[0], margins[1]) + 2
