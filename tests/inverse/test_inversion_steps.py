"""Experiment 1's error table and frame-step count, pinned (issue 16, part 3).

The values below were measured with ``facemech experiment pitermann2001-synthetic --preset
lucero1999 --method lsq``: they are measurements, not results the method must reach. A faster
inversion must keep the per-frame errors within 10 % of them and take no more frame steps.

Until issue 32 these numbers hung on the last bit: the seeds' skull contact (eq. 10) switched on
an exact comparison, so OpenBLAS's kernels or a 1e-12 change of the markers moved the median
error by a factor of two. With the contact's 1-nm band (``physics.assembly.SKULL_BAND``) the
whole table is the same under the machine's kernels, Prescott's and with the markers perturbed
by 1e-12: frame steps equal, errors equal to 1e-6 relative (tools/spread.py, commit 82f879e,
docs/reproducibility.md). The band changes the physics, so the numbers were measured again
there; the steps keep a margin of 2 % for CPUs not measured.
"""

from facemech.inverse.experiments import run_synthetic
from facemech.params import preset
from facemech.physics.model import model as face_model

#: measured at commit 82f879e (the same in the default, Prescott and perturbed environments):
#: label -> (median, max per-frame error in mm, frame steps over 35 frames)
MEASURED = {
    "lsq, no constraint": (0.000720874, 0.00421505, 161),
    "lsq, positive": (0.00223895, 0.00535992, 176),
}


def test_experiment1_errors_stay_within_10_percent_and_steps_do_not_grow(face):
    result = run_synthetic(face_model(face, preset("lucero1999")), methods=("lsq",))
    assert result.frames == 36
    for label, (median, worst, steps) in MEASURED.items():
        run = result.runs[label]
        err = run.frame_error_mm
        assert err["median"] <= 1.10 * median, label
        assert err["max"] <= 1.10 * worst, label
        assert run.evaluations <= round(1.02 * steps), label
