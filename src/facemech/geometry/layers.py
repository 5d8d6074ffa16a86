"""The three node layers under the skin: where the fascia and the skull layer lie.

Two tissue geometries (:attr:`BuildOptions.tissue`):

``uniform`` (the seeds')
    fascia ``depth_fascia`` (1.5 mm) and skull ``depth_skull`` (2.5 mm) further below the skin
    along its normals, everywhere. The fascia is free (untied from the skull) in an ellipse
    around the mouth and a disc in each cheek; the skull layer never moves.
``anatomical``
    the skull layer lies at the soft-tissue depth of :mod:`tissue` (3 mm on the nasal bridge to
    16 mm in the upper lip and over the buccal teeth), along normals smoothed over about a
    centimetre so that the thick layers do not fold in concave places; the fascia (the plane of
    the mimetic muscles) lies at ``fascia_fraction`` of that depth. Under the lips and the chin
    pad the skull layer is the deep surface of the tissue (labial mucosa, chin fat), which moves
    and slides on the teeth and bone. Where a real head curves more sharply than that (the jaw
    angles, under the chin, the ears), the tissue thins or its offset turns towards the skin's
    normal until no prism folds, and a note says where and by how much (:mod:`thinning`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import tissue
from .kinds import FASCIA, SKULL, layer_nodes
from .mesh import smoothed_normals
from .mouth import MouthCut, uniform_lip_region
from .options import BuildOptions
from .thinning import relieve_folds


@dataclass(frozen=True)
class Layers:
    """The nodes of the three layers at rest and what each part of them does.

    Parameters
    ----------
    rest : (3 n, 3) array, metres
        Epidermis, fascia, skull: node ``i`` and its copies ``i + n``, ``i + 2 n``.
    skull_normals : (3 n, 3) array
        Unit outward direction of the layers' offset, per node (the same in every layer).
    lip_region : (n,) bool
        Epidermal nodes of the lips.
    free : (n,) bool
        Where the fascia is not tied to the skull (the seeds' restoration, eq. 11).
    slides : (n,) bool
        Where the skull layer is the moving deep surface of the tissue (anatomical).
    sliding_tether : (slides.sum(),) array or None
        How firmly each sliding node is held to the bone, a factor on the preset's tether
        stiffness (:func:`tissue.tether_weight`); None where nothing slides (uniform).
    notes : what was changed to keep the layers from folding, one line per place
        (:func:`thinning.relieve_folds`); empty on a face that needs nothing
    """

    rest: np.ndarray
    skull_normals: np.ndarray
    lip_region: np.ndarray
    free: np.ndarray
    slides: np.ndarray
    sliding_tether: np.ndarray | None = None
    notes: tuple[str, ...] = ()

    @property
    def n_surface(self) -> int:
        return len(self.free)

    @property
    def tied(self) -> np.ndarray:
        """Epidermal nodes whose fascia is tied to the skull, sorted."""
        return np.nonzero(~self.free)[0]

    @property
    def tied_fascia(self) -> np.ndarray:
        """The tied fascia nodes (indices into :attr:`rest`)."""
        return layer_nodes(self.tied, FASCIA, self.n_surface)

    @property
    def sliding(self) -> np.ndarray:
        """The sliding skull nodes (indices into :attr:`rest`)."""
        return layer_nodes(np.nonzero(self.slides)[0], SKULL, self.n_surface)


def cheek_discs(vertices: np.ndarray, landmarks: dict[str, np.ndarray],
                radius: float) -> np.ndarray:
    """Nodes within ``radius`` (m) of the point midway between each cheek and mouth corner."""
    out = np.zeros(len(vertices), bool)
    for s in ("left", "right"):
        centre = 0.5 * (landmarks[f"cheek_{s}"] + landmarks[f"mouth_corner_{s}"])
        out |= np.linalg.norm(vertices - centre, axis=1) < radius
    return out


def uniform_layers(mouth: MouthCut, landmarks: dict[str, np.ndarray],
                   opt: BuildOptions) -> Layers:
    """The seeds' layers: constant depths along the skin's normals (Lucero & Munhall 1999, I.A)."""
    v, normals = mouth.vertices, mouth.normals
    fascia = v - opt.depth_fascia * normals
    skull = v - (opt.depth_fascia + opt.depth_skull) * normals
    lip_region = uniform_lip_region(v, mouth.line, landmarks, opt)
    free = lip_region | cheek_discs(v, landmarks, opt.cheek_radius)
    return Layers(rest=np.concatenate([v, fascia, skull]),
                  skull_normals=np.concatenate([normals, normals, normals]),
                  lip_region=lip_region, free=free, slides=np.zeros(len(v), bool))


def anatomical_layers(mouth: MouthCut, generic_xy: np.ndarray, opt: BuildOptions) -> Layers:
    """The anatomical layers: the soft-tissue depth map along smoothed normals.

    Parameters
    ----------
    mouth : the cut surface
    generic_xy : (n, 2) array, mm, generic frontal coordinates of its nodes (:mod:`warp`)
    opt : the build options (``normal_smoothing``, ``fascia_fraction``)
    """
    v = mouth.vertices
    gx, gy = generic_xy[:, 0], generic_xy[:, 1]
    offset, depth, notes = _offsets(v, mouth, generic_xy, opt)
    if _folded(v, mouth, offset, depth, opt).any():
        v, offset, depth, notes = _smoothed(mouth, generic_xy, opt)
    fascia = v - (opt.fascia_fraction * depth)[:, None] * offset
    skull = v - depth[:, None] * offset
    slides = tissue.sliding_region(gx, gy)
    return Layers(rest=np.concatenate([v, fascia, skull]),
                  skull_normals=np.concatenate([offset, offset, offset]),
                  lip_region=tissue.lip_ellipse(gx, gy), free=slides, slides=slides,
                  sliding_tether=tissue.tether_weight(gx[slides], gy[slides]),
                  notes=tuple(notes))


def _offsets(v: np.ndarray, mouth: MouthCut, generic_xy: np.ndarray, opt: BuildOptions):
    """The layers' offsets (n, 3), depths (n,) m and notes of skin nodes ``v`` (n, 3) m."""
    depth = tissue.tissue_depth_mm(generic_xy[:, 0], generic_xy[:, 1]) * 1e-3
    offset = smoothed_normals(v, mouth.faces, opt.normal_smoothing)
    offset[mouth.pairs[:, 1]] = offset[mouth.pairs[:, 0]]  # the slit's twins stay together
    return relieve_folds(v, mouth.faces, offset, depth, opt.fascia_fraction,
                         generic_xy=generic_xy, twins=mouth.pairs)


def _folded(v, mouth, offset, depth, opt) -> np.ndarray:
    """(f,) bool: the triangles whose prisms keep less than :data:`thinning.FOLDING` of a flat
    slab's volume after :func:`thinning.relieve_folds` (as good as folded: a simulation blows
    up there)."""
    from .thinning import FOLDING, prism_quality

    return prism_quality(v, mouth.faces, offset, depth, opt.fascia_fraction) < FOLDING


def _smoothed(mouth: MouthCut, generic_xy: np.ndarray, opt: BuildOptions):
    """Skin nodes, offsets, depths and notes with the skin smoothed where no tissue fits
    (:mod:`skin_smoothing`): the (as good as) folded prisms' nodes and two rings round them,
    more steps and rings in turn; the skin as it is (and no note) if that does not mend it."""
    from . import skin_smoothing as sm

    v0 = mouth.vertices
    offset, depth, notes = _offsets(v0, mouth, generic_xy, opt)
    bad = np.zeros(len(v0), bool)
    bad[mouth.faces[_folded(v0, mouth, offset, depth, opt)]] = True
    adj = sm._neighbours(mouth.faces, len(v0))
    v = v0
    for rings, steps, curve in sm.TRIES:
        v = sm.smooth_region(v0, mouth.faces, sm.grow(adj, bad, rings), mouth.pairs, steps,
                             curve)
        if v is None:
            continue
        offset, depth, notes = _offsets(v, mouth, generic_xy, opt)
        if not _folded(v, mouth, offset, depth, opt).any():
            return v, offset, depth, [*notes, sm.note(v0, v, generic_xy)]
    return v0, *_offsets(v0, mouth, generic_xy, opt)
