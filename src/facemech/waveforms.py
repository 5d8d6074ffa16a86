"""Smooth control waveforms: the raised-cosine ramp and bump used by every synthetic gesture.

Both are the same curve. The ramp rises from 0 at ``u <= 0`` to 1 at ``u >= 1`` as
``(1 - cos(pi u)) / 2``; the bump of width ``w`` centred on ``c`` is the ramp mirrored about its
centre, ``ramp(1 - 2 |t - c| / w)``, which equals ``(1 + cos(2 pi (t - c) / w)) / 2`` inside the
width and 0 outside.
"""

from __future__ import annotations

import numpy as np

__all__ = ["cosine_ramp", "cosine_bump"]


def cosine_ramp(u) -> np.ndarray:
    """Raised-cosine step: 0 for ``u <= 0``, 1 for ``u >= 1``, ``(1 - cos(pi u)) / 2`` between.

    Parameters
    ----------
    u : array_like
        Normalised time (dimensionless).

    Returns
    -------
    ndarray, same shape as ``u``, values in [0, 1].
    """
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


def cosine_bump(t, centre: float, width: float) -> np.ndarray:
    """Raised-cosine bump of unit height and total width ``width``, centred on ``centre``.

    Parameters
    ----------
    t : array_like
        Times, s.
    centre : float
        Time of the peak, s.
    width : float
        Total width from zero to zero, s (> 0).

    Returns
    -------
    ndarray, same shape as ``t``: 1 at ``centre``, 0 at and beyond ``centre +- width / 2``.
    """
    u = np.clip((np.asarray(t, dtype=float) - centre) / width, -0.5, 0.5)
    return 0.5 * (1.0 + np.cos(2.0 * np.pi * u))
