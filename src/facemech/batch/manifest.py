"""Batch manifests: one row per item (its id, its job kind, its inputs and options), read and
checked completely before anything runs.

A manifest is CSV (a header row with ``id`` and ``job``, then one row per item; the other
columns are options, a blank cell an option not given) or TOML (``[[item]]`` tables with ``id``,
``job`` and options; an optional ``[defaults]`` table gives options to every item whose job has
them). Option names are the command's (``jaw-chin`` or ``jaw_chin``); relative paths are taken
from the manifest's folder; ``files`` (regions) lists paths separated by ``;`` in CSV (or a
TOML array), each of which may be a glob pattern. Rows are numbered from 1, the first item.

Each :class:`Item` carries the content hashes of its input files and a ``key``: a hash of the
job kind, its settings and those content hashes, which decides whether a finished item is up
to date (:mod:`.records`).
"""

from __future__ import annotations

import csv
import glob
import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, missing_input
from .job import Job, check_kind

__all__ = ["Item", "item_key", "parse_item", "read_manifest", "read_rows"]

_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")
_RESERVED = {"summary.csv"}
_TRUE, _FALSE = {"true", "yes", "1", "on"}, {"false", "no", "0", "off"}


@dataclass(frozen=True)
class Item:
    """One checked manifest row.

    Attributes
    ----------
    id : the item's id, the name of its output folder
    job : its job kind (a key of :data:`facemech.workflows.batch_jobs.JOBS`)
    row : its row in the manifest (1 = the first item)
    options : option name -> value (typed; files as absolute paths, ``files`` a list)
    settings : the options that are not files, as given (typed)
    inputs : input name -> content hash of the file (a list of hashes for ``files``)
    key : hash of ``job``, ``settings`` and ``inputs``: the item is up to date when its
        done-record has this key
    """

    id: str
    job: str
    row: int
    options: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    key: str = ""


def read_rows(path: str | Path, jobs: dict[str, Job]) -> list[dict]:
    """The rows of a CSV or TOML manifest as dicts of the given cells (values as read), each
    with its row number under ``"_row"``. A manifest that cannot be read raises InputError."""
    path = Path(path)
    if not path.is_file():
        raise InputError("manifest not found", source=str(path))
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".toml"):
        raise InputError("a manifest is .csv or .toml", source=str(path))
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise InputError("not a UTF-8 text file", source=str(path)) from None
    rows = _csv_rows(text, path) if suffix == ".csv" else _toml_rows(text, path, jobs)
    if not rows:
        raise InputError("the manifest lists no items", source=str(path))
    return rows


def _csv_rows(text: str, path: Path) -> list[dict]:
    try:
        reader = csv.DictReader(text.splitlines())
        header = [(h or "").strip() for h in (reader.fieldnames or [])]
        for col in ("id", "job"):
            if col not in header:
                raise InputError(f"the header has no '{col}' column", source=str(path),
                                 field=col)
        rows = []
        for k, rec in enumerate(reader, start=1):
            if None in rec:
                raise InputError(f"row {k} has more cells than the header", source=str(path))
            cells = {h.strip(): (v or "").strip() for h, v in rec.items()}
            if any(cells.values()):
                rows.append({**{h: v for h, v in cells.items() if v != ""}, "_row": k})
    except csv.Error as exc:
        raise InputError(f"not a readable CSV file ({exc})", source=str(path)) from None
    return rows


def _toml_rows(text: str, path: Path, jobs: dict[str, Job]) -> list[dict]:
    from ..io.tables import toml_tables

    items, defaults = toml_tables(text, path, "item")
    known = {_name(o) for job in jobs.values() for o in job.options}
    for name in defaults:
        if _name(name) not in known:
            raise InputError("no job kind has this option", source=str(path),
                             field=f"defaults.{name}")
    rows = []
    for k, item in enumerate(items, start=1):
        job = jobs.get(str(item.get("job", "")))
        given = {} if job is None else {n: v for n, v in defaults.items()
                                        if _name(n) in job.options}
        rows.append({**given, **item, "_row": k})
    return rows


def _name(column: str) -> str:
    return column.strip().replace("-", "_")


def _convert(kind: str, value, *, base: Path, where: dict):
    """A cell as the option's kind; files resolved from ``base`` and checked to exist."""
    if kind in ("str", "int", "float", "bool") and isinstance(value, (list, dict)):
        raise InputError(f"row {where['row']}: expected a single value", **where["err"])
    text = str(value).strip()
    try:
        if kind == "int":
            if isinstance(value, float) or (isinstance(value, str) and not re.fullmatch(
                    r"[+-]?\d+", text)):
                raise ValueError
            return int(text)
        if kind == "float":
            return float(text)
    except ValueError:
        want = "an integer" if kind == "int" else "a number"
        raise InputError(f"row {where['row']}: expected {want}, got {text!r}",
                         **where["err"]) from None
    if kind == "bool":
        if isinstance(value, bool):
            return value
        if text.lower() not in _TRUE | _FALSE:
            raise InputError(f"row {where['row']}: expected true or false, got {text!r}",
                             **where["err"])
        return text.lower() in _TRUE
    if kind == "str":
        return text
    if kind == "paths":
        parts = value if isinstance(value, list) else text.split(";")
        files: list[str] = []
        for part in (str(p).strip() for p in parts):
            if not part:
                continue
            if glob.has_magic(part):
                hits = sorted(glob.glob(str(base / part)))
                if not hits:
                    raise InputError(f"row {where['row']}: no file matches {part!r}",
                                     **where["err"])
                files.extend(_file(h, base, where) for h in hits)
            else:
                files.append(_file(part, base, where))
        if not files:
            raise InputError(f"row {where['row']}: no files given", **where["err"])
        return files
    if kind == "file_or_name" and not Path(text).suffix:
        return text  # a built-in face or preset
    if kind == "path_or_first" and text == "first":
        return text
    return _file(text, base, where)


