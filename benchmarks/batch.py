"""Batch benchmark (prints JSON): a corpus of short inversions run by ``facemech batch`` on a
local dask cluster of 2 worker processes against 1.

Six synthetic utterances (``--frames`` frames each, by default 120: 2 s, a sentence; windows of
the demo's controls, simulated on the built-in face from rest) are written as marker CSVs with
a manifest of ``invert`` items.
The batch is run twice into fresh folders, with 1 and with 2 workers; each wall time includes
the cluster's start and the workers' imports, as a user sees it. ``speedup`` is the 1-worker
wall time over the 2-worker one (target >= 1.7 on 2 free cores). ``cpu_share`` is the items'
CPU seconds over wall seconds times workers: near 1 when each worker had a core to itself; far
below 1 the machine was shared (compare ``load_average_before`` with ``cores``) and the
speedup measures the other load more than the batch.

Usage: python benchmarks/batch.py [--utterances 6] [--frames 120] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from facemech.physics.model import model as face_model

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def make_corpus(folder: Path, utterances: int, frames: int) -> Path:
    """Marker CSVs of ``utterances`` synthetic utterances and their manifest."""
    from facemech import MarkerSet, default_face, simulate
    from facemech.demo import utterance
    from facemech.io.markers import write_markers

    face = default_face()
    _, act, jaw = utterance()
    step = max(1, (len(act) - frames) // max(1, utterances - 1))
    rows = ["id,job,markers"]
    for k in range(utterances):
        a = slice(k * step, k * step + frames)
        sim = simulate(face_model(face), act[a], jaw[a])
        ms = MarkerSet(sim.markers, tuple(sim.marker_names), 60.0)
        write_markers(folder / f"utt{k}.csv", ms)
        rows.append(f"u{k},invert,utt{k}.csv")
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    return folder / "manifest.csv"


def timed_batch(manifest: Path, out: Path, workers: int) -> dict:
    from facemech.workflows.batch import run_batch

    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    rep = run_batch(manifest, out, workers=workers)
    wall = time.perf_counter() - t0
    cpu = sum(o.cpu_s for o in rep.outcomes)
    return {"workers": workers, "wall_s": round(wall, 2), "failed": rep.count("failed"),
            "item_wall_s": [round(o.wall_s, 2) for o in rep.outcomes],
            "items_cpu_s": round(cpu, 2),
            "cpu_share": round(cpu / (wall * workers), 2),
            "load_average_before": round(load, 2),
            "median_error_mm": [o.numbers.get("median_error_mm") for o in rep.outcomes]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--utterances", type=int, default=6)
    ap.add_argument("--frames", type=int, default=120, help="frames of each utterance (60 Hz)")
    ap.add_argument("--keep", type=Path, default=None, help="work in this folder and keep it")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="facemech-batch-bench-") as tmp:
        work = args.keep or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        manifest = make_corpus(work, args.utterances, args.frames)
        from facemech.workflows.invert import invert

        invert(work / "utt0.csv", work / "warm.nc")  # numba's disk cache filled before timing
        one = timed_batch(manifest, work / "out-1", 1)
        two = timed_batch(manifest, work / "out-2", 2)
    print(json.dumps({
        "utterances": args.utterances, "frames_each": args.frames, "cores": os.cpu_count(),
        "one_worker": one, "two_workers": two,
        "speedup": round(one["wall_s"] / two["wall_s"], 2), "target_speedup": 1.7,
    }, indent=2))


if __name__ == "__main__":
    main()
