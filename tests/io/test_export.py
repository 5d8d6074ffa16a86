"""Exports of a result: glTF (morph targets + animation), OBJ/PLY sequences, TRC/C3D markers."""

import json
import struct
import subprocess
import sys

import numpy as np
import pygltflib
import pytest
import trimesh

from conftest import activity, run_cli
from facemech import InputError, load_face, read_markers, read_results, simulate, write_results
from facemech.io.export import (
    export_results,
    vertex_normals,
    write_gltf,
    write_markers,
    write_mesh_sequence,
)
from facemech.physics.model import model as face_model

FRAMES = 19  # 0.3 s at 60 Hz


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    """0.3 s of the coarse face: lips at rest for 5 frames, then OOS and OOI at 0.5."""
    model = load_face("default-coarse")
    act = activity(FRAMES, OOS=0.5, OOI=0.5)
    act[:5] = 0.0
    sim = simulate(face_model(model), act)
    path = tmp_path_factory.mktemp("result") / "r.nc"
    write_results(path, sim)
    return path


@pytest.fixture(scope="module")
def ds(result):
    return read_results(result)


# ---- a small glTF reader over pygltflib: every accessor decoded by the spec ------------------
_DTYPES = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "u1"}
_WIDTH = {"SCALAR": 1, "VEC3": 3}


class Glb:
    def __init__(self, path):
        self.gltf = pygltflib.GLTF2().load(str(path))
        self.blob = self.gltf.binary_blob()

    def _view(self, index, dtype, count, width, offset=0):
        view = self.gltf.bufferViews[index]
        start = (view.byteOffset or 0) + offset
        assert start % np.dtype(dtype).itemsize == 0  # aligned as the spec asks
        return np.frombuffer(self.blob, dtype, count * width, start).reshape(count, width)

    def accessor(self, index) -> np.ndarray:
        acc = self.gltf.accessors[index]
        dtype, width = _DTYPES[acc.componentType], _WIDTH[acc.type]
        if acc.bufferView is None:
            data = np.zeros((acc.count, width), dtype)
        else:
            data = self._view(acc.bufferView, dtype, acc.count, width, acc.byteOffset or 0).copy()
        if acc.sparse is not None:
            sp = acc.sparse
            rows = self._view(sp.indices.bufferView, _DTYPES[sp.indices.componentType], sp.count,
                              1, sp.indices.byteOffset or 0)[:, 0]
            assert np.all(np.diff(rows.astype(int)) > 0)
            data[rows] = self._view(sp.values.bufferView, dtype, sp.count, width,
                                    sp.values.byteOffset or 0)
        return data if width > 1 else data[:, 0]

    def kind(self, index) -> str:
        acc = self.gltf.accessors[index]
        return "sparse" if acc.sparse else ("zero" if acc.bufferView is None else "dense")


def morph_frames(glb: Glb) -> np.ndarray:
    """(frames, nodes, 3) positions: the base mesh and base + each morph target, float32."""
    prim = glb.gltf.meshes[0].primitives[0]
    base = glb.accessor(prim.attributes.POSITION)
    return np.stack([base] + [base + glb.accessor(t["POSITION"]) for t in prim.targets or []])


def check_minmax(glb: Glb, index):
    acc = glb.gltf.accessors[index]
    data = glb.accessor(index)
    np.testing.assert_array_equal(acc.min, data.min(axis=0))
    np.testing.assert_array_equal(acc.max, data.max(axis=0))


# ---- glTF -------------------------------------------------------------------------------------
def test_glb_container_layout(ds, tmp_path):
    path = write_gltf(ds, tmp_path / "a.glb").path
    raw = path.read_bytes()
    magic, version, length = struct.unpack_from("<III", raw)
    assert (magic, version, length) == (0x46546C67, 2, len(raw))
    json_len, json_type = struct.unpack_from("<II", raw, 12)
    assert json_type == 0x4E4F534A and json_len % 4 == 0
    doc = json.loads(raw[20:20 + json_len])
    bin_len, bin_type = struct.unpack_from("<II", raw, 20 + json_len)
    assert bin_type == 0x004E4942 and bin_len % 4 == 0
    assert 28 + json_len + bin_len == len(raw)
    assert doc["buffers"][0]["byteLength"] <= bin_len
    assert all(v["byteOffset"] % 4 == 0 for v in doc["bufferViews"])
    assert doc["asset"]["version"] == "2.0" and doc["asset"]["extras"]["units"] == "m"


