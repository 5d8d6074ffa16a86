"""The anatomical preset's continuum tissue: resolution-consistent constants, the volume term,
the muscles' bead-space Jacobian and the Woodbury solve, each against an analytic value or a
finite-difference / direct reference."""

import numpy as np
import pytest

from facemech.params import preset
from facemech.physics.materials import continuum_constants, extra_bulk_modulus
from facemech.physics.volume import prism_pressure, symmetric_volume


def test_volume_springs_store_a_linear_solids_energy_under_uniform_strain(face):
    """Springs of k = mu V / |e|^2 per prism edge store V (mu tr(e^2) + mu/2 tr(e)^2) for an
    isotropic spread of edge directions; on the face the stored energy of a uniform stretch
    lies within a factor 2 of that continuum value (the mesh is anisotropic, not random)."""
    p = preset("anatomical")
    rest = face.rest_positions
    e = rest[face.spring_j] - rest[face.spring_i]
    length = np.linalg.norm(e, axis=1)
    u = e / length[:, None]
    eps = 0.01
    strain = np.diag([eps, 0.0, 0.0])
    dl = length * np.einsum("sa,ab,sb->s", u, strain, u)
    membrane = p.with_(skin_modulus_thickness=0.0)  # the volume springs alone
    energy = 0.5 * np.sum(continuum_constants(face, membrane).spring_k * dl**2)
    from facemech.physics.materials import prism_shear_modulus
    from facemech.physics.volume import rest_geometry

    vols, _ = rest_geometry(rest, face.prism_nodes, symmetric=True)
    mu = prism_shear_modulus(face, p)
    continuum = np.sum(vols * mu * (eps**2 + 0.5 * eps**2))
    assert 0.5 < energy / continuum < 2.0


def test_masses_lump_the_tissue_density(face):
    from facemech.physics.volume import rest_geometry

    p = preset("anatomical")
    c = continuum_constants(face, p)
    vols, _ = rest_geometry(face.rest_positions, face.prism_nodes, symmetric=True)
    assert c.node_mass.sum() == pytest.approx(p.density * vols.sum(), rel=1e-12)
    assert np.all(c.node_mass[face.dynamic_nodes] > 0)


def test_membrane_stiffness_is_van_gelders_on_an_equilateral_patch():
    """A stretched equilateral triangle mesh of springs E t A / |e|^2 (sum over the triangles
    of an edge) has the in-plane Young's modulus x thickness E t (Poisson's ratio 1/3): the
    energy of a uniaxial stress state matches (E t / 2) eps^2 per area."""
    et = 100.0
    a = 1e-3
    # one equilateral triangle; uniform strain; energy per area
    pts = np.array([[0, 0], [a, 0], [a / 2, a * np.sqrt(3) / 2]])
    area = np.sqrt(3) / 4 * a * a
    edges = [(0, 1), (1, 2), (2, 0)]
    k = et * area / a**2  # one triangle per edge in this patch
    nu = 1 / 3
    eps = 1e-3
    strain = np.diag([eps, -nu * eps])  # uniaxial stress
    energy = sum(0.5 * k * (a * (pts[j] - pts[i]) @ strain @ (pts[j] - pts[i]) / a**2) ** 2
                 for i, j in edges)
    assert energy / area == pytest.approx(0.5 * et * eps**2, rel=1e-9)


def test_extra_bulk_modulus_gives_the_poisson_ratio():
    mu = 5e3
    for nu in (0.3, 0.45, 0.48):
        k_total = extra_bulk_modulus(mu, nu) + 5 * mu / 3
        # K = 2 mu (1 + nu) / (3 (1 - 2 nu))
        assert k_total == pytest.approx(2 * mu * (1 + nu) / (3 * (1 - 2 * nu)), rel=1e-12)
    assert extra_bulk_modulus(mu, 0.2) == 0.0  # the springs alone are already stiffer


def _prism(rng):
    top = np.array([[0, 0, 0], [2e-3, 0, 0], [0.7e-3, 1.8e-3, 0]], float)
    bottom = top + np.array([0.0, 0.0, -4e-3])
    p = np.concatenate([top, bottom]) + rng.normal(0, 3e-4, (6, 3))
    return p


