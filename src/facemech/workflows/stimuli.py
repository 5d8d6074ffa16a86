"""``facemech stimuli``'s wiring: every stimulus of a design table made into files.

:func:`run_design` reads a design table (checked whole first by
:func:`facemech.speech.design.check_design`), loads each row's face and sound (a results file
and a WAV, or the ``make_item`` hook's), applies the row's manipulations
(:func:`facemech.speech.design.make_stimulus`), draws the blinks, gaze shifts and head motion
the row turns on (:func:`facemech.speech.design.stimulus_liveliness`; off by default), writes
``ID.nc``, ``ID.wav`` and ``ID.mp4`` (the movie showing them) and rewrites the manifest
(``manifest.json`` and ``manifest.csv``, ``alive`` with their times) after each row. The
table's columns are described in :mod:`facemech.speech.design`.
"""

from __future__ import annotations

import csv
import hashlib
import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import NamedTuple

from ..errors import FacemechError, InputError
from ..speech.design import (
    ALIVE_COLUMNS,
    MANIPULATION_COLUMNS,
    MakeItem,
    RowError,
    Stimulus,
    check_design,
    make_stimulus_and_voice,
    stimulus_liveliness,
    with_source,
)
from ..speech.wav import Audio
from ..speech.wav import read_audio as read_wav
from ..speech.wav import write_audio as write_wav

__all__ = ["DesignReport", "run_design"]


@dataclass
class DesignReport:
    """What :func:`run_design` did: ids made and skipped, the rows that failed (RowError), and
    the manifest's paths."""

    made: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    failed: list[RowError] = field(default_factory=list)
    manifest_json: Path | None = None
    manifest_csv: Path | None = None

    def summary(self) -> str:
        where = "no manifest written" if self.manifest_json is None else \
            f"manifest -> {self.manifest_json}"
        return (f"{len(self.made)} made, {len(self.skipped)} unchanged, {len(self.failed)} "
                f"failed; {where}")


def _hash_json(obj) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _source_hash(source: dict, make_item) -> dict:
    from ..io.results import file_hash

    if "results" in source:
        return {"results": file_hash(source["results"]), "audio": file_hash(source["audio"])}
    return {"item": _hash_json({**source, "hook": getattr(make_item, "version", "")})}


def _load_source(source: dict, make_item, row: int):
    from ..io.results import read_results

    if "results" in source:
        try:
            ds = read_results(source["results"])
        except InputError as exc:
            raise RowError(exc.message, row=row, column="results") from None
        face = source.get("face")
        if face is not None and str(ds.attrs.get("face", "")) != face:
            raise RowError(f"the results were made with the face {ds.attrs.get('face')!r}, "
                           f"not {face!r}", row=row, column="face")
        try:
            audio = read_wav(source["audio"])
        except InputError as exc:
            raise RowError(exc.message, row=row, column="audio") from None
        return ds, audio
    try:
        ds, wav = make_item(dict(source))
    except FacemechError as exc:
        raise RowError(exc.one_line(), row=row, column="text") from None
    return ds, (wav if isinstance(wav, Audio) else read_wav(wav))


