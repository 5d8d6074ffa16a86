"""Alignments in files: Praat TextGrids (word and phone tiers) and a CSV of intervals.

TextGrids are read and written with ``praatio`` (the ``speech`` extra); both of Praat's text
forms (long and short) are read, in UTF-8 or UTF-16 (with or without a byte-order mark).
The tiers are chosen by name; by default the ones the Montreal Forced Aligner writes: ``words``
and ``phones`` (also ``word``/``phone``/``phonemes``, and ``SPEAKER - words`` as MFA names them
for several speakers). Intervals labelled ``""``, ``sil``, ``sp``, ``<eps>``, ``pau`` or ``_``
(any case) are pauses: they are left out, so pauses are gaps between segments.

The CSV has the columns ``tier,label,start_s,end_s`` (tier ``words`` or ``phones``), preceded by
comment lines ``# notation: ...``, ``# duration_s: ...`` that say how to read it back.
Both writers take further tiers (``tiers``): :func:`facemech.speech.phone_labels.relabel`'s
IPA or ARPABET phones keep eSpeak NG's own codes in a tier :data:`ESPEAK_TIER`, which the
readers leave aside (a TextGrid's can be read with ``phone_tier="espeak"``).
"""

from __future__ import annotations

import codecs
import csv
import io
import os
import re
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from .alignment import NOTATIONS, Alignment, Segment

__all__ = ["read_textgrid", "write_textgrid", "read_alignment_csv", "write_alignment_csv",
           "detect_notation", "is_pause", "ESPEAK_TIER", "PAUSE_LABELS"]

PAUSE_LABELS = frozenset({"", "sil", "sp", "<eps>", "pau", "_", "<sil>"})
"""Labels (compared in lower case, stripped) that mark a pause, not a segment."""

WORD_TIER_NAMES = ("words", "word")
PHONE_TIER_NAMES = ("phones", "phone", "phonemes", "phoneme", "segments")

#: the tier of eSpeak NG's own codes beside IPA or ARPABET phones
ESPEAK_TIER = "espeak"

#: CMUdict's 39 phones and TIMIT's additions (DX, Q, WH, IX, AX, AXR, EL, EM, EN, ...)
ARPABET = frozenset("AA AE AH AO AW AY B CH D DH EH ER EY F G HH IH IY JH K L M N NG OW OY P "
                    "R S SH T TH UH UW V W Y Z ZH DX Q WH IX UX AX AXR EL EM EN ENG NX "
                    "HV".split())
_ARPABET_LABEL = re.compile(r"^([A-Z]{1,3})([012])?$")
_ESPEAK_MARKS = re.compile(r"[@:',#0-9]|[a-z][A-Z]|[A-Z][a-z]|^[A-Z]")


def is_pause(label: str, notation: str | None = None) -> bool:
    """True for a pause label (see :data:`PAUSE_LABELS`; eSpeak's ``_:``, ``_!`` too)."""
    text = label.strip().lower()
    return text in PAUSE_LABELS or (notation == "espeak" and text.startswith("_"))


def detect_notation(labels, *, source: str | None = None) -> str:
    """Guess the notation of phone labels: ``"arpabet"``, ``"ipa"`` or ``"espeak"``.

    ARPABET when every label is an ARPABET phone in capitals, with or without a stress digit
    (``AA1``, ``P``); IPA when any label has a character outside ASCII (``ə``, ``ʃ``, ``ː``);
    eSpeak when labels have eSpeak's marks (``@ : ' , #``, digits, mixed case: ``'0``, ``oU``);
    otherwise (plain lower-case letters such as ``p a t``, valid in IPA) IPA.
    """
    labels = [s.strip() for s in labels if not is_pause(s, "espeak")]
    if not labels:
        raise InputError("no phone labels to tell the notation from", source=source,
                         field="notation")
    if all((m := _ARPABET_LABEL.match(s)) and m.group(1) in ARPABET for s in labels):
        return "arpabet"
    if any(not s.isascii() for s in labels):
        return "ipa"
    if any(_ESPEAK_MARKS.search(s) for s in labels):
        return "espeak"
    return "ipa"


def _check_notation(notation: str | None, source) -> None:
    if notation is not None and notation not in NOTATIONS:
        raise InputError(f"unknown phone notation {notation!r} (expected "
                         f"{', '.join(NOTATIONS)})", source=source, field="notation")


