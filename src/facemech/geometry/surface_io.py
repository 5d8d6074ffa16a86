"""Reading face surfaces (OBJ/PLY/STL via trimesh) and landmark CSV files."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import length_scale

REQUIRED_LANDMARKS: tuple[str, ...] = (
    "nose_tip", "subnasale", "upper_lip_center", "lower_lip_center", "mouth_corner_left",
    "mouth_corner_right", "chin", "menton", "cheek_left", "cheek_right", "jaw_angle_left",
    "jaw_angle_right", "brow_left", "brow_right",
)  # fmt: skip


def read_surface(path: str | Path, *, units: str = "mm") -> tuple[np.ndarray, np.ndarray]:
    """Read a triangulated face surface.

    Parameters
    ----------
    path : path to an OBJ, PLY or STL file
    units : length unit of the file's coordinates (default mm)

    Returns
    -------
    vertices : (n, 3) float array, metres
    faces : (f, 3) int array

    Raises
    ------
    InputError
        Unreadable file, no triangles, or a surface that is not an edge-manifold.
    """
    import trimesh

    path = Path(path)
    scale = length_scale(units, source=str(path))
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    try:
        mesh = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise InputError(f"cannot read mesh ({type(exc).__name__}: {exc})", source=str(path),
                         field="geometry") from None
    if not hasattr(mesh, "faces") or len(mesh.faces) == 0:
        raise InputError("no triangles in the mesh", source=str(path), field="faces")
    faces = np.asarray(mesh.faces, dtype=np.int64)
    vertices = np.asarray(mesh.vertices, dtype=float) * scale
    check_manifold(faces, source=str(path))
    return vertices, faces


def check_manifold(faces: np.ndarray, *, source: str | None = None) -> None:
    """Raise if an edge is shared by more than two triangles or the winding is inconsistent."""
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    if np.any(counts > 2):
        raise InputError(f"non-manifold surface: {int(np.sum(counts > 2))} edges shared by more "
                         "than two triangles", source=source, field="faces")
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    if np.any(dcounts > 1):
        raise InputError("inconsistent triangle winding (some neighbours face opposite ways)",
                         source=source, field="faces")


def read_landmarks(path: str | Path, *, units: str = "mm",
                   required: tuple[str, ...] = REQUIRED_LANDMARKS) -> dict[str, np.ndarray]:
    """Read a landmark CSV with columns ``name,x,y,z`` (mm by default).

    Returns
    -------
    dict name -> (3,) array in metres
    """
    path = Path(path)
    scale = length_scale(units, source=str(path))
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    out: dict[str, np.ndarray] = {}
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        cols = [c.strip().lower() for c in (reader.fieldnames or [])]
        for need in ("name", "x", "y", "z"):
            if need not in cols:
                raise InputError("missing column", source=str(path), field=need)
        for lineno, row in enumerate(reader, start=2):
            row = {k.strip().lower(): (v or "").strip() for k, v in row.items() if k}
            try:
                xyz = np.array([float(row["x"]), float(row["y"]), float(row["z"])])
            except ValueError:
                raise InputError(f"line {lineno}: coordinates are not numbers", source=str(path),
                                 field=row.get("name", "?")) from None
            if not np.all(np.isfinite(xyz)):
                raise InputError(f"line {lineno}: non-finite coordinate", source=str(path),
                                 field=row["name"])
            out[row["name"]] = xyz * scale
    missing = [n for n in required if n not in out]
    if missing:
        raise InputError(f"missing landmarks: {', '.join(missing)}", source=str(path),
                         field=missing[0])
    return out


def write_landmarks(path: str | Path, landmarks: dict[str, np.ndarray]) -> None:
    """Write landmarks (metres) as a ``name,x,y,z`` CSV in mm."""
    from ..io.atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "x", "y", "z"])
        for name, p in landmarks.items():
            w.writerow([name, *(f"{1e3 * v:.4f}" for v in p)])
