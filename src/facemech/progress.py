"""Progress of long runs as plain log lines, for output that is not a terminal.

Library workflows report progress through a *staged* callback, ``report(stage, done, total)``
(:data:`StagedProgress`): ``stage`` names the part of the work (``"simulate"``, ``"render"``),
``done`` counts its items, ``total`` is their number (None when unknown). :class:`LogProgress`
turns such calls into lines on stderr, with the time left estimated from the rate since the
stage's first item::

    facemech: simulate: frame 120/155, 7.1 s elapsed, about 2 s left

at most every ``every`` seconds per stage and when a stage completes, and runs a *heartbeat*: a
daemon thread that prints the stage's count again (or, before its first item, ::

    facemech: simulate: still working (23 s)

) whenever nothing has been printed for ``heartbeat`` seconds, so that a log (``make``, a pipe,
a batch job) never stays silent longer than that, even while no callback comes (numba compiling
the kernels, a face being built, files being written). The thread stops when the context ends.

The command line shows bars instead when stderr is a terminal (:mod:`facemech.cli`).
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

#: a staged progress callback: ``report(stage, done, total)``; total None when unknown
StagedProgress = Callable[[str, int, "int | None"], None]

#: seconds of silence after which the heartbeat prints a line
HEARTBEAT_S = 6.0

#: what the items of a stage are, where it is known: its counts read "frame 40/116"
NOUNS = {"simulate": "frame", "render": "frame", "invert": "frame", "render and read": "frame",
         "plan": "iteration"}


def duration(seconds: float) -> str:
    """``seconds`` as a short text: "<1 s", "7 s", "2 min 05 s"."""
    if seconds < 1:
        return "<1 s"
    if seconds < 60:
        return f"{seconds:.0f} s"
    m, s = divmod(round(seconds), 60)
    return f"{m} min {s:02d} s"


def count_line(stage: str, done: int, total: int | None, elapsed: float,
               left: float | None = None) -> str:
    """A stage's progress line: ``"invert (lsq): frame 40/116, 4.1 s elapsed, about 7 s
    left"``; ``elapsed`` and ``left`` in s (``left`` None, or the stage complete: no
    estimate)."""
    noun = NOUNS.get(stage.split(" (")[0])
    of = f"/{total}" if total is not None else ""
    text = f"{stage}: {noun + ' ' if noun else ''}{done}{of}, {elapsed:.1f} s elapsed"
    if left is not None and total is not None and done < total:
        text += f", about {duration(left)} left"
    return text


def stage(progress: StagedProgress | None, name: str) -> Callable[[int, int], None] | None:
    """The per-item callback ``(done, total)`` of one stage of a staged ``progress`` (None
    passes through), for functions that take a plain ``progress(done, total)``."""
    if progress is None:
        return None
    return lambda done, total: progress(name, done, total)


def staged(display) -> StagedProgress:
    """The staged callback of a progress display with ``add_task(description, total=)`` and
    ``update(task, completed=, total=)`` (:class:`LogProgress`, or the command line's bars):
    one task per stage, added on the stage's first report."""
    tasks: dict[str, int] = {}

    def report(stage: str, done: int, total: int | None) -> None:
        if stage not in tasks:
            tasks[stage] = display.add_task(stage, total=total)
        display.update(tasks[stage], completed=done, total=total)

    return report


@dataclass
class _Task:
    description: str
    total: int | None
    start: float
    last: float
    done: int = -1
    first: tuple[float, int] | None = None  # (time, count) of the first report of an item

    @property
    def finished(self) -> bool:
        return self.total is not None and self.done >= self.total

    def line(self, now: float) -> str:
        """The count line at time ``now``: the time left at the rate since the first item
        (the time before it, numba compiling or a face being built, not counted)."""
        left = None
        if self.first is not None and self.total is not None and self.done > self.first[1]:
            rate = (now - self.first[0]) / (self.done - self.first[1])
            left = rate * (self.total - self.done)
        return count_line(self.description, self.done, self.total, now - self.start, left)


class LogProgress:
    """Progress as plain lines on ``stream`` (default: stderr), with a heartbeat.

    The interface is that of the progress bars (rich's) that the command line uses
    (``add_task``, ``update``, a context manager), plus ``report``, a staged callback. The
    context may be entered again while it is open (a command's stages inside the command's
    whole run): the heartbeat starts with the first entry and stops with the last exit.

    Parameters
    ----------
    label : what the heartbeat names while no stage is under way (the command)
    every : s, the shortest time between two lines of one stage (a stage's completion always
        prints)
    heartbeat : s, the longest silence: the heartbeat prints when no line came for this long;
        None or 0 for none
    stream : text stream (default: ``sys.stderr`` at the time of each line)
    clock : a monotonic clock in seconds (a fake one in tests)
    """

    def __init__(self, label: str = "facemech", *, every: float = 5.0,
                 heartbeat: float | None = HEARTBEAT_S, stream=None,
                 clock: Callable[[], float] = time.monotonic):
        self.label = label
        self.every = every
        self.heartbeat = heartbeat
        self._stream = stream
        self._clock = clock
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._depth = 0
        self.tasks: list[_Task] = []
        self._current: int | None = None
        self.start = self._last_line = clock()
        self.report = staged(self)

    # ---- context: the heartbeat's thread -------------------------------------------------
    def __enter__(self) -> LogProgress:
        self._depth += 1
        if self._depth == 1:
            self.start = self._last_line = self._clock()
            if self.heartbeat:
                self._stop.clear()
                self._thread = threading.Thread(target=self._beat_loop, daemon=True,
                                                name="facemech-heartbeat")
                self._thread.start()
        return self

    def __exit__(self, *exc) -> bool:
        self._depth = max(0, self._depth - 1)
        if self._depth == 0:
            self.close()
        return False

    def close(self) -> None:
        """Stop the heartbeat (waits for its thread); no line is printed after this returns."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def _beat_loop(self) -> None:
        while not self._stop.wait(min(0.25, self.heartbeat / 4)):
            self.beat()

    # ---- lines ---------------------------------------------------------------------------
    def _print(self, text: str) -> None:
        stream = self._stream or sys.stderr
        print(f"facemech: {text}", file=stream, flush=True)
        self._last_line = self._clock()

    def beat(self) -> bool:
        """Print the heartbeat line if nothing was printed for ``heartbeat`` seconds: the stage
        under way with its count and time left (:func:`count_line`), or before its first item
        (or with none under way: the label) its elapsed time. Returns whether it printed."""
        with self._lock:
            now = self._clock()
            if not self.heartbeat or now - self._last_line < self.heartbeat:
                return False
            task = None if self._current is None else self.tasks[self._current]
            if task is not None and not task.finished and task.done > 0:
                self._print(task.line(now))
                task.last = now
                return True
            if task is None or task.finished:
                name, since = self.label, self.start
            else:
                name, since = task.description, task.start
            self._print(f"{name}: still working ({now - since:.0f} s)")
            return True

    def add_task(self, description: str, total: int | None = None) -> int:
        """A new stage; returns its id for :meth:`update`."""
        with self._lock:
            now = self._clock()
            self.tasks.append(_Task(description, total, now, now))
            self._current = len(self.tasks) - 1
            return self._current

    def update(self, task: int, completed: int, total: int | None = None) -> None:
        """Items ``completed`` of stage ``task`` (and its ``total``, if it changed)."""
        with self._lock:
            t = self.tasks[task]
            if total is not None:
                t.total = total
            now = self._clock()
            was_finished = t.finished
            t.done = completed
            if t.first is None and completed > 0:
                t.first = (now, completed)
            self._current = task
            if (t.finished and not was_finished) or now - t.last >= self.every:
                self._print(t.line(now))
                t.last = now
