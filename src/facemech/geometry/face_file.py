"""The face file: a :class:`~.model.FaceModel` in a ``.npz`` archive (docs/formats.md).

The format alone, below the model: :func:`write_face` reads the model's fields by name and
:func:`read_face` hands the fields it read to a constructor that the caller gives
(:meth:`FaceModel.load <facemech.geometry.model.FaceModel.load>` gives the model's own), so this
module imports no model.

Arrays are stored under their field names (the muscles' with a ``muscle_`` prefix, the
surface's with ``surface_``, the appearance's with ``appearance_``); a JSON string ``meta``
holds the names, node maps and counts: ``{"format": "facemech-face", "version": 2, ...}``.
Version 1 files (no sliding nodes, tether, beads or appearance) read with their defaults.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from .appearance import Appearance

FORMAT = "facemech-face"
VERSION = 2
#: the model's arrays stored under their own names
MODEL_ARRAYS = ("rest_positions", "faces", "spring_i", "spring_j", "spring_kind", "prism_nodes",
                "tied_fascia", "skull_normals", "jaw_nodes", "hinge_point", "hinge_axis",
                "lip_pairs", "lip_normals")
#: the muscles' arrays, stored as ``muscle_<name>``
MUSCLE_ARRAYS = ("group", "kind", "origin", "ptr", "nodes", "weights", "rest_length")


def face_arrays(model) -> dict[str, np.ndarray]:
    """Everything the face file holds, as named arrays (``meta``: a JSON string)."""
    arrays = {k: getattr(model, k) for k in MODEL_ARRAYS}
    m = model.muscles
    arrays.update({f"muscle_{k}": getattr(m, k) for k in MUSCLE_ARRAYS})
    arrays["muscle_bead"] = m.beads()
    arrays["muscle_origin_offset"] = m.offsets()
    arrays["jaw_weights"] = model.jaw_weight
    arrays["sliding"] = np.asarray(model.sliding, np.int64)
    arrays["sliding_weights"] = model.sliding_weight
    arrays["sliding_tether"] = (np.ones(len(model.sliding)) if model.sliding_tether is None
                                else np.asarray(model.sliding_tether, float))
    if model.lip_region is not None:
        arrays["lip_region"] = np.asarray(model.lip_region, bool)
    surface_landmarks = None
    if model.surface is not None:
        arrays["surface_vertices"] = np.asarray(model.surface["vertices"], float)
        arrays["surface_faces"] = np.asarray(model.surface["faces"], np.int64)
        surface_landmarks = {k: np.asarray(v, float).tolist()
                             for k, v in model.surface["landmarks"].items()}
    appearance_source = None
    if model.appearance is not None:
        a = model.appearance
        appearance_source = a.source
        for key, value in (("uv", a.uv), ("image", a.image), ("vertex_colours", a.vertex_colours),
                           ("hair", a.hair)):
            if value is not None:
                arrays[f"appearance_{key}"] = value
    meta = {"format": FORMAT, "version": VERSION, "name": model.name,
            "tissue": model.tissue, "n_surface": model.n_surface,
            "muscle_names": list(m.names),
            "landmarks": {k: int(v) for k, v in model.landmarks.items()},
            "markers": {k: int(v) for k, v in model.markers.items()},
            "surface_landmarks": surface_landmarks,
            "appearance_source": appearance_source}
    arrays["meta"] = np.array(json.dumps(meta))
    return arrays


def write_face(model, path: str | Path) -> None:
    """Write ``model`` to a ``.npz`` face file, atomically (temporary file, then rename)."""
    from ..atomic import atomic_path

    arrays = face_arrays(model)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)


def read_face(path: str | Path, make: Callable[[dict, dict], Any]):
    """Read a face file written by :func:`write_face` (format versions 1 and 2).

    Parameters
    ----------
    path : the ``.npz`` file
    make : make(muscles, fields) -> model: the model of the muscles' keyword arguments and the
        model's other fields (the arrays in m, the names, maps and counts)

    Raises
    ------
    InputError
        The file is missing, not a face file, or lacks an array or a metadata field.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        meta = json.loads(str(data.pop("meta")))
    except Exception as exc:
        raise InputError(f"not a facemech face file ({type(exc).__name__})",
                         source=str(path)) from None
    if meta.get("format") != FORMAT:
        raise InputError("not a facemech face file", source=str(path), field="format")
    try:
        return _face_from_arrays(data, meta, str(path), make)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"incomplete facemech face file ({exc})", source=str(path),
                         field="format") from None


def _face_from_arrays(data: dict, meta: dict, source: str, make: Callable[[dict, dict], Any]):
    """The model of a face file's arrays and metadata (``data`` is consumed)."""
    muscles = dict(names=tuple(meta["muscle_names"]),
                   bead=data.pop("muscle_bead", None),
                   origin_offset=data.pop("muscle_origin_offset", None),
                   **{k: data.pop(f"muscle_{k}") for k in MUSCLE_ARRAYS})
    surface = None
    if "surface_vertices" in data:
        surface = {"vertices": data.pop("surface_vertices"),
                   "faces": data.pop("surface_faces"),
                   "landmarks": {k: np.asarray(v, float)
                                 for k, v in meta["surface_landmarks"].items()}}
    appearance = None
    if meta.get("appearance_source") is not None:
        try:
            appearance = Appearance(
                uv=data.pop("appearance_uv", None),
                image=data.pop("appearance_image", None),
                vertex_colours=data.pop("appearance_vertex_colours", None),
                source=meta["appearance_source"], hair=data.pop("appearance_hair", None))
            appearance.check_surface(int(meta["n_surface"]), len(data["faces"]))
        except InputError as exc:
            raise InputError(exc.message, source=source,
                             field=f"appearance_{exc.field}") from None
    return make(muscles, dict(appearance=appearance, n_surface=int(meta["n_surface"]),
                              name=meta["name"],
                              landmarks=meta["landmarks"], markers=meta["markers"],
                              tissue=meta.get("tissue", "uniform"),
                              jaw_weights=data.pop("jaw_weights", None),
                              sliding=data.pop("sliding", np.zeros(0, np.int64)),
                              sliding_weights=data.pop("sliding_weights", None),
                              sliding_tether=data.pop("sliding_tether", None),
                              lip_region=data.pop("lip_region", None), surface=surface,
                              **{k: data[k] for k in MODEL_ARRAYS}))
