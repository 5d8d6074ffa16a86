"""Face scans as they come (issue 14, parts 1-3) and landmark plausibility (issue 18).

The generic face is written as a lab's scan would arrive: in cm or um, z-up, mirrored, with
texture seams, loose fragments, a closed head, a sliver, iBUG-68 landmarks. Each either loads
to the same surface and landmarks (and builds the same face), or is refused in one line naming
the file and the field.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree

from facemech import InputError
from facemech.geometry.builder import build_face, default_surface, tissue_options
from facemech.geometry.ibug import (
    DIRECT,
    generic_ibug68,
    ibug_to_landmarks,
    read_ibug68,
    write_pts,
)
from facemech.geometry.scan import load_scan
from facemech.geometry.scan_frame import axes_text, check_unit, infer_unit, parse_axes
from facemech.workflows.faces import build_face_file
from scans import reshape, scan_face, write_landmark_csv, write_obj


@pytest.fixture(scope="module")
def generic():
    """The generic face's surface (m), triangles, landmarks (m) and the face built from them."""
    v, f, lm = default_surface()
    return v, f, lm, build_face(v, f, lm, options=tissue_options("anatomical"))


def one_line(exc: pytest.ExceptionInfo, *needles: str) -> str:
    text = str(exc.value)
    assert "\n" not in text
    for n in needles:
        assert n in text, (n, text)
    return text


def write_scan(folder, v, f, lm, *, scale=1e3, name="scan"):
    """The surface and landmark CSV in the file's numbers (metres times ``scale``)."""
    obj, csv = folder / f"{name}.obj", folder / f"{name}_lm.csv"
    write_obj(obj, v * scale, f)
    write_landmark_csv(csv, lm, scale)
    return obj, csv


def assert_same_scan(scan, v, lm, atol=2e-9):
    assert scan.vertices.shape == v.shape
    np.testing.assert_allclose(scan.vertices, v, atol=atol)
    for k, p in lm.items():
        np.testing.assert_allclose(scan.landmarks[k], p, atol=atol, err_msg=k)


# ---- landmark plausibility (issue 18) ----------------------------------------------------------
def test_a_landmark_off_the_skin_is_refused_with_its_distance(generic, tmp_path):
    v, f, lm, _ = generic
    off = dict(lm, nose_tip=lm["nose_tip"] + [0.0, 0.0, 0.100])
    obj, csv = write_scan(tmp_path, v, f, off)
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    text = one_line(exc, "scan_lm.csv", "field 'nose_tip'", "mm from the surface")
    assert float(text.split("lies ")[1].split(" mm")[0]) == pytest.approx(100.0, abs=0.5)
    assert exc.value.field == "nose_tip"
    # 4 mm off is accepted: the limit is 5 mm
    near = dict(lm, nose_tip=lm["nose_tip"] + [0.0, 0.0, 0.004])
    obj, csv = write_scan(tmp_path, v, f, near, name="near")
    assert load_scan(obj, csv).landmarks["nose_tip"][2] == pytest.approx(lm["nose_tip"][2]
                                                                         + 0.004, abs=1e-9)


def test_a_duplicated_landmark_is_refused_naming_both(generic, tmp_path):
    v, f, lm, _ = generic
    dup = dict(lm, chin=lm["menton"] + 0.0003)
    obj, csv = write_scan(tmp_path, v, f, dup)
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "scan_lm.csv", "'chin'", "'menton'", "0.52 mm apart")


@pytest.mark.parametrize("left, right", [("mouth_corner_left", "mouth_corner_right"),
                                         ("eye_left", "eye_right")])
def test_swapped_left_and_right_landmarks_are_refused(generic, tmp_path, left, right):
    v, f, lm, _ = generic
    swapped = dict(lm, **{left: lm[right], right: lm[left]})
    obj, csv = write_scan(tmp_path, v, f, swapped)
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "scan_lm.csv", f"field '{left}'", right, "swapped")


