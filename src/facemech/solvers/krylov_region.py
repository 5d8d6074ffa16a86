"""The Krylov correction of the predictor's step on a region about the mouth only.

The step is first solved with the constant matrix over the whole face; the GMRES correction on
the forces' true linearisation is then sought over the moving nodes within
``StepOptions.krylov_region`` metres of the mouth:

    A_t,RR d = r_R,    r = h f(x + h v, v) - A_t dv0,

``A_t u`` applied by a finite difference of the forces of what touches the region (springs,
prisms, tethers, every muscle), preconditioned by the constant matrix's block over the region
(its own Cholesky factor, made once) with the muscles' bead-space Jacobian joined by the
Woodbury identity (:mod:`.muscle_implicit`). Nodes outside keep the constant matrix's step.
The cost and the region's effect on the gestures: docs/model.md, "The correction on a region
about the mouth".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np
import scipy.sparse as sp
from scipy.linalg import lu_factor, lu_solve

from ..errors import InputError
from ..physics.bundles import Anchors, ForceBundles, SlabBundle
from .cholesky import factorise

#: the spring arrays that have one entry per spring (the rest are numbers)
_SPRING_ARRAYS = ("i", "j", "rest_length", "k_low", "k_high", "biphasic", "damping",
                  "knee_length")


def mouth_centre(model) -> np.ndarray:
    """(3,) m: the middle of the mouth, the stomion landmark, or else the mean of the lip
    contact pairs' nodes; InputError naming ``krylov_region`` when the face has neither."""
    if "stomion" in model.landmarks:
        return np.asarray(model.rest_positions[model.landmarks["stomion"]], float)
    pairs = getattr(model, "lip_pairs", None)
    if pairs is not None and len(pairs):
        return np.asarray(model.rest_positions[np.asarray(pairs).reshape(-1)].mean(axis=0))
    raise InputError("krylov_region centres the correction on the mouth, but this face has "
                     "neither a stomion landmark nor lip contact pairs", field="krylov_region")


def restrict_forces(forces: ForceBundles, in_region: np.ndarray) -> tuple[ForceBundles,
                                                                          np.ndarray]:
    """The force bundles of what touches the region: springs with an end in it, prisms with a
    node in it, its tethers, and every muscle (a muscle's beads may lie anywhere); one thread
    (no slabs). With them every node of the region gets its whole force.

    Parameters
    ----------
    forces : ForceBundles -- the whole face's
    in_region : (nodes,) bool

    Returns
    -------
    ForceBundles, and (t_r,) int64 -- the region's tethers among the whole face's
    """
    s = forces.springs
    keep = in_region[s.i] | in_region[s.j]
    springs = s._replace(**{k: getattr(s, k)[keep] for k in _SPRING_ARRAYS})
    p = forces.prisms
    keep_p = in_region[p.nodes].any(axis=1) if len(p.nodes) else np.zeros(0, bool)
    prisms = p._replace(nodes=p.nodes[keep_p], rest_volume=p.rest_volume[keep_p],
                        rest_rel=p.rest_rel[keep_p], bulk=p.bulk[keep_p])
    r = forces.restoration
    tethers = np.flatnonzero(in_region[r.nodes]).astype(np.int64)
    restoration = r._replace(nodes=r.nodes[tethers], skull=r.skull[tethers],
                             height=r.height[tethers], k_restore=r.k_restore[tethers],
                             bone_k=r.bone_k[tethers])
    return forces._replace(springs=springs, prisms=prisms, restoration=restoration,
                           slabs=SlabBundle.empty()), tethers


