"""The tongue tip's pose per frame from a phone alignment (kinematic: render geometry only).

The tongue is not part of the physics; the renderer bends its tip (:mod:`facemech.viz.dentition`)
by a pose of two numbers, in the mandible's frame, from the resting tip: ``protrusion`` (m,
forward +z) and ``elevation`` (m, up +y). Each articulatory class (:mod:`.phoneclass`) has a
target (:data:`TARGETS`: dental /θ ð/ 2.5 mm past the upper incisors, interdental, Ladefoged &
Maddieson 1996, Dart 1991; alveolar and /l/ raised towards the ridge; postalveolar 3 mm further
back; every other class rest). The targets are blended as the visemes are
(:mod:`.coarticulation`, Cohen & Massaro 1993), the tip consonants dominating strongly and the
vowels weakly (coarticulatory resistance, Recasens et al. 1997), with no lead (no muscle lag),
tapered to rest over :data:`~facemech.speech.coarticulation.EDGE_S` at the ends and scaled by
the articulation's strength and rules. Details: docs/stimuli.md, "The tongue".
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ..errors import InputError
from ..geometry.teeth import LOWER_ARCH_SETBACK
from ..viz.dentition import TONGUE_TIP_SETBACK
from .alignment import Alignment
from .articulation import Articulation, as_articulation
from .coarticulation import Gesture, gestures, log_dominance, taper
from .phoneclass import PAUSE

#: m, how far the resting tongue tip stands behind the upper incisors' labial face
REST_TIP_BEHIND_INCISORS = LOWER_ARCH_SETBACK + TONGUE_TIP_SETBACK


@dataclass(frozen=True)
class TongueTarget:
    """One class's tongue-tip target and its dominance.

    Attributes
    ----------
    protrusion : m, forward from the resting tip
    elevation : m, up from the resting tip (the mandible's frame)
    dominance : magnitude alpha of the dominance function
    anticipatory_rate : 1/s, its fall-off before the phone's centre
    carryover_rate : 1/s, its fall-off after it
    """

    protrusion: float = 0.0
    elevation: float = 0.0
    dominance: float = 0.3
    anticipatory_rate: float = 15.0
    carryover_rate: float = 18.0


_TIP = dict(anticipatory_rate=25.0, carryover_rate=30.0)
#: the targets of the classes that use the tongue tip; every other class: :data:`FREE`
TARGETS: MappingProxyType = MappingProxyType({
    "dental": TongueTarget(REST_TIP_BEHIND_INCISORS + 0.004, 0.009, 10.0, **_TIP),
    "alveolar": TongueTarget(0.0005, 0.013, 10.0, **_TIP),
    "l": TongueTarget(0.0005, 0.013, 6.0, **_TIP),
    "postalveolar": TongueTarget(-0.003, 0.011, 6.0, **_TIP),
    PAUSE: TongueTarget(0.0, 0.0, 3.0, 30.0, 30.0),
})
#: the target of a class that asks nothing of the tip: rest, weakly dominant
FREE = TongueTarget()


def target_of(cls: str) -> TongueTarget:
    """The tongue-tip target of an articulatory class (:data:`TARGETS`, else :data:`FREE`)."""
    return TARGETS.get(cls, FREE)


def blend_tongue(t: np.ndarray, items: list[Gesture]) -> np.ndarray:
    """(frames, 2) m, the dominance-weighted (protrusion, elevation) at times ``t`` (s) of
    ``items`` (:func:`facemech.speech.coarticulation.gestures`, with the rest before and after
    them as pauses); each target scaled by its gesture's ``scale``."""
    t = np.asarray(t, float)
    tg = [target_of(g.cls) for g in items]
    targets = np.array([[x.protrusion, x.elevation] for x in tg])
    targets *= np.array([g.scale for g in items])[:, None]
    logd = np.stack([log_dominance(t, g, x.dominance, x.anticipatory_rate, x.carryover_rate)
                     for g, x in zip(items, tg, strict=True)], axis=1)  # (T, S)
    logd -= logd.max(axis=1, keepdims=True)
    w = np.exp(logd)
    return (w / w.sum(axis=1, keepdims=True)) @ targets


def tongue_tip(alignment: Alignment, time: np.ndarray,
               strength: float | Articulation = 1.0) -> np.ndarray:
    """The tongue tip's pose per frame of an alignment.

    Parameters
    ----------
    alignment : Alignment, phones in any of its notations
    time : (frames,) s, the frames' times (e.g. a results file's)
    strength : scale of every target's departure from rest, or an :class:`Articulation`
        (as :func:`facemech.speech.coarticulation.controls_from_alignment`)

    Returns
    -------
    (frames, 2) m: protrusion (forward) and elevation (up) of the tip from its rest, in the
    mandible's frame; rest before 0 and after the alignment's duration.

    Raises
    ------
    InputError
        An unknown phone label, non-finite times, a negative strength.
    """
    articulation = as_articulation(strength)
    s = articulation.strength
    if not (np.isfinite(s) and s >= 0):
        raise InputError(f"strength must be a finite number >= 0, got {s!r}",
                         source=alignment.source, field="strength")
    time = np.asarray(time, float)
    if time.ndim != 1 or not np.all(np.isfinite(time)):
        raise InputError("times must be a finite (frames,) series", source=alignment.source,
                         field="time")
    items = [Gesture(PAUSE, -np.inf, 0.0), *gestures(alignment, articulation),
             Gesture(PAUSE, alignment.duration, np.inf)]
    pose = blend_tongue(time, items)
    edge = taper(time, alignment.duration) if alignment.duration > 0 else np.zeros_like(time)
    return s * edge[:, None] * pose
