"""Exports of a simulation result: animated glTF, one mesh file per frame, marker files.

Every function takes a results dataset (:func:`~facemech.io.results.read_results`) or the path of
a results file. Lengths leave in metres unless a unit is asked for; the axes are facemech's (+x
the subject's left, +y up, +z forward, right-handed), which are also glTF's (+Y up, +Z forward,
right-handed), so no coordinate is changed. Files are written atomically and an output never
replaces the input results file.

- :func:`write_gltf`: binary glTF 2.0 (``.glb``): the skin of frame 0 with vertex normals, one
  morph target per later frame (its displacement from frame 0, sparse where that is smaller) and
  one animation on the results' own time line whose ``weights`` switch the targets (linear
  interpolation between frames reproduces linear interpolation of the positions); the markers
  are nodes named by marker with an animated translation.
- :func:`write_mesh_sequence`: ``frame_00000.obj`` (or ``.ply``, each by trimesh's exporter)
  ... and ``index.json`` (frame times, units) in a folder; the folder's atomic replacement, the
  frame's note in each file and the index are facemech's own.
- :func:`write_markers`: the model's markers as TRC, C3D or CSV through the marker writers.

The exports carry the skin (and the markers), not the render-only parts (eyes, teeth, tongue).
A result with a tongue tip series (``tongue_tip``, from ``facemech speak``) carries it as data:
the glTF's ``asset.extras.tongue_tip`` (m, per frame) and, in a mesh sequence, each frame's
``tongue_tip`` in ``index.json`` (in the sequence's units) with its description at the top.
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import atomic_path, pending_folder
from ..errors import InputError
from ..params import FRAME_RATE_HZ
from ..units import length_scale

GLB_MAGIC = 0x46546C67  # "glTF"
CHUNK_JSON = 0x4E4F534A  # "JSON"
CHUNK_BIN = 0x004E4942  # "BIN\0"
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
_COMPONENT = {np.dtype("<f4"): 5126, np.dtype("<u4"): 5125, np.dtype("<u2"): 5123}
_TYPE = {1: "SCALAR", 3: "VEC3"}

SEQUENCE_FORMAT = "facemech-mesh-sequence"
SEQUENCE_FORMATS = ("obj", "ply")
MARKER_SUFFIXES = (".trc", ".c3d", ".csv")


@dataclass(frozen=True)
class Exported:
    """What an export wrote.

    Attributes
    ----------
    path : the file or folder written
    kind : ``"glTF"``, ``"OBJ sequence"``, ``"PLY sequence"``, ``"TRC"``, ``"C3D"``, ``"CSV"``
    frames : number of frames
    files : number of files written
    nbytes : total size, bytes
    """

    path: Path
    kind: str
    frames: int
    files: int
    nbytes: int

    def summary(self) -> str:
        """One line for the command line."""
        what = f"{self.files} files, " if self.files > 1 else ""
        return (f"{self.kind}: {self.frames} frames, {what}{self.nbytes / 1e6:.2f} MB "
                f"-> {self.path}")


# ---- shared helpers -------------------------------------------------------------------------
def _open(results):
    """(dataset, path of the file it came from or None)."""
    from .results import read_results

    if isinstance(results, (str, os.PathLike)):
        path = Path(results)
        return read_results(path), path
    src = getattr(results, "encoding", {}).get("source")
    return results, (Path(src) if src else None)


def _same_file(a: Path, b: Path | None) -> bool:
    return b is not None and a.exists() and b.exists() and os.path.samefile(a, b)


def _refuse_input(output: Path, source: Path | None) -> None:
    if _same_file(output, source):
        raise InputError("the output would overwrite the input results file",
                         source=str(output), field="-o")


def _frames(ds, source: Path | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (frames, nodes, 3) m, triangles (tris, 3) and times (frames,) s, checked."""
    src = None if source is None else str(source)
    pos = ds["positions"].transpose("time", "node", "axis").values.astype(float)
    tris = np.asarray(ds["triangles"].values)
    times = np.asarray(ds["time"].values, float)
    if pos.shape[0] == 0:
        raise InputError("no frames", source=src, field="positions")
    if not np.all(np.isfinite(pos)):
        raise InputError("non-finite positions", source=src, field="positions")
    if tris.ndim != 2 or tris.shape[1] != 3 or tris.min() < 0 or tris.max() >= pos.shape[1]:
        raise InputError("triangles must be (n, 3) node indices", source=src, field="triangles")
    if len(times) > 1 and not np.all(np.diff(times) > 0):
        raise InputError("times must increase strictly", source=src, field="time")
    return pos, tris.astype(np.int64), times


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit vertex normals (n, 3) as :func:`facemech.geometry.builder.vertex_normals`, with
    +z for a vertex without area (glTF wants unit normals everywhere)."""
    from ..geometry.builder import vertex_normals as area_weighted

    n = area_weighted(np.asarray(vertices, float), np.asarray(triangles))
    n[np.linalg.norm(n, axis=1) == 0] = (0.0, 0.0, 1.0)
    return n


# ---- glTF -----------------------------------------------------------------------------------
class _GlbBuffer:
    """The binary chunk of a GLB with its bufferViews and accessors (4-byte aligned)."""

    def __init__(self):
        self.parts: list[bytes] = []
        self.length = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def view(self, data: np.ndarray, target: int | None = None) -> int:
        raw = np.ascontiguousarray(data).tobytes()
        entry = {"buffer": 0, "byteOffset": self.length, "byteLength": len(raw)}
        if target is not None:
            entry["target"] = target
        pad = -len(raw) % 4
        self.parts.append(raw + b"\0" * pad)
        self.length += len(raw) + pad
        self.views.append(entry)
        return len(self.views) - 1

    @staticmethod
    def _index_dtype(limit: int) -> np.dtype:
        return np.dtype("<u2") if limit < 65535 else np.dtype("<u4")

    def accessor(self, data: np.ndarray, *, target: int | None = None, minmax: bool = False,
                 sparse: bool = False) -> int:
        """An accessor over ``data`` (n,) or (n, 3); with ``sparse``, stored as a sparse
        accessor over zeros when that is smaller (or with no data at all if it is all zero)."""
        data = np.ascontiguousarray(data)
        flat = data.reshape(len(data), -1)
        acc = {"componentType": _COMPONENT[data.dtype], "count": len(data),
               "type": _TYPE[flat.shape[1]]}
        if minmax:
            acc["min"] = [v.item() for v in flat.min(axis=0)]
            acc["max"] = [v.item() for v in flat.max(axis=0)]
        rows = np.flatnonzero(np.any(flat != 0, axis=1)) if sparse else None
        if rows is not None and len(rows) == 0:
            pass  # no bufferView: the accessor is all zeros by definition
        elif rows is not None and self._sparse_pays(len(rows), len(data), flat.shape[1]):
            idx_type = self._index_dtype(len(data))
            acc["sparse"] = {
                "count": len(rows),
                "indices": {"bufferView": self.view(rows.astype(idx_type)),
                            "componentType": _COMPONENT[idx_type]},
                "values": {"bufferView": self.view(data[rows])},
            }
        else:
            acc["bufferView"] = self.view(data, target)
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def _sparse_pays(self, stored: int, count: int, width: int) -> bool:
        idx = self._index_dtype(count).itemsize * stored
        return idx + -idx % 4 + 4 * width * stored < 4 * width * count

    def tobytes(self) -> bytes:
        return b"".join(self.parts)


def _glb(document: dict, binary: bytes) -> bytes:
    """A GLB container: 12-byte header, JSON chunk (space padded), BIN chunk (zero padded)."""
    text = json.dumps(document, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return b"".join([struct.pack("<III", GLB_MAGIC, 2, total),
                     struct.pack("<II", len(text), CHUNK_JSON), text,
                     struct.pack("<II", len(binary), CHUNK_BIN), binary])


def _tongue_extras(ds, scale: float, units: str) -> dict:
    """``{"tongue_tip": {...}}``, the results' tongue tip pose per frame (protrusion, elevation
    from rest, the mandible's frame; :func:`~facemech.io.results.results_tongue`) in ``units``
    (``scale`` m each), or ``{}`` for results without it. The exports carry the skin only: the
    tongue travels as this series, for a renderer that draws its own."""
    from .results import TONGUE_AXES, results_tongue

    tongue = results_tongue(ds)
    if tongue is None:
        return {}
    return {"tongue_tip": {"units": units, "axes": list(TONGUE_AXES),
                           "frame": "the mandible's, from the resting tip (protrusion +z, "
                                    "elevation +y); render geometry, not the skin",
                           "values": (tongue / scale).round(9).tolist()}}


def gltf_document(ds, source: Path | None = None) -> tuple[dict, bytes]:
    """The glTF JSON document and binary buffer of a results dataset (see :func:`write_gltf`)."""
    from .._version import __version__

    pos, tris, times = _frames(ds, source)
    n_frames, n_nodes = pos.shape[:2]
    if times[0] < 0:
        raise InputError("glTF animation times must not be negative", field="time",
                         source=None if source is None else str(source))
    p32 = pos.astype("<f4")
    base = p32[0]
    buf = _GlbBuffer()
    attributes = {
        "POSITION": buf.accessor(base, target=ARRAY_BUFFER, minmax=True),
        "NORMAL": buf.accessor(vertex_normals(pos[0], tris).astype("<f4"), target=ARRAY_BUFFER),
    }
    index_type = buf._index_dtype(n_nodes)
    primitive = {"attributes": attributes, "mode": 4, "material": 0,
                 "indices": buf.accessor(tris.reshape(-1).astype(index_type),
                                         target=ELEMENT_ARRAY_BUFFER)}
    targets = [{"POSITION": buf.accessor(p32[k] - base, target=ARRAY_BUFFER, minmax=True,
                                         sparse=True)} for k in range(1, n_frames)]
    mesh = {"name": "skin", "primitives": [primitive]}
    if targets:
        primitive["targets"] = targets
        mesh["weights"] = [0.0] * len(targets)
        mesh["extras"] = {"targetNames": [f"frame_{k:05d}" for k in range(1, n_frames)]}

    names = [str(n) for n in ds["marker"].values]
    markers = ds["markers"].transpose("time", "marker", "axis").values.astype("<f4")
    nodes = [{"name": "skin", "mesh": 0},
             {"name": "markers", "children": list(range(2, 2 + len(names)))}]
    nodes += [{"name": n, "translation": [v.item() for v in markers[0, m]]}
              for m, n in enumerate(names)]
    document = {
        "asset": {"version": "2.0", "generator": f"facemech {__version__}",
                  "extras": {"units": "m", "axes": "+x subject's left, +y up, +z forward "
                             "(glTF's own: +Y up, +Z forward, right-handed)",
                             "frame_rate_hz": float(ds.attrs.get("frame_rate_hz", FRAME_RATE_HZ)),
                             "frames": n_frames, "face": str(ds.attrs.get("face", "")),
                             "preset": str(ds.attrs.get("preset", "")),
                             "source": "" if source is None else Path(source).name,
                             "morph_targets": "frame k > 0 is frame 0 plus target k - 1",
                             **_tongue_extras(ds, 1.0, "m")}},
        "scene": 0,
        "scenes": [{"name": "facemech", "nodes": [0, 1]}],
        "nodes": nodes,
        "meshes": [mesh],
        "materials": [{"name": "skin", "doubleSided": True,
                       "pbrMetallicRoughness": {"baseColorFactor": [0.87, 0.70, 0.62, 1.0],
                                                "metallicFactor": 0.0,
                                                "roughnessFactor": 0.6}}],
    }
    if n_frames > 1:
        t = times.astype("<f4")
        t_acc = buf.accessor(t, minmax=True)
        weights = np.zeros((n_frames, n_frames - 1), "<f4")
        weights[np.arange(1, n_frames), np.arange(n_frames - 1)] = 1.0
        samplers = [{"input": t_acc, "interpolation": "LINEAR",
                     "output": buf.accessor(weights.reshape(-1), sparse=True)}]
        channels = [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]
        for m in range(len(names)):
            samplers.append({"input": t_acc, "interpolation": "LINEAR",
                             "output": buf.accessor(markers[:, m])})
            channels.append({"sampler": len(samplers) - 1,
                             "target": {"node": 2 + m, "path": "translation"}})
        document["animations"] = [{"name": "simulation", "samplers": samplers,
                                   "channels": channels}]
    document["accessors"] = buf.accessors
    document["bufferViews"] = buf.views
    binary = buf.tobytes()
    document["buffers"] = [{"byteLength": len(binary)}]
    return document, binary


def write_gltf(results, path: str | Path) -> Exported:
    """Write the animated skin of a result as binary glTF 2.0 (``.glb``).

    Parameters
    ----------
    results : xarray.Dataset or path
        A results dataset or file.
    path : the ``.glb`` file

    Notes
    -----
    Metres and glTF's own axes (+Y up, +Z forward, right-handed), which are facemech's. The mesh
    is frame 0's skin (``triangles`` over ``positions``, float32) with vertex normals; frame k > 0
    is morph target k - 1, the displacement from frame 0 (float32; a sparse accessor when fewer
    than about 6/7 of the nodes move, none when no node moves). The animation ``simulation``
    samples the targets' weights linearly at the results' times (one-hot per frame, all zero at
    frame 0) and moves one node per marker (named by marker) by translation. The normals are
    frame 0's: a viewer does not update them as the skin moves.
    """
    path = Path(path)
    if path.suffix.lower() != ".glb":
        raise InputError("a binary glTF file must end in .glb", source=str(path), field="-o")
    ds, source = _open(results)
    _refuse_input(path, source)
    document, binary = gltf_document(ds, source)
    with atomic_path(path) as tmp:
        tmp.write_bytes(_glb(document, binary))
    return Exported(path, "glTF", len(ds["time"]), 1, path.stat().st_size)


# ---- mesh sequence --------------------------------------------------------------------------
def _trimesh(vertices: np.ndarray, triangles: np.ndarray):
    import trimesh

    return trimesh.Trimesh(vertices, triangles, process=False)  # order kept, nothing merged


def _obj_text(vertices: np.ndarray, triangles: np.ndarray, note: str, scale: float) -> str:
    """An OBJ by trimesh: the note as its header, vertices to 0.1 nm in the file's unit."""
    from trimesh.exchange.obj import export_obj

    digits = max(0, int(round(10 + np.log10(scale))))
    return export_obj(_trimesh(vertices, triangles), include_normals=False,
                      include_color=False, include_texture=False, digits=digits, header=note)