def run_design(table_path: str | Path, out_dir: str | Path, make_item: MakeItem | None = None,
               *, options=None, video: bool = True,
               progress: Callable[[str, int, int], None] | None = None) -> DesignReport:
    """Make every stimulus of a design table in ``out_dir``, with a manifest.

    Each stimulus writes ``ID.nc`` (results), ``ID.wav`` and, with ``video``, ``ID.mp4``
    (:func:`facemech.viz.video.render_results`, the sound muxed in, with the blinks, gaze shifts
    and head motion the row's ``blinks``, ``gaze``, ``head_motion`` and ``seed`` turn on: off by
    default; the manifest's ``alive`` records them and their times), each atomically; then the
    manifest (``manifest.json`` and ``manifest.csv``) is rewritten, so an interrupted run keeps
    what it made. The whole table is checked first (:func:`~facemech.speech.design.check_design`:
    its cells, files, sounds, results and frames); nothing is written when it is refused. A row
    that still cannot be made is reported (a :class:`RowError` in the report, and in the
    manifest once a row has been made) and the others are still made; a run that makes no row
    writes no manifest. A stimulus whose key (a hash of its settings,
    its inputs' hashes, the render settings and facemech's version) matches the manifest's, and
    whose files are all there, is skipped.

    Parameters
    ----------
    table_path : CSV or TOML design (see the module)
    out_dir : folder for the stimuli and the manifest
    make_item : hook for rows without ``results``: ``make_item(row) -> (dataset, WAV path or
        Audio)``; may carry a ``version`` attribute that enters the key
    options : :class:`facemech.viz.render.RenderOptions` of the movies
    video : render the movies
    progress : callable(stage, done, total)

    Returns
    -------
    DesignReport
    """
    table_path, out_dir = Path(table_path), Path(out_dir)
    parsed = check_design(table_path, make_item)  # the whole table, before anything is written
    specs = {spec.id: spec for spec in parsed}  # every row parsed: a RowError refused it
    render = _render_settings(options, video)
    old = _old_entries(out_dir / "manifest.json")
    cache: dict[str, tuple] = {}
    _rehearse(parsed, specs, make_item, table_path, render, video, old, out_dir, cache)
    report = DesignReport()
    entries: list[dict] = []
    total = len(parsed)
    for done, spec in enumerate(parsed):
        if progress is not None:
            progress("stimuli", done, total)
        try:
            key, inputs, outputs = _row_key(spec, specs, make_item, render, video)
            if _unchanged(old.get(spec.id), key, outputs, out_dir):
                entries.append({**old[spec.id], "row": spec.row, "status": "unchanged"})
                report.skipped.append(spec.id)
                _write_manifest(out_dir, table_path, render, entries, report)
                continue
            entries.append(_make_stimulus(spec, key, inputs, outputs, _DesignRun(
                specs, make_item, cache, out_dir, options, video, progress)))
            report.made.append(spec.id)
        except RowError as exc:
            report.failed.append(with_source(exc, table_path))
            entries.append(_failed_entry(exc, spec))
        except FacemechError as exc:
            err = with_source(RowError(exc.one_line(), row=spec.row), table_path)
            report.failed.append(err)
            entries.append(_failed_entry(err, spec))
        if report.made or report.skipped:  # a run that makes nothing writes nothing
            _write_manifest(out_dir, table_path, render, entries, report)
    if progress is not None:
        progress("stimuli", total, total)
    if report.made or report.skipped:
        _write_manifest(out_dir, table_path, render, entries, report)
    return report


class _DesignRun(NamedTuple):
    """What every row of a design run shares: the parsed rows, the hook, the synthesis cache,
    the output folder, the render options, whether movies are made and the progress."""

    specs: dict
    make_item: object
    cache: dict
    out_dir: Path
    options: object
    video: bool
    progress: object


def _make_stimulus(spec, key, inputs, outputs, run: _DesignRun) -> dict:
    """One row's stimulus written into ``run.out_dir`` (its results, sound and, with
    ``run.video``, movie, each atomically); its manifest entry."""
    from ..analysis.describe import describe
    from ..io.results import write_dataset

    out_dir, options, progress = run.out_dir, run.options, run.progress

    ds, audio, voice = _stimulus(spec, run.specs, run.make_item, run.cache)
    lively = _row_call(spec, stimulus_liveliness, ds, voice, spec.settings)
    ds.attrs["stimulus_id"] = spec.id
    ds.attrs["stimulus_key"] = key
    out_dir.mkdir(parents=True, exist_ok=True)
    write_dataset(out_dir / outputs["results"], ds)
    write_wav(out_dir / outputs["audio"], audio)
    if run.video:
        from ..viz.video import FrameMotion, render_results

        render_results(ds, out_dir / outputs["movie"], options=options,
                       audio=out_dir / outputs["audio"], source=spec.id,
                       progress=None if progress is None else (
                           lambda d, n, s=spec.id: progress(f"render {s}", d, n)),
                       motion=_motion(lively, FrameMotion))
    desc = describe(ds, source=spec.id)
    return {"id": spec.id, "row": spec.row, "status": "made", "key": key,
            "settings": spec.settings, "source": spec.source, "inputs": inputs,
            "extra": spec.extra, "notes": spec.notes, "outputs": outputs,
            "description": desc.to_dict(), "flat": desc.flat(), "alive": lively.record()}


