"""Reading face surfaces (OBJ/PLY/STL via trimesh), their textures, and landmark CSV files."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..errors import InputError, missing_input
from ..units import length_scale
from .appearance import Appearance

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
    vertices : (n, 3) float array, metres; one vertex per position (texture seams merged)
    faces : (f, 3) int array

    Raises
    ------
    InputError
        Unreadable file, no triangles, or a surface that is not an edge-manifold.
    """
    vertices, faces, _ = _read(Path(path), units, with_appearance=False)
    return vertices, faces


def read_surface_with_appearance(path: str | Path, *, units: str = "mm"
                                 ) -> tuple[np.ndarray, np.ndarray, Appearance | None]:
    """Read a face surface and its look: a texture (OBJ + MTL + image) or vertex colours.

    The geometry is the same as :func:`read_surface`'s: one vertex per position, so that a UV
    seam (one position with two texture coordinates) does not crack the surface. The texture
    coordinates are kept per triangle corner, in the order of the returned ``faces``.

    Parameters
    ----------
    path : path to an OBJ (with ``mtllib``/``map_Kd``, or ``v x y z r g b`` colours), PLY
        (``red green blue`` vertex properties, or a texture) or STL file
    units : length unit of the file's coordinates (default mm)

    Returns
    -------
    vertices : (n, 3) float array, metres
    faces : (f, 3) int array
    appearance : :class:`~facemech.geometry.appearance.Appearance` or None (an untextured,
        uncoloured mesh)

    Raises
    ------
    InputError
        As :func:`read_surface`; also a material library or texture image named by the OBJ
        that is missing (field ``mtllib`` or ``map_Kd``).
    """
    return _read(Path(path), units, with_appearance=True)


def _read(path: Path, units: str, *, with_appearance: bool):
    import trimesh

    scale = length_scale(units, source=str(path))
    if not path.is_file():
        raise missing_input(path)
    if path.suffix.lower() == ".obj":
        try:  # trimesh would guess an encoding (and may need a module that is not there)
            path.read_bytes().decode("utf-8")
        except UnicodeDecodeError:
            raise InputError("binary data where a text OBJ file was expected", source=str(path),
                             field="geometry") from None
    if with_appearance and path.suffix.lower() == ".obj":
        _check_obj_materials(path)
    try:
        loaded = trimesh.load(path, process=False)
        parts = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
        parts = [m for m in parts if isinstance(m, trimesh.Trimesh) and len(m.faces)]
    except ImportError:  # a loader that needs an optional module: the file was not readable
        raise InputError(f"cannot read mesh (not a readable {path.suffix.lstrip('.').upper()} "
                         "file)", source=str(path), field="geometry") from None
    except Exception as exc:  # trimesh raises many types for malformed files
        raise InputError(f"cannot read mesh ({type(exc).__name__}: {exc})", source=str(path),
                         field="geometry") from None
    if not parts:
        raise InputError("no triangles in the mesh", source=str(path), field="faces")
    offsets = np.cumsum([0] + [len(m.vertices) for m in parts])
    raw_vertices = np.concatenate([np.asarray(m.vertices, float) for m in parts])
    raw_faces = np.concatenate([np.asarray(m.faces, np.int64) + o
                                for m, o in zip(parts, offsets, strict=False)])
    for m in parts:  # a face naming a vertex the file does not have
        f = np.asarray(m.faces, np.int64)
        if f.size and (f.min() < 0 or f.max() >= len(m.vertices)):
            bad = int(f.max()) if f.max() >= len(m.vertices) else int(f.min())
            raise InputError(f"a face names vertex {bad}, but the mesh has {len(m.vertices)} "
                             "vertices", source=str(path), field="faces")
    # the geometry alone, its vertices merged by position (texture seams and all)
    mesh = trimesh.Trimesh(raw_vertices, raw_faces, process=True)
    if len(mesh.faces) == 0:
        raise InputError("no triangles in the mesh", source=str(path), field="faces")
    faces = np.asarray(mesh.faces, dtype=np.int64)
    vertices = np.asarray(mesh.vertices, dtype=float)
    check_manifold(faces, source=str(path))
    appearance = None
    if with_appearance:
        appearance = _appearance(parts, raw_vertices, raw_faces, vertices, faces, str(path))
    return vertices * scale, faces, appearance


