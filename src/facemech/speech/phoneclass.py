"""Phone labels in eSpeak NG mnemonics, IPA or ARPABET -> articulatory classes.

A class says what a phone asks of the visible articulators (the lips and the jaw): the place of
a consonant (bilabial, labiodental, ...) or the shape of a vowel (close front spread, close back
rounded, open, ...). :mod:`facemech.speech.visemes` gives each class a target of the face.

A diphthong is a sequence of two (or three) vowel classes, its interval shared between them;
every other phone is one class. Pauses (silence labels) are the class ``"pause"``: the face at
rest.

What is read as neutral rather than rejected (documented in docs/stimuli.md):

- stress, tone and syllable marks around a label (eSpeak ``' , % =``, IPA ``ˈ ˌ .``), length
  marks (IPA ``ː ˑ``), combining diacritics (IPA nasalisation, syllabicity, ...), tie bars, and
  ARPABET's stress digit (but ``AH0`` is the schwa and ``ER0`` the r-coloured schwa);
- eSpeak variant suffixes after ``/`` (``l/2``) and its appended palatal ``;`` (a ``;`` on its
  own, which eSpeak sometimes emits as a phone, has no classes and makes no gesture).

Any other unknown label raises :class:`~facemech.errors.InputError` naming the label.
"""

from __future__ import annotations

import unicodedata

from ..errors import InputError

#: consonant classes: (name, description)
CONSONANT_CLASSES: dict[str, str] = {
    "bilabial": "p b m: the lips closed",
    "labiodental": "f v: the lower lip against the upper teeth",
    "dental": "th (T D): the tongue between the teeth, the jaw nearly closed",
    "alveolar": "t d n s z: the jaw nearly closed, the lips neutral",
    "postalveolar": "sh zh ch j (S Z tS dZ): the lips rounded and a little forward",
    "velar": "k g ng: the jaw a little open, the lips neutral",
    "glottal": "h and the glottal stop: the lips and jaw of the neighbours",
    "w": "w: the lips rounded and protruded, close",
    "r": "r: the lips a little rounded",
    "l": "l: the jaw a little open, the lips neutral",
    "j": "y (j): the lips spread, close",
}
#: vowel classes: (name, description)
VOWEL_CLASSES: dict[str, str] = {
    "close_front_spread": "i: close front, lips spread",
    "close_front_lax": "I (the vowel of \"kit\", /ɪ/, and the end of /eɪ aɪ ɔɪ/): lax, the jaw "
                       "and the lips' spreading halfway from i: to the mid vowels",
    "close_back_rounded": "u: close back, lips rounded and protruded",
    "open": "a: open, the jaw well open",
    "open_rounded": "O: (the vowel of \"thought\", /ɔ/): open, the lips somewhat rounded",
    "mid": "e, E, V, 3: mid, the jaw half open, the lips neutral",
    "mid_rounded": "o: mid back, the lips rounded",
    "schwa": "@: central and short, the jaw a little open",
}
PAUSE = "pause"
#: every class, in table order
CLASSES: tuple[str, ...] = (*CONSONANT_CLASSES, *VOWEL_CLASSES, PAUSE)

_B, _LD, _D, _A, _PA, _V, _G = ("bilabial", "labiodental", "dental", "alveolar", "postalveolar",
                                "velar", "glottal")
_I, _U, _O, _M, _MR, _S = ("close_front_spread", "close_back_rounded", "open", "mid",
                           "mid_rounded", "schwa")
_OR = "open_rounded"
_IL = "close_front_lax"

#: labels that mean silence, in every notation (compared after stripping, case-insensitive)
PAUSE_LABELS = frozenset({"", "_", "_:", "_!", "_^_", "__", "|", "||", "#", "sil", "sp", "spn",
                          "pau", "pause", "<p:>", "<sil>", "h#", "silence"})

