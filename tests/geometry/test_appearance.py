"""A textured or coloured scan keeps its look: reading, the mouth cut, face files, results."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree
from typer.testing import CliRunner

from conftest import run_cli as cli
from facemech import InputError, read_results
from facemech.cli import app
from facemech.geometry.appearance import Appearance, appearance_from_dataset
from facemech.geometry.builder import (
    FaceModel,
    build_face,
    for_tissue,
    surface_appearance,
    tissue_options,
)
from facemech.geometry.surface_io import (
    match_triangles,
    read_surface,
    read_surface_with_appearance,
    write_landmarks,
)
from facemech.physics.model import model as face_model
from scans import scan_face

TEX_H, TEX_W = 96, 160


def texture_image() -> np.ndarray:
    """A colour gradient with a checker in blue: every texel tells where it is."""
    rows, cols = np.mgrid[0:TEX_H, 0:TEX_W]
    img = np.zeros((TEX_H, TEX_W, 3), np.uint8)
    img[..., 0] = np.round(255 * cols / (TEX_W - 1))
    img[..., 1] = np.round(255 * rows / (TEX_H - 1))
    img[..., 2] = np.where((rows // 8 + cols // 8) % 2 == 0, 40, 220)
    return img


def scan_uv(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per-corner UVs (f, 3, 2) in two charts split at the midline: a seam through the mouth.

    Triangles whose centroid lies right of the midline (x < 0) take the left half of the image,
    the others the right half, each the whole face's frontal projection.
    """
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    s = (vertices[:, 0] - lo[0]) / (hi[0] - lo[0])
    t = (vertices[:, 1] - lo[1]) / (hi[1] - lo[1])
    chart = (vertices[faces].mean(axis=1)[:, 0] >= 0).astype(float)  # (f,)
    u = 0.02 + 0.46 * s[faces] + 0.5 * chart[:, None]
    v = 0.02 + 0.96 * t[faces]
    return np.stack([u, v], axis=-1)


def write_textured_obj(folder, vertices, faces, uv, *, image=True, reverse=False):
    """OBJ (mm) + MTL + PNG, one ``v`` line per (vertex, texture coordinate) pair as exporters
    write them: the positions on a seam appear twice."""
    if reverse:
        faces, uv = faces[:, ::-1], uv[:, ::-1]
    keys = {}
    corner_index = np.zeros(faces.shape, np.int64)
    for t in range(len(faces)):
        for k in range(3):
            key = (int(faces[t, k]), round(float(uv[t, k, 0]), 6), round(float(uv[t, k, 1]), 6))
            corner_index[t, k] = keys.setdefault(key, len(keys))
    obj = folder / "scan.obj"
    with open(obj, "w") as fh:
        fh.write("mtllib scan.mtl\nusemtl skin\n")
        for vi, _, _ in keys:
            fh.write("v {:.6f} {:.6f} {:.6f}\n".format(*(vertices[vi] * 1e3)))
        for _, u, w in keys:
            fh.write(f"vt {u:.6f} {w:.6f}\n")
        for tri in corner_index + 1:
            fh.write("f " + " ".join(f"{i}/{i}" for i in tri) + "\n")
    (folder / "scan.mtl").write_text("newmtl skin\nKa 1 1 1\nKd 1 1 1\nmap_Kd skin.png\n")
    if image:
        Image.fromarray(texture_image()).save(folder / "skin.png")
    return obj, len(keys)


