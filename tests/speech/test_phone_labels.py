"""Phone labels in IPA (and ARPABET on request) in what facemech writes, eSpeak NG's codes in a
tier of their own, and alignments read in any of the three into the same phone classes
(facemech.speech.phone_labels, alignment_io, speak --phone-labels)."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.speech import phone_labels as L
from facemech.speech.alignment import Alignment, Segment
from facemech.speech.alignment_io import (
    ESPEAK_TIER,
    read_alignment_csv,
    read_textgrid,
    write_alignment_csv,
    write_textgrid,
)
from facemech.speech.phoneclass import _ESPEAK, phone_classes

pytest.importorskip("praatio")
VOICES = ("en-us", "en-gb")
CMU_CONSONANTS = "B CH D DH F G HH JH K L M N NG P R S SH T TH V W Y Z ZH".split()
CMU_VOWELS = "AA AE AH AO AW AY EH ER EY IH IY OW OY UH UW".split()


def _classes(alignment: Alignment) -> list[tuple[str, ...]]:
    voice = alignment.meta.get("voice")
    return [c for s in alignment.phones
            if (c := phone_classes(s.label, alignment.notation, voice=voice))]


@pytest.mark.parametrize("voice", VOICES)
def test_every_espeak_code_of_the_class_table_has_ipa_of_the_same_classes(voice):
    """Each of the class table's eSpeak codes (all that the English voices emit, and a few
    variants), bare and stressed, has an IPA label that reads back into its classes; in
    ARPABET too, but for the listed vowels ARPABET has no phone for."""
    assert len(_ESPEAK) > 100
    approximate = set()
    for code in _ESPEAK:
        want = phone_classes(code, "espeak", voice=voice)
        for label in (code, "'" + code, "," + code):
            ipa = L.espeak_to_ipa(label, voice)
            assert ipa and ipa.isprintable(), (code, ipa)
            assert phone_classes(ipa, "ipa") == want, (voice, label, ipa)
            arpa = L.ipa_to_arpabet(ipa)
            if phone_classes(arpa, "arpabet") != want:
                approximate.add(code)
    assert approximate <= L.ARPABET_APPROXIMATE
    assert approximate >= L.ARPABET_APPROXIMATE - {"0", "0#"}  # en-us's 0 is AA exactly


def test_espeak_codes_become_the_ipa_espeak_itself_writes():
    """Against eSpeak NG 1.52's own IPA (espeak_TextToPhonemes, IPA mode) on English words:
    the same symbol, stress before the phone."""
    us = {"'0": "ˈɑː", "a": "æ", "t#": "ɾ", "I#": "ᵻ", "oU": "oʊ", "3:": "ɜː", "@L": "əl",
          "tS": "tʃ", "dZ": "dʒ", "N": "ŋ", "g": "ɡ", "r": "ɹ", "n-": "n̩", "a#": "ɐ",
          ",aI": "ˌaɪ", "OI": "ɔɪ", "V": "ʌ", "T": "θ", "D": "ð", "S": "ʃ", "Z": "ʒ"}
    gb = {"'0": "ˈɒ", "a": "a", "e@": "eə", "U@": "ʊə", "i@3": "iə", "3": "ə", "A@": "ɑː"}
    assert {k: L.espeak_to_ipa(k, "en-us+f3") for k in us} == us
    assert {k: L.espeak_to_ipa(k, "en-gb") for k in gb} == gb
    # en-us's r-coloured vowels keep the colour as the rhotic hook (eSpeak: ɑːɹ, ɚ)
    assert L.espeak_to_ipa("A@", "en-us") == "ɑ˞" and L.espeak_to_ipa("3", "en-us") == "ə˞"
    # variants, palatalisation, the lone ';', and a code not in the table
    assert L.espeak_to_ipa("l/2", "en-us") == "l" and L.espeak_to_ipa("l;", "en-us") == "lʲ"
    assert L.espeak_to_ipa(";", "en-us") is None
    with pytest.raises(InputError) as exc:
        L.espeak_to_ipa("y", "fr-fr", source="take")
    assert exc.value.field == "phones" and "'y'" in exc.value.message


def test_arpabet_and_ipa_go_both_ways_with_stress():
    for base in CMU_CONSONANTS:
        assert L.ipa_to_arpabet(L.arpabet_to_ipa(base)) == base
    for base in CMU_VOWELS:
        for digit in "012":
            label = base + digit
            back = L.ipa_to_arpabet(L.arpabet_to_ipa(label))
            assert back == label, (label, L.arpabet_to_ipa(label), back)
            assert phone_classes(L.arpabet_to_ipa(label), "ipa") == \
                phone_classes(label, "arpabet"), label
    assert L.arpabet_to_ipa("AH0") == "ə" and L.arpabet_to_ipa("AH1") == "ˈʌ"
    assert L.arpabet_to_ipa("ER0") == "ɚ" and L.ipa_to_arpabet("ˈɝ") == "ER1"
    for bad in (lambda: L.arpabet_to_ipa("XYZ1"), lambda: L.ipa_to_arpabet("ʘ")):
        with pytest.raises(InputError) as exc:
            bad()
        assert exc.value.field == "phones"


@pytest.fixture(scope="module")
def spoken():
    pytest.importorskip("espeakng_loader")
    from facemech.speech.tts import synthesize

    return synthesize("Bob bought a puppy for the water party.", voice="en-us").alignment


@pytest.mark.parametrize("notation", ["ipa", "arpabet"])
def test_a_textgrid_in_ipa_or_arpabet_reads_back_into_the_same_phones(spoken, tmp_path,
                                                                      notation):
    written = L.relabel(spoken, notation)
    assert written.notation == notation and len(written.phones) == len(spoken.phones)
    assert [(s.start, s.end) for s in written.phones] == \
        [(s.start, s.end) for s in spoken.phones]
    path = write_textgrid(tmp_path / "a.TextGrid", written, tiers={ESPEAK_TIER: spoken.phones})
    back = read_textgrid(path)  # the notation detected from the labels
    assert back.notation == notation
    assert [s.label for s in back.phones] == [s.label for s in written.phones]
    assert back.words == spoken.words
    if notation == "ipa":
        assert _classes(back) == _classes(spoken)
    codes = read_textgrid(path, phone_tier=ESPEAK_TIER)
    assert codes.notation == "espeak" and codes.phones == spoken.phones
    csv = read_alignment_csv(write_alignment_csv(tmp_path / "a.csv", written,
                                                 tiers={ESPEAK_TIER: spoken.phones}))
    assert csv.notation == notation and csv.phones == back.phones


MFA = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 1.6
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 1.6
        intervals: size = 4
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.6
            text = "bob"
        intervals [3]:
            xmin = 0.6
            xmax = 1.1
            text = "water"
        intervals [4]:
            xmin = 1.1
            xmax = 1.6
            text = "later"
    item [2]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 1.6
        intervals: size = %d
%s'''


def _mfa(labels) -> str:
    times = [0.0, 0.1, 0.2, 0.45, 0.6, 0.7, 0.85, 0.95, 1.1, 1.2, 1.35, 1.45, 1.6]
    rows = [f"        intervals [{k + 1}]:\n            xmin = {a}\n            xmax = {b}\n"
            f'            text = "{lab}"\n'
            for k, (a, b, lab) in enumerate(zip(times[:-1], times[1:], labels, strict=True))]
    return MFA % (len(rows), "".join(rows))


def test_an_mfa_arpabet_textgrid_reads_into_the_classes_of_ipa_and_espeak(tmp_path):
    """"Bob water later" as MFA's English ARPABET model writes it (stress digits, a flap DX,
    ER0, silences), the same in IPA and in eSpeak's en-us codes: the same classes."""
    arpabet = ["sil", "B", "AA1", "B", "W", "AO1", "DX", "ER0", "L", "EY1", "DX", "ER0"]
    ipa = ["", "b", "ˈɑ", "b", "w", "ˈɔ", "ɾ", "ɚ", "l", "ˈeɪ", "ɾ", "ɚ"]
    espeak = ["_", "b", "'0", "b", "w", "'O:", "t#", "3", "l", "'eI", "t#", "3"]
    got = {}
    for name, labels in (("arpabet", arpabet), ("ipa", ipa), ("espeak", espeak)):
        path = tmp_path / f"{name}.TextGrid"
        path.write_text(_mfa(labels), encoding="utf-8")
        al = read_textgrid(path)
        assert al.notation == name and len(al.phones) == 11
        got[name] = [phone_classes(s.label, al.notation, voice="en-us") for s in al.phones]
    # eSpeak en-us's 3 is its plain schwa class; ARPABET's ER0 and IPA's ɚ add the r
    r_coloured = [k for k, lab in enumerate(arpabet[1:]) if lab == "ER0"]
    assert got["arpabet"] == got["ipa"]
    assert all(a == b for k, (a, b) in enumerate(zip(got["arpabet"], got["espeak"],
                                                     strict=True)) if k not in r_coloured)
    assert all(got["arpabet"][k] == ("schwa", "r") for k in r_coloured)
    # the IPA that facemech writes for them reads as the eSpeak codes do
    mine = [L.espeak_to_ipa(s, "en-us") for s in espeak[1:]]
    assert [phone_classes(s, "ipa") for s in mine] == got["espeak"]