# eSpeak NG English mnemonics (phsource/ph_english and the base consonants of the English set)
_ESPEAK: dict[str, tuple[str, ...]] = {
    **dict.fromkeys(("p", "b", "m", "m-"), (_B,)),
    **dict.fromkeys(("f", "v"), (_LD,)),
    **dict.fromkeys(("T", "D"), (_D,)),
    **dict.fromkeys(("t", "d", "n", "s", "z", "t2", "t#", "d#", "z#", "n-", "?t"), (_A,)),
    **dict.fromkeys(("S", "Z", "tS", "dZ"), (_PA,)),
    **dict.fromkeys(("k", "g", "N", "x"), (_V,)),
    **dict.fromkeys(("h", "?"), (_G,)),
    **dict.fromkeys(("w", "w#", "W"), ("w",)),
    **dict.fromkeys(("r", "r-", "R", "*"), ("r",)),
    **dict.fromkeys(("l", "L", "l-"), ("l",)),
    "j": ("j",), "@L": (_S, "l"),
    # vowels
    **dict.fromkeys(("i:", "i", "i2"), (_I,)),
    **dict.fromkeys(("I", "I2", "I#", "I2#", "@#"), (_IL,)),
    **dict.fromkeys(("u:", "U", "u"), (_U,)),
    **dict.fromkeys(("a", "a2", "aa", "A:", "A@", "A#", "a#2", "A~", "A"), (_O,)),
    **dict.fromkeys(("e", "E", "E#", "E2", "e#", "e:", "V", "3:"), (_M,)),
    **dict.fromkeys(("O", "O2", "O:"), (_OR,)),
    **dict.fromkeys(("0", "0#", "02", "O@", "o@", "o:", "o", "O~", "oU#"), (_MR,)),
    **dict.fromkeys(("@", "@2", "@5", "3", "a#"), (_S,)),
    # diphthongs and triphthongs: their parts in order
    "aI": (_O, _IL), "aU": (_O, _U), "eI": (_M, _IL), "oU": (_MR, _U), "OI": (_MR, _IL),
    "e@": (_M, _S), "i@": (_I, _S), "i@3": (_I, _S), "I@": (_IL, _S), "U@": (_U, _S),
    "aI@": (_O, _IL, _S), "aI3": (_O, _IL, _S), "aU@": (_O, _U, _S), "IR": (_S, "r"),
    "VR": (_M, "r"), "ju:": ("j", _U),
}

# ARPABET (CMUdict's 39 phones and the TIMIT additions), without the stress digit
_ARPABET: dict[str, tuple[str, ...]] = {
    **dict.fromkeys(("P", "B", "M", "EM"), (_B,)),
    **dict.fromkeys(("F", "V"), (_LD,)),
    **dict.fromkeys(("TH", "DH"), (_D,)),
    **dict.fromkeys(("T", "D", "N", "S", "Z", "DX", "EN", "NX"), (_A,)),
    **dict.fromkeys(("SH", "ZH", "CH", "JH"), (_PA,)),
    **dict.fromkeys(("K", "G", "NG", "ENG"), (_V,)),
    **dict.fromkeys(("HH", "Q", "HV"), (_G,)),
    **dict.fromkeys(("W", "WH"), ("w",)),
    "R": ("r",), "L": ("l",), "EL": (_S, "l"), "Y": ("j",),
    "IY": (_I,), **dict.fromkeys(("IH", "IX"), (_IL,)),
    **dict.fromkeys(("UW", "UH", "UX"), (_U,)),
    **dict.fromkeys(("AA", "AE"), (_O,)),
    **dict.fromkeys(("EH", "AH"), (_M,)),
    "ER": (_M, "r"), "AXR": (_S, "r"),
    "AO": (_OR,), "AX": (_S,),
    "AY": (_O, _IL), "AW": (_O, _U), "EY": (_M, _IL), "OW": (_MR, _U), "OY": (_MR, _IL),
}

# IPA segments (matched longest first); affricates and diphthongs as written with or without a
# tie bar (tie bars are removed before matching)
_IPA: dict[str, tuple[str, ...]] = {
    **dict.fromkeys(("p", "b", "m", "ɸ", "β"), (_B,)),
    **dict.fromkeys(("f", "v", "ɱ", "ʋ"), (_LD,)),
    **dict.fromkeys(("θ", "ð"), (_D,)),
    **dict.fromkeys(("t", "d", "n", "s", "z", "ɾ", "ɬ", "ʔt"), (_A,)),
    **dict.fromkeys(("ʃ", "ʒ", "tʃ", "dʒ", "ʧ", "ʤ"), (_PA,)),
    **dict.fromkeys(("k", "g", "ɡ", "ŋ", "x", "ɣ"), (_V,)),
    **dict.fromkeys(("h", "ʔ", "ɦ"), (_G,)),
    **dict.fromkeys(("w", "ʍ"), ("w",)),
    **dict.fromkeys(("r", "ɹ", "ɻ", "ʁ"), ("r",)),
    **dict.fromkeys(("l", "ɫ"), ("l",)),
    **dict.fromkeys(("j", "c", "ɟ", "ʝ"), ("j",)),  # palatals (ç decomposes to c)
    **dict.fromkeys(("i", "y", "ʏ", "ɨ"), (_I,)), **dict.fromkeys(("ɪ", "ᵻ"), (_IL,)),
    **dict.fromkeys(("u", "ʊ", "ʉ", "ɯ"), (_U,)),
    **dict.fromkeys(("a", "æ", "ɑ", "ɶ"), (_O,)),
    **dict.fromkeys(("e", "ɛ", "ʌ", "ɜ", "ø", "œ"), (_M,)),
    **dict.fromkeys(("ɝ", "ɜ˞"), (_M, "r")), **dict.fromkeys(("ɚ", "ə˞"), (_S, "r")),
    **dict.fromkeys(("o", "ɒ"), (_MR,)), "ɔ": (_OR,),
    **dict.fromkeys(("ə", "ɐ", "ɘ", "ɵ"), (_S,)),
    "ɔɪ": (_MR, _IL),  # CHOICE starts mid rounded, as eSpeak's OI and ARPABET's OY
}
_IPA_STRIP = frozenset("ˈˌ.ːˑ‿͜͡ʰʲʷˠˤ˞'ˀ")
_IPA_LONGEST = max(len(k) for k in _IPA)


