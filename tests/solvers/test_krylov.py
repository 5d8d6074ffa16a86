"""Issue 27's step on the forces' true linearisation: GMRES iterations on the step about its
explicit predictor, the constant shared matrix their preconditioner
(``StepOptions.krylov_iterations``, :func:`facemech.solvers.krylov.krylov_step`)."""

from __future__ import annotations

import numpy as np
import pytest

from facemech import default_face
from facemech.errors import InputError
from facemech.params import MUSCLE_GROUPS, preset_pair
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate
from facemech.stepping import STEP_FIELDS

#: the step about its predictor with dashpots on the rate of stretch (a Kelvin-Voigt tissue)
KV = {"predictor": True, "implicit_stiffness_share": 0.75, "implicit_volume_scale": 3.0,
      "dashpot_isotropy": 0.0, "volume_floor": 0.5, "volume_floor_modulus": 1e6,
      "stiffening": 4.0}


def _path(face, params, group, landmark, frames=24):
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    act[:, MUSCLE_GROUPS.index(group)] = 1.0
    sim = simulate(face_model(face, params), act)
    return sim.positions[:, face.landmarks[landmark]]


@pytest.fixture(scope="module")
def lower_lip():
    """Under full DLI, the lower lip's path on the coarse face at 4 steps per frame with 0, 2
    and 4 iterations, and with 48 steps per frame and none."""
    face = default_face("default-coarse")
    p = preset_pair("anatomical").with_(**KV)
    paths = {k: _path(face, p.with_(krylov_iterations=k), "DLI", "lower_lip_center")
             for k in (0, 2, 4)}
    paths["fine"] = _path(face, p.with_(substeps=48), "DLI", "lower_lip_center")
    return paths


def _off(a, b):
    return float(np.abs(a - b).max())


@pytest.mark.slow
def test_the_iterations_converge_on_the_true_linearisation(lower_lip):
    """The constant matrix's excess stiffness acts on its step as inertia: without iterations
    the lower lip's path is millimetres from the path of the step solved with 4 iterations (the
    same step size); two iterations take out three quarters of that (measured: 5.1 and 1.35
    mm at worst)."""
    plain = _off(lower_lip[0], lower_lip[4])
    assert plain > 3e-3
    assert _off(lower_lip[2], lower_lip[4]) < 0.4 * plain


@pytest.mark.slow
def test_the_solved_step_follows_the_fine_steps(lower_lip):
    """And the 4-step path solved so lies closer to the 48-step path than the constant matrix's
    alone (measured: 1.28 and 4.85 mm at worst; what is left is backward Euler's own error at
    4.2-ms steps, and the fine step's added inertia, 12 times smaller)."""
    assert _off(lower_lip[4], lower_lip["fine"]) < 0.4 * _off(lower_lip[0], lower_lip["fine"])


def test_krylov_iterations_need_the_predictor():
    with pytest.raises(InputError, match="krylov_iterations"):
        preset_pair("anatomical").with_(krylov_iterations=2)
    with pytest.raises(InputError, match="krylov_iterations"):
        preset_pair("anatomical").with_(**KV, krylov_iterations=-1)
    assert preset_pair("anatomical").with_(**KV, krylov_iterations=2).steps.krylov_iterations == 2


def test_a_drag_on_the_mass_stops_the_released_lip_ringing():
    """Without the matrix's added inertia a drag proportional to the mass acts (with it, the
    inertia was 200 times the mass's and the drag did nothing measurable): the lower lip
    released after a 100-ms full DLI pulse overshoots its rest by a fifth without the drag, by
    nothing with 200 s^-1, while the step of full DLI keeps its rise within 10 % (measured on
    the coarse face: 20.7 % and 0; 247 and 257 ms)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    import speed as S  # benchmarks/speed.py: the measures of the speed table

    face = default_face("default-coarse")
    got = {}
    for drag in (0.0, 200.0):
        p = preset_pair("anatomical").with_(**KV, krylov_iterations=4, mass_drag=drag)
        got[drag] = (S.overshoot(face, p, ("DLI",), "lower_lip_center", 1, 0.8),
                     S.measure(face, p, ("DLI",), "lower_lip_center", 1, 0.8)["rise_ms"])
    assert got[0.0][0] > 0.1 and got[200.0][0] < 0.02
    assert got[200.0][1] < 1.1 * got[0.0][1]


def test_the_mass_drag_needs_the_linearly_implicit_step():
    with pytest.raises(InputError, match="mass_drag"):
        preset_pair("lucero1999").with_(mass_drag=50.0)
    with pytest.raises(InputError, match="mass_drag"):
        preset_pair("anatomical").with_(integrator="rosenbrock", mass_drag=50.0)
    with pytest.raises(InputError, match="mass_drag"):
        preset_pair("anatomical").with_(mass_drag=-1.0)


def test_the_fast_lips_preset_file_is_the_measured_step():
    """benchmarks/presets/fast-lips.json, the preset file of docs/model.md's measurements of
    visible speech on the step solved on its tangent, reads as the anatomical preset with the
    step the speed table measured (4 iterations, the mass drag 200 s^-1, the correction within
    60 mm of the mouth)."""
    from pathlib import Path

    p = preset_pair(str(Path(__file__).resolve().parents[2] / "benchmarks" / "presets"
                        / "fast-lips.json"))
    want = preset_pair("anatomical").with_(**KV, krylov_iterations=4, mass_drag=200.0,
                                           krylov_region=0.060)

    def value(pair, field):
        return getattr(pair.steps if field in STEP_FIELDS else pair.params, field)

    for field in (*KV, "krylov_iterations", "mass_drag", "krylov_region", "fv_vmax",
                  "tau_activation", "k_force", "substeps"):
        assert value(p, field) == pytest.approx(value(want, field), rel=1e-12), field
