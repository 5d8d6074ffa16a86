"""How far the published numbers move with the floating-point environment (prints JSON).

Each *job* computes published numbers: Experiment 1 of Pitermann & Munhall (2001) under a preset
(``e1-lucero1999``, ``e1-anatomical``: least squares with and without the positive constraint,
as docs/inversion.md and the tests run it), the default inversion of benchmarks/inversion.py
(``inversion-default``: 3 s of the demo utterance, the jaw estimated), the demo twin through the
command line (``demo-twin``: ``facemech invert`` on the demo's markers, the jaw estimated, as
tests/inverse/test_inversion_trust.py) and the subject twin (``subject-twin``: ``facemech
subject`` and ``facemech analyse`` on a lab recording of the demo, as
tests/workflows/test_subject.py), the visemes
(``visemes``), ``facemech speak`` (``speak``) and docs/model.md's gesture table (``gestures``).
Each runs in a child process once per *environment*:

==================  =========================================================================
``default``         one thread everywhere (numba, OpenBLAS), the machine's own OpenBLAS kernels
``prescott``        ``OPENBLAS_CORETYPE=Prescott`` (SSE3 kernels)
``nehalem``         ``OPENBLAS_CORETYPE=Nehalem`` (SSE4 kernels)
``haswell``         ``OPENBLAS_CORETYPE=Haswell`` (AVX2 kernels)
``blas-2``          ``OPENBLAS_NUM_THREADS=2``
``numba-2``         two threads for the force kernels (``FACEMECH_THREADS=2``)
``generic``         numba compiled for a generic x86-64 CPU (``NUMBA_CPU_NAME=generic``)
``perturbed``       every marker set given to the inversion multiplied by ``1 + 1e-12 u``, u a
                    fixed pseudo-random number in [-1, 1] per coordinate
==================  =========================================================================

For every number the output gives its value in each environment and its spread: the largest
deviation from ``default`` (absolute, and relative to the default's magnitude). ``--markdown``
prints the tables of docs/reproducibility.md instead. The results of each (job, environment) are
kept in ``--cache`` (default ``.spread-cache/``) and reused, so that an interrupted measurement
goes on where it stopped; delete the folder (or use ``--fresh``) after changing the code.

Usage::

    python tools/spread.py [--jobs e1-lucero1999,demo-twin] [--envs default,prescott]
                           [--parallel 2] [--cache DIR] [--fresh] [--cached] [--markdown]
                           [--write-docs] [-o OUT.json]
    python tools/spread.py --list
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from facemech.physics.model import model as face_model

ROOT = Path(__file__).resolve().parent.parent
PERTURBATION = 1e-12  #: relative size of the ``perturbed`` environment's marker changes

#: the environments, as variables over the base (:data:`BASE_ENV`)
ENVS: dict[str, dict[str, str]] = {
    "default": {},
    "prescott": {"OPENBLAS_CORETYPE": "Prescott"},
    "nehalem": {"OPENBLAS_CORETYPE": "Nehalem"},
    "haswell": {"OPENBLAS_CORETYPE": "Haswell"},
    "blas-2": {"OPENBLAS_NUM_THREADS": "2"},
    "numba-2": {"FACEMECH_THREADS": "2", "NUMBA_NUM_THREADS": "2"},
    "generic": {"NUMBA_CPU_NAME": "generic"},
    "perturbed": {"FACEMECH_SPREAD_PERTURB": str(PERTURBATION)},
}
#: the environments measured by default (haswell: only on request; the default kernels of an
#: AVX-512 machine are SkylakeX, of an AVX2 one Haswell)
DEFAULT_ENVS = ("default", "prescott", "nehalem", "blas-2", "generic", "perturbed", "numba-2")
#: every child starts from this: one thread for numba and the BLAS, as the docs' tables and the
#: tests are measured
BASE_ENV = {"FACEMECH_THREADS": "1", "NUMBA_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
            "MPLBACKEND": "Agg"}
JOBS = ("e1-lucero1999", "e1-anatomical", "inversion-default", "demo-twin", "subject-twin",
        "visemes", "speak", "gestures")
#: the sentences of tests/speech/test_speak.py's viseme targets
SENTENCES = ("Bob bought a puppy", "Pop, a blue balloon, and a large car.")


# ---- in the child ---------------------------------------------------------------------------

def _perturb_inversions(rel: float) -> None:
    """Make every inversion see its markers times ``1 + rel u`` (u fixed, in [-1, 1])."""
    import dataclasses

    import numpy as np

    import facemech.inverse.experiments as experiments
    import facemech.inverse.invert as inv

    original = inv.invert

    def invert(face, markers, mapping, **kw):
        u = np.random.default_rng(12345).uniform(-1.0, 1.0, markers.positions.shape)
        moved = dataclasses.replace(markers, positions=markers.positions * (1.0 + rel * u))
        return original(face, moved, mapping, **kw)

    inv.invert = experiments.invert = invert


def _cli(*args) -> int:
    """``facemech ARGS`` in this process, quietly; its exit status."""
    import contextlib
    import io

    from facemech.cli import main

    sys.argv = ["facemech", *map(str, args)]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            main()
        except SystemExit as exc:
            return exc.code if isinstance(exc.code, int) else 1
    return 0


def _recovery(truth_path, inv_path, frames=None) -> dict:
    """Correlation of each recovered control with the truth, and whether it is identifiable
    (as tests/inverse/test_inversion_trust.py and tests/workflows/test_subject.py compute them)."""
    import numpy as np

    from facemech import read_results

    truth, inv = read_results(truth_path), read_results(inv_path)
    n = frames or min(truth.sizes["time"], inv.sizes["time"])
    out = {}
    for name, seen in zip(inv["control"].values, inv["identifiable"].values, strict=True):
        if name == "jaw":
            a, b = truth["jaw_angle"].values[:n], inv["jaw_angle"].values[:n]
        else:
            a = truth["activity"].sel(muscle=name).values[: n - 1]
            b = inv["activity"].sel(muscle=name).values[: n - 1]
        out[f"r {name}"] = float(np.corrcoef(a, b)[0, 1])
        out[f"identifiable {name}"] = bool(seen)
    out["error median mm"] = float(inv.attrs["rms_error_mm_median"])
    out["error max mm"] = float(inv.attrs["rms_error_mm_max"])
    return out


def job_experiment1(preset_name: str) -> dict:
    from facemech import default_face
    from facemech.inverse.experiments import run_synthetic
    from facemech.params import preset

    res = run_synthetic(face_model(default_face(), preset(preset_name)), methods=("lsq",))
    out = {}
    for label, run in res.runs.items():
        for c, r in run.activity_correlation.items():
            out[f"{label}: r {c}"] = r
        out[f"{label}: error median mm"] = run.frame_error_mm["median"]
        out[f"{label}: error max mm"] = run.frame_error_mm["max"]
        out[f"{label}: frame steps"] = run.evaluations
        out[f"{label}: 3-D corr >= 0.95"] = run.corr3d_at_least
        out[f"{label}: 3-D corr > 0.8"] = run.corr3d_above
        out[f"{label}: lowest 3-D corr"] = min(v["published"] for v in run.corr3d.values())
        out[f"{label}: movement mm"] = run.movement_mm
    return out


def job_inversion_default() -> dict:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from facemech import default_face
    from inversion import default_inversion

    res = default_inversion(default_face(), 3.0)
    out = {f"r {c}": r for c, r in res["activity_r"].items()}
    out["r jaw"] = res["jaw_r"]
    out["frame steps"] = res["steps"]
    out["error median mm"] = res["median_frame_error_mm"]
    out["error max mm"] = res["max_frame_error_mm"]
    return out


def job_demo_twin(folder: Path) -> dict:
    assert _cli("demo", "-o", folder / "demo", "--no-video") == 0
    assert _cli("export", folder / "demo" / "result.nc", "-o", folder / "markers.trc") == 0
    out = {}
    for jaw, extra in (("estimated", []), ("chin marker", ["--chin-marker", "R01"])):
        inv = folder / f"inv-{jaw.replace(' ', '-')}.nc"
        assert _cli("invert", "--markers", folder / "markers.trc", "-o", inv, *extra) == 0
        rec = _recovery(folder / "demo" / "result.nc", inv)
        out.update({f"jaw {jaw}: {k}": v for k, v in rec.items()})
    return out


def job_subject_twin(folder: Path) -> dict:
    sys.path.insert(0, str(ROOT / "tests"))
    from facemech.workflows.demo import run as run_demo
    from facemech.workflows.subject import make_subject
    from twin_recording import lab_recordings

    run_demo(folder / "demo", video=False)
    rec = lab_recordings(folder / "demo" / "result.nc", folder)
    make_subject("default", rec["rest"], folder / "S", head=",".join(rec["head"]),
                 frame=",".join(rec["frame"]), chin_marker=rec["chin"], units="mm")
    assert _cli("analyse", folder / "S", rec["speech"], "-o", folder / "OUT", "--units",
                "mm") == 0
    return _recovery(folder / "demo" / "result.nc", folder / "OUT" / "result.nc")


def job_speak(folder: Path) -> dict:
    """``facemech speak`` on :data:`SENTENCES`: at the acoustic middle of each phone, what
    tests/speech/test_speak.py checks (bilabials' lip gap, rounded lips' protrusion, /i/'s width,
    /a/'s jaw angle)."""
    import numpy as np

    from facemech import default_face, read_results
    from facemech.speech.alignment_io import read_alignment_csv
    from facemech.speech.mouth import mouth_measures
    from facemech.speech.phoneclass import phone_classes

    out = {}
    for n, text in enumerate(SENTENCES):
        d = folder / f"s{n}"
        assert _cli("speak", text, "-o", d, "--no-video") == 0
        ds = read_results(d / "result.nc")
        m = mouth_measures(default_face(), ds["positions"].values)
        jaw = np.degrees(ds["jaw_angle"].values)
        al = read_alignment_csv(d / "alignment.csv")
        for i, ph in enumerate(al.phones):
            k = int(round(ph.mid * 60))
            key = f"{text.split(',')[0]}: phone {i} {ph.label}"
            c = phone_classes(ph.label, al.notation)
            if c == ("bilabial",):
                out[f"{key}: lip gap mm"] = float(m["lip_gap"][k] * 1e3)
            elif c in (("close_back_rounded",), ("w",)):
                out[f"{key}: lower lip forward mm"] = float(m["lower_forward"][k] * 1e3)
            elif c == ("close_front_spread",):
                out[f"{key}: width change mm"] = float(m["width_change"][k] * 1e3)
            elif c == ("open",):
                out[f"{key}: jaw deg"] = float(jaw[k])
    return out


def job_gestures() -> dict:
    """docs/model.md's gesture table under the default preset: each group named by a minimum of
    :data:`facemech.analysis.gestures.TARGETS` at full activity (forward simulations), every
    measure in mm."""
    from facemech import default_face
    from facemech.analysis.gestures import TARGETS, gesture_table

    groups = sorted({"+".join(t[0]) for t in TARGETS})
    table = gesture_table(face_model(default_face()), groups=groups)
    return {f"{g}: {k} mm": float(v) for g, row in table.items() for k, v in row.items()}


def _flatten(tree, prefix: str = "") -> dict:
    """Numeric leaves of a JSON tree, keyed ``a: b: c``; timings (``wall``, ``_s`` keys) left
    out."""
    if isinstance(tree, dict):
        out = {}
        for k, v in tree.items():
            if "wall" in str(k) or str(k).endswith("_s"):
                continue
            out.update(_flatten(v, f"{prefix}{k}: "))
        return out
    if isinstance(tree, list):
        return {} if len(tree) > 16 else _flatten(dict(enumerate(tree)), prefix)
    if isinstance(tree, (int, float)) and not isinstance(tree, bool):
        return {prefix[:-2]: tree}
    return {}


def job_script(script: str) -> dict:
    """A benchmark that prints JSON, run as it is (a child of this child): its numbers."""
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script)],
                          capture_output=True, text=True, check=True, cwd=ROOT)
    return _flatten(json.loads(proc.stdout))


