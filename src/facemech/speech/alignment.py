"""A time alignment of speech: words and phones with start and end times (s).

Phone labels keep the notation they came in (eSpeak NG mnemonics, IPA or ARPABET, said by
``notation``); :mod:`facemech.speech.phoneclass` maps any of them to articulatory classes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import InputError

NOTATIONS = ("espeak", "ipa", "arpabet")


@dataclass(frozen=True)
class Segment:
    """One labelled interval: ``label`` from ``start`` to ``end`` (s)."""

    label: str
    start: float
    end: float

    @property
    def mid(self) -> float:
        return 0.5 * (self.start + self.end)


@dataclass(frozen=True)
class Alignment:
    """Words and phones of an utterance, each a tuple of :class:`Segment` in time order.

    ``notation`` names the phone labels' notation (one of :data:`NOTATIONS`); ``duration`` is
    the audio's length (s); ``source`` where it came from (for messages and manifests).
    """

    words: tuple[Segment, ...]
    phones: tuple[Segment, ...]
    notation: str
    duration: float
    source: str | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.notation not in NOTATIONS:
            raise InputError(f"unknown phone notation {self.notation!r} (expected "
                             f"{', '.join(NOTATIONS)})", source=self.source, field="notation")
        for tier, segs in (("words", self.words), ("phones", self.phones)):
            last = 0.0
            for s in segs:
                if not (0.0 <= s.start <= s.end) or s.start < last - 1e-9:
                    raise InputError(f"interval {s.label!r} at {s.start:.3f}-{s.end:.3f} s is "
                                     "out of order", source=self.source, field=tier)
                last = s.end
        if self.phones and self.phones[-1].end > self.duration + 1e-6:
            raise InputError(f"phones run to {self.phones[-1].end:.3f} s, past the audio's "
                             f"{self.duration:.3f} s", source=self.source, field="duration")
