"""The integer codes the physics reads from a face model: spring kinds, muscle kinds, pulls.

The values are those :mod:`facemech.geometry.builder` stores in ``FaceModel.spring_kind`` and
``Muscles.kind`` (they are part of the face file and never change). The enums name them for
Python code; the plain ``int`` constants below them are what the numba kernels compare with
(numba freezes a module's integer globals into the compiled code).
"""

from __future__ import annotations

from enum import IntEnum


class SpringKind(IntEnum):
    """What a spring joins; the index stored in ``FaceModel.spring_kind``.

    The first four are the seeds' springs (Lucero & Munhall 1999, I.A); the anatomical tissue
    adds the edges of the skull layer where it slides (lips, chin) and the diagonals of the side
    faces of both prism layers, which give the tissue its shear stiffness.
    """

    EPIDERMIS = 0  # an edge of the skin surface
    DERMAL_FATTY = 1  # epidermis -> fascia, one per node (biphasic in the seeds, eq. 1)
    FASCIA = 2  # an edge of the fascia surface
    MUSCLE_LAYER = 3  # fascia -> skull, one per node (seeds: where the fascia is tied)
    SKULL = 4  # an edge of the sliding deep surface, the mucosa (anatomical)
    SUPERFICIAL_DIAGONAL = 5  # epidermis -> fascia across a side face of a prism (anatomical)
    DEEP_DIAGONAL = 6  # fascia -> skull across a side face of a prism (anatomical)


#: the spring kinds that have a stiffness of their own in the seeds' presets, in the order of
#: their constants (``k_epidermis``, ``k_dermal_low``, ``k_fascia``, ``k_muscle_layer``)
SEED_SPRING_KINDS = (SpringKind.EPIDERMIS, SpringKind.DERMAL_FATTY, SpringKind.FASCIA,
                     SpringKind.MUSCLE_LAYER)


class MuscleKind(IntEnum):
    """How a muscle instance runs; the index stored in ``Muscles.kind``."""

    LINEAR = 0  # from an origin on the skull to a weighted insertion
    SPHINCTER = 1  # along a closed or open chain of points (orbicularis oris)


class MusclePull(IntEnum):
    """How a muscle's tension reaches the nodes (``Physics.muscle_pull``)."""

    TOWARDS_ORIGIN = 0  # the seeds': each insertion node pulled towards the origin node
    ALONG_LENGTH = 1  # the continuum's: minus the tension times the gradient of the length,
    # through beads (weighted means of nodes), so the force does work on the length only


# plain integers for the numba kernels
LINEAR: int = MuscleKind.LINEAR.value
SPHINCTER: int = MuscleKind.SPHINCTER.value
PULL_TOWARDS_ORIGIN: int = MusclePull.TOWARDS_ORIGIN.value
PULL_ALONG_LENGTH: int = MusclePull.ALONG_LENGTH.value

__all__ = ["SpringKind", "SEED_SPRING_KINDS", "MuscleKind", "MusclePull", "LINEAR", "SPHINCTER",
           "PULL_TOWARDS_ORIGIN", "PULL_ALONG_LENGTH"]
