"""Marker-file workflows: describe, convert, head-correct, resample, re-frame, fill gaps and
trim (named trajectories on a time grid: :mod:`facemech.io.trajectories`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..atomic import check_output
from ..checks import check_value
from ..errors import InputError
from ..io.trajectories import names_of, on_times, trajectories  # noqa: F401 (re-exported)
from .inputs import Bounds, MarkerReading
from .outcome import Written


@dataclass(frozen=True)
class MarkerInfo:
    """What ``markers info`` shows of a marker file: rate, units, markers and gaps."""

    path: Path
    markers: object  # MarkerSet
    gaps: list

    def to_dict(self) -> dict:
        ms = self.markers
        return {"file": str(self.path), "format": ms.meta.get("format"), "rate_hz": ms.rate,
                "frames": ms.n_frames, "duration_s": float(ms.time[-1] - ms.time[0]),
                "units": ms.source_units, "markers": list(ms.names),
                "missing_samples": int((~ms.valid).sum()), "notes": list(ms.meta.get("notes", [])),
                "roles": dict(ms.meta.get("roles") or {}), "axes": ms.meta.get("axes"),
                "gaps": [{"marker": g.marker, "start": g.start, "frames": g.length,
                          "interior": g.interior} for g in self.gaps]}

    def text(self, as_json: bool = False, max_gaps: int = 50) -> str:
        """JSON (:meth:`to_dict`), or lines: format, rate, frames, units, markers and gaps."""
        d, ms = self.to_dict(), self.markers
        if as_json:
            return json.dumps(d, indent=2)
        lines = [f"{self.path}: {d['format']}, {ms.rate:g} Hz, {ms.n_frames} frames "
                 f"({d['duration_s']:.2f} s), unit {ms.source_units}, {ms.n_markers} markers",
                 "markers: " + ", ".join(ms.names),
                 *(f"note: {n}" for n in ms.meta.get("notes", []) if n.startswith("dropped")),
                 *([f"axes: {ms.meta['axes']}"] if "axes" in ms.meta else []),
                 f"gaps: {len(self.gaps)} ({d['missing_samples']} missing samples)"]
        return "\n".join(lines + [f"  {gap_text(g)}" for g in self.gaps[:max_gaps]])


def gap_text(g) -> str:
    """``MARKER: frames A-B (N)`` for a :class:`~facemech.kinematics.gaps.Gap`."""
    return (f"{g.marker}: frames {g.start}-{g.stop - 1} ({g.length})"
            + ("" if g.interior else " at an end"))


def marker_info(path: str | Path, *, units: str | None = None,
                reader: MarkerReading | None = None, **keywords) -> MarkerInfo:
    """Read a marker file and find its gaps (``units``: length unit if the file has none;
    ``reader``: :class:`~.inputs.MarkerReading`, or its ``rate=`` and ``sensors=``)."""
    from ..io.markers import read_markers
    from ..kinematics.gaps import find_gaps

    ms = read_markers(path, units=units, **_reading(reader, keywords).options())
    return MarkerInfo(Path(path), ms, find_gaps(ms))


def convert_markers(source: str | Path, target: str | Path | None, *, units: str | None = None,
                    out_units: str | None = None, reader: MarkerReading | None = None,
                    **keywords):
    """Copy a marker file (or a results file's model markers) to ``target`` (``.c3d``, ``.trc``
    or ``.csv``; a CSV keeps articulography's roles) in ``out_units`` (default: the input's);
    ``reader`` (:class:`~.inputs.MarkerReading`, or its ``rate=`` and ``sensors=``) for
    formats without times or names. Returns :class:`Written` with the MarkerSet read."""
    from ..io.markers import read_markers, write_markers

    if target is None:
        raise InputError("give the output file (-o)", field="output")
    check_output(target, [source], field="-o")
    ms = read_markers(source, units=units, **_reading(reader, keywords).options())
    write_markers(target, ms, units=out_units)
    return Written(Path(target), ms, f"{ms.n_markers} markers, {ms.n_frames} frames -> {target}")


def head_correct_file(source: str | Path, output: str | Path, head: str | Sequence[str], *,
                      reference: int | None = None, units: str | None = None,
                      report: str | Path | None = None):
    """Remove head motion by a per-frame rigid fit of ``head`` markers (at least three) to a
    reference frame (default: the first with every head marker); write the corrected markers
    to ``output`` and, with ``report``, the per-frame residuals (mm) as JSON.

    Returns
    -------
    Written : ``data`` the :class:`~facemech.kinematics.rigid.HeadCorrection`; a warning names
        the frames with fewer than three usable head markers (left empty)
    """
    from ..atomic import atomic_path
    from ..io.markers import read_markers, write_markers
    from ..kinematics.rigid import head_correct

    if reference is not None:
        check_value("reference", reference)  # the command line's interval (facemech.checks)
    check_output(output, [source], field="-o")
    ms = read_markers(source, units=units)
    res = head_correct(ms, names_of(head), reference=reference)
    write_markers(output, res.markers)
    if report is not None:
        data = {**res.summary(), "residual_mm": (res.residual * 1e3).tolist(),
                "head_markers_used": res.head_markers_used.tolist()}
        with atomic_path(report, suffix=".json") as tmp:
            tmp.write_text(json.dumps(data, allow_nan=True))
    s = res.summary()
    line = (f"head-corrected {s['frames']} frames against frame {s['reference_frame']}: "
            f"median residual {s['residual_mm']['median']:.3f} mm, max "
            f"{s['residual_mm']['max']:.3f} mm -> {output}")
    warn = ""
    if len(res.unfixed_frames):
        warn = (f"facemech: warning: {len(res.unfixed_frames)} frames had fewer than 3 usable "
                f"head markers and are left empty: {res.unfixed_frames[:20].tolist()}\n")
    return Written(Path(output), res, line, warn)


def resample_file(source: str | Path, output: str | Path, *, rate: float | None = None,
                  units: str | None = None):
    """Resample a marker file to ``rate`` Hz (default: the parameters' frame rate) with
    anti-aliasing (gaps stay gaps). Returns :class:`Written` with the resampled MarkerSet."""
    from ..io.markers import read_markers, write_markers
    from ..kinematics.resample import resample
    from .emg import frame_rate

    check_output(output, [source], field="-o")
    ms = read_markers(source, units=units)
    res = resample(ms, frame_rate(rate))
    write_markers(output, res)
    return Written(Path(output), res, f"{ms.rate:g} Hz -> {res.rate:g} Hz, {res.n_frames} frames "
                   f"-> {output}")


def frame_file(source: str | Path, output: str | Path, *, right: str, left: str, front: str,
               origin: str | None = None, reference: int = 0, units: str | None = None):
    """Express markers in an anatomical frame (+x right to left, +y up, +z forward) set by
    three markers in frame ``reference``, origin at ``origin`` (default: ``front``); write them
    to ``output``. Returns :class:`Written` with the MarkerSet written."""
    from ..io.markers import read_markers, write_markers
    from ..kinematics.frames import to_anatomical_frame

    check_value("reference", reference)  # the command line's interval (facemech.checks)
    check_output(output, [source], field="-o")
    ms = read_markers(source, units=units)
    res = to_anatomical_frame(ms, right=right, left=left, front=front, origin=origin,
                              reference=reference)
    write_markers(output, res)
    return Written(Path(output), res, f"markers in the frame of {right}, {left}, {front} (origin "
                   f"{origin or front}) -> {output}")


def fill_gaps_file(source: str | Path, output: str | Path, *, max_gap: float = 0.1,
                   units: str | None = None):
    """Fill interior gaps of at most ``max_gap`` s with a cubic spline (filled samples are
    flagged) and write the result.

    Returns
    -------
    Written : ``data`` (MarkerSet, gaps filled, gaps left); the gaps left (first 20) as
        warnings
    """
    from ..io.markers import read_markers, write_markers
    from ..kinematics.gaps import fill_gaps

    check_output(output, [source], field="-o")
    ms = read_markers(source, units=units)
    res, done, left = fill_gaps(ms, int(round(max_gap * ms.rate)))
    write_markers(output, res)
    line = (f"filled {len(done)} gaps ({sum(g.length for g in done)} samples); {len(left)} left "
            f"-> {output}")
    notes = "".join(f"  not filled: {gap_text(g)}\n" for g in left[:20])
    if any(not g.interior for g in left):
        notes += ("  gaps at an end are never filled (nothing to interpolate from): cut them "
                  "(facemech markers trim)\n")
    return Written(Path(output), (res, done, left), line, notes)


def gap_hint(ms, frame: int, marker: int | None = None) -> str:
    """What to do about a missing sample at ``frame`` (of ``marker``; None: of every marker):
    fill it where fill-gaps can (a gap with samples before and after), else cut the ends."""
    valid = ms.valid.any(axis=1) if marker is None else ms.valid[:, marker]
    if valid[:frame].any() and valid[frame:].any():
        return "fill the gap (facemech markers fill-gaps) or cut it off (facemech markers trim)"
    return ("cut the recording to where the data are (facemech markers trim; fill-gaps fills "
            "only gaps with data on both sides)")


def trim_file(source: str | Path, output: str | Path, *, bounds: Bounds | None = None,
              units: str | None = None, reader: MarkerReading | None = None, **keywords):
    """Keep the frames of a marker file between two times (s, the file's own) or two frame
    numbers (from 0, as ``markers info`` shows them): ``bounds`` (:class:`~.inputs.Bounds`, or
    its ``start=``, ``stop=``, ``first=``, ``last=``), and write them (``.csv``, ``.trc`` or
    ``.c3d``; a CSV keeps articulography's roles). Without bounds, the leading and trailing
    frames where no marker is present are dropped. The input is never overwritten; the output
    is written atomically. ``reader`` (:class:`~.inputs.MarkerReading`, or its ``rate=`` and
    ``sensors=``) for the formats that do not say them.

    Returns
    -------
    Written : ``data`` the MarkerSet written
    """
    from dataclasses import asdict, replace

    from ..io.markers import read_markers, write_markers
    from ..kinematics.trim import drop_empty_ends, trim

    bounds = replace(bounds or Bounds(), **{k: keywords.pop(k) for k in ("start", "stop",
                                                                          "first", "last")
                                             if k in keywords})
    check_output(output, [source], field="-o")
    ms = read_markers(source, units=units, **_reading(reader, keywords).options())
    n, t0, t1 = ms.n_frames, ms.time[0], ms.time[-1]
    if not bounds.given():
        res, note = drop_empty_ends(ms)
        how = note or "no frame without markers at either end: all kept"
    else:
        res = trim(ms, **asdict(bounds))
        a, b = res.meta["trimmed"]
        how = (f"kept frames {a}-{b} (t = {res.time[0]:.3f}-{res.time[-1]:.3f} s) of {n} "
               f"({t0:.3f}-{t1:.3f} s)")
    write_markers(output, res)
    return Written(Path(output), res, f"{how}; {res.n_frames} frames -> {output}")


def _reading(reader: MarkerReading | None, keywords: dict) -> MarkerReading:
    """``reader`` (None: the defaults) with its fields given as keywords (``rate=``,
    ``sensors=``); a TypeError for any other keyword."""
    from dataclasses import replace

    unknown = sorted(set(keywords) - {"rate", "sensors"})
    if unknown:
        raise TypeError(f"unexpected keyword {unknown[0]!r}")
    return replace(reader or MarkerReading(), **keywords)
