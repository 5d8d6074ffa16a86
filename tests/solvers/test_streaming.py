"""Streaming long runs to the results file (issue 18): the streamed file reads exactly as the one
written in memory, blocks follow each other, and a failed run leaves nothing behind."""

from __future__ import annotations

import numpy as np
import pytest

from facemech import simulate
from facemech.demo import utterance
from facemech.errors import InputError
from facemech.io.results import read_results, write_results
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate_blocks
from facemech.workflows.simulate import simulate_to_file

FRAMES = 40


@pytest.fixture(scope="module")
def controls():
    """40 frames of the demo utterance from its first closure: the lips and the jaw move."""
    _, act, jaw = utterance()
    return act[10:10 + FRAMES], jaw[10:10 + FRAMES]


@pytest.fixture(scope="module")
def in_memory(face, controls, tmp_path_factory):
    """The in-memory run and its results file, written by write_results."""
    sim = simulate(face_model(face), *controls)
    path = tmp_path_factory.mktemp("mem") / "r.nc"
    write_results(path, sim, inputs={"activity": "0123456789abcdef"})
    return sim, path


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    if a.dtype == object or b.dtype == object:
        return a.shape == b.shape and [str(v) for v in a.ravel()] == [str(v) for v in b.ravel()]
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("block", [13, 600])
def test_streamed_file_reads_exactly_as_the_in_memory_one(face, controls, in_memory, tmp_path,
                                                          block):
    _, mem_path = in_memory
    out = tmp_path / "s.nc"
    run = simulate_to_file(out, face_model(face), *controls,
                           inputs={"activity": "0123456789abcdef"},
                           block_frames=block)
    mem, streamed = read_results(mem_path), read_results(out)
    assert list(streamed.variables) == list(mem.variables)
    assert dict(streamed.sizes) == dict(mem.sizes)
    assert streamed.sizes["time"] == FRAMES == len(run.time)
    for name in mem.variables:
        assert streamed[name].dims == mem[name].dims, name
        assert streamed[name].attrs == mem[name].attrs, name
        assert _same_array(streamed[name].values, mem[name].values), name
    # every attribute equal but the wall-clock time, which is each run's own
    wall = "wall_seconds"
    assert {k: v for k, v in streamed.attrs.items() if k != wall} == \
        {k: v for k, v in mem.attrs.items() if k != wall}
    assert streamed.attrs[wall] > 0 and mem.attrs[wall] > 0
    assert "time" in streamed.encoding["unlimited_dims"]  # extendable: frames were appended


def test_blocks_follow_each_other_and_make_the_in_memory_run(face, controls, in_memory):
    sim, _ = in_memory
    blocks = []
    run = simulate_blocks(face_model(face), *controls, sink=blocks.append, block_frames=13)
    assert [len(b.time) for b in blocks] == [13, 13, 13, 1]
    assert [round(b.time[0] * 60) for b in blocks] == [0, 13, 26, 39]
    for name in ("time", "positions", "markers", "activity", "jaw_angle", "jaw_shift"):
        joined = np.concatenate([getattr(b, name) for b in blocks])
        assert joined.tobytes() == getattr(sim, name).tobytes(), name
    force = np.concatenate([b.muscles.force for b in blocks])
    assert force.tobytes() == sim.muscles.force.tobytes()
    assert run.final_state.positions.tobytes() == sim.final_state.positions.tobytes()
    assert run.integrator == sim.integrator and run.dt == sim.dt


def test_failed_run_leaves_no_file_and_keeps_the_old_one(face, controls, tmp_path):
    out = tmp_path / "r.nc"

    def stop(done, total):
        if done == 30:  # two blocks already in the temporary file
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        simulate_to_file(out, face_model(face), *controls, block_frames=13, progress=stop)
    assert list(tmp_path.iterdir()) == []  # neither the output nor a temporary file
    out.write_text("an earlier result")
    with pytest.raises(RuntimeError, match="boom"):
        simulate_to_file(out, face_model(face), *controls, block_frames=13,
                         progress=lambda d, t: (_ for _ in ()).throw(RuntimeError("boom"))
                         if d == 20 else None)
    assert list(tmp_path.iterdir()) == [out] and out.read_text() == "an earlier result"


def test_block_size_must_be_positive(face, controls, tmp_path):
    with pytest.raises(InputError, match="block_frames") as e:
        simulate_to_file(tmp_path / "r.nc", face_model(face), *controls, block_frames=0)
    assert e.value.field == "block_frames"
    assert list(tmp_path.iterdir()) == []