def position_colours(vertices: np.ndarray) -> np.ndarray:
    """A colour per vertex that is a function of its position."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    return np.round(255 * (vertices - lo) / (hi - lo)).astype(np.uint8)


def write_coloured_ply(path, vertices, faces, colours):
    with open(path, "w") as fh:
        fh.write(f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty float x\n"
                 "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
                 f"property uchar blue\nelement face {len(faces)}\n"
                 "property list uchar int vertex_indices\nend_header\n")
        for p, c in zip(vertices * 1e3, colours, strict=True):
            fh.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {c[0]} {c[1]} {c[2]}\n")
        for a, b, c in faces:
            fh.write(f"3 {a} {b} {c}\n")


@pytest.fixture(scope="module")
def scan():
    # lip-line nodes 2.4 mm apart: the build takes the scan's vertices as they are (a coarser
    # lip line is refined first: tests/geometry/test_refine.py)
    return scan_face(lip_points=25)


@pytest.fixture(scope="module")
def textured(scan, tmp_path_factory):
    """The scan written as a textured OBJ and built through ``facemech face build``."""
    v, f, lm = scan
    d = tmp_path_factory.mktemp("textured")
    uv = scan_uv(v, f)
    obj, n_written = write_textured_obj(d, v, f, uv)
    write_landmarks(d / "lm.csv", lm)
    # capsys is function-scoped: a module-wide fixture runs the command through typer's runner
    res = CliRunner().invoke(app, ["face", "build", str(obj), str(d / "lm.csv"), "-o",
                                   str(d / "face.npz")])
    assert res.exit_code == 0, res.output
    assert "texture 160x96" in res.output
    return {"dir": d, "obj": obj, "uv": uv, "written_vertices": n_written,
            "model": FaceModel.load(d / "face.npz")}


def test_texture_follows_the_skin_through_the_build(scan, textured):
    """At points inside every built triangle (its centroid, and an off-centre point that tells
    the corners apart) the built UVs sample the colour the scan's own UVs give there."""
    v, f, _ = scan
    model, uv0 = textured["model"], textured["uv"]
    look = model.appearance
    assert look is not None and look.textured
    assert np.array_equal(look.image, texture_image())
    assert look.uv.shape == (len(model.faces), 3, 2) and look.uv.dtype == np.float32
    n = model.n_surface
    x = model.rest_positions[:n][model.faces]  # (f, 3, 3) m
    tree = cKDTree(v[f].mean(axis=1))
    for w in (np.full(3, 1 / 3), np.array([0.6, 0.3, 0.1])):
        p = np.einsum("k,tkd->td", w, x)
        uv_built = np.einsum("k,tkd->td", w, look.uv.astype(float))
        _, orig = tree.query(x.mean(axis=1))  # the same triangle of the scan
        a, b, c = (v[f[orig, k]] for k in range(3))
        # barycentric coordinates of p in the scan's triangle (least squares, in the plane)
        m = np.stack([b - a, c - a], axis=-1)  # (f, 3, 2)
        mt = np.swapaxes(m, 1, 2)
        st = np.linalg.solve(mt @ m, (mt @ (p - a)[..., None]))[..., 0]
        bary = np.column_stack([1 - st.sum(axis=1), st])
        assert np.abs(np.einsum("tk,tkd->td", bary, v[f[orig]]) - p).max() < 1e-9
        assert np.all(bary > -1e-6)
        uv_scan = np.einsum("tk,tkd->td", bary, uv0[orig])
        assert np.abs(uv_built - uv_scan).max() < 2e-6
        assert np.array_equal(look.sample(uv_built), Appearance(
            uv=uv0, image=texture_image()).sample(uv_scan))
    # the sampled colour says which chart a triangle is in: right half of the face (x < 0) ->
    # left half of the image (red below 128), left half of the face -> right half
    red = look.sample(look.uv.astype(float).mean(axis=1))[:, 0].astype(int)
    left = x.mean(axis=1)[:, 0] >= 0
    assert np.all(red[~left] < 128) and np.all(red[left] >= 128)


def test_uv_seams_do_not_split_the_geometry(scan, textured):
    v, f, _ = scan
    model = textured["model"]
    n = model.n_surface
    assert textured["written_vertices"] > len(v) + 30  # the file repeats positions on the seam
    pairs = model.lip_pairs[model.lip_pairs[:, 0] < n]
    assert n == len(v) + len(pairs)
    distinct = np.unique(np.round(model.rest_positions[:n] * 1e7), axis=0)
    assert len(distinct) == len(v)
    assert np.allclose(model.rest_positions[pairs[:, 0]], model.rest_positions[pairs[:, 1]])
    assert len(model.faces) == len(f)
    # the surface read back is the scan's: same positions, same triangles
    rv, rf = read_surface(textured["obj"])
    assert len(rv) == len(v) and len(rf) == len(f)
    _, idx = cKDTree(v).query(rv)
    assert np.abs(rv - v[idx]).max() < 1e-9
    assert {tuple(sorted(t)) for t in idx[rf].tolist()} == {tuple(sorted(t)) for t in f.tolist()}


