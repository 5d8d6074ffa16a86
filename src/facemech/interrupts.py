"""Interrupted commands: SIGINT and SIGTERM end a command cleanly.

The handler removes the temporary files being written (:func:`facemech.io.atomic.remove_pending`),
prints ``facemech: interrupted`` on stderr and exits with the shell's status for the signal:
130 for SIGINT (Ctrl-C), 143 for SIGTERM. Finished outputs are complete files (they were renamed
into place whole); nothing half-written is left.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["EXIT_STATUS", "install", "handle"]

#: the exit status of a command ended by each signal (128 + the signal number)
EXIT_STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}


def handle(signum: int, frame=None) -> None:
    """Clean up and exit: remove pending temporary files, say so, exit 128 + ``signum``."""
    from .io.atomic import remove_pending

    remove_pending()
    try:
        sys.stderr.write("facemech: interrupted\n")
        sys.stderr.flush()
    finally:
        os._exit(EXIT_STATUS.get(signum, 128 + int(signum)))


def install():
    """Install :func:`handle` for SIGINT and SIGTERM; return a function that restores the
    handlers found. Outside the main thread (where signals cannot be handled) nothing changes."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = {sig: signal.signal(sig, handle) for sig in EXIT_STATUS}

    def restore() -> None:
        for sig, old in previous.items():
            signal.signal(sig, old)

    return restore
