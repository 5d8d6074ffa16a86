"""Hill-type muscle (Lucero & Munhall 1999, eqs. 3-7) as pure kernels."""

from __future__ import annotations

import numba as nb
import numpy as np


def steady_force(k_force: float, area, activity):
    """Steady-state force M_bar = k_f S E (eq. 3). k_f in N/m^2, S in m^2, E in [0, 1] -> N."""
    return k_force * np.asarray(area, float) * np.asarray(activity, float)


@nb.njit(cache=True, inline="always")
def force_length(length, rest_length):
    """Force-length factor exp(-|((l/l0)^2.3 - 1)/1.26|^1.62) of eq. (5) (1 at rest length)."""
    r = length / rest_length
    return np.exp(-np.abs((r**2.3 - 1.0) / 1.26) ** 1.62)


@nb.njit(cache=True, inline="always")
def hill_force(m_filtered, length, rest_length, velocity, k_passive, f1, f2, f3, f4):
    """Total muscle tension F (N), eqs. (5)-(7).

    ``F = M' [f1 + f2 atan(f3 + f4 dl/dt)] + [k_m (l - l0)]^+`` with the length-scaled
    ``M' = M fl(l)`` of eq. (5) (the paper writes M; SPEC reads it as M'). ``velocity`` is dl/dt in
    m/s (negative when shortening), f4 in s/m.
    """
    mp = m_filtered * force_length(length, rest_length)
    active = mp * (f1 + f2 * np.arctan(f3 + f4 * velocity))
    passive = k_passive * (length - rest_length)
    if passive < 0.0:
        passive = 0.0
    return active + passive


@nb.njit(cache=True, inline="always")
def activation_euler(m, m_rate, m_steady, tau, dt):
    """One explicit Euler step of tau^2 M'' + 2 tau M' + M = M_bar (eq. 4)."""
    m_acc = (m_steady - m - 2.0 * tau * m_rate) / (tau * tau)
    return m + dt * m_rate, m_rate + dt * m_acc


@nb.njit(cache=True, inline="always")
def activation_exact(m, m_rate, m_steady, tau, dt):
    """Exact solution of eq. (4) over ``dt`` for a constant M_bar (critically damped)."""
    e0 = m - m_steady
    c = m_rate + e0 / tau
    decay = np.exp(-dt / tau)
    e = (e0 + c * dt) * decay
    rate = (m_rate - c * dt / tau) * decay
    return m_steady + e, rate


def activation_response(t, m_steady, tau):
    """Step response of eq. (4) from rest: M(t) = M_bar [1 - (1 + t/tau) exp(-t/tau)]."""
    t = np.asarray(t, float)
    return m_steady * (1.0 - (1.0 + t / tau) * np.exp(-t / tau))
