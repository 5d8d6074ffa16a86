"""WAV files, the one reader and writer of them: the samples as stored (:func:`read_samples`,
:func:`write_samples`), as an :class:`Audio` (:func:`read_audio`, :func:`write_audio`, which
:mod:`facemech.speech.audio` gives as its ``read_wav`` and ``write_wav``), and mono audio as float
samples in [-1, 1], written as 16-bit PCM (:func:`read_wav`, :func:`write_wav`)."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError, missing_input


@dataclass(frozen=True)
class Audio:
    """Sampled sound: ``samples`` (n, channels) in the file's dtype, ``rate`` (Hz)."""

    samples: np.ndarray
    rate: int
    source: str | None = None

    @property
    def duration(self) -> float:
        """Length, s."""
        return len(self.samples) / self.rate

    def mono(self) -> np.ndarray:
        """The channels' mean as float64 (n,), full scale 1 for integer samples."""
        x = self.samples.astype(float)
        if np.issubdtype(self.samples.dtype, np.integer):
            x /= float(np.iinfo(self.samples.dtype).max)
        return x.mean(axis=1)

    def with_samples(self, samples: np.ndarray) -> Audio:
        return Audio(np.asarray(samples).astype(self.samples.dtype, copy=False), self.rate,
                     self.source)


def read_audio(path: str | os.PathLike) -> Audio:
    """Read a WAV file (PCM 8/16/24/32-bit or float), keeping its samples as stored."""
    data, rate = read_samples(path)
    return Audio(data, rate, str(path))


def write_audio(path: str | os.PathLike, audio: Audio) -> Path:
    """Write ``audio`` as WAV atomically, in its own sample type."""
    data = audio.samples[:, 0] if audio.samples.shape[1] == 1 else audio.samples
    return write_samples(path, data, audio.rate)


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
    return write_samples(path, pcm, int(rate))


def write_samples(path: str | os.PathLike, samples: np.ndarray, rate: int) -> Path:
    """Write samples ((n,) or (n, channels), in their own sample type) as WAV, atomically."""
    from scipy.io import wavfile

    path = Path(path)
    with atomic_path(path, suffix=".wav") as tmp:
        wavfile.write(tmp, int(rate), np.asarray(samples))
    return path


def read_samples(path: str | os.PathLike) -> tuple[np.ndarray, int]:
    """The samples of a WAV file as stored: ((n, channels) in the file's type, rate Hz)."""
    from scipy.io import wavfile

    path = Path(path)
    if not path.is_file():
        if not path.exists():
            raise InputError("no such audio file", source=path)
        raise missing_input(path, what="WAV file")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)  # unknown chunks are fine
            rate, data = wavfile.read(path)
    except Exception as exc:  # scipy's parser raises many kinds on a damaged file (ValueError,
        # struct.error, EOFError, even UnboundLocalError): all mean "not readable"
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"not a readable WAV file ({first})", source=path) from None
    data = np.asarray(data)
    if data.ndim == 1:
        data = data[:, None]
    if len(data) == 0:
        raise InputError("the WAV file holds no samples", source=path, field="data")
    if not rate > 0:
        raise InputError(f"sample rate {rate} Hz", source=path, field="rate")
    return data, int(rate)


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
    data, rate = read_samples(path)
    if data.dtype == np.uint8:
        a = (data.astype(float) - 128.0) / 128.0
    elif np.issubdtype(data.dtype, np.integer):
        a = data.astype(float) / float(-np.iinfo(data.dtype).min)
    else:
        a = data.astype(float)
    return a.mean(axis=1), rate


def check_audio(path: str | os.PathLike | None, field: str = "audio") -> float | None:
    """Check a WAV file before any long work that will use it (reading it whole, which is
    quick): it must exist, be a readable WAV and hold some sound.

    Parameters
    ----------
    path : the WAV file (None: nothing to check)
    field : the option or column that gave it, for the message

    Returns
    -------
    Its length in s (None for no file).

    Raises
    ------
    InputError
        Naming the file and ``field`` when the file is missing, not a WAV, empty or silent.
    """
    if path is None:
        return None
    try:
        data, rate = read_samples(path)
    except InputError as exc:
        raise InputError(exc.message, source=str(path), field=field) from None
    if not np.any(data):
        raise InputError("the WAV file is silent (every sample is zero)", source=str(path),
                         field=field)
    return len(data) / rate
