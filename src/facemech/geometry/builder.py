"""Build the three-layer face model from a surface and landmarks (Lucero & Munhall 1999, I.A).

:func:`build_face` is a pipeline of the geometry package's steps:

1. check the surface and wind it so that its normals point out of the face;
2. cut the mouth slit along the lip line (:mod:`mouth`): upper and lower lips become separate
   sheets that touch at rest, and the cut's twins are the lip contact pairs;
3. copy the skin inwards to make the fascia and skull layers (:mod:`layers`), in the
   ``uniform`` (the seeds') or ``anatomical`` tissue geometry (:attr:`BuildOptions.tissue`),
   and join them by springs and prisms (:mod:`topology`);
4. attach the deep layer to the jaw (:mod:`jaw`);
5. place the landmarks, virtual markers and muscles (:mod:`sites`, :mod:`muscle_sites`) by the
   landmark warp from the generic face (:mod:`warp`).

The choices the paper leaves open (SPEC section 6) are the fields of :class:`BuildOptions`.
This module also gives the built-in faces (:func:`default_face`, cached) and faces rebuilt for
another tissue geometry (:func:`for_tissue`).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from . import generic
from .appearance import Appearance
from .jaw import anatomical_bone_weight, attach_jaw, uniform_bone_weight
from .kinds import (  # noqa: F401  (re-exported: the model's codes, by their old names)
    EPIDERMIS,
    FASCIA,
    LAYER_NAMES,
    LINEAR,
    SKULL,
    SPHINCTER,
    SPRING_KINDS,
)
from .layers import Layers, anatomical_layers, uniform_layers
from .mesh import (  # noqa: F401  (re-exported: their old home)
    boundary_nodes,
    smoothed_normals,
    surface_edges,
    vertex_areas,
    vertex_normals,
)
from .model import TISSUES, FaceModel, Muscles  # noqa: F401  (re-exported)
from .mouth import MouthCut, appearance_after_cut, cut_mouth, lip_contact
from .muscle_sites import Attachment, assemble_muscles, muscle_instances
from .options import BuildOptions, tissue_options
from .sites import landmark_nodes, marker_nodes, surface_sites
from .surface_io import REQUIRED_LANDMARKS, check_manifold
from .topology import Topology, anatomical_topology, check_prisms, uniform_topology
from .warp import generic_frontal_mm

_boundary_nodes = boundary_nodes  # the old private name (tests/geometry/test_face.py)
#: a surface with fewer vertices or triangles is too coarse to build a face from
MIN_VERTICES, MIN_TRIANGLES = 200, 300


def build_face(
    vertices: np.ndarray,
    faces: np.ndarray,
    landmarks: dict[str, np.ndarray],
    *,
    options: BuildOptions | None = None,
    name: str = "face",
    source: str | None = None,
    appearance: Appearance | None = None,
    notes: list[str] | None = None,
) -> FaceModel:
    """Build the layered face model from an epidermal surface (metres) and its landmarks.

    Parameters
    ----------
    vertices : (n, 3) array, metres; +x subject's left, +y up, +z forward
    faces : (f, 3) int array; a closed mouth (the lips fused along the lip line)
    landmarks : dict name -> (3,) metres; at least :data:`REQUIRED_LANDMARKS`
    options : geometric choices (default: the seeds' uniform tissue, :class:`BuildOptions`)
    name : the model's name
    source : name of the input, for error messages
    appearance : the surface's texture (UVs per corner of ``faces``) or vertex colours (per
        row of ``vertices``), carried onto the model: the nodes the mouth cut adds take their
        twins' colours, and the triangles keep their corners' texture coordinates
    notes : a list the build appends its notes to: where the tissue was thinned (or its offset
        turned) so that its layers do not fold (:mod:`thinning`), one line each

    Raises
    ------
    InputError
        Unknown tissue, missing landmarks, a surface too coarse, not manifold, open at the
        mouth corners, or folded over itself where the anatomical tissue would fold
        (:mod:`thinning` mends what it can first).
    """
    opt = options or BuildOptions()
    vertices, faces, appearance = checked_surface(vertices, faces, landmarks, opt, source,
                                                  appearance)
    lm = {k: np.asarray(v, float) for k, v in landmarks.items()}
    mouth = cut_mouth(vertices, faces, lm, source)
    layers, topology, bone_weight = tissue_geometry(mouth, lm, opt, source)
    skin = layers.rest[:len(mouth.vertices)]
    if not np.array_equal(skin, mouth.vertices):  # smoothed where no tissue fitted
        mouth = replace(mouth, vertices=skin.copy())
    if notes is not None:
        notes.extend(layers.notes)
    jaw = attach_jaw(bone_weight, layers.slides, lm, opt)
    sites = surface_sites(mouth, lm)
    area = vertex_areas(mouth.vertices, mouth.faces)
    muscles = assemble_muscles(muscle_instances(Attachment(sites, area, layers, jaw), opt))
    lip_pairs, lip_normals = lip_contact(mouth.pairs, mouth.n_surface, deep=opt.anatomical)
    surface = {"vertices": vertices.copy(), "faces": faces.copy(),
               "landmarks": {k: np.asarray(v, float).copy() for k, v in landmarks.items()}}
    return FaceModel(
        rest_positions=layers.rest, faces=mouth.faces, n_surface=mouth.n_surface,
        spring_i=topology.spring_i, spring_j=topology.spring_j,
        spring_kind=topology.spring_kind, prism_nodes=topology.prism_nodes,
        tied_fascia=layers.tied_fascia, skull_normals=layers.skull_normals, jaw_nodes=jaw.nodes,
        hinge_point=jaw.hinge_point, hinge_axis=jaw.hinge_axis, lip_pairs=lip_pairs,
        lip_normals=lip_normals, muscles=muscles, landmarks=landmark_nodes(sites, lm),
        markers=marker_nodes(sites), name=name, tissue=opt.tissue, jaw_weights=jaw.weights,
        sliding=layers.sliding, sliding_tether=layers.sliding_tether,
        sliding_weights=bone_weight[layers.slides] if opt.anatomical else None,
        lip_region=layers.lip_region, surface=surface,
        appearance=appearance_after_cut(appearance, mouth.pairs),
    )


def checked_surface(vertices: np.ndarray, faces: np.ndarray, landmarks: dict[str, np.ndarray],
                    opt: BuildOptions, source: str | None,
                    appearance: Appearance | None) -> tuple[np.ndarray, np.ndarray,
                                                            Appearance | None]:
    """The surface as float vertices (n, 3) m and int64 faces (f, 3), wound outwards.

    Checks the tissue name, the landmarks, the mesh's size and that it is a manifold; reverses
    every triangle (and its texture corners) if the normals point into the face.
    """
    if opt.tissue not in TISSUES:
        raise InputError(f"unknown tissue geometry {opt.tissue!r}", source=source, field="tissue")
    missing = [n for n in REQUIRED_LANDMARKS if n not in landmarks]
    if missing:
        raise InputError(f"missing landmarks: {', '.join(missing)}", source=source,
                         field=missing[0])
    vertices = np.asarray(vertices, float)
    faces = np.asarray(faces, np.int64)
    if len(vertices) < MIN_VERTICES or len(faces) < MIN_TRIANGLES:
        raise InputError(f"surface too coarse ({len(vertices)} vertices)", source=source,
                         field="vertices")
    check_manifold(faces, source=source)
    if appearance is not None:
        appearance.check_surface(len(vertices), len(faces), source=source)
    if vertex_normals(vertices, faces)[:, 2].mean() < 0:
        faces = faces[:, ::-1].copy()
        if appearance is not None and appearance.uv is not None:
            appearance = replace(appearance, uv=appearance.uv[:, ::-1])
    return vertices, faces, appearance


def tissue_geometry(mouth: MouthCut, landmarks: dict[str, np.ndarray], opt: BuildOptions,
                    source: str | None = None) -> tuple[Layers, Topology, np.ndarray]:
    """The layers, their springs and prisms, and the jaw weight (n,) of the bone under each node.

    ``uniform``: the seeds' constant depths. ``anatomical``: the depth map of :mod:`tissue`
    over the generic face's frontal plane, checked for folded prisms.
    """
    if not opt.anatomical:
        layers = uniform_layers(mouth, landmarks, opt)
        return (layers, uniform_topology(mouth.faces, layers),
                uniform_bone_weight(mouth, landmarks))
    generic_xy = generic_frontal_mm(mouth.vertices, landmarks)
    layers = anatomical_layers(mouth, generic_xy, opt)
    topology = anatomical_topology(mouth.faces, layers)
    check_prisms(layers.rest, topology.prism_nodes, source)
    return layers, topology, anatomical_bone_weight(mouth.side, generic_xy, opt)


#: the built-in face at three mesh resolutions: (rows, columns) of :func:`generic.make_surface`
DEFAULT_RESOLUTIONS = {"default-coarse": (38, 31), "default": (48, 41),
                       "default-fine": (62, 53)}
_DEFAULT_CACHE: dict[tuple[str, str], FaceModel] = {}
_REBUILT: OrderedDict = OrderedDict()


def default_surface(resolution: str = "default"):
    """The generic face's surface and landmarks, in metres.

    ``resolution`` is one of :data:`DEFAULT_RESOLUTIONS`: ``default-coarse`` (about 2.6 mm
    between nodes at the lips), ``default`` (about 2 mm) or ``default-fine`` (about 1.5 mm).
    """
    if resolution not in DEFAULT_RESOLUTIONS:
        raise InputError(f"unknown built-in face {resolution!r} (expected "
                         f"{', '.join(DEFAULT_RESOLUTIONS)})", field="face")
    rows, cols = DEFAULT_RESOLUTIONS[resolution]
    surf = generic.make_surface(rows, cols)
    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    return surf.vertices * 1e-3, surf.faces, lm


def default_face(resolution: str = "default", *, tissue: str | None = None) -> FaceModel:
    """The built-in generic adult face, built by :func:`build_face` (cached).

    ``resolution``: ``default-coarse``, ``default`` or ``default-fine``; ``tissue``: the tissue
    geometry, ``anatomical`` (the default preset's) or ``uniform`` (the seeds').
    """
    from ..params import DEFAULT_PRESET, preset

    tissue = tissue or preset(DEFAULT_PRESET).tissue
    key = (resolution, tissue)
    if key not in _DEFAULT_CACHE:
        v, f, lm = default_surface(resolution)
        name = "generic-adult" if resolution == "default" else f"generic-adult-{resolution[8:]}"
        _DEFAULT_CACHE[key] = build_face(v, f, lm, name=name, options=tissue_options(tissue))
    return _DEFAULT_CACHE[key]


def for_tissue(model: FaceModel, tissue: str) -> FaceModel:
    """``model`` with the tissue geometry ``tissue``, rebuilt from its surface if it differs.

    A preset names its tissue geometry (:attr:`facemech.params.Parameters.tissue`); a face
    built for another one is rebuilt from the surface and landmarks it remembers (cached).
    """
    if model.tissue == tissue:
        return model
    for (name, _), face in _DEFAULT_CACHE.items():
        if face is model:
            return default_face(name, tissue=tissue)
    key = (id(model), tissue)
    if key in _REBUILT and _REBUILT[key][0] is model:
        return _REBUILT[key][1]
    if model.surface is None:
        raise InputError(f"face {model.name!r} was built for the {model.tissue} tissue and does "
                         f"not keep its surface: rebuild it (facemech face build) to use the "
                         f"{tissue} tissue", field="face")
    s = model.surface
    rebuilt = build_face(s["vertices"], s["faces"], s["landmarks"], name=model.name,
                         options=tissue_options(tissue), appearance=surface_appearance(model))
    _REBUILT[key] = (model, rebuilt)
    while len(_REBUILT) > 8:
        _REBUILT.popitem(last=False)
    return rebuilt


def load_face(spec: str | Path | None, *, tissue: str | None = None) -> FaceModel:
    """A face from a built-in name or a ``.npz`` written by ``face build``.

    ``spec``: ``None``, ``default``, ``default-coarse``, ``default-fine`` or a path. With
    ``tissue``, the face comes with that tissue geometry (:func:`for_tissue`).
    """
    name = "default" if spec is None else str(spec)
    if name in DEFAULT_RESOLUTIONS:
        return default_face(name, tissue=tissue)
    model = FaceModel.load(spec)
    return model if tissue is None else for_tissue(model, tissue)


def with_options(model: FaceModel, **changes) -> FaceModel:
    """Rebuild ``model`` from its surface with some build options changed."""
    if model.surface is None:
        raise InputError("the face does not keep its surface", field="face")
    s = model.surface
    opt = replace(tissue_options(model.tissue), **changes)
    return build_face(s["vertices"], s["faces"], s["landmarks"], name=model.name, options=opt,
                      appearance=surface_appearance(model))


def surface_appearance(model: FaceModel) -> Appearance | None:
    """The appearance of the surface ``model`` remembers (before the mouth cut).

    The cut appends the lower-lip twins after the surface's vertices and keeps the triangles'
    rows and corners, so the surface's appearance is the model's without the twins' colours.
    """
    a = model.appearance
    if a is None or a.vertex_colours is None or model.surface is None:
        return a
    return replace(a, vertex_colours=a.vertex_colours[: len(model.surface["vertices"])])
