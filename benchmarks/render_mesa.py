"""Mesa's CPU rasteriser (llvmpipe through a headless EGL context, moderngl) on the face (JSON).

Issue 12 weighs a real rasteriser on the CPU against the project's own numba rasteriser for
perception-grade face movies (target: a 1280x720 frame in at most 50 ms on one core). This
benchmark renders the built-in face's epidermis (frontal orthographic view, +x the subject's
left on the image's right, +y up) with per-vertex normals and colours, per-pixel Blinn-Phong
shading from two lights, optionally 4x multisampling (multisample framebuffer resolved by a
blit), and reads every frame back into a (h, w, 3) uint8 array, as a movie writer needs.
Each frame moves the nodes (a small travelling wave on the lower face), recomputes the vertex
normals in numpy and uploads positions and normals.

Reported per configuration (size, samples) and llvmpipe thread count (``LP_NUM_THREADS``; the
process is pinned to as many cores, so ``threads = 1`` is one core), medians over the timed
frames after a warm-up, in ms:

- ``gl_ms``: upload + draw + resolve + readback (``render_ms`` + ``readback_ms``: the split
  uses one ``glFinish`` after the resolve);
- ``normals_ms``: vertex normals in numpy (face normals scattered to nodes by a sparse
  incidence matrix), ``total_ms`` = ``gl_ms`` + ``normals_ms`` (``normals_add_at_ms``: the
  library's ``vertex_normals``, scattering with ``np.add.at``, for comparison);
- ``cpu_ms``: process CPU time per frame (all threads), to show how many cores were busy;
- ``first_frame_ms``: the first frame, which includes LLVM compiling the shaders.

Also: the context's start-up time (``import moderngl`` + EGL context), the renderer strings,
and a SHA-256 of one fixed frame per configuration, to see whether a frame is bit-identical
when re-rendered and across thread counts. Each thread count runs in its own process because
llvmpipe reads ``LP_NUM_THREADS`` once. Mesa's on-disk shader cache is disabled (cold start,
nothing written to ~/.cache). Without moderngl or a working EGL the output is
``{"available": false, "why": ...}`` and the exit status 0.

Usage: python benchmarks/render_mesa.py [--frames N] [--png PATH] [--quick]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import time

import numpy as np

SIZES = ((1280, 720), (1920, 1080))
SAMPLES = (4, 0)
THREADS = (1, 2)
TARGET_720P_MS = 50.0

SKIN = np.array([0.87, 0.68, 0.58])
LIPS = np.array([0.74, 0.38, 0.38])
BACKGROUND = (0.16, 0.17, 0.20)

VERTEX_SHADER = """
#version 330
uniform vec3 centre;
uniform vec3 scale;      // model metres -> clip coordinates, y negated (rows top-down)
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_colour;
out vec3 v_normal;
out vec3 v_colour;
void main() {
    v_normal = in_normal;
    v_colour = in_colour;
    gl_Position = vec4((in_pos - centre) * scale, 1.0);
}
"""

# Orthographic frontal view: the viewer looks along -z, so the view direction is +z.
FRAGMENT_SHADER = """
#version 330
uniform vec3 light_dir[2];
uniform vec3 light_rgb[2];
uniform float ambient;
uniform float specular;
uniform float shininess;
in vec3 v_normal;
in vec3 v_colour;
out vec4 f_colour;
void main() {
    vec3 n = normalize(v_normal);
    const vec3 view = vec3(0.0, 0.0, 1.0);
    if (dot(n, view) < 0.0) n = -n;
    vec3 rgb = ambient * v_colour;
    for (int k = 0; k < 2; ++k) {
        vec3 l = normalize(light_dir[k]);
        vec3 h = normalize(l + view);
        float diffuse = max(dot(n, l), 0.0);
        float spec = diffuse > 0.0 ? pow(max(dot(n, h), 0.0), shininess) : 0.0;
        rgb += light_rgb[k] * (diffuse * v_colour + specular * spec);
    }
    f_colour = vec4(min(rgb, vec3(1.0)), 1.0);
}
"""


def incidence(faces: np.ndarray, n: int):
    """Sparse (n, f) matrix with a one where node i is a corner of triangle t."""
    from scipy.sparse import csr_matrix

    f = len(faces)
    rows = faces.T.ravel()
    cols = np.tile(np.arange(f), 3)
    return csr_matrix((np.ones(3 * f), (rows, cols)), shape=(n, f))


def normals(positions: np.ndarray, faces: np.ndarray, inc) -> np.ndarray:
    """Area-weighted unit vertex normals (n, 3) float32 of positions (n, 3)."""
    a, b, c = positions[faces[:, 0]], positions[faces[:, 1]], positions[faces[:, 2]]
    vn = inc @ np.cross(b - a, c - a)
    norm = np.sqrt(np.einsum("ij,ij->i", vn, vn))[:, None]
    return (vn / np.where(norm > 0, norm, 1.0)).astype(np.float32)


def moved(rest: np.ndarray, t: float) -> np.ndarray:
    """Rest positions (n, 3) m with a 2-mm travelling wave on the lower face at time t (s)."""
    x, y = rest[:, 0], rest[:, 1]
    lower = np.clip((-0.04 - y) / 0.03, 0.0, 1.0)
    wave = 0.002 * lower * np.sin(2 * np.pi * 3.0 * t + 60.0 * x)
    out = rest.copy()
    out[:, 2] += wave
    out[:, 1] -= 0.5 * wave
    return out


def face_scene():
    """Skin positions (n, 3) m, triangles (f, 3) int32 and colours (n, 3) float32."""
    from facemech.geometry.builder import default_face

    m = default_face()
    rest = np.asarray(m.rest_positions[: m.n_surface], float)
    faces = np.ascontiguousarray(m.faces, dtype=np.int32)
    colours = np.where(m.lip_region[: m.n_surface, None], LIPS, SKIN).astype(np.float32)
    return rest, faces, colours


class Renderer:
    """One moderngl program and framebuffers for a (width, height) and sample count."""

    def __init__(self, ctx, rest, faces, colours, size, samples):
        self.ctx = ctx
        w, h = size
        self.size = size
        self.samples = samples
        self.prog = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)
        lo, hi = rest.min(axis=0), rest.max(axis=0)
        centre = 0.5 * (lo + hi)
        extent = 0.55 * max(hi[1] - lo[1], (hi[0] - lo[0]) * h / w)
        depth = 0.6 * (hi[2] - lo[2]) + 0.01
        self.prog["centre"].value = tuple(centre)
        self.prog["scale"].value = (h / w / extent, -1.0 / extent, -1.0 / depth)
        self.prog["light_dir"].value = [(0.35, 0.45, 0.82), (-0.6, 0.1, 0.5)]
        self.prog["light_rgb"].value = [(0.75, 0.75, 0.72), (0.22, 0.24, 0.3)]
        self.prog["ambient"].value = 0.22
        self.prog["specular"].value = 0.15
        self.prog["shininess"].value = 40.0
        n = len(rest)
        self.vbo_pos = ctx.buffer(reserve=n * 12, dynamic=True)
        self.vbo_nrm = ctx.buffer(reserve=n * 12, dynamic=True)
        self.vbo_col = ctx.buffer(np.ascontiguousarray(colours, np.float32).tobytes())
        self.ibo = ctx.buffer(faces.tobytes())
        self.vao = ctx.vertex_array(
            self.prog,
            [(self.vbo_pos, "3f", "in_pos"), (self.vbo_nrm, "3f", "in_normal"),
             (self.vbo_col, "3f", "in_colour")],
            index_buffer=self.ibo, index_element_size=4,
        )
        self.out = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer((w, h), 4)],
            depth_attachment=ctx.depth_renderbuffer((w, h)) if samples == 0 else None,
        )
        if samples:
            self.msaa = ctx.framebuffer(
                color_attachments=[ctx.renderbuffer((w, h), 4, samples=samples)],
                depth_attachment=ctx.depth_renderbuffer((w, h), samples=samples),
            )
        else:
            self.msaa = None
        self.pixels = np.empty((h, w, 3), np.uint8)

    def render(self, positions32: np.ndarray, normals32: np.ndarray):
        """Upload, draw and resolve (ends with glFinish)."""
        ctx = self.ctx
        self.vbo_pos.write(positions32)
        self.vbo_nrm.write(normals32)
        target = self.msaa or self.out
        target.use()
        ctx.enable(ctx.DEPTH_TEST)
        target.clear(*BACKGROUND, 1.0, depth=1.0)
        self.vao.render()
        if self.msaa is not None:
            ctx.copy_framebuffer(dst=self.out, src=self.msaa)
        ctx.finish()

    def readback(self) -> np.ndarray:
        """The frame as a (h, w, 3) uint8 array, first row the image's top."""
        self.out.read_into(self.pixels, components=3, alignment=1)
        return self.pixels