# --- TextGrid ---------------------------------------------------------------------------------

def _decode(raw: bytes, source: str) -> str:
    """TextGrid bytes to text: UTF-8 or UTF-16 (by byte-order mark, or by NUL bytes)."""
    if raw.startswith(codecs.BOM_UTF8):
        enc = "utf-8-sig"
    elif raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        enc = "utf-16"
    elif raw[:200].count(b"\0") > 10:
        enc = "utf-16-le" if raw[1:2] == b"\0" else "utf-16-be"
    else:
        enc = "utf-8"
    try:
        return raw.decode(enc)
    except UnicodeDecodeError as exc:
        raise InputError(f"not {enc.upper().replace('-SIG', '')} text (byte {exc.start})",
                         source=source) from None


def _find_tier(names: list[str], wanted: str | None, defaults: tuple[str, ...],
               kind: str, source: str) -> str | None:
    if wanted is not None:
        if wanted in names:
            return wanted
        raise InputError(f"no tier named {wanted!r} (tiers: {', '.join(map(repr, names))})",
                         source=source, field=f"{kind}_tier")
    for name in names:
        low = name.strip().lower()
        if low in defaults or any(low.endswith(f" - {d}") for d in defaults):
            return name
    return None


def _chosen_tiers(tiers: dict, phone_tier, word_tier, src: str) -> tuple[str, str | None]:
    """The phone tier's and the word tier's names (``word_tier`` False: no word tier), each an
    interval tier; InputError naming ``phone_tier`` or ``word_tier``."""
    names = list(tiers)
    pname = _find_tier(names, phone_tier, PHONE_TIER_NAMES, "phone", src)
    if pname is None:
        raise InputError("no phone tier (looked for one named "
                         f"{'/'.join(PHONE_TIER_NAMES)}; tiers: {', '.join(map(repr, names))})",
                         source=src, field="phone_tier")
    wname = None
    if word_tier is not False:
        wname = _find_tier(names, word_tier, WORD_TIER_NAMES, "word", src)
        if wname is None:
            raise InputError("no word tier (looked for one named "
                             f"{'/'.join(WORD_TIER_NAMES)}; tiers: "
                             f"{', '.join(map(repr, names))}; or read phones only)",
                             source=src, field="word_tier")
    for kind, name in (("phone", pname), ("word", wname)):
        if name is not None and tiers[name]["class"] != "IntervalTier":
            raise InputError(f"tier {name!r} is a point tier, not an interval tier",
                             source=src, field=f"{kind}_tier")
    return pname, wname


def _tier_segments(entries, name: str, kind: str, note: str | None,
                   src: str) -> tuple[Segment, ...]:
    """An interval tier's labelled intervals in time order, pauses (in ``note``'s notation)
    left out; InputError naming the tier for an interval that is not (start, end, label) with
    finite, ordered times."""
    out = []
    for entry in entries:
        try:
            start, end, label = float(entry[0]), float(entry[1]), str(entry[2])
        except (ValueError, TypeError, IndexError):
            raise InputError(f"an interval {tuple(entry)!r} is not (start, end, label)",
                             source=src, field=f"{kind}_tier {name}") from None
        if not (np.isfinite(start) and np.isfinite(end)):
            raise InputError(f"interval {label!r} has a time that is not a number",
                             source=src, field=f"{kind}_tier {name}")
        if end < start:
            raise InputError(f"interval {label!r} ends ({end:g} s) before it starts "
                             f"({start:g} s)", source=src, field=f"{kind}_tier {name}")
        if not is_pause(label, note):
            out.append(Segment(label.strip(), start, end))
    return tuple(sorted(out, key=lambda s: s.start))


