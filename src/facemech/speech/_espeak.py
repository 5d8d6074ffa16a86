"""eSpeak NG through ctypes: samples and synthesis events for one text.

This file imports nothing from facemech (nor numpy), so that it can also run on its own as a
small worker process: ``python _espeak.py LIBRARY DATA`` reads one JSON request on stdin and
writes one JSON line, then the 16-bit samples, on stdout. eSpeak NG keeps state from one
utterance to the next (the same text comes out a few samples longer or shorter depending on
what was said before in the process), so :func:`facemech.speech.tts.synthesize` uses a fresh
worker per utterance by default, which makes its output depend on its arguments only.

Declarations follow eSpeak NG's speak_lib.h (API revision 12).
"""

from __future__ import annotations

import ctypes
import json
import sys

AUDIO_OUTPUT_SYNCHRONOUS = 2
INITIALIZE_PHONEME_EVENTS = 0x0001
INITIALIZE_DONT_EXIT = 0x8000
CHARS_UTF8 = 1
POS_CHARACTER = 1
EV_END_OF_LIST = 0
EV_WORD = 1
EV_PHONEME = 7
PARAM_RATE = 1
PARAM_PITCH = 3
EE_OK = 0


class _EventId(ctypes.Union):
    _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p),
                ("string", ctypes.c_char * 8)]


class _Event(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint),
                ("text_position", ctypes.c_int), ("length", ctypes.c_int),
                ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                ("user_data", ctypes.c_void_p), ("id", _EventId)]


class _Voice(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char_p), ("languages", ctypes.c_char_p),
                ("identifier", ctypes.c_char_p), ("gender", ctypes.c_ubyte),
                ("age", ctypes.c_ubyte), ("variant", ctypes.c_ubyte), ("xx1", ctypes.c_ubyte),
                ("score", ctypes.c_int), ("spare", ctypes.c_void_p)]


_Callback = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int,
                             ctypes.POINTER(_Event))


class EngineError(Exception):
    """eSpeak NG could not start or could not synthesise; ``kind`` says which request field."""

    def __init__(self, message: str, kind: str = "engine"):
        super().__init__(message)
        self.kind = kind