def child(job: str) -> dict:
    import warnings

    warnings.simplefilter("ignore")
    rel = os.environ.get("FACEMECH_SPREAD_PERTURB")
    if rel:
        _perturb_inversions(float(rel))
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="facemech-spread-") as tmp:
        if job.startswith("e1-"):
            numbers = job_experiment1(job[3:])
        elif job == "inversion-default":
            numbers = job_inversion_default()
        elif job == "demo-twin":
            numbers = job_demo_twin(Path(tmp))
        elif job == "subject-twin":
            numbers = job_subject_twin(Path(tmp))
        elif job == "speak":
            numbers = job_speak(Path(tmp))
        elif job == "visemes":
            numbers = job_script("visemes.py")
        elif job == "gestures":
            numbers = job_gestures()
        else:
            raise SystemExit(f"unknown job {job!r} (expected one of {', '.join(JOBS)})")
    from facemech.io.results import numerics_attrs

    env = numerics_attrs()
    return {"numbers": numbers, "wall_s": time.perf_counter() - t0,
            "blas_core": env["blas_core"], "numba_cpu": env["numba_cpu"]}


# ---- in the parent --------------------------------------------------------------------------

def run_child(job: str, env_name: str, cache: Path, fresh: bool) -> dict:
    path = cache / f"{job}@{env_name}.json"
    if path.exists() and not fresh:
        return json.loads(path.read_text())
    env = {k: v for k, v in os.environ.items() if k != "FACEMECH_SPREAD_PERTURB"}
    env.update({**BASE_ENV, **ENVS[env_name]})
    t0 = time.monotonic()
    cache.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([sys.executable, __file__, "--child", job, "--to", str(path)], env=env,
                          cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{job} under {env_name} failed:\n{proc.stderr[-3000:]}")
    res = json.loads(path.read_text())
    print(f"spread: {job} under {env_name}: {time.monotonic() - t0:.0f} s", file=sys.stderr,
          flush=True)
    return res


def spread(values: dict[str, object]) -> dict:
    """The spread of one number over the environments: the default, min, max and the largest
    deviation from the default (absolute and relative)."""
    base = values.get("default")
    nums = {k: v for k, v in values.items() if isinstance(v, (int, float))
            and not isinstance(v, bool) and math.isfinite(v)}
    if isinstance(base, bool) or not nums or base not in nums.values():
        return {"values": values, "same": len({json.dumps(v) for v in values.values()}) == 1}
    dev = max(abs(v - base) for v in nums.values())
    return {"values": values, "default": base, "min": min(nums.values()),
            "max": max(nums.values()), "max_abs_dev": dev,
            "max_rel_dev": dev / abs(base) if base else (0.0 if dev == 0 else math.inf)}


def _commit() -> str:
    try:
        sha = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=ROOT, capture_output=True, text=True).stdout.strip()
        return sha + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def markdown(report: dict) -> str:
    """The tables of docs/reproducibility.md: one per job, a row per number that moves (the
    numbers that are the same in every environment are counted below the table)."""
    envs = list(report["envs"])
    lines = []
    for job, rows in report["spread"].items():
        lines += [f"#### {job}", "", "| number | " + " | ".join(envs) + " | spread |",
                  "|---|" + "---|" * (len(envs) + 1)]
        same = 0
        for key, s in rows.items():
            moved = s.get("max_abs_dev", 0) > 0 if "max_abs_dev" in s else not s["same"]
            if not moved:
                same += 1
                continue
            cells = ["" if s["values"].get(e) is None else _fmt(key, s["values"][e])
                     for e in envs]
            if "max_abs_dev" in s:
                tail = (f"±{s['max_abs_dev']:.2f}" if _is_corr(key)
                        else f"±{s['max_abs_dev']:.3g} ({100 * s['max_rel_dev']:.0f} %)")
            else:
                tail = "differs"
            lines.append(f"| {key} | " + " | ".join(cells) + f" | {tail} |")
        lines += ["", f"{same} other numbers of {job}: the same in every environment.", ""]
    return "\n".join(lines)


