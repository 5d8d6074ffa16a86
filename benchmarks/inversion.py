"""Inversion benchmark (prints JSON), one core.

1. The default: 3 s of the demo utterance (jaw moving), simulated under the default preset,
   its 37 landmarks and markers inverted with the default method and options (lsq, the jaw
   estimated). Target: at most 15 s per 3 s of speech.
2. Experiment 1 of Pitermann & Munhall (2001) under ``lucero1999`` by the methods of
   ``--methods`` (default: lsq only; Powell is opt-in, ``--methods lsq,powell``). Powell is run
   on the first ``--powell-frames`` frames only and its time per frame extrapolated to the whole
   experiment (said so in the output). Each method reports its model frame steps per frame.
3. Experiment 1 under the default preset (``anatomical``), least squares, both constraints:
   the case where a frame takes several trial rolls (frame steps per frame and errors).

Usage: python benchmarks/inversion.py [--seconds 3] [--methods lsq[,powell]] [--powell-frames 6]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import MarkerSet, default_face, simulate  # noqa: E402
from facemech.demo import utterance  # noqa: E402
from facemech.inverse.experiments import EXPERIMENT_SETTINGS, synthetic_data  # noqa: E402
from facemech.inverse.invert import invert  # noqa: E402
from facemech.params import preset  # noqa: E402
from facemech.physics.model import model as face_model  # noqa: E402


def default_inversion(face, seconds: float) -> dict:
    t, act, jaw = utterance()
    n = min(int(round(seconds * 60)), len(t))
    sim = simulate(face_model(face), act[:n], jaw[:n])
    names = list(sim.marker_names)
    ms = MarkerSet(sim.markers, tuple(names), 60.0)
    mapping = dict(zip(names, [*face.landmarks.values(), *face.markers.values()], strict=True))
    t0 = time.perf_counter()
    res = invert(face_model(face), ms, mapping)
    wall = time.perf_counter() - t0
    s = res.error_summary()
    g = [res.control_names.index(c) for c in res.control_names if c != "jaw"]
    r = {c: float(np.corrcoef(act[: n - 1, idx], res.activity[:-1, idx])[0, 1])
         for c, idx in ((res.control_names[j], _group(res.control_names[j])) for j in g)
         if np.std(act[: n - 1, idx]) > 0}
    return {"frames": n, "seconds": n / 60, "wall_s": wall, "wall_s_per_3s": wall * 180 / n,
            "target_s_per_3s": 15.0, "steps": int(res.evaluations.sum()),
            "steps_per_frame": float(res.evaluations[1:].mean()),
            "median_frame_error_mm": s["median_mm"], "max_frame_error_mm": s["max_mm"],
            "jaw_r": float(np.corrcoef(jaw[:n], res.jaw_angle)[0, 1]),
            "activity_r": r, "identifiable": dict(zip(res.control_names,
                                                      map(bool, res.identifiable),
                                                      strict=True))}


def _group(name: str) -> int:
    from facemech.params import MUSCLE_GROUPS

    return MUSCLE_GROUPS.index(name)


def experiment1(face, powell_frames: int, methods=("lsq",)) -> dict:
    prm = preset("lucero1999")
    data, truth = synthetic_data(face_model(face, prm))
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    out: dict = {"frames": data.n_frames, "preset": "lucero1999", "methods": {}}
    for method in methods:
        n = data.n_frames if method == "lsq" else min(powell_frames, data.n_frames)
        part = MarkerSet(data.positions[:n], data.names, 60.0)
        kw = (dict(EXPERIMENT_SETTINGS) if method == "lsq"
              else {"controls": EXPERIMENT_SETTINGS["controls"]})
        t0 = time.perf_counter()
        res = invert(face_model(face, prm), part, used, method=method,
                     jaw_angle=np.zeros(n), **kw)
        wall = time.perf_counter() - t0
        entry = {"frames_run": n, "wall_s": wall, "steps": int(res.evaluations.sum()),
                 "steps_per_frame": float(res.evaluations[1:].mean()),
                 "median_frame_error_mm": res.error_summary()["median_mm"]}
        if n < data.n_frames:
            entry["wall_s_extrapolated"] = wall * (data.n_frames - 1) / max(n - 1, 1)
            entry["note"] = (f"run on the first {n} of {data.n_frames} frames; the time is "
                             "extrapolated by frames")
        out["methods"][method] = entry
    if "powell" in out["methods"] and "lsq" in out["methods"]:
        p = out["methods"]["powell"]
        out["speedup_lsq_over_powell"] = (p.get("wall_s_extrapolated", p["wall_s"])
                                          / out["methods"]["lsq"]["wall_s"])
    return out


def experiment1_default(face) -> dict:
    """Experiment 1 under the default preset by least squares, with and without the positive
    constraint: frame steps per frame and the median / max per-frame error (mm)."""
    from facemech.inverse.experiments import run_synthetic

    prm = preset("anatomical")
    t0 = time.perf_counter()
    res = run_synthetic(face_model(face, prm), methods=("lsq",))
    out: dict = {"preset": "anatomical", "frames": res.frames,
                 "wall_s": time.perf_counter() - t0, "runs": {}}
    for label, run in res.runs.items():
        out["runs"][label] = {"steps": run.evaluations,
                              "steps_per_frame": run.evaluations / (res.frames - 1),
                              "median_frame_error_mm": run.frame_error_mm["median"],
                              "max_frame_error_mm": run.frame_error_mm["max"]}
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=3.0, help="speech to invert, s")
    ap.add_argument("--powell-frames", type=int, default=6)
    ap.add_argument("--methods", default="lsq",
                    help="Experiment 1's methods, comma-separated: lsq, powell (slow)")
    args = ap.parse_args()
    methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
    if not methods or set(methods) - {"lsq", "powell"}:
        ap.error(f"--methods takes lsq and/or powell (got {args.methods!r})")
    warnings.simplefilter("ignore")
    from threadpoolctl import threadpool_limits

    face = default_face()
    with threadpool_limits(1):
        out = {"benchmark": "inversion", "default": default_inversion(face, args.seconds),
               "experiment1": experiment1(face, args.powell_frames, methods),
               "experiment1_anatomical": experiment1_default(face)}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
