"""Phone labels from one notation to another: eSpeak NG mnemonics -> IPA, IPA <-> ARPABET.

:func:`relabel` rewrites an :class:`~facemech.speech.alignment.Alignment`'s phones (times kept).
eSpeak NG -> IPA follows :data:`ESPEAK_IPA` (its English voices; en-us overrides in
:data:`ESPEAK_IPA_EN_US`, any other voice reads the en-gb column), written so that each IPA
label reads back (:func:`facemech.speech.phoneclass.phone_classes`) into the eSpeak code's own
classes: where eSpeak's own IPA would read otherwise, the label departs from it as little as it
can (an r-coloured vowel with the rhotic hook, ``ɑ˞`` for eSpeak's ``ɑːɹ``; docs/stimuli.md
lists them). Stress: eSpeak's ``'`` and ``,`` become IPA's ``ˈ ˌ`` before the phone and
ARPABET's digit 1 or 2 on a vowel (0 on an unstressed one). eSpeak's lone ``;`` (it palatalises
the phone before) has no segment of its own in IPA or ARPABET: it is left out; ``l;`` is
``lʲ``. ARPABET has fewer vowels than IPA: :data:`IPA_ARPABET` maps each IPA vowel to its nearest
(``ɒ`` to ``AA``, ``o`` to ``OW`` ...), so a few eSpeak codes read back into other classes in
ARPABET (:data:`ARPABET_APPROXIMATE`). A label not in a table raises
:class:`~facemech.errors.InputError` naming it: nothing is passed through unconverted.
"""

from __future__ import annotations

import unicodedata
from dataclasses import replace

from ..errors import InputError
from .alignment import Alignment, Segment

__all__ = ["ARPABET_APPROXIMATE", "ARPABET_IPA", "ESPEAK_IPA", "ESPEAK_IPA_EN_US",
           "IPA_ARPABET", "LABEL_NOTATIONS", "arpabet_to_ipa", "espeak_to_ipa",
           "ipa_to_arpabet", "phone_stress", "reads_stress", "relabel"]

#: the notations a command can write its phone labels in (``--phone-labels``)
LABEL_NOTATIONS = ("ipa", "arpabet", "espeak")

#: eSpeak NG English mnemonic -> IPA (en-gb, and every voice but en-us)
ESPEAK_IPA: dict[str, str] = {
    # consonants
    "p": "p", "b": "b", "m": "m", "m-": "m̩", "f": "f", "v": "v", "T": "θ", "D": "ð",
    "t": "t", "d": "d", "n": "n", "s": "s", "z": "z", "t2": "t", "t#": "ɾ", "d#": "ɾ",
    "z#": "z", "n-": "n̩", "?t": "ʔt", "S": "ʃ", "Z": "ʒ", "tS": "tʃ", "dZ": "dʒ",
    "k": "k", "g": "ɡ", "N": "ŋ", "x": "x", "h": "h", "?": "ʔ", "w": "w", "w#": "w",
    "W": "ʍ", "r": "ɹ", "r-": "ɹ", "R": "ɹ", "*": "r", "l": "l", "L": "ɫ", "l-": "l̩",
    "j": "j", "@L": "əl",
    # vowels
    "i:": "iː", "i": "i", "i2": "i", "I": "ɪ", "I2": "ɪ", "I#": "ᵻ", "I2#": "ᵻ", "@#": "ᵻ",
    "u:": "uː", "U": "ʊ", "u": "u",
    "a": "a", "a2": "a", "aa": "a", "A:": "ɑː", "A@": "ɑː", "A#": "ɑ", "a#2": "a",
    "A~": "ɑ̃", "A": "ɑ",
    "e": "e", "E": "ɛ", "E#": "ɛ", "E2": "ɛ", "e#": "e", "e:": "eː", "V": "ʌ", "3:": "ɜː",
    "O": "ɔ", "O2": "ɔ", "O:": "ɔː",
    "0": "ɒ", "0#": "ɒ", "02": "ɒ", "O@": "oː", "o@": "oː", "o:": "oː", "o": "o",
    "O~": "õ", "oU#": "o",
    "@": "ə", "@2": "ə", "@5": "ə", "3": "ə", "a#": "ɐ",
    # diphthongs and triphthongs
    "aI": "aɪ", "aU": "aʊ", "eI": "eɪ", "oU": "oʊ", "OI": "ɔɪ", "e@": "eə", "i@": "iə",
    "i@3": "iə", "I@": "ɪə", "U@": "ʊə", "aI@": "aɪə", "aI3": "aɪə", "aU@": "aʊə",
    "IR": "ɚ", "VR": "ɝ", "ju:": "juː",
}
#: en-us's own values where they differ (eSpeak NG's ph_english_us): unrounded ``0``, the
#: r-coloured vowels with the rhotic hook, TRAP before a voiceless fricative (``aa``)
ESPEAK_IPA_EN_US: dict[str, str] = {
    "a": "æ", "aa": "æ", "0": "ɑː", "0#": "ɑ", "3": "ə˞", "A@": "ɑ˞", "O@": "o˞", "o@": "o˞",
    "e@": "ɛə˞", "i@3": "iə˞", "U@": "ʊə˞", "aI3": "aɪə˞",
}

