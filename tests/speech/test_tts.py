"""Text to speech (eSpeak NG) and alignment files (TextGrid, CSV)."""

from __future__ import annotations

import numpy as np
import pytest

from facemech.errors import InputError
from facemech.speech.alignment import Segment
from facemech.speech.alignment_io import (
    detect_notation,
    read_alignment_csv,
    read_textgrid,
    write_alignment_csv,
    write_textgrid,
)
from facemech.speech.tts import read_wav, synthesize, write_wav

TEXT = "Bob bought a puppy"


@pytest.fixture(scope="module")
def bob():
    return synthesize(TEXT)


def _rms(audio, rate, t0, t1):
    seg = audio[int(t0 * rate):int(t1 * rate)]
    return float(np.sqrt(np.mean(seg.astype(float) ** 2)))


def test_bob_bought_a_puppy_audio_and_alignment(bob):
    a = bob.alignment
    assert bob.sample_rate == 22050
    assert bob.audio.dtype == np.float32 and bob.audio.ndim == 1
    assert 1.0 <= bob.duration <= 3.0
    assert a.duration == pytest.approx(len(bob.audio) / 22050, abs=1e-12)
    assert _rms(bob.audio, 22050, 0, bob.duration) > 0.02
    assert np.abs(bob.audio).max() <= 1.0
    assert a.notation == "espeak"
    assert a.meta["voice"] == "en-us" and a.meta["engine"].startswith("eSpeak NG")
    assert [w.label for w in a.words] == ["Bob", "bought", "a", "puppy"]
    # phones tile their words: in time order, each ending where the next starts, inside the audio
    starts = np.array([p.start for p in a.phones])
    ends = np.array([p.end for p in a.phones])
    assert np.all(np.diff(starts) >= 0) and np.all(ends >= starts)
    assert starts[0] >= 0 and ends[-1] <= a.duration
    assert np.all(ends[:-1] == starts[1:])
    for w in a.words:
        inside = [p for p in a.phones if w.start <= p.start and p.end <= w.end]
        assert inside and inside[0].start == w.start and inside[-1].end == w.end
    labels = [p.label for p in a.phones]
    assert labels.count("b") == 3 and labels.count("p") == 2
    word_of = {p: next(w.label for w in a.words if w.start <= p.mid <= w.end) for p in a.phones}
    assert [word_of[p] for p in a.phones if p.label == "b"] == ["Bob", "Bob", "bought"]
    assert [word_of[p] for p in a.phones if p.label == "p"] == ["puppy", "puppy"]
    # both /p/ of "puppy" (word-initial and inside the word) start with their closure: the
    # first 40 % of each is near silence against the vowel after it, and so is the /t/
    for p in (p for p in a.phones if p.label in ("p", "t")):
        vowel = a.phones[a.phones.index(p) + 1]
        closure = _rms(bob.audio, 22050, p.start, p.start + 0.4 * (p.end - p.start))
        assert closure < 0.05 * _rms(bob.audio, 22050, vowel.start, vowel.end)
        assert p.end - p.start > 0.06


def test_a_word_final_phone_before_a_vowel_keeps_its_time():
    """eSpeak gives the word event of "again" at the last /m/ of "mom": only a stop's closure is
    taken back to its word's event, so that /m/ keeps its 58 ms (it had none), and it is the
    nasal murmur, quieter than the open vowel before it, as the first /m/ is. No phone of the
    sentence is empty."""
    sp = synthesize("Say mom again.", rate_wpm=175)
    a = sp.alignment
    labels = [p.label for p in a.phones]
    assert labels[2:5] == ["m", "'0", "m"], labels
    m1, vowel, m2 = a.phones[2:5]
    assert all(p.end - p.start > 0.03 for p in a.phones), [(p.label, p.end - p.start)
                                                         for p in a.phones]
    assert 0.04 < m2.end - m2.start < 0.09
    for m in (m1, m2):
        assert _rms(sp.audio, 22050, m.start, m.end) < 0.8 * _rms(sp.audio, 22050, vowel.start,
                                                                  vowel.end)


