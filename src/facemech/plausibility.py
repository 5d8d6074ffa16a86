"""Plausibility checks at the edges: input that is readable but cannot be what it claims.

A value in the wrong unit reads without complaint and gives a wrong answer later (a time column
in milliseconds makes 1 s of speech last 17 minutes; degrees typed as radians open the jaw by
1146 degrees). Each check here raises :class:`~facemech.errors.InputError` naming the file, the
field and the likely cause, and returns its input unchanged when it passes. The limits are
module constants, and each check takes its limits as arguments for a user who really means it.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["JAW_LIMITS_DEG", "EMG_MIN_RATE_HZ", "MAX_CONTROL_STEP_S", "MAX_DURATION_S",
           "FACE_SIZE_M", "check_jaw_angles", "check_time_column", "check_face_size"]

#: degrees, the anatomical range of jaw opening: slightly closed past rest (a clench) to a wide
#: yawn; speech uses 0-20 degrees (Ostry & Flanagan 1989; REALISM.md)
JAW_LIMITS_DEG = (-5.0, 35.0)
#: Hz, the lowest sampling rate of surface EMG worth processing (its energy lies at 20-450 Hz)
EMG_MIN_RATE_HZ = 200.0
#: s, the longest interval between two rows of a control (activity or jaw) table
MAX_CONTROL_STEP_S = 10.0
#: s, the longest single recording accepted (two hours)
MAX_DURATION_S = 7200.0
#: m, the largest extent of a face scan: an adult face is 120-160 mm wide (bizygomatic) and
#: 180-250 mm from hairline to chin; a head with neck and shoulders reaches about 500 mm
FACE_SIZE_M = (0.10, 0.60)


def check_jaw_angles(angles_rad, *, source=None, field: str = "jaw_angle",
                     limits_deg: tuple[float, float] = JAW_LIMITS_DEG) -> np.ndarray:
    """Refuse jaw angles outside the anatomical range.

    Parameters
    ----------
    angles_rad : array_like, rad, positive opening the mouth
    source, field : the file and the column, for the message
    limits_deg : (lowest, highest) accepted angle, degrees

    Returns
    -------
    ndarray
        The angles, rad.
    """
    a = np.asarray(angles_rad, dtype=float)
    if not np.all(np.isfinite(a)):
        raise InputError("jaw angles must be finite", source=source, field=field)
    lo, hi = np.radians(limits_deg)
    bad = (a < lo) | (a > hi)
    if not bad.any():
        return a
    k = int(np.argmax(bad))
    deg = np.degrees(a[k])
    hint = ""
    if limits_deg[0] <= a[k] <= limits_deg[1] and abs(a[k]) > hi:
        hint = f"; {a[k]:g} looks like degrees given as radians"
    raise InputError(f"sample {k + 1}: a jaw angle of {deg:.1f} degrees is outside the "
                     f"anatomical range {limits_deg[0]:g} to {limits_deg[1]:g} degrees{hint}",
                     source=source, field=field)


def check_time_column(t, *, kind: str, source=None, field: str = "time") -> np.ndarray:
    """Refuse a time column whose sampling says it is not in seconds.

    Parameters
    ----------
    t : array_like, s as declared, strictly increasing
    kind : ``"emg"`` (a raw signal: at least :data:`EMG_MIN_RATE_HZ`) or ``"control"`` (activity
        or jaw rows: at most :data:`MAX_CONTROL_STEP_S` apart)
    source, field : the file and the column, for the message

    Returns
    -------
    ndarray
        The times, s.
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return t
    step = float(np.median(np.diff(t)))
    duration = float(t[-1] - t[0])
    as_ms = "; the times look like milliseconds (the column must be seconds)"
    if kind == "emg" and 1.0 / step < EMG_MIN_RATE_HZ:
        hint = as_ms if 1e3 / step >= EMG_MIN_RATE_HZ else ""
        raise InputError(f"EMG sampled at {1.0 / step:.4g} Hz, below the {EMG_MIN_RATE_HZ:g} Hz "
                         f"that surface EMG needs{hint}", source=source, field=field)
    if kind == "control" and step > MAX_CONTROL_STEP_S:
        raise InputError(f"rows {step:.4g} s apart{as_ms}", source=source, field=field)
    if duration > MAX_DURATION_S:
        raise InputError(f"a recording of {duration:.4g} s is longer than "
                         f"{MAX_DURATION_S:g} s{as_ms}", source=source, field=field)
    return t


def check_face_size(size_m: float, *, unit: str, source=None, field: str = "units",
                    limits_m: tuple[float, float] = FACE_SIZE_M) -> float:
    """Refuse a face scan whose size, read in its declared unit, is not a face's.

    Parameters
    ----------
    size_m : the scan's largest extent along the three axes, metres as read with ``unit``
    unit : the declared length unit of the file (``m``, ``cm``, ``mm``, ``um``)
    source, field : the file and the field, for the message
    limits_m : (smallest, largest) accepted extent, m

    Returns
    -------
    float
        ``size_m``.
    """
    from .units import LENGTH_TO_M, length_scale

    lo, hi = limits_m
    if lo <= size_m <= hi:
        return size_m
    values = size_m / length_scale(unit, source=source)
    guess = min(LENGTH_TO_M, key=lambda u: abs(np.log(values * LENGTH_TO_M[u] / 0.15)))
    hint = f"; the values look like {guess}" if guess != unit.strip().lower() else ""
    raise InputError(f"the face spans {size_m * 1e3:.4g} mm read in {unit}, not "
                     f"{lo * 1e3:g}-{hi * 1e3:g} mm{hint}", source=source, field=field)
