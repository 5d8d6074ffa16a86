"""The voice's fundamental frequency and intensity per frame: Praat's pitch, YIN as a fallback.

:func:`track_f0` asks Praat (praat-parselmouth, the ``speech`` extra) for its autocorrelation
pitch, "To Pitch (ac)" (Boersma 1993, Proc Inst Phonetic Sci Amsterdam 17:97): per 10-ms frame,
the autocorrelation of the Hanning-windowed signal divided by the window's own, its peaks as
candidates, and a Viterbi path through them with Praat's standard costs
(:data:`PRAAT_AC`). The pitch range is the manual's standard 75-500 Hz for adult speech (Praat
manual, Intro 4.2: 75-300 Hz suits most low voices, 100-500 Hz most high ones).
Without parselmouth it falls back to YIN (de Cheveigné & Kawahara 2002, J Acoust Soc Am
111:1917; :data:`YIN_RANGE_HZ`, threshold :data:`THRESHOLD`), which finds fewer voiced frames
than Praat on running speech (it agrees in F0 where both find voice). :func:`intensity_db` is
the RMS level per frame in dB (re full scale). Everything is SI: s, Hz; samples full scale 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["F0_RANGE_HZ", "F0Track", "METHODS", "PRAAT_AC", "WINDOW_S", "f0_method",
           "intensity_db", "track_f0"]

#: Hz, Praat's pitch floor and ceiling (the manual's standard range for speech)
F0_RANGE_HZ = (75.0, 500.0)
#: Praat's "To Pitch (ac)" settings: its standard values, the range above; time step
#: 0.75 / floor (10 ms), window three periods of the floor (40 ms)
PRAAT_AC = {"time_step": 0.75 / F0_RANGE_HZ[0], "pitch_floor": F0_RANGE_HZ[0],
            "max_number_of_candidates": 15, "very_accurate": False, "silence_threshold": 0.03,
            "voicing_threshold": 0.45, "octave_cost": 0.01, "octave_jump_cost": 0.35,
            "voiced_unvoiced_cost": 0.14, "pitch_ceiling": F0_RANGE_HZ[1]}
#: the trackers: Praat's autocorrelation (default where parselmouth imports) and YIN
METHODS = ("praat", "yin")
#: Hz, the lowest and highest F0 YIN looks for (an adult's speaking range, with margin)
YIN_RANGE_HZ = (60.0, 400.0)
#: s, the integration window of YIN's difference function and of the level (two periods of
#: 80 Hz)
WINDOW_S = 0.025
#: the cumulative-mean-normalised difference under which a dip is a period (YIN's threshold)
THRESHOLD = 0.15
#: dB, YIN: frames quieter than the loudest by more than this are unvoiced (silence, breath)
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
    method : the tracker that made it (one of :data:`METHODS`)
    """

    time: np.ndarray
    f0: np.ndarray
    voiced: np.ndarray
    level_db: np.ndarray
    method: str = "praat"


def f0_method() -> str:
    """The default tracker: ``"praat"`` where praat-parselmouth imports, else ``"yin"``."""
    try:
        import parselmouth  # noqa: F401
    except ImportError:
        return "yin"
    return "praat"


def _check(samples, rate) -> np.ndarray:
    x = np.asarray(samples, float)
    if x.ndim != 1 or len(x) == 0:
        raise InputError(f"audio samples of shape {x.shape}: give a mono (n,) array",
                         field="audio")
    if not np.all(np.isfinite(x)):
        raise InputError("audio samples are not finite", field="audio")
    if not (np.isfinite(rate) and rate >= 8 * F0_RANGE_HZ[1]):
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


def track_f0(samples, rate: float, time, *, method: str | None = None) -> F0Track:
    """F0 and voicing at each time: Praat's autocorrelation pitch (or YIN; module doc).

    Parameters
    ----------
    samples : (n,) float, full scale 1
    rate : Hz, the sampling rate (at least 4 kHz)
    time : (T,) s, where to estimate (e.g. the video frames)
    method : ``"praat"``, ``"yin"``, or None: :func:`f0_method` (Praat where it imports)

    Returns
    -------
    F0Track
        Praat's frames sampled at ``time``: voiced where the nearest frame is, F0 linear
        between two voiced frames (else the nearest's); unvoiced outside the frames.
    """
    x = _check(samples, rate)
    time = np.asarray(time, float)
    method = f0_method() if method is None else method
    if method not in METHODS:
        raise InputError(f"unknown F0 tracker {method!r} (expected {', '.join(METHODS)})",
                         field="f0_method")
    level = intensity_db(x, rate, time)
    f0 = _praat(x, rate, time) if method == "praat" else _yin(x, rate, time, level)
    return F0Track(time=time, f0=f0, voiced=np.isfinite(f0), level_db=level, method=method)


def _praat(x: np.ndarray, rate: float, time: np.ndarray) -> np.ndarray:
    """(T,) Hz or NaN: Praat's "To Pitch (ac)" (:data:`PRAAT_AC`) sampled at ``time``."""
    try:
        import parselmouth
    except ImportError:
        raise InputError("Praat's pitch needs praat-parselmouth (pip install "
                         "'facemech[speech]'), or choose the F0 tracker yin",
                         field="f0_method") from None
    f0 = np.full(len(time), np.nan)
    if len(x) / rate <= 3.0 / PRAAT_AC["pitch_floor"]:  # shorter than one analysis window
        return f0
    pitch = parselmouth.Sound(x, sampling_frequency=float(rate)).to_pitch_ac(**PRAAT_AC)
    frames = np.asarray(pitch.xs(), float)
    hz = np.asarray(pitch.selected_array["frequency"], float)
    hz[hz <= 0] = np.nan
    if len(frames) == 0:
        return f0
    step = PRAAT_AC["time_step"]
    pos = (time - frames[0]) / step
    inside = (pos >= -0.5) & (pos <= len(frames) - 0.5)
    near = np.clip(np.round(pos).astype(int), 0, len(frames) - 1)
    lo = np.clip(np.floor(pos).astype(int), 0, len(frames) - 1)
    hi = np.minimum(lo + 1, len(frames) - 1)
    frac = np.clip(pos - lo, 0.0, 1.0)
    between = hz[lo] + frac * (hz[hi] - hz[lo])
    value = np.where(np.isfinite(between), between, hz[near])
    voiced = inside & np.isfinite(hz[near])
    f0[voiced] = value[voiced]
    return f0


def _yin(x: np.ndarray, rate: float, time: np.ndarray, level_db: np.ndarray) -> np.ndarray:
    """(T,) Hz or NaN: YIN F0 at each time (de Cheveigné & Kawahara 2002)."""
    w = int(round(WINDOW_S * rate))
    tau_min = int(np.floor(rate / YIN_RANGE_HZ[1]))
    tau_max = int(np.ceil(rate / YIN_RANGE_HZ[0]))
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
    loud = level_db > level_db.max() - VOICING_DB
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
    return f0
