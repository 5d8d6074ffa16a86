"""The layered face model as data: geometry and topology, no material constants.

:class:`FaceModel` is what :func:`facemech.geometry.builder.build_face` makes and what the
physics reads; :meth:`FaceModel.save` and :meth:`FaceModel.load` keep it in a ``.npz`` file
(:mod:`facemech.geometry.face_file`). The integer codes it stores are in :mod:`~.kinds`.
A model remembers the surface and landmarks it was built from, so that a preset whose tissue
geometry differs (the seeds' uniform 4-mm layers, or the anatomical thickness map) can rebuild
it (:func:`facemech.geometry.builder.for_tissue`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..params import MUSCLE_GROUPS
from .appearance import Appearance
from .face_file import read_face, write_face
from .kinds import (  # noqa: F401  (re-exported: the model's codes, by their old names)
    EPIDERMIS,
    FASCIA,
    LAYER_NAMES,
    LINEAR,
    SKULL,
    SPHINCTER,
    SPRING_KINDS,
    Layer,
    MuscleKind,
    SpringKind,
    layer_nodes,
)

#: the tissue geometries a face is built with (:class:`~.options.BuildOptions`)
TISSUES = ("uniform", "anatomical")


@dataclass(frozen=True)
class Muscles:
    """Muscle instances of a face (left and right are separate instances).

    Node lists are in CSR form: the insertion (or path) nodes of muscle ``m`` are
    ``nodes[ptr[m]:ptr[m + 1]]`` with weights ``weights[ptr[m]:ptr[m + 1]]``.

    ``bead`` groups the entries of a muscle into the points it acts through: a linear muscle has
    one (its insertion, the weighted mean of its nodes); a sphincter runs through a chain of
    them, in order. The seeds' sphincter has one node per bead (the lip-line nodes); the
    anatomical one a patch of nodes per bead, so that its tension spreads over the lip.
    """

    names: tuple[str, ...]
    group: np.ndarray  # (m,) index into MUSCLE_GROUPS
    kind: np.ndarray  # (m,) MuscleKind: LINEAR or SPHINCTER
    origin: np.ndarray  # (m,) skull node (-1 for sphincters)
    ptr: np.ndarray  # (m + 1,)
    nodes: np.ndarray  # insertion fascia nodes, or the sphincter path in order
    weights: np.ndarray  # share of the force per insertion node (1 on sphincter paths)
    rest_length: np.ndarray  # (m,) metres
    bead: np.ndarray | None = None  # (entries,) bead of each entry within its muscle
    #: (m, 3) m: the origin point is the origin node's position plus this (fixed origins only)
    origin_offset: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.names)

    def offsets(self) -> np.ndarray:
        """Origin offsets (m, 3), metres (zeros by default)."""
        if self.origin_offset is None:
            return np.zeros((len(self.names), 3))
        return np.asarray(self.origin_offset, float)

    def beads(self) -> np.ndarray:
        """Bead of each entry within its muscle (default: one per sphincter node)."""
        if self.bead is not None:
            return np.asarray(self.bead, np.int64)
        out = np.zeros(len(self.nodes), np.int64)
        for m in range(len(self.names)):
            a, b = self.ptr[m], self.ptr[m + 1]
            if self.kind[m] == SPHINCTER:
                out[a:b] = np.arange(b - a)
        return out


def empty_nodes() -> np.ndarray:
    """No nodes: an empty int64 index array."""
    return np.zeros(0, np.int64)


@dataclass(frozen=True)
class FaceModel:
    """A three-layer face: geometry and topology, no material constants.

    Node ``i`` of the epidermis has copies ``i + n_surface`` (fascia) and ``i + 2 n_surface``
    (skull). All positions in metres, +x the subject's left, +y up, +z forward.

    The epidermis and fascia always move. Skull nodes are kinematic (fixed, or turned with the
    mandible by ``jaw_weights``), except the ``sliding`` ones: the deep surface of the lips and
    the chin pad in the anatomical tissue, which move and rest on the teeth and bone without
    passing into them.
    """

    rest_positions: np.ndarray  # (3 n_surface, 3)
    faces: np.ndarray  # (f, 3) epidermal triangles
    n_surface: int
    spring_i: np.ndarray
    spring_j: np.ndarray
    spring_kind: np.ndarray  # (s,) int8 SpringKind (names: SPRING_KINDS)
    prism_nodes: np.ndarray  # (p, 6): top triangle then the one below
    tied_fascia: np.ndarray  # fascia nodes tied to the skull (the seeds' restoration, eq. 11)
    skull_normals: np.ndarray  # (3 n_surface, 3) outward normals of the skull layer at rest
    jaw_nodes: np.ndarray  # skull nodes that turn with the mandible
    hinge_point: np.ndarray  # (3,) a point on the hinge axis
    hinge_axis: np.ndarray  # (3,) unit axis (+x): positive angles open the mouth
    lip_pairs: np.ndarray  # (q, 2) upper-lip node, lower-lip twin (every moving layer)
    lip_normals: np.ndarray  # (q, 3) rest direction from the lower to the upper lip
    muscles: Muscles
    landmarks: dict = field(default_factory=dict)  # name -> epidermal node
    markers: dict = field(default_factory=dict)  # virtual marker name -> epidermal node
    name: str = "face"
    tissue: str = "uniform"  # one of TISSUES
    #: (len(jaw_nodes),) share of the jaw's rotation each jaw node takes, in [0, 1]; None: all 1
    jaw_weights: np.ndarray | None = None
    sliding: np.ndarray = field(default_factory=empty_nodes)  # skull nodes that move
    #: (len(sliding),) share of the jaw's rotation of the bone under each sliding node
    sliding_weights: np.ndarray | None = None
    #: (len(sliding),) how firmly each sliding node is held to the bone, 0 to 1 (None: 1)
    sliding_tether: np.ndarray | None = None
    #: (n_surface,) bool, epidermal nodes of the lips (the free lip region); None: unknown
    lip_region: np.ndarray | None = None
    #: the input the model was built from: vertices (m), faces, landmarks (m), or None
    surface: dict | None = None
    #: the scan's look: texture coordinates per corner of ``faces`` and the image, or a colour
    #: per epidermal node (:mod:`facemech.geometry.appearance`); None for an untextured face
    appearance: Appearance | None = None

    # ---- derived views -------------------------------------------------------------------
    @property
    def n_nodes(self) -> int:
        return self.rest_positions.shape[0]

    @property
    def layer(self) -> np.ndarray:
        """The :class:`Layer` of every node, (n_nodes,) int8."""
        return np.repeat(np.arange(len(Layer), dtype=np.int8), self.n_surface)

    @property
    def free_fascia(self) -> np.ndarray:
        """Fascia nodes not tied to the skull (lips and cheeks)."""
        fascia = layer_nodes(np.arange(self.n_surface), FASCIA, self.n_surface)
        return np.setdiff1d(fascia, self.tied_fascia)

    @property
    def jaw_weight(self) -> np.ndarray:
        """Share of the jaw's rotation of every jaw node, (len(jaw_nodes),) in [0, 1]."""
        if self.jaw_weights is None:
            return np.ones(len(self.jaw_nodes))
        return np.asarray(self.jaw_weights, float)

    @property
    def sliding_weight(self) -> np.ndarray:
        """Share of the jaw's rotation of the bone under each sliding node, in [0, 1]."""
        if self.sliding_weights is None:
            return np.zeros(len(self.sliding))
        return np.asarray(self.sliding_weights, float)

    @property
    def dynamic_nodes(self) -> np.ndarray:
        """Nodes that move under forces: epidermis, fascia and the sliding skull nodes."""
        return np.concatenate([np.arange(layer_nodes(0, SKULL, self.n_surface)),
                               np.sort(np.asarray(self.sliding, np.int64))])

    def skull_node(self, epidermal_node: int) -> int:
        """The skull-layer copy of an epidermal node."""
        return int(layer_nodes(int(epidermal_node), SKULL, self.n_surface))

    def landmark_positions(self) -> dict[str, np.ndarray]:
        return {k: self.rest_positions[v] for k, v in self.landmarks.items()}

    def summary(self) -> dict:
        """Counts a user checks a model by (``facemech face info``)."""
        # the seeds' four kinds always, the anatomical ones where the model has them
        kinds = {k: int(np.sum(self.spring_kind == i)) for i, k in enumerate(SPRING_KINDS)
                 if np.any(self.spring_kind == i) or i <= SpringKind.MUSCLE_LAYER}
        return {
            "name": self.name,
            "tissue": self.tissue,
            "nodes_per_layer": {k: self.n_surface for k in LAYER_NAMES},
            "nodes": self.n_nodes,
            "moving_nodes": int(len(self.dynamic_nodes)),
            "triangles": int(len(self.faces)),
            "springs": int(len(self.spring_i)),
            "springs_by_kind": kinds,
            "prisms": int(len(self.prism_nodes)),
            "muscles": int(len(self.muscles)),
            "muscle_groups": sorted({MUSCLE_GROUPS[g] for g in self.muscles.group}),
            "free_fascia_nodes": int(len(self.free_fascia)),
            "tied_fascia_nodes": int(len(self.tied_fascia)),
            "sliding_skull_nodes": int(len(self.sliding)),
            "jaw_nodes": int(len(self.jaw_nodes)),
            "lip_contact_pairs": int(len(self.lip_pairs)),
            "landmarks": sorted(self.landmarks),
            "markers": list(self.markers),
            "extent_mm": (np.ptp(self.rest_positions[: self.n_surface], axis=0) * 1e3)
            .round(1)
            .tolist(),
            "tissue_thickness_mm": _thickness_summary(self),
            "appearance": "none" if self.appearance is None else self.appearance.describe(),
        }

    # ---- persistence (:mod:`facemech.geometry.face_file`) ----------------------------------
    def save(self, path: str | Path) -> None:
        """Write the model to a ``.npz`` file, atomically (:func:`~.face_file.write_face`)."""
        write_face(self, path)

    @classmethod
    def load(cls, path: str | Path) -> FaceModel:
        """Read a model written by :meth:`save` (:func:`~.face_file.read_face`)."""
        return read_face(path, lambda muscles, fields: cls(muscles=Muscles(**muscles), **fields))


def _thickness_summary(model: FaceModel) -> dict:
    """Skin-to-bone depth (mm) at a few landmarks: what the tissue geometry gave."""
    n = model.n_surface
    rest = model.rest_positions
    depth = np.linalg.norm(rest[:n] - rest[layer_nodes(0, SKULL, n):], axis=1) * 1e3
    out = {"min": round(float(depth.min()), 2), "max": round(float(depth.max()), 2)}
    for name in ("upper_lip_center", "lower_lip_center", "chin", "cheek_right", "nasion"):
        if name in model.landmarks:
            out[name] = round(float(depth[model.landmarks[name]]), 2)
    return out
