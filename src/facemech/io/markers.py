"""Marker trajectories in the documented wide CSV: ``time, NAME_x, NAME_y, NAME_z, ...``.

The length unit is given by a comment line ``# units: mm`` (or m, cm) or by the caller; it is
never guessed. Empty cells are missing samples (NaN).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import length_scale
from .atomic import atomic_path
from .tables import read_table


@dataclass(frozen=True)
class MarkerTable:
    """Markers (frames, markers, 3) in metres with their names and times (s)."""

    time: np.ndarray
    names: tuple[str, ...]
    positions: np.ndarray

    def marker(self, name: str, *, source: str | None = None) -> np.ndarray:
        if name not in self.names:
            raise InputError(f"no such marker (have {', '.join(self.names[:12])})",
                             source=source, field=name)
        return self.positions[:, self.names.index(name)]


def read_marker_csv(path: str | Path, *, units: str | None = None) -> MarkerTable:
    """Read a wide marker CSV; positions are returned in metres."""
    t, cols = read_table(path)
    meta = cols.pop("__meta__")
    unit = units or meta.get("units")
    if unit is None:
        raise InputError("no length unit: add a '# units: mm' line or pass units", source=str(path),
                         field="units")
    scale = length_scale(unit, source=str(path))
    names: list[str] = []
    for col in cols:
        base, _, axis = col.rpartition("_")
        if axis.lower() not in ("x", "y", "z") or not base:
            raise InputError("marker columns must be named NAME_x, NAME_y, NAME_z",
                             source=str(path), field=col)
        if base not in names:
            names.append(base)
    pos = np.empty((len(t), len(names), 3))
    for m, name in enumerate(names):
        for a, axis in enumerate("xyz"):
            key = next((c for c in cols if c.lower() == f"{name}_{axis}".lower()), None)
            if key is None:
                raise InputError("missing coordinate column", source=str(path),
                                 field=f"{name}_{axis}")
            pos[:, m, a] = cols[key] * scale
    return MarkerTable(t, tuple(names), pos)


def write_marker_csv(path: str | Path, table: MarkerTable, *, units: str = "mm") -> None:
    """Write a marker table (metres inside) as wide CSV in ``units``, atomically."""
    scale = length_scale(units)
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(f"# units: {units}\n")
        fh.write("time," + ",".join(f"{n}_{a}" for n in table.names for a in "xyz") + "\n")
        for k, t in enumerate(table.time):
            vals = table.positions[k].reshape(-1) / scale
            fh.write(f"{t:.6f}," + ",".join("" if not np.isfinite(v) else f"{v:.6f}"
                                             for v in vals) + "\n")
