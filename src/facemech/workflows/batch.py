"""``facemech batch``: the items of a manifest (simulate, invert, speak, stimuli, regions) run
on dask.distributed, each into its own folder, finished items skipped on a rerun, a summary
table at the end.

dask.distributed (the ``batch`` extra) is imported only here, inside the functions.
"""

from __future__ import annotations

import contextlib
import logging
import os
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..batch.execute import Outcome, skipped
from ..batch.manifest import Item
from ..batch.records import remove_partial, up_to_date, write_summary
from ..checks import check_value
from ..errors import InputError
from .batch_jobs import read_manifest, run_job

__all__ = ["BatchReport", "report", "run_batch"]

#: per-item callback: on_item(outcome, finished, total), finished counting skipped items too
OnItem = Callable[[Outcome, int, int], None]


@dataclass
class BatchReport:
    """What :func:`run_batch` did: every item's :class:`~facemech.batch.execute.Outcome` in
    the manifest's order, the summary table's path, and where the items ran."""

    outcomes: list[Outcome] = field(default_factory=list)
    summary_csv: Path | None = None
    cluster: str = "none (nothing to run)"

    def count(self, status: str) -> int:
        return sum(o.status == status for o in self.outcomes)

    @property
    def exit_code(self) -> int:
        """0 when every item is done or skipped, 1 when some failed (or did not run)."""
        return 0 if all(o.ok for o in self.outcomes) else 1

    def summary(self) -> str:
        return (f"{len(self.outcomes)} items: {self.count('done')} done, "
                f"{self.count('skipped')} unchanged, {self.count('failed')} failed"
                + (f", {self.count('not run')} not run" if self.count("not run") else "") + " "
                f"(on {self.cluster}); summary -> {self.summary_csv}")


def report(rep: BatchReport) -> tuple[list[str], list[str]]:
    """What ``facemech batch`` prints: (the summary lines, the failed items' error lines)."""
    return ([rep.summary()],
            [f"error: {o.id}: {o.error}" for o in rep.outcomes if not o.ok])


def _all_inputs(items: list[Item]) -> list[str]:
    paths: list[str] = []
    for item in items:
        for name in item.inputs:
            value = item.options.get(name)
            paths.extend(value if isinstance(value, list) else [value] if value else [])
    return paths


def _input_bytes(item: Item) -> int:
    """The summed size (bytes) of an item's input files: the estimate of its work by which the
    largest items are sent first (a missing file counts 0; the item then fails by itself)."""
    total = 0
    for path in _all_inputs([item]):
        try:
            total += os.path.getsize(path)
        except OSError:
            pass
    return total


def _stop_workers(out: Path, clusters: list, created: bool) -> None:
    """On an interrupt: tell the local cluster's nannies not to restart their workers, end
    this command's child processes at once (SIGKILL, so that none logs or starts another
    item; multiprocessing's resource tracker is left to release their semaphores when this
    process ends), then remove the items' half-made folders, and ``out`` itself when this
    command made it and it is empty."""
    logging.disable(logging.CRITICAL)  # dask's threads go on a moment: nothing more from them
    for cluster in clusters:
        with contextlib.suppress(Exception):
            from distributed.core import Status

            for nanny in list(getattr(cluster, "workers", {}).values()):
                nanny.status = Status.closing  # a nanny restarts a worker that dies, else
    try:
        import psutil  # a dependency of dask.distributed
    except ImportError:
        psutil = None
    if psutil is not None:
        from multiprocessing import resource_tracker

        tracker = getattr(resource_tracker._resource_tracker, "_pid", None)
        for _ in range(3):  # again, for a process started while the first ones were ended
            children = [c for c in psutil.Process().children(recursive=True)
                        if c.pid != tracker]
            if not children:
                break
            for child in children:
                with contextlib.suppress(psutil.Error):
                    child.kill()
            psutil.wait_procs(children, timeout=5)
    remove_partial(out)
    if created:
        with contextlib.suppress(OSError):
            out.rmdir()  # only when empty: finished items stay


def _quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker with its stderr on the null device: when an
    interrupt ends the command at once, the tracker still releases the semaphores of the local
    cluster, without printing its "leaked semaphore objects" warning after the command's one
    line. A tracker already running is left as it is."""
    from multiprocessing import resource_tracker

    tracker = resource_tracker._resource_tracker
    if getattr(tracker, "_pid", None) is not None:
        return
    try:
        saved = os.dup(2)
    except OSError:
        return
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 2)
        os.close(null)
        tracker.ensure_running()
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _connect(workers: int | None, scheduler: str | None, processes: bool, n_jobs: int):
    """A dask Client and its description: the scheduler at ``scheduler``, else a new
    LocalCluster (``workers`` processes, one thread each; default one per core, at most one
    per item). Not dask's default client: a batch leaves the caller's dask settings (and any
    client of theirs) as they were."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("facemech batch needs dask.distributed: pip install "
                         "'facemech[batch]'", field="scheduler") from None
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f"cannot reach the dask scheduler ({exc})", source=scheduler,
                             field="scheduler") from None
        return client, None, f"the scheduler {scheduler}"
    n = workers if workers is not None else min(n_jobs, os.cpu_count() or 1)
    if n < 1:
        raise InputError(f"workers must be at least 1 (got {n})", field="workers")
    import dask

    if processes:
        _quiet_resource_tracker()
    # one item at a time on each worker, the next one handed to whichever worker is free
    # first (dask's default, 1.1, gives a one-thread worker a second item to hold: at the end
    # of a batch one worker may sit idle while another has two to do)
    with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                               dashboard_address=":0", silence_logs=logging.ERROR)
    kind = "processes" if processes else "threads"
    return (Client(cluster, set_as_default=False), cluster,
            f"a local cluster of {n} worker {kind}")


