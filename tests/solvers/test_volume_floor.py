"""The prisms' volume floor stepped implicitly after the implicit methods' solve
(facemech.solvers.volume_floor, issue 27's creep): the analytic backward-Euler step of one
prism, a prism above its floor left alone, a contraction for any stiffness, and a held gesture
whose crushed prisms it holds at the floor."""

import numpy as np
import pytest

from facemech.geometry.prism import rest_geometry, volume_gradients
from facemech.params import MUSCLE_GROUPS, preset_pair
from facemech.physics.model import model as face_model
from facemech.solvers.volume_floor import VolumeFloor, resolve_volume_floor

#: a right prism 2 mm high over a right triangle of legs 2 mm: volume 4 mm^3
PRISM = 1e-3 * np.array([[0, 0, 2], [2, 0, 2], [0, 2, 2], [0, 0, 0], [2, 0, 0], [0, 2, 0]], float)
NODES = np.arange(6)[None, :]


def _squashed(height_mm: float) -> np.ndarray:
    p = PRISM.copy()
    p[:3, 2] = height_mm * 1e-3
    return p


def _volume(p):
    return rest_geometry(p, NODES, symmetric=True)[0][0]


def test_a_squashed_prism_takes_the_backward_euler_step_of_its_floor():
    """mu = -h kappa C / (1 + h^2 kappa w), Delta v_i = mu g_i / m_i: with the volume
    linearised, the new deficit is C / (1 + h^2 kappa w); the position moves by h Delta v."""
    h, m = 1 / 240, 1e-6
    inv_mass = np.array([1 / m] * 3 + [0.0] * 3)  # the bottom nodes on the bone
    pos = _squashed(0.6)
    vel = np.zeros((6, 3))
    v0 = _volume(PRISM)
    floor = VolumeFloor.of(NODES, np.array([v0]), 0.5, 50.0)  # a soft floor: one step shows
    g = volume_gradients(pos[None])[0]
    w = float(np.sum(g[:3] ** 2) / m)
    deficit = _volume(pos) - 0.5 * v0
    assert deficit < 0
    mu = -h * floor.kappa[0] * deficit / (1 + h * h * floor.kappa[0] * w)
    acted = resolve_volume_floor(pos, vel, inv_mass, floor.nodes, floor.floor, floor.kappa, h)
    assert acted == 1
    # the sweeps solve the volume itself, the formula linearises it: equal to the curvature
    np.testing.assert_allclose(vel[:3], mu * g[:3] / m, rtol=2e-2, atol=2e-6)
    np.testing.assert_allclose(vel[3:], 0.0, atol=0)  # kinematic nodes do not move
    # the top rises (the volume grows toward the floor) and the deficit shrinks
    assert np.all(vel[:3, 2] > 0)
    assert abs(_volume(pos) - 0.5 * v0) < abs(deficit)
    np.testing.assert_allclose(pos[:3] - _squashed(0.6)[:3], vel[:3] / 240, rtol=1e-12)
    # the backward-Euler equation of the penalty holds at the new volume:
    # m dx / h^2 = -kappa C(x_new) g, i.e. lam = -h^2 kappa C(x_new)
    lam = float(np.linalg.norm((pos[:3] - _squashed(0.6)[:3]) * m) / np.linalg.norm(g[:3]))
    assert lam == pytest.approx(-h * h * floor.kappa[0] * (_volume(pos) - 0.5 * v0), rel=2e-2)


def test_a_prism_above_its_floor_is_left_alone_to_the_bit():
    pos = _squashed(1.2)  # J = 0.6, floor 0.5
    vel = np.full((6, 3), 0.01)
    before = pos.copy(), vel.copy()
    floor = VolumeFloor.of(NODES, np.array([_volume(PRISM)]), 0.5, 1e6)
    assert resolve_volume_floor(pos, vel, np.full(6, 1e6), floor.nodes, floor.floor,
                                floor.kappa, 1 / 240) == 0
    np.testing.assert_array_equal(pos, before[0])
    np.testing.assert_array_equal(vel, before[1])


@pytest.mark.parametrize("modulus", [1.0, 1e3, 1e6, 1e9])
def test_the_step_contracts_the_deficit_for_any_stiffness(modulus):
    """No perturbation grows through the floor, however stiff (an explicit penalty of the
    stiffest would multiply it by up to h^2 kappa w)."""
    v0 = _volume(PRISM)
    for height in (0.99, 0.6, 0.1):
        pos = _squashed(height)
        vel = np.zeros((6, 3))
        deficit = _volume(pos) - 0.5 * v0
        floor = VolumeFloor.of(NODES, np.array([v0]), 0.5, modulus)
        resolve_volume_floor(pos, vel, np.full(6, 1e6), floor.nodes, floor.floor,
                             floor.kappa, 1 / 240)
        after = _volume(pos) - 0.5 * v0
        assert abs(after) < abs(deficit)


def test_no_floor_means_no_prism():
    assert len(VolumeFloor.of(NODES, np.ones(1), 0.0, 1e6).floor) == 0


