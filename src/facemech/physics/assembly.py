"""Assembly of every force of eq. (8) (Lucero & Munhall 1999) over the whole mesh.

:class:`Physics` turns a :class:`~facemech.geometry.builder.FaceModel` and
:class:`~facemech.params.Parameters` into flat arrays once; :func:`accumulate_forces` is the
numba kernel that maps the pure element kernels of :mod:`springs`, :mod:`volume` and
:mod:`muscle` over springs, prisms and muscles, then applies restoration (eq. 11), lip contact and
skull non-penetration (eq. 10). The kernels take their constants as the typed bundles of
:mod:`.bundles`, which :class:`Physics` builds and holds (``physics.forces``): the model's one
shape for the kernels, no copy made from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from ..errors import InputError
from ..geometry.builder import FaceModel
from ..params import MUSCLE_GROUPS, Parameters
from .bundles import (
    Anchors,
    ContactBundle,
    ForceBundles,
    MuscleBundle,
    PrismBundle,
    RestorationBundle,
    SpringBundle,
)
from .kinds import (
    PULL_ALONG_LENGTH,
    PULL_TOWARDS_ORIGIN,
    SEED_SPRING_KINDS,
    SPHINCTER,
    SpringKind,
)
from .materials import continuum_constants
from .muscle import fibre_f4, hill_force, steady_force
from .slabs import slab_bundles
from .springs import scaled_stiffness, tension_at
from .threads import kernel_threads
from .volume import (
    PRESSURE_BLOCK,
    add_pressure_blocks,
    add_prism_forces,
    add_prism_pressure,
    rest_geometry,
)


@dataclass(frozen=True, eq=False)
class Physics:
    """A face model with its material constants (SI) as the force kernels read them. Built
    once, read-only.

    ``physics.forces`` holds the kernels' typed bundles (:mod:`.bundles`): the springs, prisms,
    muscles, tied nodes, lip contact and the slabs for numba's threads, built here once and
    handed as they are to every solver (:class:`~facemech.solvers.solver_state.SolverState`).
    ``Physics.build`` reads the constants as the preset says (:attr:`Parameters.material`): the
    seeds' per-spring values, or tissue moduli turned into per-element constants by
    :mod:`materials`. The face must have the preset's tissue geometry
    (:attr:`Parameters.tissue`): another is an :class:`~facemech.errors.InputError` naming
    both, never swapped silently; :func:`~facemech.geometry.builder.for_tissue` rebuilds a face
    for a preset explicitly. ``physics.model`` is the face simulated.
    """

    model: FaceModel
    params: Parameters
    dynamic: np.ndarray  # nodes that move under forces, ascending
    inv_mass: np.ndarray  # (nodes,) 1/kg (0 for kinematic nodes)
    forces: ForceBundles  # the force kernel's constants: springs, prisms, muscles, tied nodes
    # (the seeds' tied fascia, eq. 11; the continuum's sliding skull nodes), lip contact, slabs
    tied_weight: np.ndarray  # share of the jaw's rotation of each tied node's anchor
    jaw_nodes: np.ndarray
    jaw_weights: np.ndarray  # share of the jaw's rotation of each jaw node
    muscle_group: np.ndarray  # (muscles,) the group (column of the activity) of each instance
    muscle_area: np.ndarray  # (muscles,) m^2

    @classmethod
    def build(cls, model: FaceModel, params: Parameters) -> Physics:
        if model.tissue != params.tissue:
            raise InputError(
                f"face {model.name!r} has the {model.tissue} tissue, the preset "
                f"{params.name!r} the {params.tissue} tissue: rebuild the face for the preset "
                f"(facemech.geometry.builder.for_tissue)", field="face")
        rest = model.rest_positions
        l0 = np.linalg.norm(rest[model.spring_j] - rest[model.spring_i], axis=1)
        vols, rel = rest_geometry(rest, model.prism_nodes, symmetric=params.is_continuum)
        dynamic = model.dynamic_nodes.astype(np.int64)
        (k_low, k_high, biphasic, damping, inv_mass, bulk, contact, tied, restore_k, bone_k,
         tied_skull, tied_height) = (_continuum_constants(model, params, dynamic)
                                     if params.is_continuum else
                                     _seed_constants(model, params, l0, dynamic))
        jaw = np.zeros(model.n_nodes)
        jaw[model.jaw_nodes] = model.jaw_weight
        jaw[model.sliding] = model.sliding_weight
        groups = [MUSCLE_GROUPS[g] for g in model.muscles.group]
        mus = model.muscles
        springs = SpringBundle.make(
            i=model.spring_i.astype(np.int64), j=model.spring_j.astype(np.int64),
            rest_length=l0, k_low=np.asarray(k_low, float), k_high=np.asarray(k_high, float),
            biphasic=biphasic, damping=np.asarray(damping, float), knee=params.biphasic_knee,
            sigma=params.sigma, isotropy=params.dashpot_isotropy if params.is_continuum else 1.0)
        prisms = PrismBundle(
            nodes=model.prism_nodes.astype(np.int64), rest_volume=vols, rest_rel=rel,
            k_volume=params.k_volume, k_shape=params.k_shape, bulk=np.asarray(bulk, float))
        muscles = _muscle_bundle(mus, params, groups)
        restoration = RestorationBundle(
            nodes=tied, skull=tied_skull, height=tied_height,
            k_restore=np.asarray(restore_k, float), bone_k=np.asarray(bone_k, float),
            skull_contact=bool(params.fixed_skull_contact and not params.is_continuum))
        contact = ContactBundle(pairs=model.lip_pairs, normals=model.lip_normals,
                                k=np.asarray(contact, float))
        return cls(
            model=model, params=params, dynamic=dynamic, inv_mass=inv_mass,
            forces=_with_slabs(ForceBundles(springs, prisms, muscles, restoration, contact),
                               rest, dynamic),
            tied_weight=jaw[tied_skull], jaw_nodes=np.asarray(model.jaw_nodes, np.int64),
            jaw_weights=np.asarray(model.jaw_weight, float), muscle_group=mus.group,
            muscle_area=np.array([params.instance_area(nm, g)
                                  for nm, g in zip(mus.names, groups, strict=True)]))

    @property
    def n_muscles(self) -> int:
        return len(self.muscle_group)

    @property
    def n_dynamic(self) -> int:
        """Number of moving nodes."""
        return len(self.dynamic)

    def steady_force(self, activity: np.ndarray) -> np.ndarray:
        """M_bar per muscle instance (N) from group activity (groups,) in [0, 1] (eq. 3)."""
        return steady_force(self.params.k_force, self.muscle_area,
                            np.asarray(activity)[self.muscle_group])


@nb.njit(cache=True)
def bead_positions(pos, vel, nodes, weights, bead, n_beads):
    """Positions and velocities (beads, 3) of the beads: weighted means of their nodes."""
    bp = np.zeros((n_beads, 3))
    bv = np.zeros((n_beads, 3))
    for e in range(nodes.shape[0]):
        b = bead[e]
        w = weights[e]
        u = nodes[e]
        for a in range(3):
            bp[b, a] += w * pos[u, a]
            bv[b, a] += w * vel[u, a]
    return bp, bv


@nb.njit(cache=True, inline="always")
def segment_length_rate(p, v, i, j):
    """Length (m) of the segment from point i to point j of ``p`` and its rate of change (m/s)
    from the velocities ``v``."""
    dx = p[j, 0] - p[i, 0]
    dy = p[j, 1] - p[i, 1]
    dz = p[j, 2] - p[i, 2]
    seg = np.sqrt(dx * dx + dy * dy + dz * dz)
    rate = (dx * (v[j, 0] - v[i, 0]) + dy * (v[j, 1] - v[i, 1])
            + dz * (v[j, 2] - v[i, 2])) / seg
    return seg, rate


@nb.njit(cache=True, inline="always")
def muscle_length_rate(muscles, m, pos, vel, bp, bv):
    """Length l (m) and lengthening rate dl/dt (m/s) of muscle instance ``m``, as the force
    kernels measure them (the one definition they and the muscle outputs share).

    Parameters
    ----------
    muscles : MuscleBundle
    m : int -- the muscle instance
    pos, vel : (nodes, 3) m and m/s
    bp, bv : (beads, 3) m and m/s -- the beads' positions and velocities
        (:func:`bead_positions`); read only when the muscles pull along their length

    Pulling along the length (the continuum's beads): a sphincter is the chain of its beads, a
    linear muscle runs from its origin point (origin node plus ``offset``) to its bead. Pulling
    towards the origin (the seeds'): a sphincter is the chain of its path nodes, a linear muscle
    runs from its origin node to the weighted mean of its insertion nodes.
    """
    kind = muscles.kind
    origin = muscles.origin
    offset = muscles.offset
    length = 0.0
    rate = 0.0
    if muscles.pull == PULL_ALONG_LENGTH:
        bead_start = muscles.bead_start
        b0 = bead_start[m]
        if kind[m] == SPHINCTER:
            for b in range(b0, bead_start[m + 1] - 1):
                seg, r = segment_length_rate(bp, bv, b, b + 1)
                length += seg
                rate += r
        else:
            o = origin[m]
            dx = bp[b0, 0] - pos[o, 0] - offset[m, 0]
            dy = bp[b0, 1] - pos[o, 1] - offset[m, 1]
            dz = bp[b0, 2] - pos[o, 2] - offset[m, 2]
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            rate = (dx * (bv[b0, 0] - vel[o, 0]) + dy * (bv[b0, 1] - vel[o, 1])
                    + dz * (bv[b0, 2] - vel[o, 2])) / length
    else:
        nodes = muscles.nodes
        weights = muscles.weights
        a0 = muscles.ptr[m]
        a1 = muscles.ptr[m + 1]
        if kind[m] == SPHINCTER:
            for k in range(a0, a1 - 1):
                seg, r = segment_length_rate(pos, vel, nodes[k], nodes[k + 1])
                length += seg
                rate += r
        else:
            o = origin[m]
            cx = cy = cz = 0.0
            vx = vy = vz = 0.0
            for k in range(a0, a1):
                w = weights[k]
                u = nodes[k]
                cx += w * pos[u, 0]
                cy += w * pos[u, 1]
                cz += w * pos[u, 2]
                vx += w * vel[u, 0]
                vy += w * vel[u, 1]
                vz += w * vel[u, 2]
            dx = cx - pos[o, 0]
            dy = cy - pos[o, 1]
            dz = cz - pos[o, 2]
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            rate = (dx * (vx - vel[o, 0]) + dy * (vy - vel[o, 1]) + dz * (vz - vel[o, 2])) / length
    return length, rate


@nb.njit(cache=True)
def muscle_lengths(muscles, pos, vel):
    """Length and lengthening rate of every muscle instance, exactly as
    :func:`accumulate_forces` measures them.

    Parameters
    ----------
    muscles : MuscleBundle
    pos, vel : (nodes, 3) m and m/s

    Returns
    -------
    length : (muscles,) m
    rate : (muscles,) m/s, lengthening positive
    """
    n = muscles.kind.shape[0]
    length = np.empty(n)
    rate = np.empty(n)
    if muscles.pull == PULL_ALONG_LENGTH:
        bp, bv = bead_positions(pos, vel, muscles.nodes, muscles.weights, muscles.bead,
                                muscles.bead_start[muscles.bead_start.shape[0] - 1])
    else:
        bp = np.zeros((0, 3))
        bv = np.zeros((0, 3))
    for m in range(n):
        length[m], rate[m] = muscle_length_rate(muscles, m, pos, vel, bp, bv)
    return length, rate


@nb.njit(cache=True)
def bead_muscle_forces(muscles, pos, vel, muscle_force, out):
    """Muscle forces (eqs. 5-7) acting through beads (the continuum tissue), added to ``out``.

    A linear muscle pulls its bead (the weighted mean of its insertion nodes) towards its origin;
    a sphincter's tension acts along the chain of its beads. Each bead's force is shared among
    its nodes by their weights, so the force on the nodes is minus the tension times the
    gradient of the muscle's length.

    Parameters
    ----------
    muscles : MuscleBundle -- pulling along their length
    pos, vel : (nodes, 3) m and m/s
    muscle_force : (muscles,) N -- the filtered force M of eq. (4)
    out : (nodes, 3) N -- the forces are added to it
    """
    kind = muscles.kind
    origin = muscles.origin
    offset = muscles.offset
    nodes = muscles.nodes
    weights = muscles.weights
    bead = muscles.bead
    bead_start = muscles.bead_start
    rest_length = muscles.rest_length
    k_passive = muscles.k_passive
    f1, f2, f3, f4 = muscles.f1, muscles.f2, muscles.f3, muscles.f4
    nb_ = bead_start[bead_start.shape[0] - 1]
    bp, bv = bead_positions(pos, vel, nodes, weights, bead, nb_)
    fb = np.zeros((nb_, 3))
    for m in range(kind.shape[0]):
        b0 = bead_start[m]
        b1 = bead_start[m + 1]
        length, rate = muscle_length_rate(muscles, m, pos, vel, bp, bv)
        if kind[m] == SPHINCTER:
            tf = hill_force(muscle_force[m], length, rest_length[m], rate, k_passive[m],
                            f1, f2, f3, f4[m])
            for b in range(b0, b1 - 1):
                dx = bp[b + 1, 0] - bp[b, 0]
                dy = bp[b + 1, 1] - bp[b, 1]
                dz = bp[b + 1, 2] - bp[b, 2]
                s = tf / np.sqrt(dx * dx + dy * dy + dz * dz)
                fb[b, 0] += s * dx
                fb[b, 1] += s * dy
                fb[b, 2] += s * dz
                fb[b + 1, 0] -= s * dx
                fb[b + 1, 1] -= s * dy
                fb[b + 1, 2] -= s * dz
        else:
            o = origin[m]
            dx = bp[b0, 0] - pos[o, 0] - offset[m, 0]
            dy = bp[b0, 1] - pos[o, 1] - offset[m, 1]
            dz = bp[b0, 2] - pos[o, 2] - offset[m, 2]
            tf = hill_force(muscle_force[m], length, rest_length[m], rate, k_passive[m],
                            f1, f2, f3, f4[m])
            s = tf / length
            fb[b0, 0] -= s * dx
            fb[b0, 1] -= s * dy
            fb[b0, 2] -= s * dz
    for e in range(nodes.shape[0]):
        b = bead[e]
        w = weights[e]
        u = nodes[e]
        for a in range(3):
            out[u, a] += w * fb[b, a]


#: springs and prisms below which :func:`accumulate_forces` stays on one thread (a parallel
#: region costs a few microseconds; the default face has about 47 000 elements)
PARALLEL_MIN_ELEMENTS = 4096
#: m, the band of eq. (10)'s skull contact: a tied fascia node within this height of its rest
#: height above the skull counts as touching it. The seeds' nodes sit *at* their rest height,
#: so a sharp comparison let the last bit of the height switch a whole force on or off and
#: turned a rounding difference of 1e-17 m into 5e-7 m (docs/reproducibility.md); 1 nm is far
#: below any modelled motion and far above rounding.
SKULL_BAND = 1e-9


@nb.njit(cache=True, inline="always")
def spring_forces(springs, pos, vel, s0, s1, sigma, out):
    """Add the forces (N) of springs ``s0:s1`` (eqs. 1-2 and their dashpots, eq. 8), with the
    compression law's ``sigma``, to ``out`` (nodes, 3); False when a spring has no length (see
    :func:`element_forces`)."""
    spring_i = springs.i
    spring_j = springs.j
    spring_rest = springs.rest_length
    k_low = springs.k_low
    k_high = springs.k_high
    knee_length = springs.knee_length
    damping = springs.damping
    knee = springs.knee
    isotropy = springs.isotropy
    ok = True
    # unsigned indices: numba then reads the arrays without its test for a negative index
    # (wrap-around), 15 % of this loop (measured on the default face)
    for s in range(np.uint64(s0), np.uint64(s1)):
        i = np.uint64(spring_i[s])
        j = np.uint64(spring_j[s])
        dx = pos[j, 0] - pos[i, 0]
        dy = pos[j, 1] - pos[i, 1]
        dz = pos[j, 2] - pos[i, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        ok &= length != 0.0  # (not finite: left to the solvers' checks, as before)
        t = tension_at(length, spring_rest[s], k_low[s], k_high[s], knee, knee_length[s], sigma)
        t /= length
        r = damping[s]
        wx = vel[j, 0] - vel[i, 0]
        wy = vel[j, 1] - vel[i, 1]
        wz = vel[j, 2] - vel[i, 2]
        if isotropy != 1.0:  # a share on the rate of stretch only: (w . d) d / |d|^2
            a = (1.0 - isotropy) * r * (wx * dx + wy * dy + wz * dz) / (length * length)
            r *= isotropy
            fx = (t + a) * dx + r * wx
            fy = (t + a) * dy + r * wy
            fz = (t + a) * dz + r * wz
        else:
            fx = t * dx + r * wx
            fy = t * dy + r * wy
            fz = t * dz + r * wz
        out[i, 0] += fx
        out[i, 1] += fy
        out[i, 2] += fz
        out[j, 0] -= fx
        out[j, 1] -= fy
        out[j, 2] -= fz
    return ok


@nb.njit(cache=True, inline="always")
def element_forces(springs, prisms, pos, vel, s0, s1, e0, e1, out):
    """Add the forces (N) of springs ``s0:s1`` (eqs. 1-2 and their dashpots, eq. 8) and of
    prisms ``e0:e1`` (eq. 9, or the continuum's pressure) to ``out`` (nodes, 3).

    Parameters
    ----------
    springs : SpringBundle
    prisms : PrismBundle
    pos, vel : (nodes, 3) m and m/s
    s0, s1, e0, e1 : int -- the ranges of springs and prisms
    out : (nodes, 3) N -- the forces are added to it

    Returns
    -------
    bool -- False when a spring has no length (its two nodes at one point): its force is then
        not finite (the kernels compile with numpy's error model, without a test of every
        division; the callers raise ZeroDivisionError, as the division did before)
    """
    # springs, eqs. (1)-(2), and damping r (v_j - v_i), eq. (8) second term; the continuum's
    # loop compiled without eq. (2)'s test (sigma a constant)
    if springs.sigma > 0.0:
        ok = spring_forces(springs, pos, vel, s0, s1, springs.sigma, out)
    else:
        ok = spring_forces(springs, pos, vel, s0, s1, 0.0, out)
    # prism elements, eq. (9), or the continuum's pressure
    prism_nodes = prisms.nodes
    rest_volume = prisms.rest_volume
    bulk = prisms.bulk
    k_volume = prisms.k_volume
    k_shape = prisms.k_shape
    if k_volume != 0.0 or k_shape != 0.0:  # the seeds' eq. (9), and a pressure if any
        for e in range(e0, e1):
            add_prism_forces(pos, prism_nodes, e, rest_volume[e], prisms.rest_rel, k_volume,
                             k_shape, out)
            if bulk[e] != 0.0:
                add_prism_pressure(pos, prism_nodes, e, rest_volume[e], bulk[e], out)
    else:  # the continuum's pressure alone (0 where a prism's bulk is 0), in vector blocks
        add_pressure_blocks(pos, prism_nodes, rest_volume, bulk, e0, e1,
                            np.empty((18, PRESSURE_BLOCK)), np.empty((18, PRESSURE_BLOCK)), out)
    return ok


@nb.njit(cache=True, error_model="numpy")
def element_forces_one_thread(springs, prisms, pos, vel, out):
    """:func:`element_forces` of all springs and prisms, in their order, added to ``out``
    (nodes, 3) N; False as :func:`element_forces` (for tests and benchmarks)."""
    return element_forces(springs, prisms, pos, vel, 0, springs.i.shape[0], 0,
                          prisms.nodes.shape[0], out)


@nb.njit(cache=True, error_model="numpy")
def element_range(springs, prisms, pos, vel, s0, s1, e0, e1, out):
    """:func:`element_forces` compiled on its own, for the threads of :func:`slab_forces` (a
    call, not inlined into the parallel loop's body, where it compiles 10 % slower)."""
    return element_forces(springs, prisms, pos, vel, s0, s1, e0, e1, out)


@nb.njit(cache=True, parallel=True, error_model="numpy")
def slab_forces(springs, prisms, spring_ptr, prism_ptr, zero, zero_ptr, pos, vel, out):
    """:func:`element_forces` of all springs and prisms, slab by slab on numba's threads, into
    ``out`` (nodes, 3) N: the threads take the even slabs, each first zeroing the forces of its
    share of the nodes (``zero``) and then adding into ``out`` directly (even slabs share no
    node), then the odd ones (:mod:`facemech.physics.slabs`). The arguments are a
    :class:`~facemech.physics.bundles.SlabBundle`'s fields.

    Returns False as :func:`element_forces` does (``prange`` cannot raise: the caller does).
    """
    sp = spring_ptr
    pp = prism_ptr
    pairs = (sp.shape[0] - 1) // 2
    ok = np.ones(2 * pairs, np.bool_)
    for q in nb.prange(pairs):
        for k in range(zero_ptr[q], zero_ptr[q + 1]):
            u = zero[k]
            out[u, 0] = 0.0
            out[u, 1] = 0.0
            out[u, 2] = 0.0
        k = 2 * q
        ok[k] = element_range(springs, prisms, pos, vel, sp[k], sp[k + 1], pp[k], pp[k + 1],
                              out)
    for q in nb.prange(pairs):
        k = 2 * q + 1
        ok[k] = element_range(springs, prisms, pos, vel, sp[k], sp[k + 1], pp[k], pp[k + 1],
                              out)
    return ok.all()


@nb.njit(cache=True, error_model="numpy")
def accumulate_forces(forces, pos, vel, muscle_force, anchors, out):
    """Net force (N) on every node: the terms of eq. (8) moved to the right-hand side.

    Parameters
    ----------
    forces : ForceBundles -- the springs, prisms, muscles, restoration and lip contact
        (:attr:`Physics.forces`)
    pos, vel : (nodes, 3) m and m/s
    muscle_force : (muscles,) N -- the filtered force M of eq. (4) of each muscle instance
    anchors : Anchors -- the tied nodes' anchors and the bone's normals there, already moved
        with the jaw (:func:`facemech.solvers.mandible.place_jaw`)
    out : (nodes, 3) N -- overwritten with the forces

    Each spring's dashpot acts on the whole relative velocity of its ends (eq. 8); a prism's
    ``bulk`` switches on the volume-preserving pressure of the continuum tissue, ``k_volume``
    and ``k_shape`` eq. (9); the muscles pull as ``muscles.pull`` says; restoration holds each
    tied node to its anchor (eq. 11) with a one-sided contact with the bone's tangent plane
    there (``bone_k``); ``skull_contact`` switches eq. (10) on.
    """
    muscles = forces.muscles
    muscle_kind = muscles.kind
    muscle_origin = muscles.origin
    muscle_ptr = muscles.ptr
    muscle_nodes = muscles.nodes
    muscle_weights = muscles.weights
    muscle_rest = muscles.rest_length
    muscle_k_passive = muscles.k_passive
    f1, f2, f3, f4 = muscles.f1, muscles.f2, muscles.f3, muscles.f4
    restoration = forces.restoration
    tied = restoration.nodes
    tied_skull = restoration.skull
    tied_height = restoration.height
    k_restore = restoration.k_restore
    bone_k = restoration.bone_k
    tied_rest = anchors.rest
    tied_normal = anchors.normal
    lip_pairs = forces.contact.pairs
    lip_normals = forces.contact.normals
    k_contact = forces.contact.k
    # springs, eqs. (1)-(2), their dashpots, and the prisms, eq. (9) or the continuum's
    # pressure: on the threads numba has (facemech.physics.threads) when the mesh is large
    if kernel_threads() > 1 and forces.slabs.spring_ptr.shape[0] > 1:
        slabs = forces.slabs
        ok = slab_forces(slabs.springs, slabs.prisms, slabs.spring_ptr, slabs.prism_ptr,
                         slabs.zero, slabs.zero_ptr, pos, vel, out)
    else:
        out[:] = 0.0
        ok = element_forces(forces.springs, forces.prisms, pos, vel, 0,
                            forces.springs.i.shape[0], 0, forces.prisms.nodes.shape[0], out)
    if not ok:
        raise ZeroDivisionError("a spring collapsed: its two nodes met")
    # muscles, eqs. (5)-(7); muscle_force holds the filtered M of eq. (4)
    if muscles.pull == PULL_ALONG_LENGTH:
        bead_muscle_forces(muscles, pos, vel, muscle_force, out)
    for m in range(muscle_kind.shape[0] if muscles.pull == PULL_TOWARDS_ORIGIN else 0):
        a0 = muscle_ptr[m]
        a1 = muscle_ptr[m + 1]
        length, rate = muscle_length_rate(muscles, m, pos, vel, pos, vel)
        if muscle_kind[m] == SPHINCTER:  # sphincter path: tension along the chain of nodes
            tf = hill_force(muscle_force[m], length, muscle_rest[m], rate, muscle_k_passive[m],
                            f1, f2, f3, f4[m])
            for k in range(a0, a1 - 1):
                u = muscle_nodes[k]
                w = muscle_nodes[k + 1]
                dx = pos[w, 0] - pos[u, 0]
                dy = pos[w, 1] - pos[u, 1]
                dz = pos[w, 2] - pos[u, 2]
                s = tf / np.sqrt(dx * dx + dy * dy + dz * dz)
                out[u, 0] += s * dx
                out[u, 1] += s * dy
                out[u, 2] += s * dz
                out[w, 0] -= s * dx
                out[w, 1] -= s * dy
                out[w, 2] -= s * dz
        else:  # linear muscle: insertion nodes pulled towards the origin on the skull
            o = muscle_origin[m]
            tf = hill_force(muscle_force[m], length, muscle_rest[m], rate, muscle_k_passive[m],
                            f1, f2, f3, f4[m])
            for k in range(a0, a1):
                u = muscle_nodes[k]
                dx = pos[o, 0] - pos[u, 0]
                dy = pos[o, 1] - pos[u, 1]
                dz = pos[o, 2] - pos[u, 2]
                s = muscle_weights[k] * tf / np.sqrt(dx * dx + dy * dy + dz * dz)
                out[u, 0] += s * dx
                out[u, 1] += s * dy
                out[u, 2] += s * dz
    # restoration of tied fascia nodes, eq. (11); the continuum's sliding nodes: a tether to
    # their anchor and a one-sided contact with the bone's tangent plane there
    for k in range(tied.shape[0]):
        i = tied[k]
        for a in range(3):
            out[i, a] -= k_restore[k] * (pos[i, a] - tied_rest[k, a])
        if bone_k[k] > 0.0:
            gap = 0.0
            for a in range(3):
                gap += (pos[i, a] - tied_rest[k, a]) * tied_normal[k, a]
            if gap < 0.0:
                for a in range(3):
                    out[i, a] -= bone_k[k] * gap * tied_normal[k, a]
    # lips never pass through each other: penalty on the twin nodes of the lip line
    for c in range(lip_pairs.shape[0]):
        u = lip_pairs[c, 0]
        w = lip_pairs[c, 1]
        gap = 0.0
        for a in range(3):
            gap += (pos[u, a] - pos[w, a]) * lip_normals[c, a]
        if gap < 0.0:
            for a in range(3):
                out[u, a] -= k_contact[c] * gap * lip_normals[c, a]
                out[w, a] += k_contact[c] * gap * lip_normals[c, a]
    # skull non-penetration, eq. (10): cancel the net force on a tied fascia node into the skull
    # while the node sits at or below its rest height above the skull, within SKULL_BAND (a node
    # lifted off the skull may come back down; otherwise nothing would ever pull it back)
    for k in range(tied.shape[0] if restoration.skull_contact else 0):
        i = tied[k]
        s = tied_skull[k]
        fn = 0.0
        height = 0.0
        for a in range(3):
            fn += out[i, a] * tied_normal[k, a]
            height += (pos[i, a] - pos[s, a]) * tied_normal[k, a]
        if fn < 0.0 and height <= tied_height[k] + SKULL_BAND:
            for a in range(3):
                out[i, a] -= fn * tied_normal[k, a]


def _continuum_constants(model: FaceModel, params: Parameters, dynamic: np.ndarray) -> tuple:
    """The continuum tissue's springs, masses, pressure, contacts and tethers
    (:func:`continuum_constants`), in :meth:`Physics.build`'s order."""
    c = continuum_constants(model, params)
    kind = model.spring_kind
    # strain stiffening, both ways, of every spring but the mucosa's (skull layer)
    biphasic = (kind != SpringKind.SKULL) & (params.stiffening != 1.0)
    k_high = np.where(biphasic, c.spring_k * params.stiffening, c.spring_k)
    mass = c.node_mass
    if np.any(mass[dynamic] <= 0):
        raise InputError("a moving node belongs to no tissue element", field="face")
    inv_mass = np.zeros(model.n_nodes)
    inv_mass[dynamic] = 1.0 / mass[dynamic]
    tied = np.sort(np.asarray(model.sliding, np.int64))
    return (c.spring_k, k_high, biphasic, c.spring_damping, inv_mass, c.prism_bulk, c.contact_k,
            tied, c.tether_k, c.bone_k, tied, np.zeros(len(tied)))


def _seed_constants(model: FaceModel, params: Parameters, l0: np.ndarray,
                    dynamic: np.ndarray) -> tuple:
    """The seeds' springs (eqs. 1-2 scaled to their rest lengths ``l0``), masses, contacts and
    tied fascia (eqs. 10-11), in :meth:`Physics.build`'s order."""
    kind = model.spring_kind
    n = model.n_surface
    # the seeds' constants, in the order of SEED_SPRING_KINDS (a later kind takes the muscle
    # layer's)
    k_ref = np.choose(np.minimum(kind, SEED_SPRING_KINDS[-1]),
                      [params.k_epidermis, params.k_dermal_low, params.k_fascia,
                       params.k_muscle_layer])
    k_low = scaled_stiffness(k_ref, l0, params.spring_ref_length)
    dermal = kind == SpringKind.DERMAL_FATTY
    k_high = np.where(dermal, scaled_stiffness(params.k_dermal_high, l0,
                                               params.spring_ref_length), k_low)
    inv_mass = np.zeros(model.n_nodes)
    inv_mass[dynamic] = 1.0 / params.node_mass
    tied = np.asarray(model.tied_fascia, np.int64)
    rest = model.rest_positions
    tied_height = np.einsum("ka,ka->k", rest[tied] - rest[tied + n],
                            model.skull_normals[tied + n])
    return (k_low, k_high, dermal, np.full(len(l0), params.damping), inv_mass,
            np.zeros(len(model.prism_nodes)), np.full(len(model.lip_pairs), params.k_lip_contact),
            tied, np.full(len(tied), params.k_restore), np.zeros(len(tied)), tied + n,
            tied_height)


def _muscle_bundle(mus, params: Parameters, groups) -> MuscleBundle:
    """The muscles' kernel bundle: their beads numbered across the muscles, the passive
    stiffness and the Hill constants of ``params``."""
    local = mus.beads()
    counts = np.array([local[mus.ptr[m]:mus.ptr[m + 1]].max() + 1 if mus.ptr[m + 1] > mus.ptr[m]
                       else 0 for m in range(len(mus))], np.int64)
    bead_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    owner = np.repeat(np.arange(len(mus)), np.diff(mus.ptr))
    muscle_bead = (bead_start[owner] + local).astype(np.int64)
    return MuscleBundle(
        kind=mus.kind, origin=mus.origin, offset=mus.offsets(), ptr=mus.ptr,
        nodes=mus.nodes, weights=mus.weights, bead=muscle_bead, bead_start=bead_start,
        rest_length=mus.rest_length,
        k_passive=np.array([params.passive_stiffness(g) for g in groups]),
        pull=PULL_ALONG_LENGTH if params.is_continuum else PULL_TOWARDS_ORIGIN,
        f1=params.f1, f2=params.f2, f3=params.f3, f4=muscle_f4(params, mus.rest_length))


def _with_slabs(forces: ForceBundles, rest: np.ndarray, dynamic: np.ndarray) -> ForceBundles:
    """``forces`` with the springs and prisms also sorted into slabs for numba's threads
    (:func:`~facemech.physics.slabs.slab_bundles`), where the mesh has
    :data:`PARALLEL_MIN_ELEMENTS` of them or more.

    Parameters
    ----------
    forces : ForceBundles -- without slabs
    rest : (nodes, 3) m -- rest positions
    dynamic : (d,) int64 -- the nodes that move under forces

    Returns
    -------
    ForceBundles
    """
    if len(forces.springs.i) + len(forces.prisms.nodes) < PARALLEL_MIN_ELEMENTS:
        return forces
    return forces._replace(slabs=slab_bundles(forces.springs, forces.prisms, rest,
                                              nb.config.NUMBA_NUM_THREADS, dynamic))


def muscle_f4(p: Parameters, rest_length: np.ndarray) -> np.ndarray:
    """The velocity scale f4 of eq. (6) of each muscle instance, s/m: the preset's one value
    (the seeds', 20 s/m) or, when the preset gives an intrinsic speed ``fv_vmax`` (fibre lengths
    per second), one from each muscle's fibre length (its rest length,
    :func:`facemech.physics.muscle.fibre_f4`)."""
    rest_length = np.asarray(rest_length, float)
    if p.fv_vmax <= 0.0:
        return np.full(rest_length.shape, float(p.f4))
    return fibre_f4(rest_length, p.fv_vmax, p.fv_curvature, p.f1, p.f2, p.f3)


def rest_anchors(physics: Physics) -> Anchors:
    """The tied nodes' anchors with the jaw closed: their rest positions and the bone's
    normals there (new arrays)."""
    restoration = physics.forces.restoration
    return Anchors(rest=physics.model.rest_positions[restoration.nodes].copy(),
                   normal=physics.model.skull_normals[restoration.skull].copy())


__all__ = ["Physics", "accumulate_forces", "muscle_f4", "muscle_lengths", "rest_anchors",
           "SPHINCTER"]
