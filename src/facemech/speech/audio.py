"""Audio for stimuli: WAV in and out, shifting by whole samples, time stretching, onsets.

WAV in and out are :mod:`facemech.speech.wav`'s, the one reader and writer of WAV files:
:func:`read_wav` and :func:`write_wav` here are its :func:`~facemech.speech.wav.read_audio` and
:func:`~facemech.speech.wav.write_audio` (samples as stored), and :class:`Audio` is its class.

:class:`Audio` holds samples (n, channels) in the file's own sample type, so a shift or a trim
writes back exactly the samples it read. Times are in seconds, offsets in ms at the edges.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .wav import Audio
from .wav import read_audio as read_wav
from .wav import write_audio as write_wav

__all__ = ["Audio", "fit_length", "onset", "peak", "read_wav", "shift", "time_stretch",
           "write_wav"]


def shift(audio: Audio, seconds: float, *, length: int | None = None) -> tuple[Audio, int]:
    """Move the sound later (``seconds`` > 0) or earlier (< 0) by whole samples.

    Later: silence (zeros) is put in front; earlier: the first samples are dropped. The result
    then has ``length`` samples (default: the input's), cut at the end or padded with silence.

    Returns
    -------
    (Audio, samples) : the shifted sound and the shift in samples (``round(seconds * rate)``)
    """
    k = int(round(seconds * audio.rate))
    n = len(audio.samples) if length is None else int(length)
    x = audio.samples
    zeros = np.zeros((max(k, 0), x.shape[1]), x.dtype)
    moved = np.concatenate([zeros, x]) if k >= 0 else x[-k:]
    if len(moved) >= n:
        moved = moved[:n]
    else:
        moved = np.concatenate([moved, np.zeros((n - len(moved), x.shape[1]), x.dtype)])
    return audio.with_samples(moved), k


def fit_length(audio: Audio, seconds: float) -> Audio:
    """Cut or pad (silence) the sound to ``seconds``."""
    return shift(audio, 0.0, length=int(round(seconds * audio.rate)))[0]


def time_stretch(audio: Audio, factor: float, *, method: str = "stretch",
                 frame_s: float = 0.04, tolerance_s: float = 0.01) -> Audio:
    """Make the sound ``factor`` times as long.

    Parameters
    ----------
    factor : new duration / old duration (> 0)
    method : ``stretch``
        WSOLA (waveform-similarity overlap-add; Verhelst & Roelands 1993): Hann frames of
        ``frame_s`` overlap by half in the output; each is taken from the input near its
        nominal place (within ``tolerance_s``) where it best continues the previous one, so
        the pitch and the spectrum stay and the tempo changes.
        ``resample``: played slower or faster (varispeed): pitch falls by the factor.
    """
    if not factor > 0:
        raise InputError("the time scale must be positive", field="time_scale")
    if method == "resample":
        from fractions import Fraction

        from scipy.signal import resample_poly

        fr = Fraction(factor).limit_denominator(1000)
        y = resample_poly(audio.samples.astype(float), fr.numerator, fr.denominator, axis=0)
        return audio.with_samples(_to_dtype(y, audio.samples.dtype))
    if method != "stretch":
        raise InputError(f"unknown audio time-scaling {method!r} (stretch, resample or none)",
                         field="time_scale_audio")
    if abs(factor - 1.0) < 1e-12:
        return audio
    return audio.with_samples(_to_dtype(_wsola(audio.samples.astype(float), audio.rate, factor,
                                               frame_s, tolerance_s), audio.samples.dtype))


def _to_dtype(y: np.ndarray, dtype) -> np.ndarray:
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        return np.clip(np.round(y), info.min, info.max).astype(dtype)
    return y.astype(dtype)


def _wsola(x: np.ndarray, rate: int, factor: float, frame_s: float,
           tolerance_s: float) -> np.ndarray:
    from scipy.signal import correlate

    n = max(16, int(round(frame_s * rate)) // 2 * 2)
    hop = n // 2
    tol = max(1, int(round(tolerance_s * rate)))
    win = np.sin(np.pi * np.arange(n) / n) ** 2  # periodic Hann: halves overlap to 1
    out_len = int(round(len(x) * factor))
    frames = out_len // hop + 3
    pad = n + tol + int(np.ceil(hop / factor))  # frame 0 lies a hop before the start
    xp = np.concatenate([np.zeros((pad, x.shape[1])), x, np.zeros((pad + n * 2 + int(
        frames * hop / factor), x.shape[1]))])
    mono = xp.mean(axis=1)
    y = np.zeros((frames * hop + n, x.shape[1]))
    prev = pad  # where the previous frame was taken from (in xp)
    for k in range(frames):
        nominal = pad + int(round((k - 1) * hop / factor))
        if k == 0:
            start = nominal
        else:
            natural = mono[prev + hop: prev + hop + n]  # what would follow the last frame
            lo = max(nominal - tol, 0)
            region = mono[lo: nominal + tol + n]
            c = correlate(region, natural, mode="valid")
            start = lo + int(np.argmax(c)) if np.any(natural) and c.size else nominal
        y[k * hop: k * hop + n] += win[:, None] * xp[start: start + n]
        prev = start
    return y[hop: hop + out_len]  # output time 0 is frame 1's start: full overlap-add


def onset(audio: Audio, *, fraction: float = 0.1, window_s: float = 0.01) -> float:
    """The first time (s) the sound's RMS envelope (``window_s`` moving window) reaches
    ``fraction`` of its maximum: the acoustic onset, e.g. a stop's release burst."""
    env = _envelope(audio, window_s)
    if not env.max() > 0:
        raise InputError("the audio is silent: it has no onset", source=audio.source,
                         field="audio")
    return float(np.argmax(env >= fraction * env.max())) / audio.rate


def peak(audio: Audio, *, window_s: float = 0.01) -> float:
    """The time (s) of the RMS envelope's maximum (``window_s`` moving window)."""
    return float(np.argmax(_envelope(audio, window_s))) / audio.rate


def _envelope(audio: Audio, window_s: float) -> np.ndarray:
    x = audio.mono()
    w = max(1, int(round(window_s * audio.rate)))
    c = np.concatenate([[0.0], np.cumsum(x * x)])
    idx = np.arange(len(x))
    lo = np.clip(idx - w // 2, 0, len(x))
    hi = np.clip(idx + w - w // 2, 0, len(x))
    return np.sqrt(np.maximum(c[hi] - c[lo], 0.0) / np.maximum(hi - lo, 1))
