"""How long a photo takes to become a talker, as a user runs it.

For each portrait of tests/data/portraits, ``facemech face from-photo PHOTO -o talker.npz`` is
run in a fresh process (imports, dlib's models, detection, fit, texture, build, save: what a
user waits for), timed on the wall clock and in CPU seconds (the child's user + system time:
on a machine shared with other work, the wall clock counts their time too). Then, in this
process with everything imported and dlib's models loaded, each stage of the same path is
timed alone. Prints one JSON line per portrait: ``wall_s``, ``cpu_s`` and ``stages`` (each
stage's wall and CPU seconds), and the machine's load average before and after.

``python benchmarks/photo_time.py [--only obama] [--repeat 2]``  (needs the ``photo`` extra)
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

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

PORTRAITS = Path(__file__).resolve().parents[1] / "tests" / "data" / "portraits"


def cold(photo: Path, out: Path) -> dict:
    """Wall and CPU seconds of the command in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "facemech", "face", "from-photo", str(photo), "-o",
                    str(out)], check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}


def stages(photo: Path, detector) -> dict:
    """Wall and CPU seconds of each stage, in this (warm) process."""
    from facemech.geometry.builder import build_face, tissue_options
    from facemech.geometry.photo_fit import DLIB_OFFSETS_MM, fit_frontal
    from facemech.io.photo import frontal_landmarks, read_photo
    from facemech.viz.photo_texture import bake_photo_texture

    out, clock = {}, [time.perf_counter(), time.process_time()]

    def lap(name):
        w, c = time.perf_counter(), time.process_time()
        out[name] = {"wall_s": round(w - clock[0], 3), "cpu_s": round(c - clock[1], 3)}
        clock[:] = [w, c]

    image = read_photo(photo)
    lap("read")
    points = frontal_landmarks(image, source=photo.name, detector=detector).points
    lap("detect")
    fit = fit_frontal(points, image.shape[:2], offsets=DLIB_OFFSETS_MM, source=photo.name)
    lap("fit")
    texture = bake_photo_texture(fit, image, source=photo.name)
    lap("texture")
    model = build_face(fit.vertices, fit.faces, fit.landmarks, name=photo.stem,
                       source=photo.name, options=tissue_options("anatomical"),
                       appearance=texture.appearance, notes=[])
    lap("build")
    with tempfile.TemporaryDirectory() as tmp:
        model.save(Path(tmp) / "talker.npz")
    lap("save")
    return out


def main(argv=None) -> int:
    from facemech.io.photo import DlibDetector

    ap = argparse.ArgumentParser()
    ap.add_argument("--only")
    ap.add_argument("--repeat", type=int, default=1, help="cold runs per portrait (the best)")
    args = ap.parse_args(argv)
    t0, c0 = time.perf_counter(), time.process_time()
    detector = DlibDetector()
    load = {"wall_s": round(time.perf_counter() - t0, 3),
            "cpu_s": round(time.process_time() - c0, 3)}
    for photo in sorted(PORTRAITS.glob("*.jpg")):
        if args.only and args.only != photo.stem:
            continue
        load_before = os.getloadavg()[0]
        with tempfile.TemporaryDirectory() as tmp:
            runs = [cold(photo, Path(tmp) / "talker.npz") for _ in range(args.repeat)]
        best = min(runs, key=lambda r: r["wall_s"])
        row = {"portrait": photo.name, **best, "stages": {"dlib_models": load,
                                                          **stages(photo, detector)},
               "load_average": [round(load_before, 2), round(os.getloadavg()[0], 2)],
               "cores": os.cpu_count()}
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
