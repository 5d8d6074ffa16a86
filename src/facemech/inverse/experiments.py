"""Pitermann & Munhall (2001), Experiment 1: inverting synthetic data.

All 16 muscles of the seeds' EMG model (the 8 perioral pairs of Lucero & Munhall 1999, Table II:
DAO, DLI, LAO, ZYG, LLS, MEN, OOS, OOI, left and right) follow the triangle sequence
0, 1/6, ..., 1, ..., 1/6 three times (36 frames at 60 Hz); the face moves accordingly (jaw
closed). The 11 right-side markers (R01-R11) are used for the inversion, the 8 left-side ones
(L01-L08) are held out. The inversion recovers the seven EMG controls, with and without the
positive constraint. Synthesis and inversion use the same explicit Euler step (1 ms by default).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable

import numpy as np

from ..markerset import MarkerSet
from ..params import MUSCLE_GROUPS
from . import stats
from .invert import invert

PERIORAL = ("DAO", "DLI", "LAO", "ZYG", "LLS", "MEN", "OOS", "OOI")

PAPER = {
    "activity_correlations_no_constraint": {"LLS": 0.28, "LAO": 0.43, "DAO": -0.02,
                                            "DLI": 0.14, "MEN": 0.38, "OOS": 0.65, "OOI": 0.14},
    "kinematic_corr_above_0.8": "33 of 38",
    "kinematic_corr_above_0.9": "16 of 38",
    "median_error_mm": {"no_constraint": 0.293, "positive": 0.339},
    "movement_mm": 2.024,
}


def triangle_sequence(repeats: int = 3) -> np.ndarray:
    """0, 1/6, ..., 1, 5/6, ..., 1/6, repeated: (12 * repeats,) activity."""
    one = np.concatenate([np.arange(0, 7) / 6, np.arange(5, 0, -1) / 6])
    return np.tile(one, repeats)


def synthetic_data(face, *, dt: float = 1e-3, noise: float = 0.0, seed: int = 0):
    """The synthetic markers (MarkerSet, metres), the true group activity (36, 16)."""
    from ..solvers.forward import simulate

    tri = triangle_sequence()
    act = np.zeros((len(tri), len(MUSCLE_GROUPS)))
    for g in PERIORAL:
        act[:, MUSCLE_GROUPS.index(g)] = tri
    sim = simulate(face, act, integrator="euler", dt=dt)
    names = [n for n in face.markers if n[0] in "RL"]
    pos = sim.positions[:, [face.markers[n] for n in names]]
    if noise > 0:
        pos = pos + np.random.default_rng(seed).normal(0.0, noise, pos.shape)
    return MarkerSet(pos, tuple(names), 60.0), act


def run_synthetic(face, *, methods=("lsq",), dt: float = 1e-3, noise: float = 0.0,
                  progress: Callable[[str, int, int], None] | None = None) -> dict:
    """Experiment 1 for each method, with and without the positive constraint (tables as dicts).

    Table I: correlation of each recovered control with the true activity; Table II: 3-D
    correlations (published and unbiased) of every marker, the 8 held-out ones included;
    Table III (top): per-frame error summary and movement.
    """
    data, truth = synthetic_data(face, dt=dt, noise=noise)
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    all_nodes = [face.markers[n] for n in data.names]
    out: dict = {"frames": data.n_frames, "noise_mm": noise * 1e3, "dt_s": dt,
                 "markers_used": list(used), "held_out": [n for n in data.names
                                                          if n.startswith("L")],
                 "runs": {}, "paper": PAPER}
    for method in methods:
        for positive in (False, True):
            label = f"{method}, {'positive' if positive else 'no constraint'}"
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                res = invert(face, data, used, method=method, positive=positive, dt=dt,
                             progress=None if progress is None else
                             (lambda d, n, _l=label: progress(_l, d, n)))
            wall = time.perf_counter() - t0
            model = res.positions[:, all_nodes]
            table1 = {}
            for j, c in enumerate(res.control_names):
                a = res.controls[:-1, j]
                b = truth[:-1, MUSCLE_GROUPS.index(c)]
                table1[c] = (float(np.corrcoef(a, b)[0, 1]) if np.std(a) > 0 else float("nan"))
            table2 = {n: {"published": float(stats.corr3d(model[:, m], data.positions[:, m])),
                          "unbiased": float(stats.corr3d(model[:, m], data.positions[:, m],
                                                         published=False))}
                      for m, n in enumerate(data.names)}
            err = stats.frame_errors(model[1:, :len(used)], data.positions[1:, :len(used)])
            corr = np.array([v["published"] for v in table2.values()])
            out["runs"][label] = {
                "method": method, "positive": positive, "wall_s": wall,
                "evaluations": int(res.evaluations.sum()),
                "table1_activity_correlation": table1,
                "table2_corr3d": table2,
                "corr3d_at_least_0.95": int(np.sum(corr >= 0.95)),
                "corr3d_above_0.8": int(np.sum(corr > 0.8)),
                "table3_frame_error_mm": stats.summary5(err * 1e3),
                "movement_mm": stats.movement(data.positions[:, :len(used)]) * 1e3,
                "condition_median": float(np.nanmedian(res.condition))
                if np.isfinite(res.condition).any() else None,
            }
    return out
