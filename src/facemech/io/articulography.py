"""Articulography in: EMA (MOCHA-TIMIT, mngu0) and X-ray microbeam (Wisconsin XRMB) files.

Each reader returns a :class:`~facemech.markerset.MarkerSet` in metres and in the model's axes
(+x the subject's left, +y up, +z forward out of the face), the file's sensors by their own
names, NaN where a sample is missing. ``meta`` carries ``format``, ``axes`` (how the file's axes
became the model's, and the evidence), ``missing_value``, ``midsagittal`` (True for 2-D data:
every sensor has x = 0 and only y and z are data) and ``roles`` (sensor name -> one of
:data:`ROLES`), plus ``file_units``, ``notes`` and the channels left out.

Layouts: EST track files (``.ema``, ``.est``; Edinburgh Speech Tools), MOCHA-TIMIT's 20
channels in 0.01 mm (EST or plain text, 500 Hz), mngu0's ``NAME_px NAME_py NAME_pz`` coils in
mm, XRMB ``.txy`` pellets in micrometres (1000000: lost; the time unit taken from the step).
Axes: the anatomy decides the signs where the sensors allow (the lips in front of the tongue,
velum or molar; the upper lip above the lower lip and the lower incisor), the layout's
convention otherwise; a 3-D file stays right-handed. Layouts, sources and axes in full:
docs/formats.md, "Articulography".
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..kinematics.trim import drop_empty_ends
from ..markerset import SENSOR_ROLES as ROLES  # noqa: F401  (re-exported: the roles a reader gives)
from ..markerset import MarkerSet
from ..units import length_scale
from .plausible_ema import check_anatomy

#: MOCHA-TIMIT's 20 EMA channels, in file order (``****``: unused channels)
MOCHA_CHANNELS = ("ui_x", "li_x", "ul_x", "ll_x", "tt_x", "ui_y", "li_y", "ul_y", "ll_y", "tt_y",
                  "tb_x", "td_x", "v_x", "****", "bn_x", "tb_y", "td_y", "v_y", "****", "bn_y")
MOCHA_RATE_HZ = 500.0  #: Hz, MOCHA-TIMIT's EMA sampling rate (its plain layout has no time)
MOCHA_UNIT_M = 1e-5  #: m per file unit, MOCHA-TIMIT EMA (0.01 mm; MOCHAtools divide by 100)
MNGU0_UNIT_M = 1e-3  #: m per file unit, mngu0 EMA (mm)
XRMB_PELLETS = ("UL", "LL", "T1", "T2", "T3", "T4", "MNI", "MNM")  #: XRMB pellet order
XRMB_MISSING = 1_000_000.0  #: XRMB's code for a lost pellet coordinate
XRMB_UNIT = "um"  #: XRMB pellet coordinates are in micrometres
XRMB_RATES_HZ = (20.0, 2000.0)  #: Hz, the rates that decide the unit of a .txy time column

#: m: a front-back (vertical) separation of the sensors smaller than this leaves the sign of
#: that axis to the layout's documented convention (lips 20-60 mm in front of the tongue,
#: upper lip about 10 mm above the lower lip at rest)
FRONT_BACK_EVIDENCE = 0.005
VERTICAL_EVIDENCE = 0.002

_ALIASES = {
    "upper_lip": {"ul", "upperlip", "ulip", "ls"},
    "lower_lip": {"ll", "lowerlip", "llip"},
    "lower_incisor": {"li", "jaw", "lj", "mni", "mi", "mani", "lowerincisor", "lowerjaw",
                      "jawincisor", "lowerincisors"},
    "upper_incisor": {"ui", "upperincisor", "upperincisors", "maxi"},
    "molar": {"mm", "mnm", "manm", "molar", "jawmolar", "lowermolar"},
    "velum": {"v", "vel", "velum"},
    "reference": {"bn", "ref", "nose", "nasion", "maxn", "maxg", "head", "hl", "hr", "hc"},
    "tongue": {"tt", "tb", "td", "tm", "tbl", "tbk", "tr", "tongue"},
}


def sensor_role(name: str) -> str:
    """The role of a sensor from its name (one of :data:`ROLES`; ``other`` if unknown).

    Names are compared without case, digits at the end and punctuation: ``ul``, ``UL``,
    ``upperlip`` -> ``upper_lip``; ``li``, ``jaw``, ``MNI`` -> ``lower_incisor``; ``T1``-``T4``,
    ``tt``, ``tb``, ``td`` -> ``tongue``; ``bn``, ``ref`` -> ``reference``.
    """
    key = re.sub(r"[^a-z0-9]", "", str(name).lower())
    if re.fullmatch(r"t\d+", key) or key.startswith("tongue"):
        return "tongue"
    for role, names in _ALIASES.items():
        if key in names or key.rstrip("0123456789") in names:
            return role
    if key.startswith(("ref", "head", "nose")):
        return "reference"
    return "other"


# ---- EST track files ------------------------------------------------------------------------
@dataclass(frozen=True)
class EstTrack:
    """An EST track file as stored: header, channel names, times, break flags and values.

    Attributes
    ----------
    header : key -> value text of the header lines
    names : (channels,) channel names (``""`` where the header names none)
    time : (frames,) s
    present : (frames,) bool, False for a break frame
    values : (frames, channels) float, the file's units
    binary : whether the body was binary
    """

    header: dict
    names: tuple
    time: np.ndarray
    present: np.ndarray
    values: np.ndarray
    binary: bool


EST_MAGIC = b"EST_File"


def is_est(path: str | Path) -> bool:
    """Whether ``path`` starts with the EST file magic ``EST_File``."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(EST_MAGIC)) == EST_MAGIC
    except OSError:
        return False


