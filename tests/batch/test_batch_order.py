"""facemech batch hands out the largest items first (a module of its own: its one-worker cluster
must not overlap test_batch's, whose client is dask's default while that module runs)."""

from __future__ import annotations

from facemech.workflows import batch as wb
from facemech.workflows.batch_jobs import read_manifest
from test_batch import write_activity


def test_largest_items_run_first(tmp_path):
    """Items are handed out largest input first (ties in the manifest's order): on one worker
    the 12-frame item finishes first, then the 8-frame ones in their order, the 4-frame last."""
    import logging

    from distributed import Client, LocalCluster

    rows = ["id,job,activity,integrator"]
    for k, frames in enumerate((4, 12, 8, 8)):
        write_activity(tmp_path / f"act{k}.csv", 0.3, frames)
        rows.append(f"s{k},simulate,act{k}.csv,implicit")
    (tmp_path / "manifest.csv").write_text("\n".join(rows) + "\n")
    assert wb._input_bytes(read_manifest(tmp_path / "manifest.csv")[1]) == \
        (tmp_path / "act1.csv").stat().st_size
    seen = []
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as c:
        rep = wb.run_batch(tmp_path / "manifest.csv", tmp_path / "out", client=c,
                           on_item=lambda o, n, total: seen.append(o.id))
    assert rep.exit_code == 0
    assert seen == ["s1", "s2", "s3", "s0"]
