"""Inversion benchmark (prints JSON): Experiment 1 of Pitermann & Munhall (2001) by the fast
method (lsq) and by Powell in one process, and a 3-s utterance inverted by the fast method.

Usage: python benchmarks/inversion.py [--frames N] [--skip-powell] [--preset NAME --dt S]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import MarkerSet, default_face, simulate  # noqa: E402
from facemech.demo import utterance  # noqa: E402
from facemech.inverse import stats  # noqa: E402
from facemech.inverse.experiments import synthetic_data  # noqa: E402
from facemech.inverse.invert import invert  # noqa: E402
from facemech.params import preset  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=36, help="frames of Experiment 1 to use")
    ap.add_argument("--skip-powell", action="store_true")
    ap.add_argument("--utterance-frames", type=int, default=180)
    ap.add_argument("--preset", default="lucero1999")
    ap.add_argument("--dt", type=float, default=None,
                    help="Euler step, s (default: the preset's fast step)")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    face = default_face()
    prm = preset(args.preset)
    dt = prm.fast_dt if args.dt is None else args.dt
    data, truth = synthetic_data(face, params=prm, dt=dt)
    data = MarkerSet(data.positions[: args.frames], data.names, 60.0)
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    out = {"benchmark": "inversion", "experiment1_frames": args.frames, "preset": args.preset,
           "dt_s": dt, "methods": {}}
    for method in ("lsq", "powell"):
        if method == "powell" and args.skip_powell:
            continue
        t0 = time.perf_counter()
        res = invert(face, data, used, method=method, positive=True, params=prm, dt=dt)
        wall = time.perf_counter() - t0
        err = stats.frame_errors(res.model_markers[1:], data.select(list(used)).positions[1:])
        out["methods"][method] = {"wall_s": wall, "steps": int(res.evaluations.sum()),
                                  "median_frame_error_mm": float(np.median(err) * 1e3),
                                  "max_frame_error_mm": float(err.max() * 1e3)}
    if "powell" in out["methods"]:
        out["speedup_lsq_over_powell"] = (out["methods"]["powell"]["wall_s"]
                                          / out["methods"]["lsq"]["wall_s"])
    # a speech-like utterance (the demo's), markers from the model, jaw from the chin marker
    t, act, jaw = utterance()
    n = min(args.utterance_frames, len(t))
    sim = simulate(face, act[:n], jaw[:n], integrator="euler", dt=dt, params=prm)
    names = [m for m in face.markers if m.startswith("R")]
    ms = MarkerSet(sim.positions[:, [face.markers[m] for m in names]], tuple(names), 60.0)
    t0 = time.perf_counter()
    res = invert(face, ms, {m: face.markers[m] for m in names}, jaw_angle=jaw[:n], params=prm,
                 dt=dt)
    wall = time.perf_counter() - t0
    out["utterance"] = {"frames": n, "seconds": n / 60, "wall_s": wall,
                        "wall_s_per_3s": wall * 180 / n,
                        "median_frame_error_mm": float(np.median(res.rms_error[1:]) * 1e3),
                        "target_s_per_3s": 60.0}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