def _int_field(header: dict, key: str, src: str, *, minimum: int) -> int:
    if key not in header:
        raise InputError("missing header line", source=src, field=key)
    try:
        value = int(header[key].split()[0])
    except (ValueError, IndexError):
        raise InputError(f"{header[key]!r} is not an integer", source=src, field=key) from None
    if value < minimum:
        raise InputError(f"{value} is below {minimum}", source=src, field=key)
    return value


def read_est_track(path: str | Path) -> EstTrack:
    """Read an EST track file (binary or ascii body), as stored.

    Parameters
    ----------
    path : the file

    Returns
    -------
    EstTrack

    Raises
    ------
    InputError
        Naming the header field (``EST_File``, ``DataType``, ``ByteOrder``, ``NumFrames``,
        ``NumChannels``, ``EST_Header_End``, ``Channel_N``) or the body (``data``): a
        truncated or over-long binary body, a row with the wrong number of values, a value that
        is not a number.
    """
    src = str(path)
    raw = Path(path).read_bytes()
    if not raw.startswith(EST_MAGIC):
        raise InputError("not an EST file (no 'EST_File' at the start)", source=src,
                         field="EST_File")
    end = re.search(rb"(^|\n)[ \t]*EST_Header_End[^\n]*(\n|$)", raw)
    if end is None:
        raise InputError("the header has no end line", source=src, field="EST_Header_End")
    head = raw[:end.start()].decode("latin-1").splitlines()
    body = raw[end.end():]
    kind = head[0].split()[1:2]
    if kind != ["Track"]:
        raise InputError(f"an EST {' '.join(kind) or 'file'} of no known type, not a Track",
                         source=src, field="EST_File")
    header: dict[str, str] = {}
    for line in head[1:]:
        parts = line.strip().split(None, 1)
        if parts and not parts[0].startswith(";"):
            header[parts[0]] = parts[1].strip() if len(parts) > 1 else ""
    n_frames = _int_field(header, "NumFrames", src, minimum=1)
    n_channels = _int_field(header, "NumChannels", src, minimum=1)
    n_aux = _int_field(header, "NumAuxChannels", src, minimum=0) \
        if "NumAuxChannels" in header else 0
    names = [""] * n_channels
    for key, value in header.items():
        m = re.fullmatch(r"Channel_(\d+)", key)
        if m:
            k = int(m.group(1))
            if k >= n_channels:
                raise InputError(f"channel {k} but NumChannels = {n_channels}", source=src,
                                 field=key)
            names[k] = value.strip()
    data_type = header.get("DataType", "ascii").strip().lower()
    if data_type not in ("ascii", "binary"):
        raise InputError(f"DataType {header['DataType']!r} (expected binary or ascii)",
                         source=src, field="DataType")
    breaks = "BreaksPresent" in header  # EST reads a break flag whenever the line is there
    width = 1 + int(breaks) + n_channels
    if data_type == "binary":
        table = _binary_body(body, header, n_frames, width, src)
    else:
        table = _ascii_rows(body, n_frames, width, n_aux, src)
    present = table[:, 1] != 0.0 if breaks else np.ones(n_frames, bool)
    return EstTrack(header, tuple(names), table[:, 0].copy(), present,
                    table[:, 1 + int(breaks):].copy(), data_type == "binary")