def _ply_bytes(vertices: np.ndarray, triangles: np.ndarray, comment: str) -> bytes:
    """A binary little-endian PLY (float32 vertices) by trimesh, its fixed comment line
    replaced by ``comment``."""
    from trimesh.exchange.ply import export_ply

    data = export_ply(_trimesh(vertices, triangles), encoding="binary",
                      include_attributes=False)
    end = data.index(b"end_header\n")
    head = [line for line in data[:end].decode("ascii").split("\n")
            if not line.startswith("comment")]
    head.insert(2, f"comment {comment}")
    return "\n".join(head).encode("ascii") + data[end:]


def _index_text(index: dict) -> str:
    """JSON of the index with one line per frame."""
    head = json.dumps({k: v for k, v in index.items() if k != "frames"}, indent=1)
    rows = ",\n".join("  " + json.dumps(e) for e in index["frames"])
    return head[:-2] + ',\n "frames": [\n' + rows + "\n ]\n}\n"


def _our_sequence(folder: Path) -> bool:
    """True if the folder holds only a mesh sequence facemech wrote (index.json and its files)."""
    try:
        index = json.loads((folder / "index.json").read_text())
        ours = {"index.json", *(f["file"] for f in index["frames"])}
        if index.get("format") != SEQUENCE_FORMAT:
            return False
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return all(p.name in ours and p.is_file() for p in folder.iterdir())


