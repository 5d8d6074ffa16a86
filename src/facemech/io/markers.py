"""Marker files: wide CSV (read/write), Qualisys TSV (read), and dispatch over all formats.

A facemech results file (``.nc``) also reads as a marker file: its model markers (read only).
Articulography reads too (:mod:`facemech.io.articulography`, :mod:`facemech.io.ema_formats`):
EMA as EST track files (``.ema``, ``.est``, or any file starting with ``EST_File``) or
MOCHA-TIMIT's plain layout (``.ema``), X-ray microbeam pellets (``.txy``), Carstens AG500/AG501
(``.pos``) and NDI Wave exports (``.tsv`` with ``Tx Ty Tz`` columns).

Wide CSV: a comment line ``# units: mm`` (or m, cm), a header ``time, NAME_x, NAME_y, NAME_z,
...`` and one row per frame; empty cells are missing samples; an optional ``# filled:`` comment
lists the samples a gap filler made up; ``# roles:`` (``NAME=role; ...``) and ``# midsagittal:``
keep articulography's sensor roles. The unit is never guessed: a file without one needs the
caller's ``units``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError, missing_input
from ..markerset import MarkerSet
from ..units import length_scale
from .tables import read_table, uniform_rate

FORMATS = {".csv": "csv", ".trc": "trc", ".c3d": "c3d", ".tsv": "tsv", ".nc": "results",
           ".ema": "ema", ".est": "ema", ".txy": "txy", ".pos": "pos"}


def read_marker_csv(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Read a wide marker CSV; positions are returned in metres."""
    path = Path(path)
    t, cols = read_table(path)
    meta = cols.pop("__meta__")
    unit = units or meta.get("units")
    if unit is None:
        raise InputError("no length unit: add a '# units: mm' line or pass units (--units)",
                         source=str(path), field="units")
    scale = length_scale(unit, source=str(path))
    names: list[str] = []
    for col in cols:
        base, _, axis = col.rpartition("_")
        if axis.lower() not in ("x", "y", "z") or not base:
            raise InputError("marker columns must be named NAME_x, NAME_y, NAME_z",
                             source=str(path), field=col)
        if base not in names:
            names.append(base)
    lookup = {c.lower(): c for c in cols}
    pos = np.empty((len(t), len(names), 3))
    for m, name in enumerate(names):
        for a, axis in enumerate("xyz"):
            key = lookup.get(f"{name}_{axis}".lower())
            if key is None:
                raise InputError("missing coordinate column", source=str(path),
                                 field=f"{name}_{axis}")
            pos[:, m, a] = cols[key] * scale
    filled = None
    if "filled" in meta:
        filled = np.zeros(pos.shape[:2], bool)
        for part in meta["filled"].split(";"):
            name, _, frames = part.strip().partition("=")
            if name not in names:
                raise InputError("filled samples of an unknown marker", source=str(path),
                                 field=name)
            filled[np.asarray(frames.split(), int), names.index(name)] = True
    extra = _roles_from(meta, names, str(path))
    return MarkerSet(pos, tuple(names), uniform_rate(t, source=str(path)), time=t,
                     source_units=unit, filled=filled,
                     meta={"source": str(path), "format": "csv", **extra})


def _roles_from(meta: dict, names: list[str], src: str) -> dict:
    """``roles`` and ``midsagittal`` of a CSV's ``# roles:`` and ``# midsagittal:`` comments."""
    from ..markerset import SENSOR_ROLES

    out: dict = {}
    if "roles" in meta:
        roles = {}
        for part in meta["roles"].split(";"):
            name, _, role = (x.strip() for x in part.partition("="))
            if not name:
                continue
            if name not in names:
                raise InputError("a role for an unknown marker", source=src, field=name)
            if role not in SENSOR_ROLES:
                raise InputError(f"unknown role {role!r} (expected one of "
                                 f"{', '.join(SENSOR_ROLES)})", source=src, field="roles")
            roles[name] = role
        out["roles"] = roles
    if "midsagittal" in meta:
        out["midsagittal"] = meta["midsagittal"].strip().lower() in ("yes", "true", "1")
    return out


