"""The MOCHA-TIMIT sentence inverted by the whole command, warm (prints JSON).

``facemech invert --markers ../shared/data/mocha/fsew0_001.ema`` (1.93 s of articulography),
the command's wall time with its finite-difference columns on one process and shared between
two (``FACEMECH_WORKERS``), interleaved, best of ``--repeat``; the ratio of the two in the
same run. ``--preset`` adds ``--preset P`` (e.g. benchmarks/presets/fast-lips.json). The
first run of each (not timed) compiles or loads the kernels.

Usage: python benchmarks/invert_mocha.py [--repeat 2] [--preset P] [--workers 1,2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EMA = ROOT.parent / "shared" / "data" / "mocha" / "fsew0_001.ema"


def run(workers: int, out: Path, preset: str | None) -> float:
    cmd = [sys.executable, "-m", "facemech", "invert", "--markers", str(EMA), "-o", str(out)]
    if preset:
        cmd += ["--preset", preset]
    env = dict(os.environ, FACEMECH_WORKERS=str(workers))
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--preset", default=None)
    ap.add_argument("--workers", default="1,2")
    args = ap.parse_args(argv)
    counts = [int(w) for w in args.workers.split(",")]
    best = {w: float("inf") for w in counts}
    with tempfile.TemporaryDirectory() as tmp:
        for w in counts:
            run(w, Path(tmp) / "warm.nc", args.preset)
        for _ in range(args.repeat):
            for w in counts:
                best[w] = min(best[w], run(w, Path(tmp) / f"w{w}.nc", args.preset))
    out = {"recording": str(EMA.name), "preset": args.preset or "anatomical",
           "cpu_count": os.cpu_count(), "load_1min": round(os.getloadavg()[0], 2),
           "wall_s": {str(w): round(best[w], 2) for w in counts}}
    if len(counts) > 1:
        out["speedup_vs_first"] = {str(w): round(best[counts[0]] / best[w], 3)
                                   for w in counts[1:]}
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
