"""What the Krylov correction costs on a region about the mouth against on the whole face.

For each variant, the demo utterance (``facemech.demo.utterance``, 2.6 s, the built-in face)
simulated on one core (one numba thread, one BLAS thread): wall seconds and the real-time
factor (simulated seconds per wall second), the variants interleaved and each timed
``--repeat`` times, the best kept (the machine is shared: read the ratios, measured in one
run). The variants are those of ``benchmarks/speed.py`` (``--variants``), whose gestures'
rise, speed and ringing that script measures.

Prints JSON. ``python benchmarks/krylov_region.py [--variants a,b] [--repeat 2]``
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from facemech.physics.model import model as face_model
from speed import VARIANTS  # noqa: E402  (benchmarks/ is the script's folder)

DEFAULT = ("default,kv_krylov4_floor_stiff4_drag200,kv_krylov4_floor_stiff4_drag200_region45,"
           "kv_krylov4_floor_stiff4_drag200_region60")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", default=DEFAULT)
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits

    from facemech import default_face
    from facemech.demo import utterance
    from facemech.params import preset_pair
    from facemech.physics.threads import set_threads
    from facemech.solvers.forward import simulate

    set_threads(1)
    face = default_face("default")
    t, act, jaw = utterance()
    names = args.variants.split(",")
    params = {n: preset_pair("anatomical").with_(**VARIANTS[n]) for n in names}
    best = {n: float("inf") for n in names}
    with threadpool_limits(1):
        for n in names:  # compile and load once, untimed
            simulate(face_model(face, params[n]), act[:3], jaw[:3])
        for _ in range(args.repeat):
            for n in names:
                t0 = time.perf_counter()
                simulate(face_model(face, params[n]), act, jaw)
                best[n] = min(best[n], time.perf_counter() - t0)
                print(f"{n} {best[n]:.2f} s", file=sys.stderr, flush=True)
    seconds = len(t) / params[names[0]].params.frame_rate
    out = {"utterance_s": round(seconds, 3), "repeat": args.repeat, "variants": {
        n: {"changes": {k: float(v) for k, v in VARIANTS[n].items()},
            "wall_s": round(best[n], 2), "real_time_factor": round(seconds / best[n], 2)}
        for n in names}}
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
