"""Issue 31: SIGTERM and SIGINT remove every temporary file and folder (an export's meshes, a
render's frames, a batch's ``.partial-*`` folders and workers) and print one line, nothing else.
Each case runs in a child interpreter that interrupts itself."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import facemech

SRC = str(Path(facemech.__file__).parents[1])


def _run(script: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=SRC, FACEMECH_THREADS="1", OPENBLAS_NUM_THREADS="1",
               MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120,
                          stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_an_interrupted_export_leaves_no_temporary_folder(tmp_path, sig):
    script = f"""
        import os, sys
        import numpy as np, xarray as xr
        import facemech.io.export as ex
        from facemech.cli import main

        pos = np.zeros((6, 3, 3)); pos[:, 1, 0] = 0.03; pos[:, 2, 1] = 0.03
        xr.Dataset({{"positions": (("time", "node", "axis"), pos),
                    "markers": (("time", "marker", "axis"), pos[:, :1]),
                    "triangles": (("triangle", "corner"), np.array([[0, 1, 2]]))}},
                   coords={{"marker": ["A"], "axis": list("xyz")}},
                   attrs={{"frame_rate_hz": 60.0}}).to_netcdf("r.nc", engine="h5netcdf")
        real, calls = ex._obj_text, []

        def interrupted(*args):
            calls.append(1)
            if len(calls) == 3:
                os.kill(os.getpid(), {int(sig)})
            return real(*args)

        ex._obj_text = interrupted
        sys.argv = ["facemech", "export", "r.nc", "-o", "frames", "--format", "obj"]
        main()
    """
    run = _run(script, tmp_path)
    assert run.returncode == 128 + int(sig), run.stderr
    assert run.stderr == "facemech: interrupted\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.nc"]


def test_an_interrupted_batch_leaves_no_partial_folder_worker_or_warning(tmp_path):
    script = """
        import multiprocessing as mp, os, signal, time
        from pathlib import Path
        from facemech import interrupts
        from facemech.batch.records import new_partial
        from facemech.workflows.batch import _quiet_resource_tracker, _stop_workers

        if __name__ == "__main__":
            interrupts.install()
            out = Path("out")
            _quiet_resource_tracker()
            ctx = mp.get_context("spawn")
            lock = ctx.Lock()  # a semaphore the tracker would call leaked
            worker = ctx.Process(target=time.sleep, args=(60,))
            worker.start()
            Path("worker.pid").write_text(str(worker.pid))
            (new_partial(out, "s1") / "half.nc").write_text("half")
            interrupts.on_interrupt(lambda: _stop_workers(out, [], False))
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(30)
    """
    (tmp_path / "main.py").write_text(textwrap.dedent(script))
    env = dict(os.environ, PYTHONPATH=SRC)
    run = subprocess.run([sys.executable, "main.py"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode == 143, run.stderr
    assert run.stderr == "facemech: interrupted\n"
    assert [p.name for p in (tmp_path / "out").iterdir()] == []
    pid = int((tmp_path / "worker.pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
