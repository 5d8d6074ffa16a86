"""An inversion's step-response columns shared between processes: the same numbers as one
process, whatever the count; a column's error reaches the caller; the count's setting."""

import numpy as np
import pytest

from facemech import InputError
from facemech.inverse.columns import column_workers, map_columns
from facemech.inverse.invert import control_matrix
from facemech.inverse.uncertainty import step_responses
from facemech.params import Parameters
from facemech.physics.model import model as face_model
from facemech.physics.threads import get_threads
from facemech.solvers.state import State
from facemech.solvers.step import Stepper


def test_columns_in_order_and_a_copys_error_raised_here():
    assert map_columns(lambda j: j * j, 7, workers=3) == [j * j for j in range(7)]
    assert map_columns(lambda j: j, 0, workers=2) == []

    def bad(j):
        if j == 4:  # in the forked copy's share
            raise ValueError("column 4 cannot be computed")
        return j

    with pytest.raises(ValueError, match="column 4"):
        map_columns(bad, 5, workers=2)
    # the kernels' thread count is given back
    before = get_threads()
    map_columns(lambda j: get_threads(), 2, workers=2)
    assert get_threads() == before
    assert map_columns(lambda j: get_threads(), 3, workers=2) == [1, 1, 1]


def test_worker_count_from_the_environment():
    assert column_workers({"FACEMECH_WORKERS": "3"}) == 3
    assert 1 <= column_workers({}) <= 2
    for bad in ("0", "two", "-1", "65"):
        with pytest.raises(InputError, match="FACEMECH_WORKERS") as err:
            column_workers({"FACEMECH_WORKERS": bad})
        assert err.value.field == "FACEMECH_WORKERS"


def test_step_responses_the_same_on_one_and_two_processes(seeds_face, monkeypatch):
    face = seeds_face
    st = Stepper(face_model(face, Parameters()), integrator="euler", dt=1e-3)
    _, g = control_matrix(["DLI", "OOS", "LLS"])
    rest = State.at_rest(face.rest_positions, st.physics.n_muscles)
    nodes = np.array([face.landmarks["lower_lip_center"], face.landmarks["upper_lip_center"]])

    def advance(s, c):
        return st.advance(s, g @ c, 0.0)

    got = {}
    for w in ("1", "2"):
        monkeypatch.setenv("FACEMECH_WORKERS", w)
        got[w] = step_responses(advance, rest, nodes, 3, frames=3)
    np.testing.assert_array_equal(got["1"], got["2"])
    # every column moves the lips (mm per unit, after 3 ms: 0.01-0.04)
    assert np.all(np.abs(got["1"]).max(axis=0) > 5e-3)


def test_a_bad_worker_count_refused_before_a_command_runs(tmp_path):
    import os
    import subprocess
    import sys

    out = tmp_path / "out.nc"
    env = dict(os.environ, FACEMECH_WORKERS="zero", FACEMECH_WARMUP="0")
    run = subprocess.run([sys.executable, "-m", "facemech", "simulate", "-o", str(out)],
                         env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert "FACEMECH_WORKERS" in run.stderr and "Traceback" not in run.stderr
    assert not out.exists()
