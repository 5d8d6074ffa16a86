"""One model made once (``facemech.model``): the preset's tissue applied and the physics built
there and nowhere below; the method apart from the constants (``StepOptions``); any object of
the ``Solver`` protocol steps it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

import facemech as fm
from facemech.geometry import builder
from facemech.params import MUSCLE_GROUPS, preset, preset_pair, preset_steps
from facemech.physics.assembly import Physics
from facemech.solvers.explicit import ExplicitEuler
from facemech.solvers.solver_state import Solver
from facemech.solvers.step import Stepper
from facemech.stepping import PRESET_STEPS, STEP_FIELDS, StepOptions


@pytest.fixture(scope="module")
def seeds():
    return fm.model("default-coarse", "lucero1999")


def test_the_model_holds_the_face_in_its_presets_tissue(seeds):
    anatomical_face = builder.default_face("default-coarse", tissue="anatomical")
    m = fm.model(anatomical_face, "lucero1999")
    assert m.face.tissue == "uniform" and m.params.name == "lucero1999"
    assert m.physics.model is m.face and m.physics.params is m.params
    assert m.steps == PRESET_STEPS["lucero1999"] == StepOptions()
    assert seeds.face.tissue == "uniform"


def test_overrides_go_to_the_constants_or_to_the_method():
    m = fm.model("default-coarse", "anatomical", substeps=8, k_force=1e5)
    assert m.steps.substeps == 8 and m.params.k_force == 1e5
    assert m.steps.integrator == "implicit" and m.steps.implicit_contacts
    p = preset_pair("anatomical").with_(substeps=8, k_force=1e5)
    assert p.steps == m.steps and p.params == m.params
    with pytest.raises(fm.InputError) as info:
        fm.model("default-coarse", "anatomical", substeps=0)
    assert info.value.field == "substeps"


def test_nothing_below_the_model_rebuilds_the_physics_or_the_tissue(seeds, monkeypatch):
    import sys

    builds, rebuilds = [], []
    monkeypatch.setattr(Physics, "build", classmethod(lambda cls, *a: builds.append(a)))
    for name, module in list(sys.modules.items()):  # every module that holds for_tissue
        if name.startswith("facemech") and hasattr(module, "for_tissue"):
            monkeypatch.setattr(module, "for_tissue", lambda *a: rebuilds.append(a))
    act = np.zeros((3, len(MUSCLE_GROUPS)))
    act[:, MUSCLE_GROUPS.index("OOS")] = 0.5
    sim = fm.simulate(seeds, act, np.radians([0.0, 2.0, 4.0]))
    assert sim.model is seeds.face and sim.params is seeds.params
    assert builds == [] and rebuilds == []
    with pytest.raises(TypeError, match="Model"):
        fm.simulate(seeds.face, act)


def test_the_constants_hold_no_numerical_method():
    from dataclasses import fields

    assert not {f.name for f in fields(fm.Parameters)} & STEP_FIELDS
    assert preset_steps("anatomical").integrator == "implicit"
    assert preset_steps("pitermann2001").fast_dt == preset_steps("calibrated").fast_dt == 0.33e-3
    assert preset("anatomical").is_continuum


@dataclass(frozen=True)
class HalfSteps:
    """A new integrator in a few lines: explicit Euler at half the preset's step."""

    dt: float
    name: ClassVar[str] = "half-euler"

    def init(self, physics):
        return ExplicitEuler(self.dt / 2).init(physics)

    def step(self, solver_state, state, controls):
        return ExplicitEuler(self.dt / 2).step(solver_state, state, controls)


def test_any_object_of_the_solver_protocol_steps_the_model(seeds):
    solver = HalfSteps(seeds.steps.dt)
    assert isinstance(solver, Solver) and not isinstance("euler", Solver)
    half = Stepper(seeds, integrator=solver)
    plain = Stepper(seeds, integrator=ExplicitEuler(seeds.steps.dt / 2))
    assert half.integrator == "half-euler" and half.n_steps == plain.n_steps == 101
    state = fm.State.at_rest(seeds.face.rest_positions, seeds.physics.n_muscles)
    act = np.zeros(len(MUSCLE_GROUPS))
    act[MUSCLE_GROUPS.index("ZYG")] = 0.6
    a, b = half.advance(state, act, 0.02), plain.advance(state, act, 0.02)
    np.testing.assert_array_equal(a.positions, b.positions)
    assert np.abs(a.positions - state.positions).max() > 1e-6
