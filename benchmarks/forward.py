"""Forward-simulation benchmark on the built-in face (prints JSON).

For the demo utterance: the default (anatomical) preset's wall seconds per simulated second and
real-time factor on one core, and where its step's time goes; then, for the seeds' lucero1999,
mesh counts, each integrator's real-time factor and its largest deviation from the paper's
explicit Euler (all epidermal nodes and the markers), and one step's force assembly and
sparse solve.

First, the explicit step's cost against a bare kernel: one explicit Euler step of the default
(anatomical) face's full forces (``euler_frame``: springs, prisms, muscles, tethers, contact)
and a bare numba spring-and-dashpot Euler step over the same nodes and springs, timed
interleaved in this process (best of the repeats, frames of 50 steps), with their ratio and
where one thread's step goes (springs, prisms, the rest); with ``--threads 1,2`` the full step
and the force assembly alone (``accumulate_forces``) on each thread count, interleaved, and
their speed-ups against the first, beside the machine's ceiling (``machine_ceiling_speedup``:
n independent bare kernels side by side against one; below n when other work holds the
cores, so that a speed-up is read against it); ``--preset lucero1999``
the same for the seeds' tissue.

Usage: python benchmarks/forward.py [--quick] [--threads 1,2] [--step-only] [--preset P]
       [--repeat N] [--face FACE.npz]
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numba as nb
import numpy as np

from facemech import Physics, Stepper, default_face, load_face, preset, simulate
from facemech.demo import utterance
from facemech.physics.assembly import accumulate_forces, element_forces_one_thread, rest_anchors
from facemech.physics.bundles import PrismBundle, SlabBundle
from facemech.physics.model import model as face_model
from facemech.physics.slabs import slab_axis
from facemech.physics.threads import set_threads
from facemech.solvers.explicit import EulerSteps, euler_frame
from facemech.solvers.solver_state import solver_state


@nb.njit(cache=True)
def bare_euler(spring_i, spring_j, rest, k, damping, inv_mass, dynamic, pos, vel, dt, n_steps):
    """The reference: n_steps Euler-Cromer steps of linear springs with dashpots alone."""
    out = np.zeros_like(pos)
    for _ in range(n_steps):
        out[:] = 0.0
        for s in range(spring_i.shape[0]):
            i = spring_i[s]
            j = spring_j[s]
            dx = pos[j, 0] - pos[i, 0]
            dy = pos[j, 1] - pos[i, 1]
            dz = pos[j, 2] - pos[i, 2]
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            t = k[s] * (length - rest[s]) / length
            r = damping[s]
            fx = t * dx + r * (vel[j, 0] - vel[i, 0])
            fy = t * dy + r * (vel[j, 1] - vel[i, 1])
            fz = t * dz + r * (vel[j, 2] - vel[i, 2])
            out[i, 0] += fx
            out[i, 1] += fy
            out[i, 2] += fz
            out[j, 0] -= fx
            out[j, 1] -= fy
            out[j, 2] -= fz
        for q in range(dynamic.shape[0]):
            i = dynamic[q]
            for a in range(3):
                vel[i, a] += dt * inv_mass[i] * out[i, a]
                pos[i, a] += dt * vel[i, a]


@nb.njit(cache=True, parallel=True)
def bare_side_by_side(spring_i, spring_j, rest, k, damping, inv_mass, dynamic, pos, vel, dt,
                      n_steps):
    """:func:`bare_euler` on ``len(pos)`` independent copies of the face at once, one a thread:
    no shared data, no waiting, so its throughput against one copy is the most that this
    machine's cores give at the moment (the ceiling of any thread speed-up)."""
    for c in nb.prange(pos.shape[0]):
        bare_euler(spring_i, spring_j, rest, k, damping, inv_mass, dynamic, pos[c], vel[c], dt,
                   n_steps)


@nb.njit(cache=True)
def assembly_steps(forces, pos, vel, m, anchors, out, n_steps):
    """The force assembly alone, ``n_steps`` times (no Python between the calls)."""
    for _ in range(n_steps):
        accumulate_forces(forces, pos, vel, m, anchors, out)


