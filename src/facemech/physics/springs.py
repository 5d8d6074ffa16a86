"""Spring laws of the skin mesh (Lucero & Munhall 1999, eqs. 1-2).

Pure scalar kernels compiled with numba; :func:`spring_force` is the vectorised form for users
and tests. Forces are tensions: positive when the spring pulls its ends together.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True, inline="always")
def tension(length, rest_length, k_low, k_high, knee, sigma, biphasic):
    """Tension (N) of one spring at ``length`` (m).

    Elongation: linear ``k dl``, or biphasic for dermal-fatty springs (eq. 1):
    ``k1 dl`` up to ``dl/l0 = knee``, then ``knee k1 l0 + k2 (dl - knee l0)``.
    Compression (eq. 2): ``k l0 tan(pi sigma dl / (2 l0))``, which grows without bound as the
    length goes to zero (the argument is held just inside -pi/2 beyond full compression).

    Eq. (2) as printed, ``k tan(...)``, is not dimensionally consistent (a stiffness times a pure
    number); it matches the CGS model for the 1-cm reference spring when the force scale is
    ``k l0``, which we use: the compression stiffness at rest is then ``pi sigma k / 2``
    (1.54 k), and it does not depend on the length unit.

    ``sigma <= 0`` replaces eq. (2) by the mirror image of eq. (1) (the continuum tissue): linear
    ``k dl`` in compression, stiffening to ``k_high`` beyond ``knee`` of compression for
    biphasic springs, so that the tissue stiffens both ways and no element collapses.
    """
    return tension_at(length, rest_length, k_low, k_high, knee,
                      knee * rest_length if biphasic else np.inf, sigma)


@nb.njit(cache=True, inline="always")
def tension_at(length, rest_length, k_low, k_high, knee, knee_length, sigma):
    """:func:`tension` with the spring's knee as a length: ``knee_length`` (m) is ``knee *
    rest_length`` for a biphasic spring and ``inf`` for a linear one (the force kernels keep it
    per spring, :attr:`~facemech.physics.bundles.SpringBundle.knee_length`).

    Beyond the knee is rare, and comes in whole regions of the face at a time: a branch the
    processor predicts well. (Computing all three laws and selecting cost a quarter of the spring
    loop; the numbers are the same.)
    """
    dl = length - rest_length
    if sigma > 0.0 and dl < 0.0:
        arg = 0.5 * np.pi * sigma * dl / rest_length
        if arg < -0.4999 * np.pi:
            arg = -0.4999 * np.pi
        return k_low * rest_length * np.tan(arg)
    if abs(dl) > knee_length:
        if dl > knee_length:
            return knee * k_low * rest_length + k_high * (dl - knee_length)
        return -knee * k_low * rest_length + k_high * (dl + knee_length)
    return k_low * dl


def spring_force(length, rest_length, k_low, k_high=None, *, biphasic=False, knee=0.2,
                 sigma=0.98):
    """Vectorised :func:`tension` (eqs. 1-2). Arrays broadcast; lengths in m, stiffness in N/m."""
    length, rest_length, k_low = np.broadcast_arrays(
        np.asarray(length, float), np.asarray(rest_length, float), np.asarray(k_low, float))
    k_high = k_low * 10 if k_high is None else np.broadcast_to(np.asarray(k_high, float),
                                                                length.shape)
    out = np.empty(length.shape)
    flat = out.reshape(-1)
    for n, (l, l0, k1, k2) in enumerate(zip(length.reshape(-1), rest_length.reshape(-1),
                                             k_low.reshape(-1), np.reshape(k_high, -1),
                                             strict=True)):
        flat[n] = tension(l, l0, k1, k2, knee, sigma, biphasic)
    return out


def scaled_stiffness(k_ref: float, rest_length, ref_length: float = 1e-2):
    """Stiffness of a spring of ``rest_length`` given ``k_ref`` for a 1-cm one: k_ref l_ref / l0."""
    return k_ref * ref_length / np.asarray(rest_length, float)
