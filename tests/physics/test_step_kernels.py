"""The fast forward step (issue 16): the unrolled prism kernels, the pressure in vector blocks,
the volume about one node, the spring law with its knee as a length, and the threaded force
assembly against one thread."""

import numpy as np
import pytest

from facemech import preset
from facemech.errors import InputError
from facemech.physics import volume
from facemech.physics.springs import tension, tension_at
from facemech.physics.threads import get_threads, set_threads


def random_prisms(rng, n=50):
    """Warped prisms of a few mm, far from the origin."""
    top = np.array([[0, 0, 0], [2e-3, 0, 0], [0.7e-3, 1.8e-3, 0]], float)
    base = np.concatenate([top, top + np.array([0.0, 0.0, -4e-3])])
    return base + rng.normal(0, 4e-4, (n, 6, 3)) + rng.normal(0, 0.05, (n, 1, 3))


def eight_triangle_volume(p):
    """The former formula: the eight triangles of PRISM_TRIANGLES about the centre."""
    r = p - p.mean(axis=0)
    t = volume.PRISM_TRIANGLES
    return np.einsum("ta,ta->", r[t[:, 0]], np.cross(r[t[:, 1]], r[t[:, 2]])) / 6.0


def eq9_forces(p, v0, rel0, k_volume, k_shape):
    """Eq. (9) with the former volume, in numpy."""
    def unit(n):
        return n / (np.linalg.norm(n) + 1e-300)
    top = unit(np.cross(p[1] - p[0], p[2] - p[0]))
    bottom = unit(np.cross(p[4] - p[3], p[5] - p[3]))
    normals = np.array([top] * 3 + [-bottom] * 3)
    dv = k_volume * (eight_triangle_volume(p) - v0)
    return -dv * normals - k_shape * ((p - p.mean(axis=0)) - rel0)


def test_volume_about_one_node_equals_the_eight_triangles():
    """Four triple products about node 0 (volume._volume_about_node0) and prism_volume give
    the eight-triangle volume, and prism_forces eq. (9)'s forces, to 1e-12 relative on random
    warped prisms."""
    rng = np.random.default_rng(16)
    prisms = random_prisms(rng)
    for p in prisms:
        want = eight_triangle_volume(p)
        assert volume.prism_volume(p) == pytest.approx(want, rel=1e-12)
        assert volume._volume_about_node0(p[1:] - p[0]) == pytest.approx(want, rel=1e-12)
        v0 = want * 0.9
        rel0 = p - p.mean(axis=0) + rng.normal(0, 1e-5, (6, 3))
        out = np.empty((6, 3))
        volume.prism_forces(p, v0, rel0, 4e5, 3.0, out)
        ref = eq9_forces(p, v0, rel0, 4e5, 3.0)
        np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_unrolled_prism_kernels_equal_the_array_kernels_to_the_bit():
    """add_prism_forces and add_prism_pressure, reading the nodes through the element's node
    list, add exactly what prism_forces and prism_pressure compute on the (6, 3) prism."""
    rng = np.random.default_rng(17)
    prisms = random_prisms(rng, 20)
    pos = prisms.reshape(-1, 3)
    nodes = rng.permutation(len(pos)).reshape(-1, 6)  # scattered node numbers
    pos = pos[np.argsort(nodes.reshape(-1))]  # node nodes[e, k] sits at prisms[e, k]
    rest = np.array([volume.prism_volume(p) for p in prisms]) * 1.1
    rel = prisms - prisms.mean(axis=1, keepdims=True) + rng.normal(0, 1e-5, prisms.shape)
    got_f = np.zeros_like(pos)
    got_p = np.zeros_like(pos)
    want_f = np.zeros_like(pos)
    want_p = np.zeros_like(pos)
    q = np.empty((6, 3))
    for e in range(len(nodes)):
        volume.add_prism_forces(pos, nodes, e, rest[e], rel, 4e5, 3.0, got_f)
        volume.prism_forces(prisms[e], rest[e], rel[e], 4e5, 3.0, q)
        want_f[nodes[e]] += q
        vol = volume.add_prism_pressure(pos, nodes, e, rest[e], 2e4 / rest[e], got_p)
        assert vol == volume.prism_pressure(prisms[e], rest[e], 2e4 / rest[e], q)
        want_p[nodes[e]] += q
    assert np.array_equal(got_f, want_f) and np.abs(want_f).max() > 0
    assert np.array_equal(got_p, want_p) and np.abs(want_p).max() > 0


