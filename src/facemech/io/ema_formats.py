"""Articulography in: Carstens AG500/AG501 ``.pos`` and NDI Wave text exports.

Both give 3-D sensor positions without names in the data: the sensors are ``Ch1``, ``Ch2``, ...
(Carstens) or ``S1``, ``S2``, ... (NDI), or the caller's ``sensors`` (names in channel order,
whose roles :func:`facemech.io.articulography.sensor_role` finds). The result is a MarkerSet as
:mod:`facemech.io.articulography` makes it (metres, model axes, ``meta["roles"]``, empty ends
dropped, the anatomy checked).

Carstens ``.pos``: an optional text header (``AG50xDATA_V00n``, its length in bytes,
``NumberOfChannels``, ``SamplingFrequencyHz``), then float32 little-endian records of 7 values
per frame and channel (``x y z phi theta rms extra``, mm and degrees; without a header 12
channels at 200 Hz); y front-back, z up; x = y = z = 0 or NaN is missing. NDI Wave: a time
column, then per sensor a group ending in ``Q0 Qx Qy Qz Tx Ty Tz`` (mm); a frame whose state
is not ``OK`` is missing; x front-back, z up. Sources and details: docs/formats.md.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..units import length_scale
from .articulography import _assemble, _check_time, _Layout, _time_unit, _units

CARSTENS = _Layout("Carstens AG50x", "y", -1, "z", +1, "x")
NDI = _Layout("NDI Wave", "x", +1, "z", +1, "y")
POS_VALUES = 7  #: float32 values per channel and frame: x y z phi theta rms extra
AG500_CHANNELS = 12  #: channels of a header-less AG500 .pos file
AG500_RATE_HZ = 200.0  #: Hz, the AG500's sampling rate
POS_MAGIC = b"AG50xDATA_V00"


def _names(sensors, n: int, prefix: str, src: str) -> list[str]:
    if sensors is None:
        return [f"{prefix}{k + 1}" for k in range(n)]
    names = [s.strip() for s in (sensors.split(",") if isinstance(sensors, str) else sensors)]
    if len(names) != n or not all(names):
        raise InputError(f"{len(names)} sensor names for {n} sensors", source=src,
                         field="sensors")
    return names


def _pos_header(raw: bytes, src: str) -> tuple[int, int, float]:
    """(header bytes, channels, rate in Hz) of an AG50x header."""
    lines = raw[:4096].split(b"\n")
    if len(lines) < 4 or not re.fullmatch(rb"AG50xDATA_V00[123]", lines[0].strip()):
        raise InputError("not a Carstens AG50x header (AG50xDATA_V001-3)", source=src,
                         field="AG50xDATA")
    if not re.fullmatch(rb"\d{1,8}", lines[1].strip()):
        raise InputError(f"header length {lines[1][:20]!r} is not a number", source=src,
                         field="header length")
    size = int(lines[1])
    text = raw[:size].decode("latin-1")
    fields = dict(m.groups() for m in re.finditer(r"(?m)^(\w+)=([^\r\n\x00]*)", text))
    try:
        n = int(fields["NumberOfChannels"])
    except (KeyError, ValueError):
        raise InputError("no channel count", source=src, field="NumberOfChannels") from None
    try:
        rate = float(fields["SamplingFrequencyHz"])
    except (KeyError, ValueError):
        raise InputError("no sampling rate", source=src, field="SamplingFrequencyHz") from None
    if not 1 <= n <= 64:
        raise InputError(f"{n} channels (expected 1-64)", source=src, field="NumberOfChannels")
    if not (np.isfinite(rate) and 0 < rate <= 100_000):
        raise InputError(f"{rate:g} Hz is not a sampling rate", source=src,
                         field="SamplingFrequencyHz")
    if size < len(lines[0]) + len(lines[1]) + 2 or size > len(raw):
        raise InputError(f"header length {size} bytes does not fit the file ({len(raw)} "
                         "bytes)", source=src, field="header length")
    return size, n, rate


def read_carstens_pos(path: str | Path, *, units: str | None = None, rate: float | None = None,
                      sensors=None):
    """Read a Carstens AG500/AG501 ``.pos`` file (layout in the module docstring).

    Parameters
    ----------
    path : the file
    units : the positions' unit (default mm)
    rate : Hz, for a header-less AG500 file (default 200); a header's rate is the file's
    sensors : names of the channels in order (a list or comma-separated), for their roles

    Returns
    -------
    MarkerSet
        The channels' positions in m, model axes; angles, RMS and spare values in
        ``meta["pos_extra"]`` ((frames, channels, 4): phi, theta deg, rms, extra).
    """
    src = str(path)
    raw = Path(path).read_bytes()
    if raw.startswith(POS_MAGIC):
        size, n, file_rate = _pos_header(raw, src)
        if rate is not None and abs(rate - file_rate) > 1e-9 * file_rate:
            raise InputError(f"the header says {file_rate:g} Hz; a rate is not needed",
                             source=src, field="rate")
        rate, body, fmt = file_rate, raw[size:], "carstens-ag501"
    else:
        n, body, fmt = AG500_CHANNELS, raw, "carstens-ag500"
        rate = AG500_RATE_HZ if rate is None else float(rate)
        if not (np.isfinite(rate) and rate > 0):
            raise InputError(f"sampling rate {rate:g} Hz is not a positive rate", source=src,
                             field="rate")
    record = n * POS_VALUES * 4
    if len(body) == 0 or len(body) % record:
        raise InputError(f"{len(body)} bytes of samples are not whole frames of {n} channels x "
                         f"{POS_VALUES} float32 ({record} bytes)", source=src, field="data")
    with np.errstate(all="ignore"):
        vals = np.frombuffer(body, "<f4").astype(float).reshape(-1, n, POS_VALUES)
    xyz = vals[..., :3].copy()
    xyz[np.all(xyz == 0.0, axis=2) | ~np.all(np.isfinite(xyz), axis=2)] = np.nan
    names = _names(sensors, n, "Ch", src)
    scale, source_units = _units(units, length_scale("mm"), "mm", src)
    time = np.arange(len(vals)) / rate
    return _assemble(src, fmt, CARSTENS, time,  # x y z: lateral, front-back, up
                     {c: xyz[:, k] for k, c in enumerate(names)},
                     scale, source_units, units or "mm", "NaN, or x = y = z = 0",
                     {"pos_extra": vals[..., 3:].copy(), "rate_from": "header" if
                      fmt == "carstens-ag501" else "the AG500's 200 Hz or --rate"})


# ---- NDI Wave -------------------------------------------------------------------------------
_T = re.compile(r"(?i)^(?:.*\b)?T([xyz])(?:[ ._]*\d+)?$")


def _ndi_groups(header: list[str], src: str) -> tuple[int, list[tuple[int, int, int, int | None]]]:
    """(time column, per sensor (Tx, Ty, Tz, state column or None)) from the header row."""
    low = [h.strip().lower() for h in header]
    times = [k for k, h in enumerate(low) if "time" in h]
    if not times:
        raise InputError("no time column (a column whose name holds 'time')", source=src,
                         field="time")
    groups, state = [], None
    k = 0
    while k < len(header):
        m = _T.match(header[k].strip())
        if "state" in low[k] or "status" in low[k]:
            state = k
        if m and m.group(1).lower() == "x":
            tri = [_T.match(header[j].strip()) if j < len(header) else None
                   for j in (k, k + 1, k + 2)]
            if not all(tri) or [t.group(1).lower() for t in tri] != ["x", "y", "z"]:
                raise InputError("a Tx column not followed by Ty and Tz", source=src,
                                 field=header[k].strip())
            groups.append((k, k + 1, k + 2, state))
            state = None
            k += 3
            continue
        k += 1
    if not groups:
        raise InputError("no sensor positions (columns Tx Ty Tz)", source=src, field="Tx")
    return times[0], groups


def read_ndi_wave(path: str | Path, *, units: str | None = None, sensors=None):
    """Read an NDI Wave (WaveFront) tab-separated export (layout in the module docstring).

    Parameters
    ----------
    path : the file
    units : the positions' unit (default mm)
    sensors : names of the sensors in column order (a list or comma-separated)

    Returns
    -------
    MarkerSet
        The sensors' positions in m, model axes; ``meta["time_units"]`` the time column's.
    """
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise InputError("binary data where a text NDI Wave export was expected",
                         source=src) from None
    lines = [ln.rstrip("\r") for ln in text.split("\n") if ln.strip()]
    if len(lines) < 3:
        raise InputError("needs a header row and at least two frames", source=src,
                         field="data")
    header = lines[0].split("\t")
    tcol, groups = _ndi_groups(header, src)
    frames = len(lines) - 1
    t = np.empty(frames)
    xyz = np.full((frames, len(groups), 3), np.nan)
    for r, line in enumerate(lines[1:]):
        cells = line.split("\t")
        if len(cells) < len(header):
            raise InputError(f"row {r + 2} has {len(cells)} cells, the header {len(header)}",
                             source=src, field="columns")
        try:
            t[r] = float(cells[tcol])
        except ValueError:
            raise InputError(f"row {r + 2}: the time is not a number", source=src,
                             field=header[tcol].strip()) from None
        for s, (cx, cy, cz, cs) in enumerate(groups):
            if cs is not None and cells[cs].strip().lower() not in ("ok", ""):
                continue
            raw = [cells[c].strip() for c in (cx, cy, cz)]
            if any(not v for v in raw):
                continue
            try:
                xyz[r, s] = [float(v) for v in raw]
            except ValueError:
                raise InputError(f"row {r + 2}: a position that is not a number", source=src,
                                 field=header[cx].strip()) from None
    _check_time(t, src, "time")
    unit, factor = _time_unit(float(np.median(np.diff(t))), src)
    xyz[~np.all(np.isfinite(xyz), axis=2)] = np.nan
    names = _names(sensors, len(groups), "S", src)
    scale, source_units = _units(units, length_scale("mm"), "mm", src)
    # the file's (Tx, Ty, Tz) reordered as (lateral, front-back, up): an odd permutation, so
    # the lateral column changes sign to keep the frame right-handed (Ty = Tz x Tx)
    return _assemble(src, "ndi-wave", NDI, t * factor,
                     {c: xyz[:, k][:, [1, 0, 2]] * [-1.0, 1.0, 1.0] for k, c in enumerate(names)},
                     scale, source_units,
                     units or "mm", "empty, or a State other than OK", {"time_units": unit})


def is_ndi_wave(path: str | Path) -> bool:
    """Whether a tab-separated file's first line has NDI Wave's Tx Ty Tz columns."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            first = fh.readline()
    except OSError:
        return False
    cells = [c.strip() for c in first.split("\t")]
    return any(_T.match(c) for c in cells) and not first.startswith("NO_OF_FRAMES")
