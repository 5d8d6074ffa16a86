"""What a batch leaves in its output folder: one folder per finished item, holding a
done-record, and the summary table.

An item is made in a hidden temporary folder ``OUT/.partial-<id>-<random>/``; its done-record
``done.json`` is written there last, and the folder is then renamed to ``OUT/<id>/`` (an older
``OUT/<id>/`` is moved aside first and removed after). So ``OUT/<id>/done.json`` exists only
for an item made completely, and a killed run leaves at most hidden temporary folders, which
the next run removes (:func:`remove_partial`).
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["DONE", "SUMMARY_COLUMNS", "commit_folder", "new_partial", "read_done",
           "remove_partial", "up_to_date", "write_done", "write_summary"]

#: the done-record's file name inside an item's folder
DONE = "done.json"
_PARTIAL, _REPLACED = ".partial-", ".replaced-"

#: the summary's first columns; the items' other key numbers follow, in the order first seen
SUMMARY_COLUMNS = ("id", "job", "status", "wall_s", "cpu_s", "frames", "median_error_mm",
                   "max_error_mm")


def read_done(folder: str | Path) -> dict | None:
    """The done-record of an item's folder, or None when there is none (or it is unreadable)."""
    try:
        rec = json.loads((Path(folder) / DONE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def up_to_date(folder: str | Path, key: str) -> dict | None:
    """The done-record of ``folder`` when it was made with ``key`` (the item's inputs and
    settings unchanged), else None."""
    rec = read_done(folder)
    return rec if rec is not None and rec.get("key") == key else None


def write_done(folder: str | Path, record: dict) -> Path:
    """Write ``record`` as the done-record of ``folder`` (atomically). Returns its path."""
    from ..atomic import atomic_path

    path = Path(folder) / DONE
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(record, indent=2, sort_keys=True, default=str) + "\n",
                       encoding="utf-8")
    return path


def new_partial(out_dir: str | Path, item_id: str) -> Path:
    """A new, empty hidden folder in ``out_dir`` to make item ``item_id`` in."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = Path(tempfile.mkdtemp(prefix=f"{_PARTIAL}{item_id}-", dir=out_dir))
    umask = os.umask(0)
    os.umask(umask)
    path.chmod(0o777 & ~umask)  # mkdtemp makes 0700; give the usual permissions
    return path


def commit_folder(partial: str | Path, final: str | Path) -> Path:
    """Rename the finished folder ``partial`` to ``final``, replacing an older ``final``."""
    partial, final = Path(partial), Path(final)
    old = None
    if final.exists():
        old = Path(tempfile.mkdtemp(prefix=f"{_REPLACED}{final.name}-", dir=final.parent))
        os.replace(final, old / final.name)
    os.replace(partial, final)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return final


def remove_partial(out_dir: str | Path) -> int:
    """Remove the temporary folders of items that were never finished (a killed run) and of
    replaced ones. Returns how many were removed."""
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        return 0
    n = 0
    for p in out_dir.iterdir():
        if p.is_dir() and p.name.startswith((_PARTIAL, _REPLACED)):
            shutil.rmtree(p, ignore_errors=True)
            n += 1
    return n


def write_summary(path: str | Path, rows: list[dict]) -> Path:
    """Write the batch's summary table (CSV, atomically): one row per item, the columns
    :data:`SUMMARY_COLUMNS`, the items' other key numbers, then ``error``."""
    from ..atomic import atomic_path

    cols = list(SUMMARY_COLUMNS)
    for row in rows:
        cols.extend(c for c in row if c not in cols and c != "error")
    cols.append("error")
    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, restval="", extrasaction="ignore")
        w.writeheader()
        for row in rows:
            w.writerow(row)
    return Path(path)


def folder_files(folder: str | Path) -> list[str]:
    """The files under ``folder`` (relative paths, sorted), the done-record excepted."""
    folder = Path(folder)
    with contextlib.suppress(OSError):
        return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                      if p.is_file() and p.name != DONE)
    return []