# ---- units ------------------------------------------------------------------------------------
def test_units_are_inferred_from_the_size_and_checked():
    assert [infer_unit(x) for x in (0.2, 20.0, 200.0, 2e5, 2e3, 0.01)] == [
        "m", "cm", "mm", "um", None, None]
    assert check_unit(200.0, "mm") == "mm" and check_unit(20.0, None) == "cm"
    with pytest.raises(InputError) as exc:  # the 180-m face
        check_unit(180000.0, "mm", source="head.obj")
    one_line(exc, "head.obj: field 'units'", "180,000 mm across read in mm", "180 mm in um",
             "it looks like micrometres; the file says mm; use --units um")
    with pytest.raises(InputError) as exc:  # no unit fits: the nearest
        check_unit(18000.0, "mm", source="head.obj")
    one_line(exc, "18,000 mm across read in mm", "18 mm in um", "use --units um")
    with pytest.raises(InputError) as exc:
        check_unit(0.02, "m", source="bead.obj")
    one_line(exc, "bead.obj: field 'units'", "20 mm across read in m", "is it a face?")


@pytest.mark.parametrize("unit, scale, words", [("cm", 1e2, "centimetres"),
                                                ("um", 1e6, "micrometres")])
def test_a_scan_in_cm_or_um_builds_the_same_face(generic, tmp_path, unit, scale, words):
    v, f, lm, ref = generic
    obj, csv = write_scan(tmp_path, v, f, lm, scale=scale)
    with pytest.raises(InputError) as exc:  # declared mm: refused, naming the unit it looks like
        load_scan(obj, csv, units="mm")
    one_line(exc, "scan.obj", "field 'units'", words, f"use --units {unit}")
    scan = load_scan(obj, csv, units=unit)
    assert scan.unit == unit and scan.notes == []
    assert_same_scan(scan, v, lm, atol=1e-6 / scale * 1e3)
    inferred = load_scan(obj, csv, units=None)
    assert inferred.unit == unit and inferred.notes == [f"scan.obj: read in {unit} (from its size)"]
    out = build_face_file(obj, csv, tmp_path / "f.npz", units=unit)
    model = out.data
    assert model.n_surface == ref.n_surface
    width = np.ptp(model.rest_positions[: model.n_surface, 0])
    assert width == pytest.approx(np.ptp(ref.rest_positions[: ref.n_surface, 0]), rel=1e-3)


def test_landmarks_in_another_unit_than_the_surface_are_refused(generic, tmp_path):
    v, f, lm, _ = generic
    obj = tmp_path / "scan.obj"
    write_obj(obj, v * 1e3, f)
    write_landmark_csv(tmp_path / "lm.csv", lm, 1e2)  # cm, the surface mm
    with pytest.raises(InputError) as exc:
        load_scan(obj, tmp_path / "lm.csv")
    one_line(exc, "lm.csv: field 'units'", "they look like cm")


