"""Is an articulography recording the size of a mouth? Distances between sensors by role.

A unit off by ten (mm read as 0.1 mm, cm as mm) keeps a recording inside the marker readers'
1 mm - 5 m window but not inside a mouth. Each row below holds between two sensors of known
roles (:data:`facemech.markerset.SENSOR_ROLES`), or for one sensor's motion, in every speaker:

- upper to lower lip coil, median over the frames: 5-80 mm. At closure the coils lie at
  least the vermilion heights apart (upper 7-9 mm, lower 8-10 mm in adults; Farkas 1994,
  *Anthropometry of the Head and Face*); the mouth opens at most 36-70 mm between the incisors
  (Khare et al. 2012, J Maxillofac Oral Surg 11:309; mean 48.8 mm, Zawawi et al. 2003,
  J Can Dent Assoc 69:737). MOCHA fsew0: 23 mm; X-ray microbeam speakers: 15-30 mm.
- lower lip to lower incisor coil, median: 4-40 mm (the lower lip's vermilion to the incisor's
  labial gum, across the lip's thickness; MOCHA fsew0: 12.8 mm).
- the lower incisor's range over the recording: at most 80 mm (the largest mouth opening above,
  with a margin).
- all sensors together: at most 250 mm (a head is about 180-200 mm long, glabella to
  opisthocranion; Farkas 1994).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import InputError
from ..markerset import MarkerSet

#: (role a, role b, lowest, highest median distance in m, what it is)
DISTANCES = (("upper_lip", "lower_lip", 0.005, 0.080, "the upper to the lower lip"),
             ("lower_lip", "lower_incisor", 0.004, 0.040, "the lower lip to the lower incisor"))
JAW_RANGE_MAX = 0.080  #: m, the lower incisor's largest range of motion accepted
HEAD_SPAN_MAX = 0.250  #: m, the largest extent of all sensors accepted


def _first(roles: dict, role: str, ms: MarkerSet) -> int | None:
    for name, r in roles.items():
        if r == role and name in ms.names:
            return ms.names.index(name)
    return None


def _fail(what: str, value: float, low: float | None, high: float, ms: MarkerSet, source):
    """An InputError naming the unit: the value as it reads, the window, the factor off."""
    window = f"{low * 1e3:g}-{high * 1e3:g} mm" if low is not None else f"at most {high * 1e3:g} mm"
    mid = np.sqrt(low * high) if low is not None else high / 4
    factor = 10.0 ** round(float(np.log10(value / mid))) if value > 0 else 0.0
    hint = ""
    if factor >= 10:
        hint = f": the values look {factor:g} times too large"
    elif 0 < factor <= 0.1:
        hint = f": the values look {1 / factor:g} times too small"
    unit = ms.meta.get("file_units", ms.source_units)
    raise InputError(f"{what}: {value * 1e3:.3g} mm, outside a mouth ({window}){hint}; is the "
                     f"file's unit ({unit}) right? (--units)", source=source, field="units")


def check_anatomy(ms: MarkerSet, *, source: str | None = None) -> MarkerSet:
    """Refuse an articulography set whose sensors are not a mouth's size apart (rows above).

    Parameters
    ----------
    ms : positions in m, ``meta["roles"]`` naming the sensors' roles
    source : the file, for the message

    Returns
    -------
    MarkerSet
        ``ms`` unchanged.

    Raises
    ------
    InputError
        Field ``units``, naming the distance, its window and the factor it is off by.
    """
    roles = ms.meta.get("roles") or {}
    pos = ms.positions
    with warnings.catch_warnings():  # a sensor without data is not an error here
        warnings.simplefilter("ignore", RuntimeWarning)
        for a, b, low, high, what in DISTANCES:
            ia, ib = _first(roles, a, ms), _first(roles, b, ms)
            if ia is None or ib is None:
                continue
            d = np.linalg.norm(pos[:, ia] - pos[:, ib], axis=1)
            d = d[np.isfinite(d)]
            med = float(np.median(d)) if len(d) else 0.0  # 0: coils not placed (zeros)
            if med > 0 and not low <= med <= high:
                _fail(f"{what} ({ms.names[ia]} to {ms.names[ib]}, median)",
                      med, low, high, ms, source)
        jaw = _first(roles, "lower_incisor", ms)
        if jaw is not None:
            p = pos[:, jaw][np.all(np.isfinite(pos[:, jaw]), axis=1)]
            if len(p) > 1 and float(np.ptp(p, axis=0).max()) > JAW_RANGE_MAX:
                _fail(f"the lower incisor's ({ms.names[jaw]}) range of motion",
                      float(np.ptp(p, axis=0).max()), None, JAW_RANGE_MAX, ms, source)
    pts = pos[ms.valid]
    if len(pts) > 1 and ms.n_markers > 1 and float(np.ptp(pts, axis=0).max()) > HEAD_SPAN_MAX:
        _fail("the sensors' span", float(np.ptp(pts, axis=0).max()), None, HEAD_SPAN_MAX, ms,
              source)
    return ms
