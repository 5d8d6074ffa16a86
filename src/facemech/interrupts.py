"""Interrupted commands: SIGINT and SIGTERM end a command cleanly.

The handler removes the temporary files being written (:func:`facemech.atomic.remove_pending`),
prints ``facemech: interrupted`` on stderr and exits with the shell's status for the signal:
130 for SIGINT (Ctrl-C), 143 for SIGTERM. Finished outputs are complete files (they were renamed
into place whole); nothing half-written is left.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["EXIT_STATUS", "handle", "install", "on_interrupt"]

#: the exit status of a command ended by each signal (128 + the signal number)
EXIT_STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}


#: clean-ups of the running command (e.g. a batch's workers and half-made folders), run first
_CLEANUPS: list = []


def on_interrupt(cleanup):
    """Run ``cleanup()`` if the command is interrupted (before the temporary files are
    removed); returns a function that unregisters it. Its errors are ignored: the command is
    ending anyway, and it says so in one line."""
    _CLEANUPS.append(cleanup)

    def remove() -> None:
        if cleanup in _CLEANUPS:
            _CLEANUPS.remove(cleanup)

    return remove


def _quietly(fn) -> None:
    import contextlib
    import io

    with contextlib.suppress(Exception), contextlib.redirect_stderr(io.StringIO()), \
            contextlib.redirect_stdout(io.StringIO()):
        fn()


def _mute_stderr() -> int:
    """Point file descriptor 2 at the null device, for this process's other threads and the
    processes it starts from now on (multiprocessing's resource tracker, a worker a pool
    restarts); return a descriptor of the real stderr (2 where that fails)."""
    try:
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass
    try:
        real = os.dup(2)
    except OSError:
        return 2
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 2)
        os.close(null)
    except OSError:
        pass
    return real


def handle(signum: int, frame=None) -> None:
    """Clean up and exit: run the registered clean-ups (:func:`on_interrupt`), remove pending
    temporary files and folders, say so, exit 128 + ``signum``. Anything else written to
    stderr meanwhile (by other threads or the processes being ended) goes to the null
    device: the command's last line on stderr is ``facemech: interrupted``."""
    from .atomic import remove_pending

    for sig in EXIT_STATUS:  # a second signal during the clean-up does not cut it short
        signal.signal(sig, signal.SIG_IGN)
    say = _mute_stderr()
    try:
        for cleanup in reversed(_CLEANUPS):
            _quietly(cleanup)
        _quietly(remove_pending)
        os.write(say, b"facemech: interrupted\n")
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
