"""Cutting a recording: the frames kept by time or by frame number, and the empty ends dropped.

A recording often starts or ends with frames where no sensor was tracked (the articulograph
or the X-ray beam running before the talker speaks). Those frames carry nothing: they are
dropped (:func:`drop_empty_ends`) with a note; anything else is cut only when asked
(:func:`trim`). Gaps inside the kept span stay gaps (:mod:`facemech.kinematics.gaps`).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..markerset import MarkerSet

__all__ = ["drop_empty_ends", "empty_ends", "trim"]


def empty_ends(ms: MarkerSet) -> tuple[int, int]:
    """(leading, trailing): how many frames at each end have no marker at all.

    A recording with no sample at all gives ``(n_frames, 0)``.
    """
    any_marker = ms.valid.any(axis=1)
    if not any_marker.any():
        return ms.n_frames, 0
    first = int(np.argmax(any_marker))
    last = ms.n_frames - 1 - int(np.argmax(any_marker[::-1]))
    return first, ms.n_frames - 1 - last


def _keep(ms: MarkerSet, start: int, stop: int) -> MarkerSet:
    """Frames ``start`` to ``stop - 1`` of the set (the rate kept; the times are the file's);
    per-frame arrays in its meta (a ``.pos`` file's angles) are cut with them."""
    meta = {k: v[start:stop] if isinstance(v, np.ndarray) and v.ndim and len(v) == ms.n_frames
            else v for k, v in ms.meta.items()}
    return MarkerSet(ms.positions[start:stop], ms.names, ms.rate, time=ms.time[start:stop],
                     source_units=ms.source_units, filled=ms.filled[start:stop], meta=meta)


def drop_empty_ends(ms: MarkerSet) -> tuple[MarkerSet, str | None]:
    """The set without its leading and trailing frames where no marker is present, and a note
    saying what was dropped (None when nothing was).

    Raises
    ------
    InputError
        (field ``data``) when no frame has a marker, or fewer than two frames are left.
    """
    lead, trail = empty_ends(ms)
    if lead == 0 and trail == 0:
        return ms, None
    src = ms.meta.get("source")
    if lead == ms.n_frames:
        raise InputError("no frame has a marker: no sample to use", source=src, field="data")
    stop = ms.n_frames - trail
    if stop - lead < 2:
        raise InputError(f"only {stop - lead} frame has a marker: a recording needs at least "
                         "two", source=src, field="data")
    parts = []
    if lead:
        parts.append(f"{lead} leading (t = {ms.time[0]:.3f}-{ms.time[lead - 1]:.3f} s)")
    if trail:
        parts.append(f"{trail} trailing (t = {ms.time[stop]:.3f}-{ms.time[-1]:.3f} s)")
    note = (f"dropped {' and '.join(parts)} frames where no sensor is present; kept "
            f"t = {ms.time[lead]:.3f}-{ms.time[stop - 1]:.3f} s (the file's times)")
    out = _keep(ms, lead, stop)
    notes = [*out.meta.get("notes", []), note]
    return out.with_positions(out.positions, meta={**out.meta, "notes": notes,
                                                   "dropped_frames": [lead, trail]}), note


def trim(ms: MarkerSet, *, start: float | None = None, stop: float | None = None,
         first: int | None = None, last: int | None = None) -> MarkerSet:
    """The frames of ``ms`` between two times or two frame numbers (inclusive).

    Parameters
    ----------
    ms : the marker set
    start, stop : s, on the set's own time axis; frames with ``start <= t <= stop`` are kept
        (None: from the first, to the last)
    first, last : frame numbers counted from 0, as ``facemech markers info`` shows them;
        frames ``first`` to ``last`` are kept (None: from the first, to the last); not with
        ``start``/``stop``

    Returns
    -------
    MarkerSet
        The kept frames, their times unchanged, ``meta["trimmed"]`` the (first, last) frames.

    Raises
    ------
    InputError
        Naming ``start``/``stop`` or ``first``/``last`` when both kinds are given, a bound is
        not a number or lies outside the recording, or fewer than two frames are left.
    """
    src = ms.meta.get("source")
    if (start is not None or stop is not None) and (first is not None or last is not None):
        raise InputError("cut by time (--start/--stop) or by frames (--first/--last), not both",
                         source=src, field="start")
    n = ms.n_frames
    if first is not None or last is not None:
        a = 0 if first is None else int(first)
        b = n - 1 if last is None else int(last)
        for name, v in (("first", a), ("last", b)):
            if not 0 <= v < n:
                raise InputError(f"frame {v} is outside the recording (frames 0-{n - 1})",
                                 source=src, field=name)
    else:
        t = ms.time
        lo = t[0] if start is None else float(start)
        hi = t[-1] if stop is None else float(stop)
        for name, v in (("start", lo), ("stop", hi)):
            if not np.isfinite(v):
                raise InputError(f"{v!r} is not a time", source=src, field=name)
        if lo > t[-1] + 1e-9 or hi < t[0] - 1e-9:
            raise InputError(f"{lo:g}-{hi:g} s lies outside the recording ({t[0]:.3f}-"
                             f"{t[-1]:.3f} s)", source=src, field="start" if lo > t[-1] else
                             "stop")
        keep = np.nonzero((t >= lo - 1e-9) & (t <= hi + 1e-9))[0]
        a, b = (int(keep[0]), int(keep[-1])) if len(keep) else (1, 0)
    if b - a + 1 < 2:
        raise InputError(f"keeps {max(b - a + 1, 0)} frame: a recording needs at least two",
                         source=src, field="stop" if first is None and last is None else "last")
    out = _keep(ms, a, b + 1)
    return out.with_positions(out.positions, meta={**out.meta, "trimmed": [a, b]})
