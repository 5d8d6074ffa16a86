"""How many threads the force kernels use.

:func:`~facemech.physics.assembly.accumulate_forces` spreads the springs and prisms of a large
mesh over numba's threads in slabs across the face (:mod:`facemech.physics.slabs`): on two or
more threads the forces are the same to the bit whatever the count, and differ from one
thread's only by the order of their additions (about 1e-16 relative). :func:`set_threads` sets
the count for the calling thread; the kernels read it at every call (:func:`kernel_threads`),
so it may change between steps.

Importing the package leaves numba's count as it is (numba's default: every CPU, or
``NUMBA_NUM_THREADS``); a command of the command line runs on :func:`default_threads`, the cores
it may run on (``FACEMECH_THREADS`` in the environment, or ``--threads``, sets it instead), and a
program calls :func:`set_threads` for the same. On a machine busy with other work, threads that
wait for each other at every step cost more than they save: set one there.
"""

from __future__ import annotations

import os

import numba as nb
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from ..errors import InputError


def affinity_cores() -> int:
    """The cores this process may run on: its CPU affinity where the system tells it, else
    the machine's CPU count (at least 1)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def available_cores() -> int:
    """The cores this process may run on (:func:`affinity_cores`), at most numba's thread pool
    (``NUMBA_NUM_THREADS``)."""
    return max(1, min(affinity_cores(), nb.config.NUMBA_NUM_THREADS))


def default_threads(environ=None) -> int:
    """The thread count a process starts on: ``FACEMECH_THREADS`` where set, else the cores
    available (:func:`available_cores`). Not the machine's load: a script run twice on one
    machine runs on the same count, and gives the same numbers to the bit.

    Parameters
    ----------
    environ : mapping, optional -- the environment (default ``os.environ``)

    Raises
    ------
    InputError
        ``FACEMECH_THREADS`` is not a whole number from 1 to ``NUMBA_NUM_THREADS``
        (``field="FACEMECH_THREADS"``).
    """
    environ = os.environ if environ is None else environ
    limit = nb.config.NUMBA_NUM_THREADS
    text = environ.get("FACEMECH_THREADS", "").strip()
    if text:
        if not text.isdigit() or not 1 <= int(text) <= limit:
            raise InputError(f"FACEMECH_THREADS must be a whole number from 1 to {limit} "
                             f"(got {text!r})", field="FACEMECH_THREADS")
        return int(text)
    return available_cores()


def set_threads(n: int | None = None) -> int:
    """Set the threads the force kernels use (``numba.set_num_threads``).

    Parameters
    ----------
    n : int, optional
        1 to ``NUMBA_NUM_THREADS`` (numba's pool, fixed when numba starts); default:
        :func:`default_threads` (the cores available, or ``FACEMECH_THREADS``).

    Returns
    -------
    int -- the thread count now set

    Raises
    ------
    InputError
        ``n`` is not an integer from 1 to the pool's size (``field="threads"``).
    """
    limit = nb.config.NUMBA_NUM_THREADS
    if n is None:
        n = default_threads()
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= limit:
        raise InputError(f"threads must be a whole number from 1 to {limit} (got {n!r}); "
                         "NUMBA_NUM_THREADS sets the largest", field="threads")
    nb.set_num_threads(n)
    return n


def get_threads() -> int:
    """The threads the force kernels use now (``numba.get_num_threads``)."""
    return nb.get_num_threads()


@intrinsic
def _num_threads(typingctx):
    """numba's thread count of the calling thread, read through the threading layer's
    ``get_num_threads`` symbol by name (as numba's own parallel loops do), so that the kernels
    calling it stay cacheable (``numba.get_num_threads`` inside a kernel goes through a ctypes
    pointer, which numba cannot cache)."""

    def codegen(context, builder, signature, args):
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(cgutils.intp_t, []),
                                            "get_num_threads")
        return builder.call(fn, [])

    return types.intp(), codegen


@nb.njit(cache=True, inline="always")
def kernel_threads():
    """Inside a compiled kernel: the thread count :func:`set_threads` set."""
    return _num_threads()


# start numba's threads now: that registers the symbol the kernels read (a kernel loaded from
# numba's cache is not compiled, so nothing else would). The count stays numba's: importing
# facemech changes no thread count (the command line and the caller set it, set_threads)
nb.get_num_threads()

__all__ = ["set_threads", "get_threads", "affinity_cores", "available_cores", "default_threads",
           "kernel_threads"]
