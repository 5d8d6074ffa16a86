"""The arguments of the force kernels as a few typed bundles of flat arrays.

Each bundle is a :class:`typing.NamedTuple` of arrays and numbers, which numba compiles as a
typed tuple (attribute access by name inside the kernels, no cost per call beyond a tuple's).
:class:`~facemech.physics.assembly.Physics` builds them from a face model and holds them
(``physics.forces``, a :class:`ForceBundles`); a test or a small system can make them by name.
Units are SI; ``s`` springs, ``p`` prisms, ``m`` muscle instances, ``e`` muscle entries (node and
weight pairs), ``b`` beads, ``t`` tied nodes, ``c`` lip contact pairs.

The bundles hold what does not change while a simulation runs. What does is passed beside them:
the positions and velocities, the filtered muscle forces, and the :class:`Anchors` of the tied
nodes, which move with the jaw (:func:`facemech.solvers.mandible.place_jaw`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .kinds import PULL_TOWARDS_ORIGIN


class SpringBundle(NamedTuple):
    """The springs of eqs. (1)-(2) and their dashpots (eq. 8).

    Attributes
    ----------
    i, j : (s,) int64 -- the nodes at each end
    rest_length : (s,) m
    k_low : (s,) N/m -- stiffness below the knee (eq. 1, k1), and in compression (eq. 2)
    k_high : (s,) N/m -- stiffness beyond the knee of a biphasic spring (eq. 1, k2)
    biphasic : (s,) bool -- whether the spring follows the biphasic law
    damping : (s,) N s/m -- dashpot on the whole relative velocity of the ends
    knee : float -- strain at the knee of the biphasic law
    sigma : float -- the compression law's sigma (eq. 2); <= 0: mirror of eq. (1) (continuum)
    knee_length : (s,) m -- ``knee * rest_length`` of a biphasic spring, ``inf`` of a linear one
        (:meth:`make` fills it)
    isotropy : float -- the share of each dashpot that acts on the whole relative velocity of
        its ends (eq. 8's form, 1); the rest acts on the rate of stretch only (the relative
        velocity along the spring, a Kelvin-Voigt solid's viscosity), which damps no rigid turn
    """

    i: np.ndarray
    j: np.ndarray
    rest_length: np.ndarray
    k_low: np.ndarray
    k_high: np.ndarray
    biphasic: np.ndarray
    damping: np.ndarray
    knee: float
    sigma: float
    knee_length: np.ndarray
    isotropy: float = 1.0

    @classmethod
    def make(cls, i, j, rest_length, k_low, k_high, biphasic, damping, knee, sigma,
             isotropy=1.0):
        """The bundle of these springs, with the knee of each as a length."""
        biphasic = np.asarray(biphasic, bool)
        knee_length = np.where(biphasic, knee * np.asarray(rest_length, float), np.inf)
        return cls(i, j, rest_length, k_low, k_high, biphasic, damping, float(knee),
                   float(sigma), knee_length, float(isotropy))


class PrismBundle(NamedTuple):
    """The prism elements: the seeds' volume and shape terms (eq. 9), the continuum's pressure.

    Attributes
    ----------
    nodes : (p, 6) int64 -- the upper triangle's nodes, then the lower's
    rest_volume : (p,) m^3
    rest_rel : (p, 6, 3) m -- rest positions of the nodes about the prism's centroid
    k_volume : float -- N/m^3, volume stiffness k_e1 of eq. (9)
    k_shape : float -- N/m, shape stiffness k_e2 of eq. (9)
    bulk : (p,) N/m^5 -- K / V0 of the continuum's pressure term (0: none, the seeds')
    """

    nodes: np.ndarray
    rest_volume: np.ndarray
    rest_rel: np.ndarray
    k_volume: float
    k_shape: float
    bulk: np.ndarray

    @classmethod
    def empty(cls) -> PrismBundle:
        """No prisms (a bare spring network)."""
        return cls(np.zeros((0, 6), np.int64), np.zeros(0), np.zeros((0, 6, 3)), 0.0, 0.0,
                   np.zeros(0))


class MuscleBundle(NamedTuple):
    """The muscle instances and the constants of their Hill law (eqs. 5-7).

    Node lists are in CSR form: the entries of muscle ``m`` are ``ptr[m]:ptr[m + 1]``.

    Attributes
    ----------
    kind : (m,) int64 -- :class:`~facemech.physics.kinds.MuscleKind` (linear or sphincter)
    origin : (m,) int64 -- the origin node of a linear muscle (-1 for sphincters)
    offset : (m, 3) m -- origin point minus origin node (fixed origins; zeros otherwise)
    ptr : (m + 1,) int64
    nodes : (e,) int64 -- insertion nodes, or a sphincter's path in order
    weights : (e,) -- share of each node in its bead (or insertion)
    bead : (e,) int64 -- global bead of each entry
    bead_start : (m + 1,) int64 -- first global bead of each muscle
    rest_length : (m,) m
    k_passive : (m,) N/m -- passive stiffness k_m of eq. (7)
    pull : int -- :class:`~facemech.physics.kinds.MusclePull`
    f1, f2, f3 : float -- the force-velocity constants of eq. (6)
    f4 : (m,) s/m -- eq. (6)'s velocity scale of each muscle (the seeds': one value for all)
    """

    kind: np.ndarray
    origin: np.ndarray
    offset: np.ndarray
    ptr: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    bead: np.ndarray
    bead_start: np.ndarray
    rest_length: np.ndarray
    k_passive: np.ndarray
    pull: int
    f1: float
    f2: float
    f3: float
    f4: np.ndarray

    @classmethod
    def empty(cls, f1: float = 0.82, f2: float = 0.5, f3: float = 0.43,
              ) -> MuscleBundle:
        """No muscles (a bare spring network)."""
        none_i = np.zeros(0, np.int64)
        return cls(none_i, none_i, np.zeros((0, 3)), np.zeros(1, np.int64), none_i, np.zeros(0),
                   none_i, np.zeros(1, np.int64), np.zeros(0), np.zeros(0), PULL_TOWARDS_ORIGIN,
                   f1, f2, f3, np.zeros(0))


class RestorationBundle(NamedTuple):
    """Nodes held to anchors on the bone: the seeds' tied fascia (eqs. 10-11), the continuum's
    sliding skull nodes (a tether and a one-sided contact with the bone).

    Attributes
    ----------
    nodes : (t,) int64 -- the tied nodes
    skull : (t,) int64 -- the skull node under each (the seeds'; eq. 10)
    height : (t,) m -- rest height of each tied node above its skull node (eq. 10)
    k_restore : (t,) N/m -- stiffness holding each node to its anchor (eq. 11)
    bone_k : (t,) N/m -- one-sided contact with the bone's tangent plane at the anchor (0: none)
    skull_contact : bool -- eq. (10) on the tied nodes
    """

    nodes: np.ndarray
    skull: np.ndarray
    height: np.ndarray
    k_restore: np.ndarray
    bone_k: np.ndarray
    skull_contact: bool

    @classmethod
    def empty(cls) -> RestorationBundle:
        """No tied nodes."""
        none_i = np.zeros(0, np.int64)
        return cls(none_i, none_i, np.zeros(0), np.zeros(0), np.zeros(0), False)


class ContactBundle(NamedTuple):
    """The penalty that keeps the lips from passing through each other.

    Attributes
    ----------
    pairs : (c, 2) int64 -- twin nodes of the lip line (upper, lower)
    normals : (c, 3) -- unit normal of each pair, pointing from the lower to the upper lip
    k : (c,) N/m -- contact stiffness of each pair
    """

    pairs: np.ndarray
    normals: np.ndarray
    k: np.ndarray

    @classmethod
    def empty(cls) -> ContactBundle:
        """No lip contact."""
        return cls(np.zeros((0, 2), np.int64), np.zeros((0, 3)), np.zeros(0))


class SlabBundle(NamedTuple):
    """The springs and prisms again, sorted into slabs across the face for the threads
    (:func:`facemech.physics.slabs.slab_bundles`): slabs of one parity share no node.

    Attributes
    ----------
    springs : SpringBundle -- slab by slab; slab ``k`` is ``spring_ptr[k]:spring_ptr[k + 1]``
    prisms : PrismBundle -- slab by slab, likewise with ``prism_ptr``
    spring_ptr, prism_ptr : (slabs + 1,) int64 -- an even count of slabs; none: one thread
    zero : (n,) int64 -- every node once: ``zero[zero_ptr[q]:zero_ptr[q + 1]]`` are those whose
        forces the thread of slabs ``2q`` and ``2q + 1`` zeroes before it takes slab ``2q``
    zero_ptr : (slabs / 2 + 1,) int64
    dynamic : (d,) int64 -- the nodes that move under forces, in bands across the face (band
        ``q`` where slabs ``2q`` and ``2q + 1`` lie): the explicit step moves each band's
        nodes on its slabs' thread, in that core's cache
    dynamic_ptr : (slabs / 2 + 1,) int64
    """

    springs: SpringBundle
    prisms: PrismBundle
    spring_ptr: np.ndarray
    prism_ptr: np.ndarray
    zero: np.ndarray
    zero_ptr: np.ndarray
    dynamic: np.ndarray
    dynamic_ptr: np.ndarray

    @classmethod
    def empty(cls) -> SlabBundle:
        """No slabs: the forces are assembled on one thread."""
        springs = SpringBundle.make(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0),
                                    np.zeros(0), np.zeros(0), np.zeros(0, bool), np.zeros(0),
                                    0.0, 0.0)
        none = np.zeros(0, np.int64)
        one = np.zeros(1, np.int64)
        return cls(springs, PrismBundle.empty(), one, one, none, one, none, one)


class ForceBundles(NamedTuple):
    """Every constant argument of :func:`~facemech.physics.assembly.accumulate_forces`
    (``Physics.forces``); ``slabs`` (none by default) lets it use several threads."""

    springs: SpringBundle
    prisms: PrismBundle
    muscles: MuscleBundle
    restoration: RestorationBundle
    contact: ContactBundle
    slabs: SlabBundle = SlabBundle.empty()


class Anchors(NamedTuple):
    """Where the tied nodes are held, moved with the jaw.

    Attributes
    ----------
    rest : (t, 3) m -- the anchor of each tied node (its rest position, turned with the jaw by
        its jaw weight)
    normal : (t, 3) -- the outward unit normal of the bone under it, turned likewise
    """

    rest: np.ndarray
    normal: np.ndarray


__all__ = ["SpringBundle", "PrismBundle", "MuscleBundle", "RestorationBundle", "ContactBundle",
           "ForceBundles", "Anchors"]
