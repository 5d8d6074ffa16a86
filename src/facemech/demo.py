"""The one-command demo: a synthetic utterance on the built-in face, simulated and shown.

The utterance is a string of CV syllables, /ba pi ma wu pa/, 0.42 s apart, built from smooth
(raised-cosine) bursts: bilabial closures bring in OOS and OOI and close the jaw, /a/ opens the
jaw with DLI and DAO, /i/ spreads the lips with ZYG, LAO and RIS, /u/ rounds them with OOS, OOI
and MEN. Activity levels are plausible fractions of maximal effort, not measured data.

The controls and the summary live here; the command that simulates, writes and renders them is
:func:`facemech.workflows.demo.run_demo`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .params import FRAME_RATE_HZ, MUSCLE_GROUPS
from .waveforms import cosine_bump

SYLLABLES = ("ba", "pi", "ma", "wu", "pa")
SYLLABLE_S = 0.42
LEAD_S = 0.25

# vowel targets: jaw angle (deg) and muscle activity
_VOWELS = {
    "a": (9.0, {"DLI": 0.35, "DAO": 0.25}),
    "i": (3.0, {"ZYG": 0.55, "LAO": 0.45, "RIS": 0.6, "LLS": 0.2}),
    "u": (4.0, {"OOS": 0.55, "OOI": 0.55, "MEN": 0.4}),
}
# consonant targets: muscle activity at the closure (the jaw closes towards 0.5 deg)
_CONSONANTS = {
    "b": {"OOS": 0.6, "OOI": 0.7, "MEN": 0.3},
    "p": {"OOS": 0.8, "OOI": 0.85, "MEN": 0.4},
    "m": {"OOS": 0.45, "OOI": 0.5},
    "w": {"OOS": 0.6, "OOI": 0.6, "MEN": 0.2},
}


_bump = cosine_bump


def utterance(frame_rate: float = FRAME_RATE_HZ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Synthetic speech-like controls.

    Returns
    -------
    time : (frames,) s
    activity : (frames, groups) in [0, 1]
    jaw_angle : (frames,) rad
    """
    duration = 2 * LEAD_S + SYLLABLE_S * len(SYLLABLES)
    t = np.arange(int(round(duration * frame_rate))) / frame_rate
    act = np.zeros((len(t), len(MUSCLE_GROUPS)))
    jaw = np.zeros(len(t))
    for k, syl in enumerate(SYLLABLES):
        onset = LEAD_S + k * SYLLABLE_S
        cons, vow = syl[0], syl[1]
        closure = _bump(t, onset + 0.06, 0.20)
        vowel = _bump(t, onset + 0.24, 0.30)
        for g, a in _CONSONANTS[cons].items():
            act[:, MUSCLE_GROUPS.index(g)] += a * closure
        angle, muscles = _VOWELS[vow]
        for g, a in muscles.items():
            act[:, MUSCLE_GROUPS.index(g)] += a * vowel
        jaw += np.radians(angle) * vowel
    return t, np.clip(act, 0.0, 1.0), jaw


@dataclass(frozen=True)
class DemoSummary:
    frames: int
    simulated_seconds: float
    wall_seconds: float
    simulation_seconds: float
    real_time_factor: float
    largest_lip_displacement_mm: float
    integrator: str
    output: dict
    preset: str = "anatomical"

    def as_dict(self) -> dict:
        return self.__dict__.copy()
