"""Blendshape exports: a glTF 2.0 face with named morph targets and their weight animation, and
the per-frame weights as CSV and JSON.

- :func:`blendshape_gltf`: binary glTF (``.glb``): the rest mesh with one morph target per
  shape (its displacement at weight 1; sparse where smaller, no data where zero), the targets'
  names in ``mesh.extras.targetNames`` (the convention Blender's importer and three.js read) and
  one animation ``blendshapes`` that samples the weights linearly at the frames' times.
- :func:`write_weights_csv`: ``time_s`` then one column per shape, one row per frame.
- :func:`write_weights_json`: names, times, weights, the fit's error and the shapes' table.

Metres, facemech's axes (+x the subject's left, +y up, +z forward), which are glTF's own.
Files are written atomically.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from .export import ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER, _glb, _GlbBuffer, vertex_normals


def _check(names, displacement, times, weights) -> None:
    if displacement.shape[0] != len(names):
        raise InputError(f"{displacement.shape[0]} shapes for {len(names)} names",
                         field="displacement")
    if weights.shape != (len(times), len(names)):
        raise InputError(f"weights {weights.shape} for {len(times)} frames and {len(names)} "
                         "shapes", field="weights")
    if len(times) > 1 and not np.all(np.diff(times) > 0):
        raise InputError("times must increase strictly", field="time")
    if len(times) and times[0] < 0:
        raise InputError("glTF animation times must not be negative", field="time")


def blendshape_gltf(rest: np.ndarray, triangles: np.ndarray, names, displacement: np.ndarray,
                    times: np.ndarray, weights: np.ndarray, extras: dict | None = None
                    ) -> bytes:
    """The GLB bytes of a face with named morph targets and their weight animation.

    Parameters
    ----------
    rest : (n, 3) m, the rest mesh's vertices; ``triangles`` (f, 3) node indices
    names : (k,) the targets' names
    displacement : (k, n, 3) m, each target at weight 1
    times : (frames,) s, non-negative and increasing; ``weights`` (frames, k)
    extras : JSON-able, stored as ``asset.extras``
    """
    from .._version import __version__

    rest = np.asarray(rest, float)
    displacement, times = np.asarray(displacement, float), np.asarray(times, float)
    weights, names = np.asarray(weights, float), [str(n) for n in names]
    _check(names, displacement, times, weights)
    buf = _GlbBuffer()
    index_type = buf._index_dtype(len(rest))
    primitive = {
        "attributes": {
            "POSITION": buf.accessor(rest.astype("<f4"), target=ARRAY_BUFFER, minmax=True),
            "NORMAL": buf.accessor(vertex_normals(rest, triangles).astype("<f4"),
                                   target=ARRAY_BUFFER)},
        "indices": buf.accessor(np.asarray(triangles).reshape(-1).astype(index_type),
                                target=ELEMENT_ARRAY_BUFFER),
        "mode": 4, "material": 0,
        "targets": [{"POSITION": buf.accessor(d.astype("<f4"), target=ARRAY_BUFFER,
                                              minmax=True, sparse=True)}
                    for d in displacement]}
    document = {
        "asset": {"version": "2.0", "generator": f"facemech {__version__}",
                  "extras": {"units": "m", "axes": "+x subject's left, +y up, +z forward "
                             "(glTF's own)", **(extras or {})}},
        "scene": 0,
        "scenes": [{"name": "facemech", "nodes": [0]}],
        "nodes": [{"name": "face", "mesh": 0}],
        "meshes": [{"name": "face", "primitives": [primitive], "weights": [0.0] * len(names),
                    "extras": {"targetNames": names}}],
        "materials": [{"name": "skin", "doubleSided": True,
                       "pbrMetallicRoughness": {"baseColorFactor": [0.87, 0.70, 0.62, 1.0],
                                                "metallicFactor": 0.0,
                                                "roughnessFactor": 0.6}}],
    }
    if len(times):
        sampler = {"input": buf.accessor(times.astype("<f4"), minmax=True),
                   "interpolation": "LINEAR",
                   "output": buf.accessor(weights.astype("<f4").reshape(-1))}
        document["animations"] = [{"name": "blendshapes", "samplers": [sampler],
                                   "channels": [{"sampler": 0,
                                                 "target": {"node": 0, "path": "weights"}}]}]
    document["accessors"], document["bufferViews"] = buf.accessors, buf.views
    binary = buf.tobytes()
    document["buffers"] = [{"byteLength": len(binary)}]
    return _glb(document, binary)


def write_blendshape_gltf(path: str | Path, rest, triangles, names, displacement, times,
                          weights, extras: dict | None = None) -> Path:
    """Write :func:`blendshape_gltf` to ``path`` (``.glb``) atomically."""
    path = Path(path)
    if path.suffix.lower() != ".glb":
        raise InputError("a binary glTF file must end in .glb", source=str(path), field="-o")
    data = blendshape_gltf(rest, triangles, names, displacement, times, weights, extras)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return path


def weights_csv_text(names, times, weights) -> str:
    """CSV text: ``time_s`` and one column per shape, weights to 6 decimals."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["time_s", *names])
    for t, row in zip(np.asarray(times, float), np.asarray(weights, float), strict=True):
        writer.writerow([f"{t:.6f}", *(f"{w:.6f}" for w in row)])
    return out.getvalue()


def write_weights_csv(path: str | Path, names, times, weights) -> Path:
    """Write the weights (frames, k) at ``times`` (s) as CSV, atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(weights_csv_text(names, times, weights))
    return path


def write_weights_json(path: str | Path, names, times, weights, info: dict) -> Path:
    """Write ``{"names", "time_s", "weights" (frames x k), **info}`` as JSON, atomically."""
    path = Path(path)
    doc = {"names": [str(n) for n in names],
           "time_s": np.round(np.asarray(times, float), 9).tolist(),
           "weights": np.round(np.asarray(weights, float), 6).tolist(), **info}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(doc, indent=1) + "\n")
    return path


def read_weights_csv(path: str | Path) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(names, times (frames,) s, weights (frames, k)) of a weights CSV."""
    path = Path(path)
    rows = list(csv.reader(path.read_text().splitlines()))
    if not rows or rows[0][:1] != ["time_s"]:
        raise InputError("not a blendshape weights CSV (first column time_s)", source=str(path),
                         field="time_s")
    table = np.array(rows[1:], float).reshape(len(rows) - 1, len(rows[0]))
    return rows[0][1:], table[:, 0], table[:, 1:]
