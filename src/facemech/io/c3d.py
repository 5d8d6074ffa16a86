"""C3D files via ezc3d: marker points (read and write) and analog channels (read).

ezc3d can crash the interpreter (a segfault, not an exception) on malformed files, so every read
runs in a child process; a crash there becomes a one-line error here. Missing points (residual
< 0, or NaN coordinates) become NaN. Labels beyond 255 are taken from LABELS2, LABELS3, ....
POINT:UNITS is honoured; a file without it needs the caller's ``units``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError, missing_input
from ..markerset import MarkerSet
from ..units import length_scale

_CHILD = r"""
import json, sys
import numpy as np
import ezc3d

def labels(group, key="LABELS"):
    out = []
    for suffix in ["", *map(str, range(2, 100))]:
        if key + suffix not in group:
            break
        out.extend(str(s).strip() for s in group[key + suffix]["value"])
    return out

path, what, target = sys.argv[1:4]
c = ezc3d.c3d(path)
if what == "analog":
    g = c["parameters"]["ANALOG"]
    rate = float(g["RATE"]["value"][0])
    data = np.asarray(c["data"]["analogs"], float)[0].T
    meta = {"rate": rate, "labels": labels(g), "units": ""}
else:
    g = c["parameters"]["POINT"]
    rate = float(g["RATE"]["value"][0])
    units = [str(u).strip() for u in g.get("UNITS", {}).get("value", [])]
    data = np.asarray(c["data"]["points"], float)[:3].transpose(2, 1, 0).copy()
    res = np.asarray(c["data"]["meta_points"]["residuals"], float)[0].T
    data[res < 0] = np.nan
    meta = {"rate": rate, "labels": labels(g)[: data.shape[1]],
            "units": units[0] if units else ""}
with open(target, "wb") as fh:
    np.savez(fh, data=data, meta=np.array(json.dumps(meta)))
"""


#: C3D processor types: the byte order of the header's integers, and which byte of the 4-byte
#: scale factor holds its sign bit (IEEE little-endian: the last; DEC VAX F: the second, the
#: high byte of its first 16-bit word; IEEE big-endian: the first)
PROCESSORS = {84: ("<", 3), 85: ("<", 1), 86: (">", 0)}


def check_header(path: Path) -> None:
    """Cheap sanity checks of a C3D header before ezc3d sees the file.

    ezc3d may crash or loop forever on a malformed or truncated file; these checks catch the
    common cases (wrong magic byte, data start beyond the end, fewer data bytes than the header
    announces, in any of the three byte orders) with a clear message.
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
    if processor not in PROCESSORS:
        raise InputError(f"corrupt C3D: unknown processor type {processor} (expected 84 Intel, "
                         "85 DEC or 86 MIPS)", source=str(path), field="processor")
    order, sign_byte = PROCESSORS[processor]
    w = np.frombuffer(head[:24], f"{order}u2")
    points, analog_total, first, last, data_start = (int(w[1]), int(w[2]), int(w[3]), int(w[4]),
                                                      int(w[8]))
    float_data = bool(head[12 + sign_byte] & 0x80)  # POINT:SCALE < 0 means float samples
    if last < first:
        raise InputError("corrupt C3D: last frame before first frame", source=str(path),
                         field="header")
    frames = last - first + 1
    per_value = 4 if float_data else 2
    need = (data_start - 1) * 512 + frames * (4 * points + analog_total) * per_value
    if data_start < 2 or need > size:
        raise InputError(f"truncated or corrupt C3D: the header announces {need} bytes, the "
                         f"file has {size}", source=str(path), field="header")


def _isolated_read(path: str | Path, what: str, timeout: float = 60.0):
    """Read points or analogs with ezc3d in a separate interpreter (crash- and hang-proof)."""
    path = Path(path)
    if not path.is_file():
        raise missing_input(path)
    try:
        import ezc3d  # noqa: F401
    except ImportError:
        raise InputError("reading C3D needs ezc3d (pip install 'facemech[c3d]')",
                         source=str(path)) from None
    check_header(path)
    fd, target = tempfile.mkstemp(suffix=".npz")
    os.close(fd)
    try:
        try:
            run = subprocess.run([sys.executable, "-c", _CHILD, str(path), what, target],
                                 capture_output=True, text=True, timeout=timeout,
                                 stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            raise InputError("corrupt C3D: the reader stopped (timed out)",
                             source=str(path)) from None
        if run.returncode != 0:
            last = (run.stderr.strip().splitlines() or [f"exit code {run.returncode}"])[-1]
            raise InputError(f"corrupt C3D ({last[-160:]})", source=str(path))
        with np.load(target) as z:
            data = z["data"]
            meta = json.loads(str(z["meta"]))
    finally:
        Path(target).unlink(missing_ok=True)
    if what == "analog":
        return meta["rate"], meta["labels"], data
    return meta["rate"], meta["labels"], meta["units"], data


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
