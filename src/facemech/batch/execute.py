"""One batch item run into its own folder: skipped when its done-record is up to date, else
made in a temporary folder, its done-record written last, the folder renamed into place.

:func:`run_item` is what a dask worker runs; it never raises for the item's own failure (bad
input or any exception): the :class:`Outcome` says ``failed`` with the error's one line.
"""

from __future__ import annotations

import shutil
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import FacemechError
from .job import Job
from .manifest import Item
from .records import commit_folder, folder_files, new_partial, up_to_date, write_done

__all__ = ["Outcome", "run_item", "skipped"]


@dataclass(frozen=True)
class Outcome:
    """What became of one item.

    Attributes
    ----------
    id, job : the item's id and job kind
    status : ``done`` (made now), ``skipped`` (its done-record was up to date), ``failed``, or
        ``not run`` (the batch stopped before it)
    wall_s : seconds the item took to make (for a skipped item: when it was made)
    cpu_s : CPU seconds of the thread that made it (the same)
    numbers : its key numbers (frames, errors, ...; see :mod:`facemech.workflows.batch_jobs`)
    error : the one-line error of a failed item ("" otherwise)
    folder : its output folder (None when failed)
    """

    id: str
    job: str
    status: str
    wall_s: float = 0.0
    cpu_s: float = 0.0
    numbers: dict = field(default_factory=dict)
    error: str = ""
    folder: Path | None = None

    @property
    def ok(self) -> bool:
        return self.status in ("done", "skipped")

    def line(self) -> str:
        """One line for the user: ``ID (JOB): STATUS ...``."""
        if not self.ok:
            return f"{self.id} ({self.job}): failed: {self.error}"
        if self.status == "not run":
            return f"{self.id} ({self.job}): not run"
        nums = ", ".join(f"{k} {v}" for k, v in self.numbers.items())
        how = (f"done in {self.wall_s:.1f} s" if self.status == "done"
               else f"unchanged (made in {self.wall_s:.1f} s)")
        return f"{self.id} ({self.job}): {how}" + (f"; {nums}" if nums else "")

    def row(self) -> dict:
        """Its row of the summary table."""
        return {"id": self.id, "job": self.job, "status": self.status,
                "wall_s": f"{self.wall_s:.3f}", "cpu_s": f"{self.cpu_s:.3f}", **self.numbers,
                "error": self.error}


def skipped(item: Item, record: dict, folder: Path) -> Outcome:
    """The outcome of an item whose done-record ``record`` is up to date."""
    return Outcome(item.id, item.job, "skipped", float(record.get("wall_s", 0.0)),
                   float(record.get("cpu_s", 0.0)), dict(record.get("numbers", {})), "", folder)


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, FacemechError):
        return exc.one_line()
    text = " ".join(str(exc).split())
    frame = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
    where = f" (at {Path(frame.filename).name}:{frame.lineno})" if frame else ""
    return f"{type(exc).__name__}: {text}{where}"


def run_item(item: Item, out_dir: str | Path, jobs: dict[str, Job]) -> Outcome:
    """Make ``item`` into ``out_dir/<id>/`` unless its done-record there is up to date.

    Parameters
    ----------
    item : a checked manifest item
    out_dir : the batch's output folder
    jobs : the job kinds, kind -> :class:`~.job.Job` (:data:`facemech.workflows.batch_jobs.JOBS`)

    Returns
    -------
    Outcome
        ``skipped`` (nothing run), ``done`` (the folder replaced atomically, its done-record
        holding the item's key, input hashes, settings, wall time and key numbers) or
        ``failed`` (nothing written; the error's one line).
    """
    from .._version import __version__
    from ..physics.threads import set_threads

    final = Path(out_dir) / item.id
    record = up_to_date(final, item.key)
    if record is not None:
        return skipped(item, record, final)
    start, cpu = time.perf_counter(), time.thread_time()
    partial = None
    try:
        # one core per item: the workers are the parallelism (docs/batch.md)
        set_threads(1)
        partial = new_partial(out_dir, item.id)
        numbers, lines = jobs[item.job].run(dict(item.options), partial)
        lines = [str(line).replace(str(partial), str(final)) for line in lines]
        wall, cpu = time.perf_counter() - start, time.thread_time() - cpu
        write_done(partial, {
            "id": item.id, "job": item.job, "key": item.key, "inputs": item.inputs,
            "settings": item.settings, "options": item.options, "numbers": numbers,
            "report": list(lines), "files": folder_files(partial), "wall_s": round(wall, 3),
            "cpu_s": round(cpu, 3),
            "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "facemech": __version__})
        commit_folder(partial, final)
    except Exception as exc:  # the item fails, the batch goes on
        if partial is not None:
            shutil.rmtree(partial, ignore_errors=True)
        return Outcome(item.id, item.job, "failed", time.perf_counter() - start,
                       time.thread_time() - cpu, {}, _one_line(exc), None)
    return Outcome(item.id, item.job, "done", wall, cpu, numbers, "", final)