def _texture(mesh) -> tuple[np.ndarray, np.ndarray] | None:
    """(image (h, w, 3) uint8, per-vertex UVs) of a trimesh, or None if it has no texture."""
    visual = mesh.visual
    if visual.kind != "texture" or visual.uv is None or len(visual.uv) != len(mesh.vertices):
        return None
    material = getattr(visual, "material", None)
    picture = getattr(material, "image", None)
    if picture is None:  # glTF-style materials
        picture = getattr(material, "baseColorTexture", None)
    if picture is None:
        return None
    return np.asarray(picture.convert("RGB"), dtype=np.uint8), np.asarray(visual.uv, float)


def _appearance(parts, raw_vertices, raw_faces, vertices, faces, source) -> Appearance | None:
    """The look of the loaded parts carried onto their merged geometry.

    Several textured parts (one per material) share one atlas: their images stacked top to
    bottom, each keeping its texels; a part without a texture takes a texel of its colour.
    """
    from scipy.spatial import cKDTree

    textures = [_texture(m) for m in parts]
    uv = image = colours = None
    if any(t is not None for t in textures):
        images, uvs = [], []
        for m, t in zip(parts, textures, strict=True):
            if t is None:
                material = getattr(m.visual, "material", None)
                colour = getattr(material, "main_color", None)
                if colour is None:
                    colour = getattr(m.visual, "main_color", (128, 128, 128))
                colour = np.asarray(colour)[:3]
                t = (np.asarray(colour, np.uint8).reshape(1, 1, 3),
                     np.full((len(m.vertices), 2), 0.5))
            images.append(t[0])
            uvs.append(t[1])
        image, vertex_uv = _atlas(images, uvs)
        tri, corner = match_triangles(raw_vertices[raw_faces], vertices[faces], source=source)
        uv = vertex_uv[raw_faces][tri[:, None], corner]
    if any(m.visual.kind == "vertex" for m in parts):
        raw_colours = np.concatenate([np.asarray(m.visual.vertex_colors)[:, :3] for m in parts])
        _, nearest = cKDTree(raw_vertices).query(vertices)
        colours = raw_colours[nearest]
    if uv is None and colours is None:
        return None
    return Appearance(uv=uv, image=image, vertex_colours=colours, source=source)


