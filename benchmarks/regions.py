"""Region-analysis benchmark (prints JSON): QR with column pivoting of 57 markers x 100,000
samples (a (300000, 57) displacement matrix), the epsilon-rank and the fit.

BLAS is left at its default thread count (OpenBLAS: one per core): the fit caps it at one thread
itself (:func:`facemech.analysis.regions.one_blas_thread`). The same run also times the path
before that change (scipy's ``qr(mode="r")`` of a row-major matrix, a full (rows, 57) triangle
copied out, BLAS at its default threads) and prints the ratio. Target: the fit in at most 2 s.

Usage: python benchmarks/regions.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
import warnings

import numpy as np
import scipy.linalg as sla

from facemech.analysis import regions
from facemech.analysis.regions import IndependentMarkers, displacement_matrix


def utterances(n_markers: int = 57, samples: int = 100_000, n_utt: int = 40, seed: int = 0):
    """Markers mixed from 8 smooth sources plus 0.5 mm of noise, metres."""
    rng = np.random.default_rng(seed)
    frames = samples // n_utt
    mix = rng.normal(size=(8, n_markers))
    utts = []
    for _ in range(n_utt):
        t = np.linspace(0, 1, frames)[:, None]
        src = np.stack([3e-3 * np.sin(2 * np.pi * rng.uniform(1, 5, 3) * t
                                      + rng.uniform(0, 6, 3)) for _ in range(8)], axis=1)
        x = np.einsum("fsc,sm->fmc", src, mix) + rng.normal(0, 0.5e-3, (frames, n_markers, 3))
        utts.append(x)
    return utts


def _old_pivoted_qr(a, *, pivoting=True, overwrite_a=False):
    """The factorisation as it was: row-major A, the full triangle, BLAS threads as they are."""
    out = sla.qr(np.ascontiguousarray(a), mode="r", pivoting=pivoting)
    n = a.shape[1]
    return out[0][:n], (out[1] if pivoting else np.arange(n))


@contextlib.contextmanager
def old_path():
    """The fit as before the one-thread, economical factorisation (for the ratio)."""
    saved = regions.pivoted_qr, regions.one_blas_thread
    regions.pivoted_qr, regions.one_blas_thread = _old_pivoted_qr, contextlib.nullcontext
    try:
        yield
    finally:
        regions.pivoted_qr, regions.one_blas_thread = saved


def best_of(repeats: int, f):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3, help="best of this many runs")
    args = ap.parse_args()
    warnings.simplefilter("ignore", UserWarning)  # k = 10 lies above this data's rank of 8
    from threadpoolctl import threadpool_info

    n_markers, samples = 57, 100_000
    utts = utterances(n_markers, samples)
    t_stack, a = best_of(1, lambda: displacement_matrix(utts))
    # interleaved, so that both paths see the same load of a shared machine
    new_t, old_t = [], []
    for _ in range(args.repeats):
        with old_path():
            t, old = best_of(1, lambda: IndependentMarkers(k=10).fit(utts))
        old_t.append(t)
        t, new = best_of(1, lambda: IndependentMarkers(k=10).fit(utts))
        new_t.append(t)
    t_qr_new, _ = best_of(args.repeats, lambda: regions.pivoted_qr(a))
    t_qr_old, _ = best_of(args.repeats, lambda: _old_pivoted_qr(a))
    t_strong, _ = best_of(1, lambda: IndependentMarkers(k=10, eps=0.5e-3,
                                                         method="strong").fit(utts))
    same = bool(np.array_equal(new.order_, old.order_) and new.rank_ == old.rank_
                and np.allclose(new.R_, old.R_, rtol=0, atol=1e-12 * np.abs(old.R_).max()))
    print(json.dumps({
        "benchmark": "regions", "markers": n_markers, "samples": samples,
        "matrix_shape": list(a.shape), "repeats": args.repeats,
        "blas_default_threads": [i["num_threads"] for i in threadpool_info()
                                 if i["user_api"] == "blas"],
        "stack_s": t_stack,
        "fit_s_qrcp_with_eps_rank_and_pca": min(new_t),
        "fit_s_before": min(old_t), "fit_speedup": min(old_t) / min(new_t),
        "qr_s": t_qr_new, "qr_s_before": t_qr_old, "qr_speedup": t_qr_old / t_qr_new,
        "fit_s_strong_rrqr": t_strong, "same_pivots_rank_and_R": same,
        "rank": int(new.rank_), "eps_mm": new.eps_ * 1e3, "target_s": 2.0,
    }, indent=2))


if __name__ == "__main__":
    main()