#: IPA (stress, length, diacritics and the rhotic hook removed) -> ARPABET, without the digit
IPA_ARPABET: dict[str, str] = {
    "p": "P", "b": "B", "m": "M", "f": "F", "v": "V", "θ": "TH", "ð": "DH", "t": "T",
    "d": "D", "n": "N", "s": "S", "z": "Z", "ɾ": "DX", "ʔt": "T", "ʃ": "SH", "ʒ": "ZH",
    "tʃ": "CH", "dʒ": "JH", "k": "K", "ɡ": "G", "g": "G", "ŋ": "NG", "x": "K", "h": "HH",
    "ʔ": "Q", "w": "W", "ʍ": "WH", "ɹ": "R", "r": "R", "l": "L", "ɫ": "L", "j": "Y",
    "əl": "EL", "i": "IY", "ɪ": "IH", "ᵻ": "IX", "u": "UW", "ʊ": "UH", "a": "AA", "æ": "AE",
    "ɑ": "AA", "e": "EH", "ɛ": "EH", "ʌ": "AH", "ɜ": "ER", "ɔ": "AO", "ɒ": "AA", "o": "OW",
    "ə": "AH", "ɐ": "AH", "ɚ": "ER", "ɝ": "ER",
    "aɪ": "AY", "aʊ": "AW", "eɪ": "EY", "oʊ": "OW", "ɔɪ": "OY", "eə": "EH", "ɛə": "EH",
    "iə": "IY", "ɪə": "IH", "ʊə": "UH", "aɪə": "AY", "aʊə": "AW", "ju": "UW",
}
#: ARPABET (CMUdict's 39 and TIMIT's additions) -> IPA; AH0 and ER0 are the unstressed ə and ɚ
ARPABET_IPA: dict[str, str] = {
    "P": "p", "B": "b", "M": "m", "EM": "m̩", "F": "f", "V": "v", "TH": "θ", "DH": "ð",
    "T": "t", "D": "d", "N": "n", "EN": "n̩", "NX": "ɾ̃", "S": "s", "Z": "z", "DX": "ɾ",
    "SH": "ʃ", "ZH": "ʒ", "CH": "tʃ", "JH": "dʒ", "K": "k", "G": "ɡ", "NG": "ŋ", "ENG": "ŋ̍",
    "HH": "h", "HV": "ɦ", "Q": "ʔ", "W": "w", "WH": "ʍ", "R": "ɹ", "L": "l", "EL": "l̩",
    "Y": "j", "IY": "i", "IH": "ɪ", "IX": "ᵻ", "UW": "u", "UH": "ʊ", "UX": "ʉ", "AA": "ɑ",
    "AE": "æ", "EH": "ɛ", "AH": "ʌ", "ER": "ɝ", "AXR": "ɚ", "AO": "ɔ", "AX": "ə",
    "AY": "aɪ", "AW": "aʊ", "EY": "eɪ", "OW": "oʊ", "OY": "ɔɪ",
}
_ARPABET_VOWELS = frozenset("IY IH IX UW UH UX AA AE EH AH ER AXR AO AX AY AW EY OW OY".split())
#: eSpeak codes whose ARPABET label reads into other classes than the code (ARPABET has no
#: such vowel): the mid rounded monophthongs, the centring diphthongs, NURSE, en-gb's LOT
ARPABET_APPROXIMATE = frozenset({
    "0", "0#", "02", "o", "o:", "O@", "o@", "O~", "oU#", "3:", "e@", "i@", "i@3", "I@", "U@",
    "aI@", "aI3", "aU@", "ju:",
})

_IPA_MARKS = "ˈˌ"
_IPA_DROP = frozenset("ːˑ˞ʲ‿͜͡.")
_ESPEAK_STRESS = {"'": "ˈ", ",": "ˌ"}


def _voice_table(voice: str | None) -> dict[str, str]:
    language = (voice or "").split("+", 1)[0].strip().lower()
    return {**ESPEAK_IPA, **ESPEAK_IPA_EN_US} if language.startswith("en-us") else ESPEAK_IPA


def espeak_to_ipa(label: str, voice: str | None = None, *,
                  source: str | None = None) -> str | None:
    """IPA of one eSpeak NG mnemonic (stress as ``ˈ ˌ``), None for eSpeak's lone ``;``.

    Raises InputError (field ``phones``) for a code the tables do not hold.
    """
    text = label.strip()
    stress = ""
    while text and text[0] in "',%=":
        stress = _ESPEAK_STRESS.get(text[0], stress)
        text = text[1:]
    base = text.split("/", 1)[0] if "/" in text and text not in ESPEAK_IPA else text
    if not base.strip(";"):
        return None
    palatal = "ʲ" if base.endswith(";") else ""
    ipa = _voice_table(voice).get(base.rstrip(";"))
    if ipa is None:
        raise InputError(f"no IPA for the eSpeak NG phone {label!r} (voice "
                         f"{voice or 'unknown'}): the table holds the English voices' codes; "
                         "write the labels as espeak", source=source, field="phones")
    return stress + ipa + palatal


