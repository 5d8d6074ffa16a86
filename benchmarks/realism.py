"""How realistic is the default face? Prints JSON (takes several minutes).

- ``gestures``: each of the 16 muscle groups (and OOS+OOI) at full activity, ramped over 0.2 s
  and held 0.5 s, under the anatomical preset and the seeds' ``lucero1999``: the anatomical
  measures of :mod:`facemech.analysis.gestures` (mm), with the issue's minimum amplitudes;
- ``resolutions``: the same gestures on the coarse, default and fine built-in faces;
- ``dynamics``: 10-90 % rise time of steps of activity (0.3 and 1.0) and the overshoot past
  rest after a 100-ms full pulse, at the preset's steps and at 8 times finer steps;
- ``crease``: the largest growth of a fold angle outside the lips for a 10-degree jaw opening;
- ``reachability``: the RMS error of inverting synthetic lip targets with the ranges of real
  speech, the jaw driven from the lower incisor (analysis/reachability.py), with the speech
  controls and orbicularis oris's marginal part, and with the speech controls alone, with the
  RMS of each component (upper and lower lip vertical and front-back, the lower lip on the jaw,
  the corners); benchmarks/reachability.py breaks it down by cause.

Usage: python benchmarks/realism.py [--quick]   (--quick: gestures and crease only)
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import default_face, simulate  # noqa: E402
from facemech.analysis.folds import largest_fold_increase  # noqa: E402
from facemech.analysis.gestures import TARGETS, check_targets, run_gesture  # noqa: E402
from facemech.params import MUSCLE_GROUPS, preset  # noqa: E402
from facemech.physics.model import model as face_model  # noqa: E402

KEYS = ("corner_up", "corner_out", "corner_forward", "upper_lip_up", "lower_lip_down",
        "chin_up", "upper_lip_forward", "lower_lip_forward", "mouth_narrower", "largest")


def gesture_table(face, params) -> dict:
    out = {}
    for name in [*MUSCLE_GROUPS, "OOS+OOI"]:
        m = run_gesture(face_model(face, params), tuple(name.split("+"))).measures
        out[name] = {k: round(float(m[k]), 2) for k in (*KEYS, "lips_forward")}
    return out


def rise_and_overshoot(face, params, substeps=None) -> dict:
    cases = [("ZYG", "mouth_corner_right", 1), ("LLS", "upper_lip_center", 1),
             ("DLI", "lower_lip_center", 1), ("MEN", "chin", 1),
             ("OOS+OOI", "mouth_corner_right", 0), ("DAO", "mouth_corner_right", 1)]
    out = {}
    for group, lm, ax in cases:
        row = {}
        for level in (0.3, 1.0):
            act = np.zeros((61, len(MUSCLE_GROUPS)))
            for g in group.split("+"):
                act[:, MUSCLE_GROUPS.index(g)] = level
            sim = simulate(face_model(face, params), act, substeps=substeps)
            node = sim.model.landmarks[lm]
            y = np.abs(sim.positions[:, node, ax] - sim.positions[0, node, ax])
            fin = y[-1]
            t = np.arange(len(y)) / 60.0
            mono = np.maximum.accumulate(y)
            rise = np.interp(0.9 * fin, mono, t) - np.interp(0.1 * fin, mono, t)
            row[f"rise_ms_at_{level}"] = round(1e3 * float(rise), 1)
            row[f"final_mm_at_{level}"] = round(1e3 * float(fin), 2)
        act = np.zeros((60, len(MUSCLE_GROUPS)))
        for g in group.split("+"):
            act[:6, MUSCLE_GROUPS.index(g)] = 1.0
        sim = simulate(face_model(face, params), act, substeps=substeps)
        node = sim.model.landmarks[lm]
        x = sim.positions[:, node, ax] - sim.positions[0, node, ax]
        x = x * np.sign(x[np.argmax(np.abs(x))])
        k = int(np.argmax(x))
        row["pulse_peak_mm"] = round(1e3 * float(x[k]), 2)
        row["overshoot_past_rest_percent"] = round(100 * float(max(0.0, -x[k:].min()) / x[k]),
                                                   1)
        out[f"{group} ({lm})"] = row
    return out


def crease(face, params) -> float:
    jaw = np.radians(10.0) * np.clip(np.arange(40) / 15, 0, 1)
    sim = simulate(face_model(face, params), np.zeros((40, len(MUSCLE_GROUPS))), jaw)
    return round(largest_fold_increase(sim.model, sim.positions[-1]), 1)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    anat, seeds = preset("anatomical"), preset("lucero1999")
    face = default_face()
    t0 = time.perf_counter()
    report: dict = {"benchmark": "realism", "preset_scales": {
        "force": anat.k_force, "lip_stiffness_factor": anat.lip_stiffness_factor}}
    table = gesture_table(face_model(face, anat))
    report["gestures"] = {"anatomical": table,
                          "lucero1999": gesture_table(face_model(default_face(tissue="uniform"),
                                                                 seeds)),
                          "targets": [{"groups": "+".join(g), "measure": m, "at_least": v}
                                      for g, m, v in TARGETS],
                          "misses": check_targets(table)}
    report["crease_deg"] = {"anatomical": crease(face, anat),
                            "lucero1999": crease(default_face(tissue="uniform"), seeds)}
    if not args.quick:
        res = {}
        for name in ("default-coarse", "default", "default-fine"):
            f = default_face(name)
            for g in ("ZYG", "RIS", "LAO", "DAO", "LLS", "DLI", "MEN", "OOS+OOI"):
                m = run_gesture(face_model(f, anat), tuple(g.split("+"))).measures
                for k in ("corner_up", "corner_out", "upper_lip_up", "lower_lip_down",
                          "chin_up", "mouth_narrower", "lips_forward"):
                    res.setdefault(f"{g} {k}", []).append(round(float(m[k]), 2))
        report["resolutions"] = {
            k: {"coarse_default_fine_mm": v,
                "spread_percent": round(100 * (max(map(abs, v)) - min(map(abs, v)))
                                        / max(abs(v[1]), 1e-9), 1)}
            for k, v in res.items() if abs(v[1]) > 0.5}
        report["dynamics"] = {"preset_steps": rise_and_overshoot(face, anat),
                              "8x_finer_steps": rise_and_overshoot(face, anat,
                                                                   8 * anat.substeps)}
        from facemech.analysis.reachability import REACH_CONTROLS, reach
        from facemech.inverse.invert import SPEECH_CONTROLS

        report["reachability"] = {}
        for label, controls in (("speech+marginal", REACH_CONTROLS),
                                ("speech", SPEECH_CONTROLS)):
            r = reach(face_model(face, anat), controls=controls)
            report["reachability"][label] = {
                "rms_mm": round(r.rms * 1e3, 3),
                "median_frame_rms_mm": round(float(np.median(r.frame_rms)) * 1e3, 3),
                "largest_mm": round(r.largest * 1e3, 2),
                "controls_on_a_bound": round(r.activity_on_bound, 2),
                "components_rms_mm": {k: round(v * 1e3, 3) for k, v in r.components.items()},
                "wall_s": round(r.wall_seconds, 1)}
    report["wall_s"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
