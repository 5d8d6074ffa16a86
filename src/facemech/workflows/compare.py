"""``facemech compare``: the statistics of one trajectory file against another."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import InputError

__all__ = ["compare_files", "report"]


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
    facemech.inverse.stats.Comparison
        Numbers in mm; its ``warnings`` say when the largest per-frame error exceeds 1 mm or
        5 x the median.
    """
    from ..inverse.stats import compare
    from ..io.markers import read_markers

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
    return compare(ma.select(names).positions, mb.select(names).positions, names, ra)


def report(res, *, as_json: bool = False) -> list[str]:
    """What ``facemech compare`` prints: strict JSON (NaN as null), or a summary line and one
    line per marker (3-D correlation)."""
    from ..inverse.stats import json_safe

    if as_json:
        return [json.dumps(json_safe(res.as_dict()), indent=2)]
    e, s = res.error, res.frame_error_mm
    head = (f"{res.frames} frames, {len(res.markers)} markers; per-frame error (RMS over the "
            f"markers, mm): median {e['median_mm']:.3f}, max {e['max_mm']:.3f} at "
            f"{e['max_time_s']:.2f} s (min {s['min']:.3f} q1 {s['q1']:.3f} q3 {s['q3']:.3f}); "
            f"movement {res.movement_mm:.3f} mm")
    return [head, *(f"  {n}: 3-D r {v.corr3d_published:.3f}" for n, v in res.markers.items())]
