"""Text to speech with eSpeak NG: audio and a word and phone alignment from synthesis events.

eSpeak NG comes from the ``espeakng-loader`` package (the ``speech`` extra), which ships the
shared library and its data. The library is driven through ctypes in synchronous retrieval
mode: a callback receives the 16-bit samples and the synthesis events (phoneme events give
eSpeak's mnemonic and its first sample, word events the word's place in the text).

The alignment (notation ``"espeak"``): each phone runs from its event to the next phone's;
pauses (mnemonics starting with ``_``) are gaps; a word's first stop or affricate
(:func:`_has_closure`) starts at the word's event when that comes earlier (eSpeak marks a stop's
release), and a phone after at least 10 ms of digital silence starts where the silence starts
(a bilabial's lips shut at its middle); labels keep eSpeak's stress marks (``'``, ``,``).

eSpeak NG carries state from one utterance to the next (the same text a few samples longer or
shorter), so by default each call runs it in a fresh worker process and the audio depends on
the arguments only, bit for bit; ``isolated=False`` uses one engine in this process (a lock
makes threads take turns). Details: docs/stimuli.md, "What eSpeak NG gives".
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FacemechError, InputError
from .alignment import Alignment, Segment
from .wav import read_wav, write_wav

__all__ = ["Speech", "check_variant", "synthesize", "variants", "voices", "write_wav", "read_wav",
           "RATE_RANGE_WPM"]

RATE_RANGE_WPM = (80, 450)
"""eSpeak NG's speaking rates (words per minute), ``espeakRATE_MINIMUM`` to ``_MAXIMUM``."""

_EV_WORD = 1
_WORKER = Path(__file__).with_name("_espeak.py")
_COMMON_VOICES = ("en-us", "en-gb", "fr-fr", "de", "es", "it", "nl", "pt", "ja", "cmn")


@dataclass(frozen=True)
class Speech:
    """Synthesised speech.

    Attributes
    ----------
    audio : (samples,) float32 mono samples, full scale = 1
    sample_rate : Hz (22050 for eSpeak NG)
    alignment : words and phones (eSpeak mnemonics) with times (s) from the audio's start
    """

    audio: np.ndarray
    sample_rate: int
    alignment: Alignment

    @property
    def duration(self) -> float:
        """Length of the audio (s)."""
        return len(self.audio) / self.sample_rate


def _paths() -> tuple[str, str]:
    try:
        import espeakng_loader
    except ImportError:
        raise FacemechError("text to speech needs espeakng-loader "
                            "(pip install 'facemech[speech]')") from None
    return espeakng_loader.get_library_path(), espeakng_loader.get_data_path()


_ENGINE = None
_LOCK = threading.Lock()


def _engine():
    """The process's one in-process engine (made on first use; hold :data:`_LOCK`)."""
    global _ENGINE
    if _ENGINE is None:
        from . import _espeak

        try:
            _ENGINE = _espeak.Engine(*_paths())
        except _espeak.EngineError as exc:
            raise FacemechError(str(exc)) from None
    return _ENGINE


def voices() -> list[tuple[str, str]]:
    """The installed eSpeak NG voices as (language, name) pairs, e.g. ``("en-us", ...)``."""
    with _LOCK:
        return [tuple(v) for v in _engine().voices()]


def variants() -> list[str]:
    """The voice variants eSpeak NG has: the names that may follow ``+`` in a voice (``f3``,
    ``m1``, ``klatt``; a number N is ``mN`` below 10 and ``f(N-10)`` from 10 on)."""
    folder = Path(_paths()[1]) / "voices" / "!v"
    try:
        return sorted(p.name for p in folder.iterdir() if p.is_file())
    except OSError:
        raise FacemechError(f"eSpeak NG's voice variants are missing ({folder})") from None


def check_variant(voice: str) -> None:
    """Refuse (InputError, field ``voice``) a ``+variant`` that eSpeak NG does not have: it
    would speak with the plain voice and say nothing. A numeric variant is eSpeak's shorthand
    (see :func:`variants`). The voice itself is checked when it speaks."""
    base, plus, variant = str(voice).strip().partition("+")
    if not plus:
        return
    if not base.strip():
        raise InputError(f"--voice {voice!r}: no voice before the '+{variant}'", field="voice")
    have = variants()
    name = variant
    if variant[:1].isdigit():
        digits = variant[:len(variant) - len(variant.lstrip("0123456789"))]
        number = int(digits)
        name = "" if variant != digits or number == 0 else \
            f"m{number}" if number < 10 else f"f{number - 10}"
    if name not in have:
        raise InputError(f"--voice {voice!r}: eSpeak NG has no voice variant {variant!r}; "
                         f"it has {', '.join(have)}", field="voice")


