"""Unit conversions used at the edges of the library (SI inside).

The papers give CGS values (dyne, cm, g); marker files are mostly in millimetres. Everything inside
facemech is in metres, kilograms, seconds and newtons.
"""

from __future__ import annotations

from .errors import InputError

#: metres per unit, for the length units marker and mesh files use
LENGTH_TO_M = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6}

DYNE = 1e-5  #: newton per dyne
CM = 1e-2  #: metre per centimetre
GRAM = 1e-3  #: kilogram per gram


def length_scale(unit: str, *, source: str | None = None, field: str | None = "units") -> float:
    """Metres per ``unit``.

    Parameters
    ----------
    unit : str
        One of ``m``, ``cm``, ``mm``, ``um`` (case-insensitive).

    Raises
    ------
    InputError
        If the unit is not known; units are never guessed.
    """
    key = str(unit).strip().lower()
    if key not in LENGTH_TO_M:
        raise InputError(
            f"unknown length unit {unit!r} (expected one of {', '.join(LENGTH_TO_M)})",
            source=source,
            field=field,
        )
    return LENGTH_TO_M[key]
