"""The reachability check's breakdown by component (issue 27): each component's RMS and share of
the squared error add up to the total, and the lower lip's error on the jaw equals its absolute
error when the jaw follows the incisor exactly."""

import numpy as np
import pytest

from facemech.analysis.reachability import COMPONENTS, GROUPS, reach, speech_targets
from facemech.physics.model import model as face_model


def test_components_add_up_to_the_total(face):
    # a short /p/: the upper lip 3 mm down in 0.05 s, 10 frames
    ms = speech_targets(face, posture_s=0.05, transition_s=0.05, sequence=("rest", "p"))
    r = reach(face_model(face), markers=ms)
    assert set(r.components) == {*COMPONENTS, "lower_lip_on_jaw_vertical"}
    # mean square over the 6 fitted markers = the groups' (2 markers each) per-axis squares
    lateral = 1.0 - sum(r.share.values())  # the lips' lateral coordinates
    assert 0.0 <= lateral < 0.05
    per_marker = sum(v**2 for k, v in r.components.items() if k in COMPONENTS) * 2 / 6
    assert r.rms**2 * (1 - lateral) == pytest.approx(per_marker, rel=1e-9)
    for key, v in r.components.items():
        if key in COMPONENTS:
            assert r.share[key] == pytest.approx(v**2 * 2 / 6 / r.rms**2, rel=1e-9)
    # the incisor drives the jaw exactly (jaw_bone), so on the jaw = absolute
    assert r.components["lower_lip_on_jaw_vertical"] == pytest.approx(
        r.components["lower_lip_vertical"], abs=1e-9)
    assert len(GROUPS["upper"]) == len(GROUPS["lower"]) == len(GROUPS["corner"]) == 2
    assert np.isfinite(r.rms) and r.rms > 0