def _ipa_core(label: str) -> tuple[str, str]:
    """(stress mark or "", the IPA label without stress, length, hooks, diacritics)."""
    text = label.strip()
    stress = next((c for c in text if c in _IPA_MARKS), "")
    norm = unicodedata.normalize("NFD", text)
    core = "".join(c for c in norm if c not in _IPA_MARKS and c not in _IPA_DROP
                   and unicodedata.category(c) != "Mn")
    return stress, unicodedata.normalize("NFC", core)


def ipa_to_arpabet(label: str, *, source: str | None = None) -> str:
    """ARPABET of one IPA phone label: its nearest phone, a vowel with its stress digit.

    Raises InputError (field ``phones``) for a label :data:`IPA_ARPABET` does not hold.
    """
    stress, core = _ipa_core(label)
    arpa = IPA_ARPABET.get(core)
    if arpa is None:
        raise InputError(f"no ARPABET for the IPA phone {label!r}", source=source,
                         field="phones")
    if arpa not in _ARPABET_VOWELS:
        return arpa
    if core in ("ə", "ɐ", "ɚ"):
        return arpa + "0"  # CMUdict's schwa and r-coloured schwa: AH0, ER0
    if arpa in ("AH", "ER") and not stress:
        return arpa + "2"  # ʌ and ɜ are never unstressed in ARPABET (AH0, ER0 are schwas)
    return arpa + {"ˈ": "1", "ˌ": "2"}.get(stress, "0")


def arpabet_to_ipa(label: str, *, source: str | None = None) -> str:
    """IPA of one ARPABET label (stress digit 1/2 as ``ˈ ˌ``; AH0 ``ə``, ER0 ``ɚ``)."""
    text = label.strip().upper()
    base, digit = (text[:-1], text[-1]) if text[-1:] in "012" else (text, "")
    ipa = ARPABET_IPA.get(base)
    if ipa is None:
        raise InputError(f"no IPA for the ARPABET phone {label!r}", source=source,
                         field="phones")
    if digit == "0" and base in ("AH", "ER"):
        return "ə" if base == "AH" else "ɚ"
    return {"1": "ˈ", "2": "ˌ"}.get(digit, "") + ipa


def _label(seg: Segment, source_notation: str, target: str, voice, src) -> str | None:
    if source_notation == target:
        return seg.label
    ipa = seg.label
    if source_notation == "espeak":
        ipa = espeak_to_ipa(seg.label, voice, source=src)
        if ipa is None:
            return None
    elif source_notation == "arpabet":
        ipa = arpabet_to_ipa(seg.label, source=src)
    return ipa if target == "ipa" else ipa_to_arpabet(ipa, source=src)


def relabel(alignment: Alignment, notation: str) -> Alignment:
    """The alignment with its phones in ``notation`` (:data:`LABEL_NOTATIONS`), times kept.

    eSpeak codes come from eSpeak NG (``alignment.meta["voice"]`` picks the column); IPA and
    ARPABET go either way; nothing becomes eSpeak codes (InputError, field ``phone_labels``).
    """
    if notation not in LABEL_NOTATIONS:
        raise InputError(f"unknown phone labels {notation!r} (expected "
                         f"{', '.join(LABEL_NOTATIONS)})", field="phone_labels")
    if notation == alignment.notation:
        return alignment
    if notation == "espeak":
        raise InputError(f"{alignment.notation} labels cannot be written as eSpeak NG codes "
                         "(only synthesised speech has them)", source=alignment.source,
                         field="phone_labels")
    voice, src = alignment.meta.get("voice"), alignment.source
    phones = []
    for seg in alignment.phones:
        label = _label(seg, alignment.notation, notation, voice, src)
        if label is not None:
            phones.append(Segment(label, seg.start, seg.end))
    return replace(alignment, phones=tuple(phones), notation=notation)


def phone_stress(label: str, notation: str = "espeak") -> str | None:
    """The stress a label marks: eSpeak's ``'``/``,`` before it, IPA's ``ˈ``/``ˌ`` before
    it, ARPABET's digit ``1``/``2`` after it; None where it marks none."""
    t = label.strip()
    if notation == "arpabet":
        return {"1": "primary", "2": "secondary"}.get(t[-1:])
    first, second = ("ˈ", "ˌ") if notation == "ipa" else ("'", ",")
    return "primary" if t.startswith(first) else "secondary" if t.startswith(second) else None


def reads_stress(alignment) -> bool:
    """Whether an alignment's labels carry stress: always in eSpeak's notation, in IPA and
    ARPABET where any label marks it (an alignment with no mark at all is read as unmarked,
    not as wholly unstressed)."""
    if alignment.notation == "espeak":
        return True
    return any(phone_stress(s.label, alignment.notation) is not None for s in alignment.phones)