def _binary_body(body: bytes, header: dict, n_frames: int, width: int, src: str) -> np.ndarray:
    """The binary body's table (frames, width) in the header's byte order: InputError naming
    ``ByteOrder`` when it is unknown or makes the times no time series (the other order
    would), ``NumFrames`` when the body's length is not the header's."""
    order = header.get("ByteOrder", "").strip().lower()
    endian = {"01": "<", "10": ">", "littleendian": "<", "bigendian": ">"}.get(order)
    if endian is None:
        raise InputError(f"ByteOrder {header.get('ByteOrder')!r} (expected 01 for "
                         "little-endian or 10 for big-endian)", source=src, field="ByteOrder")
    need = n_frames * width * 4
    if len(body) != need:
        what = "truncated" if len(body) < need else "longer than the header says"
        raise InputError(f"binary body {what}: {len(body)} bytes, NumFrames = {n_frames} "
                         f"frames of {width} float32 need {need}", source=src,
                         field="NumFrames")
    table = _binary_table(body, endian, n_frames, width)
    if not _is_time(table[:, 0]):
        other = "<" if endian == ">" else ">"
        if _is_time(_binary_table(body, other, n_frames, width)[:, 0]):
            said = "big" if endian == ">" else "little"
            raise InputError(f"ByteOrder {header['ByteOrder']} ({said}-endian) makes the "
                             f"times no time series; the data are {_ENDIAN[other]}: the "
                             "header's byte order is wrong", source=src, field="ByteOrder")
    return table


_ENDIAN = {"<": "little-endian", ">": "big-endian"}


def _binary_table(body: bytes, endian: str, n_frames: int, width: int) -> np.ndarray:
    """(frames, width) float of a float32 body; bytes that make no number give NaN, silently."""
    with np.errstate(all="ignore"):
        return np.frombuffer(body, dtype=f"{endian}f4").reshape(n_frames, width).astype(float)


def _is_time(t: np.ndarray) -> bool:
    """Whether ``t`` is a plausible time column: finite, strictly increasing, below a day."""
    with np.errstate(all="ignore"):
        return bool(np.all(np.isfinite(t)) and np.all(np.abs(t) < 86400.0)
                    and np.all(np.diff(t) > 0))


def _ascii_rows(body: bytes, n_frames: int, width: int, n_aux: int, src: str) -> np.ndarray:
    try:
        text = body.decode("ascii")
    except UnicodeDecodeError:
        raise InputError("binary data in an ascii EST body (DataType ascii)", source=src,
                         field="DataType") from None
    rows = [ln.split() for ln in text.splitlines() if ln.strip()]
    if len(rows) != n_frames:
        raise InputError(f"{len(rows)} rows but NumFrames = {n_frames}", source=src,
                         field="NumFrames")
    table = np.empty((n_frames, width))
    for k, cells in enumerate(rows):
        if len(cells) != width + n_aux:
            raise InputError(f"row {k + 1} has {len(cells)} values, expected {width + n_aux} "
                             "(time, break flag, channels)", source=src, field="columns")
        try:
            table[k] = [float(c) for c in cells[:width]]
        except ValueError:
            raise InputError(f"row {k + 1}: a value that is not a number", source=src,
                             field="data") from None
    return table


