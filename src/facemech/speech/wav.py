"""WAV files: mono audio as float samples in [-1, 1], written as 16-bit PCM."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_path


def write_wav(path: str | os.PathLike, audio: np.ndarray, rate: int) -> Path:
    """Write mono audio as a 16-bit PCM WAV file, atomically.

    Parameters
    ----------
    path : the WAV file to write (its folder is made if missing)
    audio : (samples,) float samples, full scale = 1; values beyond [-1, 1] are clipped
    rate : sample rate (Hz), a positive integer

    Returns
    -------
    The path written.
    """
    from scipy.io import wavfile

    path = Path(path)
    a = np.asarray(audio, dtype=float)
    if a.ndim != 1:
        raise InputError(f"audio must be one channel of samples, got shape {a.shape}",
                         source=path, field="audio")
    if not np.all(np.isfinite(a)):
        raise InputError("audio has non-finite samples", source=path, field="audio")
    if int(rate) != rate or rate <= 0:
        raise InputError(f"sample rate must be a positive whole number of Hz, got {rate!r}",
                         source=path, field="rate")
    pcm = np.round(np.clip(a, -1.0, 1.0) * 32767.0).astype(np.int16)
    with atomic_path(path, suffix=".wav") as tmp:
        wavfile.write(tmp, int(rate), pcm)
    return path


def read_wav(path: str | os.PathLike) -> tuple[np.ndarray, int]:
    """Read a WAV file as mono float samples.

    Integer PCM (8, 16, 24 or 32 bit) is scaled to full scale = 1; float WAV is kept as is.
    Several channels are averaged to one.

    Parameters
    ----------
    path : the WAV file

    Returns
    -------
    audio : (samples,) float64
    rate : sample rate (Hz)
    """
    from scipy.io import wavfile

    path = Path(path)
    if not path.is_file():
        raise InputError("no such audio file", source=path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)  # unknown chunks are fine
            rate, data = wavfile.read(path)
    except (ValueError, OSError, EOFError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"not a readable WAV file ({first})", source=path) from None
    if data.dtype == np.uint8:
        a = (data.astype(float) - 128.0) / 128.0
    elif np.issubdtype(data.dtype, np.integer):
        a = data.astype(float) / float(-np.iinfo(data.dtype).min)
    else:
        a = data.astype(float)
    if a.ndim == 2:
        a = a.mean(axis=1)
    if a.size == 0:
        raise InputError("the WAV file holds no samples", source=path, field="data")
    return a, int(rate)
