"""Milliseconds per rendered frame of the built-in face at 720p and 1080p, on one core.

Prints one JSON object. Every view of the demo's open-mouth frame is timed (median of
``--frames`` renders after a warm-up), with 2x2 anti-aliasing (the default) and without, and
split into the scene update, the rasterisation and the shading/resolve passes for frontal 720p.
``--mesa`` also runs ``benchmarks/render_mesa.py`` (moderngl on Mesa's llvmpipe) in the same
session for the comparison in docs/rendering.md.

``--against SRC`` instead compares this tree with another checkout's ``src`` folder (e.g. the
main branch's, for a before/after ratio): the frontal 720p frame with 2x2 anti-aliasing is
timed in both, one subprocess each, alternately for ``--rounds`` rounds (so that both see the
same load), and the medians over all rounds (wall clock and process CPU time) and their
ratios are printed.

``--movie N`` instead times a movie's rendering: N frontal 720p frames with 2x2 anti-aliasing
(the demo's opening jaw, back and forth), drawn as :func:`facemech.viz.movie.write_movie`
draws them (:func:`facemech.viz.frame_pool.in_order`, without the encoder: ``draw``) and
written by it to an H.264 MP4 (``write_movie``), each on 1 and on 2 threads, alternately for
``--rounds`` rounds in this one process; it prints the medians (s for the N frames, ms per
frame), the ratio of 2 threads to 1, and that of their best rounds.

    python benchmarks/render.py [--frames 15] [--mesa]
    python benchmarks/render.py --against ../main/src [--rounds 5] [--frames 9]
    python benchmarks/render.py --movie 60 [--rounds 3]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from facemech.physics.model import model as face_model


def _median_ms(fn, n: int) -> float:
    fn()
    times = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=15)
    ap.add_argument("--mesa", action="store_true")
    ap.add_argument("--against", help="another checkout's src folder to compare with")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--movie", type=int, help="time N movie frames on 1 and 2 threads")
    ap.add_argument("--skin", help=argparse.SUPPRESS)  # child: time one tree on this skin
    args = ap.parse_args()
    if args.skin:
        return _frontal_child(args.skin, args.frames)

    from facemech.geometry.builder import default_face
    from facemech.params import MUSCLE_GROUPS
    from facemech.solvers.forward import simulate
    from facemech.viz import render as R
    from facemech.viz.raster import (
        GROUND,
        LINEAR_TO_SRGB_LUT,
        SKY,
        WRAP,
        rasterise_grid,
        vertex_light,
    )
    from facemech.viz.raster import shade_resolve as shade
    from facemech.viz.scene import build_scene, look_from_model

    face = default_face()
    n = 19
    act = np.zeros((n, len(MUSCLE_GROUPS)))
    jaw = np.radians(12.0) * np.linspace(0, 1, n)
    sim = simulate(face_model(face), act, jaw)
    skin, angle = sim.positions[-1], float(jaw[-1])
    if args.against:
        return _compare(args, skin, angle)
    if args.movie:
        return _movie(sim.positions, jaw, args.movie, args.rounds)
    t0 = time.perf_counter()
    scene = build_scene(look_from_model(face))
    build_s = time.perf_counter() - t0
    out = {"machine_cores_used": 1, "frames_timed": args.frames,
           "scene_build_s": round(build_s, 3), "triangles": int(len(scene.tris)),
           "ms_per_frame": {}}
    with threadpool_limits(1):
        for size_name, size in (("720p", (720, 1280)), ("1080p", (1080, 1920))):
            for view in ("frontal", "three-quarter", "mouth", "frontal+profile"):
                for aa in (2, 1):
                    r = R.Renderer(scene, view, size, supersample=aa)
                    key = f"{size_name} {view} aa{aa}"
                    out["ms_per_frame"][key] = round(_median_ms(lambda r=r: r(skin, angle),
                                                                args.frames), 1)
        # where the time goes: frontal 720p, 2x2 samples
        r = R.Renderer(scene, "frontal", (720, 1280))
        cam = r.cameras[0]
        verts, norms = scene.frame(skin, angle)
        s = 2
        p = cam.project(verts, s)
        x0, x1 = int(p[:, 0].min() / s), int(p[:, 0].max() / s) + 1
        y0, y1 = max(int(p[:, 1].min() / s), 0), min(int(p[:, 1].max() / s) + 1, 720)
        bh, bw = (y1 - y0) * s, (x1 - x0) * s
        px, py = p[:, 0] - x0 * s, p[:, 1] - y0 * s
        bufs = {}

        def ras():
            bufs["z"] = np.full((bh, bw), -np.inf, np.float32)
            bufs["t"] = np.full((bh, bw), -1, np.int32)
            bufs["b"] = np.empty((bh, bw, 2), np.float32)
            rasterise_grid(px, py, p[:, 2], scene.tris, scene.uv, scene.tex,
                           scene.alpha_test, scene.two_sided, scene.atlas,
                           (bufs["z"], bufs["t"], bufs["b"]), s)

        ras()
        sub = np.empty((y1 - y0, x1 - x0, 4), np.uint8)

        def light():
            return vertex_light(norms @ cam.rotation.T, scene.gloss, R._LIGHTS, SKY, GROUND,
                                WRAP)

        lit = light()

        def sh():
            shade(bufs["t"], bufs["b"], s, scene.tris, lit, scene.albedo, scene.uv, scene.tex,
                  scene.atlas, r.background, LINEAR_TO_SRGB_LUT, sub)

        out["frontal_720p_split_ms"] = {
            "scene_update": round(_median_ms(lambda: scene.frame(skin, angle), args.frames), 2),
            "project": round(_median_ms(lambda: cam.project(verts, s), args.frames), 2),
            "rasterise": round(_median_ms(ras, args.frames), 2),
            "vertex_light": round(_median_ms(light, args.frames), 2),
            "shade_resolve": round(_median_ms(sh, args.frames), 2),
            "samples_covered": int((bufs["t"] >= 0).sum()),
        }
    fps = 60.0
    ms = out["ms_per_frame"]["720p frontal aa2"]
    out["seconds_to_render_3s_stimulus_720p_frontal"] = round(3 * fps * ms / 1e3, 2)
    if args.mesa:
        script = Path(__file__).with_name("render_mesa.py")
        run = subprocess.run([sys.executable, str(script), "--quick"], capture_output=True,
                             text=True)
        try:
            out["mesa"] = json.loads(run.stdout)
        except json.JSONDecodeError:
            out["mesa"] = {"available": False, "why": run.stderr.strip()[-300:]}
    print(json.dumps(out, indent=2))


def _movie(positions: np.ndarray, jaw: np.ndarray, frames: int, rounds: int) -> None:
    """Print the seconds that ``frames`` frontal 720p frames take on 1 and on 2 threads.

    ``positions`` (T, n, 3) m and ``jaw`` (T,) rad are played back and forth to ``frames``
    frames; each thread count draws them all once per round, the counts alternating."""
    from facemech.geometry.builder import default_face
    from facemech.physics.threads import affinity_cores
    from facemech.viz.frame_pool import in_order
    from facemech.viz.render import RenderOptions
    from facemech.viz.scene import build_scene, look_from_model

    scene = build_scene(look_from_model(default_face()))
    opt = RenderOptions(view="frontal", size=(720, 1280), supersample=2)
    cycle = np.concatenate([np.arange(len(positions)), np.arange(len(positions))[::-1]])
    order = cycle[np.arange(frames) % len(cycle)]

    def draw(render, k: int) -> np.ndarray:
        f = order[k]
        return np.ascontiguousarray(render(positions[f], jaw[f])[..., :3])

    opt.renderer(scene)(positions[0], jaw[0])  # compile and build the scene's caches
    def drawn(workers: int) -> None:
        for _ in in_order(lambda: opt.renderer(scene), draw, frames, workers):
            pass

    def encoded(workers: int) -> None:  # the movie as write_movie makes it, H.264 included
        with tempfile.TemporaryDirectory() as tmp:
            pos = positions[order]
            write_movie(Path(tmp) / "m.mp4", scene, pos, jaw[order], options=opt,
                        workers=workers)

    import tempfile

    from facemech.viz.movie import write_movie

    opt.renderer(scene)(positions[0], jaw[0])  # compile and build the scene's caches
    out = {"frames": frames, "frame": "720p frontal aa2", "rounds": rounds,
           "cores_available": affinity_cores(),
           "load_average_1min_before": round(os.getloadavg()[0], 2)}
    with threadpool_limits(1):
        for name, run in (("draw", drawn), ("write_movie", encoded)):
            out[name] = _rounds(run, frames, rounds)
    print(json.dumps(out, indent=2))


def _rounds(run, frames: int, rounds: int) -> dict:
    """``run(workers)`` for 1 and 2 workers, alternately, ``rounds`` times: the medians (s,
    ms per frame), every round's seconds, the CPU time over the wall time, the encoder's
    (ffmpeg's) CPU time per frame (0 where nothing is encoded) and the ratio."""
    import resource

    def children() -> float:  # s of CPU time of the finished child processes (ffmpeg)
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    times: dict[int, list[float]] = {1: [], 2: []}
    cpu: dict[int, list[float]] = {1: [], 2: []}
    child: dict[int, list[float]] = {1: [], 2: []}
    for _ in range(rounds):
        for workers in times:
            t, c, e = time.perf_counter(), time.process_time(), children()
            run(workers)
            times[workers].append(time.perf_counter() - t)
            cpu[workers].append(time.process_time() - c)
            child[workers].append(children() - e)
    med = {w: float(np.median(v)) for w, v in times.items()}
    return {
        "encoder_cpu_ms_per_frame": round(1e3 * float(np.median(child[1] + child[2])) / frames,
                                          1),
        "seconds": {f"{w}_workers": round(v, 3) for w, v in med.items()},
        "ms_per_frame": {f"{w}_workers": round(1e3 * v / frames, 1) for w, v in med.items()},
        "all_rounds_s": {f"{w}_workers": [round(x, 3) for x in v] for w, v in times.items()},
        # this process's CPU time over the wall time: near the number of threads when each has
        # a core to itself (the encoder, ffmpeg, is another process)
        "cores_busy": {f"{w}_workers": round(float(np.sum(cpu[w]) / np.sum(times[w])), 2)
                       for w in times},
        "ratio_2_to_1": round(med[2] / med[1], 3),
        # the least disturbed round of each (a shared machine's load comes and goes)
        "best_ratio_2_to_1": round(min(times[2]) / min(times[1]), 3),
    }


def _frontal_child(path: str, frames: int) -> None:
    """Print {"wall_ms", "cpu_ms"}: medians of the frontal 720p 2x2 frame of this tree."""
    from facemech.geometry.builder import default_face
    from facemech.viz import render as R
    from facemech.viz.scene import build_scene, look_from_model

    data = np.load(path)
    skin, angle = data["skin"], float(data["angle"])
    r = R.Renderer(build_scene(look_from_model(default_face())), "frontal", (720, 1280))
    with threadpool_limits(1):
        r(skin, angle)
        wall, cpu = [], []
        for _ in range(frames):
            t, c = time.perf_counter(), time.process_time()
            r(skin, angle)
            wall.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
    print(json.dumps({"wall_ms": 1e3 * float(np.median(wall)),
                      "cpu_ms": 1e3 * float(np.median(cpu))}))


def _compare(args, skin, angle) -> None:
    """This tree against ``args.against``, alternately (see the module text)."""
    import tempfile

    here = str(Path(__file__).resolve().parents[1] / "src")
    trees = {"this": here, "against": str(Path(args.against).resolve())}
    runs = {k: [] for k in trees}
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "skin.npz")
        np.savez(path, skin=skin, angle=angle)
        for _ in range(args.rounds):
            for name, src in trees.items():
                env = {**os.environ, "PYTHONPATH": src,
                       "NUMBA_CACHE_DIR": str(Path(tmp) / f"numba-{name}")}
                run = subprocess.run([sys.executable, __file__, "--skin", path, "--frames",
                                      str(args.frames)], capture_output=True, text=True,
                                     env=env, check=True)
                runs[name].append(json.loads(run.stdout.strip().splitlines()[-1]))
    out = {"frame": "720p frontal aa2", "rounds": args.rounds, "frames_per_round": args.frames,
           "trees": trees}
    for key in ("wall_ms", "cpu_ms"):
        med = {k: round(float(np.median([r[key] for r in v])), 1) for k, v in runs.items()}
        out[key] = med
        out[key.replace("_ms", "_ratio")] = round(med["this"] / med["against"], 3)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