# ---- conventions and assembly ---------------------------------------------------------------
@dataclass(frozen=True)
class _Layout:
    """How a layout's axes point: file axis names and their documented signs."""

    name: str  # for messages: "MOCHA-TIMIT", "mngu0", "XRMB"
    front_back: str  # file axis along the front-back direction
    front_sign: int  # +1: the file's axis points forward; -1: backward
    vertical: str
    up_sign: int
    lateral: str | None = None  # 3-D files only


MOCHA = _Layout("MOCHA-TIMIT", "x", -1, "y", +1)
MNGU0 = _Layout("mngu0", "py", -1, "pz", +1, "px")
XRMB = _Layout("XRMB", "x", +1, "y", +1)


def _sign(coords: np.ndarray, names: list[str], roles: dict, a_roles, b_roles, paired: bool,
          evidence: float):
    """Which way group a lies from group b along one file axis, from medians over the frames.

    Parameters
    ----------
    coords : (frames, sensors) one file coordinate, m
    a_roles, b_roles : the roles of the two groups
    paired : compare the first sensor of each group frame by frame (else all of each group)
    evidence : m, the smallest separation that decides

    Returns
    -------
    (sign, separation in m, name of a, name of b), or None without both groups or evidence
    """
    a = [k for k, n in enumerate(names) if roles[n] in a_roles]
    b = [k for k, n in enumerate(names) if roles[n] in b_roles]
    if not a or not b:
        return None
    with warnings.catch_warnings():  # a sensor without data is not an error here
        warnings.simplefilter("ignore", RuntimeWarning)
        if paired:
            d = float(np.nanmedian(coords[:, a[0]] - coords[:, b[0]]))
        else:
            d = float(np.nanmedian(coords[:, a])) - float(np.nanmedian(coords[:, b]))
    if not np.isfinite(d) or abs(d) < evidence:
        return None
    if paired:
        return (1 if d > 0 else -1), abs(d), names[a[0]], names[b[0]]
    return (1 if d > 0 else -1), abs(d), "lips", "+".join(names[k] for k in b)


def _orient(layout: _Layout, fb: np.ndarray, vert: np.ndarray, names: list[str],
            roles: dict) -> tuple[int, int, str, list[str]]:
    """Signs (front, up) of the file's axes and a sentence saying what decided them."""
    notes = []
    front = _sign(fb, names, roles, ("upper_lip", "lower_lip"), ("tongue", "velum", "molar"),
                  False, FRONT_BACK_EVIDENCE)
    if front is None:
        f_sign, f_how = layout.front_sign, f"{layout.name}'s documented convention"
    else:
        f_sign = front[0]
        f_how = (f"the lips lie {front[1] * 1e3:.0f} mm toward "
                 f"{'+' if f_sign > 0 else '-'}{layout.front_back} of {front[3]}")
        if f_sign != layout.front_sign:
            notes.append(f"front-back axis opposite to {layout.name}'s documented convention "
                         f"(decided by the sensors: {f_how})")
    up = _sign(vert, names, roles, ("upper_lip",), ("lower_lip",), True, VERTICAL_EVIDENCE)
    if up is None:
        up = _sign(vert, names, roles, ("upper_lip",), ("lower_incisor",), True,
                   VERTICAL_EVIDENCE)
    if up is None:
        u_sign, u_how = layout.up_sign, f"{layout.name}'s documented convention"
    else:
        u_sign = up[0]
        u_how = (f"{up[2]} lies {up[1] * 1e3:.0f} mm toward "
                 f"{'+' if u_sign > 0 else '-'}{layout.vertical} of {up[3]}")
        if u_sign != layout.up_sign:
            notes.append(f"vertical axis opposite to {layout.name}'s documented convention "
                         f"(decided by the sensors: {u_how})")
    z = f"{'+' if f_sign > 0 else '-'}file {layout.front_back}"
    y = f"{'+' if u_sign > 0 else '-'}file {layout.vertical}"
    if layout.lateral is None:
        x = "0 (midsagittal)"
    else:  # right-handed: x = y cross z
        x = f"{'+' if -f_sign * u_sign > 0 else '-'}file {layout.lateral} (right-handed frame)"
    text = (f"model z (forward) = {z} [{f_how}]; model y (up) = {y} [{u_how}]; "
            f"model x = {x}")
    return f_sign, u_sign, text, notes