@dataclass(frozen=True, eq=False)
class KrylovRegion:
    """The region of the Krylov correction and its constant parts.

    Attributes
    ----------
    rows : (r,) int64 -- the region's rows among the moving nodes
    nodes : (r,) int64 -- its nodes
    forces : ForceBundles -- what touches it (:func:`restrict_forces`)
    tethers : (t_r,) int64 -- its tethers among the whole face's
    lu : the factorisation of the constant matrix's block over the region
    weights : (r, beads) sparse CSC -- the muscles' bead weights on its rows
    solved : (r, beads) -- ``A0,RR^-1`` times them
    gram : (beads, beads) -- ``weights^T solved``
    """

    rows: np.ndarray
    nodes: np.ndarray
    forces: ForceBundles
    tethers: np.ndarray
    lu: object
    weights: sp.csc_matrix
    solved: np.ndarray
    gram: np.ndarray
    #: the bead subspaces of the active muscles' sets seen (a cache: the results are those
    #: of a fresh object)
    _subspaces: dict = field(default_factory=dict, repr=False)

    def anchors(self, anchors: Anchors) -> Anchors:
        """The region's tethers' anchors among the whole face's."""
        return Anchors(anchors.rest[self.tethers], anchors.normal[self.tethers])

    def linearise(self, jac, h: float):
        """The region's Woodbury system for the muscles' bead-space Jacobian ``jac`` (of
        :meth:`~facemech.solvers.muscle_implicit.MuscleJacobian.linearise`, None: no active
        muscle) at the step ``h``: None, or (W_a^T, (A0,RR^-1 W_a)^T, S, the factor of
        ``I + S (G_a x I3)``), ``S = h C_b + h^2 K_b``."""
        if jac is None:
            return None
        key = jac.beads.tobytes()
        hit = self._subspaces.get(key)
        if hit is None:
            b = jac.beads
            hit = (self.weights[:, b].T.tocsr(), np.ascontiguousarray(self.solved[:, b].T),
                   np.kron(self.gram[np.ix_(b, b)], np.eye(3)))
            if len(self._subspaces) > 32:
                self._subspaces.clear()
            self._subspaces[key] = hit
        wat, yat, g3 = hit
        s, _ = jac.system(h)  # the whole face's S, made (and kept) for its own solve
        return wat, yat, s, lu_factor(np.eye(len(s)) + s @ g3)

    def solve(self, rhs: np.ndarray, system) -> np.ndarray:
        """``(A0,RR + U_R S U_R^T)^-1 rhs`` for rhs (r, 3), ``system`` from
        :meth:`linearise`."""
        z = self.lu.solve(rhs)
        if system is None:
            return z
        wat, yat, s, factor = system
        q = np.asarray(wat @ z).reshape(-1)
        y = lu_solve(factor, s @ q, check_finite=False).reshape(-1, 3)
        z -= (y.T @ yat).T
        return z


@nb.njit(cache=True)
def displace(xp, vp, x, v, nodes, u, dx, dv):
    """``xp[n] = x[n] + dx u``, ``vp[n] = v[n] + dv u`` for the nodes ``nodes`` (r,) and
    ``u`` (r, 3), in place: a finite difference's moved state without temporaries."""
    for k in range(nodes.shape[0]):
        n = nodes[k]
        for a in range(3):
            xp[n, a] = x[n, a] + dx * u[k, a]
            vp[n, a] = v[n, a] + dv * u[k, a]


@nb.njit(cache=True)
def restore(xp, vp, x, v, nodes):
    """``xp[n] = x[n]``, ``vp[n] = v[n]`` for the nodes ``nodes``, in place."""
    for k in range(nodes.shape[0]):
        n = nodes[k]
        for a in range(3):
            xp[n, a] = x[n, a]
            vp[n, a] = v[n, a]


@nb.njit(cache=True)
def tangent_product(inertia, u, work, nodes, base, scale):
    """``inertia u - scale (work[nodes] - base)`` (r, 3): the step's matrix applied to ``u``
    from the forces ``work`` at the moved state and ``base`` at the unmoved one."""
    out = np.empty_like(u)
    for k in range(nodes.shape[0]):
        n = nodes[k]
        for a in range(3):
            out[k, a] = inertia[k] * u[k, a] - scale * (work[n, a] - base[k, a])
    return out


def krylov_region(physics, forces: ForceBundles, a_mat: sp.spmatrix,
                  muscle_weights: sp.spmatrix | None, radius: float) -> KrylovRegion:
    """The moving nodes within ``radius`` m of the mouth (:func:`mouth_centre`) and the
    constant parts of their correction: what of ``forces`` (the step's force kernel's bundles,
    without the contacts it steps apart) touches them, the factor of the constant matrix
    ``a_mat`` (moving nodes x moving nodes) over them, and the muscles' bead weights
    ``muscle_weights`` (moving nodes x beads) on them solved by it."""
    model = physics.model
    dyn = physics.dynamic
    centre = mouth_centre(model)
    near = np.linalg.norm(model.rest_positions[dyn] - centre, axis=1) < radius
    rows = np.flatnonzero(near).astype(np.int64)
    if len(rows) == 0:
        raise InputError(f"krylov_region of {radius * 1e3:g} mm holds no moving node of the "
                         "face", field="krylov_region")
    in_region = np.zeros(model.n_nodes, bool)
    in_region[dyn[rows]] = True
    forces, tethers = restrict_forces(forces, in_region)
    block = sp.csc_matrix(a_mat)[rows][:, rows].tocsc()
    lu = factorise(block)
    if muscle_weights is None or muscle_weights.shape[1] == 0:
        weights = sp.csc_matrix((len(rows), 0))
        solved = np.zeros((len(rows), 0))
    else:
        weights = sp.csr_matrix(muscle_weights)[rows].tocsc()
        solved = lu.solve(weights.toarray())
    gram = np.asarray(weights.T @ solved)
    return KrylovRegion(rows, dyn[rows].astype(np.int64), forces, tethers, lu, weights, solved,
                        gram)


__all__ = ["KrylovRegion", "krylov_region", "restrict_forces", "mouth_centre", "displace",
           "restore", "tangent_product"]
