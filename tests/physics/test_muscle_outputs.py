"""Muscle outputs (tension, length, lengthening velocity, activation) against eqs. (3)-(7) of
Lucero & Munhall (1999) by hand, and their results-file round trip."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conftest import activity
from facemech import Stepper, simulate
from facemech.io.results import read_results, results_muscles, write_results
from facemech.params import MUSCLE_GROUPS, preset
from facemech.physics.assembly import Physics
from facemech.physics.model import model as face_model
from facemech.physics.muscle import activation_response
from facemech.physics.muscle_outputs import muscle_output_variables, muscle_series
from facemech.solvers.state import State

FRAMES = 8
LEVEL = 0.6


def hand_kinematics(physics, pos, vel):
    """Length (m) and lengthening rate (m/s) of every instance, in plain numpy from the nodes."""
    ph = physics
    mus = ph.model.muscles
    beads = mus.beads()
    lengths, rates = [], []
    for m in range(ph.n_muscles):
        a, b = mus.ptr[m], mus.ptr[m + 1]
        nodes, w, bead = mus.nodes[a:b], mus.weights[a:b], beads[a:b]
        if ph.forces.muscles.pull == 1:  # beads: weighted means of their nodes
            pts = np.array([w[bead == k] @ pos[nodes[bead == k]] for k in range(bead.max() + 1)])
            vts = np.array([w[bead == k] @ vel[nodes[bead == k]] for k in range(bead.max() + 1)])
            offset = mus.offsets()[m]
        else:  # the seeds': path nodes; the insertion's weighted mean; no offset
            pts, vts = pos[nodes], vel[nodes]
            if mus.kind[m] == 0:
                pts, vts = (w @ pos[nodes])[None], (w @ vel[nodes])[None]
            offset = np.zeros(3)
        if mus.kind[m] == 1:
            d = np.diff(pts, axis=0)
            seg = np.linalg.norm(d, axis=1)
            lengths.append(seg.sum())
            rates.append(np.sum(np.einsum("ka,ka->k", d, np.diff(vts, axis=0)) / seg))
        else:
            o = mus.origin[m]
            d = pts[0] - pos[o] - offset
            lengths.append(np.linalg.norm(d))
            rates.append(d @ (vts[0] - vel[o]) / np.linalg.norm(d))
    return np.array(lengths), np.array(rates)


def hand_tension(params, groups, m_filtered, length, rest, velocity):
    """F = M fl(l) [f1 + f2 atan(f3 + f4 dl/dt)] + [k_m (l - l0)]^+ (eqs. 5-7), with f4 the
    preset's or, under an intrinsic speed, (f3 - x_half) / (v_half l0) per muscle."""
    p = params
    f4 = p.f4
    if p.fv_vmax > 0:
        x_half = np.tan(((p.f1 + p.f2 * np.arctan(p.f3)) / 2 - p.f1) / p.f2)
        a = p.fv_curvature
        f4 = (p.f3 - x_half) / (a / (2 * a + 1) * p.fv_vmax * rest)
    fl = np.exp(-np.abs(((length / rest) ** 2.3 - 1.0) / 1.26) ** 1.62)
    k_m = np.array([p.passive_stiffness(g) for g in groups])
    active = m_filtered * fl * (p.f1 + p.f2 * np.arctan(p.f3 + f4 * velocity))
    return active + np.maximum(k_m * (length - rest), 0.0)


#: the anatomical preset with the intrinsic-speed force-velocity law and the lips' measured
#: activation dynamics (Ito et al. 2004: 6.1 Hz, damping ratio 0.7): per-muscle f4, an
#: underdamped filter
FIBRE_DYNAMICS = {"fv_vmax": 20.0, "tau_activation": 1 / (2 * np.pi * 6.1),
                  "activation_damping": 0.7}


@pytest.fixture(scope="module", params=["anatomical", "lucero1999", "fibre-dynamics"])
def constant_run(request, face, seeds_face):
    """ZYG (linear) and OOS (sphincter) at 0.6 from frame 0, an implicit integrator (which
    integrates the filter of eq. 4 exactly)."""
    prm = (preset("anatomical").with_(**FIBRE_DYNAMICS) if request.param == "fibre-dynamics"
           else preset(request.param))
    model = face if prm.tissue != "uniform" else seeds_face
    sim = simulate(face_model(model, prm), activity(FRAMES, ZYG=LEVEL, OOS=LEVEL),
                   integrator="implicit")
    return prm, sim


