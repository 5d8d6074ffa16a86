"""Dynamics of the assembled kernel with the paper's integrator on small systems."""

import numpy as np
import pytest

from facemech.params import MUSCLE_GROUPS, Parameters
from facemech.physics.bundles import (
    ContactBundle,
    ForceBundles,
    MuscleBundle,
    PrismBundle,
    RestorationBundle,
    SpringBundle,
)
from facemech.physics.springs import scaled_stiffness
from facemech.solvers.explicit import ExplicitEuler
from facemech.solvers.mandible import JawBundle
from facemech.solvers.solver_state import SolverState
from facemech.solvers.state import Controls, State


def network(n_nodes, springs_ij, rest, k, *, damping, biphasic=None, tied=(), tied_rest=None,
            k_restore=0.0):
    """The force bundles of a bare spring network (nothing but springs and tied nodes), built
    by name, and the jaw bundle that carries its tied nodes' anchors (a jaw with no nodes)."""
    i = np.array([s[0] for s in springs_ij], np.int64)
    j = np.array([s[1] for s in springs_ij], np.int64)
    l0 = np.linalg.norm(rest[j] - rest[i], axis=1)
    k = np.broadcast_to(np.asarray(k, float), l0.shape).copy()
    bip = np.zeros(len(i), bool) if biphasic is None else np.asarray(biphasic)
    tied = np.asarray(tied, np.int64)
    t_rest = rest[tied] if tied_rest is None else np.asarray(tied_rest, float)
    forces = ForceBundles(
        springs=SpringBundle.make(i=i, j=j, rest_length=l0, k_low=k, k_high=10 * k, biphasic=bip,
                                  damping=np.full(len(i), float(damping)), knee=0.2,
                                  sigma=0.98),
        prisms=PrismBundle.empty(),
        muscles=MuscleBundle.empty(),
        restoration=RestorationBundle(nodes=tied, skull=tied + n_nodes,
                                      height=np.full(len(tied), -1.0),
                                      k_restore=np.full(len(tied), float(k_restore)),
                                      bone_k=np.zeros(len(tied)), skull_contact=True),
        contact=ContactBundle.empty(),
    )
    jaw = JawBundle(hinge_point=np.zeros(3), hinge_axis=np.array([1.0, 0.0, 0.0]),
                    nodes=np.zeros(0, np.int64), weights=np.zeros(0),
                    rest_from_hinge=np.zeros((0, 3)), anchor_weights=np.zeros(len(tied)),
                    anchor_rest=t_rest, anchor_normal=np.zeros((len(tied), 3)))
    return forces, jaw


def run_euler(pos, vel, net, n_dynamic, mass, dt, steps):
    """Positions after ``steps`` explicit Euler steps of ``dt`` s: one frame of the public
    solver, with a solver state made by name."""
    forces, jaw = net
    ss = SolverState(forces=forces, jaw=jaw, dynamic=np.arange(n_dynamic, dtype=np.int64),
                     inv_mass=np.full(len(pos), 1.0 / mass),
                     muscle_group=np.zeros(0, np.int64), max_force=np.zeros(0), tau=0.015,
                     frame_duration=steps * dt, n_steps=steps, step=dt)
    state = State(pos, vel, np.zeros(0), np.zeros(0))
    controls = Controls(np.zeros(len(MUSCLE_GROUPS)), np.zeros(3), np.zeros(3))
    return ExplicitEuler(dt).step(ss, state, controls).positions


def single_oscillator(dt, duration, mass, k, r, x0=1e-4):
    """Node 0 (mass) on a 1-cm spring to fixed node 1, pulled x0 along the spring, released."""
    rest = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0]])
    net = network(2, [(0, 1)], rest, k, damping=r)
    pos = rest.copy()
    pos[0, 0] -= x0  # stretched: elongation regime, linear law
    vel = np.zeros_like(pos)
    pos = run_euler(pos, vel, net, 1, mass, dt, round(duration / dt))
    return -pos[0, 0]


def exact_oscillator(t, mass, k, r, x0=1e-4):
    """m x'' + r x' + k x = 0, x(0) = x0, x'(0) = 0 (over- or under-damped)."""
    disc = np.emath.sqrt(r * r - 4 * mass * k)
    s1, s2 = (-r + disc) / (2 * mass), (-r - disc) / (2 * mass)
    a = x0 * s2 / (s2 - s1)
    return np.real(a * np.exp(s1 * t) + (x0 - a) * np.exp(s2 * t))


