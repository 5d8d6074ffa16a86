"""Face-model workflows: build a face from a scan, describe one, export the built-in template."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from ..progress import StagedProgress
from .outcome import Written


def build_face_file(surface: str | Path, landmarks: str | Path, output: str | Path, *,
                    units: str | None = "mm", axes: str | None = None, name: str | None = None,
                    tissue: str = "anatomical", progress: StagedProgress | None = None):
    """Build a three-layer face model from a surface mesh and landmarks; save it to ``output``.

    The scan is read and checked by :func:`~facemech.geometry.scan.load_scan`: its unit against
    its size, its axes from the landmarks, loose fragments dropped, and the landmarks on the
    skin, unique and with the subject's left on the left.

    Parameters
    ----------
    surface : OBJ (with its MTL and texture image beside it), PLY or STL of the face; a textured
        OBJ or a PLY with vertex colours keeps its look in the model
    landmarks : landmark CSV ``name,x,y,z``, or 68 iBUG points (``.pts``, ``.ljson``, CSV of 68
        rows ``x,y,z``)
    output : the model file (``.npz``), written atomically
    units : length unit of both files (``m``, ``cm``, ``mm`` or ``um``); None or ``auto``
        infers it from the scan's size
    axes : the file's axes for facemech's x (left), y (up), z (forward), e.g. ``"x,z,-y"``; None
        detects them from the landmarks
    name : model name (default: the surface file's stem)
    tissue : tissue geometry, ``anatomical`` or ``uniform``
    progress : staged callback; reports the stage ``build`` (0 then 1 of 1)

    Returns
    -------
    Written : ``data`` the :class:`~facemech.geometry.model.FaceModel`; its line gives nodes per
        layer, springs, prisms, muscles and appearance; ``warnings`` the scan's notes
        ("facemech: note: ..." lines: a unit inferred, axes turned, fragments dropped)
    """
    from ..atomic import check_output
    from ..geometry.builder import build_face, tissue_options
    from ..geometry.scan import load_scan

    surface = Path(surface)
    check_output(output, [surface, landmarks], field="-o")
    opts = tissue_options(tissue)
    if progress is not None:
        progress("build", 0, 1)
    scan = load_scan(surface, landmarks, units=None if units == "auto" else units, axes=axes)
    model = build_face(scan.vertices, scan.faces, scan.landmarks, name=name or surface.stem,
                       source=str(surface), options=opts, appearance=scan.appearance,
                       notes=scan.notes)
    model.save(output)
    if progress is not None:
        progress("build", 1, 1)
    s = model.summary()
    return Written(Path(output), model,
                   f"built {s['name']}: {s['nodes_per_layer']['epidermis']} nodes per layer, "
                   f"{s['springs']} springs, {s['prisms']} prisms, {s['muscles']} muscles, "
                   f"appearance: {s['appearance']} -> {output}",
                   "".join(f"facemech: note: {n}\n" for n in scan.notes))


@dataclass(frozen=True)
class FaceInfo:
    """The summary of a face model (:meth:`FaceModel.summary`), as a dict and as text."""

    summary: dict

    def text(self, as_json: bool = False) -> str:
        """JSON, or ``key: value`` lines (nested dicts as ``name value`` pairs)."""
        if as_json:
            return json.dumps(self.summary, indent=2)

        def flat(v) -> str:
            if isinstance(v, dict):
                return ", ".join(f"{k} {flat(x)}" for k, x in v.items())
            if isinstance(v, (list, tuple)):
                return ", ".join(map(str, v))
            return str(v)

        return "\n".join(f"{k.replace('_', ' ')}: {flat(v)}" for k, v in self.summary.items())


def face_info(face: str | Path = "default", *, tissue: str | None = None) -> FaceInfo:
    """Counts of a face model (:meth:`FaceModel.summary`): nodes per layer, springs by kind,
    prisms, muscles, free fascia, extent (mm) and tissue thickness (mm).

    ``face`` is a ``.npz`` file or a built-in face (``default``, ``default-coarse``,
    ``default-fine``); ``tissue`` rebuilds it with that tissue geometry.
    """
    from ..geometry.builder import load_face

    return FaceInfo(load_face(face, tissue=tissue).summary())


def export_default_face(folder: str | Path) -> tuple[Path, Path]:
    """Write the built-in face's surface (``generic_face.obj``, mm) and its landmarks
    (``generic_face_landmarks.csv``, mm) into ``folder``, as a template for ``face build``.

    Returns
    -------
    (obj, landmarks) : the two paths written
    """
    import trimesh

    from ..atomic import atomic_path
    from ..geometry.builder import default_surface
    from ..geometry.surface_io import write_landmarks

    folder = Path(folder)
    v, f, lm = default_surface()
    folder.mkdir(parents=True, exist_ok=True)
    obj, csv = folder / "generic_face.obj", folder / "generic_face_landmarks.csv"
    with atomic_path(obj, suffix=".obj") as tmp:
        trimesh.Trimesh(v * 1e3, f, process=False).export(tmp, file_type="obj")
    write_landmarks(csv, lm)
    return obj, csv