def test_face_file_round_trip_and_info(textured, monkeypatch, capsys):
    model, d = textured["model"], textured["dir"]
    model.save(d / "again.npz")
    back = FaceModel.load(d / "again.npz")
    assert back.appearance == model.appearance
    assert back.appearance.image.dtype == np.uint8
    assert back.appearance.source == str(textured["obj"])
    code, out, err = cli(monkeypatch, capsys, "face", "info", d / "face.npz", "--json")
    assert code == 0, err
    assert json.loads(out)["appearance"] == "texture 160x96"
    code, out, _ = cli(monkeypatch, capsys, "face", "info", "default-coarse", "--json")
    assert json.loads(out)["appearance"] == "none"


def test_results_keep_the_texture(textured, monkeypatch, capsys):
    d, model = textured["dir"], textured["model"]
    with open(d / "act.csv", "w") as fh:
        fh.write("time,OOS,ZYG\n")
        fh.writelines(f"{k / 60:.6f},0.2,0.1\n" for k in range(3))
    code, _, err = cli(monkeypatch, capsys, "simulate", "--face", d / "face.npz", "--activity",
                       d / "act.csv", "-o", d / "r.nc")
    assert code == 0, err
    ds = read_results(d / "r.nc")
    assert ds.sizes["time"] == 3
    look = appearance_from_dataset(ds)
    assert look == model.appearance
    assert ds["texture_image"].dtype == np.uint8 and ds["texture_uv"].dtype == np.float32
    assert np.array_equal(ds["triangles"].values, model.faces)
    assert ds["texture_uv"].dims == ("triangle", "corner", "uv")
    assert "vertex_colour" not in ds


def test_vertex_colours_map_to_the_same_positions(scan, tmp_path, monkeypatch, capsys):
    v, f, lm = scan
    colours = position_colours(v)
    write_coloured_ply(tmp_path / "scan.ply", v, f, colours)
    write_landmarks(tmp_path / "lm.csv", lm)
    code, out, err = cli(monkeypatch, capsys, "face", "build", tmp_path / "scan.ply",
                         tmp_path / "lm.csv", "-o", tmp_path / "f.npz", "--tissue", "uniform")
    assert code == 0, err
    assert "vertex colours" in out
    model = FaceModel.load(tmp_path / "f.npz")
    n = model.n_surface
    look = model.appearance
    assert look.uv is None and look.vertex_colours.shape == (n, 3)
    _, idx = cKDTree(v).query(model.rest_positions[:n])
    assert np.array_equal(look.vertex_colours, colours[idx])  # the lip twins included
    pairs = model.lip_pairs[model.lip_pairs[:, 0] < n]
    assert np.array_equal(look.vertex_colours[pairs[:, 1]], look.vertex_colours[pairs[:, 0]])
    # rebuilt for the other tissue (what a preset does), the colours stay on their nodes
    other = for_tissue(model, "anatomical")
    assert other.tissue == "anatomical" and other.appearance == look
    assert surface_appearance(model).vertex_colours.shape == (len(v), 3)
    # and the results file keeps them
    from conftest import activity
    from facemech.io.results import to_dataset
    from facemech.solvers.forward import simulate

    ds = to_dataset(simulate(face_model(other), activity(2, OOS=0.1)))
    assert appearance_from_dataset(ds) == look and ds["vertex_colour"].dims == ("node", "rgb")
    assert "texture_uv" not in ds