def read_textgrid(path: str | os.PathLike, *, word_tier: str | None = None,
                  phone_tier: str | None = None, notation: str | None = None,
                  words: bool = True) -> Alignment:
    """Read a word and a phone tier of a Praat TextGrid as an :class:`Alignment`.

    Parameters
    ----------
    path : the TextGrid (long or short text form; UTF-8 or UTF-16)
    word_tier, phone_tier : tier names; None picks the tier named ``words`` / ``phones`` (or
        ``word``, ``phone``, ``phonemes``, ``SPEAKER - words`` ...), as the Montreal Forced
        Aligner writes them
    notation : ``"arpabet"``, ``"ipa"`` or ``"espeak"``; None detects it from the phone labels
        (see :func:`detect_notation`)
    words : False reads the phone tier only (for TextGrids without words)

    Returns
    -------
    Alignment
        Times (s) as in the file; pauses left out; ``duration`` the TextGrid's end time;
        ``source`` the path; ``meta`` the tier names.
    """
    try:
        from praatio.utilities import textgrid_io
    except ImportError:
        raise InputError("reading TextGrids needs praatio (pip install 'facemech[speech]')",
                         source=str(path)) from None
    path = Path(path)
    src = str(path)
    _check_notation(notation, src)
    if not path.is_file():
        raise InputError("file not found", source=src)
    text = _decode(path.read_bytes(), src)
    if "TextGrid" not in text[:400]:
        raise InputError("not a Praat TextGrid (no 'File type = \"ooTextFile\"' / 'TextGrid' "
                         "header)", source=src)
    try:
        tg = textgrid_io.parseTextgridStr(text, includeEmptyIntervals=True)
    except Exception as exc:  # praatio raises many kinds on malformed text
        raise InputError(f"not a readable TextGrid ({type(exc).__name__}: "
                         f"{str(exc).splitlines()[0] if str(exc) else ''})", source=src) from None
    tiers = {t["name"]: t for t in tg["tiers"]}
    pname, wname = _chosen_tiers(tiers, phone_tier, word_tier if words else False, src)

    def segments(name: str, kind: str, note: str | None) -> tuple[Segment, ...]:
        return _tier_segments(tiers[name]["entries"], name, kind, note, src)

    raw_phones = segments(pname, "phone", None)
    if notation is None:
        try:
            notation = detect_notation([s.label for s in raw_phones], source=src)
        except InputError:
            raise InputError("the phone tier has no labelled intervals", source=src,
                             field=f"phone_tier {pname}") from None
    phones = segments(pname, "phone", notation)
    word_segs = segments(wname, "word", None) if wname is not None else ()
    try:
        duration = float(tg["xmax"])
    except (ValueError, TypeError, KeyError):
        duration = float("nan")
    if not np.isfinite(duration):
        raise InputError(f"the end time xmax {tg.get('xmax')!r} is not a number", source=src,
                         field="xmax")
    return Alignment(words=word_segs, phones=phones, notation=notation,
                     duration=duration, source=src,
                     meta={"word_tier": wname, "phone_tier": pname, "format": "TextGrid"})


def write_textgrid(path: str | os.PathLike, alignment: Alignment, *, short: bool = False,
                   word_tier: str = "words", phone_tier: str = "phones",
                   tiers: dict | None = None) -> Path:
    """Write an alignment as a Praat TextGrid with a word and a phone interval tier, atomically.

    Gaps between segments become empty intervals (Praat's tiers cover the whole time span);
    times are written in full precision; intervals of zero length are left out (Praat has none).

    Parameters
    ----------
    path : the TextGrid to write
    alignment : words and phones (times in s)
    short : Praat's short text form instead of the long one
    word_tier, phone_tier : tier names (defaults as the Montreal Forced Aligner names them)
    tiers : further interval tiers after the phones, name -> segments (e.g. ``{"espeak":
        ...}``: eSpeak NG's codes beside IPA phones)
    """
    try:
        from praatio import textgrid
    except ImportError:
        raise InputError("writing TextGrids needs praatio (pip install 'facemech[speech]')",
                         source=str(path)) from None
    path = Path(path)
    extra = dict(tiers or {})
    end = max([alignment.duration] + [s.end for s in alignment.words + alignment.phones]
              + [s.end for segs in extra.values() for s in segs])
    tg = textgrid.Textgrid(minTimestamp=0.0, maxTimestamp=end)
    for name, segs in ((word_tier, alignment.words), (phone_tier, alignment.phones),
                       *extra.items()):
        entries = [(s.start, s.end, s.label) for s in segs if s.end > s.start]
        tg.addTier(textgrid.IntervalTier(name, entries, 0.0, end))
    with atomic_path(path, suffix=".TextGrid") as tmp:
        tg.save(str(tmp), format="short_textgrid" if short else "long_textgrid",
                includeBlankSpaces=True, minimumIntervalLength=None, reportingMode="error")
    return path