def test_pressure_is_minus_the_gradient_of_its_energy():
    rng = np.random.default_rng(1)
    p = _prism(rng)
    v0 = symmetric_volume(p) * 0.9
    bulk = 2e4 / v0  # K / V0
    out = np.zeros((6, 3))
    prism_pressure(p, v0, bulk, out)

    def energy(q):
        return 0.5 * bulk * (symmetric_volume(q) - v0) ** 2

    h = 1e-9
    for k in range(6):
        for a in range(3):
            q1, q2 = p.copy(), p.copy()
            q1[k, a] += h
            q2[k, a] -= h
            assert out[k, a] == pytest.approx(-(energy(q1) - energy(q2)) / (2 * h), rel=1e-5,
                                              abs=1e-12)


def test_symmetric_volume_does_not_depend_on_the_node_order():
    rng = np.random.default_rng(2)
    p = _prism(rng)
    # the same prism with its triangle wound from another corner, and mirrored
    order = [1, 2, 0, 4, 5, 3]
    assert symmetric_volume(p[order]) == pytest.approx(symmetric_volume(p), rel=1e-12)
    mirrored = p * np.array([-1.0, 1.0, 1.0])
    assert symmetric_volume(mirrored[[0, 2, 1, 3, 5, 4]]) == pytest.approx(symmetric_volume(p),
                                                                         rel=1e-12)


def test_bead_jacobian_matches_finite_differences():
    """Bead-space stiffness -df/dp and damping -df/dv of a linear muscle and a sphincter
    (one node per bead) equal central differences of the bead forces. The stiffness is taken at
    rest velocities: the linearisation leaves out dF/dl' dl'/dx, which vanishes there."""
    from facemech.physics.assembly import bead_muscle_forces
    from facemech.physics.bundles import MuscleBundle
    from facemech.physics.kinds import MusclePull
    from facemech.solvers.muscle_implicit import bead_jacobian

    p = preset("anatomical")
    rng = np.random.default_rng(3)
    # nodes 0-3 move; node 4 is the linear muscle's origin
    pos = np.array([[0.0, 0, 0], [0.01, 0.002, 0.001], [0.02, 0.0, 0.003], [0.03, -0.004, 0],
                    [0.01, 0.04, -0.02]]) + rng.normal(0, 1e-4, (5, 3))
    vel = rng.normal(0, 2e-3, (5, 3))
    kind = np.array([0, 1])
    origin = np.array([4, -1])
    offset = np.zeros((2, 3))
    ptr = np.array([0, 1, 4])
    nodes = np.array([0, 1, 2, 3])
    weights = np.ones(4)
    bead = np.array([0, 1, 2, 3])
    bead_start = np.array([0, 1, 4])
    rest = np.array([0.9 * np.linalg.norm(pos[0] - pos[4]),
                     0.95 * sum(np.linalg.norm(pos[k + 1] - pos[k]) for k in (1, 2))])
    k_passive = np.array([2.0, 5.0])
    m_force = np.array([2.0, 4.0])
    muscles = MuscleBundle(kind=kind, origin=origin, offset=offset, ptr=ptr, nodes=nodes,
                           weights=weights, bead=bead, bead_start=bead_start, rest_length=rest,
                           k_passive=k_passive, pull=MusclePull.ALONG_LENGTH.value, f1=p.f1,
                           f2=p.f2, f3=p.f3, f4=np.full(2, p.f4))

    def forces(q, u):
        out = np.zeros_like(q)
        bead_muscle_forces(muscles, q, u, m_force, out)
        return out[:4].reshape(-1)

    still = np.zeros_like(vel)
    active = np.array([0, 1])
    stiff, _ = bead_jacobian(muscles, pos[:4].copy(), still[:4].copy(), pos, still, m_force,
                             active)
    _, damp = bead_jacobian(muscles, pos[:4].copy(), vel[:4].copy(), pos, vel, m_force, active)
    h = 1e-7
    for col in range(12):
        k, a = divmod(col, 3)
        dq = np.zeros((5, 3))
        dq[k, a] = h
        fd_k = -(forces(pos + dq, still) - forces(pos - dq, still)) / (2 * h)
        fd_c = -(forces(pos, vel + dq * 1e3) - forces(pos, vel - dq * 1e3)) / (2 * h * 1e3)
        np.testing.assert_allclose(stiff[:, col], fd_k, rtol=1e-4, atol=1e-4)
        np.testing.assert_allclose(damp[:, col], fd_c, rtol=1e-4, atol=1e-6)


