"""The jaw's motion in the implicit step's stiffness correction (:mod:`facemech.solvers.implicit`).

Linearly implicit Euler solves ``A dv = h (f(x, v) - h K v)``: the correction ``- h K v`` is
the forces' change over the step. The constant matrix is over the moving nodes only, so its
stiffness held no coupling to the kinematic nodes (the jaw's bone) nor to the tethers' anchors
on it: a node carried along by the jaw at its speed met the drag ``h k v`` of every spring and
tether to the bone, as if the bone stood still. The step now adds the coupling
(:meth:`~facemech.solvers.implicit.ImplicitSystem.apply_boundary`)."""

from __future__ import annotations

import numpy as np
import pytest

from facemech import default_face
from facemech.params import MUSCLE_GROUPS, preset, preset_steps
from facemech.physics.assembly import Physics
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.solvers.implicit import implicit_system
from facemech.waveforms import cosine_ramp


@pytest.fixture(scope="module")
def coarse():
    return default_face("default-coarse")


def test_a_rigid_translation_meets_no_stiffness_in_the_step(coarse):
    """Every node, kinematic or not, and every anchor moving at one velocity: the constant
    stiffness's correction, its coupling to the bone included, is zero (the springs' graph, the
    volume term's Gram matrices and the tethers resist no translation); without the coupling it
    is the drag the jaw's tissue met."""
    physics = Physics.build(coarse, preset("anatomical"))
    system = implicit_system(physics, 1.0 / 240.0, preset_steps("anatomical"))
    u = np.array([0.01, -0.02, 0.005])  # m/s
    everywhere = np.broadcast_to(u, (coarse.n_nodes, 3)).copy()
    moving = everywhere[physics.dynamic]
    anchors = np.broadcast_to(u, (len(physics.forces.restoration.nodes), 3))
    alone = system.apply_stiffness(moving, None)
    whole = alone + system.apply_boundary(everywhere, anchors)
    drag = np.abs(alone).max()  # N/s: the bone's springs and tethers, without the coupling
    assert drag > 1.0  # measured 12.6 on the coarse face
    assert np.abs(whole).max() < 1e-10 * drag  # rounding (measured 2e-15 of it)


def test_the_lower_lip_rides_an_opening_jaw_as_the_fine_step_does(coarse):
    """The jaw opens 6 degrees in 100 ms: at the end of the opening the lower lip has moved
    down at least 80 % as far at the preset's 4 steps per frame as at 24 (measured 0.86; 0.67
    without the coupling), and its path stays within 1.6 mm of the fine path (1.28 mm; 2.14
    without)."""
    p = preset("anatomical")
    n = 36
    t = np.arange(n) / 60.0
    jaw = np.radians(6.0) * cosine_ramp(np.clip((t - 0.1) / 0.1, 0, 1))
    node = coarse.landmarks["lower_lip_center"]
    paths = {}
    for sub in (4, 24):
        sim = simulate(face_model(coarse, p), np.zeros((n, len(MUSCLE_GROUPS))), jaw, substeps=sub)
        paths[sub] = sim.positions[:, node] - sim.positions[0, node]
    end = 12  # the frame the jaw stops
    assert paths[24][end, 1] < -5e-3
    assert paths[4][end, 1] / paths[24][end, 1] >= 0.8
    assert np.abs(paths[4] - paths[24]).max() < 1.6e-3