# ---- axes -------------------------------------------------------------------------------------
def test_axes_strings():
    r = parse_axes("x,z,-y")
    np.testing.assert_array_equal(r, [[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    assert np.linalg.det(r) == pytest.approx(1.0) and axes_text(r) == "x,z,-y"
    assert np.linalg.det(parse_axes("-x, y, +z")) == pytest.approx(-1.0)
    for bad in ("x,y", "x,x,z", "x,y,w", "x,y,--z"):
        with pytest.raises(InputError) as exc:
            parse_axes(bad)
        assert exc.value.field == "axes"


def test_a_z_up_scan_is_turned_with_a_note_and_builds_the_same_face(generic, tmp_path):
    v, f, lm, ref = generic
    to_file = parse_axes("x,z,-y").T  # facemech -> file: (x, y, z) -> (x, -z, y)
    obj, csv = write_scan(tmp_path, v @ to_file.T, f, {k: to_file @ p for k, p in lm.items()})
    scan = load_scan(obj, csv)
    assert scan.axes == "x,z,-y"
    assert scan.notes == ["scan.obj: turned to facemech's axes (x left, y up, z forward) from "
                          "the landmarks, as --axes x,z,-y"]
    assert_same_scan(scan, v, lm, atol=1e-8)
    # the same axes given: the same scan, no note
    given = load_scan(obj, csv, axes="x,z,-y")
    assert given.notes == [] and np.array_equal(given.vertices, scan.vertices)
    # axes that do not fit the landmarks are refused
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv, axes="x,y,z")
    one_line(exc, "scan_lm.csv: field 'axes'", "with --axes x,y,z", "do not fit")
    model = build_face_file(obj, csv, tmp_path / "f.npz").data
    assert model.n_surface == ref.n_surface
    np.testing.assert_allclose(model.rest_positions, ref.rest_positions, atol=1e-6)
    assert "turned to facemech's axes" in build_face_file(obj, csv, tmp_path / "g.npz").warnings


def test_a_mirrored_scan_is_refused_and_builds_with_its_axes_given(generic, tmp_path):
    v, f, lm, ref = generic
    flip = np.array([-1.0, 1.0, 1.0])
    obj, csv = write_scan(tmp_path, v * flip, f[:, ::-1], {k: p * flip for k, p in lm.items()})
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "scan_lm.csv", "field 'mouth_corner_left'", "mirrored", "--axes=-x,y,z")
    scan = load_scan(obj, csv, axes="-x,y,z")
    assert_same_scan(scan, v, lm, atol=1e-8)
    model = build_face_file(obj, csv, tmp_path / "f.npz", axes="-x,y,z").data
    np.testing.assert_allclose(model.rest_positions, ref.rest_positions, atol=1e-6)


def test_a_tilted_scan_asks_for_its_axes(generic, tmp_path):
    v, f, lm, _ = generic
    a = np.radians(45.0)
    turn = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    obj, csv = write_scan(tmp_path, v @ turn.T, f, {k: turn @ p for k, p in lm.items()})
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    text = one_line(exc, "scan_lm.csv: field 'axes'", "degrees from every axis", "--axes")
    assert float(text.split(" degrees")[0].split()[-1]) == pytest.approx(45.0, abs=3.0)


# ---- scans as they come -----------------------------------------------------------------------
def test_texture_seams_are_merged_and_the_texture_kept(generic, tmp_path):
    v, f, lm, ref = generic
    chart = (v[f].mean(axis=1)[:, 0] >= 0).astype(float)  # two charts: a seam on the midline
    lo, hi = v.min(axis=0), v.max(axis=0)
    s, t = ((v[:, k] - lo[k]) / (hi[k] - lo[k]) for k in (0, 1))
    uv = np.stack([0.02 + 0.46 * s[f] + 0.5 * chart[:, None], 0.02 + 0.96 * t[f]], axis=-1)
    written = write_obj(tmp_path / "scan.obj", v * 1e3, f, uv=uv, material="scan")
    (tmp_path / "scan.mtl").write_text("newmtl skin\nKd 1 1 1\nmap_Kd skin.png\n")
    Image.fromarray(np.full((8, 8, 3), 200, np.uint8)).save(tmp_path / "skin.png")
    write_landmark_csv(tmp_path / "lm.csv", lm)
    assert written > len(v) + 20  # the seam's positions are written twice
    out = build_face_file(tmp_path / "scan.obj", tmp_path / "lm.csv", tmp_path / "f.npz")
    model = out.data
    assert model.n_surface == ref.n_surface  # the merged vertices come in another order
    dist, _ = cKDTree(ref.rest_positions).query(model.rest_positions)
    assert dist.max() < 1e-6 and len(model.muscles) == len(ref.muscles)
    for k, node in model.landmarks.items():
        np.testing.assert_allclose(model.rest_positions[node],
                                   ref.rest_positions[ref.landmarks[k]], atol=1e-6)
    assert model.appearance.uv.shape == (len(model.faces), 3, 2)
    assert "texture" in out.line


def test_loose_fragments_are_dropped_with_a_note(generic, tmp_path):
    v, f, lm, ref = generic
    # two specks floating behind the head (5 and 2 triangles) and a vertex nothing uses
    speck = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 2, 0], [4, 0, 0], [4, 2, 0]]) * 1e-3
    tris = np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3], [4, 5, 3], [3, 5, 2]])
    v2 = np.concatenate([v, speck + [0.0, 0.0, -0.05], speck[:4] + [0.03, 0.0, -0.05],
                         [[0.0, 0.0, -0.1]]])
    f2 = np.concatenate([f, tris + len(v), tris[:2] + len(v) + 6])
    obj, csv = write_scan(tmp_path, v2, f2, lm)
    scan = load_scan(obj, csv)
    assert len(scan.notes) == 1 and scan.notes[0].startswith(
        "scan.obj: dropped 2 loose fragments (7 triangles, ")
    assert_same_scan(scan, v, lm, atol=1e-8)
    np.testing.assert_array_equal(scan.faces, f)
    model = build_face_file(obj, csv, tmp_path / "f.npz").data
    assert model.n_surface == ref.n_surface
    # a second piece as large as a face is not a fragment
    obj, csv = write_scan(tmp_path, np.concatenate([v, v + [0.3, 0, 0]]),
                          np.concatenate([f, f + len(v)]), lm, name="two")
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "two.obj: field 'faces'", "2 pieces", "50 % of its area")