def _mapping_notes(roles: dict) -> list[str]:
    """What the lip and incisor sensors stand for on the model (for ``meta['notes']``)."""
    say = {"upper_lip": "the upper lip's vermilion point on the midline",
           "lower_lip": "the lower lip's vermilion point on the midline",
           "lower_incisor": "the lower incisor, a bone point that drives the jaw",
           "molar": "a mandibular molar, a second bone point of the jaw",
           "upper_incisor": "the upper incisor (skull reference)"}
    out = [f"{n} -> {say[r]}" for n, r in roles.items() if r in say]
    kept = [n for n, r in roles.items() if r in ("tongue", "velum", "reference", "other")]
    if kept:
        out.append(f"kept, not on the face model: {', '.join(kept)}")
    return out


def _assemble(src: str, fmt: str, layout: _Layout, time: np.ndarray, coils: dict,
              scale: float, source_units: str, file_units: str, missing: str,
              extra: dict | None = None) -> MarkerSet:
    """A MarkerSet in the model's axes from coils name -> (frames, 2 or 3) file coordinates.

    The columns are (front-back, vertical) for 2-D layouts and (lateral, front-back, vertical)
    for 3-D ones, already NaN where missing.
    """
    names = list(coils)
    if not names:
        raise InputError("no position channels (NAME_x/NAME_y or NAME_px/NAME_py/NAME_pz)",
                         source=src, field="Channel_0")
    time = np.asarray(time, float)
    _check_time(time, src, "time")
    data = np.stack([coils[n] for n in names], axis=1) * scale  # (frames, sensors, 2|3)
    if not np.isfinite(data).any():
        raise InputError(f"only missing values ({missing}): no sample to use", source=src,
                         field="data")
    data[~np.all(np.isfinite(data), axis=2)] = np.nan
    roles = {n: sensor_role(n) for n in names}
    three_d = layout.lateral is not None
    fb, vert = (data[..., 1], data[..., 2]) if three_d else (data[..., 0], data[..., 1])
    f_sign, u_sign, axes, notes = _orient(layout, fb, vert, names, roles)
    pos = np.zeros(data.shape[:2] + (3,))
    pos[..., 1] = u_sign * vert
    pos[..., 2] = f_sign * fb
    if three_d:
        pos[..., 0] = -f_sign * u_sign * data[..., 0]
    pos[~np.all(np.isfinite(pos), axis=2)] = np.nan
    empty = [n for k, n in enumerate(names) if not np.isfinite(pos[:, k, 1]).any()]
    if empty:
        notes.append(f"no data at all for {', '.join(empty)} (kept, all NaN)")
    rate = (len(time) - 1) / float(time[-1] - time[0])  # over the whole span: float32 times
    meta = {"source": src, "format": fmt, "axes": axes, "missing_value": missing,
            "midsagittal": not three_d, "roles": roles, "file_units": file_units,
            "notes": notes + _mapping_notes(roles)}
    meta.update(extra or {})
    ms = MarkerSet(pos, tuple(names), rate, time=time, source_units=source_units, meta=meta)
    ms, _ = drop_empty_ends(ms)
    check_anatomy(ms, source=src)
    return ms


