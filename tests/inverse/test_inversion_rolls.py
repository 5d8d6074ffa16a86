"""Trial rolls of the least-squares inversion under the default preset (issue 16, part 3).

Under ``anatomical`` the chord Jacobian over-promises and a frame of Experiment 1 takes several
trial rolls. The count below was measured for one Experiment 1 inversion with the positive
constraint (35 frames, window 3). The test fails if the rolls grow by more than 5 % or the
fit's per-frame error grows by more than 10 %.

Since the contacts are stepped on their own and the passive stiffness is blended at the rest
length (issue 32), the numbers no longer hang on the last bit: tools/spread.py measured the same
896 frame steps and the same errors (to 1e-8 relative) under this machine's OpenBLAS kernels,
Prescott's, and with the markers moved by 1e-12 (docs/reproducibility.md). Before, they moved by
a fifth (827 against 692 steps), and the bounds took the largest value measured.
"""

import warnings

import numpy as np
import pytest

from facemech.inverse.experiments import EXPERIMENT_SETTINGS, synthetic_data
from facemech.inverse.invert import invert
from facemech.params import preset
from facemech.physics.model import model as face_model

#: measured (main after the switch to the measured muscle laws, 2026-11-29; tools/spread.py,
#: e1-anatomical, lsq positive): frame steps over the 35 fitted frames, median / max per-frame
#: RMS error (mm); the same in the default, Prescott, Nehalem and perturbed environments to
#: 1e-8 (896, 0.007845 and 0.022773 under the seeds' muscle laws)
STEPS, MEDIAN_MM, MAX_MM = 905, 0.008194, 0.056424


@pytest.mark.slow
def test_anatomical_experiment1_trial_rolls_do_not_come_back(face):
    prm = preset("anatomical")
    data, _ = synthetic_data(face_model(face, prm))
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        res = invert(face_model(face, prm), data, used, positive=True,
                     jaw_angle=np.zeros(data.n_frames), **EXPERIMENT_SETTINGS)
    steps = int(res.evaluations.sum())
    # a frame step is one model frame; the minimum is 1 + 3 per frame (a warm start and a roll)
    assert 4 * (data.n_frames - 1) <= steps <= STEPS * 1.05
    err = res.error_summary()
    assert err["median_mm"] <= MEDIAN_MM * 1.10
    assert err["max_mm"] <= MAX_MM * 1.10
