"""``facemech compare``: the statistics of one trajectory file against another."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import InputError

__all__ = ["MAX_MEDIAN_ERROR_MM", "check_magnitude", "compare_files", "report"]


def compare_files(a: str | Path, b: str | Path, *, markers: str | list[str] | None = None,
                  units: str | None = None):
    """3-D statistics, per-axis correlations and per-frame errors of ``a`` against ``b``.

    Parameters
    ----------
    a, b : results (.nc) or marker files (the model and the data), the same frames at the same
        rate
    markers : the markers to compare, a list or comma-separated (default: all in both, in
        ``a``'s order)
    units : length unit of marker files that carry none

    Returns
    -------
    facemech.kinematics.stats.Comparison
        Numbers in mm; its ``warnings`` say when the largest per-frame error exceeds 1 mm or
        5 x the median.
    """
    from ..io.markers import read_markers
    from ..kinematics.stats import compare

    ma, mb = read_markers(a, units=units), read_markers(b, units=units)
    ra, rb = ma.rate, mb.rate
    if abs(ra - rb) > 1e-3 * ra or ma.n_frames != mb.n_frames:
        raise InputError(f"A has {ma.n_frames} frames at {ra:g} Hz, B {mb.n_frames} at "
                         f"{rb:g} Hz", source=str(b), field="time")
    if isinstance(markers, str):
        markers = [m.strip() for m in markers.split(",")]
    names = markers or [n for n in ma.names if n in mb.names]
    for n in names:
        if n not in ma.names or n not in mb.names:
            raise InputError("marker not in both inputs", field=n)
    if not names:
        raise InputError("no marker names shared by the inputs", field="markers")
    ma, mb = ma.select(names), mb.select(names)
    try:
        res = compare(ma.positions, mb.positions, names, ra)
    except InputError as exc:  # nothing in both: name the file that lacks the data
        lacks_a = mb.valid.any() and not ma.valid.any()
        raise InputError(exc.message + _why(ma.valid, mb.valid), source=str(a if lacks_a else b),
                         field=exc.field) from None
    check_magnitude(res.error["median_mm"], ma, mb, a, b)
    return res


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
