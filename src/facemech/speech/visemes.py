"""Visemes: the target of the face for each articulatory class, and its dominance.

A target is the activity of the muscle groups (in [0, 1], both sides alike) and a jaw angle
(rad, positive opens) that, held, give the face the visible shape of the class. The targets were
set on the default face (anatomical preset) and measured with ``benchmarks/visemes.py``: each
held for 300 ms after a 100-ms ramp; docs/stimuli.md ("Visemes and coarticulation") lists the
measured lip gap, protrusion, mouth width and jaw drop beside the magnitudes of real speech they
aim at.

Each target also carries the parameters of its dominance function (Cohen & Massaro 1993, used by
:mod:`facemech.speech.coarticulation`): a magnitude for the lips (the muscle activity) and one for
the jaw, and the rates at which the dominance falls off before (anticipatory) and after
(carry-over) the phone's centre. A high magnitude makes the class win over its neighbours: the
bilabials and labiodentals, whose lips must close or touch, dominate; the lips of an alveolar or
velar are free, so they take the rounding or spreading of the vowels around them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from ..errors import InputError
from ..params import MUSCLE_GROUPS


@dataclass(frozen=True)
class Viseme:
    """The target of one articulatory class and its dominance.

    Attributes
    ----------
    activity : mapping group -> activity in [0, 1] (groups not named: 0)
    jaw : float, rad (positive opens)
    lips_dominance : float, magnitude alpha of the dominance of the muscle activity
    jaw_dominance : float, magnitude alpha of the dominance of the jaw
    anticipatory_rate : float, 1/s, theta of the dominance before the phone's centre
    carryover_rate : float, 1/s, theta of the dominance after the phone's centre
    """

    activity: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    jaw: float = 0.0
    lips_dominance: float = 1.0
    jaw_dominance: float = 1.0
    anticipatory_rate: float = 12.0
    carryover_rate: float = 15.0

    def activity_vector(self) -> np.ndarray:
        """(groups,) activity in the order of :data:`~facemech.params.MUSCLE_GROUPS`."""
        a = np.zeros(len(MUSCLE_GROUPS))
        for g, v in self.activity.items():
            a[MUSCLE_GROUPS.index(g)] = v
        return a


def _v(jaw_deg: float, lips: float, jaw_dom: float, ant: float, carry: float, **act) -> Viseme:
    return Viseme(MappingProxyType(act), float(np.radians(jaw_deg)), lips, jaw_dom, ant, carry)


#: class -> viseme on the default face (numbers measured in docs/stimuli.md)
VISEMES: MappingProxyType = MappingProxyType({
    # consonants                 jaw deg, lips alpha, jaw alpha, theta ant, theta carry (1/s)
    "bilabial": _v(-2.0, 60.0, 60.0, 30.0, 40.0, MEN=0.8),
    # /f v/: the jaw nearly closed, the lower lip drawn down and back to the upper incisors'
    # edge by its own muscles (Ladefoged & Maddieson 1996; the jaw high for /f/, Keating et
    # al. 1994). Held on the default face: the lip's edge 0.75 mm above the upper incisors'
    # edge, 2.1 mm of them showing, the lower incisors hidden (a jaw of 2.5 degrees with DLI
    # 0.18, DAO 0.1 and OOIM 0.3 left the lip's edge 1.7 mm under the edge, the lower
    # incisors bared)
    "labiodental": _v(1.0, 25.0, 40.0, 40.0, 45.0, DLI=0.12, OOI=0.3, OOIM=0.4),
    "dental": _v(1.5, 1.0, 4.0, 20.0, 25.0, LLS=0.1),
    "alveolar": _v(1.5, 0.4, 4.0, 20.0, 25.0),
    "postalveolar": _v(1.5, 4.0, 4.0, 20.0, 25.0, OOS=0.4, OOI=0.4),
    "velar": _v(3.0, 0.4, 1.5, 20.0, 25.0),
    "glottal": _v(4.0, 0.05, 0.05, 20.0, 25.0),
    # /w/: the jaw nearly closed, as for /u/; its jaw's dominance 12, so that an open vowel after
    # it does not open the jaw within the /w/ and draw the lower lip back with it
    "w": _v(1.5, 40.0, 12.0, 15.0, 20.0, OOS=0.9, OOI=1.0, MEN=0.5),
    "r": _v(2.0, 2.0, 1.5, 18.0, 22.0, OOS=0.35, OOI=0.3),
    "l": _v(3.5, 0.4, 1.5, 20.0, 25.0),
    "j": _v(1.5, 2.0, 2.0, 18.0, 22.0, ZYG=0.4, RIS=0.5, LLS=0.15, DLI=0.1),
    # vowels (/i/: ZYG and RIS at 0.6 widen 2.7 mm a side; at 1.0 the lower lip went 7 mm
    # back along the teeth, rolled in, docs/stimuli.md)
    "close_front_spread": _v(2.5, 8.0, 1.5, 12.0, 15.0, ZYG=0.6, RIS=0.6, LAO=0.15, LLS=0.2,
                             DLI=0.12),
    # /ɪ/ and the ends of /eɪ aɪ ɔɪ/: lax, every number halfway from /i/ to the mid vowel (a
    # near-close near-front vowel); with /i/'s spread, ZYG and RIS held the lower lip up over
    # the teeth through whole sentences (docs/stimuli.md)
    "close_front_lax": _v(4.25, 4.5, 1.75, 12.0, 15.0, ZYG=0.3, RIS=0.3, LAO=0.075,
                          LLS=0.1, DLI=0.11),
    "close_back_rounded": _v(2.5, 24.0, 1.5, 15.0, 15.0, OOS=0.9, OOI=1.0, MEN=0.5),
    # /ɑ æ a/: the lips' own opening (DLI, LLS) beside the jaw's, so that a short open vowel
    # under the jaw's speed limit still opens and shows the upper incisors (held: 21 mm
    # open, 5.7 mm of the upper incisors showing; with DLI 0.3 alone 15.7 and 1.8 mm)
    "open": _v(12.0, 4.0, 8.0, 12.0, 15.0, DLI=0.4, LLS=0.2),
    "open_rounded": _v(11.0, 4.0, 8.0, 12.0, 15.0, OOS=0.25, OOI=0.25),
    "mid": _v(6.0, 1.0, 2.0, 12.0, 15.0, DLI=0.1),
    "mid_rounded": _v(6.5, 2.0, 2.0, 12.0, 15.0, OOS=0.45, OOI=0.45),
    "schwa": _v(3.5, 0.5, 0.8, 15.0, 18.0),
    # silence: the face at rest
    "pause": _v(0.0, 3.0, 3.0, 15.0, 15.0),
})  # fmt: skip


def viseme(cls: str) -> Viseme:
    """The viseme of an articulatory class (:data:`~facemech.speech.phoneclass.CLASSES`)."""
    try:
        return VISEMES[cls]
    except KeyError:
        raise InputError(f"no viseme for class {cls!r}", field="class") from None