def write_marker_csv(path: str | Path, ms: MarkerSet, *, units: str | None = None) -> None:
    """Write a marker set as wide CSV in ``units`` (default: its source unit), atomically."""
    units = units or ms.source_units
    scale = length_scale(units)
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write(f"# units: {units}\n")
        if ms.filled.any():
            parts = [f"{n}=" + " ".join(map(str, np.nonzero(ms.filled[:, k])[0]))
                     for k, n in enumerate(ms.names) if ms.filled[:, k].any()]
            fh.write(f"# filled: {'; '.join(parts)}\n")
        roles = {n: r for n, r in (ms.meta.get("roles") or {}).items() if n in ms.names}
        if roles:  # articulography keeps its roles, and planar data says so
            fh.write(f"# roles: {'; '.join(f'{n}={r}' for n, r in roles.items())}\n")
            fh.write(f"# midsagittal: {'yes' if ms.meta.get('midsagittal') else 'no'}\n")
        fh.write("time," + ",".join(f"{n}_{a}" for n in ms.names for a in "xyz") + "\n")
        for k, t in enumerate(ms.time):
            vals = ms.positions[k].reshape(-1) / scale
            fh.write(f"{t:.6f}," + ",".join("" if not np.isfinite(v) else repr(float(v))
                                             for v in vals) + "\n")


def read_qualisys_tsv(path: str | Path, *, units: str | None = None) -> MarkerSet:
    """Read a Qualisys Track Manager 3-D TSV export.

    The header lines (``NO_OF_FRAMES``, ``FREQUENCY``, ``MARKER_NAMES``, ...) give the rate and
    labels; QTM's 3-D export is in millimetres by definition of the format (``units`` overrides).
    Samples with all three coordinates exactly 0 are QTM's missing samples.
    """
    path = Path(path)
    if not path.is_file():
        raise missing_input(path)
    header: dict[str, list[str]] = {}
    rows: list[list[str]] = []
    with path.open(encoding="utf-8-sig") as fh:  # a byte-order mark is read
        for line in fh:
            cells = line.rstrip("\r\n").split("\t")
            if not cells or not cells[0].strip():
                continue
            key = cells[0].strip()
            if key.replace("_", "").isalpha() and key.isupper():
                header[key] = cells[1:]
            elif key.lower() == "frame":
                continue  # column titles of newer exports
            else:
                rows.append(cells)
    for need in ("FREQUENCY", "MARKER_NAMES"):
        if need not in header:
            raise InputError("missing header line", source=str(path), field=need)
    names = tuple(n.strip() for n in header["MARKER_NAMES"] if n.strip())
    try:
        rate = float(header["FREQUENCY"][0])
        data = np.array([[float(c) if c.strip() else np.nan for c in r] for r in rows])
    except (ValueError, IndexError):
        raise InputError("non-numeric data", source=str(path), field="data") from None
    n3 = 3 * len(names)
    if data.ndim != 2 or data.shape[1] < n3:
        raise InputError(f"expected {n3} coordinate columns", source=str(path), field="data")
    coords = data[:, -n3:].reshape(len(data), len(names), 3)
    coords[np.all(coords == 0.0, axis=2)] = np.nan
    unit = units or "mm"
    return MarkerSet(coords * length_scale(unit, source=str(path)), names, rate,
                     source_units=unit, meta={"source": str(path), "format": "tsv"})


def read_markers(path: str | Path, *, units: str | None = None, rate: float | None = None,
                 sensors=None) -> MarkerSet:
    """Read any supported marker file (CSV, TRC, C3D, Qualisys TSV, EMA, XRMB, Carstens .pos,
    NDI Wave), in metres.

    A results file (``.nc``) gives the model's markers at the results' frame rate (``units`` is
    not needed: results are in metres). Articulography (EMA, X-ray microbeam, Carstens, NDI
    Wave) comes in the model's axes with its sensors' roles in ``meta["roles"]``
    (:mod:`facemech.io.articulography`, :mod:`facemech.io.ema_formats`); a file of any other
    suffix that starts with ``EST_File`` reads as EMA; a ``.tsv`` whose header has ``Tx Ty Tz``
    columns as NDI Wave, else as Qualisys.

    Parameters
    ----------
    path : the file
    units : the length unit of a file that has none (or to override a layout's)
    rate : Hz, for a format without times (MOCHA's 20-column text, a header-less AG500 .pos)
    sensors : sensor names in channel order, for formats without names (.pos, NDI Wave)
    """
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        from .articulography import is_est

        fmt = "ema" if is_est(path) else None
    if fmt is None:
        raise InputError(f"unknown marker format {path.suffix!r} (expected "
                         f"{', '.join(FORMATS)})", source=str(path))
    if not path.is_file():
        raise missing_input(path)
    try:
        return check_span(check_frames(_read(path, fmt, units, rate, sensors)), source=path)
    except UnicodeDecodeError:
        raise InputError(f"binary data where a text {fmt.upper()} file was expected",
                         source=str(path)) from None
    except InputError as exc:
        if exc.source is None:  # raised by the marker-set type: name the file it came from
            raise InputError(exc.message, source=str(path), field=exc.field) from None
        raise