def _check_folder(folder: Path) -> None:
    if folder.exists() and not folder.is_dir():
        raise InputError("exists and is not a folder", source=str(folder), field="-o")
    if folder.is_dir() and any(folder.iterdir()) and not _our_sequence(folder):
        raise InputError("folder is not empty and holds files that are not a facemech mesh "
                         "sequence (choose another folder)", source=str(folder), field="-o")


def write_mesh_sequence(results, folder: str | Path, fmt: str = "obj", *,
                        units: str = "m") -> Exported:
    """Write one mesh file per frame and an index of the frame times.

    Parameters
    ----------
    results : xarray.Dataset or path
        A results dataset or file.
    folder : the output folder
    fmt : ``"obj"`` (text, vertices to 0.1 nm) or ``"ply"`` (binary little-endian, float32),
        each written by trimesh's exporters
    units : length unit of the vertices: ``m`` (default), ``mm``, ``cm`` or ``um``

    Notes
    -----
    Files ``frame_00000.obj`` ... (frame k at ``time[k]``) with the same triangles (counter-
    clockwise seen from outside) and ``index.json``: format, units, axes, frame rate and
    ``frames`` = [{"file", "time_s"}, ...]. The folder is written beside the target under a
    temporary name and renamed into place, so no half-written sequence is ever seen. An existing
    folder is replaced only if it is empty or holds nothing but a sequence facemech wrote (its
    ``index.json`` and the files it lists); anything else, the input results file included,
    makes it refuse.
    """
    fmt = str(fmt).lower()
    folder = Path(folder)
    if fmt not in SEQUENCE_FORMATS:
        raise InputError(f"unknown mesh format {fmt!r} (expected obj or ply)", field="format")
    scale = length_scale(units, field="units")
    ds, source = _open(results)
    pos, tris, times = _frames(ds, source)
    _check_folder(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    with pending_folder(tmp):  # removed whole if the command is interrupted
        try:
            entries = []
            for k in range(len(pos)):
                name = f"frame_{k:05d}.{fmt}"
                note = (f"facemech frame {k}, t = {times[k]:.6f} s, units {units}, "
                        "+x subject's left, +y up, +z forward")
                if fmt == "obj":
                    (tmp / name).write_text(_obj_text(pos[k] / scale, tris, note, scale))
                else:
                    (tmp / name).write_bytes(_ply_bytes(pos[k] / scale, tris, note))
                entries.append({"file": name, "time_s": float(times[k])})
            tongue = _tongue_extras(ds, scale, units)
            if tongue:  # the tongue tip's pose per frame, beside its mesh file
                for entry, pose in zip(entries, tongue["tongue_tip"]["values"], strict=True):
                    entry["tongue_tip"] = pose
                tongue["tongue_tip"].pop("values")
            index = {"format": SEQUENCE_FORMAT, "version": 1, "mesh_format": fmt, "units": units,
                     "axes": "+x subject's left, +y up, +z forward",
                     "frame_rate_hz": float(ds.attrs.get("frame_rate_hz", FRAME_RATE_HZ)),
                     "nodes": int(pos.shape[1]), "triangles": int(len(tris)),
                     "source": "" if source is None else Path(source).name,
                     **tongue, "frames": entries}
            (tmp / "index.json").write_text(_index_text(index))
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes 0700
            _check_folder(folder)  # again: it may have changed while we wrote
            if folder.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.old.", dir=folder.parent))
                os.replace(folder, old / "previous")
                os.replace(tmp, folder)
                shutil.rmtree(old, ignore_errors=True)
            else:
                os.replace(tmp, folder)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)
    nbytes = sum(p.stat().st_size for p in folder.iterdir())
    return Exported(folder, f"{fmt.upper()} sequence", len(pos), len(pos) + 1, nbytes)


