"""Experiment 1's error table and frame-step count, pinned against main (issue 16, part 3).

The values below were measured on main (commit 2d26959) with ``facemech experiment
pitermann2001-synthetic --preset lucero1999 --method lsq``: they are measurements, not results
the method must reach. A faster inversion must keep the per-frame errors within 10 % of them and
take no more frame steps per frame.

Those numbers hang on the last bit (issue 32): the seeds' forward model switches its skull
contact (eq. 10) on an exact comparison, so OpenBLAS's kernels, threads or a 1e-12 change of the
markers move the median error by a factor of two and the step count by a few. The bounds are
therefore the largest value measured over those environments by ``tools/spread.py``
(docs/reproducibility.md), with the same 10 % (errors) and no (steps) margin as before; an
inversion whose errors fall below them passes.
"""

from facemech.inverse.experiments import run_synthetic
from facemech.params import preset

#: measured on main (the default environment of an AVX-512 machine): label -> (median, max
#: per-frame error in mm, frame steps over 35 frames)
BEFORE = {
    "lsq, no constraint": (0.0009595026100078416, 0.004220168031156206, 170),
    "lsq, positive": (0.002125654463953251, 0.0042376673184466645, 158),
}
#: the largest of each over the environments of tools/spread.py (OpenBLAS's kernels: the
#: machine's, Prescott and Nehalem; BLAS on 1 and 2 threads; markers moved by 1e-12): the spread
#: of docs/reproducibility.md; and the unconstrained median of 0.0021 mm that an AMD EPYC gave
#: (issue 32's report)
SPREAD_MAX = {
    "lsq, no constraint": (0.0021, 0.004935, 170),
    "lsq, positive": (0.002126, 0.004595, 161),
}


def test_experiment1_errors_stay_within_10_percent_and_steps_do_not_grow(face):
    result = run_synthetic(face, methods=("lsq",), params=preset("lucero1999"))
    assert result.frames == 36
    for label, (median, worst, steps) in SPREAD_MAX.items():
        run = result.runs[label]
        err = run.frame_error_mm
        assert err["median"] <= 1.10 * max(median, BEFORE[label][0]), label
        assert err["max"] <= 1.10 * max(worst, BEFORE[label][1]), label
        assert run.evaluations <= max(steps, BEFORE[label][2]), label
