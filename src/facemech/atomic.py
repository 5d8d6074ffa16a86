"""Safe writing: temporary file then rename, outputs checked before any long work.

:func:`atomic_path` writes beside the target and renames on success, so a reader never sees a
half-written file; the temporary files alive at any moment are kept in a registry, so that an
interrupted command (:mod:`facemech.interrupts`) removes them. :func:`check_output` refuses an
output that would destroy an input or cannot be written, before the work starts.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "check_output", "pending_folder", "remove_pending"]

#: temporary files being written right now (removed on success, failure or interruption)
_PENDING: set[Path] = set()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path; on success it replaces ``path``, on error it is removed.

    Parameters
    ----------
    path : the final file
    suffix : suffix of the temporary file (defaults to the final file's, so writers that look at
        the extension behave)
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.",
                                   suffix=suffix or path.suffix or ".tmp", dir=path.parent)
    except OSError as exc:
        raise InputError(f"cannot write here: {exc.strerror or exc}", source=str(path)) from None
    os.close(fd)
    tmp = Path(tmp)
    _PENDING.add(tmp)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the usual permissions
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise InputError(f"cannot write here: {exc.strerror or exc}",
                             source=str(path)) from None
    finally:
        _PENDING.discard(tmp)
        if tmp.exists():
            tmp.unlink()


@contextlib.contextmanager
def pending_folder(folder: str | os.PathLike) -> Iterator[Path]:
    """Mark a temporary folder as being filled: removed (whole) if the command is interrupted
    (:func:`remove_pending`) while inside the block; yields it as a path."""
    folder = Path(folder)
    _PENDING.add(folder)
    try:
        yield folder
    finally:
        _PENDING.discard(folder)


def remove_pending() -> int:
    """Remove every temporary file or folder still being written; return how many there
    were."""
    import shutil

    n = 0
    for tmp in list(_PENDING):
        _PENDING.discard(tmp)
        with contextlib.suppress(OSError):
            if tmp.is_dir() and not tmp.is_symlink():
                shutil.rmtree(tmp)
            else:
                tmp.unlink()
            n += 1
    return n


def _same(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output(output: str | os.PathLike, inputs: Iterable[str | os.PathLike | None] = (), *,
                 folder: bool = False, field: str = "output") -> Path:
    """Check an output path before any long work: never an input, and writable.

    Parameters
    ----------
    output : the file (or, with ``folder``, the folder) the command will write
    inputs : the files the command reads (None entries are skipped)
    folder : True when ``output`` is a folder that the command fills with several files
    field : the option that gave ``output``, for the message (e.g. ``-o``)

    Returns
    -------
    Path
        ``output`` as a path.

    Raises
    ------
    InputError
        When ``output`` is one of the inputs (or, for a folder, is an input file), is a folder
        where a file is expected (or the reverse), lies under an existing file, or cannot be
        written (no permission, read-only file system).
    """
    out = Path(output)
    for item in inputs:
        if item is not None and _same(out, Path(item)):
            raise InputError(f"the output is the input {item}: refusing to overwrite an input",
                             source=str(out), field=field)
    if folder and out.exists() and not out.is_dir():
        raise InputError("a file is in the way of the output folder", source=str(out),
                         field=field)
    if not folder and out.is_dir():
        raise InputError("a folder is in the way of the output file", source=str(out),
                         field=field)
    probe_dir = out if folder else out.parent
    existing = probe_dir
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise InputError(f"the path goes through the file {existing}", source=str(out),
                         field=field)
    try:
        fd, probe = tempfile.mkstemp(prefix=".facemech-probe.", dir=existing)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"cannot write here: {exc.strerror or exc}", source=str(out),
                         field=field) from None
    return out
