"""EMG processing: raw multichannel EMG -> muscle activity E in [0, 1] at the frame rate.

Lucero & Munhall (1999, II.B): full-wave rectify, integrate and downsample to 60 Hz with a 17-ms
trapezoidal window, normalise each muscle so that 0 is the mean baseline activity and 1 the
maximum over the session including maximal non-speech gestures.

Our choices where the paper is silent: the DC offset of each channel (its median) is removed
before rectifying; the trapezoid rises over its first quarter, is flat over the middle half and
falls over the last quarter, with unit area, so the integrated value is a weighted mean of the
rectified signal; without a baseline interval the baseline is the mean of the lowest 10 % of the
integrated samples (the quietest stretches of the recording).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .params import FRAME_RATE_HZ, MUSCLE_GROUPS

WINDOW_S = 0.017  #: s, trapezoidal integration window
QUIET_FRACTION = 0.10  #: fraction of lowest samples averaged for the default baseline


@dataclass(frozen=True)
class EMGActivity:
    """Processed EMG.

    Attributes
    ----------
    time : (frames,) s
    activity : (frames, channels) in [0, 1]
    channels : channel (muscle group) names
    baseline, maximum : (channels,) integrated EMG levels (the raw unit) mapped to 0 and 1
    notes : what the user should know of the scaling (e.g. that no calibration was given)
    """

    time: np.ndarray
    activity: np.ndarray
    channels: tuple[str, ...]
    baseline: np.ndarray
    maximum: np.ndarray
    notes: tuple[str, ...] = ()


def trapezoid_kernel(rate: float, width: float = WINDOW_S) -> np.ndarray:
    """Unit-area trapezoidal window sampled at ``rate`` Hz (ramps of width/4, flat width/2)."""
    n = max(3, int(round(width * rate)) | 1)
    u = np.linspace(-0.5, 0.5, n)
    w = np.clip((0.5 - np.abs(u)) / 0.25, 0.0, 1.0)
    return w / w.sum()


def integrate(signal: np.ndarray, rate: float, out_rate: float = FRAME_RATE_HZ,
              width: float = WINDOW_S) -> tuple[np.ndarray, np.ndarray]:
    """Rectify and integrate (n, channels) EMG, sampled at ``out_rate`` Hz.

    Returns the output times (s, from the first sample) and the (frames, channels) envelope.
    """
    x = np.asarray(signal, float)
    x = np.abs(x - np.median(x, axis=0))
    kern = trapezoid_kernel(rate, width)
    env = np.column_stack([np.convolve(x[:, c], kern, mode="same") for c in range(x.shape[1])])
    duration = (len(x) - 1) / rate
    t_out = np.arange(int(np.floor(duration * out_rate + 1e-9)) + 1) / out_rate
    t_in = np.arange(len(x)) / rate
    out = np.column_stack([np.interp(t_out, t_in, env[:, c]) for c in range(env.shape[1])])
    return t_out, out


def _check(signal, channels, rate, source):
    x = np.asarray(signal, float)
    if x.ndim != 2 or x.shape[1] != len(channels):
        raise InputError("EMG must be (samples, channels)", source=source, field="channels")
    if not rate > 0:
        raise InputError("sampling rate must be positive", source=source, field="rate")
    if len(x) < int(WINDOW_S * rate) + 2:
        raise InputError("recording shorter than the integration window", source=source,
                         field="time")
    for c, name in enumerate(channels):
        if name.upper() not in MUSCLE_GROUPS:
            raise InputError(f"unknown EMG channel (expected muscle groups such as "
                             f"{', '.join(MUSCLE_GROUPS[:7])})", source=source, field=name)
        bad = ~np.isfinite(x[:, c])
        if bad.any():
            raise InputError(f"non-finite sample at {int(np.nonzero(bad)[0][0])}", source=source,
                             field=name)
    return x


def process_emg(
    signal: np.ndarray,
    rate: float,
    channels: tuple[str, ...] | list[str],
    *,
    out_rate: float = FRAME_RATE_HZ,
    baseline: tuple[float, float] | None = None,
    calibration: np.ndarray | None = None,
    calibration_rate: float | None = None,
    calibration_baseline: tuple[float, float] | None = None,
    source: str | None = None,
) -> EMGActivity:
    """Turn raw EMG into normalised muscle activity (eq. 3's E).

    Parameters
    ----------
    signal : (samples, channels) raw EMG, any unit (volts usually)
    rate : sampling rate of ``signal``, Hz (2500 in the seeds)
    channels : muscle group of each channel
    out_rate : output rate, Hz
    baseline : (start, stop) s of a rest interval in ``signal``, optional
    calibration : (samples, channels) a recording of maximal gestures (same channels), optional;
        its maximum raises the 1-level, and its ``calibration_baseline`` interval, if given,
        sets the 0-level
    """
    channels = tuple(c.upper() for c in channels)
    x = _check(signal, channels, rate, source)
    t, env = integrate(x, rate, out_rate)

    def base_of(e, tt, interval, src):
        if interval is None:
            k = max(1, int(QUIET_FRACTION * len(e)))
            return np.sort(e, axis=0)[:k].mean(axis=0)
        sel = (tt >= interval[0]) & (tt <= interval[1])
        if not sel.any():
            raise InputError(f"baseline interval {interval} holds no samples", source=src,
                             field="baseline")
        return e[sel].mean(axis=0)

    b = base_of(env, t, baseline, source)
    top = env.max(axis=0)
    if calibration is not None:
        crate = calibration_rate or rate
        xc = _check(calibration, channels, crate, "calibration")
        tc, envc = integrate(xc, crate, out_rate)
        top = np.maximum(top, envc.max(axis=0))
        if calibration_baseline is not None:
            b = base_of(envc, tc, calibration_baseline, "calibration")
    span = top - b
    flat = span <= 0
    if flat.any():
        raise InputError("channel has no activity above its baseline", source=source,
                         field=channels[int(np.nonzero(flat)[0][0])])
    act = np.clip((env - b) / span, 0.0, 1.0)
    notes = () if calibration is not None else (
        "EMG scaled without a calibration recording: each channel's activity 1 is its own "
        "maximum in this recording, so a channel that barely moves reaches full activity; "
        "give a recording of maximal gestures (--calibration) to scale to maximal effort",)
    return EMGActivity(t, act, channels, b, top, notes)