def test_faster_rate_is_shorter_and_output_is_repeatable(bob):
    fast = synthesize(TEXT, rate_wpm=300)
    assert fast.duration < 0.7 * bob.duration
    assert [w.label for w in fast.alignment.words] == ["Bob", "bought", "a", "puppy"]
    again = synthesize(TEXT)
    assert np.array_equal(again.audio, bob.audio) and again.alignment == bob.alignment
    here = synthesize(TEXT, isolated=False)  # one engine in this process: same phones
    assert [p.label for p in here.alignment.phones] == [p.label for p in bob.alignment.phones]
    assert here.duration == pytest.approx(bob.duration, rel=0.02)
    assert bob.alignment.meta["rate_wpm"] == 160 and fast.alignment.meta["rate_wpm"] == 300


@pytest.mark.parametrize("kwargs, field", [
    ({"text": "  "}, "text"),
    ({"text": "hi", "rate_wpm": 50}, "rate_wpm"),
    ({"text": "hi", "rate_wpm": 500}, "rate_wpm"),
    ({"text": "hi", "pitch": 150}, "pitch"),
    ({"text": "hi", "voice": "xx-nonesuch"}, "voice"),
])
def test_bad_synthesis_arguments(kwargs, field):
    text = kwargs.pop("text")
    with pytest.raises(InputError) as err:
        synthesize(text, **kwargs)
    assert err.value.field == field
    if field == "voice":
        assert "en-us" in str(err.value) and "en-gb" in str(err.value)


@pytest.mark.parametrize("voice", ["en-gb", "en-gb+f3", "fr-fr"])
def test_the_language_names_the_voice_list_gives_are_voices(voice):
    """eSpeak NG finds voices by file name ("gmw/en"); the language codes that voices() lists,
    and the error message suggests, are taken too: en-gb speaks with its own flap-less /t/ in
    "water" (en-us: the flap "t#"), fr-fr switches to French for "car"."""
    labels = [p.label for p in synthesize("water car", voice=voice).alignment.phones]
    assert "t#" not in labels and "t" in labels
    if voice == "fr-fr":
        assert "(fr)" in labels
    assert [p.label for p in synthesize("water car").alignment.phones][2] == "t#"


