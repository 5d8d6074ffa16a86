"""Peak memory of long simulations: streamed to the results file vs held in memory (prints JSON).

The utterance is the demo's (/ba pi ma wu pa/, :func:`facemech.demo.utterance`) repeated to the
length asked. Each run is a child process that builds the default face, simulates and writes
the results file, then reports its own peak resident memory (``ru_maxrss``), so the numbers are
the simulation's alone. ``floor`` is a child that only builds the face and simulates 3 frames:
what every run costs before its frames.

Usage: python benchmarks/memory.py [--minutes 1 2 4] [--modes stream memory] [--block 600]

``stream`` runs :func:`facemech.workflows.simulate.simulate_to_file` (what ``facemech simulate``
does); ``memory`` runs :func:`facemech.simulate` then :func:`facemech.io.results.write_results`
(about 0.05 MB per frame held: keep it to short runs).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from facemech.physics.model import model as face_model

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def controls(minutes: float):
    """The demo utterance's activity and jaw angles tiled to ``minutes`` at 60 Hz."""
    import numpy as np

    from facemech.demo import utterance

    _, act, jaw = utterance()
    frames = max(int(round(minutes * 60 * 60)), 2)
    reps = -(-frames // len(act))
    return np.tile(act, (reps, 1))[:frames], np.tile(jaw, reps)[:frames]


def child(mode: str, minutes: float, block: int, out: str) -> dict:
    """One measured run in this process (called in a child)."""
    from facemech import default_face, preset, simulate

    face, prm = default_face(), preset("anatomical")
    act, jaw = controls(minutes)
    t0 = time.perf_counter()
    if mode == "floor":
        simulate(face_model(face, prm), act[:3], jaw[:3])
        frames = 3
    elif mode == "memory":
        from facemech.io.results import write_results

        write_results(out, simulate(face_model(face, prm), act, jaw))
        frames = len(act)
    else:
        from facemech.workflows.simulate import simulate_to_file

        simulate_to_file(out, face_model(face, prm), act, jaw, block_frames=block)
        frames = len(act)
    wall = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux
    size = Path(out).stat().st_size / 1e6 if Path(out).exists() else 0.0
    return {"mode": mode, "minutes": minutes, "frames": frames, "wall_s": round(wall, 1),
            "real_time_factor": round(frames / 60 / wall, 3), "peak_rss_mb": round(peak_mb, 1),
            "file_mb": round(size, 1)}


def measure(mode: str, minutes: float, block: int) -> dict:
    """:func:`child` in a fresh Python process."""
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "r.nc")
        proc = subprocess.run([sys.executable, __file__, "--child", mode, str(minutes),
                               str(block), out], capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--minutes", type=float, nargs="+", default=[1.0, 2.0, 4.0])
    ap.add_argument("--modes", nargs="+", default=["stream"], choices=["stream", "memory"])
    ap.add_argument("--block", type=int, default=600, help="frames per streamed block")
    ap.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        mode, minutes, block, out = args.child
        print(json.dumps(child(mode, float(minutes), int(block), out)))
        return
    runs = [measure("floor", 0.0, args.block)]
    for minutes in args.minutes:
        for mode in args.modes:
            runs.append(measure(mode, minutes, args.block))
            print(json.dumps(runs[-1]), file=sys.stderr, flush=True)
    print(json.dumps({"block_frames": args.block, "runs": runs}, indent=1))


if __name__ == "__main__":
    main()