# --- CSV --------------------------------------------------------------------------------------

def write_alignment_csv(path: str | os.PathLike, alignment: Alignment, *,
                        tiers: dict | None = None) -> Path:
    """Write ``tier,label,start_s,end_s`` rows (words, then phones, then ``tiers``: name ->
    segments, e.g. :data:`ESPEAK_TIER`), atomically.

    Comment lines before the header keep the notation, the duration (s) and the source.
    """
    path = Path(path)
    buf = io.StringIO()
    buf.write(f"# notation: {alignment.notation}\n")
    buf.write(f"# duration_s: {alignment.duration!r}\n")
    if alignment.source:
        buf.write(f"# source: {alignment.source}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["tier", "label", "start_s", "end_s"])
    for tier, segs in (("words", alignment.words), ("phones", alignment.phones),
                       *(tiers or {}).items()):
        for s in segs:
            w.writerow([tier, s.label, repr(float(s.start)), repr(float(s.end))])
    with atomic_path(path, suffix=".csv") as tmp:
        tmp.write_text(buf.getvalue(), encoding="utf-8")
    return path


def read_alignment_csv(path: str | os.PathLike, *, notation: str | None = None) -> Alignment:
    """Read an alignment CSV written by :func:`write_alignment_csv` (or by hand).

    Columns ``tier`` (``words``/``phones``), ``label``, ``start_s``, ``end_s``; lines starting
    with ``#`` are comments, ``# notation: ...`` and ``# duration_s: ...`` are used (else the
    notation is detected and the duration is the last end). Pause labels are left out, and
    so are the rows of the tier :data:`ESPEAK_TIER`.
    """
    path = Path(path)
    src = str(path)
    _check_notation(notation, src)
    if not path.is_file():
        raise InputError("file not found", source=src)
    meta: dict[str, str] = {}
    rows: dict[str, list[tuple[str, float, float]]] = {"words": [], "phones": []}
    header = None
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte {exc.start})", source=src) from None
    for lineno, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not row or not "".join(row).strip():
            continue
        if header is None and row[0].lstrip().startswith("#"):
            body = ",".join(row).lstrip("# ").strip()
            if ":" in body:
                k, v = body.split(":", 1)
                meta[k.strip().lower()] = v.strip()
            continue
        if header is None:
            header = [c.strip().lower() for c in row]
            missing = [c for c in ("tier", "label", "start_s", "end_s") if c not in header]
            if missing:
                raise InputError(f"missing column(s) {', '.join(missing)} (expected "
                                 "tier,label,start_s,end_s)", source=src, field=missing[0])
            col = {c: header.index(c) for c in ("tier", "label", "start_s", "end_s")}
            continue
        if len(row) < len(header):
            raise InputError(f"line {lineno} has {len(row)} cells, the header "
                             f"{len(header)}", source=src, field="label")
        tier = row[col["tier"]].strip().lower()
        if tier == ESPEAK_TIER:
            continue  # eSpeak NG's own codes beside the phones (write_alignment_csv)
        if tier not in rows:
            raise InputError(f"line {lineno}: tier {tier!r} is neither 'words' nor "
                             "'phones'", source=src, field="tier")
        try:
            start, end = float(row[col["start_s"]]), float(row[col["end_s"]])
        except ValueError:
            raise InputError(f"line {lineno}: times must be numbers (s)", source=src,
                             field="start_s") from None
        rows[tier].append((row[col["label"]], start, end))
    if header is None:
        raise InputError("no header row (expected tier,label,start_s,end_s)", source=src)
    notation = notation or meta.get("notation") or None
    _check_notation(notation, src)
    if notation is None:
        notation = detect_notation([r[0] for r in rows["phones"]], source=src)
    segs = {t: tuple(Segment(lab.strip(), s, e) for lab, s, e in sorted(r, key=lambda x: x[1])
                     if not is_pause(lab, notation))
            for t, r in rows.items()}
    try:
        duration = float(meta["duration_s"]) if "duration_s" in meta else \
            max((e for r in rows.values() for _, _, e in r), default=0.0)
    except ValueError:
        raise InputError(f"duration_s {meta['duration_s']!r} is not a number", source=src,
                         field="duration_s") from None
    return Alignment(words=segs["words"], phones=segs["phones"], notation=notation,
                     duration=duration, source=src, meta={"format": "csv"})
