"""The integer codes the physics reads from a face model: spring kinds, muscle kinds, pulls.

The spring and muscle kinds are those of :mod:`facemech.geometry.kinds`, the values the
builder stores in ``FaceModel.spring_kind`` and ``Muscles.kind`` (they are part of the face file
and never change). The enums name them for Python code; the plain ``int`` constants below
them are what the numba kernels compare with (numba freezes a module's integer globals into
the compiled code).
"""

from __future__ import annotations

from enum import IntEnum

from ..geometry.kinds import MuscleKind, SpringKind  # the codes are the face file's

#: the spring kinds that have a stiffness of their own in the seeds' presets, in the order of
#: their constants (``k_epidermis``, ``k_dermal_low``, ``k_fascia``, ``k_muscle_layer``)
SEED_SPRING_KINDS = (SpringKind.EPIDERMIS, SpringKind.DERMAL_FATTY, SpringKind.FASCIA,
                     SpringKind.MUSCLE_LAYER)


class MusclePull(IntEnum):
    """How a muscle's tension reaches the nodes (``MuscleBundle.pull``)."""

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
