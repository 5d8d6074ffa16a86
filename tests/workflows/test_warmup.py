"""The kernels' warm-up: its stamp, and the line a first run prints when no warm-up was made."""

import json
import os

import pytest

from facemech import warmup
from facemech.cli import main


def test_the_stamp_says_when_a_warm_up_is_needed(tmp_path):
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    assert warmup.stamp_path(env) == tmp_path / "cache" / "facemech-kernels.json"
    assert warmup.needed(env)  # no stamp
    warmup._write_stamp(12.0, env)
    assert not warmup.needed(env)
    assert json.loads(warmup.stamp_path(env).read_text())["seconds"] == 12.0
    assert not warmup.needed({**env, "FACEMECH_WARMUP": "0"})
    warmup.stamp_path(env).write_text("{not json")
    assert warmup.needed(env)
    warmup.stamp_path(env).write_text(json.dumps({"fingerprint": "another"}))
    assert warmup.needed(env)


def test_the_fingerprint_follows_the_kernels_sources_only(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "kernel.py").write_text("import numba\n")
    (pkg / "plain.py").write_text("x = 1  # calls numba's kernels\n")
    first = warmup.fingerprint(pkg)
    assert warmup.fingerprint(pkg) == first
    (pkg / "plain.py").write_text("x = 22  # no numba import: the kernels stand\n")
    assert warmup.fingerprint(pkg) == first
    (pkg / "kernel.py").write_text("from numba import njit  # changed\n")
    assert warmup.fingerprint(pkg) != first


def test_a_first_run_says_it_compiles_and_how_long(monkeypatch, capsys, tmp_path):
    """No warm-up cached: the command says so, runs it with a count, and says how long it
    took, before its own work (here a results file that is missing: exit 2)."""
    calls = []

    def fake_warm_up(progress=None):
        for k in range(5):
            progress(warmup.STAGE, k, 4)
        calls.append(1)
        return 47.0

    monkeypatch.setattr(warmup, "needed", lambda *a, **k: True)
    monkeypatch.setattr(warmup, "warm_up", fake_warm_up)
    monkeypatch.setattr("sys.argv", ["facemech", "render", str(tmp_path / "none.nc"), "-o",
                                     str(tmp_path / "m.mp4")])
    with pytest.raises(SystemExit) as end:
        main()
    err = capsys.readouterr().err.splitlines()
    assert end.value.code == 2 and calls == [1]
    assert err[0] == (f"facemech: compiling the physics kernels once (about "
                      f"{warmup.TYPICAL_S} s)...")
    assert "facemech: physics kernels compiled in 47 s; later runs load them" in err
    assert any(ln.startswith("facemech: compile the kernels: 4/4, ") for ln in err), err
    assert "none.nc" in err[-1]


@pytest.mark.skipif(os.environ.get("FACEMECH_WARMUP") == "0", reason="warm-up turned off")
def test_after_the_warm_up_no_compile_is_needed():
    """The install step's warm-up (make) or any earlier run has left a valid stamp: a run
    in this checkout does not compile again. Skipped where no warm-up was made yet."""
    if not warmup.stamp_path().exists():
        pytest.skip("no warm-up in this checkout yet")
    assert not warmup.needed()