class Engine:
    """One eSpeak NG instance (the library is global: one per process).

    Parameters
    ----------
    library : path of libespeak-ng
    data : path of the espeak-ng-data folder
    """

    def __init__(self, library: str, data: str):
        lib = ctypes.CDLL(library)
        lib.espeak_Initialize.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p,
                                          ctypes.c_int]
        lib.espeak_Initialize.restype = ctypes.c_int
        lib.espeak_SetSynthCallback.argtypes = [_Callback]
        lib.espeak_SetSynthCallback.restype = None
        lib.espeak_SetVoiceByName.argtypes = [ctypes.c_char_p]
        lib.espeak_SetVoiceByName.restype = ctypes.c_int
        lib.espeak_SetParameter.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int]
        lib.espeak_SetParameter.restype = ctypes.c_int
        lib.espeak_GetParameter.argtypes = [ctypes.c_int, ctypes.c_int]
        lib.espeak_GetParameter.restype = ctypes.c_int
        lib.espeak_Synth.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint,
                                     ctypes.c_int, ctypes.c_uint, ctypes.c_uint,
                                     ctypes.POINTER(ctypes.c_uint), ctypes.c_void_p]
        lib.espeak_Synth.restype = ctypes.c_int
        lib.espeak_ListVoices.argtypes = [ctypes.c_void_p]
        lib.espeak_ListVoices.restype = ctypes.POINTER(ctypes.POINTER(_Voice))
        lib.espeak_Info.argtypes = [ctypes.c_void_p]
        lib.espeak_Info.restype = ctypes.c_char_p
        rate = lib.espeak_Initialize(AUDIO_OUTPUT_SYNCHRONOUS, 0, data.encode(),
                                     INITIALIZE_PHONEME_EVENTS | INITIALIZE_DONT_EXIT)
        if rate <= 0:
            raise EngineError(f"eSpeak NG did not start (data folder {data})")
        self.lib = lib
        self.sample_rate = int(rate)
        self.version = lib.espeak_Info(None).decode()
        self.default_pitch = lib.espeak_GetParameter(PARAM_PITCH, 0)
        self._pcm: list[bytes] = []
        self._events: list[list] = []
        self._callback = _Callback(self._collect)  # must live as long as the library uses it
        lib.espeak_SetSynthCallback(self._callback)

    def _collect(self, wav, n, events) -> int:
        if wav and n > 0:
            self._pcm.append(ctypes.string_at(wav, 2 * n))
        if events:
            i = 0
            while events[i].type != EV_END_OF_LIST:
                e = events[i]
                if e.type in (EV_WORD, EV_PHONEME):
                    label = ""
                    if e.type == EV_PHONEME:
                        label = bytes(e.id.string).split(b"\0")[0].decode("utf-8", "replace")
                    self._events.append([e.type, e.text_position, e.length, e.audio_position,
                                         e.sample, label])
                i += 1
        return 0

    def voices(self) -> list[list[str]]:
        """[language, name] of every installed voice."""
        out = []
        table = self.lib.espeak_ListVoices(None)
        i = 0
        while table[i]:
            v = table[i].contents
            # a priority byte, then a zero-terminated language (repeated; the first is enough)
            lang = (v.languages or b"")[1:].decode("utf-8", "replace")
            out.append([lang, (v.name or b"").decode("utf-8", "replace")])
            i += 1
        return out

    def _voice_file(self, voice: str) -> str:
        """The voice file eSpeak NG's ``SetVoiceByName`` finds for a language or voice name
        (``"en-gb"`` -> ``"gmw/en"``, keeping a ``+variant``): it looks voices up by file name,
        and the language codes that :meth:`voices` lists (en-gb, fr-fr) are not all file names.
        An unknown name is returned as given."""
        base, plus, variant = voice.partition("+")
        table = self.lib.espeak_ListVoices(None)
        i = 0
        while table[i]:
            v = table[i].contents
            lang = (v.languages or b"")[1:].decode("utf-8", "replace")
            name = (v.name or b"").decode("utf-8", "replace")
            if base in (lang, name) and v.identifier:
                return v.identifier.decode("utf-8", "replace") + plus + variant
            i += 1
        return voice

    def run(self, text: str, voice: str, rate_wpm: int, pitch: int | None
            ) -> tuple[bytes, list[list]]:
        """Speak ``text``: (native-endian int16 samples, [type, text_pos, length, ms, sample,
        phoneme] for each word and phoneme event)."""
        if self.lib.espeak_SetVoiceByName(self._voice_file(voice).encode()) != EE_OK:
            raise EngineError(f"unknown voice {voice!r}", kind="voice")
        self.lib.espeak_SetParameter(PARAM_RATE, int(rate_wpm), 0)
        self.lib.espeak_SetParameter(PARAM_PITCH,
                                     self.default_pitch if pitch is None else int(pitch), 0)
        self._pcm, self._events = [], []
        data = text.encode("utf-8") + b"\0"
        status = self.lib.espeak_Synth(data, len(data), 0, POS_CHARACTER, 0, CHARS_UTF8,
                                       None, None)
        pcm, events, self._pcm, self._events = b"".join(self._pcm), self._events, [], []
        if status != EE_OK:
            raise EngineError(f"eSpeak NG failed to synthesise (status {status})")
        return pcm, events


def _main() -> int:
    """Worker: ``_espeak.py LIBRARY DATA`` < request JSON > header JSON line + samples."""
    library, data = sys.argv[1], sys.argv[2]
    req = json.loads(sys.stdin.buffer.read().decode("utf-8"))
    out = sys.stdout.buffer
    try:
        eng = Engine(library, data)
        pcm, events = eng.run(req["text"], req["voice"], req["rate_wpm"], req["pitch"])
        head = {"sample_rate": eng.sample_rate, "version": eng.version, "events": events,
                "n_bytes": len(pcm), "byteorder": sys.byteorder}
    except EngineError as exc:
        head, pcm = {"error": str(exc), "kind": exc.kind}, b""
        if exc.kind == "voice":
            head["voices"] = eng.voices()
    out.write(json.dumps(head).encode("utf-8") + b"\n")
    out.write(pcm)
    out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(_main())