def _file(text: str, base: Path, where: dict) -> str:
    path = Path(text).expanduser()
    path = path if path.is_absolute() else base / path
    if not path.is_file():
        if not path.exists():
            raise InputError(f"row {where['row']}: input file not found: {path}",
                             **where["err"])
        raise InputError(f"row {where['row']}: input {path}: {missing_input(path).message}",
                         **where["err"])
    return str(path.resolve())


def _content_hash(path: str) -> str:
    from ..io.results import file_hash

    return file_hash(path)


def item_key(job: str, settings: dict, inputs: dict) -> str:
    """The hash (hex, 16 characters) that names an item's work: job kind, settings and the
    content hashes of its inputs."""
    blob = json.dumps({"job": job, "settings": settings, "inputs": inputs}, sort_keys=True,
                      default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def parse_item(row: dict, jobs: dict[str, Job], *, source: str, base: Path) -> Item:
    """One raw manifest row checked and typed as an :class:`Item` (see :func:`read_rows`) of a
    job kind of ``jobs`` (kind -> :class:`~.job.Job`)."""
    k = row["_row"]
    ident = str(row.get("id", "")).strip()
    if not ident:
        raise InputError(f"row {k}: no id", source=source, field="id")
    if not _ID.match(ident) or ident in _RESERVED:
        raise InputError(f"row {k}: id {ident!r} must be letters, digits, '-', '_', '.' "
                         "(not first) and not summary.csv", source=source, field="id")
    if not str(row.get("job", "")).strip():
        raise InputError(f"row {k}: no job kind", source=source, field="job")
    kind = str(row["job"]).strip()
    job = check_kind(kind, jobs, source=source, row=k)
    options, settings, inputs = {}, {}, {}
    for column, value in row.items():
        if column in ("id", "job", "_row"):
            continue
        name = _name(column)
        where = {"row": k, "err": {"source": source, "field": column}}
        if name not in job.options:
            raise InputError(f"row {k}: not an option of a {kind} job (its options: "
                             f"{', '.join(job.options)})", source=source, field=column)
        value = _convert(job.options[name], value, base=base, where=where)
        options[name] = value
        is_file = (job.options[name] in ("path", "paths")
                   or (job.options[name] in ("file_or_name", "path_or_first")
                       and Path(value).is_absolute()))
        if not is_file:
            settings[name] = value
        elif isinstance(value, list):
            inputs[name] = [_content_hash(v) for v in value]
        else:
            inputs[name] = _content_hash(value)
    for group in job.required:
        if not any(g in options for g in group):
            raise InputError(f"row {k}: a {kind} job needs {' or '.join(group)}",
                             source=source, field=group[0])
    _check_groups(job, options, source=source, row=k)
    if job.more_inputs is not None:
        try:
            more = job.more_inputs(options)
        except InputError as exc:
            raise InputError(f"row {k}: {exc.one_line()}", source=source,
                             field=job.required[0][0]) from None
        inputs.update({n: _content_hash(str(p)) for n, p in more.items()})
    return Item(ident, kind, k, options, settings, inputs, item_key(kind, settings, inputs))


def _check_groups(job: Job, options: dict, *, source: str, row: int) -> None:
    """Make each of the job's input groups from the row, which checks it (a conflict of
    options, a value out of its interval); an error names the row."""
    from ..inputs import from_manifest

    for group in job.groups:
        try:
            from_manifest(group, options)
        except InputError as exc:
            raise InputError(f"row {row}: {exc.message}", source=source,
                             field=exc.field) from None


def read_manifest(path: str | Path, jobs: dict[str, Job]) -> list[Item]:
    """Read and check a whole manifest: every row's id (unique), job kind, options and input
    files, before anything runs.

    Parameters
    ----------
    path : the manifest (``.csv`` or ``.toml``)
    jobs : its job kinds, kind -> :class:`~.job.Job`
    (:data:`facemech.workflows.batch_jobs.JOBS`)

    Returns
    -------
    list of Item, in the manifest's order

    Raises
    ------
    InputError
        Naming the manifest, the row and the field: a missing column or id, an unknown job
        kind or option, a value of the wrong type, a missing input file, a duplicate id.
    """
    path = Path(path)
    base = path.resolve().parent
    items: list[Item] = []
    seen: dict[str, int] = {}
    for row in read_rows(path, jobs):
        item = parse_item(row, jobs, source=str(path), base=base)
        if item.id in seen:
            raise InputError(f"row {item.row}: id {item.id!r} is also row {seen[item.id]}'s",
                             source=str(path), field="id")
        seen[item.id] = item.row
        items.append(item)
    return items
