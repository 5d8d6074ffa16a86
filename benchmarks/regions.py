"""Region-analysis benchmark (prints JSON): QR with column pivoting of 57 markers x 100,000
samples (a (300000, 57) displacement matrix), the epsilon-rank and the fit, on one core."""

from __future__ import annotations

import json
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from facemech.analysis.regions import IndependentMarkers, displacement_matrix  # noqa: E402


def main() -> None:
    rng = np.random.default_rng(0)
    n_markers, samples, n_utt = 57, 100_000, 40
    frames = samples // n_utt
    mix = rng.normal(size=(8, n_markers))
    utts = []
    for _ in range(n_utt):
        t = np.linspace(0, 1, frames)[:, None]
        src = np.stack([3e-3 * np.sin(2 * np.pi * rng.uniform(1, 5, 3) * t
                                      + rng.uniform(0, 6, 3)) for _ in range(8)], axis=1)
        x = np.einsum("fsc,sm->fmc", src, mix) + rng.normal(0, 0.5e-3, (frames, n_markers, 3))
        utts.append(x)
    t0 = time.perf_counter()
    a = displacement_matrix(utts)
    t_stack = time.perf_counter() - t0
    t0 = time.perf_counter()
    m = IndependentMarkers(k=10).fit(utts)
    t_fit = time.perf_counter() - t0
    t0 = time.perf_counter()
    IndependentMarkers(k=10, eps=0.5e-3, method="strong").fit(utts)
    t_strong = time.perf_counter() - t0
    print(json.dumps({
        "benchmark": "regions", "markers": n_markers, "samples": samples,
        "matrix_shape": list(a.shape), "stack_s": t_stack,
        "fit_s_qrcp_with_eps_rank_and_pca": t_fit, "fit_s_strong_rrqr": t_strong,
        "rank": int(m.rank_), "eps_mm": m.eps_ * 1e3, "target_s": 2.0,
    }, indent=2))


if __name__ == "__main__":
    main()
