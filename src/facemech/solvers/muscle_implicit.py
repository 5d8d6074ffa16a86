"""Muscles in the implicit solve: their stiffness and damping, exactly, through beads.

Physiological muscle forces (newtons, eq. 3 with the specific tension of muscle) are strong
next to soft tissue. Two of their terms are too stiff for the explicit part of a step:

- the velocity term of the Hill law (eq. 6): the tension changes by
  ``M' f2 f4 / (1 + (f3 + f4 l')^2)`` per m/s of lengthening, about 10 N s/m per newton;
- the geometric stiffness of a tension: a bead pulled with tension T along a segment of length
  l resists sideways motion with T / l, which for orbicularis oris at full activity (16 N over
  6-mm segments) is thousands of N/m.

Every muscle acts on the tissue through a few beads (weighted means of nodes, fixed weights):
the node forces are ``U f_b`` with ``U = W (x) I3`` constant, W the (moving nodes x beads)
weights. The force's Jacobian is therefore ``U K_b U^T`` and ``U C_b U^T`` with small dense
bead-space matrices, and the implicit matrix ``A0 + U S U^T`` (``S = h C_b + h^2 K_b``) is
solved with the constant factorisation of A0 by the Sherman-Morrison-Woodbury identity:
``A0^-1 W`` is solved once, when the stepper is made. The muscles are linearised once per frame,
at the frame's start and with the larger of the filtered force there and at the frame's end
(an upper bound keeps the explicit remainder stable); each step then costs a back-substitution
of the small system.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import scipy.sparse as sp
from scipy.linalg import lu_factor, lu_solve

from ..physics.assembly import bead_positions
from ..physics.kinds import SPHINCTER
from ..physics.muscle import PASSIVE_STIFFNESS_BAND, hill_derivatives

__all__ = ["PASSIVE_STIFFNESS_BAND", "hill_derivatives", "bead_jacobian", "MuscleJacobian"]

@nb.njit(cache=True)
def bead_jacobian(muscles, bp, bv, pos, vel, m_force, active):
    """Bead-space stiffness ``-df/dp`` and damping ``-df/dv`` of the active muscles.

    Parameters
    ----------
    muscles : MuscleBundle -- pulling along their length (through beads)
    bp, bv : (B, 3) m and m/s -- the beads' positions and velocities
    pos, vel : (nodes, 3) m and m/s -- the nodes' (for the linear muscles' origins)
    m_force : (muscles,) N -- the filtered force M of eq. (4)
    active : (a,) int64 -- the muscles to take

    Returns
    -------
    stiff : (3B, 3B) N/m, bead-major
    damp : (3B, 3B) N s/m, bead-major
    """
    kind = muscles.kind
    origin = muscles.origin
    offset = muscles.offset
    bead_start = muscles.bead_start
    rest_length = muscles.rest_length
    k_passive = muscles.k_passive
    f1, f2, f3, f4 = muscles.f1, muscles.f2, muscles.f3, muscles.f4
    n3 = 3 * bead_start[bead_start.shape[0] - 1]
    stiff = np.zeros((n3, n3))
    damp = np.zeros((n3, n3))
    for q in range(active.shape[0]):
        m = active[q]
        b0 = bead_start[m]
        b1 = bead_start[m + 1]
        if kind[m] == SPHINCTER:
            nseg = b1 - b0 - 1
            units = np.zeros((nseg, 3))
            seglen = np.zeros(nseg)
            length = 0.0
            rate = 0.0
            for s in range(nseg):
                b = b0 + s
                for a in range(3):
                    units[s, a] = bp[b + 1, a] - bp[b, a]
                seglen[s] = np.sqrt(units[s, 0] ** 2 + units[s, 1] ** 2 + units[s, 2] ** 2)
                for a in range(3):
                    units[s, a] /= seglen[s]
                length += seglen[s]
                for a in range(3):
                    rate += units[s, a] * (bv[b + 1, a] - bv[b, a])
            t, dl, dv = hill_derivatives(m_force[m], length, rest_length[m], rate, k_passive[m],
                                         f1, f2, f3, f4[m])
            # gradient of the path length at each bead
            grad = np.zeros((b1 - b0, 3))
            for s in range(nseg):
                for a in range(3):
                    grad[s, a] -= units[s, a]
                    grad[s + 1, a] += units[s, a]
            for i in range(b1 - b0):
                for j in range(b1 - b0):
                    for a in range(3):
                        for c in range(3):
                            gg = grad[i, a] * grad[j, c]
                            stiff[3 * (b0 + i) + a, 3 * (b0 + j) + c] += dl * gg
                            damp[3 * (b0 + i) + a, 3 * (b0 + j) + c] += dv * gg
            # geometric stiffness of the tension: T / l (I - u u^T) on each segment
            for s in range(nseg):
                g = t / seglen[s]
                for a in range(3):
                    for c in range(3):
                        pa = g * ((1.0 if a == c else 0.0) - units[s, a] * units[s, c])
                        i0 = 3 * (b0 + s)
                        i1 = 3 * (b0 + s + 1)
                        stiff[i0 + a, i0 + c] += pa
                        stiff[i1 + a, i1 + c] += pa
                        stiff[i0 + a, i1 + c] -= pa
                        stiff[i1 + a, i0 + c] -= pa
        else:
            o = origin[m]
            d = np.empty(3)
            for a in range(3):
                d[a] = bp[b0, a] - pos[o, a] - offset[m, a]
            length = np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
            rate = 0.0
            for a in range(3):
                d[a] /= length
                rate += d[a] * (bv[b0, a] - vel[o, a])
            t, dl, dv = hill_derivatives(m_force[m], length, rest_length[m], rate, k_passive[m],
                                         f1, f2, f3, f4[m])
            g = t / length
            for a in range(3):
                for c in range(3):
                    uu = d[a] * d[c]
                    stiff[3 * b0 + a, 3 * b0 + c] += dl * uu + g * ((1.0 if a == c else 0.0) - uu)
                    damp[3 * b0 + a, 3 * b0 + c] += dv * uu
    return stiff, damp


class MuscleJacobian:
    """Bead-space linearisation of the muscles and the Woodbury solve (see the module doc).

    Parameters
    ----------
    physics : Physics
    lu : the factorisation of A0 (moving nodes x moving nodes, shared by the axes)
    """

    THRESHOLD = 1e-6  # N: a muscle with less filtered and steady force takes no part

    def __init__(self, physics, lu):
        self.physics = physics
        self.muscles = physics.forces.muscles
        self.lu = lu
        row = np.full(physics.model.n_nodes, -1, np.int64)
        row[physics.dynamic] = np.arange(physics.n_dynamic)
        r = row[self.muscles.nodes]
        ok = r >= 0
        self.n_beads = int(self.muscles.bead_start[-1])
        self.W = sp.csr_matrix((self.muscles.weights[ok], (r[ok], self.muscles.bead[ok])),
                               shape=(physics.n_dynamic, self.n_beads))
        self.Y = lu.solve(self.W.toarray()) if self.n_beads else np.zeros((physics.n_dynamic, 0))
        self.G = np.asarray(self.W.T @ self.Y)
        # a cache of what depends on the set of active muscles only (no state: the results of
        # every call are those of a fresh object)
        self._subspaces: dict = {}

    def _subspace(self, active):
        """W, W^T, A0^-1 W and G x I3 restricted to the beads of the active muscles (cached per
        set of active muscles, which changes seldom)."""
        key = active.tobytes()
        hit = self._subspaces.get(key)
        if hit is None:
            bead_start = self.muscles.bead_start
            beads = np.concatenate([np.arange(bead_start[m], bead_start[m + 1])
                                    for m in active])
            wa = self.W[:, beads].tocsr()
            # (A0^-1 W)^T kept row-major: y^T (A0^-1 W)^T is a wide product (3 rows), which BLAS
            # does in about half the time of the tall (A0^-1 W) y with its 3 columns
            hit = (beads, (3 * beads[:, None] + np.arange(3)).reshape(-1), wa, wa.T.tocsr(),
                   np.ascontiguousarray(self.Y[:, beads].T),
                   np.kron(self.G[np.ix_(beads, beads)], np.eye(3)))
            if len(self._subspaces) > 32:
                self._subspaces.clear()
            self._subspaces[key] = hit
        return hit

    def linearise(self, pos, vel, m_force, m_steady):
        """Bead-space Jacobian of the active muscles at a state, or None when none is active."""
        mu = self.muscles
        active = np.nonzero((np.abs(m_force) > self.THRESHOLD)
                            | (np.abs(m_steady) > self.THRESHOLD))[0].astype(np.int64)
        if len(active) == 0:
            return None
        bp, bv = bead_positions(pos, vel, mu.nodes, mu.weights, mu.bead, self.n_beads)
        stiff, damp = bead_jacobian(mu, bp, bv, pos, vel, np.asarray(m_force, float), active)
        beads, idx, wa, wat, yat, g3 = self._subspace(active)
        return _Linearised(beads, stiff[np.ix_(idx, idx)], damp[np.ix_(idx, idx)],
                           wa, wat, yat, g3)

    def apply_stiffness(self, v: np.ndarray, jac) -> np.ndarray:
        """``U K_b U^T v`` for v (moving nodes, 3); zero without active muscles."""
        if jac is None:
            return np.zeros_like(v)
        q = np.asarray(jac.wat @ v).reshape(-1)
        return np.asarray(jac.wa @ (jac.stiff @ q).reshape(-1, 3))

    def solve(self, rhs: np.ndarray, jac, h: float) -> np.ndarray:
        """``(A0 + U (h C_b + h^2 K_b) U^T)^-1 rhs`` for rhs (moving nodes, 3)."""
        z = self.lu.solve(rhs)
        if jac is None:
            return z
        s, factor = jac.system(h)
        q = np.asarray(jac.wat @ z).reshape(-1)
        y = lu_solve(factor, s @ q, check_finite=False).reshape(-1, 3)
        z -= (y.T @ jac.yat).T
        return z


class _Linearised:
    """The active muscles' bead-space Jacobian and, per step size, the factorised small system
    ``I + S (G x I3)`` of the Woodbury identity (``S = h C_b + h^2 K_b``)."""

    def __init__(self, beads, stiff, damp, wa, wat, yat, g3):
        self.beads, self.stiff, self.damp = beads, stiff, damp
        self.wa, self.wat, self.yat, self.g3 = wa, wat, yat, g3
        self._systems: dict = {}

    def system(self, h: float):
        hit = self._systems.get(h)
        if hit is None:
            s = h * self.damp + h * h * self.stiff
            hit = (s, lu_factor(np.eye(len(s)) + s @ self.g3))
            self._systems[h] = hit
        return hit
