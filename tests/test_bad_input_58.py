"""Bad input, the rows of issue 58 outside the articulography readers: a voice variant eSpeak NG
does not have, a design row refused before any manifest, a lip coil given as a bone point."""

from __future__ import annotations

import numpy as np
import pytest

from facemech.errors import InputError
from test_bad_input_31 import refused


# ---- a voice variant eSpeak NG does not have -----------------------------------------------
def test_the_variants_are_espeaks_own():
    from facemech.speech.tts import variants

    have = variants()
    assert {"f1", "f3", "m1", "m3", "klatt"} <= set(have) and "nonexistent" not in have
    assert len(have) > 50


@pytest.mark.parametrize("voice", ["en-us+nonexistent", "en-us+", "en-us+F3", "en-us+10",
                                   "en-us+3x", "en-us+../lang/gmw/en", "+f3",
                                   "en-us+f3+m1"])
@pytest.mark.parametrize("isolated", [True, False])
def test_a_voice_variant_espeak_does_not_have_is_refused(voice, isolated):
    from facemech.speech.tts import synthesize

    with pytest.raises(InputError) as err:
        synthesize("ba", voice=voice, isolated=isolated)
    assert err.value.field == "voice" and "--voice" in str(err.value)
    if voice.startswith("en-us+"):
        assert "f3, f4" in str(err.value) and "m1" in str(err.value)  # the variants it has


def test_a_variant_it_has_is_that_variant():
    """``+f3`` speaks higher than the plain voice; eSpeak's numeric shorthand ``+13`` is f3."""
    from facemech.speech.tts import synthesize

    plain = synthesize("ba", voice="en-us")
    f3, thirteen = synthesize("ba", voice="en-us+f3"), synthesize("ba", voice="en-us+13")
    assert f3.alignment.meta["voice"] == "en-us+f3"
    assert np.array_equal(f3.audio, thirteen.audio)
    assert not (len(f3.audio) == len(plain.audio) and np.array_equal(f3.audio, plain.audio))


def test_speak_refuses_an_unknown_variant_and_writes_nothing(monkeypatch, capsys, tmp_path):
    line = refused(monkeypatch, capsys, tmp_path, "speak", "ba", "-o", "{t}/out", "--voice",
                   "en-us+nonexistent", "--no-video",
                   words=("--voice", "'en-us+nonexistent'", "field 'voice'", "f3"))
    assert "nonexistent'; it has" in line
    assert not (tmp_path / "out").exists()
