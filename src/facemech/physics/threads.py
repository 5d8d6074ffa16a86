"""How many threads the force kernels use.

:func:`~facemech.physics.assembly.accumulate_forces` spreads the springs and prisms of a large
mesh over numba's threads (``prange``, one array of forces per thread, added in thread order),
so a step's forces depend on the thread count only in the order of their additions (to
rounding, about 1e-16 relative). :func:`set_threads` sets that count for the calling thread;
a process starts on one (numba's default would be every core); ``set_threads()``
with no argument takes the cores this process may run on. The compiled kernels read it at every call
(:func:`kernel_threads`), so it may change between steps.
"""

from __future__ import annotations

import os

import numba as nb
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from ..errors import InputError


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity), at most numba's thread pool
    (``NUMBA_NUM_THREADS``)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, nb.config.NUMBA_NUM_THREADS))


def set_threads(n: int | None = None) -> int:
    """Set the threads the force kernels use (``numba.set_num_threads``).

    Parameters
    ----------
    n : int, optional
        1 to ``NUMBA_NUM_THREADS`` (numba's pool, fixed when numba starts); default: the cores
        available (:func:`available_cores`).

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
        n = available_cores()
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
# numba's cache is not compiled, so nothing else would). facemech starts on one thread: on a
# machine busy with other work, threads that wait for each other cost far more than they save
# (benchmarks/forward.py --threads; docs/performance.md)
nb.get_num_threads()
nb.set_num_threads(1)

__all__ = ["set_threads", "get_threads", "available_cores", "kernel_threads"]
