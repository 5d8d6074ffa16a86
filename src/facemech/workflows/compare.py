"""``facemech compare``: the statistics of one trajectory file against another."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["MAX_MEDIAN_ERROR_MM", "bring_together", "check_magnitude", "compare_files", "report",
           "stderr_lines"]


def compare_files(a: str | Path, b: str | Path, *, markers: str | list[str] | None = None,
                  units: str | None = None):
    """3-D statistics, per-axis correlations and per-frame errors of ``a`` against ``b``.

    Parameters
    ----------
    a, b : results (.nc) or marker files (the model and the data). Frames that differ are
        brought together as ``invert`` does (:func:`bring_together`): a marker file onto a
        results file's frames, else the faster onto the slower over the common span;
        articulography laid on a results file's marker data by its displacements
    markers : the markers to compare, a list or comma-separated (default: all in both, in
        ``a``'s order); names match ignoring case where that is unambiguous (``ul``, ``UL``)
    units : length unit of marker files that carry none

    Returns
    -------
    facemech.kinematics.stats.Comparison
        Numbers in mm; its ``warnings`` say when the largest per-frame error exceeds 1 mm or
        5 x the median, its ``notes`` how the inputs were brought together.
    """
    from dataclasses import replace

    from ..io.markers import read_markers
    from ..kinematics.stats import compare
    from ..markerset import match_name, shared_names

    ma, mb = read_markers(a, units=units), read_markers(b, units=units)
    if isinstance(markers, str):
        markers = [m.strip() for m in markers.split(",") if m.strip()]
    if markers:
        pairs = [(match_name(n, ma.names, source=str(a)), match_name(n, mb.names, source=str(b)))
                 for n in markers]
    else:
        pairs = shared_names(ma.names, mb.names, source=str(b))
    if not pairs:
        raise InputError(f"no marker names shared by the inputs (A has "
                         f"{', '.join(ma.names[:8])}; B {', '.join(mb.names[:8])})",
                         field="markers")
    names = [p for p, _ in pairs]
    ma, mb = ma.select(names), mb.select([q for _, q in pairs]).renamed(names)
    ma, mb, notes = bring_together(ma, mb, a, b)
    notes = [f"{Path(p).name}: {n}" for p, m in ((a, ma), (b, mb))
             for n in m.meta.get("notes", []) if n.startswith("dropped")] + notes
    try:
        res = compare(ma.positions, mb.positions, names, ma.rate)
    except InputError as exc:  # nothing in both: name the file that lacks the data
        lacks_a = mb.valid.any() and not ma.valid.any()
        raise InputError(exc.message + _why(ma.valid, mb.valid), source=str(a if lacks_a else b),
                         field=exc.field) from None
    check_magnitude(res.error["median_mm"], ma, mb, a, b)
    return replace(res, notes=tuple(notes))


def _is_results(ms) -> bool:
    return ms.meta.get("format") == "results"


def bring_together(ma, mb, a: str | Path, b: str | Path):
    """Marker sets ``ma`` and ``mb`` (files ``a``, ``b``) on the same frames, with notes.

    The same frames: kept. A results file and a marker file: the marker file resampled onto
    the results' frames (:func:`facemech.workflows.markers.on_times`), the results' time 0
    being the recording's first frame, as ``invert`` makes it; its articulography sensors then
    laid on the results' marker data (``data_markers``) by their displacement from their first
    common sample, as ``invert`` lays them on the face. Otherwise the faster recording is
    resampled onto the slower one's frames inside the span both cover.

    Returns
    -------
    (ma, mb, notes)
    """
    from .markers import on_times

    if (ma.n_frames == mb.n_frames and abs(ma.rate - mb.rate) <= 1e-3 * ma.rate
            and np.allclose(ma.time - ma.time[0], mb.time - mb.time[0], atol=1e-6)):
        return ma, mb, []
    notes = []
    if _is_results(ma) != _is_results(mb):
        (res, rpath), (rec, path) = ((ma, a), (mb, b)) if _is_results(ma) else ((mb, b), (ma, a))
        on, note = on_times(rec, rec.time[0] + res.time - res.time[0], label=res.time)
        notes.append(f"{Path(path).name}: {note}; the results' time 0 is its first frame "
                     f"(t = {rec.time[0]:.3f} s)")
        on, laid = _laid_on(on, rpath)
        notes += [f"{Path(path).name}: {laid}"] if laid else []
        ma, mb = (res, on) if _is_results(ma) else (on, res)
        return ma, mb, notes
    slow, fast, sp, fp = (ma, mb, a, b) if ma.rate <= mb.rate else (mb, ma, b, a)
    inside = (slow.time >= fast.time[0] - 1e-9) & (slow.time <= fast.time[-1] + 1e-9)
    if inside.sum() < 2:
        raise InputError(f"the recordings share no time span ({slow.time[0]:.3f}-"
                         f"{slow.time[-1]:.3f} s and {fast.time[0]:.3f}-{fast.time[-1]:.3f} s)",
                         source=str(fp), field="time")
    kept = np.nonzero(inside)[0]
    slow = _frames(slow, kept[0], kept[-1] + 1)
    on, note = on_times(fast, slow.time)
    notes.append(f"{Path(fp).name}: {note} of {Path(sp).name}"
                 + (f" ({len(kept)} of {len(inside)} frames in both)" if not inside.all()
                    else ""))
    return (slow, on, notes) if slow is ma else (on, slow, notes)


def _frames(ms, start: int, stop: int):
    from ..markerset import MarkerSet

    return MarkerSet(ms.positions[start:stop], ms.names, ms.rate, time=ms.time[start:stop],
                     source_units=ms.source_units, filled=ms.filled[start:stop], meta=ms.meta)


def _laid_on(ms, results: str | Path):
    """(the set, a note): its articulography sensors (roles) moved so that their first sample
    in common lies on the results' ``data_markers`` (the data as inverted), as ``invert``
    lays them on the face's points. Without roles or data markers: unchanged, no note."""
    from ..io.results import read_results

    roles = ms.meta.get("roles") or {}
    if not roles:
        return ms, None
    ds = read_results(results)
    if "data_markers" not in ds:
        return ms, None
    data = ds["data_markers"]
    have = [str(n) for n in data["marker"].values]
    pos = np.array(ms.positions)
    laid = []
    for j, name in enumerate(ms.names):
        if name not in have:
            continue
        d = data.sel(marker=name).transpose("time", "axis").values
        both = np.nonzero(np.all(np.isfinite(d) & np.isfinite(pos[:, j]), axis=1))[0]
        if len(both) == 0:
            continue
        pos[:, j] += d[both[0]] - pos[both[0], j]
        laid.append(name)
    if not laid:
        return ms, None
    return ms.with_positions(pos), (f"{', '.join(laid)} laid on the results' marker data by "
                                    "their displacement from their first common sample, as "
                                    "invert lays them on the face")


#: mm, the largest median per-frame error ``compare`` accepts: a model of the data is off by a
#: few millimetres; tens of centimetres to metres are a unit or frame mix-up
MAX_MEDIAN_ERROR_MM = 50.0


def _why(va, vb) -> str:
    """Which input lacks the data (valid: (frames, markers) bool arrays of A and B)."""
    if not vb.any():
        return " (B has no data)"
    if not va.any():
        return " (A has no data)"
    return " (A and B have data at different frames)"


def _length(mm: float) -> str:
    return f"{mm / 1e3:.3g} m" if mm >= 1e3 else f"{mm:.3g} mm"


def _spread(positions) -> float:
    """RMS distance (m) of the finite samples from their centroid: the size of the marker
    cloud, independent of the frame's origin."""
    import numpy as np

    p = positions[np.all(np.isfinite(positions), axis=-1)]
    return float(np.sqrt(np.mean(np.sum((p - p.mean(axis=0)) ** 2, axis=-1)))) if len(p) else 0.0


def check_magnitude(median_mm: float, ma, mb, a: str | Path, b: str | Path, *,
                    limit_mm: float = MAX_MEDIAN_ERROR_MM) -> float:
    """Refuse a median per-frame error beyond ``limit_mm``: a unit or frame mix-up, not a fit.

    The unit the data look like is found from the sizes of the two marker clouds (RMS distance
    from their centroid, independent of the frame's origin): B a thousand times A's size in a
    file labelled m suggests millimetres labelled as metres. A results file (``.nc``) is in
    metres, so the other file is named; of two marker files, B.

    Parameters
    ----------
    median_mm : the median per-frame error, mm
    ma, mb : the :class:`~facemech.markerset.MarkerSet` of A and B (the markers compared)
    a, b : their files, for the message
    limit_mm : the largest median error accepted, mm

    Returns
    -------
    float
        ``median_mm``.

    Raises
    ------
    InputError
        Naming the file and the field ``units``: "median error 77 m (more than 50 mm): are
        the data in mm labelled as m?", or, when the sizes agree, asking whether both are in
        the model's frame.
    """
    import numpy as np

    from ..units import LENGTH_TO_M

    if not median_mm > limit_mm:  # NaN passes: no frame in both is reported elsewhere
        return median_mm
    blame_a = Path(b).suffix.lower() == ".nc" and Path(a).suffix.lower() != ".nc"
    ms, other, path = (ma, mb, a) if blame_a else (mb, ma, b)
    head = f"median error {_length(median_mm)} (more than {limit_mm:g} mm)"
    size, ref = _spread(ms.positions), _spread(other.positions)
    label = ms.source_units
    if size > 0 and ref > 0 and label in LENGTH_TO_M:
        # values v read as v * scale(label); in unit U they would be v * scale(U)
        ratio = size / ref
        guess = min(LENGTH_TO_M, key=lambda u: abs(np.log(
            ratio * LENGTH_TO_M[u] / LENGTH_TO_M[label])))
        if guess != label:
            what = "data" if path == b else "model"
            raise InputError(f"{head}: are the {what} in {guess} labelled as {label}? "
                             "(--units, or the file's unit)", source=str(path), field="units")
    raise InputError(f"{head}: are both in the model's frame and the same unit? "
                     "(facemech markers frame)", source=str(path), field="units")


def stderr_lines(res) -> list[str]:
    """What ``facemech compare`` says on stderr: its notes, then its warnings."""
    return [f"note: {n}" for n in res.notes] + [f"warning: {w}" for w in res.warnings]


def report(res, *, as_json: bool = False) -> list[str]:
    """What ``facemech compare`` prints: strict JSON (NaN as null), or a summary line, what was
    skipped for want of data (e.g. "12 of 300 frames without data were skipped") and one line
    per marker (3-D correlation)."""
    from ..kinematics.stats import json_safe

    if as_json:
        return [json.dumps(json_safe(res.as_dict()), indent=2)]
    e, s = res.error, res.frame_error_mm
    head = (f"{res.frames} frames, {len(res.markers)} markers; per-frame error (RMS over the "
            f"markers, mm): median {e['median_mm']:.3f}, max {e['max_mm']:.3f} at "
            f"{e['max_time_s']:.2f} s (min {s['min']:.3f} q1 {s['q1']:.3f} q3 {s['q3']:.3f}); "
            f"movement {res.movement_mm:.3f} mm")
    return [head, *(f"  {g}" for g in res.gaps),
            *(f"  {n}: 3-D r {v.corr3d_published:.3f}" for n, v in res.markers.items())]
