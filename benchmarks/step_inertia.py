"""What the implicit step's shared matrix adds to a turning lip, part by part, and what a matrix
that follows each spring's direction would cost to factorise and solve.

Prints JSON. ``python benchmarks/step_inertia.py [--face default]``. For rigid turns (1 rad/s)
of the nodes within 12 mm of the lower lip's and the upper lip's centres (about the x axis) and
of the right mouth corner (about y), the inertia each part of the matrix adds at 4 steps per
60-Hz frame, in multiples of the region's own (``facemech.analysis.step_inertia``), and the
totals: ``shared`` is what the predictor step's matrix holds (3/4 of the springs' stiff branch,
3 times the volume Gram matrices, eq. 8's dashpots), ``own`` what the forces' own tangent at rest
holds (along the springs, the rank-one volume Hessian, stretch-rate dashpots). ``own`` is not
zero: the region's edge is strained by the turn. Then the time to factorise and to solve the
shared (nodes x nodes, one matrix for x, y and z) and the direction-following (3 nodes x 3
nodes) matrices with SuperLU, in one run (``ratio`` is what to read on a shared machine).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

TURNS = (("lower_lip_center", (1.0, 0.0, 0.0)), ("upper_lip_center", (1.0, 0.0, 0.0)),
         ("mouth_corner_right", (0.0, 1.0, 0.0)))
SHARES = {"springs_shared": 0.75, "volume_gram": 3.0, "dashpots_shared": 1.0,
          "springs_along": 1.0, "volume_rank_one": 1.0, "dashpots_along": 1.0}


def _timed(a_mat, columns, repeats=20):
    """Process time (s) to factorise ``a_mat`` and to solve it for ``columns`` right sides."""
    rhs = np.random.default_rng(0).normal(size=(a_mat.shape[0], columns))
    t0 = time.process_time()
    lu = splu(a_mat.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})
    factor = time.process_time() - t0
    t0 = time.process_time()
    for _ in range(repeats):
        lu.solve(rhs)
    return factor, (time.process_time() - t0) / repeats


def main() -> None:
    from facemech import default_face
    from facemech.analysis.step_inertia import added_inertia, rigid_turn, step_parts
    from facemech.params import preset
    from facemech.physics.assembly import Physics
    from facemech.solvers.implicit import implicit_system
    from facemech.stepping import StepOptions

    ap = argparse.ArgumentParser()
    ap.add_argument("--face", default="default")
    args = ap.parse_args()
    params = preset("anatomical").with_(stiffening=4.0, dashpot_isotropy=0.0)
    physics = Physics.build(default_face(args.face), params)
    h = 1.0 / (params.frame_rate * 4)
    parts = step_parts(physics)
    report: dict = {"benchmark": "step_inertia", "face": args.face, "step_s": h,
                    "turns": {}}
    for landmark, axis in TURNS:
        centre = physics.model.rest_positions[physics.model.landmarks[landmark]]
        got = added_inertia(physics, parts, rigid_turn(physics, centre, axis, 0.012), h)
        row = {k: round(v, 1) for k, v in got.items()}
        row["shared"] = round(sum(SHARES[k] * got[k] for k in
                                  ("springs_shared", "volume_gram", "dashpots_shared")), 1)
        row["own"] = round(sum(got[k] for k in
                               ("springs_along", "volume_rank_one", "dashpots_along")), 1)
        report["turns"][landmark] = row
    # the two matrices over the moving nodes: shared (the predictor's) and direction-following
    dyn = physics.dynamic
    mass = 1.0 / physics.inv_mass[dyn]
    idx = (3 * dyn[:, None] + np.arange(3)).reshape(-1)
    own = (h * parts["dashpots_along"] + h * h * (parts["springs_along"]
                                                 + parts["volume_rank_one"])).tocsr()
    a3 = sp.diags(np.repeat(mass, 3)) + own[idx][:, idx]
    shared = implicit_system(physics, h, StepOptions(
        integrator="implicit", predictor=True, implicit_stiffness_share=0.75,
        implicit_volume_scale=3.0))
    a1 = (sp.diags(shared.mass) + h * shared.damping + h * h * shared.stiffness)
    f1, s1 = _timed(a1, 3)  # x, y and z share it
    f3, s3 = _timed(a3, 1)
    report["matrices"] = {
        "shared": {"unknowns": a1.shape[0], "factor_ms": round(1e3 * f1, 1),
                   "solve_ms": round(1e3 * s1, 2)},
        "direction_following": {"unknowns": a3.shape[0], "factor_ms": round(1e3 * f3, 1),
                                "solve_ms": round(1e3 * s3, 2)},
        "solve_ratio": round(s3 / s1, 1), "factor_ratio": round(f3 / f1, 1)}
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
