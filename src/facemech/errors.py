"""Errors that carry the file and the field they are about.

The CLI turns a :class:`FacemechError` into one line on stderr and a non-zero exit; library
users can catch it and read ``source`` and ``field``.
"""

from __future__ import annotations

import re

#: numpy's repr of a scalar (NumPy >= 2), e.g. ``np.float64(nan)``: printed as the value itself
_NUMPY_REPR = re.compile(r"\bnp\.(float|int|uint|bool|complex|str)_?\d*\(([^()]*)\)")


class FacemechError(Exception):
    """A user-facing error: bad input, an impossible request, a numerical blow-up.

    Parameters
    ----------
    message : str
        What went wrong, in one line.
    source : str, optional
        The file (or other input) the problem is in.
    field : str, optional
        The field, column, channel or parameter inside ``source``.
    """

    def __init__(self, message: str, *, source: str | None = None, field: str | None = None):
        self.message = message
        self.source = None if source is None else str(source)
        self.field = field
        super().__init__(self.one_line())

    def one_line(self) -> str:
        where = []
        if self.source:
            where.append(self.source)
        if self.field:
            where.append(f"field '{self.field}'")
        prefix = ": ".join(where)
        text = f"{prefix}: {self.message}" if prefix else self.message
        return " ".join(_NUMPY_REPR.sub(r"\2", text).split())


class InputError(FacemechError):
    """A file or argument that cannot be used as given."""


class SimulationBlowUp(FacemechError):
    """The simulation produced non-finite or runaway values.

    Attributes
    ----------
    frame : int
        The 60-Hz output frame in which the blow-up was detected.
    """

    def __init__(self, message: str, *, frame: int, source: str | None = None):
        self.frame = int(frame)
        super().__init__(f"numerical blow-up at frame {frame}: {message}", source=source)


def missing_input(path, *, field: str | None = None, what: str = "file") -> InputError:
    """The error for an input that is not a readable regular file: ``"file not found"``, or,
    for a folder, FIFO, socket or device at that path, what it is instead."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except OSError:
        return InputError(f"{what} not found", source=str(path), field=field)
    kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "a device" if stat.S_ISCHR(mode)
            or stat.S_ISBLK(mode) else "not a regular file")
    return InputError(f"{kind}, not a {what}: give a regular file", source=str(path),
                      field=field)