def _check_time(t: np.ndarray, src: str, field: str) -> None:
    """Refuse a time column that is not finite and strictly increasing (a rate of 0 Hz too)."""
    if not np.all(np.isfinite(t)):
        bad = int(np.argmax(~np.isfinite(t)))
        raise InputError(f"frame {bad + 1}: time {t[bad]!r} is not a number", source=src,
                         field=field)
    if len(t) < 2:
        raise InputError("needs at least two frames", source=src, field=field)
    d = np.diff(t)
    if np.all(d == 0):
        raise InputError(f"every frame has the time {t[0]:g} s: a sampling rate of 0 Hz",
                         source=src, field=field)
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0)) + 1
        raise InputError(f"time must be strictly increasing (frame {k + 1}: {t[k]:g} after "
                         f"{t[k - 1]:g})", source=src, field=field)


def _units(units: str | None, default_scale: float, default_units: str, src: str):
    """(metres per file unit, source unit) from the caller's ``units`` or the layout's."""
    if units is None:
        return default_scale, default_units
    return length_scale(units, source=src), units


def _pair_channels(names, src: str) -> tuple[dict, list[str], bool]:
    """Coil -> channel indices ((x, y) or (px, py, pz)), the ignored channels, and 3-D-ness."""
    two: dict[str, dict[str, int]] = {}
    three: dict[str, dict[str, int]] = {}
    ignored = []
    for k, name in enumerate(names):
        m3 = re.fullmatch(r"(.+?)_p([xyz])", name.strip(), flags=re.IGNORECASE)
        m2 = re.fullmatch(r"(.+?)_([xy])", name.strip(), flags=re.IGNORECASE)
        if m3:
            three.setdefault(m3.group(1), {})[m3.group(2).lower()] = k
        elif m2 and set(m2.group(1)) != {"*"}:
            two.setdefault(m2.group(1), {})[m2.group(2).lower()] = k
        else:
            ignored.append(name or f"Channel_{k}")
    if two and three:
        first = min(min(ix.values()) for ix in two.values())
        raise InputError("the channels mix 2-D (NAME_x, NAME_y) and 3-D (NAME_px, NAME_py, "
                         "NAME_pz) coils", source=src, field=f"Channel_{first}")
    coils, axes = (three, "xyz") if three else (two, "xy")
    out = {}
    for coil, idx in coils.items():
        lost = [a for a in axes if a not in idx]
        if lost:
            have = next(iter(idx))
            raise InputError(f"coil {coil} has no {'p' if three else ''}{lost[0]} channel",
                             source=src, field=names[idx[have]])
        out[coil] = tuple(idx[a] for a in axes)
    return out, ignored, bool(three)


