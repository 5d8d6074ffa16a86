"""OpenSim TRC marker files (tab separated), read and write."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from ..markerset import MarkerSet
from ..units import length_scale


def read_trc(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Read a TRC file; the header's ``Units`` is honoured (``units`` only if it has none)."""
    path = Path(path)
    lines = path.read_text(encoding="utf-8-sig").splitlines()  # a byte-order mark is read
    if len(lines) < 5 or not lines[0].startswith("PathFileType"):
        raise InputError("not a TRC file (no PathFileType line)", source=str(path))
    keys = [k.strip() for k in lines[1].split("\t")]
    vals = [v.strip() for v in lines[2].split("\t")]
    info = dict(zip(keys, vals, strict=False))
    unit = info.get("Units") or units
    if not unit:
        raise InputError("no Units in the header: pass units (--units)", source=str(path),
                         field="Units")
    scale = length_scale(unit, source=str(path), field="Units")
    try:
        rate = float(info["DataRate"])
        n_markers = int(info["NumMarkers"])
    except (KeyError, ValueError):
        raise InputError("bad header", source=str(path), field="DataRate/NumMarkers") from None
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"DataRate {rate:g} Hz is not a positive finite rate", source=str(path),
                         field="DataRate")
    names = [c.strip() for c in lines[3].split("\t")[2:] if c.strip()]
    if len(names) != n_markers:
        raise InputError(f"{len(names)} marker labels but NumMarkers = {n_markers}",
                         source=str(path), field="NumMarkers")
    rows = []
    for ln, line in enumerate(lines[5:], start=6):
        if not line.strip():
            continue
        cells = line.split("\t")
        cells += [""] * (2 + 3 * n_markers - len(cells))
        try:
            rows.append([float(c) if c.strip() else np.nan for c in cells[: 2 + 3 * n_markers]])
        except ValueError:
            raise InputError(f"line {ln}: non-numeric value", source=str(path),
                             field="data") from None
    data = np.array(rows)
    if len(data) == 0:
        raise InputError("no frames", source=str(path), field="data")
    t = data[:, 1]
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("the Time column must be finite and strictly increasing",
                         source=str(path), field="Time")
    if len(data) > 1:
        file_rate = 1.0 / float(np.median(np.diff(data[:, 1])))
        if abs(file_rate - rate) > 0.01 * rate:
            raise InputError(f"DataRate {rate:g} Hz but the Time column is sampled at "
                             f"{file_rate:.4g} Hz", source=str(path), field="DataRate")
    pos = data[:, 2:].reshape(len(data), n_markers, 3) * scale
    return MarkerSet(pos, tuple(names), rate, time=data[:, 1], source_units=unit,
                     meta={"source": str(path), "format": "trc"})


def write_trc(path: str | Path, ms: MarkerSet, *, units: str | None = None) -> None:
    """Write a TRC file in ``units`` (default: the marker set's source unit)."""
    units = units or ms.source_units
    scale = length_scale(units)
    path = Path(path)
    n, m = ms.n_frames, ms.n_markers
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(f"PathFileType\t4\t(X/Y/Z)\t{path.name}\n")
        fh.write("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\t"
                 "OrigDataStartFrame\tOrigNumFrames\n")
        fh.write(f"{ms.rate:g}\t{ms.rate:g}\t{n}\t{m}\t{units}\t{ms.rate:g}\t1\t{n}\n")
        fh.write("Frame#\tTime\t" + "\t\t\t".join(ms.names) + "\t\t\n")
        fh.write("\t\t" + "\t".join(f"{a}{k + 1}" for k in range(m) for a in "XYZ") + "\n\n")
        for k in range(n):
            vals = ms.positions[k].reshape(-1) / scale
            fh.write(f"{k + 1}\t{ms.time[k]:.6f}\t" + "\t".join(
                "" if not np.isfinite(v) else repr(float(v)) for v in vals) + "\n")