@pytest.mark.parametrize("n", [1, 63, 64, 65, 200])
def test_pressure_in_blocks_equals_one_prism_at_a_time_to_the_bit(n):
    """add_pressure_blocks (gathered into blocks of 64, computed in vector instructions) adds
    exactly what add_prism_pressure adds prism by prism, in the prisms' order, for counts below,
    at and across a block's end, and over a sub-range; a prism of bulk 0 adds nothing."""
    rng = np.random.default_rng(19)
    prisms = random_prisms(rng, n)
    pos = prisms.reshape(-1, 3)[rng.permutation(6 * n)]
    # prisms sharing nodes: each prism takes six of the scattered nodes, some twice over
    nodes = rng.integers(0, len(pos), (n, 6))
    nodes[:, :3] = np.arange(3 * n).reshape(n, 3) % len(pos)
    rest = np.abs(rng.normal(1e-8, 2e-9, n))
    bulk = 2e4 / rest
    bulk[3::7] = 0.0
    want = np.zeros_like(pos)
    for e in range(n):
        volume.add_prism_pressure(pos, nodes, e, rest[e], bulk[e], want)
    got = np.zeros_like(pos)
    block = (np.empty((18, volume.PRESSURE_BLOCK)), np.empty((18, volume.PRESSURE_BLOCK)))
    volume_blocks(pos, nodes, rest, bulk, 0, n, *block, got)
    assert np.array_equal(got, want) and np.abs(want).max() > 0
    lone = np.zeros_like(pos)
    volume_blocks(pos, nodes, rest, np.zeros(n), 0, n, *block, lone)
    assert not lone.any()
    if n > 2:
        part_want = np.zeros_like(pos)
        for e in range(1, n - 1):
            volume.add_prism_pressure(pos, nodes, e, rest[e], bulk[e], part_want)
        part = np.zeros_like(pos)
        volume_blocks(pos, nodes, rest, bulk, 1, n - 1, *block, part)
        assert np.array_equal(part, part_want)


def volume_blocks(*args):
    """add_pressure_blocks compiled on its own (it is inlined into the force kernels)."""
    import numba as nb

    global _blocks
    if "_blocks" not in globals():
        _blocks = nb.njit(error_model="numpy")(
            lambda pos, nodes, rest, bulk, e0, e1, c, f, out: volume.add_pressure_blocks(
                pos, nodes, rest, bulk, e0, e1, c, f, out))
    _blocks(*args)


@pytest.mark.parametrize("sigma", [0.0, 0.98])
def test_spring_law_with_its_knee_as_a_length(sigma):
    """The biphasic law both ways (sigma <= 0) and eq. (2) in compression (sigma > 0), at
    strains on either side of the knee, equal the hand-written law exactly; so does
    tension_at with the knee as a length (inf for a linear spring)."""
    l0, k1, k2, knee = 2e-3, 50.0, 400.0, 0.15
    for strain in (-0.4, -0.15, -0.1, 0.0, 0.1, 0.15, 0.4):
        dl = strain * l0
        length = l0 + dl
        for bi in (False, True):
            got = tension(length, l0, k1, k2, knee, sigma, bi)
            assert got == tension_at(length, l0, k1, k2, knee, knee * l0 if bi else np.inf,
                                     sigma)
            d = length - l0
            if sigma > 0 and d < 0:
                want = k1 * l0 * np.tan(0.5 * np.pi * sigma * d / l0)
            elif bi and d > knee * l0:
                want = knee * k1 * l0 + k2 * (d - knee * l0)
            elif bi and d < -knee * l0:
                want = -knee * k1 * l0 + k2 * (d + knee * l0)
            else:
                want = k1 * d
            assert got == want