DOC = ROOT / "docs" / "reproducibility.md"
MEASURED = ("<!-- measured -->\n", "<!-- /measured -->")


def docs_block(report: dict) -> str:
    """The measured part of docs/reproducibility.md: when, where and with what, then the
    tables of :func:`markdown`."""
    m = report["machine"]
    kernels = ", ".join(f"{e}: {k['blas_core']} / {k['numba_cpu']}"
                        for e, k in report["kernels"].items())
    return (f"Measured {report['date']} at commit {report['commit']} by `tools/spread.py`, on "
            f"{m['cpu_model']} ({m['machine']}, 2 cores), Python {m['python_version']}, numpy "
            f"{m['numpy_version']}, scipy {m['scipy_version']}, numba {m['numba_version']}, "
            f"llvmlite {m['llvmlite_version']} (constraints.txt). OpenBLAS kernels / numba's CPU "
            f"in each environment: {kernels}. The spread column is the largest deviation from "
            "the default environment: absolute for correlations, absolute and relative "
            "otherwise.\n\n" + markdown(report))


def write_docs(report: dict, path: Path = DOC) -> None:
    """Replace the measured part of docs/reproducibility.md (between its markers)."""
    text = path.read_text(encoding="utf-8")
    start, end = text.index(MEASURED[0]) + len(MEASURED[0]), text.index(MEASURED[1])
    path.write_text(text[:start] + docs_block(report).rstrip("\n") + "\n" + text[end:],
                    encoding="utf-8")