# ---- markers --------------------------------------------------------------------------------
def write_markers(results, path: str | Path, *, units: str = "mm") -> Exported:
    """Write the model's markers of a result as TRC, C3D or CSV (by suffix).

    Parameters
    ----------
    results : xarray.Dataset or path
        A results dataset or file; its ``markers`` (names from the ``marker`` coordinate) at its
        frame rate and times.
    path : ``.trc``, ``.c3d`` or ``.csv``
    units : length unit in the file (default ``mm``, the usual unit of motion capture)

    Notes
    -----
    Uses the project's marker writers (:func:`facemech.io.markers.write_markers`), so the file
    reads back with :func:`facemech.read_markers` and with the formats' other readers.
    """
    from .markers import write_markers as write_marker_file
    from .results import results_markers

    path = Path(path)
    if path.suffix.lower() not in MARKER_SUFFIXES:
        raise InputError(f"markers go to {', '.join(MARKER_SUFFIXES)}", source=str(path),
                         field="-o")
    length_scale(units, field="units")
    ds, source = _open(results)
    _refuse_input(path, source)
    ms = results_markers(ds, source=source)
    write_marker_file(path, ms, units=units)
    return Exported(path, path.suffix[1:].upper(), ms.n_frames, 1, path.stat().st_size)


# ---- dispatch -------------------------------------------------------------------------------
def export_results(results, output: str | Path, *, fmt: str | None = None,
                   units: str | None = None) -> Exported:
    """Export a result by the output's suffix (what ``facemech export`` does).

    Parameters
    ----------
    results : xarray.Dataset or path
    output : ``.glb`` (glTF), ``.trc``, ``.c3d`` or ``.csv`` (markers), or a folder (no suffix,
        or an existing folder) for an OBJ sequence
    fmt : ``"obj"`` or ``"ply"``: a mesh sequence in the folder ``output`` whatever its name
    units : length unit: meshes default to ``m``, markers to ``mm``; glTF is always ``m``

    Raises
    ------
    InputError
        For an unknown suffix (field ``-o``), format (``--format``) or unit (``--units``).
    """
    output = Path(output)
    suffix = output.suffix.lower()
    if fmt is not None:
        if str(fmt).lower() not in SEQUENCE_FORMATS:
            raise InputError(f"unknown format {fmt!r} (expected obj or ply; other formats "
                             "follow the suffix of -o)", field="--format")
        return write_mesh_sequence(results, output, str(fmt).lower(), units=units or "m")
    if suffix == "" or output.is_dir():
        return write_mesh_sequence(results, output, "obj", units=units or "m")
    if suffix == ".glb":
        if units is not None and length_scale(units, field="--units") != 1.0:
            raise InputError("glTF is always in metres", field="--units")
        return write_gltf(results, output)
    if suffix in MARKER_SUFFIXES:
        return write_markers(results, output, units=units or "mm")
    if suffix == ".gltf":
        raise InputError("facemech writes binary glTF: use the suffix .glb", source=str(output),
                         field="-o")
    raise InputError(f"unknown export format {output.suffix!r} (expected .glb, "
                     f"{', '.join(MARKER_SUFFIXES)}, or a folder for an OBJ or PLY sequence)",
                     source=str(output), field="-o")