def _voice_error(voice: str, table) -> InputError:
    langs = sorted({lang for lang, _ in table})
    common = [v for v in _COMMON_VOICES if v in langs]
    return InputError(f"unknown voice {voice!r} (e.g. {', '.join(common)}; {len(langs)} "
                      "languages in all, see facemech.speech.tts.voices())", field="voice")


def _run_here(text, voice, rate_wpm, pitch):
    from . import _espeak

    with _LOCK:
        eng = _engine()
        try:
            pcm, events = eng.run(text, voice, rate_wpm, pitch)
        except _espeak.EngineError as exc:
            if exc.kind == "voice":
                raise _voice_error(voice, eng.voices()) from None
            raise FacemechError(str(exc)) from None
        return (np.frombuffer(pcm, dtype=np.int16), events, eng.sample_rate,
                eng.version)


def _run_worker(text, voice, rate_wpm, pitch, timeout: float = 120.0):
    library, data = _paths()
    request = json.dumps({"text": text, "voice": voice, "rate_wpm": rate_wpm, "pitch": pitch})
    try:
        run = subprocess.run([sys.executable, "-I", str(_WORKER), library, data],
                             input=request.encode("utf-8"), capture_output=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        raise FacemechError(f"eSpeak NG did not finish within {timeout:g} s") from None
    line, _, pcm = run.stdout.partition(b"\n")
    try:
        head = json.loads(line.decode("utf-8"))
    except ValueError:
        err = run.stderr.decode("utf-8", "replace").strip().splitlines()
        raise FacemechError("eSpeak NG stopped (status "
                            f"{run.returncode}{': ' + err[-1] if err else ''})") from None
    if "error" in head:
        if head["kind"] == "voice":
            raise _voice_error(voice, head["voices"])
        raise FacemechError(head["error"])
    if len(pcm) != head["n_bytes"]:
        raise FacemechError(f"eSpeak NG's worker sent {len(pcm)} of {head['n_bytes']} bytes")
    dtype = np.dtype(np.int16).newbyteorder("<" if head["byteorder"] == "little" else ">")
    return (np.frombuffer(pcm, dtype=dtype).astype(np.int16), head["events"],
            head["sample_rate"], head["version"])


def synthesize(text: str, *, voice: str = "en-us", rate_wpm: int = 160,
               pitch: int | None = None, isolated: bool = True) -> Speech:
    """Speak ``text`` with eSpeak NG; return the audio and its word and phone alignment.

    Parameters
    ----------
    text : what to say (UTF-8 text; punctuation shapes pauses and intonation)
    voice : an eSpeak NG voice or language name, e.g. ``"en-us"``, ``"en-gb"``, ``"fr-fr"``,
        with an optional variant (``"en-us+f3"``); see :func:`voices`
    rate_wpm : speaking rate, words per minute, 80 to 450 (eSpeak's default is 175)
    pitch : base pitch on eSpeak's 0-100 scale (50 is usual); None keeps the voice's
    isolated : run eSpeak in a fresh worker process (the default; output depends on the
        arguments only) or in this process (faster, but see the module's notes)

    Returns
    -------
    Speech
        ``audio`` (samples,) float32 at ``sample_rate`` (Hz); ``alignment`` with notation
        ``"espeak"``, times in s, ``meta`` with the voice, rate, pitch and eSpeak's version.

    Raises
    ------
    InputError
        Empty text (field ``text``), an unknown voice or voice variant (``voice``), a rate
        outside 80-450 wpm (``rate_wpm``), a pitch outside 0-100 (``pitch``).
    """
    if not isinstance(text, str) or not text.strip():
        raise InputError("nothing to say: the text is empty", field="text")
    if "\0" in text:
        raise InputError("the text holds a NUL character", field="text")
    lo, hi = RATE_RANGE_WPM
    if isinstance(rate_wpm, bool) or not (isinstance(rate_wpm, int | float)
                                          and lo <= rate_wpm <= hi):
        raise InputError(f"rate must lie in {lo}-{hi} words per minute, got {rate_wpm!r}",
                         field="rate_wpm")
    if pitch is not None and (isinstance(pitch, bool) or not (isinstance(pitch, int | float)
                                                              and 0 <= pitch <= 100)):
        raise InputError(f"pitch must lie in 0-100 (50 is usual), got {pitch!r}", field="pitch")
    if not isinstance(voice, str) or not voice.strip():
        raise InputError("no voice given", field="voice")
    voice, rate_wpm = voice.strip(), int(round(rate_wpm))
    check_variant(voice)
    pitch = None if pitch is None else int(round(pitch))
    run = _run_worker if isolated else _run_here
    pcm, events, rate, version = run(text, voice, rate_wpm, pitch)
    audio = pcm.astype(np.float32) / np.float32(32768.0)
    meta = {"voice": voice, "rate_wpm": rate_wpm, "pitch": pitch,
            "engine": f"eSpeak NG {version}", "sample_rate_hz": rate, "text": text}
    alignment = _alignment(text, events, pcm, rate, meta)
    if not alignment.phones:
        raise InputError(f"eSpeak NG found nothing to say in {text!r}", field="text")
    return Speech(audio=audio, sample_rate=rate, alignment=alignment)


def _event_time(audio_ms: int, sample: int, rate: int) -> float:
    """The event's time (s): its sample where that agrees with its ms position, else the ms."""
    if sample > 0 and abs(sample * 1000.0 / rate - audio_ms) < 2.0:
        return sample / rate
    return audio_ms / 1000.0


CLOSURE_MIN_S = 0.010
"""Shortest run of digital silence before a phone that is taken as its closure (s)."""


def _has_closure(label: str) -> bool:
    """Whether an eSpeak phoneme mnemonic is a stop or an affricate, whose closure comes
    before its event: p b t d k g and their variants (``t2``, ``t#``, ``d#``), ``tS``,
    ``dZ``; the stress marks are ignored (θ ð are ``T D``, upper case)."""
    base = label.lstrip("',%=")
    return base[:1] in ("p", "b", "t", "d", "k", "g")


def _alignment(text: str, events: list[tuple], pcm: np.ndarray, rate: int,
               meta: dict) -> Alignment:
    """Words and phones from eSpeak's word and phoneme events (see the module's notes).

    ``pcm`` (samples,) int16 is used only to find the silent closures of stops inside words.
    """
    duration = len(pcm) / rate
    # (label, start, word index or None for a pause), in event order
    marks: list[list] = []
    words: list[dict] = []
    for kind, pos, length, ms, sample, label in events:
        t = min(_event_time(ms, sample, rate), duration)
        if kind == _EV_WORD:
            words.append({"text": text[max(pos - 1, 0):max(pos - 1, 0) + length],
                          "event": t, "phones": []})
        elif label.startswith("_") or not label:
            marks.append([label, t, None])
        else:
            w = len(words) - 1 if words else None
            marks.append([label, t, w])
            if w is not None:
                words[w]["phones"].append(len(marks) - 1)
    # a word-initial stop's closure lies between the word's event and the phone's event
    for w in words:
        if w["phones"]:
            k = w["phones"][0]
            floor = marks[k - 1][1] if k > 0 else 0.0
            if _has_closure(marks[k][0]) and floor <= w["event"] < marks[k][1]:
                marks[k][1] = w["event"]
    # a stop inside a word (the second /p/ of "puppy") follows its closure: eSpeak writes the
    # closure as digital silence at the end of the previous phone; give it to the stop
    quiet = np.abs(pcm.astype(np.int32)) <= 2
    tail, shortest = int(0.0005 * rate), int(CLOSURE_MIN_S * rate)
    for k in range(1, len(marks)):
        if marks[k][2] is None or marks[k - 1][2] is None:
            continue
        s = min(int(round(marks[k][1] * rate)), len(pcm))
        back = np.nonzero(quiet[max(s - tail, 0):s])[0]
        if not back.size:
            continue
        e = max(s - tail, 0) + back[-1] + 1  # one past the silent run's last sample
        loud = np.nonzero(~quiet[:e])[0]
        st = loud[-1] + 1 if loud.size else 0
        floor = marks[k - 1][1] + CLOSURE_MIN_S
        if e - st >= shortest and st / rate < marks[k][1]:
            marks[k][1] = max(st / rate, min(floor, marks[k][1]))
    phones: list[Segment] = []
    spans: dict[int, list[float]] = {}
    for k, (label, start, w) in enumerate(marks):
        if w is None:
            continue
        end = marks[k + 1][1] if k + 1 < len(marks) else duration
        end = max(end, start)
        phones.append(Segment(label, start, end))
        span = spans.setdefault(w, [start, end])
        span[1] = end
    word_segs = tuple(Segment(words[w]["text"], s, e) for w, (s, e) in sorted(spans.items()))
    return Alignment(words=word_segs, phones=tuple(phones), notation="espeak",
                     duration=duration, source="espeak", meta=meta)
