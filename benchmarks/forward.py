"""Forward-simulation benchmark on the built-in face (prints JSON).

For the demo utterance: the default (anatomical) preset's wall seconds per simulated second and
real-time factor on one core, and where its step's time goes; then, for the seeds' lucero1999,
mesh counts, each integrator's real-time factor and its largest deviation from the paper's
explicit Euler (all epidermal nodes and the markers), and one step's force assembly and
sparse solve.

Usage: python benchmarks/forward.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech import Physics, Stepper, default_face, preset, simulate  # noqa: E402
from facemech.demo import utterance  # noqa: E402
from facemech.physics.assembly import accumulate_forces, rest_anchors  # noqa: E402


def timed(fn, repeat=3):
    best = np.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="first 60 frames only, one repeat")
    args = ap.parse_args()
    t, act, jaw = utterance()
    if args.quick:
        t, act, jaw = t[:60], act[:60], jaw[:60]
    simulated = len(t) / 60.0
    repeat = 1 if args.quick else 3
    anat = preset("anatomical")
    anat_face = default_face()
    simulate(anat_face, act[:3], jaw[:3], params=anat)
    wall, sim = timed(lambda: simulate(anat_face, act, jaw, params=anat), repeat)
    ph_a = Physics.build(anat_face, anat)
    ss_a = Stepper(ph_a).solver_state
    m_a = np.zeros(ph_a.n_muscles)
    anchors_a = rest_anchors(ph_a)
    pos_a = anat_face.rest_positions.copy()
    vel_a = np.zeros_like(pos_a)
    out_a = np.zeros_like(pos_a)
    t0 = time.perf_counter()
    for _ in range(200):
        accumulate_forces(ss_a.forces, pos_a, vel_a, m_a, anchors_a, out_a)
    force_a = (time.perf_counter() - t0) / 200 * 1e3
    rhs_a = np.random.default_rng(0).normal(size=(ph_a.n_dynamic, 3))
    t0 = time.perf_counter()
    for _ in range(200):
        ss_a.system.lu.solve(rhs_a)
    solve_a = (time.perf_counter() - t0) / 200 * 1e3
    sa = anat_face.summary()
    anatomical = {"preset": "anatomical", "integrator": sim.integrator,
                  "steps_per_frame": sim.attrs["steps_per_frame"],
                  "wall_s_per_simulated_s": wall / simulated,
                  "real_time_factor": simulated / wall,
                  "mesh": {"moving_nodes": sa["moving_nodes"], "springs": sa["springs"],
                           "prisms": sa["prisms"], "muscles": sa["muscles"]},
                  "per_step_ms": {"force_assembly": force_a, "sparse_solve_3_axes": solve_a}}
    face = default_face(tissue="uniform")
    seeds = preset("lucero1999")
    # warm up the compiled kernels
    simulate(face, act[:3], jaw[:3], params=seeds, integrator="euler")
    simulate(face, act[:3], jaw[:3], params=seeds, integrator="rosenbrock")
    variants = [("euler", "euler", {}), ("euler-1ms", "euler", {"dt": 1e-3}),
                ("implicit-4", "implicit", {"substeps": 4}),
                ("implicit-8", "implicit", {"substeps": 8}),
                ("rosenbrock-2", "rosenbrock", {"substeps": 2}),
                ("rosenbrock-4", "rosenbrock", {"substeps": 4}),
                ("rosenbrock-8", "rosenbrock", {"substeps": 8})]
    results = {}
    sims = {}
    for label, integ, kw in variants:
        wall, sim = timed(lambda i=integ, k=kw: simulate(face, act, jaw, integrator=i,
                                                         params=seeds, **k), repeat)
        sims[label] = sim
        results[label] = {"integrator": integ, **kw,
                          "wall_s_per_simulated_s": wall / simulated,
                          "real_time_factor": simulated / wall}
    ref = sims["euler"]
    for label, sim in sims.items():
        if label == "euler":
            continue
        nodes = np.linalg.norm(sim.positions - ref.positions, axis=2)
        marks = np.linalg.norm(sim.markers - ref.markers, axis=2)
        results[label]["max_deviation_nodes_mm"] = float(nodes.max() * 1e3)
        results[label]["max_deviation_markers_mm"] = float(marks.max() * 1e3)
        results[label]["rms_deviation_nodes_mm"] = float(np.sqrt(np.mean(nodes**2)) * 1e3)
    # where the time of one step goes
    ph = Physics.build(face, seeds)
    ss = Stepper(ph, integrator="rosenbrock", substeps=4).solver_state
    m = np.zeros(ph.n_muscles)
    anchors = rest_anchors(ph)
    pos = face.rest_positions.copy()
    vel = np.zeros_like(pos)
    out = np.zeros_like(pos)
    n = 300
    t0 = time.perf_counter()
    for _ in range(n):
        accumulate_forces(ss.forces, pos, vel, m, anchors, out)
    force_ms = (time.perf_counter() - t0) / n * 1e3
    rhs = np.random.default_rng(0).normal(size=(ph.n_dynamic, 3))
    t0 = time.perf_counter()
    for _ in range(n):
        ss.system.lu.solve(rhs)
    solve_ms = (time.perf_counter() - t0) / n * 1e3
    s = face.summary()
    report = {
        "benchmark": "forward",
        "utterance_frames": len(t),
        "simulated_seconds": simulated,
        "anatomical": anatomical,
        "mesh": {"epidermal_nodes": s["nodes_per_layer"]["epidermis"], "nodes": s["nodes"],
                 "springs": s["springs"], "prisms": s["prisms"], "muscles": s["muscles"],
                 "dynamic_nodes": ph.n_dynamic},
        "integrators": results,
        "per_step_ms": {"force_assembly": force_ms, "sparse_solve_3_axes": solve_ms,
                        "euler_step_estimate": force_ms,
                        "rosenbrock_step_estimate": 2 * (force_ms + solve_ms)},
        "threads": 1,
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