def _row_key(spec: Stimulus, specs: dict, make_item, render: dict, video: bool):
    """A row's key (its settings, its inputs' hashes, the render settings and facemech's
    version, hashed), its inputs' hashes and its outputs' names."""
    from .._version import __version__
    from ..io.results import file_hash

    inputs = {"source": _source_hash(spec.source, make_item)}
    if "dub_audio" in spec.settings:
        inputs["dub_audio"] = file_hash(spec.settings["dub_audio"])
    if "dub_from" in spec.settings:
        inputs["dub_from"] = _source_hash(specs[spec.settings["dub_from"]].source, make_item)
    key = _hash_json({"settings": spec.settings, "inputs": inputs, "render": render,
                      "extra": spec.extra, "version": __version__})
    outputs = {"results": f"{spec.id}.nc", "audio": f"{spec.id}.wav"}
    if video:
        outputs["movie"] = f"{spec.id}.mp4"
    return key, inputs, outputs


def _unchanged(prev: dict | None, key: str, outputs: dict, out_dir: Path) -> bool:
    return (prev is not None and prev.get("key") == key
            and prev.get("status") in ("made", "unchanged")
            and all((out_dir / f).is_file() for f in outputs.values()))


def _row_call(spec: Stimulus, fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except InputError as exc:
        raise RowError(exc.message, row=spec.row, column=exc.field) from None


def _stimulus(spec: Stimulus, specs: dict, make_item, cache: dict):
    """A row's face and sound loaded (``cache``: id -> (dataset, Audio)) and manipulated:
    :func:`~facemech.speech.design.make_stimulus_and_voice`'s (dataset, Audio, voice)."""
    ds, audio = _item(spec.id, spec.source, make_item, spec.row, cache)
    dub_audio = None
    if "dub_audio" in spec.settings:
        try:
            dub_audio = read_wav(spec.settings["dub_audio"])
        except InputError as exc:
            raise RowError(exc.message, row=spec.row, column="dub_audio") from None
    elif "dub_from" in spec.settings:
        ref = specs[spec.settings["dub_from"]]
        dub_audio = _item(ref.id, ref.source, make_item, spec.row, cache)[1]
    return _row_call(spec, make_stimulus_and_voice, ds, audio, spec.settings,
                     dub_audio=dub_audio)


def _rehearse(parsed, specs, make_item, table, render, video, old, out_dir, cache) -> None:
    """Make, in memory, every row whose face and sounds are files (no ``make_item``) and that
    is not unchanged, before anything is written: a row that cannot be made refuses the whole
    table (InputError naming the table, the row and the column)."""
    for spec in parsed:
        sources = [spec.source] + ([specs[spec.settings["dub_from"]].source]
                                   if "dub_from" in spec.settings else [])
        if any("results" not in src for src in sources):
            continue
        key, _, outputs = _row_key(spec, specs, make_item, render, video)
        if _unchanged(old.get(spec.id), key, outputs, out_dir):
            continue
        try:
            _stimulus(spec, specs, make_item, cache)
        except RowError as exc:
            err = with_source(exc, table)
            raise InputError(err.message, source=err.source) from None


def _item(sid, source, make_item, row, cache):
    if sid not in cache:
        cache[sid] = _load_source(source, make_item, row)
    return cache[sid]


def _motion(lively, frame_motion):
    """The movie's blinks, gaze and head (a ``FrameMotion``), or None where the row turns
    none of them on (the movie as without them)."""
    s = lively.settings
    if not (s.blinks or s.gaze or s.head):
        return None
    return frame_motion(lively.blink, lively.gaze, lively.head)


def _onsets(entry: dict, part: str) -> str:
    """The manifest entry's blink or gaze-shift onsets, s, separated by ';'."""
    return ";".join(f"{e['onset_s']:.4f}" for e in entry.get("alive", {}).get(part, []))


def _failed_entry(exc: RowError, spec: Stimulus) -> dict:
    return {"id": spec.id, "row": exc.row, "status": "failed",
            "error": {"column": exc.column, "message": exc.one_line()}}


def _render_settings(options, video: bool) -> dict:
    if not video:
        return {"video": False}
    if options is None:
        from ..viz.render import RenderOptions

        options = RenderOptions()
    d = dict(asdict(options) if hasattr(options, "__dataclass_fields__") else vars(options))
    if "size" in d:  # as typed: WIDTHxHEIGHT (RenderOptions keeps (height, width))
        h, w = d["size"]
        d["size"] = f"{w}x{h}"
    return {"video": True, **{k: (list(v) if isinstance(v, tuple) else v)
                              for k, v in d.items()}}


def _old_entries(path: Path) -> dict[str, dict]:
    if not path.is_file():
        return {}
    try:
        doc = json.loads(path.read_text())
        return {e["id"]: e for e in doc.get("stimuli", []) if "id" in e}
    except (ValueError, KeyError, TypeError, AttributeError):
        return {}  # an unreadable manifest: everything is made again


def _write_manifest(out_dir: Path, table: Path, render: dict, entries: list[dict],
                    report: DesignReport) -> None:
    from .._version import __version__
    from ..atomic import atomic_path
    from ..io.results import file_hash

    out_dir.mkdir(parents=True, exist_ok=True)
    doc = {"facemech_version": __version__, "table": str(table),
           "table_hash": file_hash(table), "render": render,
           "order": ["dub", "time_scale", "amplitude", "freeze", "av_offset"],
           "stimuli": entries}
    report.manifest_json = out_dir / "manifest.json"
    report.manifest_csv = out_dir / "manifest.csv"
    with atomic_path(report.manifest_json) as tmp:
        tmp.write_text(json.dumps(doc, indent=1, default=str))
    cols = ["id", "row", "status", "key", *MANIPULATION_COLUMNS, *ALIVE_COLUMNS,
            "blink_onsets_s", "gaze_shift_onsets_s", "source_results", "source_audio",
            "input_hashes"]
    flat_cols: list[str] = []
    for e in entries:
        for c in e.get("flat", {}):
            if c not in flat_cols:
                flat_cols.append(c)
    cols += [*flat_cols, "notes", "error"]
    with atomic_path(report.manifest_csv) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for e in entries:
            rec = {"id": e["id"], "row": e["row"], "status": e["status"],
                   "key": e.get("key", ""), "notes": e.get("notes", ""),
                   "error": e.get("error", {}).get("message", "")}
            rec.update({k: v for k, v in e.get("settings", {}).items()})
            if "alive" in e:
                rec["blink_onsets_s"] = _onsets(e, "blinks")
                rec["gaze_shift_onsets_s"] = _onsets(e, "gaze_shifts")
            src = e.get("source", {})
            rec["source_results"] = src.get("results", src.get("text", ""))
            rec["source_audio"] = src.get("audio", "")
            if "inputs" in e:
                rec["input_hashes"] = json.dumps(e["inputs"], sort_keys=True)
            rec.update({k: ("" if v is None else v) for k, v in e.get("flat", {}).items()})
            w.writerow(rec)
