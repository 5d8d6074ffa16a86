"""Coarticulation: a phone alignment -> muscle activity and jaw angle per frame.

Each phone's viseme target T_s (:mod:`facemech.speech.visemes`) is weighted by its dominance
(Cohen & Massaro 1993), peaking at the phone's acoustic centre::

    D_s(t) = alpha_s exp(-theta_s |tau|^c),   tau = centre_s - t,
    theta_s = anticipatory rate for tau >= 0, carry-over rate for tau < 0
    controls(t) = sum_s D_s(t) T_s / sum_s D_s(t)

separately for the muscle activity and the jaw. Pauses (and the time outside the alignment)
are the rest target with a dominance flat over the pause; a diphthong is its parts
(:mod:`.phoneclass`) sharing its interval. The activation filter (eq. 4 of Lucero & Munhall
1999) and the tissue delay the visible motion, so the activity of frame t is the blend at
t + ``lead_s`` (measured: docs/stimuli.md, "The lead"); the jaw, a kinematic drive, leads by
``jaw_lead_s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..params import MARGINAL_GROUPS, MUSCLE_GROUPS
from .alignment import Alignment
from .articulation import Articulation, as_articulation
from .phoneclass import PAUSE, phone_classes
from .visemes import VISEMES

#: s, how far the muscle activity leads the acoustics (measured: docs/stimuli.md)
LEAD_S = 0.100
#: s, how far the jaw angle leads the acoustics
JAW_LEAD_S = 0.033
#: exponent c of the dominance function (1: exponential, as in Cohen & Massaro's examples)
DOMINANCE_EXPONENT = 1.0
#: s, the controls are tapered to rest over this time at the start and the end of an utterance
EDGE_S = 0.05


@dataclass(frozen=True)
class Gesture:
    """One target in time: an articulatory class over ``[start, end]`` s with its centre."""

    cls: str
    start: float
    end: float
    #: the factor on its targets' departure from rest (:mod:`.articulation`; 1: the table's)
    scale: float = 1.0
    #: rad added to its jaw target after the scale (a plan's, :mod:`.planning`; 0: none)
    jaw: float = 0.0
    #: factors on the magnitudes alpha of its dominance, lips and jaw (a plan's; 1: the table's)
    lips_dominance: float = 1.0
    jaw_dominance: float = 1.0
    #: factor on its dominance's rates, before and after its centre (a plan's; 1: the table's)
    rate: float = 1.0
    #: factor on its jaw's dominance rates only, on top of ``rate`` (a plan's,
    #: :mod:`.planning`: a sentence whose lower lip stays slower than real lips gets a jaw
    #: less coarticulated, nearer each phone's own jaw target; 1: the table's)
    jaw_rate: float = 1.0
    #: activity added to its target's marginal orbicularis oris, both lips (``OOSM``,
    #: ``OOIM``: the lips pressed together; a plan's, for a bilabial that stayed apart; 0: none)
    press: float = 0.0
    #: s added to its dominance's centre (a plan's, :mod:`.planning`: positive later; 0: at
    #: the phone's acoustic centre). The phone's interval is unchanged.
    shift: float = 0.0

    @property
    def centre(self) -> float:
        """s, where its dominance peaks: the middle of its interval, plus its ``shift``."""
        return 0.5 * (self.start + self.end) + self.shift


def gestures(alignment: Alignment, articulation: Articulation | None = None) -> list[Gesture]:
    """The targets of an alignment in time order: a phone's classes, a diphthong's parts
    sharing its interval equally, each scaled by the rules of ``articulation`` it matches
    (:mod:`.articulation`; its global strength is not applied here). Raises InputError for an
    unknown label."""
    out = []
    for seg in alignment.phones:
        parts = phone_classes(seg.label, alignment.notation, source=alignment.source,
                              voice=alignment.meta.get("voice"))
        if not parts:
            continue
        word = _word_of(alignment, seg.start, seg.end) if articulation else None
        step = (seg.end - seg.start) / len(parts)
        for k, cls in enumerate(parts):
            scale = articulation.factor(cls, seg.label, word) if articulation else 1.0
            out.append(Gesture(cls, seg.start + k * step, seg.start + (k + 1) * step, scale))
    return out


def _word_of(alignment: Alignment, start: float, end: float) -> tuple[int, str] | None:
    """(index from 1, text) of the word holding the middle of [start, end], or None."""
    mid = 0.5 * (start + end)
    for k, w in enumerate(alignment.words, start=1):
        if w.start <= mid <= w.end:
            return k, w.label
    return None


def log_dominance(t: np.ndarray, gesture: Gesture, alpha: float, anticipatory_rate: float,
                  carryover_rate: float, exponent: float = DOMINANCE_EXPONENT) -> np.ndarray:
    """log D(t) of one gesture at times ``t`` (s): see the module doc. A pause's tau is the
    distance to its interval."""
    t = np.asarray(t, float)
    if gesture.cls == PAUSE:
        tau = np.where(t < gesture.start, gesture.start - t, np.minimum(gesture.end - t, 0.0))
    else:
        tau = gesture.centre - t
    rate = np.where(tau >= 0.0, anticipatory_rate, carryover_rate)
    return np.log(alpha) - rate * np.abs(tau) ** exponent


def blend(t: np.ndarray, items: list[Gesture], *, exponent: float = DOMINANCE_EXPONENT
          ) -> tuple[np.ndarray, np.ndarray]:
    """The dominance-weighted targets at times ``t``.

    Parameters
    ----------
    t : (frames,) s
    items : gestures (:func:`gestures`), with the rest before and after them as pauses

    Returns
    -------
    activity : (frames, groups) in [0, 1]
    jaw : (frames,) rad
    """
    t = np.asarray(t, float)
    vis = [VISEMES[g.cls] for g in items]
    scale = np.array([g.scale for g in items])
    act_targets = np.array([v.activity_vector() for v in vis]) * scale[:, None]  # (S, groups)
    act_targets[:, [MUSCLE_GROUPS.index(g) for g in MARGINAL_GROUPS]] += \
        np.array([g.press for g in items])[:, None]
    jaw_targets = np.array([v.jaw for v in vis]) * scale + np.array([g.jaw for g in items])

    def decay(jaw_rate):  # (T, S) log dominance without the magnitudes
        return np.stack([log_dominance(t, g, 1.0, v.anticipatory_rate * g.rate * jaw_rate(g),
                                       v.carryover_rate * g.rate * jaw_rate(g), exponent)
                         for g, v in zip(items, vis, strict=True)], axis=1)

    def weights(logd, alpha):
        logd = logd + np.log(alpha)[None]
        logd -= logd.max(axis=1, keepdims=True)
        w = np.exp(logd)
        return w / w.sum(axis=1, keepdims=True)

    lips = decay(lambda g: 1.0)
    # the jaw's own rates (a plan's) where any differs from the lips'
    jaws = decay(lambda g: g.jaw_rate) if any(g.jaw_rate != 1.0 for g in items) else lips
    activity = weights(lips, np.array([v.lips_dominance * g.lips_dominance
                                       for g, v in zip(items, vis, strict=True)])) @ act_targets
    jaw = weights(jaws, np.array([v.jaw_dominance * g.jaw_dominance
                                  for g, v in zip(items, vis, strict=True)])) @ jaw_targets
    return activity, jaw


def controls_from_alignment(alignment: Alignment, *, frame_rate: float = 60.0,
                            lead_s: float = LEAD_S, jaw_lead_s: float = JAW_LEAD_S,
                            strength: float | Articulation = 1.0
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Muscle activity and jaw angle per frame that make the visible speech of an alignment.

    Parameters
    ----------
    alignment : Alignment
        Phones in any of its notations; the controls cover 0 to ``alignment.duration``.
    frame_rate : Hz, the control rate of :func:`facemech.simulate` (60)
    lead_s : s, how far the muscle activity leads the acoustics (:data:`LEAD_S`)
    jaw_lead_s : s, how far the jaw angle leads the acoustics (:data:`JAW_LEAD_S`)
    strength : scale of every target's departure from rest (1: the table's; 0.5 hypo-
        articulated, the activity clipped to [0, 1]), or an :class:`Articulation` that adds
        rules scaling one phone, word or viseme class (:mod:`.articulation`)

    Returns
    -------
    time : (frames,) s, ``k / frame_rate`` from 0 to the first frame at or after the duration
    activity : (frames, groups) in [0, 1], columns :data:`~facemech.params.MUSCLE_GROUPS`
    jaw : (frames,) rad, positive opens

    The first and last frames are at rest (zero activity, jaw closed): the controls are tapered
    to rest over :data:`EDGE_S` at both ends (alignments from a synthesiser begin and end with
    silence, where the taper changes nothing).

    Raises
    ------
    InputError
        An unknown phone label, a non-positive frame rate, a negative strength, an alignment
        of no duration.
    """
    src = alignment.source
    articulation = as_articulation(strength)
    strength = articulation.strength
    if not frame_rate > 0:
        raise InputError(f"frame rate must be positive, got {frame_rate!r}", source=src,
                         field="frame_rate")
    if not (np.isfinite(strength) and strength >= 0):
        raise InputError(f"strength must be a finite number >= 0, got {strength!r}",
                         source=src, field="strength")
    if not alignment.duration > 0:
        raise InputError(f"the alignment lasts {alignment.duration!r} s: nothing to say",
                         source=src, field="duration")
    return controls_from_gestures(gestures(alignment, articulation), alignment.duration,
                                  frame_rate=frame_rate, lead_s=lead_s, jaw_lead_s=jaw_lead_s,
                                  strength=strength)