def step_benchmark(threads, repeat=15, n_steps=50, preset_name="anatomical",
                   face_spec=None) -> dict:
    """Microseconds per explicit step of the default face's full forces on each thread count
    and of :func:`bare_euler` (one thread), interleaved; best of ``repeat`` frames of
    ``n_steps`` steps (the paper's frame: 50). With where one thread's step goes: the springs,
    the prisms, and the rest (muscles, tethers, contact, the Euler-Cromer update)."""
    ph = Physics.build(load_face(face_spec), preset(preset_name))
    ss = solver_state(ph, 1)
    f = ss.forces
    s = f.springs
    anchors = rest_anchors(ph)
    rng = np.random.default_rng(0)
    pos = ph.model.rest_positions + rng.normal(0, 1e-5, ph.model.rest_positions.shape)
    m = np.full(ph.n_muscles, 0.5)
    dt = 1e-6  # a short step: the perturbed face stays put, the work per step is the same
    steps = EulerSteps(n_steps, dt, ss.tau, ss.dynamic, ss.inv_mass)
    out = np.zeros_like(pos)
    no_prisms = PrismBundle.empty()
    no_springs = SlabBundle.empty().springs

    def full():
        euler_frame(f, ss.jaw, steps, pos, np.zeros_like(pos), m, np.zeros_like(m), m, anchors,
                    np.zeros(3), np.zeros(3))

    def bare():
        bare_euler(s.i, s.j, s.rest_length, s.k_low, s.damping, ss.inv_mass, ss.dynamic,
                   pos.copy(), np.zeros_like(pos), dt, n_steps)

    def springs():
        for _ in range(n_steps):
            out[:] = 0.0
            element_forces_one_thread(s, no_prisms, pos, pos, out)

    def prisms():
        for _ in range(n_steps):
            out[:] = 0.0
            element_forces_one_thread(no_springs, f.prisms, pos, pos, out)

    vel = np.zeros_like(pos)

    def assembly():
        assembly_steps(f, pos, vel, m, anchors, out, n_steps)

    def side_by_side(n):
        def run():
            bare_side_by_side(s.i, s.j, s.rest_length, s.k_low, s.damping, ss.inv_mass,
                              ss.dynamic, np.repeat(pos[None], n, 0),
                              np.zeros((n,) + pos.shape), dt, n_steps)
        return run

    runs = {**{n: full for n in threads}, **{("assembly", n): assembly for n in threads},
            **{("ceiling", n): side_by_side(n) for n in threads[1:]},
            "bare": bare, "springs": springs, "prisms": prisms}
    best = {}
    for _ in range(repeat + 1):  # the first round compiles and warms the caches
        for key, run in runs.items():
            set_threads(key if isinstance(key, int) else key[1] if isinstance(key, tuple)
                        else 1)
            t0 = time.perf_counter()
            run()
            best[key] = min(best.get(key, np.inf), time.perf_counter() - t0)
    set_threads(1)
    us = {k: v / n_steps * 1e6 for k, v in best.items()}
    full_1 = us[threads[0]]
    report = {"preset": preset_name, "face": face_spec or "default", "nodes": len(pos),
              "springs": len(s.i), "slabs": len(f.slabs.spring_ptr) - 1,
              "slab_axis": slab_axis(s, f.prisms, ph.model.rest_positions),
              "prisms": len(f.prisms.nodes), "steps_per_frame": n_steps,
              "bare_us_per_step": us["bare"],
              "full_us_per_step": {str(n): us[n] for n in threads},
              "full_over_bare": full_1 / us["bare"], "threads_of_ratio": threads[0],
              "parts_us_per_step": {"springs": us["springs"], "prisms": us["prisms"],
                                    "rest": full_1 - us["springs"] - us["prisms"]},
              "load_average_1min": os.getloadavg()[0]}
    report["assembly_us_per_step"] = {str(n): us[("assembly", n)] for n in threads}
    if len(threads) > 1:
        report["speedup_over_threads_" + str(threads[0])] = {
            str(n): full_1 / us[n] for n in threads[1:]}
        report["assembly_speedup_over_threads_" + str(threads[0])] = {
            str(n): us[("assembly", threads[0])] / us[("assembly", n)] for n in threads[1:]}
        # n bare copies side by side against one: what the machine's cores gave in this run
        report["machine_ceiling_speedup"] = {
            str(n): n * us["bare"] / us[("ceiling", n)] for n in threads[1:]}
    return report


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
    ap.add_argument("--threads", default="1", help="thread counts of the step, e.g. 1,2")
    ap.add_argument("--step-only", action="store_true", help="the step's benchmark alone")
    ap.add_argument("--repeat", type=int, default=15, help="frames timed, best taken")
    ap.add_argument("--preset", default="anatomical", help="the step's preset (default the "
                    "default, anatomical; lucero1999: the seeds')")
    ap.add_argument("--face", default=None, help="the step's face: a built-in name or a .npz "
                    "of face build (default: the built-in face)")
    args = ap.parse_args()
    threads = [int(n) for n in args.threads.split(",")]
    step = step_benchmark(threads, repeat=args.repeat, preset_name=args.preset,
                          face_spec=args.face)
    set_threads(1)
    if args.step_only:
        print(json.dumps({"benchmark": "forward-step", "step": step}, indent=2))
        return
    t, act, jaw = utterance()
    if args.quick:
        t, act, jaw = t[:60], act[:60], jaw[:60]
    simulated = len(t) / 60.0
    repeat = 1 if args.quick else 3
    anat = preset("anatomical")
    anat_face = default_face()
    simulate(face_model(anat_face, anat), act[:3], jaw[:3])
    wall, sim = timed(lambda: simulate(face_model(anat_face, anat), act, jaw), repeat)
    ph_a = Physics.build(anat_face, anat)
    ss_a = Stepper(face_model(anat_face, anat)).solver_state
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
    simulate(face_model(face, seeds), act[:3], jaw[:3], integrator="euler")
    simulate(face_model(face, seeds), act[:3], jaw[:3], integrator="rosenbrock")
    variants = [("euler", "euler", {}), ("euler-1ms", "euler", {"dt": 1e-3}),
                ("implicit-4", "implicit", {"substeps": 4}),
                ("implicit-8", "implicit", {"substeps": 8}),
                ("rosenbrock-2", "rosenbrock", {"substeps": 2}),
                ("rosenbrock-4", "rosenbrock", {"substeps": 4}),
                ("rosenbrock-8", "rosenbrock", {"substeps": 8})]
    results = {}
    sims = {}
    for label, integ, kw in variants:
        wall, sim = timed(lambda i=integ, k=kw: simulate(face_model(face, seeds), act, jaw,
                                                         integrator=i, **k), repeat)
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
    ss = Stepper(face_model(face, seeds), integrator="rosenbrock", substeps=4).solver_state
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
        "step": step,
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
