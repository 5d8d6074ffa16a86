"""The rendered tongue tip's pose from an articulograph's tongue-tip coil.

The renderer bends the tongue's tip by a pose of two numbers in the mandible's frame, from
rest (:mod:`facemech.viz.dentition`): protrusion (m, forward, +z) and elevation (m, up, +y).
A recording with a tongue-tip coil (role ``tongue``: ``tt``, ``T1``, or the frontmost tongue
sensor) gives it: the coil's displacement from its first sample less the lower incisor's
(role ``lower_incisor``), so that what the jaw carries is not counted twice (the mandible's
rotation in speech, a few degrees, is left out: at the 10-20 mm between incisor and tip it
moves the tip under 1 mm).
"""

from __future__ import annotations

import numpy as np

from ..markerset import MarkerSet

#: the names a tongue-tip coil goes by, first found wins (case ignored)
TIP_NAMES = ("tt", "t1", "tongue_tip", "tonguetip", "ttip")


def tip_coil(ms: MarkerSet) -> str | None:
    """The tongue-tip coil of a set with roles: by name (:data:`TIP_NAMES`), else the tongue
    sensor furthest forward (median z); None without a tongue sensor with data."""
    roles = ms.meta.get("roles") or {}
    tongue = [n for n in ms.names if roles.get(n) == "tongue" and ms.valid[:, ms.index(n)].any()]
    if not tongue:
        return None
    for want in TIP_NAMES:
        for n in tongue:
            if n.casefold() == want:
                return n
    return max(tongue, key=lambda n: float(np.nanmedian(ms.marker(n)[:, 2])))


def tongue_tip_pose(ms: MarkerSet) -> tuple[np.ndarray, str] | None:
    """(frames, 2) m (protrusion, elevation) of the tongue tip from rest, and the coil used;
    None without a tongue-tip coil. Gaps are held at the last pose (the first one before it);
    the displacement is taken from the coil's first sample, the lower incisor's subtracted
    where the set has one."""
    name = tip_coil(ms)
    if name is None:
        return None
    tip = _held(ms.marker(name))
    roles = ms.meta.get("roles") or {}
    jaw = next((n for n in ms.names if roles.get(n) == "lower_incisor"
                and ms.valid[:, ms.index(n)].any()), None)
    disp = tip - tip[0]
    if jaw is not None:
        inc = _held(ms.marker(jaw))
        disp = disp - (inc - inc[0])
    return np.column_stack([disp[:, 2], disp[:, 1]]), name


def _held(p: np.ndarray) -> np.ndarray:
    """(frames, 3) with missing samples held at the nearest earlier one (the first valid one
    before the first sample)."""
    p = np.array(p, float)
    ok = np.all(np.isfinite(p), axis=1)
    idx = np.where(ok, np.arange(len(p)), -1)
    idx = np.maximum.accumulate(idx)
    first = int(np.argmax(ok))
    idx[idx < 0] = first
    return p[idx]