def controls_from_gestures(items: list[Gesture], duration: float, *, frame_rate: float = 60.0,
                           lead_s: float = LEAD_S, jaw_lead_s: float = JAW_LEAD_S,
                           strength: float = 1.0
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`controls_from_alignment` from its gestures (:func:`gestures`), each possibly
    adjusted (a plan's jaw offset, dominance and rate factors, :mod:`.planning`).

    Parameters
    ----------
    items : the utterance's gestures in time order, without the pauses around it
    duration : s, the utterance's length (the controls cover 0 to it)
    frame_rate, lead_s, jaw_lead_s : as :func:`controls_from_alignment` (Hz, s, s)
    strength : the global scale of every target's departure from rest (checked by the caller)

    Returns
    -------
    time (frames,) s, activity (frames, groups) in [0, 1], jaw (frames,) rad >= 0
    """
    frames = int(np.ceil(duration * frame_rate - 1e-9)) + 1
    time = np.arange(frames) / frame_rate
    items = [Gesture(PAUSE, -np.inf, 0.0), *items, Gesture(PAUSE, duration, np.inf)]
    activity, _ = blend(time + lead_s, items)
    _, jaw = blend(time + jaw_lead_s, items)
    edge = taper(time, duration)
    activity = np.clip(strength * edge[:, None] * activity, 0.0, 1.0)
    jaw = np.maximum(strength * edge * jaw, 0.0)  # the teeth meet: never closed past rest
    return time, activity, jaw


def taper(t: np.ndarray, duration: float) -> np.ndarray:
    """1 inside, falling smoothly (smoothstep) to 0 at 0 and at ``duration`` over EDGE_S."""
    x = np.clip(np.minimum(t, duration - t) / EDGE_S, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)