def test_parameters_refuse_a_floor_at_or_above_the_rest_volume():
    from facemech import InputError

    with pytest.raises(InputError, match="volume_floor"):
        preset_pair("anatomical").with_(volume_floor=1.0)


def test_a_held_lip_gesture_keeps_every_prism_above_the_floor():
    """Full levator labii superioris held 0.5 s crushes prisms under the nose past a volume
    ratio of -0.2 (inverted) without the floor; with it none goes below the floor."""
    from facemech.geometry.builder import default_face, for_tissue
    from facemech.solvers.forward import simulate

    p = preset_pair("anatomical")
    face = for_tissue(default_face(), p.params.tissue)
    v0 = rest_geometry(face.rest_positions, face.prism_nodes, symmetric=True)[0]
    act = np.zeros((31, len(MUSCLE_GROUPS)))
    act[:, MUSCLE_GROUPS.index("LLS")] = 1.0
    ratio = {}
    for floor in (0.0, 0.5):
        sim = simulate(face_model(face, p.with_(volume_floor=floor, volume_floor_modulus=1e6)), act)
        ratio[floor] = (rest_geometry(sim.final_state.positions, face.prism_nodes,
                                      symmetric=True)[0] / v0).min()
    assert ratio[0.0] < 0.3
    assert ratio[0.5] > 0.49  # a stiff penalty, not a wall: 0.4976 measured at 1 MPa


def _floor_without_skipping(pos, vel, inv_mass, nodes, floor, kappa, h, sweeps):
    """The floor's sweeps as first written, every prism looked at in every sweep (plain
    Python): the reference that the kernel's skipping must equal to the bit."""
    from facemech.geometry.prism import _bilinear_volume_gradient

    lam = np.zeros(len(nodes))
    g = np.empty((6, 3))
    done = 0
    for _ in range(sweeps):
        done += 1
        largest = 0.0
        for e in range(len(nodes)):
            p = pos[nodes[e]].copy()
            deficit = _bilinear_volume_gradient(p, g) / 12.0 - floor[e]
            if deficit >= 0.0 and lam[e] == 0.0:
                continue
            im = inv_mass[nodes[e]]
            w = 0.0
            for k in range(6):
                for a in range(3):
                    g[k, a] /= 12.0
                    w += g[k, a] * g[k, a] * im[k]
            if w <= 0.0:
                continue
            compliance = 1.0 / (h * h * kappa[e])
            d = (-deficit - compliance * lam[e]) / (w + compliance)
            if lam[e] + d < 0.0:
                d = -lam[e]
            lam[e] += d
            for k in range(6):
                i = nodes[e, k]
                for a in range(3):
                    dx = d * g[k, a] * inv_mass[i]
                    pos[i, a] += dx
                    vel[i, a] += dx / h
            largest = max(largest, abs(d) * w / floor[e])
        if largest < 1e-3:
            break
    return int((lam > 0).sum()), done


def test_skipping_the_prisms_far_from_the_floor_changes_nothing_to_the_bit():
    """After its first sweep the kernel looks again only at the prisms whose nodes moved (a
    prism found above its floor keeps its volume to the bit until one does); a sheet of 50
    prisms sharing nodes, 16 of its 36 top nodes pressed down, takes several sweeps and gives
    the same positions and velocities, bit for bit, as every prism looked at in every
    sweep."""
    from facemech.solvers.volume_floor import SWEEPS

    n = 6  # a 6 x 6 grid of nodes, 2 mm apart, its 50 triangles lifted 2 mm into prisms
    xy = 2e-3 * np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), -1).reshape(-1, 2)
    top = np.column_stack([xy, np.full(len(xy), 2e-3)])
    bottom = np.column_stack([xy, np.zeros(len(xy))])
    pos0 = np.vstack([top, bottom])
    tris = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, (i + 1) * n + j, i * n + j + 1, (i + 1) * n + j + 1
            tris += [(a, b, c), (b, d, c)]
    tris = np.array(tris)
    nodes = np.hstack([tris, tris + n * n]).astype(np.int64)
    v0 = rest_geometry(pos0, nodes, symmetric=True)[0]
    rng = np.random.default_rng(7)
    pos = pos0.copy()
    crushed = rng.choice(n * n, 16, replace=False)
    pos[crushed, 2] = rng.uniform(0.1e-3, 0.6e-3, 16)
    vel = rng.normal(0.0, 0.01, pos.shape)
    inv_mass = np.r_[np.full(n * n, 1e6), np.zeros(n * n)]
    floor = VolumeFloor.of(nodes, v0, 0.5, 1e6)
    got = pos.copy(), vel.copy()
    want = pos.copy(), vel.copy()
    acted = resolve_volume_floor(got[0], got[1], inv_mass, floor.nodes, floor.floor,
                                 floor.kappa, 1 / 240)
    ref, sweeps = _floor_without_skipping(want[0], want[1], inv_mass, floor.nodes, floor.floor,
                                          floor.kappa, 1 / 240, SWEEPS)
    assert acted == ref >= 8  # 9 measured
    assert sweeps > 2
    assert not np.array_equal(got[0], pos)  # the floor acted
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