def test_woodbury_solve_equals_the_direct_solve(face):
    """(A0 + U S U^T) x = b solved through the constant factorisation and the small system
    equals a sparse direct solve of the same matrix (the muscles couple the axes)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    from facemech.physics.model import model as face_model
    from facemech.solvers.step import Stepper

    p = preset("anatomical")
    model = face_model(face, p)
    ph = model.physics
    system = Stepper(model).solver_state.system
    mj = system.muscles
    m_force = np.zeros(ph.n_muscles)
    m_force[ph.model.muscles.names.index("OOI_L")] = 3.0
    m_force[ph.model.muscles.names.index("RIS_R")] = 1.0
    pos = ph.model.rest_positions.copy()
    jac = mj.linearise(pos, np.zeros_like(pos), m_force, m_force)
    h = system.factor_step
    rhs = np.random.default_rng(4).normal(size=(ph.n_dynamic, 3))
    x = mj.solve(rhs, jac, h)
    a0 = sp.diags(system.mass) + h * system.damping + h * h * system.stiffness
    u = sp.kron(jac.wa, sp.identity(3)).tocsr()
    s = sp.csr_matrix(h * jac.damp + h * h * jac.stiff)
    full = (sp.kron(a0, sp.identity(3)) + u @ s @ u.T).tocsc()
    ref = spsolve(full, rhs.reshape(-1)).reshape(-1, 3)
    np.testing.assert_allclose(x, ref, rtol=1e-7, atol=1e-10 * np.abs(ref).max())


def test_bilinear_volume_is_the_mean_of_the_two_splits():
    """The closed form of the side patches equals the mean of the two triangulations."""
    from facemech.physics.volume import PRISM_TRIANGLES, PRISM_TRIANGLES_ALT

    def split_volume(p, tris):
        c = p.mean(axis=0)
        q = p - c
        return sum(q[a] @ np.cross(q[b], q[t]) for a, b, t in tris) / 6.0

    rng = np.random.default_rng(5)
    for _ in range(5):
        p = _prism(rng) + rng.normal(0, 5e-4, (6, 3))  # warped sides
        mean = 0.5 * (split_volume(p, PRISM_TRIANGLES) + split_volume(p, PRISM_TRIANGLES_ALT))
        assert symmetric_volume(p) == pytest.approx(mean, rel=1e-12)


def test_bead_jacobian_takes_up_the_passive_stiffness_continuously_at_the_rest_length():
    """The passive branch's stiffness enters the Jacobian over a narrow band about l0, not at a
    sharp ``l > l0``: every muscle starts at its rest length to the last bit, and a sharp switch
    made the step (and a whole run, by 3e-7 m) hang on the rounding of that length (OpenBLAS's
    kernels flipped it)."""
    from facemech.solvers.muscle_implicit import PASSIVE_STIFFNESS_BAND, hill_derivatives

    p = preset("anatomical")
    l0, kp, m = 0.03, 10.0, 2.0

    def d_len(length):
        return hill_derivatives(m, length, l0, 0.0, kp, p.f1, p.f2, p.f3, p.f4)[1]

    below, at, above = d_len(l0 * (1 - 1e-15)), d_len(l0), d_len(l0 * (1 + 1e-15))
    assert abs(above - below) < 1e-6 * kp
    assert abs(at - (d_len(l0 * (1 - 3e-6)) + d_len(l0 * (1 + 3e-6))) / 2) < 1e-3 * kp
    # beyond the band (no activity: the passive branch alone): the law's exact slope
    passive = [hill_derivatives(0.0, l0 * (1 + s * PASSIVE_STIFFNESS_BAND), l0, 0.0, kp, p.f1,
                                p.f2, p.f3, p.f4)[1] for s in (-2.0, 0.0, 2.0)]
    assert passive == [0.0, 0.5 * kp, kp]
