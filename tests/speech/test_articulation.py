"""Per-phone control of visible speech (issue 29, part 4): scale one viseme class, one phone or
one word, not only a global strength (facemech.speech.articulation)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech import InputError
from facemech.params import MUSCLE_GROUPS
from facemech.speech.alignment import Alignment, Segment
from facemech.speech.articulation import Articulation
from facemech.speech.coarticulation import controls_from_alignment

OOS = MUSCLE_GROUPS.index("OOS")


def _alignment(phones, words):
    segs = tuple(Segment(label, a, b) for label, a, b in phones)
    return Alignment(words=tuple(Segment(w, a, b) for w, a, b in words), phones=segs,
                     notation="espeak", duration=segs[-1].end + 0.2, source="test")


#: "_ u: _": one rounded vowel between pauses (whose targets are rest)
U = _alignment([("_", 0.0, 0.2), ("u:", 0.2, 0.45), ("_", 0.45, 0.6)], [("ooh", 0.2, 0.45)])
#: "ma ma": two words of the same phones
MAMA = _alignment([("_", 0.0, 0.2), ("m", 0.2, 0.28), ("'a", 0.28, 0.45), ("m", 0.45, 0.53),
                   ("a", 0.53, 0.7), ("_", 0.7, 0.9)], [("ma", 0.2, 0.45), ("ma", 0.45, 0.7)])


@pytest.mark.parametrize("spec, field_text", [
    ("word:balloon", "KIND:KEY=FACTOR"), ("tone:H=2", "unknown kind"),
    ("class:rounded=0.5", "unknown viseme class"), ("class:pause=0.5", "unknown viseme class"),
    ("word:#0=2", "#1, #2"), ("phone:u:=5", "[0, 4]"), ("phone:u:=nan", "[0, 4]"),
    ("phone:u:=-1", "[0, 4]"),
])  # fmt: skip
def test_a_bad_rule_is_an_input_error_naming_the_field(spec, field_text):
    with pytest.raises(InputError) as err:
        Articulation.parse([spec], source="design.csv")
    assert err.value.field == "scale" and err.value.source == "design.csv"
    assert field_text in str(err.value) and spec in str(err.value)


def test_rules_are_read_from_a_list_or_one_cell():
    a = Articulation.parse("class:close_back_rounded=0.5; word:#2=1.5;phone:u:=1.2",
                           strength=0.8)
    assert [str(r) for r in a.rules] == ["class:close_back_rounded=0.5", "word:#2=1.5",
                                         "phone:u:=1.2"]
    assert a.to_dict() == {"strength": 0.8, "rules": [str(r) for r in a.rules]}
    assert Articulation.parse(None).rules == ()
    # a list's item may hold several rules too (a CLI value, a design cell)
    assert [str(r) for r in Articulation.parse(["word:x=1;class:open=2"]).rules] == [
        "word:x=1", "class:open=2"]


def test_a_class_rule_scales_that_class_and_only_it():
    """Between pauses (rest targets) the blend is linear in the vowel's targets: half the
    rounding is half the activity at every frame, and the rounded vowel's jaw too."""
    _, plain, jaw_plain = controls_from_alignment(U)
    _, half, jaw_half = controls_from_alignment(
        U, strength=Articulation.parse(["class:close_back_rounded=0.5"]))
    assert plain[:, OOS].max() > 0.3
    np.testing.assert_allclose(half, 0.5 * plain, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(jaw_half, 0.5 * jaw_plain, rtol=1e-12, atol=1e-15)
    # another class's rule leaves it alone, to the bit
    _, other, _ = controls_from_alignment(U, strength=Articulation.parse(["class:open=2"]))
    np.testing.assert_array_equal(other, plain)


def test_a_phone_rule_ignores_stress_marks():
    rule = Articulation.parse(["phone:a=1.5"])
    _, plain, jaw_plain = controls_from_alignment(MAMA)
    _, more, jaw_more = controls_from_alignment(MAMA, strength=rule)
    assert jaw_more.max() == pytest.approx(1.5 * jaw_plain.max(), rel=0.05)  # 'a and a


def test_a_word_rule_hyperarticulates_one_word():
    t, _, jaw_plain = controls_from_alignment(MAMA)
    _, _, jaw_second = controls_from_alignment(MAMA, strength=Articulation.parse(["word:#2=1.5"]))
    _, _, jaw_both = controls_from_alignment(MAMA, strength=Articulation.parse(["word:MA=1.5"]))
    first, second = t < 0.45, t >= 0.45
    # the second word opens half as far again; the first only by what coarticulation carries
    assert jaw_second[second].max() > 1.35 * jaw_plain[second].max()
    assert jaw_second[first].max() < 1.10 * jaw_plain[first].max()
    # by its text, every word of that text (case-insensitive)
    assert jaw_both[first].max() > 1.35 * jaw_plain[first].max()


def test_the_global_strength_is_the_same_as_a_number():
    for s in (0.5, 1.0, 1.7):
        a = controls_from_alignment(MAMA, strength=s)
        b = controls_from_alignment(MAMA, strength=Articulation(strength=s))
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)


def test_speak_takes_scale_rules_and_records_them(monkeypatch, capsys, tmp_path):
    code, _, err = run_cli(monkeypatch, capsys, "speak", "Bob saw Ann", "-o", tmp_path / "s",
                           "--no-video", "--no-blinks", "--no-gaze", "--no-head-motion",
                           "--no-plan", "--scale", "word:bob=1.5", "--scale", "class:open=0.8")
    assert code == 0, err
    manifest = json.loads((tmp_path / "s" / "manifest.json").read_text())
    assert manifest["scale"] == ["word:bob=1.5", "class:open=0.8"]
    assert manifest["strength"] == 1.0
    code, _, err = run_cli(monkeypatch, capsys, "speak", "Bob", "-o", tmp_path / "bad",
                           "--no-video", "--scale", "word:bob")
    assert code == 2 and "scale" in err and "Traceback" not in err
    assert not (tmp_path / "bad").exists()