def test_wav_round_trip_and_errors(tmp_path):
    rate = 22050
    t = np.arange(rate // 10) / rate
    audio = 0.5 * np.sin(2 * np.pi * 220 * t)
    path = write_wav(tmp_path / "a.wav", audio, rate)
    back, r = read_wav(path)
    assert r == rate and back.shape == audio.shape
    assert np.max(np.abs(back - audio)) < 1.0 / 32767
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left
    (tmp_path / "bad.wav").write_text("not audio")
    with pytest.raises(InputError) as err:
        read_wav(tmp_path / "bad.wav")
    assert err.value.source.endswith("bad.wav")
    with pytest.raises(InputError) as err:
        write_wav(tmp_path / "b.wav", audio, 0)
    assert err.value.field == "rate"


@pytest.mark.parametrize("short", [False, True])
def test_textgrid_round_trip(bob, tmp_path, short):
    a = bob.alignment
    path = write_textgrid(tmp_path / "bob.TextGrid", a, short=short)
    b = read_textgrid(path)
    assert b.notation == "espeak" and b.duration == pytest.approx(a.duration, abs=1e-9)
    for got, want in ((b.words, a.words), (b.phones, a.phones)):
        assert [s.label for s in got] == [s.label for s in want]
        assert np.allclose([(s.start, s.end) for s in got], [(s.start, s.end) for s in want],
                           rtol=0, atol=1e-9)


def test_csv_round_trip(bob, tmp_path):
    path = write_alignment_csv(tmp_path / "bob.csv", bob.alignment)
    assert path.read_text().splitlines()[3] == "tier,label,start_s,end_s"
    b = read_alignment_csv(path)
    assert b.words == bob.alignment.words and b.phones == bob.alignment.phones
    assert b.notation == "espeak" and b.duration == bob.alignment.duration


MFA = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 1.2
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 1.2
        intervals: size = 4
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.5
            text = "bob"
        intervals [3]:
            xmin = 0.5
            xmax = 0.62
            text = "sp"
        intervals [4]:
            xmin = 0.62
            xmax = 1.2
            text = "bought"
    item [2]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 1.2
        intervals: size = 8
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = "sil"
        intervals [2]:
            xmin = 0.1
            xmax = 0.2
            text = "B"
        intervals [3]:
            xmin = 0.2
            xmax = 0.4
            text = "AA1"
        intervals [4]:
            xmin = 0.4
            xmax = 0.5
            text = "B"
        intervals [5]:
            xmin = 0.5
            xmax = 0.62
            text = "sp"
        intervals [6]:
            xmin = 0.62
            xmax = 0.7
            text = "B"
        intervals [7]:
            xmin = 0.7
            xmax = 1.0
            text = "AO1"
        intervals [8]:
            xmin = 1.0
            xmax = 1.2
            text = "T"
'''


def test_mfa_textgrid_reads_as_arpabet(tmp_path):
    path = tmp_path / "take.TextGrid"
    path.write_text(MFA, encoding="utf-8")
    a = read_textgrid(path)
    assert a.notation == "arpabet" and a.duration == 1.2 and a.source == str(path)
    assert a.words == (Segment("bob", 0.1, 0.5), Segment("bought", 0.62, 1.2))
    assert [(p.label, p.start, p.end) for p in a.phones] == [
        ("B", 0.1, 0.2), ("AA1", 0.2, 0.4), ("B", 0.4, 0.5), ("B", 0.62, 0.7),
        ("AO1", 0.7, 1.0), ("T", 1.0, 1.2)]
    assert read_textgrid(path, notation="ipa").notation == "ipa"  # an explicit notation wins
    # tiers named as MFA names them for several speakers
    renamed = tmp_path / "spk.TextGrid"
    renamed.write_text(MFA.replace('"words"', '"S1 - words"').replace('"phones"',
                                                                       '"S1 - phones"'))
    assert read_textgrid(renamed).meta["phone_tier"] == "S1 - phones"


SHORT_IPA = '''File type = "ooTextFile"
Object class = "TextGrid"

0
0.9
<exists>
2
"IntervalTier"
"mots"
0
0.9
2
0
0.3
""
0.3
0.9
"chez"
"IntervalTier"
"sons"
0
0.9
3
0
0.3
""
0.3
0.5
"ʃ"
0.5
0.9
"eː"
'''


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-8"])
def test_short_textgrid_in_utf16_with_named_tiers(tmp_path, encoding):
    path = tmp_path / "chez.TextGrid"
    path.write_bytes(SHORT_IPA.encode(encoding))
    a = read_textgrid(path, word_tier="mots", phone_tier="sons")
    assert a.notation == "ipa" and a.duration == 0.9
    assert a.words == (Segment("chez", 0.3, 0.9),)
    assert a.phones == (Segment("ʃ", 0.3, 0.5), Segment("eː", 0.5, 0.9))


def test_textgrid_errors_name_file_and_tier(tmp_path):
    path = tmp_path / "take.TextGrid"
    path.write_text(MFA.replace('"phones"', '"segs"'))
    with pytest.raises(InputError) as err:
        read_textgrid(path)
    assert err.value.source == str(path) and err.value.field == "phone_tier"
    assert "'segs'" in str(err.value)
    with pytest.raises(InputError) as err:
        read_textgrid(path, phone_tier="segs", word_tier="lexemes")
    assert err.value.field == "word_tier"
    bad = tmp_path / "bad.TextGrid"
    bad.write_text('File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = oops\n'
                   "item []:\n    item [1]:\n")
    with pytest.raises(InputError) as err:
        read_textgrid(bad)
    assert err.value.source == str(bad)
    with pytest.raises(InputError) as err:
        read_textgrid(tmp_path / "missing.TextGrid")
    assert "not found" in str(err.value)
    with pytest.raises(InputError) as err:
        read_textgrid(path, phone_tier="segs", notation="sampa")
    assert err.value.field == "notation"
    csv = tmp_path / "a.csv"
    csv.write_text("tier,label,start_s,end_s\nsyllables,ba,0,0.2\n")
    with pytest.raises(InputError) as err:
        read_alignment_csv(csv)
    assert err.value.field == "tier" and err.value.source == str(csv)


def test_detect_notation():
    assert detect_notation(["sil", "P", "AH1", "P", "IY0", "sp"]) == "arpabet"
    assert detect_notation(["p", "ʌ", "p", "i"]) == "ipa"
    assert detect_notation(["p", "'V", "p", "i", "_:"]) == "espeak"
    assert detect_notation(["b", "oU", "t"]) == "espeak"
    assert detect_notation(["p", "a", "t"]) == "ipa"  # plain letters: valid IPA
    with pytest.raises(InputError):
        detect_notation(["", "sil"])

