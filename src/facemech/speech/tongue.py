"""The tongue tip's pose per frame from a phone alignment (kinematic: render geometry only).

The tongue is not part of the physics; the renderer bends its tip (:mod:`facemech.viz.dentition`)
by a pose of two numbers, in the mandible's frame, from the resting tip (behind the lower
incisors, :data:`~facemech.viz.dentition.TONGUE_TIP_SETBACK` behind their labial face,
:data:`~facemech.viz.dentition.TONGUE_TIP_BELOW_STOMION` under the stomion):

* ``protrusion`` (m): forward (+z);
* ``elevation`` (m): up (+y).

Each articulatory class (:mod:`.phoneclass`) has a target (:data:`TARGETS`); the classes that
ask nothing of the tongue tip (the vowels, the labials, the velars, ...) have the resting pose.
The targets are blended in time as the visemes are (:mod:`.coarticulation`): each gesture's
dominance peaks at its acoustic centre and falls off exponentially before and after it (Cohen &
Massaro 1993), and the pose is the dominance-weighted mean of the targets. The tip consonants
dominate strongly and the vowels weakly, so that the tip, free during a vowel, takes its
neighbours' positions (the tip's coarticulatory resistance: Recasens, Pallares & Fontdevila
1997, J. Acoust. Soc. Am. 102, 544-561). The tongue is driven directly (no muscle lag), so the
pose is computed with no lead; it is tapered to rest over the utterance's first and last
:data:`~facemech.speech.coarticulation.EDGE_S` like the controls, and scaled by the
articulation's strength and rules like them.

The targets (our estimates, set against the rendered dentition, whose incisors and resting tip
are placed as in :mod:`facemech.viz.dentition`):

* dental (/θ ð/): the tip 2.5 mm past the upper incisors' labial face and raised to just under
  their edge (American English /θ ð/ are mostly interdental, the tip visible between the teeth:
  Ladefoged & Maddieson 1996, *The Sounds of the World's Languages*, sec. 2.1; Dart 1991, UCLA
  Working Papers in Phonetics 79; the 0-5 mm the tip passes the incisal edges is our reading);
* alveolar (/t d n s z/) and /l/: the tip raised behind the upper incisors towards the alveolar
  ridge (apical contact: Dart 1991), a little forward;
* postalveolar (/ʃ ʒ tʃ dʒ/): raised a little less and 3 mm further back (the blade behind the
  ridge);
* every other class and the pauses: rest.
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
