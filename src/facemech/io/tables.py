"""Reading numeric CSV tables with a time column: one-line errors that name file and column."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..errors import InputError, missing_input


def read_table(path: str | Path, *, time_column: str = "time") -> tuple[np.ndarray, dict]:
    """Read a CSV with a header row, a time column (s) and numeric columns.

    Lines starting with ``#`` are comments; a comment ``# units: mm`` is returned as metadata.

    Returns
    -------
    time : (n,) array, seconds
    columns : dict name -> (n,) array (NaN where a cell is empty)
    """
    path = Path(path)
    if not path.is_file():
        raise missing_input(path)
    meta: dict[str, str] = {}
    rows: list[list[str]] = []
    header: list[str] | None = None
    try:  # utf-8-sig: a byte-order mark (Excel's "CSV UTF-8") is read, not part of a name
        with path.open(newline="", encoding="utf-8-sig") as fh:
            for lineno, row in enumerate(csv.reader(fh), start=1):
                if not row or not "".join(row).strip():
                    continue
                if row[0].lstrip().startswith("#"):
                    text = ",".join(row).lstrip("# ").strip()
                    if ":" in text:
                        k, v = text.split(":", 1)
                        meta[k.strip().lower()] = v.strip()
                    continue
                if header is None:
                    header = [c.strip() for c in row]
                    continue
                if len(row) != len(header):
                    raise InputError(f"line {lineno} has {len(row)} cells, the header has "
                                     f"{len(header)}", source=str(path), field="row")
                rows.append(row)
    except UnicodeDecodeError:
        raise InputError("not a text CSV file", source=str(path)) from None
    except csv.Error as exc:  # a NUL byte, a cell beyond the csv module's size limit
        raise InputError(f"not a readable CSV file ({exc})", source=str(path)) from None
    if header is None:
        raise InputError("empty file (no header row)", source=str(path))
    lower = [h.lower() for h in header]
    if time_column not in lower:
        raise InputError("missing time column", source=str(path), field=time_column)
    if len(set(lower)) != len(lower):
        raise InputError("duplicate column names", source=str(path), field="header")
    data = np.full((len(rows), len(header)), np.nan)
    for r, row in enumerate(rows):
        for c, cell in enumerate(row):
            cell = cell.strip()
            if cell == "" or cell.lower() == "nan":
                continue
            try:
                data[r, c] = float(cell)
            except ValueError:
                raise InputError(f"row {r + 1}: {cell!r} is not a number", source=str(path),
                                 field=header[c]) from None
            if np.isinf(data[r, c]):  # not a missing sample (empty or NaN): a broken one
                raise InputError(f"row {r + 1}: {cell!r} is not a finite number (leave the "
                                 "cell empty for a missing sample)", source=str(path),
                                 field=header[c])
    t = data[:, lower.index(time_column)]
    if len(t) < 2:
        raise InputError("needs at least two rows", source=str(path), field=time_column)
    if np.any(~np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError("time must be finite and strictly increasing", source=str(path),
                         field=time_column)
    cols = {h: data[:, i] for i, h in enumerate(header) if h.lower() != time_column}
    return t, {"__meta__": meta, **cols}


def uniform_rate(t: np.ndarray, *, source: str | None = None, field: str = "time") -> float:
    """Sampling rate (Hz) of a uniformly sampled time column; raise if it is not uniform."""
    d = np.diff(t)
    step = float(np.median(d))
    if np.max(np.abs(d - step)) > 0.01 * step:
        raise InputError("samples are not evenly spaced", source=source, field=field)
    return 1.0 / step


def toml_tables(text: str, path: str | Path, table: str) -> tuple[list[dict], dict]:
    """The ``[[table]]`` entries and the ``[defaults]`` table of a TOML document.

    Raises :class:`InputError` naming ``path`` for unreadable TOML (field none), a missing or
    malformed ``[[table]]`` list (field ``table``) and ``defaults`` that is not a table.
    """
    import tomllib

    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not a readable TOML file ({exc})", source=str(path)) from None
    items = doc.get(table)
    if not isinstance(items, list) or not all(isinstance(i, dict) for i in items):
        raise InputError(f"expected [[{table}]] tables", source=str(path), field=table)
    defaults = doc.get("defaults", {})
    if not isinstance(defaults, dict):
        raise InputError("[defaults] must be a table", source=str(path), field="defaults")
    return items, defaults
