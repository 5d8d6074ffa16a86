"""Independent columns of an inversion's finite differences, on the machine's cores.

:func:`map_columns` computes ``fn(j)`` for each column ``j``: in this process alone, or shared
with forked copies of it (POSIX ``fork``: a copy has the model, its compiled kernels and its
factorised matrices as they are, and only the columns' results travel back, pickled through a
pipe). Every column is computed on one kernel thread whichever process takes it, so the
numbers do not depend on how many processes share the work. :func:`column_workers` is the
count: ``FACEMECH_WORKERS`` where set, else the cores this process may run on, at most 2.
"""

from __future__ import annotations

import os
import pickle
from collections.abc import Callable, Sequence
from contextlib import contextmanager

import numpy as np

from ..errors import InputError
from ..physics.threads import affinity_cores, get_threads, set_threads

#: the most processes :func:`column_workers` takes by default (the columns of a frame are few)
DEFAULT_MOST = 2


def column_workers(environ=None) -> int:
    """The processes that share an inversion's columns: ``FACEMECH_WORKERS`` (a whole number
    from 1 to 64) where set, else the cores this process may run on, at most
    :data:`DEFAULT_MOST`; 1 where the system cannot fork."""
    environ = os.environ if environ is None else environ
    text = environ.get("FACEMECH_WORKERS", "").strip()
    if text:
        if not text.isdigit() or not 1 <= int(text) <= 64:
            raise InputError(f"FACEMECH_WORKERS must be a whole number from 1 to 64 (got "
                             f"{text!r})", field="FACEMECH_WORKERS")
        n = int(text)
    else:
        n = min(DEFAULT_MOST, affinity_cores())
    return n if hasattr(os, "fork") else 1


@contextmanager
def one_kernel_thread():
    """The force kernels on one thread within the block (the count before, after it)."""
    before = get_threads()
    set_threads(1)
    try:
        yield
    finally:
        set_threads(before)


def map_columns(fn: Callable[[int], object], n: int, *, workers: int | None = None) -> list:
    """``[fn(0), ..., fn(n - 1)]``, each on one kernel thread, the columns split in
    contiguous shares between this process and ``workers - 1`` forked copies (default
    :func:`column_workers`). An exception raised by ``fn`` in a copy is raised here."""
    workers = column_workers() if workers is None else int(workers)
    shares = [s for s in np.array_split(np.arange(n), max(1, min(workers, n))) if len(s)]
    with one_kernel_thread():
        if len(shares) <= 1:
            return [fn(j) for j in range(n)]
        children = [_fork(fn, share) for share in shares[1:]]
        out: list = [None] * n
        try:
            for j in shares[0]:
                out[j] = fn(int(j))
        finally:
            results = [_collect(child) for child in children]
        for share, (kind, value) in zip(shares[1:], results, strict=True):
            if kind == "error":
                raise value
            for j, v in zip(share, value, strict=True):
                out[j] = v
        return out


def _fork(fn, share: Sequence[int]):
    """A forked copy computing ``fn`` over ``share``: (pid, the pipe's read end)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the copy: compute, send, leave without running the parent's exit handlers
        code = 0
        try:
            os.close(read)
            try:
                payload = pickle.dumps(("ok", [fn(int(j)) for j in share]))
            except BaseException as exc:  # noqa: BLE001 (sent to the parent, raised there)
                payload = pickle.dumps(("error", _picklable(exc)))
            with os.fdopen(write, "wb") as pipe:
                pipe.write(payload)
        except BaseException:  # noqa: BLE001 (the parent sees a short read)
            code = 1
        finally:
            os._exit(code)
    os.close(write)
    return pid, read


def _collect(child) -> tuple[str, object]:
    """The (kind, value) a forked copy sent; its exit waited for."""
    pid, read = child
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()
    os.waitpid(pid, 0)
    if not data:
        return "error", RuntimeError("a process computing finite-difference columns ended "
                                     "without a result")
    return pickle.loads(data)


def _picklable(exc: BaseException) -> BaseException:
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:  # noqa: BLE001
        return RuntimeError(f"{type(exc).__name__}: {exc}")


__all__ = ["DEFAULT_MOST", "column_workers", "map_columns", "one_kernel_thread"]