def test_outputs_match_the_equations_by_hand(constant_run):
    prm, sim = constant_run
    ph = Physics.build(sim.model, prm)
    mus, st = sim.muscles, sim.final_state
    k = FRAMES - 1  # the frame of the final state
    assert st.time == pytest.approx(k / 60.0)
    names = ph.model.muscles.names
    groups = [MUSCLE_GROUPS[g] for g in ph.muscle_group]
    assert mus.names == names and list(mus.groups) == groups
    # eq. (3)-(4): the step response of the filter from rest, M_bar = k_f S E
    area = np.array([prm.instance_area(n, g) for n, g in zip(names, groups, strict=True)])
    level = np.where(np.isin(groups, ["ZYG", "OOS"]), LEVEL, 0.0)
    m_hand = activation_response(st.time, prm.k_force * area * level, prm.tau_activation,
                                 prm.activation_damping)
    np.testing.assert_allclose(mus.activation[k], m_hand, rtol=1e-9, atol=1e-15)
    np.testing.assert_array_equal(mus.activation[k], st.muscle_force)
    np.testing.assert_allclose(mus.normalised_activation[k], level
                               * (1 - (1 + st.time / prm.tau_activation)
                                  * np.exp(-st.time / prm.tau_activation))
                               if prm.activation_damping == 1.0 else
                               activation_response(st.time, level, prm.tau_activation,
                                                   prm.activation_damping), rtol=1e-9)
    # lengths and velocities from the nodes of the stored state
    length, rate = hand_kinematics(ph, st.positions, st.velocities)
    np.testing.assert_allclose(mus.length[k], length, rtol=1e-12)
    np.testing.assert_allclose(mus.velocity[k], rate, rtol=1e-9, atol=1e-12)
    # eqs. (5)-(7) with the preset's constants
    f_hand = hand_tension(prm, groups, m_hand, length, ph.model.muscles.rest_length, rate)
    np.testing.assert_allclose(mus.force[k], f_hand, rtol=1e-9, atol=1e-12)
    active = level > 0
    assert np.all(mus.force[k][active] > 0.5 * m_hand[active])
    assert np.all(np.abs(mus.velocity[k][active]) > 0)  # the check sees a moving face
    # at rest (frame 0): the rest lengths, no motion, no force
    np.testing.assert_allclose(mus.length[0], ph.model.muscles.rest_length, rtol=1e-9)
    assert np.all(mus.velocity[0] == 0)
    np.testing.assert_allclose(mus.force[0], 0.0, atol=1e-12)


def test_outputs_from_a_list_of_states_equal_the_simulation(constant_run, tmp_path):
    """The generic path an inversion takes: its accepted states -> the same numbers, the same
    file variables."""
    prm, sim = constant_run
    model = face_model(sim.model, prm)
    ph = model.physics
    stepper = Stepper(model, integrator="implicit")
    states = [State.at_rest(ph.model.rest_positions, ph.n_muscles)]
    for a in sim.activity[:-1]:
        states.append(stepper.advance(states[-1], a, 0.0))
    s = muscle_series(ph, states)
    for attr in ("force", "length", "velocity", "activation"):
        np.testing.assert_array_equal(getattr(s, attr), getattr(sim.muscles, attr))
    bare = dataclasses.replace(sim, muscles=None)
    path = write_results(tmp_path / "inv.nc", bare, extra=muscle_output_variables(ph, states))
    back = results_muscles(read_results(path))
    np.testing.assert_array_equal(back.force, sim.muscles.force)
    assert back.names == sim.muscles.names


def test_results_round_trip_with_units(constant_run, tmp_path):
    prm, sim = constant_run
    ds = read_results(write_results(tmp_path / "r.nc", sim))
    units = {"muscle_force": "N", "muscle_length": "m", "muscle_velocity": "m/s",
             "muscle_activation": "N", "muscle_max_force": "N"}
    for var, unit in units.items():
        assert ds[var].attrs["units"] == unit
    assert ds["muscle_force"].dims == ("time", "muscle_instance")
    assert list(ds["muscle_instance"].values) == list(sim.muscles.names)
    assert list(ds["muscle_group"].values) == list(sim.muscles.groups)
    assert "OOS_R" in sim.muscles.names and "ZYG_L" in sim.muscles.names
    assert list(ds["muscle"].values) == list(MUSCLE_GROUPS)  # activity keeps its groups
    back = results_muscles(ds)
    for attr in ("force", "length", "velocity", "activation", "max_force"):
        np.testing.assert_array_equal(getattr(back, attr), getattr(sim.muscles, attr))
    # a file without muscle outputs (as written before they existed) still reads
    old = read_results(write_results(tmp_path / "old.nc", dataclasses.replace(sim, muscles=None)))
    assert "muscle_force" not in old and results_muscles(old) is None
    np.testing.assert_array_equal(old["positions"].values, ds["positions"].values)