def test_relabel_refuses_what_it_cannot_write():
    al = Alignment(words=(), phones=(Segment("ə", 0.0, 0.1),), notation="ipa", duration=0.1)
    assert L.relabel(al, "ipa") is al
    assert L.relabel(al, "arpabet").phones[0].label == "AH0"
    for bad in ("espeak", "sampa"):
        with pytest.raises(InputError) as exc:
            L.relabel(al, bad)
        assert exc.value.field == "phone_labels"


def test_speak_writes_ipa_phones_and_keeps_espeaks_codes(tmp_path, monkeypatch, capsys):
    pytest.importorskip("espeakng_loader")
    out = tmp_path / "s"
    code, _, err = run_cli(monkeypatch, capsys, "speak", "Bob bought a puppy", "-o", out,
                           "--no-video", "--no-plan", "--face", "default-coarse",
                           "--no-blinks", "--no-gaze", "--no-head-motion")
    assert code == 0, err
    grid = read_textgrid(out / "alignment.TextGrid")
    codes = read_textgrid(out / "alignment.TextGrid", phone_tier=ESPEAK_TIER)
    assert grid.notation == "ipa" and codes.notation == "espeak"
    labels = [s.label for s in grid.phones]
    assert labels == ["b", "ˈɑː", "b", "b", "ˈɔː", "t", "ɐ", "p", "ˈʌ", "p", "i"]
    assert [s.label for s in codes.phones] == ["b", "'0", "b", "b", "'O:", "t", "a#", "p",
                                               "'V", "p", "i"]
    csv = read_alignment_csv(out / "alignment.csv")
    assert csv.notation == "ipa" and [s.label for s in csv.phones] == labels
    man = json.loads((out / "manifest.json").read_text())["alignment"]
    assert man["notation"] == "ipa" and man["phone_labels"] == labels
    assert man[ESPEAK_TIER] == [s.label for s in codes.phones]
    # ARPABET on request, from the command line; the recording's IPA cannot become eSpeak's
    arpa = tmp_path / "arpa"
    code, _, err = run_cli(monkeypatch, capsys, "speak", "--audio", out / "speech.wav",
                           "--textgrid", out / "alignment.TextGrid", "-o", arpa, "--no-video",
                           "--no-plan", "--face", "default-coarse", "--phone-labels", "arpabet")
    assert code == 0, err
    back = read_textgrid(arpa / "alignment.TextGrid")
    assert back.notation == "arpabet" and [s.label for s in back.phones] == [
        "B", "AA1", "B", "B", "AO1", "T", "AH0", "P", "AH1", "P", "IY0"]
    assert json.loads((arpa / "manifest.json").read_text())["alignment"]["notation"] == \
        "arpabet"
    for args in (("Bob", "--phone-labels", "sampa"),
                 ("--audio", out / "speech.wav", "--textgrid", out / "alignment.TextGrid",
                  "--phone-labels", "espeak")):
        code, _, err = run_cli(monkeypatch, capsys, "speak", *args, "-o", tmp_path / "bad",
                               "--no-video")
        assert code == 2 and "phone_labels" in err and "Traceback" not in err
        assert not (tmp_path / "bad").exists()


@pytest.mark.parametrize("notation", ["ipa", "arpabet"])
def test_stress_reads_the_same_in_every_notation(spoken, notation):
    """The planner's stressed vowels (where a slow utterance opens its jaw further) and the
    phone measures' stress come out the same from eSpeak's marks, IPA's and ARPABET's digits;
    an alignment with no mark at all is read as unmarked (every vowel a candidate)."""
    from facemech.speech.phone_labels import phone_stress as _stress
    from facemech.speech.phone_labels import reads_stress
    from facemech.speech.planning import _stressed_vowels

    written = L.relabel(spoken, notation)
    assert reads_stress(written)
    assert _stressed_vowels(written) == _stressed_vowels(spoken)
    bare = replace(written, phones=tuple(
        replace(p, label=p.label.strip().lstrip("ˈˌ").rstrip("012")) for p in written.phones))
    assert not reads_stress(bare)
    assert 0 < len(_stressed_vowels(spoken)) < len(_stressed_vowels(bare))
    assert [_stress(a.label, notation) for a in written.phones] == \
        [_stress(b.label) for b in spoken.phones]
