"""A job kind of a batch manifest: its options (names, value kinds) and the function that runs it.

A job's options are made from the input groups it takes (:func:`job`: the dataclasses of
:mod:`facemech.inputs`, whose manifest keys and kinds they declare) and a few of its own. The
kinds themselves, which call the workflows, are given to the runner by the caller
(:data:`facemech.workflows.batch_jobs.JOBS`): batch/ imports no workflow.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..inputs import manifest_kinds

__all__ = ["Job", "OPTION_KINDS", "check_kind", "job"]

#: value kinds: a file read (hashed), several files, a file or a built-in name (a value with a
#: suffix is a file), a marker file or "first", text, numbers and yes/no
OPTION_KINDS = ("path", "paths", "file_or_name", "path_or_first", "str", "int", "float", "bool")


@dataclass(frozen=True)
class Job:
    """One job kind.

    Attributes
    ----------
    options : option name -> value kind (:data:`OPTION_KINDS`)
    required : groups of options; each group needs at least one of its options given
    run : run(options, folder) -> (numbers, report lines): fills ``folder`` (it exists and is
        empty) and returns the item's key numbers and the lines its command would print
    more_inputs : more_inputs(options) -> {name: path}: files the job reads that its options
        name only indirectly (a design table's sounds and results), hashed with the others
    groups : the input groups (dataclasses) among its options: each is made from a row when
        the manifest is read, so that it checks itself before anything runs
    """

    options: dict
    required: tuple
    run: Callable[[dict, Path], tuple[dict, list[str]]]
    more_inputs: Callable[[dict], dict] | None = None
    groups: tuple = ()


def job(groups: tuple[type, ...], own: dict, required: tuple, run, more_inputs=None) -> Job:
    """A :class:`Job` whose options are its input groups' (by manifest key) and its ``own``
    (option name -> value kind)."""
    return Job({**manifest_kinds(*groups), **own}, required, run, more_inputs, tuple(groups))


def check_kind(job: str, jobs: dict[str, Job], *, source: str, row: int) -> Job:
    """The :class:`Job` of kind ``job`` in ``jobs``; an InputError naming ``source`` and ``row``
    if none."""
    if job not in jobs:
        raise InputError(f"row {row}: unknown job kind {job!r} (one of {', '.join(jobs)})",
                         source=source, field="job")
    return jobs[job]