def test_gltf_reproduces_every_frame_and_the_timeline(ds, tmp_path):
    path = write_gltf(ds, tmp_path / "a.glb").path
    glb = Glb(path)
    prim = glb.gltf.meshes[0].primitives[0]
    pos = ds["positions"].values
    assert len(prim.targets) == FRAMES - 1
    got = morph_frames(glb)
    np.testing.assert_allclose(got, pos, rtol=0, atol=3e-8)  # float32 at 0.1 m: ulp 7.5e-9
    assert np.abs(pos[-1] - pos[0]).max() > 2e-3  # the lips moved visibly
    kinds = {glb.kind(t["POSITION"]) for t in prim.targets}
    assert "dense" in kinds  # late frames: every node moves
    for index in [prim.attributes.POSITION] + [t["POSITION"] for t in prim.targets]:
        check_minmax(glb, index)
    np.testing.assert_array_equal(glb.accessor(prim.indices).reshape(-1, 3),
                                  ds["triangles"].values)
    normals = glb.accessor(prim.attributes.NORMAL)
    np.testing.assert_allclose(normals, vertex_normals(pos[0], ds["triangles"].values),
                               atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)
    # the animation: the results' times, a one-hot weight per frame, markers by translation
    (anim,) = glb.gltf.animations
    weights = next(c for c in anim.channels if c.target.path == "weights")
    assert weights.target.node == 0 and glb.gltf.nodes[0].mesh == 0
    sampler = anim.samplers[weights.sampler]
    times = glb.accessor(sampler.input)
    np.testing.assert_array_equal(times, ds["time"].values.astype(np.float32))
    assert sampler.interpolation == "LINEAR"
    w = glb.accessor(sampler.output).reshape(FRAMES, FRAMES - 1)
    np.testing.assert_array_equal(w, np.eye(FRAMES, FRAMES - 1, k=-1))
    names = list(ds["marker"].values)
    nodes = {n.name: i for i, n in enumerate(glb.gltf.nodes)}
    for c in anim.channels:
        if c.target.path == "translation":
            m = names.index(glb.gltf.nodes[c.target.node].name)
            np.testing.assert_array_equal(glb.accessor(anim.samplers[c.sampler].output),
                                          ds["markers"].values[:, m].astype(np.float32))
    assert set(names) <= set(nodes)
    assert sum(c.target.path == "translation" for c in anim.channels) == len(names)


def test_gltf_sparse_and_all_zero_targets(ds, tmp_path):
    """A frame equal to frame 0 has no data; a frame where few nodes move is sparse."""
    edited = ds.copy(deep=True)
    pos = edited["positions"].values
    pos[1] = pos[0]
    pos[2] = pos[0]
    pos[2, [3, 40, 41, 500]] += [0.001, -0.002, 0.0005]
    path = write_gltf(edited, tmp_path / "e.glb").path
    glb = Glb(path)
    targets = glb.gltf.meshes[0].primitives[0].targets
    assert glb.kind(targets[0]["POSITION"]) == "zero"
    assert glb.kind(targets[1]["POSITION"]) == "sparse"
    assert glb.gltf.accessors[targets[1]["POSITION"]].sparse.count == 4
    np.testing.assert_allclose(morph_frames(glb), pos, rtol=0, atol=3e-8)
    check_minmax(glb, targets[0]["POSITION"])
    check_minmax(glb, targets[1]["POSITION"])


def test_gltf_loads_in_trimesh(ds, tmp_path):
    path = write_gltf(ds, tmp_path / "a.glb").path
    scene = trimesh.load(path)
    (mesh,) = scene.geometry.values()
    assert len(mesh.vertices) == ds.sizes["node"]
    assert len(mesh.faces) == ds.sizes["triangle"]
    np.testing.assert_allclose(mesh.vertices, ds["positions"].values[0], atol=3e-8)
    assert {str(n) for n in ds["marker"].values} <= set(scene.graph.nodes)


# ---- OBJ / PLY sequences ----------------------------------------------------------------------
@pytest.mark.parametrize(("fmt", "units", "scale", "atol"),
                         [("obj", "m", 1.0, 1e-9), ("ply", "m", 1.0, 3e-8),
                          ("obj", "mm", 1e3, 1e-9)])