def ms(seconds) -> float:
    """Median of a list of durations (s), in ms to two decimals."""
    return round(1e3 * float(np.median(seconds)), 2)


def run_config(ctx, rest, faces, colours, inc, size, samples, frames, warmup):
    r = Renderer(ctx, rest, faces, colours, size, samples)
    still = rest.astype(np.float32)
    still_n = normals(rest, faces, inc)
    t0 = time.perf_counter()
    r.render(still, still_n)
    first_image = r.readback().copy()
    first = time.perf_counter() - t0
    gl, rend, back, nrm, cpu = [], [], [], [], []
    for k in range(warmup + frames):
        pos = moved(rest, k / 60.0)
        c0 = time.process_time()
        t0 = time.perf_counter()
        nr = normals(pos, faces, inc)
        t1 = time.perf_counter()
        r.render(pos.astype(np.float32), nr)
        t2 = time.perf_counter()
        img = r.readback()
        t3 = time.perf_counter()
        c1 = time.process_time()
        assert img.shape == (size[1], size[0], 3)
        if k >= warmup:
            nrm.append(t1 - t0)
            rend.append(t2 - t1)
            back.append(t3 - t2)
            gl.append(t3 - t1)
            cpu.append(c1 - c0)
    r.render(still, still_n)
    again = r.readback()
    return {
        "size": list(size), "samples": samples,
        "gl_ms": ms(gl), "render_ms": ms(rend), "readback_ms": ms(back),
        "normals_ms": ms(nrm), "total_ms": ms(np.add(gl, nrm)), "cpu_ms": ms(cpu),
        "first_frame_ms": round(1e3 * first, 1),
        "sha256": hashlib.sha256(first_image.tobytes()).hexdigest()[:16],
        "repeatable": bool(np.array_equal(first_image, again)),
    }, first_image