def read_est_markers(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Read an EMA EST track file (MOCHA-TIMIT, mngu0 or alike) as a marker set.

    Channels ``NAME_x``/``NAME_y`` are 2-D midsagittal coils (MOCHA-TIMIT's layout: 0.01 mm,
    +x backward, +y up); ``NAME_px``/``NAME_py``/``NAME_pz`` are 3-D coils (mngu0's layout:
    mm, py front-back, pz up, px lateral). Other channels (``****``, angles, RMS) are listed in
    ``meta["ignored_channels"]``. Break frames and NaN values are missing samples.

    Parameters
    ----------
    path : the file
    units : the file's length unit, overriding the layout's (``mm``, ``m``, ``cm``, ``um``)

    Returns
    -------
    MarkerSet
        Positions (frames, sensors, 3) in m, model axes; rate from the time column.
    """
    src = str(path)
    track = read_est_track(path)
    coils, ignored, three_d = _pair_channels(track.names, src)
    values = track.values.copy()
    values[~track.present] = np.nan
    if three_d:
        layout, fmt = MNGU0, "est-mngu0"
        scale, source_units = _units(units, MNGU0_UNIT_M, "mm", src)
        file_units = units or "mm"
    else:
        layout, fmt = MOCHA, "est-mocha"
        scale, source_units = _units(units, MOCHA_UNIT_M, "mm", src)
        file_units = units or "0.01 mm (1e-5 m)"
    return _assemble(src, fmt, layout, track.time,
                     {c: values[:, list(ix)] for c, ix in coils.items()}, scale, source_units,
                     file_units, "NaN, or a break frame (EST break flag 0)",
                     {"ignored_channels": ignored, "data_type":
                      "binary" if track.binary else "ascii",
                      "byte_order": track.header.get("ByteOrder")})


def read_mocha_text(path: str | Path, *, units: str | None = None,
                    rate: float | None = None) -> MarkerSet:
    """Read MOCHA-TIMIT EMA in its plain-text layout (columns of numbers, no header).

    22 columns: time (s), present flag (0: no data), then the 20 channels of
    :data:`MOCHA_CHANNELS`; or 20 columns: the channels alone, at ``rate`` (default MOCHA's
    500 Hz). Units 0.01 mm unless ``units`` says otherwise.

    Returns
    -------
    MarkerSet
        Nine midsagittal sensors (ui, li, ul, ll, tt, tb, td, v, bn) in m, model axes.
    """
    src = str(path)
    try:
        text = Path(path).read_text()
    except UnicodeDecodeError:
        raise InputError("binary data where a text EMA file (EST or MOCHA's plain layout) was "
                         "expected", source=src) from None
    rows = [ln.split() for ln in text.splitlines() if ln.strip() and not ln.lstrip()
            .startswith(("#", ";", "%"))]
    if not rows:
        raise InputError("no data rows", source=src, field="data")
    n = len(MOCHA_CHANNELS)
    width = len(rows[0])
    if width not in (n, n + 2):
        raise InputError(f"{width} columns; MOCHA's plain layout has {n + 2} (time, present "
                         f"flag, {n} channels) or {n}", source=src, field="columns")
    table = np.empty((len(rows), width))
    for k, cells in enumerate(rows):
        if len(cells) != width:
            raise InputError(f"row {k + 1} has {len(cells)} columns, the first has {width}",
                             source=src, field="columns")
        try:
            table[k] = [float(c) for c in cells]
        except ValueError:
            raise InputError(f"row {k + 1}: a value that is not a number", source=src,
                             field="data") from None
    if width == n + 2:
        time, values = table[:, 0], table[:, 2:].copy()
        values[table[:, 1] == 0] = np.nan
        if rate is not None:
            raise InputError("the file has a time column; a rate is not needed", source=src,
                             field="rate")
    else:
        rate = MOCHA_RATE_HZ if rate is None else float(rate)
        if not (np.isfinite(rate) and rate > 0):
            raise InputError(f"sampling rate {rate:g} Hz is not a positive rate", source=src,
                             field="rate")
        time, values = np.arange(len(table)) / rate, table
    idx = {name: k for k, name in enumerate(MOCHA_CHANNELS) if name != "****"}
    coils = {c: values[:, [idx[f"{c}_x"], idx[f"{c}_y"]]]
             for c in dict.fromkeys(nm[:-2] for nm in idx)}
    scale, source_units = _units(units, MOCHA_UNIT_M, "mm", src)
    return _assemble(src, "mocha-text", MOCHA, time, coils, scale, source_units,
                     units or "0.01 mm (1e-5 m)", "NaN, or present flag 0",
                     {"ignored_channels": ["****", "****"]})


def read_ema(path: str | Path, *, units: str | None = None,
             rate: float | None = None) -> MarkerSet:
    """Read a ``.ema``/``.est`` file: an EST track (by its magic) or MOCHA's plain layout."""
    if is_est(path):
        if rate is not None:
            raise InputError("an EST file has its own times; a rate is not needed",
                             source=str(path), field="rate")
        return read_est_markers(path, units=units)
    return read_mocha_text(path, units=units, rate=rate)


# ---- X-ray microbeam --------------------------------------------------------------------------
def _time_unit(step: float, src: str) -> tuple[str, float]:
    """The unit of a .txy time column (s, ms or us) that makes its step a 20-2000 Hz rate."""
    low, high = XRMB_RATES_HZ
    for unit, factor in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if low <= 1.0 / (step * factor) <= high:
            return unit, factor
    raise InputError(f"a time step of {step:g} gives no rate between {low:g} and {high:g} Hz "
                     "in s, ms or us", source=src, field="time")


def read_xrmb_txy(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Read a Wisconsin X-ray microbeam ``.txy`` pellet file.

    Columns: time, then x y for UL LL T1 T2 T3 T4 MNI MNM (:data:`XRMB_PELLETS`); an optional
    first line of names (``time UL_x UL_y ...`` or ``time ULx ULy ...``) renames the pellets.
    A coordinate equal to 1000000 marks a lost pellet: that sample is NaN. Micrometres unless
    ``units`` says otherwise; the time unit is read from the step (``meta["time_units"]``).

    Returns
    -------
    MarkerSet
        Eight midsagittal sensors in m, model axes (+z forward = +x of the file, +y up).
    """
    src = str(path)
    try:
        text = Path(path).read_text()
    except UnicodeDecodeError:
        raise InputError("binary data where a text .txy file was expected", source=src) from None
    lines = [(k + 1, ln.replace(",", " ").split()) for k, ln in enumerate(text.splitlines())
             if ln.strip() and not ln.lstrip().startswith(("#", "%", ";"))]
    if not lines:
        raise InputError("no data rows", source=src, field="data")
    pellets = list(XRMB_PELLETS)
    if not _numeric(lines[0][1][0]):
        pellets = _txy_names(lines[0][1], src)
        lines = lines[1:]
    width = 1 + 2 * len(pellets)
    table = np.empty((len(lines), width))
    for r, (ln, cells) in enumerate(lines):
        if len(cells) != width:
            raise InputError(f"line {ln} has {len(cells)} columns, expected {width} (time, "
                             f"then x y of {' '.join(pellets)})", source=src, field="columns")
        try:
            table[r] = [float(c) for c in cells]
        except ValueError:
            raise InputError(f"line {ln}: a value that is not a number", source=src,
                             field="data") from None
    if len(table) < 2:
        raise InputError("needs at least two frames", source=src, field="time")
    t = table[:, 0]
    _check_time(t, src, "time")
    unit, factor = _time_unit(float(np.median(np.diff(t))), src)
    xy = table[:, 1:].reshape(len(table), len(pellets), 2)
    lost = np.any(np.abs(xy) == XRMB_MISSING, axis=2)
    xy[lost] = np.nan
    if lost.all():
        raise InputError(f"only missing-value codes ({XRMB_MISSING:.0f}): no pellet was "
                         "tracked", source=src, field="data")
    scale, source_units = _units(units, length_scale(XRMB_UNIT), XRMB_UNIT, src)
    return _assemble(src, "xrmb-txy", XRMB, t * factor,
                     {p: xy[:, k] for k, p in enumerate(pellets)}, scale, source_units,
                     units or "um", f"{XRMB_MISSING:.0f}", {"time_units": unit})


def _numeric(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _txy_names(cells: list[str], src: str) -> list[str]:
    """Pellet names from a .txy header line ``time A_x A_y B_x B_y ...`` (or ``Ax Ay``)."""
    cols = cells[1:]
    if len(cols) % 2:
        raise InputError(f"the header names {len(cols)} coordinate columns, not x y pairs",
                         source=src, field="columns")
    names = []
    for cx, cy in zip(cols[::2], cols[1::2], strict=True):
        bx, by = re.sub(r"_?[xX]$", "", cx), re.sub(r"_?[yY]$", "", cy)
        if bx == cx or by == cy or bx != by:
            raise InputError(f"header columns {cx} {cy} are not an x y pair of one pellet",
                             source=src, field=cx)
        names.append(bx)
    return names
