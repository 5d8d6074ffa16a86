"""The integer codes a face model stores: layers, spring kinds and muscle kinds.

The values are part of the face file (:mod:`facemech.geometry.face_file`): ``spring_kind`` and
``muscle_kind`` arrays hold them, so they never change. Node ``i`` of the epidermis has the
copy ``i + layer * n_surface`` in each deeper layer (:func:`layer_nodes`).
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np


class Layer(IntEnum):
    """The three node layers of the face (Lucero & Munhall 1999, I.A), outside in."""

    EPIDERMIS = 0
    FASCIA = 1  # the plane of the mimetic muscles
    SKULL = 2  # bone or teeth; in the anatomical tissue, the deep surface of the lips and chin


class SpringKind(IntEnum):
    """What a spring joins; the index stored in ``FaceModel.spring_kind``.

    The first four are the seeds' (Lucero & Munhall 1999, I.A); the anatomical tissue adds the
    edges of the skull layer where it slides (lips, chin), and the diagonals of the side faces of
    both prism layers, which give the tissue its shear stiffness.
    """

    EPIDERMIS = 0  # an edge of the skin surface
    DERMAL_FATTY = 1  # epidermis -> fascia, one per node
    FASCIA = 2  # an edge of the fascia surface
    MUSCLE_LAYER = 3  # fascia -> skull, one per node (uniform: where the fascia is tied)
    SKULL = 4  # an edge of the sliding deep surface (anatomical)
    SUPERFICIAL_DIAGONAL = 5  # epidermis -> fascia across a side face of a prism (anatomical)
    DEEP_DIAGONAL = 6  # fascia -> skull across a side face of a prism (anatomical)


class MuscleKind(IntEnum):
    """How a muscle pulls; the index stored in ``Muscles.kind``."""

    LINEAR = 0  # from an origin node to a weighted insertion
    SPHINCTER = 1  # along a chain of beads (orbicularis oris)


EPIDERMIS, FASCIA, SKULL = Layer.EPIDERMIS, Layer.FASCIA, Layer.SKULL
LAYER_NAMES: tuple[str, ...] = tuple(layer.name.lower() for layer in Layer)
SPRING_KINDS: tuple[str, ...] = tuple(kind.name.lower() for kind in SpringKind)
LINEAR, SPHINCTER = MuscleKind.LINEAR, MuscleKind.SPHINCTER


def layer_nodes(epidermal: np.ndarray | int, layer: Layer, n_surface: int) -> np.ndarray | int:
    """The copies in ``layer`` of epidermal nodes (indices into the model's nodes).

    Parameters
    ----------
    epidermal : int or int array, any shape
        Epidermal node indices, ``0 <= i < n_surface``.
    layer : Layer
    n_surface : int
        Nodes per layer.
    """
    return epidermal + int(layer) * n_surface