def test_a_capped_head_is_cropped_to_the_face_and_a_ball_refused(tmp_path, generic):
    import trimesh

    from facemech.geometry.mesh import boundary_nodes

    v, f, lm, model = generic
    # the face closed by a cap: every rim edge fanned to a point 300 mm behind the face
    apex = len(v)
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    inner = {(int(a), int(b)) for a, b in directed}
    cap = np.array([[b, a, apex] for a, b in directed if (int(b), int(a)) not in inner])
    closed = np.concatenate([f, cap])
    assert len(boundary_nodes(closed)) == 0
    obj, csv = write_scan(tmp_path, np.vstack([v, [0.0, -0.05, -0.3]]), closed, lm)
    scan = load_scan(obj, csv)
    assert any("cropped to the face" in n for n in scan.notes), scan.notes
    assert_same_scan(scan, v, lm, atol=2e-9)
    # a ball is not a head: its landmarks lie off whatever is left of it
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    obj, csv = write_scan(tmp_path, np.asarray(ball.vertices), np.asarray(ball.faces), lm,
                          name="ball")
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "ball_lm.csv: field", "from the surface")


def test_degenerate_triangles_are_refused_naming_the_region(generic, tmp_path):
    v, f, lm, _ = generic
    v2 = v.copy()
    k = int(np.argmin(np.linalg.norm(v - lm["cheek_left"], axis=1)))
    nb = f[np.any(f == k, axis=1)].ravel()
    nb = nb[nb != k][0]
    v2[k] = v[nb] + 0.3 * (v[k] - v[nb]) / np.linalg.norm(v[k] - v[nb]) * 1e-4  # 0.03 mm away
    obj, csv = write_scan(tmp_path, v2, f, lm)
    with pytest.raises(InputError) as exc:
        load_scan(obj, csv)
    one_line(exc, "scan.obj: field 'faces'", "degenerate triangle", "near cheek_left",
             "edge 0.030 mm")


# ---- iBUG 68 ----------------------------------------------------------------------------------
def test_ibug68_of_the_generic_face_map_to_its_landmarks(generic):
    v, f, lm, _ = generic
    mapped = ibug_to_landmarks(generic_ibug68(), v, f)
    assert list(mapped) == list(lm)
    for k in lm:
        assert np.linalg.norm(mapped[k] - lm[k]) < 0.5e-3, k
    for k, i in DIRECT.items():
        np.testing.assert_array_equal(mapped[k], generic_ibug68()[i])


