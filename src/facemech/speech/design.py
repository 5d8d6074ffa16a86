"""Design tables: one row per stimulus, read and checked, and a row's manipulations applied to
a face and its sound (:func:`make_stimulus`). Making the files (results, WAV and MP4) and the
manifest: :func:`facemech.workflows.stimuli.run_design`.

A table is CSV (a header row, then one row per stimulus) or TOML (``[[stimulus]]`` tables, and
an optional ``[defaults]`` table whose keys every stimulus starts from). A row names its
``id``, its face item (``results`` and ``audio``, or ``text`` for ``make_item``) and its
manipulations: ``dub_*``, ``time_scale*``, ``amplitude*``, ``freeze_*``, ``av_offset_ms``,
applied in this order: dub, time scale, amplitude, freeze, AV offset. ``blinks``, ``gaze``,
``head_motion`` and ``seed`` (:mod:`facemech.speech.alive`) are off unless a row turns them
on, and are drawn for the finished stimulus's frames from the face's own voice, so that with
the same seed stimuli of the same length blink and look at the same times
(:func:`stimulus_liveliness`). Every column, its values and default: docs/stimuli.md,
"The design table".
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import FacemechError, InputError, missing_input
from .wav import Audio

SOURCE_COLUMNS = ("results", "audio", "text", "face")
MANIPULATION_COLUMNS = (
    "dub_audio", "dub_from", "dub_align", "dub_face_anchor_s", "dub_audio_anchor_s",
    "time_scale", "time_scale_audio", "amplitude", "amplitude_region", "freeze_region",
    "freeze_at", "av_offset_ms")
#: a row's switches of :class:`facemech.speech.alive.Liveliness` (named as ``speak``'s flags)
ALIVE_COLUMNS = ("blinks", "gaze", "head_motion", "seed")
COLUMNS = ("id", *SOURCE_COLUMNS, *MANIPULATION_COLUMNS, *ALIVE_COLUMNS, "notes")
_TRUE, _FALSE = ("yes", "true", "1", "on"), ("no", "false", "0", "off")
_SEED_MAX = 2 ** 32 - 1
_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")

#: make_item(row) -> (results dataset, WAV path or Audio): a face that says the row's text
MakeItem = Callable[[dict], tuple]


class RowError(FacemechError):
    """A design-table row that cannot be made: its number (1-based, data rows) and column."""

    def __init__(self, message: str, *, row: int, column: str | None = None,
                 source: str | None = None):
        self.row = int(row)
        self.column = column
        self.detail = message
        where = f"row {row}" + (f", column '{column}'" if column else "")
        super().__init__(f"{where}: {message}", source=source)


@dataclass(frozen=True)
class Stimulus:
    """One parsed row: where its face and sound come from, and its manipulations (canonical
    values, the defaults filled in)."""

    id: str
    row: int
    source: dict
    settings: dict
    notes: str = ""
    extra: dict = field(default_factory=dict)


# ---- reading ----------------------------------------------------------------------------------
def read_design(path: str | Path) -> list[dict]:
    """The rows of a CSV or TOML design table, as dicts of the non-empty cells (1-based row
    numbers under ``"_row"``). A table that cannot be read at all raises InputError."""
    path = Path(path)
    if not path.is_file():
        raise missing_input(path, what="design table")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        rows = _read_csv(path)
    elif suffix == ".toml":
        rows = _read_toml(path)
    else:
        raise InputError("a design table is .csv or .toml", source=str(path))
    if not rows:
        raise InputError("the design table has no rows", source=str(path))
    return rows


def _read_csv(path: Path) -> list[dict]:
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            if "id" not in header:
                raise InputError("the header has no 'id' column", source=str(path), field="id")
            rows = []
            for k, rec in enumerate(reader, start=1):
                if None in rec:
                    raise InputError(f"row {k} has more cells than the header", source=str(path))
                cells = {h.strip(): (v or "").strip() for h, v in rec.items()}
                if not any(cells.values()):
                    continue
                rows.append({**{h: v for h, v in cells.items() if v != ""}, "_row": k})
    except UnicodeDecodeError:
        raise InputError("not a UTF-8 text file", source=str(path)) from None
    except csv.Error as exc:
        raise InputError(f"not a readable CSV file ({exc})", source=str(path)) from None
    return rows


def _read_toml(path: Path) -> list[dict]:
    from ..io.tables import toml_tables

    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"not a readable TOML file ({exc})", source=str(path)) from None
    items, defaults = toml_tables(text, path, "stimulus")
    return [{**defaults, **item, "_row": k} for k, item in enumerate(items, start=1)]


def _number(row: dict, column: str, default: float, *, low: float | None = None,
            positive: bool = False) -> float:
    if column not in row:
        return default
    try:
        v = float(row[column])
    except (TypeError, ValueError):
        raise RowError(f"{row[column]!r} is not a number", row=row["_row"],
                       column=column) from None
    if not np.isfinite(v) or (positive and not v > 0) or (low is not None and v < low):
        need = "positive" if positive else f">= {low}" if low is not None else "finite"
        raise RowError(f"{row[column]!r} must be {need}", row=row["_row"], column=column)
    return v


def parse_row(row: dict, *, base: Path, ids: set[str], has_hook: bool) -> Stimulus:
    """Check one row and fill in the defaults; raises :class:`RowError` naming the column."""
    from .stimuli import ANCHORS, parse_regions

    k = row["_row"]
    sid = str(row.get("id", "")).strip()
    if not sid:
        raise RowError("every stimulus needs an id", row=k, column="id")
    if not _ID.match(sid):
        raise RowError(f"id {sid!r}: use letters, digits, '-', '_' and '.'", row=k, column="id")
    unknown = [c for c in row if c not in COLUMNS and c != "_row"]
    source: dict = {}
    if "results" in row or "audio" in row:
        for c in ("results", "audio"):
            if c not in row:
                raise RowError("a results file needs its audio, and audio its results file",
                               row=k, column=c)
            p = Path(str(row[c]))
            p = p if p.is_absolute() else base / p
            if not p.is_file():
                raise RowError(f"file not found: {p}", row=k, column=c)
            source[c] = str(p)
        if unknown:
            raise RowError("unknown column", row=k, column=unknown[0])
        if "face" in row:
            source["face"] = str(row["face"])
    elif "text" in row:
        if not has_hook:
            raise RowError("no text-to-speech here: give 'results' and 'audio' files", row=k,
                           column="text")
        source = {c: row[c] for c in row if c not in MANIPULATION_COLUMNS
                  and c not in ALIVE_COLUMNS and c not in ("id", "notes", "_row")}
    else:
        raise RowError("give the face item: 'results' and 'audio', or 'text'", row=k,
                       column="results")

    s: dict = {}
    if "dub_audio" in row and "dub_from" in row:
        raise RowError("give dub_audio or dub_from, not both", row=k, column="dub_from")
    if "dub_audio" in row:
        p = Path(str(row["dub_audio"]))
        p = p if p.is_absolute() else base / p
        if not p.is_file():
            raise RowError(f"file not found: {p}", row=k, column="dub_audio")
        s["dub_audio"] = str(p)
    if "dub_from" in row:
        ref = str(row["dub_from"])
        if ref not in ids:
            raise RowError(f"no row has the id {ref!r}", row=k, column="dub_from")
        if ref == sid:
            raise RowError("a stimulus cannot be dubbed from itself", row=k, column="dub_from")
        s["dub_from"] = ref
    if "dub_audio" in s or "dub_from" in s:
        align = str(row.get("dub_align", "onset")).strip().lower()
        if align not in ANCHORS:
            raise RowError(f"{align!r}: expected {', '.join(ANCHORS)}", row=k, column="dub_align")
        s["dub_align"] = align
        for c in ("dub_face_anchor_s", "dub_audio_anchor_s"):
            if c in row:
                s[c] = _number(row, c, 0.0, low=0.0)
    s["time_scale"] = _number(row, "time_scale", 1.0, positive=True)
    method = str(row.get("time_scale_audio", "stretch")).strip().lower()
    if method not in ("stretch", "resample", "none"):
        raise RowError(f"{method!r}: expected stretch, resample or none", row=k,
                       column="time_scale_audio")
    s["time_scale_audio"] = method
    s["amplitude"] = _number(row, "amplitude", 1.0, low=0.0)
    s["amplitude_region"] = _regions(row, "amplitude_region", "face", parse_regions)
    if "freeze_region" in row:
        s["freeze_region"] = _regions(row, "freeze_region", None, parse_regions)
        s["freeze_at"] = _freeze_at(row)
    elif "freeze_at" in row:
        raise RowError("freeze_at without a freeze_region holds nothing still", row=k,
                       column="freeze_at")
    s["av_offset_ms"] = _number(row, "av_offset_ms", 0.0)
    for c in ALIVE_COLUMNS[:3]:
        s[c] = _switch(row, c, False)
    s["seed"] = _seed(row)
    return Stimulus(sid, k, source, s, str(row.get("notes", "")),
                    {c: row[c] for c in unknown})


def _regions(row, column, default, parse):
    if column not in row:
        return default
    try:
        return ",".join(parse(str(row[column]), field=column))
    except InputError as exc:
        raise RowError(exc.message, row=row["_row"], column=column) from None


def _freeze_at(row) -> str | int | float:
    v = str(row.get("freeze_at", "rest")).strip().lower()
    if v == "rest":
        return "rest"
    try:
        return float(v[:-1]) if v.endswith("s") else int(v)
    except ValueError:
        raise RowError(f"{v!r}: expected rest, a frame number or a time like 0.25s",
                       row=row["_row"], column="freeze_at") from None


def _switch(row, column: str, default: bool) -> bool:
    """A yes/no cell (TOML: also a boolean, or the integers 0 and 1)."""
    if column not in row:
        return default
    v = row[column]
    if isinstance(v, bool):
        return v
    text = str(v).strip().lower()
    if text not in _TRUE + _FALSE:
        raise RowError(f"{v!r}: expected yes or no (true/false, 1/0, on/off)", row=row["_row"],
                       column=column)
    return text in _TRUE


def _seed(row) -> int:
    v = row.get("seed", 0)
    text = str(v).strip()
    if isinstance(v, (bool, float)) or not re.fullmatch(r"\+?\d+", text) or \
            int(text) > _SEED_MAX:
        raise RowError(f"{v!r}: expected an integer from 0 to {_SEED_MAX}", row=row["_row"],
                       column="seed")
    return int(text)


def liveliness_of(settings: dict):
    """A row's :class:`facemech.speech.alive.Liveliness` (its ``blinks``, ``gaze``,
    ``head_motion`` and ``seed``; off where the settings do not say)."""
    from .alive import Liveliness

    return Liveliness(blinks=bool(settings.get("blinks", False)),
                      gaze=bool(settings.get("gaze", False)),
                      head=bool(settings.get("head_motion", False)),
                      seed=int(settings.get("seed", 0)))


def stimulus_liveliness(ds, voice: Audio | None, settings: dict):
    """The blinks, gaze shifts and head motion of a finished stimulus
    (:func:`facemech.speech.alive.liveliness` at its frames, seeded by the row): an
    :class:`facemech.speech.alive.Alive`, all zeros where the row leaves them off.

    ``voice`` drives the head: the face's own sound on the stimulus's time line (the third
    value of :func:`make_stimulus_and_voice`); None: silence (no head motion).
    """
    from .alive import liveliness

    alive = liveliness_of(settings)
    if voice is None:
        samples, rate = np.zeros(1), 16000
    else:
        samples, rate = voice.mono(), voice.rate
    return liveliness(np.asarray(ds["time"].values, float), samples, rate, alive)


def make_stimulus(ds, audio: Audio, settings: dict, *, dub_audio: Audio | None = None):
    """Apply a row's manipulations (in the order dub, time scale, amplitude, freeze, AV offset)
    to a face and its sound; returns (dataset, Audio)."""
    return make_stimulus_and_voice(ds, audio, settings, dub_audio=dub_audio)[:2]


def make_stimulus_and_voice(ds, audio: Audio, settings: dict, *,
                            dub_audio: Audio | None = None):
    """:func:`make_stimulus`, and the face's own voice on the stimulus's time line (what drives
    the head, :func:`stimulus_liveliness`): ``audio`` time-scaled as the face is (stretched
    where the row's sound is not), neither dubbed nor offset; None unless the row turns
    ``head_motion`` on. Returns (dataset, Audio, Audio or None)."""
    from . import stimuli as st

    voice = audio if settings.get("head_motion") else None
    if dub_audio is not None:
        ds, audio = st.dub(ds, audio, dub_audio, align=settings.get("dub_align", "onset"),
                           face_anchor=settings.get("dub_face_anchor_s"),
                           audio_anchor=settings.get("dub_audio_anchor_s"))
    if settings.get("time_scale", 1.0) != 1.0:
        method = settings.get("time_scale_audio", "stretch")
        ds, audio = st.time_scale_with_audio(ds, audio, settings["time_scale"],
                                             audio_method=method)
        if voice is not None:
            voice = audio if dub_audio is None and method != "none" else \
                st.time_stretch(voice, settings["time_scale"],
                                method="stretch" if method == "none" else method)
    if settings.get("amplitude", 1.0) != 1.0:
        ds = st.scale_amplitude(ds, settings["amplitude"], settings.get("amplitude_region",
                                                                        "face"))
    if settings.get("freeze_region"):
        at = settings.get("freeze_at", "rest")
        times = np.asarray(ds["time"].values, float)
        half = 0.5 / float(ds.attrs.get("frame_rate_hz", 60.0))
        if isinstance(at, float) and len(times) and not \
                times[0] - half <= at <= times[-1] + half:
            raise InputError(f"{at:g} s is outside the stimulus ({times[0]:g} to "
                             f"{times[-1]:.3f} s)", field="freeze_at")
        ds = st.freeze(ds, settings["freeze_region"], at)
    if settings.get("av_offset_ms", 0.0) != 0.0:
        ds, audio = st.offset_audio(ds, audio, settings["av_offset_ms"])
    return ds, audio, voice


def check_design(table_path: str | Path, make_item: MakeItem | None = None) -> list[Stimulus]:
    """Read and check a whole design table (:func:`read_design`, :func:`parse_row`,
    :func:`refuse_table`) without making anything: its stimuli, in row order.

    Raises
    ------
    InputError
        One line naming the table, the row, the column and the value of the first problem.
    """
    table_path = Path(table_path)
    rows = read_design(table_path)
    ids = {str(r.get("id", "")).strip() for r in rows}
    seen: set[str] = set()
    parsed: list[Stimulus | RowError] = []
    for row in rows:
        try:
            spec = parse_row(row, base=table_path.parent, ids=ids,
                             has_hook=make_item is not None)
            if spec.id in seen:
                raise RowError(f"the id {spec.id!r} is used by an earlier row", row=spec.row,
                               column="id")
            seen.add(spec.id)
            parsed.append(spec)
        except RowError as exc:
            parsed.append(exc)
    refuse_table(parsed, table_path, make_item)
    return parsed


def refuse_table(parsed: list, table: Path, make_item: MakeItem | None = None) -> None:
    """Refuse a design table that cannot run, before its first row is made: the first row that
    does not parse (unknown column, a value out of range, a repeated id, a missing file), or
    whose sound cannot be read or would be moved out of the stimulus by its offset.

    ``parsed`` holds each row's :class:`Stimulus` or :class:`RowError`. A ``make_item`` hook
    may carry ``check(row) -> None`` (raising :class:`InputError`) to check its own columns.

    Raises
    ------
    InputError
        One line naming the table, the row, the column and the value.
    """
    from .wav import check_audio

    def refuse(exc: RowError):
        err = with_source(exc, table)
        raise InputError(err.message, source=err.source) from None

    for spec in parsed:
        if isinstance(spec, RowError):
            refuse(spec)
    check = getattr(make_item, "check", None)
    lengths: dict[str, float] = {}
    for spec in parsed:
        if "text" in spec.source and check is not None:
            try:
                check(dict(spec.source))
            except InputError as exc:
                refuse(RowError(exc.message, row=spec.row, column=exc.field))
        for column, path in (("audio", spec.source.get("audio")),
                             ("dub_audio", spec.settings.get("dub_audio"))):
            if path is not None and path not in lengths:
                try:
                    lengths[path] = check_audio(path, field=column)
                except InputError as exc:
                    refuse(RowError(f"{path}: {exc.message}", row=spec.row, column=column))
        sound = spec.settings.get("dub_audio", spec.source.get("audio"))
        offset = abs(spec.settings.get("av_offset_ms", 0.0)) / 1e3
        if sound is not None and "dub_from" not in spec.settings:
            length = lengths[sound] * spec.settings.get("time_scale", 1.0)
            if offset >= length:
                refuse(RowError(f"an offset of {spec.settings['av_offset_ms']:g} ms moves the "
                                f"whole sound ({1e3 * length:.0f} ms) out of the stimulus",
                                row=spec.row, column="av_offset_ms"))


def with_source(exc: RowError, table: Path) -> RowError:
    """``exc`` naming the design ``table`` as its source where it names none."""
    if exc.source is None:
        return RowError(exc.detail, row=exc.row, column=exc.column, source=str(table))
    return exc


__all__ = ["ALIVE_COLUMNS", "COLUMNS", "MANIPULATION_COLUMNS", "SOURCE_COLUMNS", "MakeItem",
           "RowError", "Stimulus", "check_design", "liveliness_of", "make_stimulus",
           "make_stimulus_and_voice", "parse_row", "read_design", "refuse_table",
           "stimulus_liveliness", "with_source"]
