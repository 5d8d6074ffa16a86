"""Gaps in marker trajectories: find them, and fill short interior ones with a cubic spline.

Filled samples are flagged in ``MarkerSet.filled``; gaps longer than the limit and gaps at the
start or end of a recording stay NaN. Nothing is filled unless asked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from ..markerset import MarkerSet


@dataclass(frozen=True)
class Gap:
    """A run of missing samples of one marker: frames ``start`` to ``stop - 1``."""

    marker: str
    start: int
    stop: int
    interior: bool

    @property
    def length(self) -> int:
        return self.stop - self.start


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in a 1-D boolean array."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.nonzero(d == 1)[0].tolist(), np.nonzero(d == -1)[0].tolist(),
                    strict=True))


def find_gaps(ms: MarkerSet) -> list[Gap]:
    """Every gap of every marker, in marker order."""
    out = []
    for m, name in enumerate(ms.names):
        for a, b in runs(~ms.valid[:, m]):
            out.append(Gap(name, a, b, a > 0 and b < ms.n_frames))
    return out


def fill_gaps(ms: MarkerSet, max_length: int) -> tuple[MarkerSet, list[Gap], list[Gap]]:
    """Fill interior gaps of at most ``max_length`` frames by a cubic spline through the valid
    samples of the marker. Returns the new set, the gaps filled and the gaps left."""
    pos = ms.positions.copy()
    filled = ms.filled.copy()
    done, left = [], []
    for g in find_gaps(ms):
        if not g.interior or g.length > max_length:
            left.append(g)
            continue
        m = ms.names.index(g.marker)
        ok = ms.valid[:, m]
        if ok.sum() < 4:
            left.append(g)
            continue
        spline = CubicSpline(ms.time[ok], ms.positions[ok, m], axis=0)
        pos[g.start:g.stop, m] = spline(ms.time[g.start:g.stop])
        filled[g.start:g.stop, m] = True
        done.append(g)
    return ms.with_positions(pos, filled=filled), done, left
