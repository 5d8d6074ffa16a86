"""``facemech batch`` interrupted (issue 58): SIGTERM, and Ctrl-C (SIGINT to the whole process
group, as a terminal sends it), while an item runs that would not end for a long time. The
command ends with one line, ``facemech: interrupted``, exit 130 or 143, no traceback (none from
multiprocessing's resource tracker either), no worker left; the finished items are kept and a
rerun skips them; an output folder the batch made and filled with nothing is not left."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import facemech
from facemech.batch.records import DONE

pytest.importorskip("distributed")
SRC = str(Path(facemech.__file__).parents[1])


def _manifest(folder: Path, frames=(10, 60_000)) -> Path:
    """s0: a short simulate item; s1: one that runs for many minutes (``frames`` each)."""
    rows = ["id,job,activity,integrator"]
    for k, n in enumerate(frames):
        (folder / f"act{k}.csv").write_text("time,OOS\n" + "".join(
            f"{i / 60:.6f},0.2\n" for i in range(n)))
        rows.append(f"s{k},simulate,act{k}.csv,implicit")
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    return folder / "manifest.csv"


def _interrupted(folder: Path, sig: int, *, group: bool, when) -> subprocess.CompletedProcess:
    """Run ``facemech batch`` in its own session; when ``when()`` holds, send ``sig`` (to the
    process group, or to the command alone); return the finished run, its session checked
    empty of processes."""
    env = dict(os.environ, PYTHONPATH=SRC, FACEMECH_THREADS="1", OPENBLAS_NUM_THREADS="1")
    proc = subprocess.Popen([sys.executable, "-m", "facemech", "batch", "manifest.csv", "-o",
                             "out", "--workers", "2"], cwd=folder, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        while not when():
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the batch did not get there"
            time.sleep(0.1)
        (os.killpg if group else os.kill)(proc.pid, sig)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    # the resource tracker ends once the command has (it then releases the semaphores)
    deadline = time.monotonic() + 10
    while True:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        if time.monotonic() > deadline:
            os.killpg(proc.pid, signal.SIGKILL)
            pytest.fail("a process of the batch outlived it")
        time.sleep(0.1)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _one_line(run: subprocess.CompletedProcess) -> None:
    lines = [ln for ln in run.stderr.splitlines() if "still working" not in ln
             and not ln.startswith("facemech: [")]  # the heartbeat and the finished items
    assert lines == ["facemech: interrupted"], run.stderr
    assert "Traceback" not in run.stderr and "KeyError" not in run.stderr


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_items_and_a_rerun_resumes(tmp_path):
    """Ctrl-C: SIGINT to the command and its workers alike, s0 finished, s1 running."""
    from facemech.workflows.batch import run_batch

    manifest = _manifest(tmp_path)
    out = tmp_path / "out"
    run = _interrupted(tmp_path, signal.SIGINT, group=True,
                       when=lambda: (out / "s0" / DONE).is_file())
    assert run.returncode == 130, run.stderr
    _one_line(run)
    assert sorted(p.name for p in out.iterdir()) == ["s0"]  # no .partial-s1-*, no summary
    made = (out / "s0" / DONE).stat().st_mtime_ns
    _manifest(tmp_path, frames=(10, 10))  # s1 made short: s0 is skipped, s1 made
    rep = run_batch(manifest, out, workers=1, processes=False)
    assert {o.id: o.status for o in rep.outcomes} == {"s0": "skipped", "s1": "done"}
    assert (out / "s0" / DONE).stat().st_mtime_ns == made


def test_sigterm_before_any_item_is_finished_leaves_no_folder(tmp_path):
    """SIGTERM to the command alone while both items run (never-ending ones)."""
    _manifest(tmp_path, frames=(60_000, 60_000))
    out = tmp_path / "out"
    started = time.monotonic()
    run = _interrupted(tmp_path, signal.SIGTERM, group=False,
                       when=lambda: any(out.glob(".partial-*"))
                       or time.monotonic() - started > 20)
    assert run.returncode == 143, run.stderr
    _one_line(run)
    assert not out.exists()
