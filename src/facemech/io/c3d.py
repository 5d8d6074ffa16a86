"""C3D analog channels via ezc3d, read in a child process.

ezc3d can crash the interpreter (a segfault, not an exception) on malformed files, so the read
runs in a separate process; a crash there becomes a one-line error here.
"""

from __future__ import annotations

import multiprocessing as mp
import queue as queue_mod
import time
from pathlib import Path

import numpy as np

from ..errors import InputError


def _read_analog_child(path: str, queue) -> None:  # pragma: no cover - runs in the child
    try:
        import ezc3d

        c = ezc3d.c3d(path)
        params = c["parameters"]["ANALOG"]
        rate = float(params["RATE"]["value"][0])
        labels = [str(s).strip() for s in params["LABELS"]["value"]]
        data = np.asarray(c["data"]["analogs"], float)[0].T  # (samples, channels)
        queue.put(("ok", rate, labels, data))
    except Exception as exc:
        queue.put(("error", f"{type(exc).__name__}: {exc}", None, None))


def read_c3d_analog(path: str | Path, timeout: float = 120.0):
    """Analog rate (Hz), channel labels and data (samples, channels) of a C3D file."""
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    try:
        import ezc3d  # noqa: F401
    except ImportError:
        raise InputError("reading C3D needs ezc3d (pip install 'facemech[c3d]')",
                         source=str(path)) from None
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_read_analog_child, args=(str(path), queue), daemon=True)
    proc.start()
    deadline = time.monotonic() + timeout
    try:
        while True:
            try:
                status, a, b, c = queue.get(timeout=0.2)
                break
            except queue_mod.Empty:
                if not proc.is_alive() or time.monotonic() > deadline:
                    proc.kill()
                    raise InputError(f"corrupt C3D: the reader stopped (exit code "
                                     f"{proc.exitcode})", source=str(path)) from None
    finally:
        proc.join(timeout=5)
    if status != "ok":
        raise InputError(f"corrupt C3D ({a})", source=str(path))
    if b is None or len(b) == 0:
        raise InputError("no analog channels", source=str(path), field="ANALOG:LABELS")
    return a, b, c