def test_two_threads_give_one_threads_forces_and_frame(face):
    """The default face's forces, and one explicit frame of it, on two threads equal one
    thread's within 1e-12 relative (only the order of the additions differs)."""
    from facemech.physics.assembly import Physics, accumulate_forces, rest_anchors
    from facemech.solvers.explicit import EulerSteps, euler_frame
    from facemech.solvers.solver_state import solver_state

    ph = Physics.build(face, preset("anatomical"))
    b = ph.forces
    anchors = rest_anchors(ph)
    rng = np.random.default_rng(18)
    pos = ph.model.rest_positions + rng.normal(0, 2e-4, ph.model.rest_positions.shape)
    vel = rng.normal(0, 1e-2, pos.shape)
    m = np.full(ph.n_muscles, 0.3)
    ss = solver_state(ph, 1)
    steps = EulerSteps(10, 1e-6, ss.tau, ss.dynamic, ss.inv_mass)
    results = []
    try:
        for n in (1, 2):
            assert set_threads(n) == n and get_threads() == n
            out = np.empty_like(pos)
            accumulate_forces(b, pos, vel, m, anchors, out)
            frame = euler_frame(b, ss.jaw, steps, pos, vel, m, np.zeros_like(m), m, anchors,
                                np.zeros(3), np.zeros(3))
            results.append((out, frame[0], frame[1]))
    finally:
        set_threads(1)
    (f1, p1, v1), (f2, p2, v2) = results
    assert np.abs(f1).max() > 1e-3
    np.testing.assert_allclose(f2, f1, rtol=0, atol=1e-12 * np.abs(f1).max())
    np.testing.assert_allclose(p2, p1, rtol=1e-12)
    np.testing.assert_allclose(v2, v1, rtol=0, atol=1e-12 * np.abs(v1).max())
    assert np.all(np.isfinite(p1)) and not np.array_equal(p1, pos)


def test_set_threads_takes_whole_counts_within_the_pool():
    with pytest.raises(InputError) as e:
        set_threads(0)
    assert e.value.field == "threads"
    with pytest.raises(InputError):
        set_threads(1.5)
    with pytest.raises(InputError):
        set_threads(10_000)
    assert set_threads(1) == 1 and get_threads() == 1


@pytest.mark.parametrize("threads", [1, 2])
def test_a_collapsed_spring_raises_on_any_thread_count(face, threads):
    """Two nodes of a spring at one point: one thread raises ZeroDivisionError, and so does the
    parallel path (``prange`` cannot raise: its forces are checked after the reduction)."""
    from facemech.physics.assembly import Physics, accumulate_forces, rest_anchors

    ph = Physics.build(face, preset("anatomical"))
    b = ph.forces
    pos = ph.model.rest_positions.copy()
    i, j = b.springs.i[0], b.springs.j[0]
    pos[j] = pos[i]
    try:
        assert set_threads(threads) == threads
        with pytest.raises(ZeroDivisionError):
            accumulate_forces(b, pos, np.zeros_like(pos), np.zeros(ph.n_muscles),
                              rest_anchors(ph), np.empty_like(pos))
    finally:
        set_threads(1)


def test_slabs_of_one_parity_share_no_node_and_hold_every_element_once(face):
    """The default face in 2 x threads slabs across the face: every spring and prism once,
    slabs of one parity without a common node, the work about even, in order along the axis
    (top to bottom, the built-in face's node order, by default; left to right across x)."""
    from facemech.physics.assembly import Physics
    from facemech.physics.slabs import slab_bundles

    ph = Physics.build(face, preset("anatomical"))
    b = ph.forces
    rest = ph.model.rest_positions
    for threads, axis in ((2, None), (3, None), (4, None), (2, "x"), (3, "x")):
        sl = slab_bundles(b.springs, b.prisms, rest, threads, axis=axis)
        sp, pp = sl.spring_ptr, sl.prism_ptr
        assert len(sp) == len(pp) == 2 * threads + 1
        pairs = {tuple(x) for x in np.stack([b.springs.i, b.springs.j], 1)}
        assert {tuple(x) for x in np.stack([sl.springs.i, sl.springs.j], 1)} == pairs
        assert len(sl.springs.i) == len(b.springs.i)
        assert sorted(map(tuple, sl.prisms.nodes)) == sorted(map(tuple, b.prisms.nodes))
        nodes = [np.unique(np.concatenate([sl.springs.i[sp[k]:sp[k + 1]],
                                           sl.springs.j[sp[k]:sp[k + 1]],
                                           sl.prisms.nodes[pp[k]:pp[k + 1]].ravel()]))
                 for k in range(2 * threads)]
        for a in range(2 * threads):
            for c in range(a + 2, 2 * threads, 2):
                assert not np.intersect1d(nodes[a], nodes[c]).size, (threads, a, c)
        zero = [sl.zero[sl.zero_ptr[q]:sl.zero_ptr[q + 1]] for q in range(threads)]
        assert np.array_equal(np.sort(sl.zero), np.arange(len(rest)))  # each node once
        for q in range(threads):  # nobody zeroes a node another thread's even slab adds to
            for p in range(threads):
                if p != q:
                    assert not np.intersect1d(zero[q], nodes[2 * p]).size
        work = np.diff(sp) + 3.0 * np.diff(pp)
        assert work.max() < 1.05 * work.min()
        col, sign = (0, 1) if axis == "x" else (1, -1)
        mid = [sign * rest[n, col].mean() for n in nodes]
        assert np.all(np.diff(mid) > 0)


