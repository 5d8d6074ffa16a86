"""Issue 14: a coarse scan's mouth region is refined to the lips' spacing before the build:
conforming splits that keep the surface, its area and its texture mapping; a 4-mm scan then
gets enough lip pairs and moves symmetrically."""

from __future__ import annotations

import numpy as np
import pytest

from facemech import simulate
from facemech.geometry.appearance import Appearance
from facemech.geometry.builder import build_face, tissue_options
from facemech.geometry.refine import lip_spacing, refine_perioral, split_faces
from facemech.params import MUSCLE_GROUPS
from facemech.physics.model import model as face_model
from facemech.workflows.faces import build_face_file
from scans import scan_face, write_landmark_csv, write_obj


def _edges(f):
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    keys, counts = np.unique(e, axis=0, return_counts=True)
    return keys, counts


def _area(v, f):
    return 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]),
                                axis=1).sum()


def test_splits_are_conforming_and_keep_the_surface():
    rng = np.random.default_rng(1)
    g = np.stack(np.meshgrid(np.arange(6.0), np.arange(5.0)), -1).reshape(-1, 2) * 1e-3
    v = np.c_[g + rng.uniform(-2e-4, 2e-4, g.shape), np.zeros(len(g))]
    f = np.array([[r * 6 + c, r * 6 + c + 1, (r + 1) * 6 + c + 1] for r in range(4)
                  for c in range(5)] + [[r * 6 + c, (r + 1) * 6 + c + 1, (r + 1) * 6 + c]
                                       for r in range(4) for c in range(5)])
    uv = (v[f][..., :2] * 100 + 0.1).astype(np.float32)  # an affine map of the plane
    colours = (rng.uniform(0, 255, (len(v), 3))).astype(np.uint8)
    look = Appearance(uv=uv, image=np.zeros((4, 4, 3), np.uint8), source="t")
    red = np.zeros(len(f), bool)
    red[[3, 7, 20]] = True
    v2, f2, look2, n = split_faces(v, f, red, look)
    assert n >= 3 and len(f2) > len(f)
    keys, counts = _edges(f2)
    assert counts.max() == 2  # manifold: no edge in three triangles
    boundary = keys[counts == 1]
    # no hanging node: every new node on a boundary edge of the old mesh or inside it
    old_keys, old_counts = _edges(f)
    assert len(boundary) >= np.sum(old_counts == 1)
    assert _area(v2, f2) == pytest.approx(_area(v, f), rel=1e-12)
    normals = np.cross(v2[f2[:, 1]] - v2[f2[:, 0]], v2[f2[:, 2]] - v2[f2[:, 0]])[:, 2]
    assert np.all(normals > 0)  # orientation kept
    np.testing.assert_allclose(look2.uv, v2[f2][..., :2] * 100 + 0.1, atol=1e-5)
    _, _, with_colours, _ = split_faces(v, f, red, Appearance(vertex_colours=colours, source="t"))
    mid = with_colours.vertex_colours[len(v):]
    assert len(mid) == len(v2) - len(v) and mid.dtype == np.uint8


@pytest.fixture(scope="module")
def coarse():
    """A 4-mm scan-like face whose lip line has 12 nodes (11 pairs)."""
    return scan_face(spacing_deg=3.2, spacing_mm=4.0, lip_points=12)


def _corner_motion(model):
    act = np.zeros((40, len(MUSCLE_GROUPS)))
    for g in ("ZYG", "RIS", "DAO", "LLS"):
        act[:, MUSCLE_GROUPS.index(g)] = 0.6 * np.clip(np.arange(40) / 15, 0, 1)
    sim = simulate(face_model(model), act)
    left = sim.marker("mouth_corner_left")[-1] - sim.marker("mouth_corner_left")[0]
    right = sim.marker("mouth_corner_right")[-1] - sim.marker("mouth_corner_right")[0]
    return left, right * [-1.0, 1.0, 1.0]  # the right side mirrored onto the left


def test_a_coarse_scan_gets_refined_lips_that_move_symmetrically(coarse, tmp_path):
    v, f, lm = coarse
    assert lip_spacing(v, f, lm) > 4.5e-3
    write_obj(tmp_path / "scan.obj", v * 1e3, f)
    write_landmark_csv(tmp_path / "lm.csv", lm)
    done = build_face_file(tmp_path / "scan.obj", tmp_path / "lm.csv", tmp_path / "f.npz",
                           tissue="anatomical")
    assert "the mouth region refined" in done.warnings
    plain = build_face(v, f, lm, options=tissue_options("anatomical"))
    assert len(plain.lip_pairs) == 33  # 11 pairs on each of the three layers
    model = done.data
    assert len(model.lip_pairs) >= 40
    left, right = _corner_motion(model)
    assert np.linalg.norm(left) / np.linalg.norm(right) == pytest.approx(1.0, abs=0.1)
    # the refined lips move more alike than the coarse ones
    pl, pr = _corner_motion(plain)
    assert np.linalg.norm(left - right) < np.linalg.norm(pl - pr)


def test_fine_lips_are_left_as_they_are():
    v, f, lm = scan_face(lip_points=25)
    v2, f2, _, note = refine_perioral(v, f, lm)
    assert note == "" and v2.shape == v.shape and np.array_equal(f2, f)


def _with_hole(centre, radius):
    from facemech.geometry.builder import default_surface

    v, f, lm = default_surface()
    keep = np.linalg.norm(v[f].mean(axis=1) - centre(lm), axis=1) > radius
    used = np.unique(f[keep])
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    return v[used], remap[f[keep]], lm


def test_a_mouth_open_in_the_middle_is_refused(tmp_path, monkeypatch, capsys):
    from conftest import run_cli

    v, f, lm = _with_hole(lambda lm: 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]),
                          0.006)
    write_obj(tmp_path / "open.obj", v * 1e3, f)
    write_landmark_csv(tmp_path / "lm.csv", lm)
    code, _, err = run_cli(monkeypatch, capsys, "face", "build", tmp_path / "open.obj",
                           tmp_path / "lm.csv", "-o", tmp_path / "f.npz")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith(f"facemech: error: {tmp_path / 'open.obj'}: field 'mouth': "
                               "the mouth is open in the middle")
    assert not (tmp_path / "f.npz").exists()
    # a hole far from the mouth (on the forehead) is not the mouth's business
    v, f, lm = _with_hole(lambda lm: lm["nasion"] + [0.0, 0.03, 0.0], 0.004)
    from facemech.geometry.scan_cleanup import check_mouth_closed

    check_mouth_closed(v, f, lm)
