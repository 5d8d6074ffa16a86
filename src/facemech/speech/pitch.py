"""The voice's fundamental frequency and intensity per frame: a YIN tracker on numpy.

:func:`track_f0` is the YIN estimator of de Cheveigné & Kawahara (2002, J Acoust Soc Am
111:1917): per analysis frame, the difference function of the signal with itself shifted by
each lag, normalised by its cumulative mean, its first dip under a threshold (0.15, the paper's
0.1-0.15) refined by a parabola through its neighbours. A frame is voiced where that dip is
under the threshold and its RMS is within :data:`VOICING_DB` of the loudest frame's.
:func:`intensity_db` is the RMS level per frame in dB (re full scale).

Everything is SI: times in s, frequencies in Hz; the samples are floats (full scale 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["F0_RANGE_HZ", "F0Track", "WINDOW_S", "intensity_db", "track_f0"]

#: Hz, the lowest and highest F0 looked for (an adult's speaking range, with margin)
F0_RANGE_HZ = (60.0, 400.0)
#: s, the integration window of the difference function (two periods of 80 Hz)
WINDOW_S = 0.025
#: the cumulative-mean-normalised difference under which a dip is a period (YIN's threshold)
THRESHOLD = 0.15
#: dB, frames quieter than the loudest by more than this are unvoiced (silence, breath)
VOICING_DB = 35.0


@dataclass(frozen=True)
class F0Track:
    """F0 per frame.

    Attributes
    ----------
    time : (T,) s, the frames' centres
    f0 : (T,) Hz, NaN where unvoiced
    voiced : (T,) bool
    level_db : (T,) dB re full scale, the frame's RMS level (-inf for silence clipped at -120)
    """

    time: np.ndarray
    f0: np.ndarray
    voiced: np.ndarray
    level_db: np.ndarray


def _check(samples, rate) -> np.ndarray:
    x = np.asarray(samples, float)
    if x.ndim != 1 or len(x) == 0:
        raise InputError(f"audio samples of shape {x.shape}: give a mono (n,) array",
                         field="audio")
    if not np.all(np.isfinite(x)):
        raise InputError("audio samples are not finite", field="audio")
    if not (np.isfinite(rate) and rate >= 2 * F0_RANGE_HZ[1] * 4):
        raise InputError(f"audio sample rate {rate} Hz is too low for F0 tracking "
                         f"(at least {8 * F0_RANGE_HZ[1]:.0f} Hz)", field="sample_rate")
    return x


def _windows(x: np.ndarray, rate: float, time: np.ndarray, length: int) -> np.ndarray:
    """(T, length) stretches of ``x`` starting half a window before each time (zero-padded)."""
    half = int(round(WINDOW_S * rate / 2))
    pad = np.concatenate([np.zeros(half + 1), x, np.zeros(length + 1)])
    start = np.clip(np.round(time * rate).astype(int), 0, len(x)) + 1  # in pad: -half
    idx = start[:, None] + np.arange(length)[None, :]
    return pad[idx]


def intensity_db(samples, rate: float, time) -> np.ndarray:
    """RMS level (dB re full scale, floored at -120) over :data:`WINDOW_S` about each time.

    Parameters
    ----------
    samples : (n,) float, full scale 1
    rate : Hz, the sampling rate
    time : (T,) s

    Returns
    -------
    (T,) dB
    """
    x = _check(samples, rate)
    w = int(round(WINDOW_S * rate))
    seg = _windows(x, rate, np.asarray(time, float), w)
    rms = np.sqrt(np.mean(seg ** 2, axis=1))
    return 20.0 * np.log10(np.maximum(rms, 1e-6))


def track_f0(samples, rate: float, time) -> F0Track:
    """YIN F0 at each time (de Cheveigné & Kawahara 2002).

    Parameters
    ----------
    samples : (n,) float, full scale 1
    rate : Hz, the sampling rate (at least 3.2 kHz)
    time : (T,) s, where to estimate (e.g. the video frames)

    Returns
    -------
    F0Track
    """
    x = _check(samples, rate)
    time = np.asarray(time, float)
    w = int(round(WINDOW_S * rate))
    tau_min = int(np.floor(rate / F0_RANGE_HZ[1]))
    tau_max = int(np.ceil(rate / F0_RANGE_HZ[0]))
    seg = _windows(x, rate, time, w + tau_max + 1)
    # d(tau) = sum_j (x_j - x_{j+tau})^2 over the window: e(0) + e(tau) - 2 r(tau)
    n = 1 << int(np.ceil(np.log2(2 * (w + tau_max + 1))))
    head = np.zeros_like(seg)
    head[:, :w] = seg[:, :w]
    r = np.fft.irfft(np.conj(np.fft.rfft(head, n)) * np.fft.rfft(seg, n), n)[:, :tau_max + 1]
    c = np.concatenate([np.zeros((len(seg), 1)), np.cumsum(seg ** 2, axis=1)], axis=1)
    taus = np.arange(tau_max + 1)
    energy = c[:, taus + w] - c[:, taus]  # sum of x^2 over [tau, tau + w)
    d = np.maximum(energy[:, :1] + energy - 2.0 * r, 0.0)
    d[:, 0] = 0.0
    cum = np.cumsum(d[:, 1:], axis=1) / taus[1:]
    cmnd = np.ones_like(d)
    np.divide(d[:, 1:], cum, out=cmnd[:, 1:], where=cum > 0)
    f0 = np.full(len(time), np.nan)
    level = 20.0 * np.log10(np.maximum(np.sqrt(energy[:, 0] / w), 1e-6))
    loud = level > level.max() - VOICING_DB
    for k in np.flatnonzero(loud):
        row = cmnd[k]
        under = np.flatnonzero(row[tau_min:tau_max] < THRESHOLD)
        if len(under) == 0:
            continue
        t = tau_min + under[0]
        while t + 1 < tau_max and row[t + 1] < row[t]:  # down to the dip's bottom
            t += 1
        a, b, cc = row[t - 1], row[t], row[t + 1]
        den = a - 2 * b + cc
        shift = 0.5 * (a - cc) / den if den > 0 else 0.0
        f0[k] = rate / (t + float(np.clip(shift, -1, 1)))
    voiced = np.isfinite(f0)
    return F0Track(time=time, f0=f0, voiced=voiced, level_db=level)
