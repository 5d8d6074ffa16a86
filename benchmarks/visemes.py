"""The viseme table measured on the default face. Prints JSON (about a minute).

- ``targets``: each class's target (:data:`facemech.speech.visemes.VISEMES`) ramped from rest
  over 100 ms and held 300 ms on the default face (anatomical preset); at the end: the lip gap
  at the midline (the lips' contact twins, :mod:`facemech.speech.mouth`), the protrusion of the
  upper and lower lip centres (+z from rest), the change of mouth width, the jaw angle and the
  lower incisor's drop (mm, degrees). A target's jaw below rest (the bilabials' virtual target)
  is held at rest, as :func:`controls_from_alignment` clips it.
- ``lag_without_lead`` and ``lag_with_lead``: one phone between pauses or vowels, controls from
  :func:`controls_from_alignment` with no lead and with the default leads: the time (ms) from
  its acoustic centre to the visible extreme of the measure the class moves most (for a
  bilabial: the middle of the interval with the lips closed, gap < 0.5 mm), and the measure at
  the acoustic centre.

Usage: python benchmarks/visemes.py [--no-lag]
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import default_face, simulate  # noqa: E402
from facemech.physics.model import model as face_model  # noqa: E402
from facemech.speech.alignment import Alignment, Segment  # noqa: E402
from facemech.speech.coarticulation import (  # noqa: E402
    JAW_LEAD_S,
    LEAD_S,
    controls_from_alignment,
)
from facemech.speech.mouth import incisor_drop, mouth_measures  # noqa: E402
from facemech.speech.visemes import VISEMES  # noqa: E402

RAMP, HOLD, RATE = 0.1, 0.3, 60.0


def held_target(face, cls: str) -> dict:
    v = VISEMES[cls]
    frames = int(round((RAMP + HOLD) * RATE)) + 1
    shape = np.clip(np.arange(frames) / RATE / RAMP, 0.0, 1.0)
    act = shape[:, None] * v.activity_vector()[None]
    jaw = max(v.jaw, 0.0)  # as the controls: the teeth meet, the jaw never closes past rest
    sim = simulate(face_model(face), act, shape * jaw)
    m = mouth_measures(sim.model, sim.positions[-1])
    return {"lip_gap_mm": round(1e3 * m["lip_gap"], 2),
            "upper_forward_mm": round(1e3 * m["upper_forward"], 2),
            "lower_forward_mm": round(1e3 * m["lower_forward"], 2),
            "width_change_mm": round(1e3 * m["width_change"], 2),
            "jaw_deg": round(float(np.degrees(jaw)), 2),
            "incisor_drop_mm": round(1e3 * incisor_drop(sim.model, sim.jaw_pose[-1]), 2)}


#: (context before, phone, context after, measure, sign of its extreme) for the lag
LAG_CASES = (("_", "u:", "_", "lips_forward", 1), ("_", "i:", "_", "width_change", 1),
             ("_", "A:", "_", "lip_gap", 1), ("A:", "b", "A:", "lip_gap", -1),
             ("u:", "m", "u:", "lip_gap", -1))


def lag_series(face, before: str, label: str, after: str, key: str, *, dur: float = 0.16,
               lead: float = 0.0, jaw_lead: float = 0.0):
    """Simulate ``before label after`` (eSpeak; 0.25-s pauses at the ends, neighbours of
    0.2 s) and return (time s, series, acoustic centre of ``label`` s)."""
    labels, durs = ["_"], [0.25]
    for lab, d in ((before, 0.2), (label, dur), (after, 0.2)):
        if lab != "_":
            labels.append(lab)
            durs.append(d)
    labels.append("_")
    durs.append(0.3)
    edges = np.concatenate([[0.0], np.cumsum(durs)])
    al = Alignment(words=(), phones=tuple(Segment(lab, a, b) for lab, a, b
                                          in zip(labels, edges[:-1], edges[1:], strict=True)),
                   notation="espeak", duration=float(edges[-1]))
    k = labels.index(label)
    t, act, jaw = controls_from_alignment(al, lead_s=lead, jaw_lead_s=jaw_lead)
    sim = simulate(face_model(face), act, jaw)
    series = mouth_measures(sim.model, sim.positions)[key]
    return t, series, 0.5 * (edges[k] + edges[k + 1])


def extreme_time(t, s) -> float:
    """Time (s) of the largest value of ``s``, refined by a parabola through its neighbours."""
    k = int(np.argmax(s))
    if 0 < k < len(s) - 1:
        a, b, c = s[k - 1], s[k], s[k + 1]
        den = a - 2 * b + c
        return float(t[k] + (0.5 * (a - c) / den if den != 0 else 0.0) * (t[1] - t[0]))
    return float(t[k])


def closure_centre(t, gap, centre, threshold=0.5e-3) -> float:
    """Midpoint (s) of the run of frames with the lip gap under ``threshold`` nearest
    ``centre``; NaN if the lips never close."""
    closed = gap < threshold
    if not closed.any():
        return float("nan")
    k = int(np.argmin(np.where(closed, np.abs(t - centre), np.inf)))
    a = b = k
    while a > 0 and closed[a - 1]:
        a -= 1
    while b < len(t) - 1 and closed[b + 1]:
        b += 1
    return 0.5 * (t[a] + t[b])


def lag(face, before, label, after, key, sign, *, lead=0.0, jaw_lead=0.0) -> dict:
    """Acoustic centre -> visible extreme (ms) of one phone in context."""
    t, s, centre = lag_series(face, before, label, after, key, lead=lead, jaw_lead=jaw_lead)
    if sign < 0:  # a closure: the middle of the closed interval
        when = closure_centre(t, s, centre)
        size = float(np.interp(centre, t, s))
    else:
        when = extreme_time(t, s)
        size = float(np.interp(centre, t, s))
    return {"visible_lag_ms": round(1e3 * (when - centre), 1),
            "at_acoustic_centre_mm": round(1e3 * size, 2)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--no-lag", action="store_true")
    args = ap.parse_args()
    face = default_face()
    out = {"targets": {c: held_target(face, c) for c in VISEMES}}
    if not args.no_lag:
        for name, lead, jaw_lead in (("lag_without_lead", 0.0, 0.0),
                                     ("lag_with_lead", LEAD_S, JAW_LEAD_S)):
            out[name] = {f"{b} {lab} {a} ({key})": lag(face, b, lab, a, key, sign, lead=lead,
                                                       jaw_lead=jaw_lead)
                         for b, lab, a, key, sign in LAG_CASES}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