def test_mesh_sequence_rereads_every_frame(ds, tmp_path, fmt, units, scale, atol):
    done = write_mesh_sequence(ds, tmp_path / "seq", fmt, units=units)
    assert (done.frames, done.files) == (FRAMES, FRAMES + 1)
    index = json.loads((tmp_path / "seq" / "index.json").read_text())
    assert index["units"] == units and index["frame_rate_hz"] == 60.0
    assert [f["time_s"] for f in index["frames"]] == ds["time"].values.tolist()
    pos = ds["positions"].values
    for k, entry in enumerate(index["frames"]):
        assert entry["file"] == f"frame_{k:05d}.{fmt}"
        mesh = trimesh.load(tmp_path / "seq" / entry["file"], process=False)
        np.testing.assert_allclose(mesh.vertices / scale, pos[k], rtol=0, atol=atol)
        np.testing.assert_array_equal(mesh.faces, ds["triangles"].values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seq"]  # no temporary left


def test_mesh_files_carry_the_frame_note_and_the_ply_layout(ds, tmp_path):
    """trimesh writes the frames; each keeps facemech's note (the OBJ's header, the PLY's only
    comment) and the PLY keeps its layout: float32 x y z, uchar-int faces, little-endian."""
    for fmt in ("obj", "ply"):
        write_mesh_sequence(ds.isel(time=slice(0, 2)), tmp_path / fmt, fmt, units="mm")
    obj = (tmp_path / "obj" / "frame_00001.obj").read_text().splitlines()
    assert obj[0].startswith("# facemech frame 1, t = 0.016667 s, units mm")
    raw = (tmp_path / "ply" / "frame_00001.ply").read_bytes()
    head = raw[: raw.index(b"end_header\n")].decode("ascii").splitlines()
    assert head[:3] == ["ply", "format binary_little_endian 1.0",
                        "comment facemech frame 1, t = 0.016667 s, units mm, +x subject's left, "
                        "+y up, +z forward"]
    assert [h for h in head if h.startswith("comment")] == head[2:3]
    assert head[3:] == [f"element vertex {ds.sizes['node']}", "property float x",
                        "property float y", "property float z",
                        f"element face {ds.sizes['triangle']}",
                        "property list uchar int vertex_indices"]
    n = ds.sizes["node"]
    body = raw[raw.index(b"end_header\n") + 11:]
    xyz = np.frombuffer(body, "<f4", 3 * n).reshape(n, 3)
    np.testing.assert_array_equal(xyz, (ds["positions"].values[1] * 1e3).astype("<f4"))


def test_mesh_sequence_folder_rules(ds, result, tmp_path):
    seq = tmp_path / "seq"
    write_mesh_sequence(ds, seq)
    short = ds.isel(time=slice(0, 3))
    write_mesh_sequence(short, seq, "ply")  # our own previous files: replaced as a whole
    assert sorted(p.name for p in seq.iterdir()) == ["frame_00000.ply", "frame_00001.ply",
                                                     "frame_00002.ply", "index.json"]
    (seq / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="not empty"):
        write_mesh_sequence(ds, seq)
    assert (seq / "notes.txt").read_text() == "mine" and len(list(seq.iterdir())) == 5
    with pytest.raises(InputError, match="not empty"):  # the input's own folder
        write_mesh_sequence(result, result.parent)
    assert read_results(result).sizes["time"] == FRAMES
    with pytest.raises(InputError, match="not a folder"):
        write_mesh_sequence(result, result)
    (tmp_path / "empty").mkdir()
    assert write_mesh_sequence(ds, tmp_path / "empty").files == FRAMES + 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty", "seq"]


def test_export_never_overwrites_its_input(result, tmp_path):
    """A results file is NetCDF whatever its name: one named like an output is still refused."""
    for name in ("in.glb", "in.trc"):
        odd = tmp_path / name
        odd.write_bytes(result.read_bytes())
        with pytest.raises(InputError, match="overwrite the input"):
            export_results(odd, odd)
        assert odd.read_bytes() == result.read_bytes()


# ---- markers ----------------------------------------------------------------------------------
@pytest.mark.parametrize(("suffix", "atol"), [(".trc", 1e-12), (".c3d", 1e-6)])
def test_markers_round_trip(ds, result, tmp_path, suffix, atol):
    path = write_markers(result, tmp_path / f"m{suffix}").path
    ms = read_markers(path)
    assert ms.names == tuple(ds["marker"].values)
    assert ms.rate == 60.0 and ms.source_units == "mm"
    np.testing.assert_allclose(ms.positions, ds["markers"].values, rtol=0, atol=atol)
    np.testing.assert_allclose(ms.time, ds["time"].values, atol=1e-6)


_EZC3D = r"""
import json, sys
import numpy as np
import ezc3d
c = ezc3d.c3d(sys.argv[1])
p = c["parameters"]["POINT"]
print(json.dumps({"rate": float(p["RATE"]["value"][0]), "units": p["UNITS"]["value"][0],
                  "labels": list(p["LABELS"]["value"]),
                  "points": np.asarray(c["data"]["points"])[:3].tolist()}))
"""


def test_c3d_reads_in_ezc3d_directly(ds, tmp_path):
    pytest.importorskip("ezc3d")
    path = write_markers(ds, tmp_path / "m.c3d").path
    # ezc3d can crash the interpreter on bad files, so it reads in a child, as io/c3d.py does
    run = subprocess.run([sys.executable, "-c", _EZC3D, str(path)], capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    assert got["rate"] == 60.0 and got["units"] == "mm"
    assert got["labels"] == list(ds["marker"].values)
    points = np.asarray(got["points"]).transpose(2, 1, 0) * 1e-3  # (frames, markers, 3) m
    np.testing.assert_allclose(points, ds["markers"].values, rtol=0, atol=1e-6)


def test_read_markers_of_a_results_file(ds, result):
    ms = read_markers(result)
    assert ms.names == tuple(ds["marker"].values) and ms.rate == 60.0
    assert ms.source_units == "m" and ms.meta["format"] == "results"
    np.testing.assert_array_equal(ms.positions, ds["markers"].values)
    np.testing.assert_array_equal(ms.time, ds["time"].values)


# ---- command line -----------------------------------------------------------------------------
def test_cli_export_each_suffix(result, ds, tmp_path, monkeypatch, capsys):
    write_gltf(result, tmp_path / "lib.glb")
    for name in ("a.glb", "m.trc", "m.c3d", "m.csv", "frames"):
        code, out, err = run_cli(monkeypatch, capsys, "export", result, "-o", tmp_path / name)
        assert code == 0, err
        assert name in out and f"{FRAMES} frames" in out
    assert (tmp_path / "a.glb").read_bytes() == (tmp_path / "lib.glb").read_bytes()
    assert read_markers(tmp_path / "m.trc").source_units == "mm"
    np.testing.assert_allclose(read_markers(tmp_path / "m.csv").positions,
                               ds["markers"].values, atol=1e-12)
    assert len(list((tmp_path / "frames").glob("frame_*.obj"))) == FRAMES
    code, _, err = run_cli(monkeypatch, capsys, "export", result, "-o", tmp_path / "p.v1",
                           "--format", "ply", "--units", "mm")
    assert code == 0, err
    mesh = trimesh.load(tmp_path / "p.v1" / "frame_00007.ply", process=False)
    np.testing.assert_allclose(mesh.vertices, ds["positions"].values[7] * 1e3, atol=1e-4)


def one_line_error(code, err):
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_cli_export_bad_input(result, tmp_path, monkeypatch, capsys):
    line = one_line_error(*run_cli(monkeypatch, capsys, "export", result, "-o",
                                   tmp_path / "x.xyz")[::2])
    assert "x.xyz" in line and "field '-o'" in line and ".glb" in line
    line = one_line_error(*run_cli(monkeypatch, capsys, "export", tmp_path / "nope.nc", "-o",
                                   tmp_path / "a.glb")[::2])
    assert "nope.nc" in line and "not found" in line
    line = one_line_error(*run_cli(monkeypatch, capsys, "export", result, "-o",
                                   tmp_path / "a.glb", "--units", "mm")[::2])
    assert "--units" in line and "metres" in line
    line = one_line_error(*run_cli(monkeypatch, capsys, "export", result, "-o",
                                   tmp_path / "d", "--format", "stl")[::2])
    assert "--format" in line
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="binary glTF"):
        export_results(result, tmp_path / "a.gltf")


def test_cli_markers_convert_reads_a_results_file(result, ds, tmp_path, monkeypatch, capsys):
    code, out, err = run_cli(monkeypatch, capsys, "markers", "convert", result, tmp_path / "o.trc",
                             "--out-units", "mm")
    assert code == 0, err
    ms = read_markers(tmp_path / "o.trc")
    assert ms.names == tuple(ds["marker"].values) and ms.source_units == "mm"
    np.testing.assert_allclose(ms.positions, ds["markers"].values, rtol=0, atol=1e-12)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info", result, "--json")
    assert code == 0, err
    info = json.loads(out)
    assert info["frames"] == FRAMES and info["rate_hz"] == 60.0 and info["format"] == "results"
