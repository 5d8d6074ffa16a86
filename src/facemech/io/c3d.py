"""C3D files via ezc3d: marker points (read and write) and analog channels (read).

ezc3d can crash the interpreter (a segfault, not an exception) on malformed files, so every read
runs in a child process; a crash there becomes a one-line error here. Missing points (residual
< 0, or NaN coordinates) become NaN. Labels beyond 255 are taken from LABELS2, LABELS3, ....
POINT:UNITS is honoured; a file without it needs the caller's ``units``.
"""

from __future__ import annotations

import multiprocessing as mp
import queue as queue_mod
import time
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..markerset import MarkerSet
from ..units import length_scale
from .atomic import atomic_path


def _labels(group: dict, key: str = "LABELS") -> list[str]:
    out: list[str] = []
    for suffix in ("", *map(str, range(2, 100))):
        k = f"{key}{suffix}"
        if k not in group:
            break
        out.extend(str(s).strip() for s in group[k]["value"])
    return out


def _read_child(path: str, what: str, q) -> None:  # pragma: no cover - runs in the child
    try:
        import ezc3d

        c = ezc3d.c3d(path)
        if what == "analog":
            group = c["parameters"]["ANALOG"]
            rate = float(group["RATE"]["value"][0])
            data = np.asarray(c["data"]["analogs"], float)[0].T  # (samples, channels)
            q.put(("ok", (rate, _labels(group), data)))
            return
        group = c["parameters"]["POINT"]
        rate = float(group["RATE"]["value"][0])
        units = [str(u).strip() for u in group.get("UNITS", {}).get("value", [])]
        pts = np.asarray(c["data"]["points"], float)[:3].transpose(2, 1, 0).copy()
        res = np.asarray(c["data"]["meta_points"]["residuals"], float)[0].T
        pts[res < 0] = np.nan
        labels = _labels(group)[: pts.shape[1]]
        q.put(("ok", (rate, labels, units[0] if units else "", pts)))
    except Exception as exc:
        q.put(("error", f"{type(exc).__name__}: {exc}"))


def check_header(path: Path) -> None:
    """Cheap sanity checks of a C3D header before ezc3d sees the file.

    ezc3d may crash or loop forever on a malformed or truncated file; these checks catch the
    common cases (wrong magic byte, data start beyond the end, fewer data bytes than the header
    announces) with a clear message.
    """
    size = path.stat().st_size
    with path.open("rb") as fh:
        head = fh.read(512)
        fh.seek(0)
    if len(head) < 512 or head[1] != 0x50:
        raise InputError("not a C3D file (bad header)", source=str(path), field="header")
    param_block = head[0]
    if param_block < 2 or (param_block - 1) * 512 + 4 > size:
        raise InputError("corrupt C3D: parameter section outside the file", source=str(path),
                         field="header")
    with path.open("rb") as fh:
        fh.seek((param_block - 1) * 512)
        phead = fh.read(4)
    processor = phead[3] if len(phead) == 4 else 0
    if processor != 84:  # only Intel (little-endian) files get the size check
        return
    w = np.frombuffer(head[:24], "<u2")
    points, analog_total, first, last, data_start = (int(w[1]), int(w[2]), int(w[3]), int(w[4]),
                                                      int(w[8]))
    scale = float(np.frombuffer(head[12:16], "<f4")[0])
    if last < first:
        raise InputError("corrupt C3D: last frame before first frame", source=str(path),
                         field="header")
    frames = last - first + 1
    per_value = 4 if scale < 0 else 2
    need = (data_start - 1) * 512 + frames * (4 * points + analog_total) * per_value
    if data_start < 2 or need > size:
        raise InputError(f"truncated or corrupt C3D: the header announces {need} bytes, the "
                         f"file has {size}", source=str(path), field="header")


def _isolated_read(path: str | Path, what: str, timeout: float = 60.0):
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    check_header(path)
    try:
        import ezc3d  # noqa: F401
    except ImportError:
        raise InputError("reading C3D needs ezc3d (pip install 'facemech[c3d]')",
                         source=str(path)) from None
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    proc = ctx.Process(target=_read_child, args=(str(path), what, q), daemon=True)
    proc.start()
    deadline = time.monotonic() + timeout
    try:
        while True:
            try:
                status, payload = q.get(timeout=0.2)
                break
            except queue_mod.Empty:
                if not proc.is_alive() or time.monotonic() > deadline:
                    proc.kill()
                    proc.join(timeout=5)
                    why = ("timed out" if proc.exitcode in (None, -9)
                           else f"exit code {proc.exitcode}")
                    raise InputError(f"corrupt C3D: the reader stopped ({why})",
                                     source=str(path)) from None
    finally:
        proc.join(timeout=5)
        q.close()
    if status != "ok":
        raise InputError(f"corrupt C3D ({payload})", source=str(path))
    return payload


def read_c3d_analog(path: str | Path):
    """Analog rate (Hz), channel labels and data (samples, channels) of a C3D file."""
    rate, labels, data = _isolated_read(path, "analog")
    if not labels or data.size == 0:
        raise InputError("no analog channels", source=str(path), field="ANALOG:LABELS")
    return rate, labels, data


def read_c3d_points(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Marker points of a C3D file as a :class:`MarkerSet` in metres."""
    rate, labels, file_units, pts = _isolated_read(path, "points")
    unit = file_units or units
    if not unit:
        raise InputError("no POINT:UNITS in the file: pass units (--units)", source=str(path),
                         field="POINT:UNITS")
    scale = length_scale(unit, source=str(path), field="POINT:UNITS")
    if len(labels) != pts.shape[1]:
        raise InputError(f"{len(labels)} labels for {pts.shape[1]} points", source=str(path),
                         field="POINT:LABELS")
    return MarkerSet(pts * scale, tuple(labels), rate, source_units=unit,
                     meta={"source": str(path), "format": "c3d"})


def write_c3d_points(path: str | Path, ms: MarkerSet, *, units: str | None = None) -> None:
    """Write a marker set to C3D (float, POINT:UNITS set, NaN samples as missing points)."""
    try:
        import ezc3d
    except ImportError:
        raise InputError("writing C3D needs ezc3d (pip install 'facemech[c3d]')",
                         source=str(path)) from None
    units = units or ms.source_units
    scale = length_scale(units)
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [ms.rate]
    c["parameters"]["POINT"]["LABELS"]["value"] = tuple(ms.names)
    c["parameters"]["POINT"]["UNITS"]["value"] = [units]
    pts = np.ones((4, ms.n_markers, ms.n_frames))
    pts[:3] = (ms.positions / scale).transpose(2, 1, 0)
    c["data"]["points"] = pts
    with atomic_path(path, suffix=".c3d") as tmp:
        c.write(str(tmp))
