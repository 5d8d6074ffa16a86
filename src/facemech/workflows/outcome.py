"""What a workflow returns: the file it wrote, the data it holds, and a line saying so."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Written:
    """A file or folder a workflow wrote.

    Attributes
    ----------
    path : what was written
    data : what it holds (a MarkerSet, an EMGActivity, a FaceModel, a dict, ...)
    line : one line for the user (the command prints it; also ``str()``)
    warnings : lines for stderr, each ending in a newline ("" for none)
    """

    path: Path
    data: object = None
    line: str = ""
    warnings: str = ""

    def __str__(self) -> str:
        return self.line

    def __rich__(self) -> str:  # what a rich console prints
        return self.line
