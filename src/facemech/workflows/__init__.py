"""Library workflows: what each ``facemech`` command does, as functions usable from Python.

Each module holds the workflows of one concept (faces, EMG, markers, simulation, pictures); a
command of :mod:`facemech.cli` parses its options, calls one of these and prints the result.
Inputs are paths and explicit parameters; outputs are written atomically and returned as data.
Long workflows take a staged ``progress(stage, done, total)`` callback
(:data:`facemech.progress.StagedProgress`).

``facemech.workflows.markers`` and its siblings load on first use (the command line's help
imports no numerical library); the imports below name them for readers, editors and type
checkers.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from . import (
        batch,
        batch_jobs,
        calibrate,
        compare,
        demo,
        emg,
        experiments,
        faces,
        invert,
        landmarks,
        lipread,
        markers,
        outcome,
        photo,
        pictures,
        regions,
        simulate,
        speak,
        speech,
        stimuli,
        subject,
    )

__all__ = ["batch", "batch_jobs", "calibrate", "compare", "demo", "emg", "experiments", "faces",
           "invert", "landmarks", "lipread", "markers", "outcome", "photo", "pictures", "regions",
           "simulate", "speak", "speech", "stimuli", "subject"]


def __getattr__(name: str):
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return importlib.import_module(f"{__name__}.{name}")
