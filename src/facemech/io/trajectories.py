"""Named marker trajectories from a marker or results file, put on a time grid (the way
``invert`` puts articulography on the model's frames): what the jaw's file drive, the plots and
the comparisons read."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["names_of", "on_times", "trajectories"]


def names_of(names: str | Sequence[str]) -> list[str]:
    """Marker names from a sequence or from comma-separated text (blanks dropped)."""
    items = names.split(",") if isinstance(names, str) else names
    return [n.strip() for n in items if n.strip()]


def trajectories(path: str | Path, names: str | Sequence[str], *, units: str | None = None,
                 times: np.ndarray | None = None, cover: str | None = None,
                 missing: str = "error", origin: str = "same"
                 ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Named marker trajectories from a marker file or a results file (its model markers).

    Parameters
    ----------
    path : any marker file :func:`facemech.read_markers` reads, or a results ``.nc`` file
    names : the markers wanted (a sequence, or comma-separated text), matched as
        :func:`facemech.markerset.match_name` does (``ul`` finds ``UL``)
    units : length unit of a marker file that does not say
    times : (frames,) s, a grid to put them on (default: the file's frames): articulography
        (sensors with roles) resampled as ``invert`` does (:func:`on_times`), other files
        interpolated linearly
    cover : with ``times``, what the trajectories are, for an error when ``times`` reach
        outside the file's time span (e.g. ``"the chin trajectory"``); None: the end samples
        are held outside it (linear) or NaN (articulography)
    missing : ``"error"`` (an :class:`~facemech.errors.InputError` naming the marker) or
        ``"skip"`` for a marker the file does not have
    origin : ``"same"``: ``times`` are on the file's time axis; ``"first"``: ``times[0]`` is
        the file's first frame (a results file's time starts at 0 at the first frame of the
        recording it was made from)

    Returns
    -------
    time : (frames,) s, ``times`` or the file's
    trajectories : name -> (frames, 3) positions, m, in the order of ``names``
    """
    from ..markerset import match_name
    from .markers import read_markers

    ms = read_markers(path, units=units)
    src = str(path)
    wanted = {}
    for n in names_of(names):
        try:
            wanted[n] = match_name(n, ms.names, source=src)
        except InputError:
            if missing == "error" or any(m.casefold() == n.casefold() for m in ms.names):
                raise
    if times is None:
        return ms.time, {n: ms.marker(m) for n, m in wanted.items()}
    times = np.asarray(times, float)
    axis = times - times[0] + ms.time[0] if origin == "first" else times
    if cover is not None and (axis[0] < ms.time[0] - 1e-6 or axis[-1] > ms.time[-1] + 1e-6):
        raise InputError(f"{cover} does not cover the activity's time span", source=src,
                         field="time")
    if ms.meta.get("roles") and wanted:
        on = on_times(ms.select(list(dict.fromkeys(wanted.values()))), axis)[0]
        return times, {n: on.marker(m) for n, m in wanted.items()}
    return times, {n: np.column_stack([np.interp(axis, ms.time, ms.marker(m)[:, a])
                                       for a in range(3)]) for n, m in wanted.items()}


def on_times(ms, times: np.ndarray, *, label: np.ndarray | None = None):
    """A marker set put on other frames as ``invert`` puts articulography on the model's.

    Parameters
    ----------
    ms : the :class:`~facemech.markerset.MarkerSet`
    times : (frames,) s on the set's time axis; where the new frames are coarser than the
        set's, each run is low-passed (4th-order Butterworth at 0.8 of the new Nyquist
        frequency), then a cubic spline through it gives the samples
        (:func:`facemech.kinematics.resample.resample_onto`); NaN outside the recording
    label : (frames,) s, the times the result carries (default: ``times``)

    Returns
    -------
    (MarkerSet, note) : the set on the new frames, and what was done (None when the frames
        were already the set's)
    """
    from ..kinematics.resample import resample_onto

    times = np.asarray(times, float)
    if len(times) == ms.n_frames and np.allclose(times, ms.time, atol=1e-6):
        out = ms
        note = None
    else:
        out = resample_onto(ms, times)
        rate = out.rate
        note = (f"{ms.rate:g} Hz ({ms.n_frames} frames) resampled onto {len(times)} frames "
                f"at {rate:g} Hz ({'low-passed, ' if rate < ms.rate * (1 - 1e-6) else ''}"
                "cubic spline), as invert does")
    if label is not None:
        from dataclasses import replace

        out = replace(out, time=np.asarray(label, float))
    return out, note