def check_frames(ms: MarkerSet, *, source: str | Path | None = None) -> MarkerSet:
    """Refuse a recording of fewer than two frames (it has no rate, no motion, and a CSV of
    it cannot be read back); returns ``ms``."""
    if ms.n_frames < 2:
        raise InputError(f"{ms.n_frames} frame: a recording needs at least two",
                         source=None if source is None else str(source), field="frames")
    return ms


#: m, the extent of a marker recording of two or more markers that is plausible for a face (or
#: a face and a body): between 1 mm (two lip markers at closure) and 5 m (a capture volume)
SPAN_LIMITS = (0.001, 5.0)
FACE_SPAN = 0.15  #: m, the extent of a face's marker set (ear to ear, brow to chin)


def check_span(ms: MarkerSet, *, source: str | Path | None = None) -> MarkerSet:
    """Refuse a recording whose size is implausible for its declared length unit.

    The span is the largest extent, over the three axes, of every measured sample. Metres
    declared as millimetres make a face 0.2 mm wide, micrometres as millimetres one 200 m wide;
    both are errors naming the unit the values look like.

    Parameters
    ----------
    ms : the marker set, positions in metres as converted with its ``source_units``
    source : the file, for the message

    Returns
    -------
    MarkerSet
        ``ms`` unchanged.
    """
    pts = ms.positions[ms.valid]
    if len(pts) < 2 or ms.n_markers < 2:
        return ms
    span = float(np.max(np.ptp(pts, axis=0)))
    low, high = SPAN_LIMITS
    if span == 0.0 or low <= span <= high:
        return ms
    unit = ms.source_units
    values = span / length_scale(unit)
    guess = min(("m", "cm", "mm", "um"),  # the unit that makes the span closest to a face's
                key=lambda u: abs(np.log(values * length_scale(u) / FACE_SPAN)))
    hint = f"; the values look like {guess}" if guess != unit else ""
    raise InputError(f"the markers span {span * 1e3:.3g} mm, not a face or a capture volume "
                     f"({low * 1e3:g} mm to {high:g} m) in the declared unit {unit!r}{hint}",
                     source=None if source is None else str(source), field="units")


def _read(path: Path, fmt: str, units: str | None, rate=None, sensors=None) -> MarkerSet:
    if fmt == "tsv":
        from .ema_formats import is_ndi_wave

        fmt = "ndi" if is_ndi_wave(path) else fmt
    takes = {"ema": ("rate",), "pos": ("rate", "sensors"), "ndi": ("sensors",)}.get(fmt, ())
    for name, value in (("rate", rate), ("sensors", sensors)):
        if value is not None and name not in takes:
            what = "times" if name == "rate" else "names"
            raise InputError(f"a {fmt.upper()} file has its own {what}: --{name} is not needed",
                             source=str(path), field=name)
    if fmt in ("pos", "ndi"):
        from .ema_formats import read_carstens_pos, read_ndi_wave

        if fmt == "pos":
            return read_carstens_pos(path, units=units, rate=rate, sensors=sensors)
        return read_ndi_wave(path, units=units, sensors=sensors)
    if fmt in ("ema", "txy"):
        from .articulography import read_ema, read_xrmb_txy

        if fmt == "ema":
            return read_ema(path, units=units, rate=rate)
        return read_xrmb_txy(path, units=units)
    if fmt == "csv":
        return read_marker_csv(path, units=units)
    if fmt == "tsv":
        return read_qualisys_tsv(path, units=units)
    if fmt == "results":
        from .results import read_results, results_markers

        return results_markers(read_results(path), source=path)
    if fmt == "trc":
        from .trc import read_trc

        return read_trc(path, units=units)
    from .c3d import read_c3d_points

    return read_c3d_points(path, units=units)


def write_markers(path: str | Path, ms: MarkerSet, *, units: str | None = None) -> Path:
    """Write a marker set as CSV, TRC or C3D (by extension), atomically, in ``units``."""
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt not in ("csv", "trc", "c3d"):
        raise InputError("can write .csv, .trc or .c3d", source=str(path))
    check_frames(ms, source=path)  # never a file that no reader takes back
    if fmt == "csv":
        write_marker_csv(path, ms, units=units)
    elif fmt == "trc":
        from .trc import write_trc

        write_trc(path, ms, units=units)
    else:
        from .c3d import write_c3d_points

        write_c3d_points(path, ms, units=units)
    return path
