"""The geometric choices of the model builder (:func:`~.builder.build_face`).

Choices the paper leaves open (SPEC section 6), each a field of :class:`BuildOptions`; lengths
in metres. Two tissue geometries, ``uniform`` (the seeds') and ``anatomical``, each with its
options (:func:`tissue_options`).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .model import TISSUES


@dataclass(frozen=True)
class BuildOptions:
    """Geometric choices of the model builder (lengths in metres).

    ``tissue_options(name)`` gives the options of each tissue geometry.
    """

    tissue: str = "uniform"  # "uniform" (the seeds') or "anatomical"
    depth_fascia: float = 1.5e-3  # uniform: epidermis -> fascia
    depth_skull: float = 2.5e-3  # uniform: fascia -> skull
    fascia_fraction: float = 0.4  # anatomical: depth of the muscle plane / soft-tissue depth
    normal_smoothing: float = 6e-3  # anatomical: m, Gaussian width of the offset directions
    lip_region_half_width: float = 1.25  # x semi-axis of the free lip ellipse, in mouth half-widths
    lip_region_up: float = 1.0  # upward semi-axis, in subnasale-stomion heights
    lip_region_down: float = 0.9  # downward semi-axis, in the same unit
    cheek_radius: float = 14e-3  # m, radius of each free cheek disc (uniform)
    insertion_radius: float = 3.5e-3  # m
    max_insertion_nodes: int = 6  # uniform: nearest nodes sharing a muscle's force
    hinge_behind_jaw_angle: float = 25e-3  # m, condyle behind the (skin) jaw angle landmark
    jaw_band: float = 30e-3  # anatomical: m, width of the jaw-weight blend lateral to the mouth
    jaw_taper: float = 30e-3  # anatomical: m, over which the blend widens from the corner
    sphincter_spacing: float = 6e-3  # anatomical: m, between the beads of orbicularis oris
    sphincter_offset: float = 3.5e-3  # anatomical: m, bead centres from the lip line into the lip
    sphincter_radius: float = 4.5e-3  # anatomical: m, radius of each bead's patch
    #: anatomical: share of each bead's force on the skin, the muscle plane and the deep surface
    sphincter_depth_weights: tuple = (0.0, 0.0, 1.0)
    modiolus: float = 5e-3  # anatomical: m, the first bead lateral to the mouth corner
    modiolus_depth_weights: tuple = (1.0, 1.0, 0.0)  # anatomical: the first bead's layers
    #: anatomical, orbicularis oris's marginal part: its beads' distance from the lip line at
    #: the midline (m; the arch falls to 0 at the corner as the red lip narrows), their patch
    #: radius (m) and their share on the skin, the muscle plane and the deep surface
    marginal_height: float = 3.0e-3
    marginal_radius: float = 3.0e-3
    marginal_depth_weights: tuple = (0.5, 0.5, 0.0)

    @property
    def anatomical(self) -> bool:
        """Whether the tissue geometry is the anatomical one (else the seeds' uniform)."""
        return self.tissue == "anatomical"


def tissue_options(name: str) -> BuildOptions:
    """The build options of a tissue geometry: ``uniform`` (seeds) or ``anatomical``."""
    if name == "uniform":
        return BuildOptions()
    if name == "anatomical":
        return BuildOptions(tissue="anatomical", insertion_radius=7e-3)
    raise InputError(f"unknown tissue geometry {name!r} (expected {', '.join(TISSUES)})",
                     field="tissue")
