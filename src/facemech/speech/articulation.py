"""Per-phone control of visible speech: scale one phone, one word or one viseme class.

A global ``strength`` scales every viseme's departure from rest (:mod:`.coarticulation`). An
:class:`Articulation` adds rules that scale the targets of some gestures only, for stimuli that
hyperarticulate one word or reduce rounding everywhere. A rule is written ``KIND:KEY=FACTOR``:

``class:close_back_rounded=0.5``
    every gesture of that viseme class (:data:`~facemech.speech.phoneclass.CLASSES`), in any
    notation (the rounded vowels at half their departure from rest);
``phone:u:=1.5``
    every phone with that label, as the alignment writes it (stress marks of eSpeak's
    notation and ARPABET's stress digit ignored: ``'u:`` and ``UW1`` match ``u:`` and ``UW``);
``word:balloon=1.5``
    every phone of every word with that text (case-insensitive), or ``word:#3=1.5`` the phones
    of the third word only (counted from 1 in the alignment's word tier).

A phone's factor is the product of the factors of every rule it matches, and the global
strength multiplies them all. The factor scales the gesture's targets (muscle activity and jaw
angle) before the coarticulation blends them, so the neighbours' anticipation and carry-over
of a scaled phone are scaled with it; the blended activity is clipped to [0, 1] as before.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from ..errors import InputError
from .phoneclass import CLASSES, PAUSE

#: the kinds of rule, in the order they are described
KINDS = ("class", "phone", "word")
#: the interval of a rule's factor (a departure from rest up to 4 times the table's)
FACTOR_RANGE = (0.0, 4.0)


@dataclass(frozen=True)
class ScaleRule:
    """One rule: scale the gestures that match ``kind`` and ``key`` by ``factor``."""

    kind: str
    key: str
    factor: float

    def __str__(self) -> str:
        return f"{self.kind}:{self.key}={self.factor:g}"


@dataclass(frozen=True)
class Articulation:
    """A global strength and per-phone rules (see the module doc).

    Attributes
    ----------
    strength : scale of every viseme's departure from rest (1: the table's)
    rules : the rules, applied in order (their factors multiply)
    """

    strength: float = 1.0
    rules: tuple[ScaleRule, ...] = ()

    @classmethod
    def parse(cls, specs: Iterable[str] | str | None, *, strength: float = 1.0,
              source: str | None = None) -> Articulation:
        """An articulation from rules written ``KIND:KEY=FACTOR`` (a list, or one string with
        rules separated by ``;``). Raises InputError naming the field ``scale`` for a rule
        that is not of that form, an unknown kind or class, or a factor outside
        :data:`FACTOR_RANGE`."""
        if specs is None:
            specs = ()
        if isinstance(specs, str):
            specs = [specs]
        parts = [part for spec in specs for part in str(spec).split(";")]
        rules = tuple(_rule(p.strip(), source) for p in parts if p.strip())
        return cls(float(strength), rules)

    def factor(self, cls_name: str, label: str, word: tuple[int, str] | None) -> float:
        """The product of the factors of the rules a gesture matches.

        Parameters
        ----------
        cls_name : the gesture's viseme class
        label : its phone's label as the alignment writes it
        word : (index from 1, text) of the word the phone lies in, or None
        """
        if cls_name == PAUSE:
            return 1.0
        f = 1.0
        for r in self.rules:
            if r.kind == "class":
                hit = r.key == cls_name
            elif r.kind == "phone":
                hit = _bare(r.key) == _bare(label)
            elif word is None:
                hit = False
            elif r.key.startswith("#"):
                hit = int(r.key[1:]) == word[0]
            else:
                hit = r.key.casefold() == word[1].strip().casefold()
            if hit:
                f *= r.factor
        return f

    def to_dict(self) -> dict:
        """The strength and the rules as written, for manifests."""
        return {"strength": self.strength, "rules": [str(r) for r in self.rules]}


def as_articulation(strength) -> Articulation:
    """``strength`` as an :class:`Articulation` (a number: no rules)."""
    if isinstance(strength, Articulation):
        return strength
    return Articulation(float(strength))


def _bare(label: str) -> str:
    """A label without eSpeak's stress marks or ARPABET's stress digit."""
    t = label.strip().lstrip("',%=")
    if len(t) > 1 and t[-1] in "012" and t[:-1].isalpha() and t[:-1].isupper():
        t = t[:-1]
    return t


def _rule(text: str, source: str | None) -> ScaleRule:
    kind, sep, rest = text.partition(":")
    key, eq, value = rest.rpartition("=")
    kind = kind.strip().lower()
    if not sep or not eq or not key.strip():
        raise InputError(f"scale rule {text!r} is not KIND:KEY=FACTOR (e.g. word:balloon=1.5, "
                         "class:close_back_rounded=0.5, phone:u:=1.2)", source=source,
                         field="scale")
    if kind not in KINDS:
        raise InputError(f"scale rule {text!r}: unknown kind {kind!r} (expected "
                         f"{', '.join(KINDS)})", source=source, field="scale")
    key = key.strip()
    if kind == "class" and (key not in CLASSES or key == PAUSE):
        raise InputError(f"scale rule {text!r}: unknown viseme class {key!r} (one of "
                         f"{', '.join(c for c in CLASSES if c != PAUSE)})", source=source,
                         field="scale")
    if kind == "word" and key.startswith("#") and not (key[1:].isdigit() and int(key[1:]) >= 1):
        raise InputError(f"scale rule {text!r}: a word's number is #1, #2, ...", source=source,
                         field="scale")
    try:
        factor = float(value)
    except ValueError:
        factor = float("nan")
    lo, hi = FACTOR_RANGE
    if not lo <= factor <= hi:
        raise InputError(f"scale rule {text!r}: the factor must be a number in [{lo:g}, {hi:g}]",
                         source=source, field="scale")
    return ScaleRule(kind, key, factor)


__all__ = ["Articulation", "ScaleRule", "as_articulation", "KINDS", "FACTOR_RANGE"]