def _atlas(images: list[np.ndarray], uvs: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """One image from several, stacked top to bottom, and the UVs (OpenGL) moved onto it.

    Every texel keeps its value: a UV that fell in texel (row, col) of its image falls in texel
    (offset + row, col) of the atlas.
    """
    if len(images) == 1:
        return images[0], uvs[0]
    width = max(im.shape[1] for im in images)
    height = sum(im.shape[0] for im in images)
    atlas = np.zeros((height, width, 3), np.uint8)
    out, top = [], 0
    for im, uv in zip(images, uvs, strict=True):
        h, w = im.shape[:2]
        atlas[top:top + h, :w] = im
        u = np.clip(uv[:, 0], 0.0, 1.0) * w / width
        v = 1.0 - (top + (1.0 - np.clip(uv[:, 1], 0.0, 1.0)) * h) / height
        out.append(np.column_stack([u, v]))
        top += h
    return atlas, np.concatenate(out)


def match_triangles(raw_corners: np.ndarray, corners: np.ndarray, *,
                    source: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Which triangle and corner of one mesh each corner of another mesh is.

    Parameters
    ----------
    raw_corners : (F, 3, 3) corner positions of the triangles as loaded
    corners : (G, 3, 3) corner positions of the same triangles after merging vertices

    Returns
    -------
    tri : (G,) index of each triangle in ``raw_corners``
    corner : (G, 3) corner ``k`` of triangle ``g`` is corner ``corner[g, k]`` of ``tri[g]``

    Raises
    ------
    InputError
        A triangle with no match (the merge changed the geometry).
    """
    from scipy.spatial import cKDTree

    extent = float(np.ptp(raw_corners.reshape(-1, 3), axis=0).max()) if raw_corners.size else 1.0
    tol = 1e-6 * max(extent, 1e-12)
    if raw_corners.shape == corners.shape and np.allclose(raw_corners, corners, rtol=0,
                                                          atol=tol):
        return np.arange(len(corners)), np.tile(np.arange(3), (len(corners), 1))
    perms = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
    tree = cKDTree(raw_corners.mean(axis=1))
    k = min(8, len(raw_corners))
    _, near = tree.query(corners.mean(axis=1), k=k)
    near = np.asarray(near).reshape(len(corners), k)
    tri = np.full(len(corners), -1)
    corner = np.zeros((len(corners), 3), np.int64)
    for g in range(len(corners)):
        for t in near[g]:
            d = np.abs(raw_corners[t][perms] - corners[g][None]).max(axis=(1, 2))
            if d.min() <= tol:
                tri[g], corner[g] = t, perms[int(np.argmin(d))]
                break
    if np.any(tri < 0):
        raise InputError(f"{int(np.sum(tri < 0))} triangles changed when their vertices were "
                         "merged: cannot carry the texture over", source=source, field="uv")
    return tri, corner


def _check_obj_materials(path: Path) -> None:
    """Raise if a material library or texture image named by an OBJ file is missing."""
    libraries = []
    with path.open(errors="replace") as fh:
        for line in fh:
            words = line.split()
            if words and words[0] == "mtllib" and len(words) > 1:
                whole = line.strip()[len("mtllib"):].strip()  # one name with spaces, or several
                libraries += [whole] if (path.parent / whole).is_file() else words[1:]
    for name in libraries:
        mtl = path.parent / name
        if not mtl.is_file():
            raise InputError(f"material library {name!r} not found beside the OBJ",
                             source=str(path), field="mtllib")
        with mtl.open(errors="replace") as fh:
            for line in fh:
                words = line.split()
                if not words or words[0] != "map_Kd" or len(words) < 2:
                    continue
                # options come before the name; a name may hold spaces or a Windows folder
                names = (line.strip()[len("map_Kd"):].strip(), words[-1],
                         Path(words[-1].replace("\\", "/")).name)
                if not any((mtl.parent / name).is_file() for name in names):
                    raise InputError(f"texture image {words[-1]!r} not found in {mtl.parent}",
                                     source=str(mtl), field="map_Kd")


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
        raise missing_input(path)
    try:
        return _landmark_rows(path, scale, required)
    except UnicodeDecodeError:
        raise InputError("binary data where a text landmark CSV was expected",
                         source=str(path)) from None
    except csv.Error as exc:
        raise InputError(f"not a readable CSV file ({exc})", source=str(path)) from None


def _landmark_rows(path: Path, scale: float, required) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    with path.open(newline="", encoding="utf-8-sig") as fh:
        reader = csv.DictReader(fh)
        cols = [c.strip().lower() for c in (reader.fieldnames or [])]
        for need in ("name", "x", "y", "z"):
            if need not in cols:
                raise InputError("missing column", source=str(path), field=need)
        for lineno, row in enumerate(reader, start=2):
            row = {k.strip().lower(): (v or "").strip() if isinstance(v, str) else ""
                   for k, v in row.items() if k}
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
    from ..atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "x", "y", "z"])
        for name, p in landmarks.items():
            w.writerow([name, *(f"{1e3 * v:.4f}" for v in p)])