def test_reversed_winding_turns_the_corners_too(scan, tmp_path):
    """A scan wound inwards is turned by the builder: its corners' UVs turn with it."""
    v, f, lm = scan
    uv = scan_uv(v, f)
    obj, _ = write_textured_obj(tmp_path, v, f, uv, reverse=True)
    rv, rf, look = read_surface_with_appearance(obj)
    model = build_face(rv, rf, lm, options=tissue_options("uniform"), appearance=look)
    x = model.rest_positions[model.faces]  # (f, 3, 3)
    # each corner's UV is the scan's UV of the vertex at that corner, in that triangle
    tree = cKDTree(v[f].mean(axis=1))
    _, orig = tree.query(x.mean(axis=1))
    for k in range(3):
        d = np.linalg.norm(v[f[orig]] - x[:, k, None], axis=2)  # (f, 3)
        j = np.argmin(d, axis=1)
        assert np.all(d[np.arange(len(j)), j] < 1e-9)
        assert np.abs(model.appearance.uv[:, k] - uv[orig, j]).max() < 2e-6
    # wound outwards again
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    assert n[:, 2].mean() > 0


def test_missing_texture_image_or_library(scan, tmp_path, monkeypatch, capsys):
    v, f, lm = scan
    obj, _ = write_textured_obj(tmp_path, v, f, scan_uv(v, f), image=False)
    write_landmarks(tmp_path / "lm.csv", lm)
    out = tmp_path / "f.npz"
    code, _, err = cli(monkeypatch, capsys, "face", "build", obj, tmp_path / "lm.csv", "-o", out)
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err
    assert "map_Kd" in lines[0] and "skin.png" in lines[0] and "scan.mtl" in lines[0]
    (tmp_path / "scan.mtl").unlink()
    code, _, err = cli(monkeypatch, capsys, "face", "build", obj, tmp_path / "lm.csv", "-o", out)
    assert code == 2 and "mtllib" in err and "scan.mtl" in err
    assert not out.exists()
    # the geometry alone still reads
    assert len(read_surface(obj)[1]) == len(f)


def test_untextured_surface_has_no_appearance_and_obj_colours_are_read(tmp_path):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    v, f, look = read_surface_with_appearance(tmp_path / "t.obj")
    assert look is None and len(v) == 4 and len(f) == 2
    (tmp_path / "c.obj").write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n"
                                    "v 1 1 0 0.2 0.4 0.6\nf 1 2 3\nf 2 4 3\n")
    v, f, look = read_surface_with_appearance(tmp_path / "c.obj")
    want = {(0, 0): [255, 0, 0], (1, 0): [0, 255, 0], (0, 1): [0, 0, 255], (1, 1): [51, 102, 153]}
    for p, c in zip(np.round(v[:, :2] * 1e3).astype(int), look.vertex_colours, strict=True):
        assert c.tolist() == want[tuple(p)]


def test_appearance_checks_and_texel_convention():
    img = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [9, 9, 9]]], np.uint8)
    uv = np.array([[[0.25, 0.75], [0.75, 0.75], [0.25, 0.25]]])
    a = Appearance(uv=uv, image=img, source="x")
    # OpenGL: v up, origin at the bottom-left; the image's row 0 is its top
    assert a.sample(uv[0]).tolist() == [[255, 0, 0], [0, 255, 0], [0, 0, 255]]
    assert a.sample(np.array([1.0, 0.0])).tolist() == [9, 9, 9]
    rgba = np.concatenate([img, np.full((2, 2, 1), 7, np.uint8)], axis=2)
    assert np.array_equal(Appearance(uv=uv, image=rgba).image, img)
    assert a == Appearance(uv=uv.astype(np.float32), image=img, source="x")
    assert a != Appearance(uv=uv, image=img[::-1], source="x")
    bad = [
        ({"uv": uv}, "image"),
        ({"uv": uv[:, :2], "image": img}, "uv"),
        ({"uv": uv + 0.5, "image": img}, "uv"),
        ({"uv": uv * np.nan, "image": img}, "uv"),
        ({"uv": uv, "image": img[..., :2]}, "image"),
        ({"vertex_colours": np.full((4, 3), 300)}, "vertex_colours"),
        ({"vertex_colours": np.zeros((4, 2))}, "vertex_colours"),
        ({}, "appearance"),
    ]
    for kwargs, field in bad:
        with pytest.raises(InputError) as exc:
            Appearance(**kwargs)
        assert exc.value.field == field, kwargs
    with pytest.raises(InputError, match="triangles"):
        a.check_surface(3, 2)