def worker(threads: int, frames: int, warmup: int, sizes, png: str | None) -> dict:
    """Measure in this process with llvmpipe on ``threads`` threads (env set by the caller)."""
    try:
        os.sched_setaffinity(0, set(sorted(os.sched_getaffinity(0))[: max(threads, 1)]))
    except (AttributeError, OSError):
        pass
    t0 = time.perf_counter()
    try:
        import moderngl

        ctx = moderngl.create_standalone_context(backend="egl", require=330)
    except Exception as exc:  # no moderngl, libEGL or driver: report, do not fail
        return {"available": False, "why": f"{type(exc).__name__}: {exc}"}
    startup = time.perf_counter() - t0
    rest, faces, colours = face_scene()
    inc = incidence(faces, len(rest))
    configs = []
    for size in sizes:
        for samples in SAMPLES:
            if samples > ctx.max_samples:
                continue
            res, image = run_config(ctx, rest, faces, colours, inc, size, samples, frames,
                                    warmup)
            configs.append(res)
            if png and size == (1280, 720) and samples == max(SAMPLES):
                import matplotlib.image

                matplotlib.image.imsave(png, image)
    pos = moved(rest, 0.1)
    ref = []
    from facemech.geometry.builder import vertex_normals

    for _ in range(5):
        t = time.perf_counter()
        vertex_normals(pos, faces)
        ref.append(time.perf_counter() - t)
    return {
        "available": True, "threads": threads, "cores": len(os.sched_getaffinity(0)),
        "renderer": ctx.info["GL_RENDERER"], "gl_version": ctx.info["GL_VERSION"],
        "max_samples": ctx.max_samples, "moderngl": moderngl.__version__,
        "startup_ms": round(1e3 * startup, 1),
        "normals_add_at_ms": ms(ref),
        "configs": configs,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=30, help="timed frames per configuration")
    ap.add_argument("--png", default=None, help="save the first 720p 4x frame (1 thread) here")
    ap.add_argument("--quick", action="store_true", help="720p only, 10 frames")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    frames = 10 if args.quick else args.frames
    sizes = SIZES[:1] if args.quick else SIZES
    warmup = 3
    if args.worker is not None:
        print(json.dumps(worker(args.worker, frames, warmup, sizes, args.png)))
        return
    try:
        import moderngl  # noqa: F401
    except ImportError as exc:
        print(json.dumps({"available": False, "why": f"moderngl not importable: {exc}"}))
        return
    runs = []
    for threads in THREADS:
        env = dict(os.environ, LP_NUM_THREADS=str(threads), MESA_SHADER_CACHE_DISABLE="true",
                   LIBGL_ALWAYS_SOFTWARE="1", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", str(threads),
               "--frames", str(frames)]
        if args.quick:
            cmd.append("--quick")
        if args.png and threads == 1:
            cmd += ["--png", args.png]
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        try:
            res = json.loads(proc.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            res = {"available": False,
                   "why": f"worker exited {proc.returncode}: {proc.stderr.strip()[-500:]}"}
        if proc.stderr.strip():
            res["stderr"] = proc.stderr.strip()[-500:]
        if not res.get("available"):
            print(json.dumps(res))
            return
        runs.append(res)
    one = runs[0]
    base = {k: one[k] for k in ("renderer", "gl_version", "max_samples", "moderngl",
                                "normals_add_at_ms")}
    hashes = [{(tuple(c["size"]), c["samples"]): c["sha256"] for c in r["configs"]}
              for r in runs]
    at720 = [c for c in one["configs"] if c["size"] == [1280, 720] and c["samples"] == 4]
    report = {
        "available": True, **base,
        "frames": frames, "warmup": warmup,
        "target_720p_one_core_ms": TARGET_720P_MS,
        "meets_target_720p_msaa4_one_core": bool(at720 and at720[0]["total_ms"]
                                                  <= TARGET_720P_MS),
        "identical_across_threads": all(h == hashes[0] for h in hashes[1:]),
        "runs": [{k: r[k] for k in ("threads", "cores", "startup_ms", "configs", "stderr")
                  if k in r} for r in runs],
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
