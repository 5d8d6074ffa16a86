"""A floor under each prism's volume, stepped implicitly prism by prism after the global solve.

A one-sided penalty below ``J_f V0`` keeps deep prisms from being crushed under held gestures
(docs/model.md, "creep"): energy ``kappa C^2 / 2`` with ``C = V - J_f V0 < 0`` and
``kappa = K_f / V0`` (``K_f`` a modulus, Pa). Each prism below its floor takes the backward-Euler
step of its own penalty along its volume gradient ``g_i`` after the solve:

    mu = -h kappa C* / (1 + h^2 kappa w),   w = sum_i |g_i|^2 / m_i,
    Delta v_i = mu g_i / m_i,               Delta x_i = h Delta v_i,

a contraction of the deficit for any stiffness. Prisms above their floor are untouched (to the
bit); kinematic nodes (``1 / m = 0``) do not move.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from ..geometry.prism import _bilinear_volume_gradient


class VolumeFloor(NamedTuple):
    """The prisms' volume floor (see the module doc).

    Attributes
    ----------
    nodes : (p, 6) int64 -- each prism's nodes
    floor : (p,) m^3 -- the volume below which the floor acts, ``J_f V0``
    kappa : (p,) N/m^5 -- ``K_f / V0``
    """

    nodes: np.ndarray
    floor: np.ndarray
    kappa: np.ndarray

    @classmethod
    def empty(cls) -> VolumeFloor:
        """No floor."""
        return cls(np.zeros((0, 6), np.int64), np.zeros(0), np.zeros(0))

    @classmethod
    def of(cls, nodes: np.ndarray, rest_volume: np.ndarray, ratio: float,
           modulus: float) -> VolumeFloor:
        """The floor at ``ratio`` (J_f, 0 < J_f < 1) of each rest volume (m^3), with the
        modulus ``modulus`` (Pa); a ratio of 0 gives no floor."""
        if ratio <= 0.0:
            return cls.empty()
        v0 = np.asarray(rest_volume, float)
        return cls(np.ascontiguousarray(nodes, np.int64), ratio * v0, modulus / v0)


#: sweeps over the prisms per step at most: a prism's step changes its neighbours' volumes
#: (they share nodes), so the coupled backward-Euler step is solved by Gauss-Seidel sweeps on
#: each prism's accumulated impulse until none changes a volume by more than SWEEP_TOL of its
#: floor
SWEEPS = 16
SWEEP_TOL = 1e-3


@nb.njit(cache=True)
def resolve_volume_floor(pos, vel, inv_mass, nodes, floor, kappa, h):
    """Step every prism below its floor implicitly (see the module doc), in place.

    The coupled step is solved by sweeps over the prisms (Gauss-Seidel, at most
    :data:`SWEEPS`): each prism keeps its accumulated position impulse ``lam = h mu`` (>= 0,
    the floor only pushes) and takes ``dlam = (-C - lam / (h^2 kappa)) / (w + 1 / (h^2
    kappa))``, which for one prism with its volume linearised is the module doc's step, and
    for many converges to the coupled one (the compliant-constraint form of the same
    backward-Euler step).

    Parameters
    ----------
    pos, vel : (nodes, 3) m, m/s -- the state after the step's global solve; changed in place
    inv_mass : (nodes,) 1/kg -- 0 for kinematic nodes
    nodes, floor, kappa : the :class:`VolumeFloor`'s arrays
    h : float, s -- the step

    Returns
    -------
    int -- the number of prisms the floor acted on
    """
    lam = np.zeros(nodes.shape[0])
    p = np.empty((6, 3))
    g = np.empty((6, 3))
    # a prism found above its floor needs no new look until one of its nodes moves: ``seen``
    # is the count of moves when it was last found so (-1: not yet), ``moved`` each node's
    # count at its last move. Skipping it changes nothing (its volume is the same to the bit),
    # and after the first sweep only the prisms near the floor's work are looked at again
    seen = np.full(nodes.shape[0], -1, np.int64)
    moved = np.full(pos.shape[0], -1, np.int64)
    moves = 0
    for _ in range(SWEEPS):
        largest = 0.0
        for e in range(nodes.shape[0]):
            if seen[e] >= 0:
                last = -1
                for k in range(6):
                    last = max(last, moved[nodes[e, k]])
                if last <= seen[e]:
                    continue
            for k in range(6):
                for a in range(3):
                    p[k, a] = pos[nodes[e, k], a]
            deficit = _bilinear_volume_gradient(p, g) / 12.0 - floor[e]
            if deficit >= 0.0 and lam[e] == 0.0:
                seen[e] = moves
                continue
            seen[e] = -1
            w = 0.0
            for k in range(6):
                im = inv_mass[nodes[e, k]]
                for a in range(3):
                    g[k, a] /= 12.0
                    w += g[k, a] * g[k, a] * im
            if w <= 0.0:
                continue
            compliance = 1.0 / (h * h * kappa[e])
            d = (-deficit - compliance * lam[e]) / (w + compliance)
            if lam[e] + d < 0.0:
                d = -lam[e]
            lam[e] += d
            moves += 1
            for k in range(6):
                i = nodes[e, k]
                moved[i] = moves
                im = inv_mass[i]
                for a in range(3):
                    dx = d * g[k, a] * im
                    pos[i, a] += dx
                    vel[i, a] += dx / h
            largest = max(largest, abs(d) * w / floor[e])
        if largest < SWEEP_TOL:
            break
    acted = 0
    for e in range(nodes.shape[0]):
        if lam[e] > 0.0:
            acted += 1
    return acted


__all__ = ["VolumeFloor", "resolve_volume_floor", "SWEEPS"]
