"""Resampling with anti-aliasing, and Savitzky-Golay derivatives.

Both work on each marker's contiguous runs of valid samples; gaps stay gaps.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import butter, savgol_filter, sosfiltfilt

from ..errors import InputError
from ..markerset import MarkerSet
from .gaps import runs


def resample(ms: MarkerSet, rate: float, *, cutoff_fraction: float = 0.8) -> MarkerSet:
    """Resample to ``rate`` Hz on a grid starting at the first sample.

    When the rate goes down, each valid run is first low-passed (4th-order Butterworth, zero
    phase, cut-off at ``cutoff_fraction`` of the new Nyquist frequency); then a cubic spline
    through the run gives the new samples. Output samples outside every run are NaN.
    """
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"rate {float(rate):g} Hz must be a positive number", field="rate")
    t0, t1 = ms.time[0], ms.time[-1]
    n = int(np.floor((t1 - t0) * rate + 1e-6)) + 1
    if n < 2:  # a one-frame recording has no rate: no reader of facemech takes it back
        raise InputError(f"{1e3 * (t1 - t0):.4g} ms of data at {float(rate):g} Hz gives {n} "
                         "frame: a recording needs at least two (raise the rate)", field="rate")
    return resample_onto(ms, t0 + np.arange(n) / rate, rate=rate,
                         cutoff_fraction=cutoff_fraction)


def resample_onto(ms: MarkerSet, times: np.ndarray, *, rate: float | None = None,
                  cutoff_fraction: float = 0.8) -> MarkerSet:
    """The set at the given times (s, increasing), as :func:`resample` makes them.

    Parameters
    ----------
    ms : the marker set
    times : (frames,) s, on the set's own time axis
    rate : Hz, the new rate (default: from the times' span); below the set's rate each run is
        low-passed first at ``cutoff_fraction`` of the new Nyquist frequency

    Returns
    -------
    MarkerSet
        NaN at times outside every valid run; ``meta["resampled_from_hz"]`` the old rate.
    """
    grid = np.asarray(times, float)
    if rate is None:
        rate = (len(grid) - 1) / float(grid[-1] - grid[0]) if len(grid) > 1 else ms.rate
    n = len(grid)
    out = np.full((n, ms.n_markers, 3), np.nan)
    filled = np.zeros((n, ms.n_markers), bool)
    sos = None
    if rate < ms.rate * (1 - 1e-6):
        sos = butter(4, cutoff_fraction * 0.5 * rate, fs=ms.rate, output="sos")
    for m in range(ms.n_markers):
        for a, b in runs(ms.valid[:, m]):
            if b - a < 2:
                continue
            seg = ms.positions[a:b, m]
            if sos is not None and b - a > 27:  # sosfiltfilt's default padding needs 27
                seg = sosfiltfilt(sos, seg, axis=0)
            tt = ms.time[a:b]
            inside = (grid >= tt[0] - 1e-9) & (grid <= tt[-1] + 1e-9)
            out[inside, m] = CubicSpline(tt, seg, axis=0)(grid[inside])
            fl = ms.filled[a:b, m]
            if fl.any():
                filled[inside, m] = np.interp(grid[inside], tt, fl.astype(float)) > 0
    return MarkerSet(out, ms.names, rate, time=grid, source_units=ms.source_units,
                     filled=filled, meta={**ms.meta, "resampled_from_hz": ms.rate})


def lowpass(ms: MarkerSet, cutoff_hz: float, *, order: int = 4) -> MarkerSet:
    """Low-pass each valid run of each marker: a Butterworth filter of ``order`` run forwards
    and backwards (zero phase), cut-off ``cutoff_hz`` Hz (below the Nyquist frequency). Runs
    too short for the filter's padding are left as they are; gaps stay gaps."""
    if not 0 < cutoff_hz < 0.5 * ms.rate:
        raise InputError(f"low-pass cut-off {cutoff_hz:g} Hz must lie in (0, {0.5 * ms.rate:g})"
                         " Hz, below the Nyquist frequency", field="lowpass")
    sos = butter(order, cutoff_hz, fs=ms.rate, output="sos")
    pad = 3 * (2 * len(sos) + 1)  # sosfiltfilt's default padding
    out = ms.positions.copy()
    for m in range(ms.n_markers):
        for a, b in runs(ms.valid[:, m]):
            if b - a > pad:
                out[a:b, m] = sosfiltfilt(sos, ms.positions[a:b, m], axis=0)
    return ms.with_positions(out, meta={**ms.meta, "lowpass_hz": cutoff_hz})


#: the default Savitzky-Golay window of derivatives, s (5 samples at 60 Hz and 100 Hz)
DERIVATIVE_WINDOW_S = 0.05


def savgol_derivative(x: np.ndarray, rate: float, order: int = 1, *,
                      window_s: float = DERIVATIVE_WINDOW_S, polyorder: int = 3) -> np.ndarray:
    """Derivative of a gap-free series along axis 0 by a Savitzky-Golay filter.

    Parameters
    ----------
    x : ndarray, shape (samples, ...)
        The series, any unit.
    rate : float
        Sampling rate, Hz.
    order : {1, 2}
        Velocity (unit/s) or acceleration (unit/s^2).
    window_s : float
        Filter window, s; made an odd sample count of at least ``polyorder + 2`` and shrunk to
        the series' length.
    polyorder : int
        Polynomial order of the local fit.

    Returns
    -------
    ndarray, the shape of ``x``; zeros when the series is too short for any window.
    """
    if order not in (1, 2):
        raise InputError("order must be 1 or 2", field="order")
    n = len(x)
    win = max(polyorder + 2, int(round(window_s * rate)) | 1)
    if win > n:
        win = n if n % 2 else n - 1
    if win <= polyorder:
        return np.zeros_like(x, dtype=float)
    return savgol_filter(x, win, polyorder, deriv=order, delta=1.0 / rate, axis=0)


def derivative(ms: MarkerSet, order: int = 1, *, window_s: float = DERIVATIVE_WINDOW_S,
               polyorder: int = 3) -> np.ndarray:
    """Velocity (order 1, m/s) or acceleration (order 2, m/s^2) of every marker.

    Each gap-free run is differentiated by :func:`savgol_derivative`. Returns
    (frames, markers, 3); NaN in gaps and in runs shorter than the window.
    """
    if order not in (1, 2):
        raise InputError("order must be 1 or 2", field="order")
    win = max(polyorder + 2, int(round(window_s * ms.rate)) | 1)
    out = np.full(ms.positions.shape, np.nan)
    for m in range(ms.n_markers):
        for a, b in runs(ms.valid[:, m]):
            if b - a < win:
                continue
            out[a:b, m] = savgol_derivative(ms.positions[a:b, m], ms.rate, order,
                                            window_s=window_s, polyorder=polyorder)
    return out