def _died(item: Item, exc: BaseException) -> Outcome:
    """A failed outcome for an item whose task ended without a result (a worker killed too
    often, a lost scheduler)."""
    text = " ".join(str(exc).split()) or "no detail"
    return Outcome(item.id, item.job, "failed", 0.0, 0.0, {},
                   f"its worker died or the task was lost ({type(exc).__name__}: {text})")


def run_batch(manifest: str | Path, output: str | Path, *, workers: int | None = None,
              scheduler: str | None = None, client=None, processes: bool = True,
              progress: Callable[[str, int, int], None] | None = None,
              on_item: OnItem | None = None) -> BatchReport:
    """Run the items of a manifest on dask.distributed, each into ``output/<id>/``.

    The manifest is read and checked whole first (:func:`facemech.batch.manifest.
    read_manifest`). Items whose done-record is up to date (same job, settings and input
    contents) are skipped without starting a cluster; the others are sent to the workers
    (:func:`facemech.batch.execute.run_item`), each made in a temporary folder renamed into
    place with its done-record. An item that fails is reported with its one-line error and
    the others go on. Temporary folders left by a killed run are removed first. Then
    ``output/summary.csv`` lists every item.

    Parameters
    ----------
    manifest : the manifest (``.csv`` or ``.toml``; see :mod:`facemech.batch.manifest`)
    output : the output folder (created)
    workers : worker processes of the local cluster (default: one per core, at most one per
        item to run); one thread each
    scheduler : address of a running dask scheduler (``tcp://HOST:8786``) to use instead of a
        local cluster; its workers must see ``manifest``, the inputs and ``output`` at the
        same paths (a shared file system) and have facemech installed
    client : an existing ``distributed.Client`` to use (takes precedence; left open)
    processes : the local cluster's workers are processes (True) or threads in this process
    progress : staged callback ``progress("batch", finished, total)``
    on_item : ``on_item(outcome, finished, total)`` after each item (skipped ones first)

    Returns
    -------
    BatchReport
        Its ``exit_code`` is 0 when no item failed, else 1.

    Raises
    ------
    InputError
        A manifest error (naming the manifest, the row and the field), an output folder that
        cannot be written or is an input, a scheduler that cannot be reached, ``workers``
        given with ``scheduler`` (or ``client``).
    """
    from ..atomic import check_output

    if workers is not None:
        check_value("workers", workers)  # the command line's interval (facemech.checks)
    if workers is not None and (scheduler is not None or client is not None):
        raise InputError("give the number of local workers or a scheduler, not both",
                         field="workers")
    items = read_manifest(manifest)
    out = check_output(output, [manifest, *_all_inputs(items)], folder=True, field="-o")
    out = out.resolve()
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    remove_partial(out)
    total = len(items)
    results: dict[str, Outcome] = {}
    rep = BatchReport()

    def finished(outcome: Outcome) -> None:
        results[outcome.id] = outcome
        if on_item is not None:
            on_item(outcome, len(results), total)
        if progress is not None:
            progress("batch", len(results), total)

    if progress is not None:
        progress("batch", 0, total)
    todo = []
    for item in items:
        record = up_to_date(out / item.id, item.key)
        if record is not None:
            finished(skipped(item, record, out / item.id))
        else:
            todo.append(item)
    from ..interrupts import on_interrupt

    clusters: list = []  # the local cluster, once started
    forget = on_interrupt(lambda: _stop_workers(out, clusters, created))  # SIGINT/SIGTERM
    try:
        if todo:
            rep.cluster = _run_on_dask(todo, out, finished, workers=workers,
                                       scheduler=scheduler, client=client, processes=processes,
                                       clusters=clusters)
    finally:
        forget()
        remove_partial(out)
        rep.outcomes = [results.get(i.id) or Outcome(i.id, i.job, "not run") for i in items]
        rep.summary_csv = write_summary(out / "summary.csv", [o.row() for o in rep.outcomes])
    return rep


def _run_on_dask(todo: list[Item], out: Path, finished: Callable[[Outcome], None], *,
                 workers, scheduler, client, processes, clusters: list) -> str:
    """Send ``todo`` to dask; call ``finished`` with each outcome as it comes (``clusters``
    gets the local cluster started for them). Returns where they ran."""
    from distributed import as_completed

    own = None
    if client is None:
        client, cluster, where = _connect(workers, scheduler, processes, len(todo))
        own = (client, cluster)
        clusters.append(cluster)
    else:
        where = f"the client's cluster ({client.scheduler.address})"
    try:
        run_id = uuid.uuid4().hex[:8]
        # the largest inputs first (sent first, and dask's priority: higher runs first; ties
        # in the manifest's order), so that no long item starts last while the other workers
        # sit idle
        size = {item.id: _input_bytes(item) for item in todo}
        futures = {client.submit(run_job, item, str(out), key=f"facemech-{item.id}-{run_id}",
                                 pure=False, priority=size[item.id]): item
                   for item in sorted(todo, key=lambda i: size[i.id], reverse=True)}
        for fut in as_completed(futures, loop=client.loop):
            item = futures[fut]
            try:
                outcome = fut.result()
            except Exception as exc:  # KilledWorker, a lost scheduler: this item failed
                outcome = _died(item, exc)
            finished(outcome)
    finally:
        if own is not None:
            own[0].close()
            if own[1] is not None:
                own[1].close()
    return where
