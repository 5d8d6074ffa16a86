"""Trial rolls of the least-squares inversion under the default preset (issue 16, part 3).

Under ``anatomical`` the chord Jacobian over-promises and a frame of Experiment 1 takes several
trial rolls. The count below was measured on main (commit 407f70f) for one Experiment 1
inversion with the positive constraint (35 frames, window 3). The test fails if the rolls grow
by more than 5 % or the fit's per-frame error grows by more than 10 %.

Those numbers hang on the last bit (issue 32): the anatomical forward model amplifies a rounding
difference about threefold per frame, so OpenBLAS's kernels, threads or a 1e-12 change of the
markers move the step count by a fifth and the largest error several times over. The bounds are
therefore the largest value measured over those environments by ``tools/spread.py``
(docs/reproducibility.md), with the same margins; smaller errors pass.
"""

import warnings

import numpy as np

from facemech.inverse.experiments import EXPERIMENT_SETTINGS, synthetic_data
from facemech.inverse.invert import invert
from facemech.params import preset

#: measured on main: frame steps over the 35 fitted frames, median / max per-frame RMS error (mm)
STEPS, MEDIAN_MM, MAX_MM = 692, 0.055418248713573356, 0.4914152796540393
#: the largest of each over the environments of tools/spread.py (e1-anatomical, lsq, positive)
SPREAD_STEPS, SPREAD_MEDIAN_MM, SPREAD_MAX_MM = 827, 0.05661, 0.4932


def test_anatomical_experiment1_trial_rolls_do_not_come_back(face):
    prm = preset("anatomical")
    data, _ = synthetic_data(face, params=prm)
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        res = invert(face, data, used, params=prm, positive=True,
                     jaw_angle=np.zeros(data.n_frames), **EXPERIMENT_SETTINGS)
    steps = int(res.evaluations.sum())
    # a frame step is one model frame; the minimum is 1 + 3 per frame (a warm start and a roll)
    assert 4 * (data.n_frames - 1) <= steps <= max(STEPS, SPREAD_STEPS) * 1.05
    err = res.error_summary()
    assert err["median_mm"] <= max(MEDIAN_MM, SPREAD_MEDIAN_MM) * 1.10
    assert err["max_mm"] <= max(MAX_MM, SPREAD_MAX_MM) * 1.10
