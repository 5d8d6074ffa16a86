"""facemech batch: manifests checked before anything runs, items run on dask, a failing item
reported while the others finish, reruns that skip finished items, a killed batch resumed."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from facemech.batch.records import DONE, read_done
from facemech.errors import InputError
from facemech.workflows import batch as wb
from facemech.workflows import batch_jobs as jobs
from facemech.workflows.batch_jobs import read_manifest


def write_activity(path: Path, level: float, frames: int = 10) -> Path:
    """An activity CSV: OOS at ``level`` for ``frames`` 60-Hz frames."""
    lines = ["time,OOS"] + [f"{k / 60:.6f},{level}" for k in range(frames)]
    path.write_text("\n".join(lines) + "\n")
    return path


def corpus(folder: Path, levels=(0.2, 0.4, 0.6), frames: int = 10) -> Path:
    """A manifest of simulate items s0, s1, ... over activity files in ``folder``."""
    rows = ["id,job,activity,integrator"]
    for k, level in enumerate(levels):
        write_activity(folder / f"act{k}.csv", level, frames)
        rows.append(f"s{k},simulate,act{k}.csv,implicit")
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    return folder / "manifest.csv"


def summary(out: Path) -> dict[str, dict]:
    with open(out / "summary.csv", newline="") as fh:
        return {r["id"]: r for r in csv.DictReader(fh)}


def mtimes(out: Path) -> dict[str, int]:
    return {p.parent.name: p.stat().st_mtime_ns for p in out.glob(f"*/{DONE}")}


@pytest.fixture(scope="module")
def client():
    """Two worker threads in this process: the fastest dask cluster to start."""
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as c:
        yield c


# ---- the manifest ----------------------------------------------------------------------------
def _error(tmp_path, text: str, name: str = "m.csv") -> InputError:
    (tmp_path / name).write_text(text)
    with pytest.raises(InputError) as info:
        read_manifest(tmp_path / name)
    assert info.value.source == str(tmp_path / name)
    return info.value


def test_manifest_errors_name_the_file_row_and_field(tmp_path):
    write_activity(tmp_path / "a.csv", 0.3)
    e = _error(tmp_path, "id,activity\ns0,a.csv\n")
    assert e.field == "job" and "no 'job' column" in e.message
    e = _error(tmp_path, "id,job,activity\ns0,simulate,a.csv\ns1,simulat,a.csv\n")
    assert e.field == "job" and "row 2" in e.message and "'simulat'" in e.message
    e = _error(tmp_path, "id,job,activity\ns0,simulate,a.csv\ns1,simulate,gone.csv\n")
    assert e.field == "activity" and "row 2" in e.message and "gone.csv" in e.message
    e = _error(tmp_path, "id,job,markers\ns0,simulate,a.csv\n")
    assert e.field == "markers" and "row 1" in e.message and "not an option" in e.message
    e = _error(tmp_path, "id,job,activity,substeps\ns0,simulate,a.csv,2.5\n")
    assert e.field == "substeps" and "integer" in e.message
    e = _error(tmp_path, "id,job,preset\ns0,simulate,anatomical\n")
    assert e.field == "activity" and "needs activity or emg" in e.message
    e = _error(tmp_path, "id,job,activity\ns0,simulate,a.csv\ns0,simulate,a.csv\n")
    assert e.field == "id" and "row 2" in e.message and "row 1" in e.message
    e = _error(tmp_path, "id,job,activity\n../x,simulate,a.csv\n")
    assert e.field == "id"
    e = _error(tmp_path, '[[item]]\nid = "r"\njob = "regions"\nfiles = "utt*.csv"\n', "m.toml")
    assert e.field == "files" and "no file matches" in e.message
    with pytest.raises(InputError) as info:
        wb.run_batch(tmp_path / "m.csv", tmp_path / "out", workers=2, scheduler="tcp://x:1")
    assert info.value.field == "workers"
    (tmp_path / "m.csv").write_text("id,job,activity\ns0,simulate,a.csv\n")
    with pytest.raises(InputError) as info:
        wb.run_batch(tmp_path / "m.csv", tmp_path / "a.csv", workers=1)  # -o is an input
    assert info.value.field == "-o" and not (tmp_path / "summary.csv").exists()
    e = _error(tmp_path, '[defaults]\nwindoww = 3\n[[item]]\nid = "a"\njob = "invert"\n',
               "m.toml")
    assert e.field == "defaults.windoww"


def test_manifest_keys_follow_content_and_settings(tmp_path):
    write_activity(tmp_path / "a.csv", 0.3)
    write_activity(tmp_path / "copy.csv", 0.3)  # same bytes, another name
    write_activity(tmp_path / "other.csv", 0.5)
    for k in range(3):
        write_activity(tmp_path / f"utt{k}.csv", 0.1)
    (tmp_path / "m.csv").write_text(
        "id,job,activity,substeps,bite-block,files,k\n"
        "a,simulate,a.csv,4,yes,,\n"
        "b,simulate,copy.csv,4,true,,\n"
        "c,simulate,other.csv,4,yes,,\n"
        "d,simulate,a.csv,5,yes,,\n"
        "r,regions,,,,utt*.csv,2\n")
    (tmp_path / "m.toml").write_text(
        '[defaults]\nsubsteps = 4\nbite_block = true\nk = 2\n'
        '[[item]]\nid = "a"\njob = "simulate"\nactivity = "a.csv"\n'
        '[[item]]\nid = "r"\njob = "regions"\nfiles = ["utt0.csv", "utt1.csv", "utt2.csv"]\n')
    a, b, c, d, r = read_manifest(tmp_path / "m.csv")
    assert a.options == {"activity": str(tmp_path.resolve() / "a.csv"), "substeps": 4,
                         "bite_block": True}
    assert a.settings == {"substeps": 4, "bite_block": True}
    assert a.key == b.key  # the content counts, not the file's name
    assert len({a.key, c.key, d.key}) == 3
    assert r.options["files"] == [str(tmp_path.resolve() / f"utt{k}.csv") for k in range(3)]
    assert len(set(r.inputs["files"])) == 1 and len(r.inputs["files"]) == 3
    ta, tr = read_manifest(tmp_path / "m.toml")
    assert (ta.key, tr.key) == (a.key, r.key)  # CSV and TOML say the same thing


# ---- running ---------------------------------------------------------------------------------
def test_corrupt_item_fails_and_the_others_finish(tmp_path, client):
    manifest = corpus(tmp_path)
    (tmp_path / "act1.csv").write_text("time,OOS\n0.0,0.2\n0.0166,abc\n")  # corrupt
    seen = []
    rep = wb.run_batch(manifest, tmp_path / "out", client=client,
                       on_item=lambda o, n, total: seen.append((o.id, o.status, n, total)))
    assert rep.exit_code == 1
    assert {s[0]: s[1] for s in seen} == {"s0": "done", "s1": "failed", "s2": "done"}
    assert [s[2:] for s in seen] == [(1, 3), (2, 3), (3, 3)]
    rows = summary(tmp_path / "out")
    assert [rows[i]["status"] for i in ("s0", "s1", "s2")] == ["done", "failed", "done"]
    assert "act1.csv" in rows["s1"]["error"] and "'OOS'" in rows["s1"]["error"]
    assert "\n" not in rows["s1"]["error"]
    assert rows["s0"]["frames"] == "10" and float(rows["s0"]["wall_s"]) > 0
    assert not (tmp_path / "out" / "s1").exists()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["s0", "s2", "summary.csv"]
    from facemech.io.results import read_results

    ds0, ds2 = (read_results(tmp_path / "out" / f"s{k}" / "result.nc") for k in (0, 2))
    assert ds0.sizes["time"] == 10 and ds2.sizes["time"] == 10
    assert ds0.activity.sel(muscle="OOS").values == pytest.approx(0.2)
    assert ds2.activity.sel(muscle="OOS").values == pytest.approx(0.6)
    rec = read_done(tmp_path / "out" / "s0")
    assert rec["files"] == ["result.nc"] and rec["numbers"]["frames"] == 10
    assert rec["key"] == read_manifest(manifest)[0].key
    lines, errors = wb.report(rep)
    assert "2 done, 0 unchanged, 1 failed" in lines[0]
    assert errors == [f"error: s1: {rows['s1']['error']}"]


def test_rerun_skips_unchanged_items_and_redoes_a_changed_one(tmp_path, client, monkeypatch):
    manifest = corpus(tmp_path)
    out = tmp_path / "out"
    assert wb.run_batch(manifest, out, client=client).exit_code == 0
    before = mtimes(out)
    assert sorted(before) == ["s0", "s1", "s2"]

    def no_cluster(*args, **kw):
        raise AssertionError("a rerun with nothing changed started a cluster")

    monkeypatch.setattr(wb, "_connect", no_cluster)
    t0 = time.perf_counter()
    rep = wb.run_batch(manifest, out, workers=2)  # would start a cluster if anything ran
    assert time.perf_counter() - t0 < 5.0
    assert [o.status for o in rep.outcomes] == ["skipped"] * 3
    assert mtimes(out) == before
    assert [r["status"] for r in summary(out).values()] == ["skipped"] * 3
    assert summary(out)["s0"]["frames"] == "10"  # the numbers come from the done-record

    write_activity(tmp_path / "act2.csv", 0.8)  # a changed input
    rep = wb.run_batch(manifest, out, client=client)
    assert [o.status for o in rep.outcomes] == ["skipped", "skipped", "done"]
    after = mtimes(out)
    assert (after["s0"], after["s1"]) == (before["s0"], before["s1"])
    assert after["s2"] != before["s2"]
    from facemech.io.results import read_results

    ds = read_results(out / "s2" / "result.nc")
    assert ds.activity.sel(muscle="OOS").values == pytest.approx(0.8)
    assert sorted(p.name for p in out.iterdir()) == ["s0", "s1", "s2", "summary.csv"]


def test_any_exception_is_one_line_and_the_batch_goes_on(tmp_path, client, monkeypatch):
    manifest = corpus(tmp_path, levels=(0.2, 0.4))

    def fake(o, folder):
        if o["activity"].endswith("act1.csv"):
            return {"x": 1} / 2  # a bug in a job
        (folder / "result.nc").write_text("fake")
        return {"frames": 3}, ["made"]

    monkeypatch.setitem(jobs.JOBS, "simulate", jobs.Job(jobs.JOBS["simulate"].options,
                                                        (("activity",),), fake))
    rep = wb.run_batch(manifest, tmp_path / "out", client=client)
    s0, s1 = rep.outcomes
    assert (s0.status, s0.numbers) == ("done", {"frames": 3})
    assert s1.status == "failed" and s1.error.startswith("TypeError: unsupported operand")
    assert "test_batch.py" in s1.error
    assert read_done(tmp_path / "out" / "s0")["report"] == ["made"]


_RUNNER = """
import sys
from facemech.workflows.batch import run_batch
run_batch(sys.argv[1], sys.argv[2], workers=1, processes=False)
"""


def test_killed_batch_resumes_without_redoing_finished_items(tmp_path, client):
    manifest = corpus(tmp_path, levels=(0.1, 0.2, 0.3, 0.4), frames=20)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    proc = subprocess.Popen([sys.executable, "-c", _RUNNER, str(manifest), str(out)],
                            start_new_session=True, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list(out.glob(f"*/{DONE}")):
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the batch and its workers, mid-batch
        proc.wait()
    before = mtimes(out)
    assert 1 <= len(before) < 4
    assert not (out / "summary.csv").exists()
    rep = wb.run_batch(manifest, out, client=client)
    status = {o.id: o.status for o in rep.outcomes}
    assert {i for i, s in status.items() if s == "skipped"} == set(before)
    assert {i for i, s in status.items() if s == "done"} == set(status) - set(before)
    after = mtimes(out)
    assert all(after[i] == before[i] for i in before)  # nothing done twice
    assert sorted(after) == [f"s{k}" for k in range(4)]  # nothing lost
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no partial folders
    frames = [json.loads((out / f"s{k}" / DONE).read_text())["numbers"]["frames"]
              for k in range(4)]
    assert frames == [20] * 4
    assert np.all([r["status"] in ("done", "skipped") for r in summary(out).values()])
