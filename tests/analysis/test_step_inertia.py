"""The parts of the implicit step's matrix and the inertia each adds to a motion
(facemech.analysis.step_inertia): the forces' own parts resist no rigid motion, the shared
(x, y, z alike) parts resist a turn, and the rank-one volume Hessian is at most 3 times the
Gram form, 3 times exactly for a dilation."""

import numpy as np
import pytest

from facemech import default_face
from facemech.analysis.step_inertia import added_inertia, rigid_turn, step_parts
from facemech.params import preset
from facemech.physics.assembly import Physics

pytestmark = pytest.mark.xdist_group("step_inertia")


@pytest.fixture(scope="module")
def physics():
    return Physics.build(default_face("default-coarse"),
                         preset("anatomical").with_(stiffening=4.0))


@pytest.fixture(scope="module")
def parts(physics):
    return step_parts(physics)


def test_the_forces_own_parts_resist_no_rigid_motion(physics, parts):
    """A turn and a drift of the whole face: ``X v`` of the along-the-spring and rank-one parts
    is below 1e-9 of the shared parts', which resist the turn."""
    rest = physics.model.rest_positions
    turn = np.cross([0.3, -1.0, 0.5], rest - rest.mean(axis=0)) + [0.01, 0.02, -0.03]
    v = turn.reshape(-1)
    for own, shared in (("springs_along", "springs_shared"), ("volume_rank_one", "volume_gram"),
                        ("dashpots_along", "dashpots_shared")):
        big = np.abs(parts[shared] @ v).max()
        assert big > 0
        assert np.abs(parts[own] @ v).max() < 1e-9 * big, own
        drift = np.tile([0.01, 0.02, -0.03], len(rest))
        assert np.abs(parts[shared] @ drift).max() < 1e-9 * big


def test_the_rank_one_volume_term_is_within_3_times_the_gram_form(physics, parts):
    """``(sum_a g_a . v_a)^2 <= 3 |sum_a v_a g_a^T|^2`` for any motion, with equality for a
    uniform dilation (``sum_a g_a x_a^T = V I`` for a volume that scales with det F)."""
    rng = np.random.default_rng(5)
    gram, one = parts["volume_gram"], parts["volume_rank_one"]
    for _ in range(5):
        v = rng.normal(size=gram.shape[0])
        assert v @ (one @ v) <= 3.0 * (v @ (gram @ v)) * (1 + 1e-12)
    rest = physics.model.rest_positions
    v = (rest - rest.mean(axis=0)).reshape(-1)
    assert v @ (one @ v) == pytest.approx(3.0 * (v @ (gram @ v)), rel=1e-9)


def test_the_shared_matrix_weighs_on_a_turning_lower_lip(physics, parts):
    """A rigid turn of the lower lip (nodes within 12 mm of its centre, about the x axis) at
    the preset's 4 steps per frame: the shared matrix (its shares of springs and volume, eq. 8's
    dashpots) adds several times more inertia than the forces' own parts, and over 100 times
    the lip's own (docs/model.md, The step's drag)."""
    p = physics.params
    h = 1.0 / (p.frame_rate * 4)
    lm = physics.model.landmarks["lower_lip_center"]
    v = rigid_turn(physics, physics.model.rest_positions[lm], [1.0, 0.0, 0.0], 0.012)
    got = added_inertia(physics, parts, v, h)
    shared = (0.75 * got["springs_shared"] + 3.0 * got["volume_gram"]
              + got["dashpots_shared"])
    own = got["springs_along"] + got["volume_rank_one"] + got["dashpots_along"]
    assert shared > 100.0
    assert shared > 4.0 * own
    # halving the step: stiffness parts a quarter, damping parts a half
    half = added_inertia(physics, parts, v, h / 2)
    assert half["volume_gram"] == pytest.approx(got["volume_gram"] / 4, rel=1e-12)
    assert half["dashpots_shared"] == pytest.approx(got["dashpots_shared"] / 2, rel=1e-12)