def test_ibug68_follow_another_face():
    """The reshaped scan-like face: its iBUG points give its own landmarks within 1 mm."""
    v, f, lm = scan_face()
    mapped = ibug_to_landmarks(reshape(generic_ibug68()), v, f)
    for k in lm:
        assert np.linalg.norm(mapped[k] - lm[k]) < 1e-3, k


def test_ibug_files_round_trip_and_build_the_same_face(generic, tmp_path):
    v, f, lm, ref = generic
    pts = generic_ibug68()
    write_pts(tmp_path / "lm.pts", pts)
    text = (tmp_path / "lm.pts").read_text().splitlines()
    assert text[:3] == ["version: 1", "n_points: 68", "{"] and text[-1] == "}"
    back = read_ibug68(tmp_path / "lm.pts")
    np.testing.assert_allclose(back, pts, atol=1e-9)
    (tmp_path / "lm.ljson").write_text(json.dumps(
        {"version": 2, "landmarks": {"points": (pts * 1e3).tolist(), "connectivity": []},
         "labels": []}))
    rows = "".join(f"{i + 1},{p[0]:.9f},{p[1]:.9f},{p[2]:.9f}\n" for i, p in
                   enumerate(pts * 1e3))
    (tmp_path / "lm68.csv").write_text("index,x,y,z\n" + rows)
    for name in ("lm.ljson", "lm68.csv"):
        np.testing.assert_allclose(read_ibug68(tmp_path / name), pts, atol=1e-9)
    obj = tmp_path / "scan.obj"
    write_obj(obj, v * 1e3, f)
    out = build_face_file(obj, tmp_path / "lm.pts", tmp_path / "f.npz")
    assert "68 iBUG points" in out.warnings
    model = out.data
    assert model.n_surface == ref.n_surface and len(model.muscles) == len(ref.muscles)
    assert np.abs(model.rest_positions - ref.rest_positions).max() < 1e-3
    assert model.landmarks == ref.landmarks


def test_2d_and_short_ibug_files_are_refused(tmp_path):
    xy = generic_ibug68()[:, :2] * 1e3
    (tmp_path / "a.pts").write_text("version: 1\nn_points: 68\n{\n"
                                    + "".join(f"{x} {y}\n" for x, y in xy) + "}\n")
    with pytest.raises(InputError) as exc:
        read_ibug68(tmp_path / "a.pts")
    one_line(exc, "a.pts: field 'points'", "2-D iBUG points")
    (tmp_path / "b.pts").write_text("version: 1\nn_points: 68\n{\n1 2 3\n}\n")
    with pytest.raises(InputError) as exc:
        read_ibug68(tmp_path / "b.pts")
    one_line(exc, "b.pts: field 'n_points'", "n_points says 68, the file holds 1")
    (tmp_path / "c.ljson").write_text(json.dumps({"landmarks": {"points": [[1, 2]] * 68}}))
    with pytest.raises(InputError) as exc:
        read_ibug68(tmp_path / "c.ljson")
    one_line(exc, "c.ljson: field 'landmarks'", "2-D")


# ---- through the command line (as it is: --units, no --axes yet) ------------------------------
def test_face_build_command_refuses_in_one_line_and_reads_ibug(generic, tmp_path, monkeypatch,
                                                               capsys):
    from conftest import run_cli

    v, f, lm, ref = generic
    obj, csv = write_scan(tmp_path, v, f, lm, scale=1e2)  # cm, declared mm by default
    out = tmp_path / "f.npz"
    code, _, err = run_cli(monkeypatch, capsys, "face", "build", obj, csv, "-o", out)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith(f"facemech: error: {obj}: field 'units'")
    assert "use --units cm" in lines[0] and not out.exists()
    write_pts(tmp_path / "lm.pts", generic_ibug68() * 1e-1)  # cm, like the surface
    code, text, err = run_cli(monkeypatch, capsys, "face", "build", obj, tmp_path / "lm.pts",
                              "-o", out, "--units", "cm")
    assert code == 0, err
    assert f"{ref.n_surface} nodes per layer" in text and out.exists()