#: eSpeak NG mnemonics whose vowel depends on the English voice: in en-us eSpeak writes ``0``
#: (the vowel of "Bob", "mom", "pot") as unrounded [ɑ] (its IPA output, phsource/ph_english_us),
#: an open vowel; in en-gb as rounded [ɒ], kept with the rounded vowels
_ESPEAK_UNROUNDED_IN = {"0": ("en-us",), "0#": ("en-us",)}


def phone_classes(label: str, notation: str, *, source: str | None = None,
                  voice: str | None = None) -> tuple[str, ...]:
    """The articulatory classes of one phone label, in order.

    Parameters
    ----------
    label : str
        A phone label in ``notation``: an eSpeak NG mnemonic (``"b"``, ``"u:"``, ``"aI"``), IPA
        (``"b"``, ``"uː"``, ``"aɪ"``) or ARPABET (``"B"``, ``"UW1"``, ``"AY0"``).
    notation : {"espeak", "ipa", "arpabet"}
    source : str, optional
        Where the label came from, for the error message.
    voice : str, optional
        The eSpeak NG voice that wrote an ``espeak`` label (e.g. ``"en-us+f3"``): eSpeak's
        ``0`` is the open unrounded [ɑ] in en-us and the rounded [ɒ] elsewhere.

    Returns
    -------
    tuple of str
        One class of :data:`CLASSES` for a consonant, a monophthong or a pause; two or three
        for a diphthong or triphthong (its parts in order); none for eSpeak's bare ``;``.

    Raises
    ------
    InputError
        The label is not a phone of the notation (the message names it).
    """
    raw = label
    text = label.strip()
    if text.lower() in PAUSE_LABELS:
        return (PAUSE,)
    if notation == "espeak":
        found = _espeak(text, voice)
    elif notation == "arpabet":
        found = _arpabet(text)
    elif notation == "ipa":
        found = _ipa(text)
    else:
        raise InputError(f"unknown phone notation {notation!r} (expected espeak, ipa or "
                         "arpabet)", source=source, field="notation")
    if found is None:
        raise InputError(f"unknown {notation} phone label {raw!r}", source=source,
                         field="phones")
    return found


def _espeak(text: str, voice: str | None = None) -> tuple[str, ...] | None:
    t = text.lstrip("',%=")
    if t.lower() in PAUSE_LABELS:
        return (PAUSE,)
    if "/" in t and t not in _ESPEAK:
        t = t.split("/", 1)[0]  # l/2, z/2: a variant of the phoneme before the slash
    if not t.strip(";"):
        return ()  # eSpeak's palatalisation mark on its own: no gesture of its own
    t = t.rstrip(";")
    language = (voice or "").split("+", 1)[0].strip().lower()
    if any(language.startswith(v) for v in _ESPEAK_UNROUNDED_IN.get(t, ())):
        return (_O,)
    return _ESPEAK.get(t)


def _arpabet(text: str) -> tuple[str, ...] | None:
    t = text.upper()
    if t[-1:] in "012":
        base, stress = t[:-1], t[-1]
    else:
        base, stress = t, None
    if base == "AH" and stress == "0":
        return (_S,)  # unstressed AH is schwa
    if base == "ER" and stress == "0":
        return (_S, "r")  # unstressed ER is the r-coloured schwa (AXR)
    return _ARPABET.get(base)


def _ipa(text: str) -> tuple[str, ...] | None:
    norm = unicodedata.normalize("NFD", text)
    chars = "".join(ch for ch in norm
                    if ch not in _IPA_STRIP and unicodedata.category(ch) != "Mn")
    chars = unicodedata.normalize("NFC", chars)
    if not chars:
        return None
    out: list[str] = []
    k = 0
    while k < len(chars):
        for n in range(min(_IPA_LONGEST, len(chars) - k), 0, -1):
            seg = chars[k:k + n]
            if seg in _IPA:
                for c in _IPA[seg]:
                    if not out or out[-1] != c:
                        out.append(c)
                k += n
                break
        else:
            return None
    return tuple(out)