def test_mass_spring_damper_relaxes_with_time_constant_r_over_k():
    p = Parameters()
    k, r = p.k_dermal_low, p.damping  # 600 dyne/cm and 30 dyne s/cm: tau = r/k = 50 ms
    t = 0.2
    got = single_oscillator(1e-5, t, p.node_mass, k, r)
    assert got == pytest.approx(exact_oscillator(t, p.node_mass, k, r), rel=2e-3)
    # with a negligible mass the relaxation is exp(-t k / r): the paper's r/k response time
    tiny = 1e-7
    got = single_oscillator(2e-6, 0.05, tiny, k, r)
    assert got == pytest.approx(1e-4 * np.exp(-0.05 * k / r), rel=2e-3)


def test_paper_integrator_converges_at_first_order():
    p = Parameters()
    k, r, t = 1.2, p.damping, 0.05
    exact = exact_oscillator(t, p.node_mass, k, r)
    errs = [abs(single_oscillator(dt, t, p.node_mass, k, r) - exact)
            for dt in (1e-4, 0.5e-4, 0.25e-4)]
    ratios = [errs[0] / errs[1], errs[1] / errs[2]]
    assert all(1.8 < q < 2.35 for q in ratios), ratios


def test_static_sag_matches_linear_solve():
    """A 5x5 grid of springs, boundary fixed, one interior node pulled by a restoration spring
    whose anchor is displaced: the damped dynamics settle on the linear static solution."""
    n = 5
    xs, ys = np.meshgrid(np.arange(n) * 2e-3, np.arange(n) * 2e-3)
    rest = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(n * n)])
    edges = []
    for a in range(n):
        for b in range(n):
            v = a * n + b
            if b + 1 < n:
                edges.append((v, v + 1))
            if a + 1 < n:
                edges.append((v, v + n))
            if a + 1 < n and b + 1 < n:
                edges.append((v, v + n + 1))
    interior = [a * n + b for a in range(1, n - 1) for b in range(1, n - 1)]
    boundary = [v for v in range(n * n) if v not in interior]
    order = interior + boundary  # dynamic nodes first
    remap = {v: q for q, v in enumerate(order)}
    rest = rest[order]
    edges = [(remap[a], remap[b]) for a, b in edges]
    k_ref = 1.2
    l0 = np.array([np.linalg.norm(rest[a] - rest[b]) for a, b in edges])
    k = scaled_stiffness(k_ref, l0)
    pulled = remap[12]  # the centre node
    shift = np.array([1e-6, 0.5e-6, 0.0])  # tiny: linear regime
    k_pull = 0.5
    net = network(len(rest), edges, rest, k, damping=0.03, tied=[pulled],
                  tied_rest=(rest[pulled] + shift)[None], k_restore=k_pull)
    pos, vel = rest.copy(), np.zeros_like(rest)
    pos = run_euler(pos, vel, net, len(interior), 2.3e-4, 1 / 3000, 30000)
    # piecewise-linear statics: a spring's stiffness is k when stretched and pi sigma k / 2
    # when compressed (slopes of eqs. 1-2 at rest); solve, update the pattern, repeat
    nd = len(interior)
    free = [q for q in range(3 * nd) if q % 3 != 2]  # the plane is floppy out of plane
    slope = np.ones(len(edges))
    for _ in range(10):
        kmat = np.zeros((3 * nd, 3 * nd))
        for (a, b), ks, sl in zip(edges, k, slope, strict=True):
            d = (rest[b] - rest[a]) / np.linalg.norm(rest[b] - rest[a])
            blk = ks * sl * np.outer(d, d)
            for u, w, sgn in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                if u < nd and w < nd:
                    kmat[3 * u:3 * u + 3, 3 * w:3 * w + 3] += sgn * blk
        kmat[3 * pulled:3 * pulled + 3, 3 * pulled:3 * pulled + 3] += k_pull * np.eye(3)
        rhs = np.zeros(3 * nd)
        rhs[3 * pulled:3 * pulled + 3] = k_pull * shift
        u = np.zeros(3 * nd)
        u[free] = np.linalg.solve(kmat[np.ix_(free, free)], rhs[free])
        disp = np.zeros_like(rest)
        disp[:nd] = u.reshape(nd, 3)
        elong = [np.dot(disp[b] - disp[a], rest[b] - rest[a]) for a, b in edges]
        new = np.where(np.asarray(elong) < 0, np.pi * 0.98 / 2, 1.0)
        if np.array_equal(new, slope):
            break
        slope = new
    got = (pos[:nd] - rest[:nd]).reshape(-1)[free]
    np.testing.assert_allclose(got, u[free], rtol=2e-3, atol=1e-13)