def test_slabs_are_cut_across_the_axis_the_nodes_are_numbered_along(face):
    """The built-in face numbers its nodes row by row from the hairline down: its slabs are cut
    across y, where the two threads' slabs share almost no 128-byte block of the forces (and
    across x, where every row is cut, many). The same mesh numbered column by column, left to
    right, is cut across x."""
    from facemech.physics.assembly import Physics
    from facemech.physics.slabs import slab_axis

    ph = Physics.build(face, preset("anatomical"))
    b = ph.forces
    rest = ph.model.rest_positions
    assert slab_axis(b.springs, b.prisms, rest) == "y"
    n = ph.model.n_surface
    layer = np.arange(len(rest)) // n
    order = np.lexsort((-rest[:, 1], np.round(rest[:, 0], 3), layer))  # column by column
    new = np.empty(len(rest), np.int64)
    new[order] = np.arange(len(rest))
    springs = b.springs._replace(i=new[b.springs.i], j=new[b.springs.j])
    prisms = b.prisms._replace(nodes=new[b.prisms.nodes])
    assert slab_axis(springs, prisms, rest[order]) == "x"


@pytest.mark.slow
def test_slab_forces_do_not_depend_on_the_thread_count(face):
    """The slabs' forces on one thread and on two are the same to the bit (each node's
    additions in the order the slabs fix), and equal the element order's within 1e-15."""
    from facemech.physics.assembly import (
        Physics,
        element_forces_one_thread,
        slab_forces,
    )

    ph = Physics.build(face, preset("anatomical"))
    b = ph.forces
    sl = b.slabs
    assert len(sl.spring_ptr) > 2
    rng = np.random.default_rng(21)
    pos = ph.model.rest_positions + rng.normal(0, 2e-4, ph.model.rest_positions.shape)
    vel = rng.normal(0, 1e-2, pos.shape)
    got = []
    try:
        for n in (1, 2):
            set_threads(n)
            out = np.zeros_like(pos)
            out = np.full_like(pos, np.nan)  # every node's forces zeroed first
            assert slab_forces(sl.springs, sl.prisms, sl.spring_ptr, sl.prism_ptr, sl.zero,
                               sl.zero_ptr, pos, vel, out)
            got.append(out)
    finally:
        set_threads(1)
    assert np.array_equal(got[0], got[1])
    ref = np.zeros_like(pos)
    assert element_forces_one_thread(b.springs, b.prisms, pos, vel, ref)
    np.testing.assert_allclose(got[0], ref, rtol=0, atol=1e-15 * np.abs(ref).max() * 10)


def test_default_threads_are_the_cores_available_or_the_environments():
    from facemech.physics.threads import available_cores, default_threads

    assert default_threads({}) == available_cores() >= 1
    assert default_threads({"FACEMECH_THREADS": "1"}) == 1
    assert default_threads({"FACEMECH_THREADS": " 1 "}) == 1
    for bad in ("0", "two", "-1", "1.5", "100000"):
        with pytest.raises(InputError) as e:
            default_threads({"FACEMECH_THREADS": bad})
        assert e.value.field == "FACEMECH_THREADS"


def test_a_wrong_facemech_threads_is_one_line_and_status_2(monkeypatch, capsys):
    from conftest import run_cli

    monkeypatch.setenv("FACEMECH_THREADS", "lots")
    try:
        code, out, err = run_cli(monkeypatch, capsys, "face", "info")
    finally:
        set_threads(1)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "FACEMECH_THREADS" in err and "'lots'" in err
