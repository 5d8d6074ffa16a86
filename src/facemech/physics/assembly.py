"""Assembly of every force of eq. (8) (Lucero & Munhall 1999) over the whole mesh.

:class:`Physics` turns a :class:`~facemech.geometry.builder.FaceModel` and
:class:`~facemech.params.Parameters` into flat arrays once; :func:`accumulate_forces` is the
numba kernel that maps the pure element kernels of :mod:`springs`, :mod:`volume` and
:mod:`muscle` over springs, prisms and muscles, then applies restoration (eq. 11), lip contact and
skull non-penetration (eq. 10).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from ..geometry.builder import SPHINCTER, FaceModel
from ..params import MUSCLE_GROUPS, Parameters
from .muscle import hill_force
from .springs import scaled_stiffness, tension
from .volume import prism_forces, rest_geometry


@dataclass(frozen=True, eq=False)
class Physics:
    """Flat arrays of a face model with its material constants (SI). Built once, read-only."""

    model: FaceModel
    params: Parameters
    n_dynamic: int  # nodes 0..n_dynamic-1 move (epidermis and fascia); the skull is kinematic
    spring_i: np.ndarray
    spring_j: np.ndarray
    spring_rest: np.ndarray
    spring_k_low: np.ndarray
    spring_k_high: np.ndarray
    spring_biphasic: np.ndarray
    prism_nodes: np.ndarray
    prism_rest_volume: np.ndarray
    prism_rest_rel: np.ndarray
    tied: np.ndarray  # tied fascia nodes
    tied_skull: np.ndarray  # their skull nodes
    tied_on_jaw: np.ndarray  # bool: the skull node below belongs to the jaw
    tied_height: np.ndarray  # m, rest height of each tied fascia node above its skull node
    jaw_nodes: np.ndarray
    muscle_group: np.ndarray
    muscle_kind: np.ndarray
    muscle_origin: np.ndarray
    muscle_ptr: np.ndarray
    muscle_nodes: np.ndarray
    muscle_weights: np.ndarray
    muscle_rest: np.ndarray
    muscle_area: np.ndarray  # m^2
    muscle_k_passive: np.ndarray  # N/m

    @classmethod
    def build(cls, model: FaceModel, params: Parameters) -> Physics:
        rest = model.rest_positions
        kind = model.spring_kind
        l0 = np.linalg.norm(rest[model.spring_j] - rest[model.spring_i], axis=1)
        k_ref = np.choose(kind, [params.k_epidermis, params.k_dermal_low, params.k_fascia,
                                 params.k_muscle_layer])
        k_low = scaled_stiffness(k_ref, l0, params.spring_ref_length)
        k_high = np.where(kind == 1,
                          scaled_stiffness(params.k_dermal_high, l0, params.spring_ref_length),
                          k_low)
        vols, rel = rest_geometry(rest, model.prism_nodes)
        n = model.n_surface
        tied = np.asarray(model.tied_fascia, np.int64)
        jaw = np.zeros(model.n_nodes, bool)
        jaw[model.jaw_nodes] = True
        groups = [MUSCLE_GROUPS[g] for g in model.muscles.group]
        return cls(
            model=model, params=params, n_dynamic=2 * n,
            spring_i=model.spring_i.astype(np.int64), spring_j=model.spring_j.astype(np.int64),
            spring_rest=l0, spring_k_low=k_low, spring_k_high=k_high,
            spring_biphasic=(kind == 1),
            prism_nodes=model.prism_nodes.astype(np.int64), prism_rest_volume=vols,
            prism_rest_rel=rel, tied=tied, tied_skull=tied + n, tied_on_jaw=jaw[tied + n],
            tied_height=np.einsum("ka,ka->k", rest[tied] - rest[tied + n],
                                  model.skull_normals[tied + n]),
            jaw_nodes=np.asarray(model.jaw_nodes, np.int64),
            muscle_group=model.muscles.group, muscle_kind=model.muscles.kind,
            muscle_origin=model.muscles.origin, muscle_ptr=model.muscles.ptr,
            muscle_nodes=model.muscles.nodes, muscle_weights=model.muscles.weights,
            muscle_rest=model.muscles.rest_length,
            muscle_area=np.array([params.muscle_area(g) for g in groups]),
            muscle_k_passive=np.array([params.passive_stiffness(g) for g in groups]),
        )

    @property
    def n_muscles(self) -> int:
        return len(self.muscle_group)

    def steady_force(self, activity: np.ndarray) -> np.ndarray:
        """M_bar per muscle instance (N) from group activity (16,) in [0, 1] (eq. 3)."""
        return self.params.k_force * self.muscle_area * np.asarray(activity)[self.muscle_group]


@nb.njit(cache=True)
def accumulate_forces(
    pos, vel, out,
    spring_i, spring_j, spring_rest, k_low, k_high, biphasic, damping, knee, sigma,
    prism_nodes, prism_rest_volume, prism_rest_rel, k_volume, k_shape,
    muscle_force, muscle_kind, muscle_origin, muscle_ptr, muscle_nodes, muscle_weights,
    muscle_rest, muscle_k_passive, f1, f2, f3, f4,
    tied, tied_skull, tied_height, tied_rest, tied_normal, k_restore,
    lip_pairs, lip_normals, k_contact,
):  # fmt: skip
    """Net force (N) on every node: the terms of eq. (8) moved to the right-hand side.

    ``out`` (N, 3) is overwritten. ``tied_rest`` and ``tied_normal`` are the rest positions and
    outward skull normals under the tied fascia nodes, already rotated with the jaw.
    """
    out[:] = 0.0
    # springs, eqs. (1)-(2), and damping r (v_j - v_i), eq. (8) second term
    for s in range(spring_i.shape[0]):
        i = spring_i[s]
        j = spring_j[s]
        dx = pos[j, 0] - pos[i, 0]
        dy = pos[j, 1] - pos[i, 1]
        dz = pos[j, 2] - pos[i, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        t = tension(length, spring_rest[s], k_low[s], k_high[s], knee, sigma, biphasic[s])
        t /= length
        fx = t * dx + damping * (vel[j, 0] - vel[i, 0])
        fy = t * dy + damping * (vel[j, 1] - vel[i, 1])
        fz = t * dz + damping * (vel[j, 2] - vel[i, 2])
        out[i, 0] += fx
        out[i, 1] += fy
        out[i, 2] += fz
        out[j, 0] -= fx
        out[j, 1] -= fy
        out[j, 2] -= fz
    # prism elements, eq. (9)
    p = np.empty((6, 3))
    q = np.empty((6, 3))
    for e in range(prism_nodes.shape[0]):
        for k in range(6):
            for a in range(3):
                p[k, a] = pos[prism_nodes[e, k], a]
        prism_forces(p, prism_rest_volume[e], prism_rest_rel[e], k_volume, k_shape, q)
        for k in range(6):
            for a in range(3):
                out[prism_nodes[e, k], a] += q[k, a]
    # muscles, eqs. (5)-(7); muscle_force holds the filtered M of eq. (4)
    for m in range(muscle_kind.shape[0]):
        a0 = muscle_ptr[m]
        a1 = muscle_ptr[m + 1]
        if muscle_kind[m] == 1:  # sphincter path: tension along the chain of nodes
            length = 0.0
            rate = 0.0
            for k in range(a0, a1 - 1):
                u = muscle_nodes[k]
                w = muscle_nodes[k + 1]
                dx = pos[w, 0] - pos[u, 0]
                dy = pos[w, 1] - pos[u, 1]
                dz = pos[w, 2] - pos[u, 2]
                seg = np.sqrt(dx * dx + dy * dy + dz * dz)
                length += seg
                rate += (dx * (vel[w, 0] - vel[u, 0]) + dy * (vel[w, 1] - vel[u, 1])
                         + dz * (vel[w, 2] - vel[u, 2])) / seg
            tf = hill_force(muscle_force[m], length, muscle_rest[m], rate, muscle_k_passive[m],
                            f1, f2, f3, f4)
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
            cx = cy = cz = 0.0
            vx = vy = vz = 0.0
            for k in range(a0, a1):
                w = muscle_weights[k]
                u = muscle_nodes[k]
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
            tf = hill_force(muscle_force[m], length, muscle_rest[m], rate, muscle_k_passive[m],
                            f1, f2, f3, f4)
            for k in range(a0, a1):
                u = muscle_nodes[k]
                dx = pos[o, 0] - pos[u, 0]
                dy = pos[o, 1] - pos[u, 1]
                dz = pos[o, 2] - pos[u, 2]
                s = muscle_weights[k] * tf / np.sqrt(dx * dx + dy * dy + dz * dz)
                out[u, 0] += s * dx
                out[u, 1] += s * dy
                out[u, 2] += s * dz
    # restoration of tied fascia nodes, eq. (11)
    for k in range(tied.shape[0]):
        i = tied[k]
        for a in range(3):
            out[i, a] -= k_restore * (pos[i, a] - tied_rest[k, a])
    # lips never pass through each other: penalty on the twin nodes of the lip line
    for c in range(lip_pairs.shape[0]):
        u = lip_pairs[c, 0]
        w = lip_pairs[c, 1]
        gap = 0.0
        for a in range(3):
            gap += (pos[u, a] - pos[w, a]) * lip_normals[c, a]
        if gap < 0.0:
            for a in range(3):
                out[u, a] -= k_contact * gap * lip_normals[c, a]
                out[w, a] += k_contact * gap * lip_normals[c, a]
    # skull non-penetration, eq. (10): cancel the net force on a tied fascia node into the skull
    # while the node sits at or below its rest height above the skull (a node lifted off the
    # skull may come back down; otherwise nothing would ever pull it back)
    for k in range(tied.shape[0]):
        i = tied[k]
        s = tied_skull[k]
        fn = 0.0
        height = 0.0
        for a in range(3):
            fn += out[i, a] * tied_normal[k, a]
            height += (pos[i, a] - pos[s, a]) * tied_normal[k, a]
        if fn < 0.0 and height <= tied_height[k]:
            for a in range(3):
                out[i, a] -= fn * tied_normal[k, a]


def force_arguments(ph: Physics, muscle_force: np.ndarray, tied_rest: np.ndarray,
                    tied_normal: np.ndarray, lip_normals: np.ndarray) -> tuple:
    """The arguments of :func:`accumulate_forces` after ``pos, vel, out``, in order."""
    p = ph.params
    return (
        ph.spring_i, ph.spring_j, ph.spring_rest, ph.spring_k_low, ph.spring_k_high,
        ph.spring_biphasic, p.damping, p.biphasic_knee, p.sigma,
        ph.prism_nodes, ph.prism_rest_volume, ph.prism_rest_rel, p.k_volume, p.k_shape,
        muscle_force, ph.muscle_kind, ph.muscle_origin, ph.muscle_ptr, ph.muscle_nodes,
        ph.muscle_weights, ph.muscle_rest, ph.muscle_k_passive, p.f1, p.f2, p.f3, p.f4,
        ph.tied, ph.tied_skull, ph.tied_height, tied_rest, tied_normal, p.k_restore,
        ph.model.lip_pairs, lip_normals, p.k_lip_contact,
    )


__all__ = ["Physics", "accumulate_forces", "force_arguments", "SPHINCTER"]