def grid(n=6):
    """A flat n x n grid of squares (m), two triangles each, and per-vertex UVs."""
    v = np.array([(x, y, 0.0) for y in range(n + 1) for x in range(n + 1)]) * 1e-2
    f = []
    for y in range(n):
        for x in range(n):
            a = y * (n + 1) + x
            f += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    return v, np.array(f), v[:, :2] / v[:, :2].max()


def test_two_materials_share_one_atlas_texel_for_texel(tmp_path):
    """An OBJ with two textured materials (trimesh regroups the triangles by material): every
    triangle samples the texel its own image had at that point."""
    v, f, uv = grid()
    rng = np.random.default_rng(1)
    images = [rng.integers(0, 256, (16, 16, 3), dtype=np.uint8),
              rng.integers(0, 256, (8, 12, 3), dtype=np.uint8)]
    for k, im in enumerate(images):
        Image.fromarray(im).save(tmp_path / f"m{k}.png")
    material = (v[f].mean(axis=1)[:, 0] > v[:, 0].mean()).astype(int)
    lines = ["mtllib m.mtl", *(f"v {x} {y} {z}" for x, y, z in v),
             *(f"vt {a:.6f} {b:.6f}" for a, b in uv)]
    for name, k in (("zeta", 0), ("alpha", 1)):
        lines.append(f"usemtl {name}")
        lines += ["f " + " ".join(f"{i + 1}/{i + 1}" for i in t) for t in f[material == k]]
    (tmp_path / "m.obj").write_text("\n".join(lines) + "\n")
    (tmp_path / "m.mtl").write_text("newmtl zeta\nmap_Kd m0.png\nnewmtl alpha\nmap_Kd m1.png\n")
    rv, rf, look = read_surface_with_appearance(tmp_path / "m.obj", units="m")
    assert len(rv) == len(v) and len(rf) == len(f) and look.image.shape == (24, 16, 3)
    _, orig = cKDTree(v[f].mean(axis=1)).query(rv[rf].mean(axis=1))
    own = [Appearance(uv=uv[f[:1]], image=im) for im in images]
    w = np.array([0.7, 0.2, 0.1])
    p = np.einsum("k,tkd->td", w, rv[rf])
    got = look.sample(np.einsum("k,tkd->td", w, look.uv.astype(float)))
    for t, o in enumerate(orig):
        a, b, c = v[f[o]]
        st = np.linalg.lstsq(np.column_stack([b - a, c - a]), p[t] - a, rcond=None)[0]
        want = own[material[o]].sample(np.array([1 - st.sum(), *st]) @ uv[f[o]])
        assert np.array_equal(got[t], want), t
    # a material without an image: one texel of its diffuse colour
    (tmp_path / "m.mtl").write_text("newmtl zeta\nmap_Kd m0.png\nnewmtl alpha\nKd 0.2 0.4 0.6\n")
    rv, rf, look = read_surface_with_appearance(tmp_path / "m.obj", units="m")
    _, orig = cKDTree(v[f].mean(axis=1)).query(rv[rf].mean(axis=1))
    assert look.image.shape == (17, 16, 3)
    got = look.sample(look.uv.astype(float).mean(axis=1))
    assert np.all(got[material[orig] == 1] == [51, 102, 153])
    assert np.array_equal(got[material[orig] == 0], own[0].sample(
        uv[f[orig[material[orig] == 0]]].mean(axis=1)))


def test_match_triangles_finds_moved_triangles_and_turned_corners():
    v, f, _ = grid(4)
    rng = np.random.default_rng(3)
    order = rng.permutation(len(f))
    turn = rng.integers(0, 3, len(f))
    moved = np.array([np.roll(f[t], -s) for t, s in zip(order, turn, strict=True)])
    tri, corner = match_triangles(v[f], v[moved])
    assert np.array_equal(tri, order)
    assert np.array_equal(f[tri[:, None], corner], moved)
    tri, corner = match_triangles(v[f], v[f])
    assert np.array_equal(tri, np.arange(len(f)))
    with pytest.raises(InputError):
        match_triangles(v[f], v[moved] + 1e-3)
