"""The implicit step's sparse solve: CHOLMOD's Cholesky factor against SuperLU (prints JSON).

The default (anatomical) preset's constant matrix ``M + h C + h^2 K`` of the built-in face (4
steps a frame) is factorised both ways: :func:`facemech.solvers.cholesky.factorise` (CHOLMOD
through cholespy, what the integrators use) and SuperLU with the symmetric settings the
integrators used before (``permc_spec="MMD_AT_PLUS_A"``, no pivoting). Each solves the same three
right-hand sides (the x, y and z columns), timed interleaved (median of ``--rounds`` rounds of
200 solves), and the two solutions are compared. Then the demo's utterance is simulated under
the default preset with each factor in turn (``--rounds`` alternate rounds, medians), wall
seconds per simulated second, and their ratio; the largest difference between the two runs'
node positions is printed (rounding only). One core (NUMBA_NUM_THREADS=1, BLAS limited to 1).

``python benchmarks/solve.py [--rounds 3] [--preset P]``
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from scipy.sparse.linalg import splu  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from facemech.physics.model import model as face_model


def _superlu(matrix):
    return splu(sp.csc_matrix(matrix), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                options={"SymmetricMode": True})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--preset", default="anatomical")
    args = ap.parse_args(argv)
    import facemech.solvers.implicit_matrix as implicit
    from facemech import Physics, default_face, preset, simulate
    from facemech.demo import utterance
    from facemech.params import preset_steps
    from facemech.solvers.cholesky import CholeskyFactor

    threadpool_limits(1)
    face = default_face()
    params = preset(args.preset)
    physics = Physics.build(face, params)
    h = 1.0 / (params.frame_rate * 4)
    steps = preset_steps(args.preset)
    system = implicit.implicit_system(physics, h, steps)
    a = (sp.diags(system.mass * (1.0 + h * steps.mass_drag)) + h * system.damping
         + h * h * system.stiffness).tocsc()
    rhs = np.random.default_rng(0).standard_normal((a.shape[0], 3))
    t0 = time.perf_counter()
    chol = CholeskyFactor(a)
    t_chol = time.perf_counter() - t0
    t0 = time.perf_counter()
    lu = _superlu(a)
    t_lu = time.perf_counter() - t0
    solves = {"cholmod": [], "superlu": []}
    for _ in range(args.rounds):
        for name, f in (("cholmod", chol), ("superlu", lu)):
            f.solve(rhs)
            t0 = time.perf_counter()
            for _ in range(200):
                f.solve(rhs)
            solves[name].append((time.perf_counter() - t0) / 200)
    x_c, x_l = chol.solve(rhs), lu.solve(rhs)
    _, act, jaw = utterance()
    duration = len(act) / params.frame_rate
    simulate(face_model(face, params), act[:3], jaw[:3])  # compile
    sims = {"cholmod": [], "superlu": []}
    runs = {}
    real = implicit.factorise
    try:
        for _ in range(args.rounds):
            for name, factor in (("cholmod", real), ("superlu", _superlu)):
                implicit.factorise = factor
                t0 = time.perf_counter()
                out = simulate(face_model(face, params), act, jaw)
                sims[name].append((time.perf_counter() - t0) / duration)
                runs[name] = np.asarray(out.positions)
    finally:
        implicit.factorise = real
    med = {k: float(np.median(v)) for k, v in solves.items()}
    sim = {k: float(np.median(v)) for k, v in sims.items()}
    print(json.dumps({
        "preset": args.preset, "unknowns": a.shape[0], "nonzeros": int(a.nnz),
        "right_hand_sides": 3, "rounds": args.rounds,
        "factor_ms": {"cholmod": round(1e3 * t_chol, 2), "superlu": round(1e3 * t_lu, 2)},
        "solve_ms": {k: round(1e3 * v, 3) for k, v in med.items()},
        "solve_ratio_cholmod_to_superlu": round(med["cholmod"] / med["superlu"], 3),
        "solution_difference_relative": float(np.abs(x_c - x_l).max() / np.abs(x_l).max()),
        "simulated_s": round(duration, 2),
        "wall_s_per_simulated_s": {k: round(v, 3) for k, v in sim.items()},
        "real_time_factor": {k: round(1.0 / v, 2) for k, v in sim.items()},
        "simulation_ratio_cholmod_to_superlu": round(sim["cholmod"] / sim["superlu"], 3),
        "positions_difference_m": float(np.abs(runs["cholmod"] - runs["superlu"]).max()),
    }, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
