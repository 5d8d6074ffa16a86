"""A movie's frames drawn on a few threads at once, handed back in order.

Each thread draws with a :class:`.render.Renderer` of its own (its own cameras and
visibility buffers); the threads share the scene, which they only read
(:meth:`.scene.Scene.frame`). The rasteriser's kernels release the GIL (:mod:`.raster`), so
the threads run in parallel; most of a frame's time is spent in them. A frame is the same
array whichever thread draws it: the frames are bit-identical to those of one thread.

At most ``2 * workers`` frames are queued or in flight at a time: an error in a thread is
raised in the caller at that frame, and an error or an interrupt (Ctrl-C) in the caller
cancels the frames not yet started and waits only for the ones being drawn.
"""

from __future__ import annotations

import queue
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager
from functools import partial
from typing import TypeVar

from ..checks import check_value
from ..interrupts import on_interrupt
from ..physics.threads import affinity_cores
from .render import Renderer

T = TypeVar("T")

#: the most threads a movie is drawn on by default
DEFAULT_WORKERS = 2


def check_workers(workers: int | None) -> int:
    """The number of drawing threads: ``workers`` checked (a whole number 1 to 1024, else an
    :class:`~facemech.errors.InputError` naming the field ``workers``), or for None
    ``min(2, the cores of this process's CPU affinity)`` (Python threads, so not capped at
    numba's pool as :func:`facemech.physics.threads.available_cores` is). 1 draws every frame in
    the caller's thread."""
    if workers is None:
        return max(1, min(DEFAULT_WORKERS, affinity_cores()))
    check_value("workers", workers)
    return int(workers)


def in_order(make: Callable[[], Renderer], task: Callable[[Renderer, int], T], count: int,
             workers: int | None = None) -> Iterator[T]:
    """``task(renderer, k)`` for k = 0 .. count - 1, yielded in that order.

    Parameters
    ----------
    make : makes a renderer; called once per thread, in the caller's thread, at the first
        frame
    task : draws frame ``k`` with a renderer (and may write it out); its result is yielded
    count : number of frames
    workers : threads (:func:`check_workers`, checked here, before any frame; None:
        ``min(2, cores)``, 1: no thread)

    Use the iterator in a ``with contextlib.closing(...)`` block or run it to the end:
    closing it early cancels the frames not yet started.
    """
    n = check_workers(workers)
    if n == 1 or count <= 1:
        return _serial(make, task, count)
    return _threaded(make, task, count, n)


def _serial(make, task, count: int):
    render = make()
    for k in range(count):
        yield task(render, k)


def _threaded(make, task, count: int, n: int):
    """:func:`in_order` on ``n`` threads, each frame drawn with a renderer that no other
    thread holds meanwhile, at most ``2 n`` frames submitted ahead of the one yielded."""
    idle: queue.SimpleQueue[Renderer] = queue.SimpleQueue()
    for _ in range(n):
        idle.put(make())

    def run(k: int):
        render = idle.get()  # never waits: n renderers for n threads
        try:
            return task(render, k)
        finally:
            idle.put(render)

    with _pool(n) as pool:
        pending: deque[Future] = deque()
        nxt = 0
        for _ in range(count):
            while nxt < count and len(pending) < 2 * n:
                pending.append(pool.submit(run, nxt))
                nxt += 1
            yield pending.popleft().result()


@contextmanager
def _pool(n: int):
    """A thread pool of ``n`` threads, shut down on leaving: the frames not yet started are
    cancelled (an error or interrupt), the ones being drawn are waited for. A command ended by
    a signal (:mod:`facemech.interrupts`, which exits without unwinding) does the same before
    it removes its temporary files, so that no thread writes a frame into a folder being
    removed."""
    pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix="facemech-frame")
    stop = partial(pool.shutdown, wait=True, cancel_futures=True)
    forget = on_interrupt(stop)
    try:
        yield pool
    finally:
        forget()
        stop()
