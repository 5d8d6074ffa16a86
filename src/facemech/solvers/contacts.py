"""Stiff one-sided contacts stepped implicitly, node by node, after the implicit methods' solve.

The continuum's penalties, the sliding deep surface on the bone (``bone_k``) and the lips on
each other (``k`` of the lip pairs), are far stiffer than their nodes' masses allow an explicit
step to carry: h^2 k / m is 40-140 on the bone and 140-700 between the lips at the default
4.2-ms step. Left in the explicit force of the constant-matrix methods, a node touching the bone
overshoots out of it, falls back and overshoots again. Since a penalty is homogeneous about a
zero gap and the sliding nodes rest at exactly zero gap, that chatter is scale-free: a rounding
difference of 1e-17 m grew threefold per frame, to 1e-4 m in 35 frames (docs/reproducibility.md).

Here each contact is a backward-Euler step of its own normal spring, applied after the global
solve (first-order operator splitting). For a node of mass m whose gap after the step is
g* < 0 (penetration),

    Delta v_n = -h k g* / (m + h^2 k),        Delta x_n = h Delta v_n,

the exact solution of m (v_n - v*_n) = -h k (g_0 + h v_n) with g_0 = g* - h v*_n; for a pair
of lip nodes the same with the reduced mass mu = m_u m_w / (m_u + m_w) and the impulse shared
by 1/m_u and 1/m_w. The new gap is g* m / (m + h^2 k): a contraction for any step, so no
perturbation grows through a contact, and the map is continuous in g* (it is zero at g* = 0).
At rest the split makes a contact stiffer than its penalty, by (m + h c) / m with c the node's
damping in the global solve: the free step's damping meets the velocity the contact then
cancels. A harder bone and a firmer lip seal; the load is carried in full.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np


class ImplicitContacts(NamedTuple):
    """The penalties the implicit methods step apart from the global solve.

    Attributes
    ----------
    tied : (t,) int64 -- the sliding nodes in one-sided contact with the bone
    bone_k : (t,) N/m -- their contact stiffness (0: none)
    pairs : (c, 2) int64 -- twin nodes of the lip line (upper, lower)
    normals : (c, 3) -- unit normal of each pair, from the lower to the upper lip
    lip_k : (c,) N/m -- the lip contact stiffness of each pair
    """

    tied: np.ndarray
    bone_k: np.ndarray
    pairs: np.ndarray
    normals: np.ndarray
    lip_k: np.ndarray

    @classmethod
    def empty(cls) -> ImplicitContacts:
        """No contact stepped apart."""
        return cls(np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 2), np.int64),
                   np.zeros((0, 3)), np.zeros(0))


@nb.njit(cache=True)
def resolve_contacts(pos, vel, inv_mass, tied, bone_k, anchor, normal, pairs, pair_normal,
                     lip_k, h):
    """Step every penetrating contact implicitly (see the module doc), in place.

    Parameters
    ----------
    pos, vel : (nodes, 3) m, m/s -- the state after the step's global solve; changed in place
    inv_mass : (nodes,) 1/kg -- 0 for kinematic nodes
    tied, bone_k : the bone contact's nodes and stiffness (N/m)
    anchor, normal : (t, 3) m and unit -- the bone's tangent plane under each tied node
    pairs, pair_normal, lip_k : the lip pairs, their normals and stiffness (N/m)
    h : float, s -- the step

    Returns
    -------
    int -- the number of contacts that acted
    """
    acted = 0
    for k in range(tied.shape[0]):
        i = tied[k]
        if bone_k[k] <= 0.0 or inv_mass[i] <= 0.0:
            continue
        gap = 0.0
        for a in range(3):
            gap += (pos[i, a] - anchor[k, a]) * normal[k, a]
        if gap < 0.0:
            m = 1.0 / inv_mass[i]
            dv = -h * bone_k[k] * gap / (m + h * h * bone_k[k])
            for a in range(3):
                vel[i, a] += dv * normal[k, a]
                pos[i, a] += h * dv * normal[k, a]
            acted += 1
    for c in range(pairs.shape[0]):
        u = pairs[c, 0]
        w = pairs[c, 1]
        iu = inv_mass[u]
        iw = inv_mass[w]
        if lip_k[c] <= 0.0 or iu + iw <= 0.0:
            continue
        gap = 0.0
        for a in range(3):
            gap += (pos[u, a] - pos[w, a]) * pair_normal[c, a]
        if gap < 0.0:
            # impulse J along the normal on u (and -J on w): J = -h k g* / (1 + h^2 k / mu)
            impulse = -h * lip_k[c] * gap / (1.0 + h * h * lip_k[c] * (iu + iw))
            for a in range(3):
                vel[u, a] += impulse * iu * pair_normal[c, a]
                vel[w, a] -= impulse * iw * pair_normal[c, a]
                pos[u, a] += h * impulse * iu * pair_normal[c, a]
                pos[w, a] -= h * impulse * iw * pair_normal[c, a]
            acted += 1
    return acted


def split_contacts(forces):
    """``forces`` (ForceBundles) without the bone and lip penalties, and those penalties as
    :class:`ImplicitContacts`, for a method that steps them with :func:`resolve_contacts`.

    Parameters
    ----------
    forces : ForceBundles

    Returns
    -------
    (ForceBundles, ImplicitContacts)
    """
    r, c = forces.restoration, forces.contact
    contacts = ImplicitContacts(tied=r.nodes, bone_k=np.asarray(r.bone_k, float),
                                pairs=c.pairs, normals=c.normals, lip_k=np.asarray(c.k, float))
    bare = forces._replace(restoration=r._replace(bone_k=np.zeros_like(r.bone_k)),
                           contact=c._replace(k=np.zeros_like(c.k)))
    return bare, contacts


__all__ = ["ImplicitContacts", "resolve_contacts", "split_contacts"]
