"""Can the default face make a round opening between its lips? Prints JSON (about a minute).

Each candidate target of a rounded vowel (a jaw angle and muscle activities, both sides alike)
is ramped from rest over 100 ms and held 300 ms on the default face (anatomical preset), as
``benchmarks/visemes.py`` holds the viseme table; at the end it reports the midline lip gap, the
opening's width seen from the front (:func:`facemech.speech.mouth.opening_width`) and their
ratio (the issue's criterion: >= 0.5), the mouth's width over rest, the protrusion of both lip
centres, the lower incisor's drop and the upper and lower incisors shown between the lips
(:func:`facemech.speech.visible_speech.teeth_shown`), mm. ``--grid`` adds the sweep of the
marginal orbicularis (OOSM, OOIM), the lips' raiser and depressor (LLS, DLI), MEN and the jaw
over which the candidates were chosen.

Usage: python benchmarks/rounding.py [--grid]
"""

from __future__ import annotations

import argparse
import itertools
import json
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import default_face, simulate  # noqa: E402
from facemech.params import MUSCLE_GROUPS  # noqa: E402
from facemech.physics.model import model as face_model  # noqa: E402
from facemech.speech.mouth import incisor_drop, mouth_measures, opening_width  # noqa: E402
from facemech.speech.visemes import VISEMES  # noqa: E402
from facemech.speech.visible_speech import teeth_shown  # noqa: E402

RAMP, HOLD, RATE = 0.1, 0.3, 60.0
_OO = {"OOS": 1.0, "OOI": 1.0, "MEN": 0.5}
#: name -> (jaw degrees, activities): the table's /u/, a more open jaw, the marginal
#: orbicularis narrowing the opening, the lips' raiser and depressor opening its middle
CANDIDATES = {
    "close_back_rounded (the table's)": (np.degrees(VISEMES["close_back_rounded"].jaw),
                                         dict(VISEMES["close_back_rounded"].activity)),
    "jaw 4": (4.0, _OO), "jaw 8": (8.0, _OO), "jaw 11": (11.0, _OO),
    "jaw 8, LLS DLI 0.15": (8.0, {**_OO, "LLS": 0.15, "DLI": 0.15}),
    "jaw 8, OOSM OOIM 0.1, LLS DLI 0.2": (8.0, {**_OO, "OOSM": 0.1, "OOIM": 0.1, "LLS": 0.2,
                                                 "DLI": 0.2}),
    "jaw 5, OOSM OOIM 0.6, LLS DLI 0.25": (5.0, {**_OO, "MEN": 0.3, "OOSM": 0.6, "OOIM": 0.6,
                                                  "LLS": 0.25, "DLI": 0.25}),
    "jaw 5, OOSM OOIM 0.6, LLS DLI 0.8": (5.0, {"OOS": 1.0, "OOI": 1.0, "OOSM": 0.6,
                                                 "OOIM": 0.6, "LLS": 0.8, "DLI": 0.8}),
}


def held(model, jaw_deg: float, activity: dict) -> dict:
    """The measures (mm, ratios) of one target held on ``model``."""
    frames = int(round((RAMP + HOLD) * RATE)) + 1
    shape = np.clip(np.arange(frames) / RATE / RAMP, 0.0, 1.0)
    act = np.zeros(len(MUSCLE_GROUPS))
    for g, v in activity.items():
        act[MUSCLE_GROUPS.index(g)] = v
    sim = simulate(model, shape[:, None] * act[None], shape * np.radians(jaw_deg))
    p, pose = sim.positions[-1], sim.jaw_pose[-1]
    m = mouth_measures(sim.model, p)
    w = opening_width(sim.model, p)
    lm, rest = sim.model.landmarks, sim.model.rest_positions
    rest_w = np.linalg.norm(rest[lm["mouth_corner_left"]] - rest[lm["mouth_corner_right"]])
    up, low = teeth_shown(sim.model, p, pose)
    return {"lip_gap_mm": round(1e3 * m["lip_gap"], 2), "opening_width_mm": round(1e3 * w, 2),
            "aspect": round(m["lip_gap"] / w, 3) if w > 0 else None,
            "width_ratio": round(1.0 + m["width_change"] / rest_w, 3),
            "upper_forward_mm": round(1e3 * m["upper_forward"], 2),
            "lower_forward_mm": round(1e3 * m["lower_forward"], 2),
            "incisor_drop_mm": round(1e3 * incisor_drop(sim.model, pose), 2),
            "upper_teeth_mm": round(1e3 * up, 2), "lower_teeth_mm": round(1e3 * low, 2)}


def grid() -> dict:
    """name -> (jaw degrees, activities) of the sweep."""
    out = {}
    for jaw, marg, open_, men, oo in itertools.product((3, 5, 8), (0.0, 0.2, 0.6, 1.0),
                                                        (0.0, 0.25, 0.8), (0.0, 0.5),
                                                        (0.5, 1.0)):
        out[f"jaw {jaw}, OOS OOI {oo}, OOSM OOIM {marg}, LLS DLI {open_}, MEN {men}"] = (
            jaw, {"OOS": oo, "OOI": oo, "OOSM": marg, "OOIM": marg, "LLS": open_,
                  "DLI": open_, "MEN": men})
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", action="store_true")
    args = ap.parse_args(argv)
    model = face_model(default_face())
    cases = {**CANDIDATES, **(grid() if args.grid else {})}
    rows = {name: held(model, jaw, act) for name, (jaw, act) in cases.items()}
    round_ = [r for r in rows.values() if (r["aspect"] or 0.0) >= 0.5]
    forward = [r for r in round_ if min(r["upper_forward_mm"], r["lower_forward_mm"]) >= 2.0]
    print(json.dumps({"targets": rows, "round": len(round_),
                      "round_with_both_lips_2mm_forward": len(forward)}, indent=1))


if __name__ == "__main__":
    main()