def _is_corr(key: str) -> bool:
    return (" r " in f" {key.split(': ')[-1]}" or "corr" in key) and "corr >" not in key \
        and "corr >=" not in key


def _fmt(key: str, v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if "mm" in key:
        return f"{v:.4g}"
    return f"{v:.3f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--to", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("--jobs", default=",".join(JOBS))
    ap.add_argument("--envs", default=",".join(DEFAULT_ENVS),
                    help=f"default: {','.join(DEFAULT_ENVS)} (also: haswell)")
    ap.add_argument("--parallel", type=int, default=2, help="children at once (default 2)")
    ap.add_argument("--cache", type=Path, default=ROOT / ".spread-cache")
    ap.add_argument("--fresh", action="store_true", help="ignore the cache")
    ap.add_argument("--cached", action="store_true",
                    help="report only what the cache holds (run nothing)")
    ap.add_argument("--markdown", action="store_true", help="print the docs' tables")
    ap.add_argument("--write-docs", action="store_true",
                    help="write the tables into docs/reproducibility.md")
    ap.add_argument("-o", "--output", type=Path, help="write the JSON here too")
    ap.add_argument("--list", action="store_true", help="list the jobs and environments")
    args = ap.parse_args(argv)
    if args.child:  # the child writes its own result: an interrupted parent loses nothing
        text = json.dumps(child(args.child), indent=1)
        if args.to:
            tmp = args.to.with_suffix(".tmp")
            tmp.write_text(text)
            os.replace(tmp, args.to)
        print(text)
        return 0
    if args.list:
        print(json.dumps({"jobs": list(JOBS), "envs": ENVS, "base_env": BASE_ENV}, indent=2))
        return 0
    jobs = [j for j in args.jobs.split(",") if j]
    envs = [e for e in args.envs.split(",") if e]
    bad = [j for j in jobs if j not in JOBS] + [e for e in envs if e not in ENVS]
    if bad:
        ap.error(f"unknown job or environment: {', '.join(bad)}")
    if "default" not in envs:
        envs.insert(0, "default")
    pairs = [(j, e) for e in envs for j in jobs  # every job's default first
             if not (j in ("visemes", "speak", "gestures") and e == "perturbed")]
    if args.cached:
        pairs = [p for p in pairs if (args.cache / f"{p[0]}@{p[1]}.json").exists()]
    with ThreadPoolExecutor(max(1, args.parallel)) as pool:
        done = list(pool.map(lambda p: run_child(*p, args.cache, args.fresh), pairs))
    results = {p: r for p, r in zip(pairs, done, strict=True)}
    envs = [e for e in envs if any(p[1] == e for p in pairs)]
    sys.path.insert(0, str(ROOT / "src"))
    from facemech.io.results import numerics_attrs

    machine = {k: v for k, v in numerics_attrs().items() if k != "blas"}
    report = {"tool": "tools/spread.py", "commit": _commit(),
              "date": datetime.date.today().isoformat(), "machine": machine,
              "base_env": BASE_ENV, "envs": {e: ENVS[e] for e in envs},
              "kernels": {e: {k: next(r[k] for (_, e2), r in results.items() if e2 == e)
                              for k in ("blas_core", "numba_cpu")} for e in envs},
              "wall_s": {f"{j}@{e}": round(results[(j, e)]["wall_s"], 1) for j, e in pairs},
              "spread": {}}
    for j in jobs:
        keys = list(results[(j, "default")]["numbers"])
        report["spread"][j] = {k: spread({e: results[(j, e)]["numbers"].get(k) for e in envs
                                          if (j, e) in results}) for k in keys}
    text = json.dumps(report, indent=2)
    if args.output:
        args.output.write_text(text + "\n")
    if args.write_docs:
        write_docs(report)
    print(markdown(report) if args.markdown else text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
