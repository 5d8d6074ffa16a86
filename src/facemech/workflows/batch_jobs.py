"""The job kinds of a batch manifest: their options (names, types, which are input files) and
the workflow each one calls to fill an item's folder; ``simulate``, ``invert`` and ``speak``
take the input groups of their commands (:mod:`facemech.workflows.inputs`,
:mod:`facemech.jaw.inputs`, :mod:`facemech.inverse.options`), whose keys are the manifest's.
The batch's runner (:mod:`facemech.batch`) is given this table (:data:`JOBS`); it imports no
workflow.

Every option is named as the command's option (``jaw-chin`` or ``jaw_chin``); a job's outputs
are the files its command writes, under fixed names inside the item's folder:

==========  ====================  ===========================================================
kind        required              outputs
==========  ====================  ===========================================================
simulate    ``activity`` or       ``result.nc``
            ``emg``
invert      ``markers``           ``result.nc`` (and ``inversion.png`` with ``figure = true``)
speak       ``text``, or          what ``facemech speak`` writes (``result.nc``, WAV, ...)
            ``audio`` and
            ``textgrid``
stimuli     ``design``            what ``facemech stimuli`` writes
regions     ``files``             ``summary.json`` and the figures
==========  ====================  ===========================================================
"""

from __future__ import annotations

from pathlib import Path

from ..batch.execute import Outcome, run_item
from ..batch.job import Job, job
from ..batch.manifest import Item
from ..batch.manifest import read_manifest as read_manifest_of
from ..errors import FacemechError
from ..inputs import from_manifest
from ..inverse.options import FitOptions, InversionOptions
from ..jaw.inputs import JawMarkers, JawSource
from .inputs import Alive, Controls, MarkerFile, PresetChoice, Recording, Speaking, Stepping

__all__ = ["JOBS", "Job", "read_manifest", "run_job"]

_RENDER = {"view": "str", "size": "str", "background": "str", "aa": "int"}


def _simulate(o: dict, folder: Path):
    from .simulate import simulate_files

    run = simulate_files(folder / "result.nc", from_manifest(Controls, o),
                         from_manifest(JawSource, o), stepping=from_manifest(Stepping, o),
                         **{k: o[k] for k in ("face", "preset") if k in o})
    sim = run.simulation
    return ({"frames": len(sim.time), "sim_wall_s": round(float(sim.wall_seconds), 3),
             "real_time_factor": round(float(sim.real_time_factor), 3)},
            str(run).splitlines())


def _invert(o: dict, folder: Path):
    from . import invert

    figure = folder / "inversion.png" if o.get("figure") else None
    out = folder / "result.nc"
    res = invert.invert(
        from_manifest(MarkerFile, o), out, params=from_manifest(PresetChoice, o),
        jaw=from_manifest(JawMarkers, o), inversion=from_manifest(InversionOptions, o),
        options=from_manifest(FitOptions, o), figure=figure,
        **{k: o[k] for k in ("face",) if k in o})
    s = res.error_summary()
    return ({"frames": len(res.time), "median_error_mm": round(float(s["median_mm"]), 4),
             "max_error_mm": round(float(s["max_mm"]), 4), "markers": len(res.marker_names)},
            invert.report(res, out.name, None if figure is None else figure.name)
            + invert.notes(res))


def _speak(o: dict, folder: Path):
    from .pictures import render_options
    from .speech import speak, speak_report

    res = speak(folder, o.get("text"), speaking=from_manifest(Speaking, o),
                recording=from_manifest(Recording, o), alive=from_manifest(Alive, o),
                render=render_options(**{k: o[k] for k in _RENDER if k in o}),
                **{k: o[k] for k in ("face", "preset") if k in o})
    return ({"frames": len(res.simulation.time), "phones": len(res.alignment.phones),
             "duration_s": round(float(res.alignment.duration), 3)},
            speak_report(res, folder.name))


def _stimuli(o: dict, folder: Path):
    from .speech import stimuli, stimuli_report

    rep = stimuli(o["design"], folder, **{k: o[k] for k in ("video", *_RENDER) if k in o})
    made, failed = stimuli_report(rep)
    if rep.failed:
        first = rep.failed[0].one_line()
        raise FacemechError(f"{len(rep.failed)} of {len(rep.failed) + len(rep.made)} stimuli "
                            f"failed; first: {first}")
    return {"stimuli": len(rep.made) + len(rep.skipped)}, made


def _design_files(o: dict) -> dict:
    """The existing files a design table's rows name (results, sounds, dubbed sounds)."""
    from ..speech.design import read_design

    base = Path(o["design"]).parent
    found = {}
    for row in read_design(o["design"]):
        for col in ("results", "audio", "dub_audio"):
            if col in row and (base / str(row[col])).is_file():
                found[f"design:{row['_row']}:{col}"] = base / str(row[col])
    return found


def _regions(o: dict, folder: Path):
    from .regions import regions, report

    keys = ("k", "eps", "neutral", "train", "test", "method", "units")
    res = regions(o["files"], folder, **{k: o[k] for k in keys if k in o})
    return ({"utterances": len(o["files"]), "rank": int(res.rank), "k": int(res.k),
             "eps_mm": round(float(res.eps_mm), 4)}, report(res, folder.name))


JOBS: dict[str, Job] = {
    "simulate": job((Controls, JawSource, Stepping), {"face": "file_or_name",
                                                      "preset": "file_or_name"},
                    (("activity", "emg"),), _simulate),
    "invert": job((MarkerFile, PresetChoice, JawMarkers, InversionOptions, FitOptions), {
        "face": "file_or_name", "figure": "bool"}, (("markers",),), _invert),
    "speak": job((Recording, Speaking, Alive), {"text": "str", "face": "file_or_name",
                                                "preset": "file_or_name", **_RENDER},
                 (("text", "audio"),), _speak),
    "stimuli": Job({"design": "path", "video": "bool", **_RENDER}, (("design",),), _stimuli,
                   _design_files),
    "regions": Job(
        {"files": "paths", "k": "int", "eps": "str", "neutral": "path_or_first", "train": "str",
         "test": "str", "method": "str", "units": "str"},
        (("files",),), _regions),
}


def read_manifest(path: str | Path) -> list[Item]:
    """Read and check a whole manifest of these job kinds
    (:func:`facemech.batch.manifest.read_manifest` with :data:`JOBS`)."""
    return read_manifest_of(path, JOBS)


def run_job(item: Item, out_dir: str | Path) -> Outcome:
    """Make ``item`` into ``out_dir/<id>/`` with its job kind of :data:`JOBS` (what a dask worker
    runs: :func:`facemech.batch.execute.run_item`)."""
    return run_item(item, out_dir, JOBS)
