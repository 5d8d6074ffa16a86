"""Hill-type muscle (Lucero & Munhall 1999, eqs. 3-7) as pure kernels."""

from __future__ import annotations

import numba as nb
import numpy as np


def max_force(k_force: float, area):
    """The force of full activity k_f S (N) of eq. (3): k_f in N/m^2, S in m^2."""
    return k_force * np.asarray(area, float)


def steady_force(k_force: float, area, activity):
    """Steady-state force M_bar = k_f S E (eq. 3). k_f in N/m^2, S in m^2, E in [0, 1] -> N.
    The one place of eq. (3): the physics (:meth:`~facemech.physics.assembly.Physics.
    steady_force`) and the solvers (``SolverState.max_force``) take it from here."""
    return max_force(k_force, area) * np.asarray(activity, float)


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


#: half-width, as a share of a muscle's rest length, of the band over which the Jacobian takes
#: up the passive stiffness (the tension's kink at the rest length, eq. 7): well above the
#: rounding of a length (1e-16) and of a rest geometry built on another BLAS (1e-13), well below
#: any motion that matters (30 nm on a 3-cm muscle)
PASSIVE_STIFFNESS_BAND = 1e-6


@nb.njit(cache=True, inline="always")
def hill_derivatives(m_filtered, length, rest_length, velocity, k_passive, f1, f2, f3, f4):
    """Tension F (N) of eqs. (5)-(7) and its derivatives dF/dl (N/m) and dF/dl' (N s/m)."""
    r = length / rest_length
    u = (r**2.3 - 1.0) / 1.26
    fl = force_length(length, rest_length)
    au = abs(u)
    dfl = 0.0
    if au > 0.0:
        sgn = 1.0 if u > 0.0 else -1.0
        dfl = fl * (-1.62 * au**0.62 * sgn) * (2.3 * r**1.3 / 1.26) / rest_length
    arg = f3 + f4 * velocity
    fv = f1 + f2 * np.arctan(arg)
    tension = m_filtered * fl * fv
    d_len = m_filtered * dfl * fv
    stretch = length - rest_length
    if stretch > 0.0:
        tension += k_passive * stretch
    # the passive branch's stiffness, blended over a narrow band about the rest length: the
    # step's matrix is then continuous in the state (a sharp switch at l = l0 flipped on a
    # rounding difference, since every muscle starts at its rest length to the last bit)
    band = PASSIVE_STIFFNESS_BAND * rest_length
    if stretch >= band:
        d_len += k_passive
    elif stretch > -band:
        d_len += k_passive * (0.5 + 0.5 * stretch / band)
    d_vel = m_filtered * fl * f2 * f4 / (1.0 + arg * arg)
    return tension, d_len, d_vel


@nb.njit(cache=True, inline="always")
def activation_euler(m, m_rate, m_steady, tau, dt, zeta=1.0):
    """One explicit Euler step of tau^2 M'' + 2 zeta tau M' + M = M_bar (eq. 4; the seeds'
    filter is critically damped, ``zeta = 1``)."""
    m_acc = (m_steady - m - 2.0 * zeta * tau * m_rate) / (tau * tau)
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


@nb.njit(cache=True, inline="always")
def activation_exact_damped(m, m_rate, m_steady, tau, zeta, dt):
    """Exact solution over ``dt`` of ``tau^2 M'' + 2 zeta tau M' + M = M_bar`` for a constant
    M_bar, damping ratio ``0 < zeta <= 1`` (eq. 4 with a measured damping ratio; ``zeta = 1`` is
    :func:`activation_exact`, to the bit).

    With ``w = 1/tau``, ``s = zeta w`` and ``wd = w sqrt(1 - zeta^2)``, the error ``e = M - M_bar``
    and the rate ``r`` evolve as ``e(t) = exp(-s t) [e0 cos wd t + (r0 + s e0) / wd sin wd t]``
    and ``r(t) = exp(-s t) [r0 cos wd t - (w^2 e0 + s r0) / wd sin wd t]``.
    """
    if zeta >= 1.0:
        return activation_exact(m, m_rate, m_steady, tau, dt)
    w = 1.0 / tau
    s = zeta * w
    wd = w * np.sqrt(1.0 - zeta * zeta)
    e0 = m - m_steady
    decay = np.exp(-s * dt)
    c = np.cos(wd * dt)
    sn = np.sin(wd * dt)
    e = decay * (e0 * c + (m_rate + s * e0) / wd * sn)
    rate = decay * (m_rate * c - (w * w * e0 + s * m_rate) / wd * sn)
    return m_steady + e, rate


def activation_response(t, m_steady, tau, zeta=1.0):
    """Step response of eq. (4) from rest: ``M(t) = M_bar [1 - (1 + t/tau) exp(-t/tau)]`` when
    critically damped (``zeta = 1``, the seeds'); for ``zeta < 1``
    ``M_bar [1 - exp(-s t) (cos wd t + s / wd sin wd t)]`` (``s = zeta / tau``,
    ``wd = sqrt(1 - zeta^2) / tau``)."""
    t = np.asarray(t, float)
    if zeta >= 1.0:
        return m_steady * (1.0 - (1.0 + t / tau) * np.exp(-t / tau))
    s = zeta / tau
    wd = np.sqrt(1.0 - zeta * zeta) / tau
    return m_steady * (1.0 - np.exp(-s * t) * (np.cos(wd * t) + s / wd * np.sin(wd * t)))


def half_force_argument(f1: float, f2: float, f3: float) -> float:
    """``x`` with ``f1 + f2 atan(x)`` half of ``f1 + f2 atan(f3)`` (eq. 6; -0.716 for the
    seeds' constants: with f4 = 20 s/m, ``f3 + f4 v`` reaches it at v = -57 mm/s)."""
    return float(np.tan(((f1 + f2 * np.arctan(f3)) / 2.0 - f1) / f2))


def hill_half_speed(curvature: float) -> float:
    """Shortening speed, as a share of Vmax, at which Hill's (1938) hyperbola
    ``F/F0 = (1 - v/Vmax) / (1 + v / (a Vmax))`` gives half the isometric force:
    ``a / (2 a + 1)`` (1/6 for the common curvature a = 0.25)."""
    return curvature / (2.0 * curvature + 1.0)


def fibre_f4(rest_length, vmax, curvature, f1, f2, f3):
    """Per-muscle f4 of eq. (6), s/m, for an intrinsic speed ``vmax`` (fibre lengths per
    second): eq. (6) halves the force at the speed at which Hill's hyperbola of curvature
    ``curvature`` does, ``hill_half_speed(a) x vmax x l0`` (``l0`` the fibre length, m)."""
    v_half = hill_half_speed(curvature) * vmax * np.asarray(rest_length, float)
    return (f3 - half_force_argument(f1, f2, f3)) / v_half
