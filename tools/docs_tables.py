"""Regenerate the numeric tables of docs/*.md from the commands that produce them.

A generated table sits between two HTML comments in its markdown file::

    <!-- table: experiment1 -->
    | ... the table, and one line naming the commands it came from ... |
    <!-- /table -->

Each table has one function below that formats it from the JSON output of the commands it
needs (the ``facemech`` command line with ``-o FILE.json``, or a ``benchmarks/*.py`` script that
prints JSON), run on pinned settings (:data:`RUNS`). A command shared by several tables runs once.
Nothing here imports facemech's library functions: the tables depend only on the commands' JSON,
whose keys the command line keeps stable (two constant tables of the code are the exception,
read where noted). Machine-dependent timings are never put in a generated table.

Usage::

    python tools/docs_tables.py              # rewrite every table in place (make docs)
    python tools/docs_tables.py --check      # exit 1, listing the tables that differ
    python tools/docs_tables.py --fast       # only the tables whose commands are quick
    python tools/docs_tables.py --only experiment1,visemes  [--jobs 2] [--list]
    python tools/docs_tables.py --cache DIR  # keep the commands' JSON in DIR, reuse it next time

Progress goes to stderr, one line per command and per table with the elapsed time.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# ---- the commands, on pinned settings -----------------------------------------------------


@dataclass(frozen=True)
class Run:
    """One command whose JSON output feeds one or more tables.

    ``argv`` starts with ``facemech`` (the command line, run as ``python -m facemech``) or a
    script path relative to the repository; ``{json}`` in it is replaced by a file the command
    writes, ``{dir}`` by a folder it writes (its ``summary.json`` is read), otherwise its stdout
    is parsed as JSON.
    """

    argv: tuple[str, ...]

    @property
    def shown(self) -> str:
        """The command as a user would type it."""
        words = [("python " + a if a.endswith(".py") else a) if i == 0 else a
                 for i, a in enumerate(self.argv)]
        return " ".join(w.replace("{json}", "OUT.json").replace("{dir}", "OUT") for w in words)


E1 = ("facemech", "experiment", "pitermann2001-synthetic")
E3 = ("facemech", "experiment", "pitermann2001-crosstalker")

#: every command, by name; the settings are pinned here (the experiments are deterministic:
#: no noise, no random seed; the benchmarks use fixed inputs)
RUNS: dict[str, Run] = {  # the longest first: they start first
    "realism": Run(("benchmarks/realism.py",)),
    "e3-anatomical": Run((*E3, "--preset", "anatomical", "--frames", "120", "-o", "{json}")),
    "e1-powell": Run((*E1, "--preset", "lucero1999", "--method", "powell",
                          "--no-figures", "-o", "{dir}")),
    "e1-calibrated": Run((*E1, "--preset", "calibrated", "--method", "lsq",
                          "--no-figures", "-o", "{dir}")),
    "e3-calibrated": Run((*E3, "--preset", "calibrated", "--frames", "120", "-o", "{json}")),
    "e1-anatomical": Run((*E1, "--preset", "anatomical", "--method", "lsq",
                          "--no-figures", "-o", "{dir}")),
    "visemes": Run(("benchmarks/visemes.py",)),
    "e3-lucero1999": Run((*E3, "--preset", "lucero1999", "--frames", "120", "-o", "{json}")),
    "e1-lucero1999": Run((*E1, "--preset", "lucero1999", "--method", "lsq",
                          "--no-figures", "-o", "{dir}")),
}


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("NUMBA_NUM_THREADS", "1")  # one core per command, as the docs measured
    env.setdefault("MPLBACKEND", "Agg")
    cache = Path(tempfile.gettempdir()) / "facemech-docs-cache"
    env.setdefault("MPLCONFIGDIR", str(cache))
    env.setdefault("XDG_CACHE_HOME", str(cache))
    return env


def cached(runner: Callable[[Run], dict], folder: Path) -> Callable[[Run], dict]:
    """``runner`` with its JSON kept in ``folder`` (one file per command) and reused from there:
    for re-formatting tables without running their commands again."""
    folder.mkdir(parents=True, exist_ok=True)
    names = {run: name for name, run in RUNS.items()}

    def run_or_load(run: Run) -> dict:
        path = folder / f"{names[run]}.json"
        if path.exists():
            log(f"run {names[run]}: reused {path}")
            return json.loads(path.read_text())
        res = runner(run)
        write_atomic(path, json.dumps(res))
        return res
    return run_or_load


def run_command(run: Run) -> dict:
    """Run one command and return its JSON output (a RuntimeError naming it if it fails)."""
    with tempfile.TemporaryDirectory(prefix="facemech-docs-") as tmp:
        out = Path(tmp) / "out.json"
        folder = Path(tmp) / "out"
        argv = [str(out) if a == "{json}" else str(folder) if a == "{dir}" else a
                for a in run.argv]
        if argv[0] == "facemech":
            argv = [sys.executable, "-m", "facemech", *argv[1:]]
        else:
            argv = [sys.executable, str(ROOT / argv[0]), *argv[1:]]
        proc = subprocess.run(argv, cwd=tmp, env=_child_env(), capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"`{run.shown}` failed ({proc.returncode}):\n"
                               f"{proc.stderr[-2000:]}")
        if "{dir}" in run.argv:  # a command that writes a folder: its summary.json
            return json.loads((folder / "summary.json").read_text())
        return json.loads(out.read_text() if "{json}" in run.argv else proc.stdout)


# ---- formatting ----------------------------------------------------------------------------

def corr(x: float | None) -> str:
    """A correlation as the papers print it: .78, -.08 (two decimals, no leading zero)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    s = f"{x:.2f}"
    return s.replace("0.", ".", 1) if abs(x) < 0.995 else s


def fixed(x: float, nd: int) -> str:
    s = f"{x:.{nd}f}"
    return s[1:] if s.startswith("-") and float(s) == 0 else s  # no "-0.00"


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


#: each preset's fast step, s (what the experiments use without --dt; the Experiment 3 command
#: does not write it to its JSON)
FAST_DT = {"anatomical": 1.0 / 240.0, "lucero1999": 1e-3, "calibrated": 0.33e-3}


def step_label(preset: str, dt_s: float | None = None) -> str:
    dt_s = FAST_DT[preset] if dt_s is None else dt_s
    kind = {"anatomical": "implicit"}.get(preset, "Euler")
    return f"{dt_s * 1e3:.2g} ms {kind}"


def preset_label(preset: str) -> str:
    return "**anatomical** (default)" if preset == "anatomical" else preset


# ---- the tables ----------------------------------------------------------------------------

TABLE1 = ("LLS", "LAO", "DAO", "DLI", "MEN", "OOS", "OOI")


def _e1_row(preset: str, res: dict, label: str) -> list[str]:
    r = res["runs"][label]
    t2 = {m: v["published"] for m, v in r["table2_corr3d"].items()}
    low = min(t2, key=lambda m: t2[m])
    e = r["table3_frame_error_mm"]
    method, constraint = label.split(", ")
    return [f"{preset_label(preset)}, {step_label(preset, res['dt_s'])}",
            f"{method}, {'none' if constraint == 'no constraint' else constraint}",
            " ".join(corr(r["table1_activity_correlation"][c]) for c in TABLE1),
            f"{r['corr3d_at_least_0.95']} / {r['corr3d_above_0.8']}, {low} {t2[low]:.2f}",
            f"{e['median']:.3f} / {e['max']:.3f} mm", str(r["evaluations"]),
            f"{r['movement_mm']:.3g} mm"]


E1_HEADER = ["preset, step", "method, constraint",
             "Table I activity correlations (LLS LAO DAO DLI MEN OOS OOI)",
             "3-D corr. >= 0.95 / > 0.8 (of 19), lowest", "per-frame error median / max",
             "frame steps", "movement"]


def experiment1(out: dict) -> str:
    rows = [_e1_row(p, out[f"e1-{p}"], label) for p in ("anatomical", "lucero1999")
            for label in ("lsq, no constraint", "lsq, positive")]
    paper = out["e1-lucero1999"]["paper"]
    a = paper["activity_correlations_no_constraint"]
    m = paper["median_error_mm"]
    rows.append(["paper (Powell)", "",
                 " ".join(corr(a[c]) for c in TABLE1) + " (none)",
                 f"> 0.8 in {paper['kinematic_corr_above_0.8']}",
                 f"{m['no_constraint']} / {m['positive']} mm (medians: none / positive)", "",
                 f"{paper['movement_mm']} mm"])
    return table(E1_HEADER, rows)


def experiment1_slow(out: dict) -> str:
    """The slower runs: Powell under lucero1999, least squares under calibrated (0.33 ms)."""
    return table(E1_HEADER, [
        *(_e1_row("lucero1999", out["e1-powell"], label)
          for label in ("powell, no constraint", "powell, positive")),
        *(_e1_row("calibrated", out["e1-calibrated"], label)
          for label in ("lsq, no constraint", "lsq, positive"))])


def experiment3(out: dict) -> str:
    rows = []
    for p in ("anatomical", "lucero1999", "calibrated"):
        res = out[f"e3-{p}"]
        for label, r in res["runs"].items():
            c = r["table6_corr3d"]
            e = r["frame_error_mm"]
            adaptation = {"scaling": "per-axis scaling",
                          "warp": "thin-plate-spline warp"}[label.rsplit(", ", 1)[1]]
            rows.append([f"{preset_label(p)}, {step_label(p, res.get('dt_s'))}", adaptation,
                         f"{min(c.values()):.2f}-{max(c.values()):.2f}",
                         f"{c['upper_lip_center']:.2f}",
                         f"{e['median']:.2f} / {e['max']:.2f} mm",
                         f"{r['movement_mm']:.2f} mm"])
    rows.append(["paper (scaling)", "", "mostly 0.75-0.97", "poor", "", ""])
    return table(["preset, step", "adaptation", "3-D correlations", "upper lip centre",
                  "median / max per-frame error", "movement"], rows)


GESTURE_COLUMNS = (("corner_up", "corner up"), ("corner_out", "corner out"),
                   ("upper_lip_up", "upper lip up"), ("lower_lip_down", "lower lip down"),
                   ("chin_up", "chin up"), ("lower_lip_forward", "lower lip forward"),
                   ("mouth_narrower", "mouth narrower"), ("lips_forward", "lips forward"),
                   ("largest", "largest"))
#: mentalis's minimum is chin up 1.5 mm *or* lower lip forward 2 mm
#: (facemech.analysis.gestures.check_targets); the rest come with the benchmark's JSON
GESTURE_OR_TARGET = {("MEN", "lower_lip_forward"): 2.0}


def gestures(out: dict) -> str:
    g = out["realism"]["gestures"]
    need = {(t["groups"], t["measure"]): t["at_least"] for t in g["targets"]}
    need.update(GESTURE_OR_TARGET)
    rows = []
    for name, anat in g["anatomical"].items():
        seeds = g["lucero1999"][name]
        cells = [name]
        for key, _ in GESTURE_COLUMNS:
            cell = f"{fixed(anat[key], 1)} / {fixed(seeds[key], 2)}"
            if (name, key) in need:
                v = need[(name, key)]
                cell = (f"**{fixed(anat[key], 1)}** / {fixed(seeds[key], 2)} "
                        f"({'>=' if v >= 0 else '<='} {v:g})")
            cells.append(cell)
        rows.append(cells)
    return table(["group", *(h for _, h in GESTURE_COLUMNS)], rows)


#: the rows of the resolution table: (benchmark key, label)
RESOLUTION_ROWS = ("ZYG corner_up", "ZYG corner_out", "LAO corner_up", "DAO corner_up",
                   "RIS corner_out", "LLS upper_lip_up", "DLI lower_lip_down", "MEN chin_up",
                   "OOS+OOI mouth_narrower", "OOS+OOI lips_forward")


def resolutions(out: dict) -> str:
    res = out["realism"]["resolutions"]
    rows = []
    for key in RESOLUTION_ROWS:
        r = res[key]
        v = r["coarse_default_fine_mm"]
        rows.append([key.replace("_", " "), " / ".join(f"{x:.2f}" for x in v),
                     f"{r['spread_percent']:.1f} %"])
    return table(["gesture, measure", "coarse / default / fine (mm)", "spread"], rows)


def dynamics(out: dict) -> str:
    d = out["realism"]["dynamics"]
    coarse, fine = d["preset_steps"], d["8x_finer_steps"]
    rows = []
    for name, a in coarse.items():
        b = fine[name]
        rows.append([name.replace("_", " "),
                     f"{a['rise_ms_at_0.3']:.0f} / {b['rise_ms_at_0.3']:.0f} ms",
                     f"{a['rise_ms_at_1.0']:.0f} / {b['rise_ms_at_1.0']:.0f} ms",
                     f"{a['final_mm_at_1.0']:.1f}", f"{a['pulse_peak_mm']:.1f}",
                     f"{a['overshoot_past_rest_percent']:g} %"])
    return table(["group (landmark)", "rise at 0.3, 4 / 32 steps", "rise at 1.0, 4 / 32 steps",
                  "final at 1.0 (mm)", "pulse peak (mm)", "overshoot"], rows)


def _num(x: float) -> str:
    return f"{x:g}"


def visemes(out: dict) -> str:
    # the targets' activity and dominance are constants of the code (read from it, so that
    # they cannot drift either); the measured columns come from the benchmark
    from facemech.speech.visemes import VISEMES

    measured = out["visemes"]["targets"]
    rows = []
    for cls, v in VISEMES.items():
        m = measured[cls]
        jaw = math.degrees(v.jaw)
        if cls == "pause":
            rows.append([cls, "- (rest)", "0", "/".join(_num(x) for x in (
                v.lips_dominance, v.jaw_dominance, v.anticipatory_rate, v.carryover_rate)),
                "0", "0", "0", "0", "0"])
            continue
        act = " ".join(f"{g} {_num(a)}" for g, a in v.activity.items()) or "-"
        jaw_cell = (f"{round(jaw, 1):g} (virtual, held at 0)" if jaw < 0 else f"{jaw:.1f}")
        dom = "/".join(_num(x) for x in (v.lips_dominance, v.jaw_dominance,
                                         v.anticipatory_rate, v.carryover_rate))
        rows.append([cls, act, jaw_cell, dom,
                     fixed(m["lip_gap_mm"], 2), fixed(m["upper_forward_mm"], 2),
                     fixed(m["lower_forward_mm"], 2), f"{m['width_change_mm']:+.2f}",
                     fixed(m["incisor_drop_mm"], 1)])
    return table(["class", "activity", "jaw °", "dominance", "gap mm", "upper fwd",
                  "lower fwd", "width mm", "incisor mm"], rows)


#: the rows of the lag table: (benchmark key, label, how the size at the centre is put)
LAG_ROWS = (("_ u: _ (lips_forward)", "_ u: _, both lips forward", "{:.1f} mm forward"),
            ("_ i: _ (width_change)", "_ i: _, mouth width", "{:.1f} mm wider"),
            ("_ A: _ (lip_gap)", "_ A: _, lip gap (jaw-driven)", "{:.1f} mm open"),
            ("A: b A: (lip_gap)", "A: b A:, middle of the closure (gap < 0.5 mm)", "gap {:.2f} mm"),
            ("u: m u: (lip_gap)", "u: m u: (m of 160 ms)", "gap {:.2f} mm"))


#: a closure found further than this from the phone's centre (ms) is the rest around the
#: utterance (the lips meet at rest), not the phone's own: the phone never closed the lips
CLOSURE_REACH_MS = 200.0


def _lag_cell(r: dict, fmt: str) -> str:
    lag = r["visible_lag_ms"]
    size = fmt.format(r["at_acoustic_centre_mm"]) + " at the centre"
    if lag is None or (isinstance(lag, float) and math.isnan(lag)):
        return f"never closes ({size})"
    if fmt.startswith("gap") and abs(lag) > CLOSURE_REACH_MS:
        return f"never closes ({size}; the nearest closure is the rest, {lag:+.0f} ms)"
    return f"{lag:+.0f} ms ({size})"


def visemes_lag(out: dict) -> str:
    v = out["visemes"]
    rows = [[label, _lag_cell(v["lag_without_lead"][key], fmt),
             _lag_cell(v["lag_with_lead"][key], fmt)] for key, label, fmt in LAG_ROWS]
    return table(["case", "without lead", "with the leads (100 ms muscles, 33 ms jaw)"], rows)


@dataclass(frozen=True)
class Table:
    """A generated table: its name (the marker's), file, commands, formatter and speed, and how
    far its numbers may move (``tolerance``: (column, absolute, relative) triples; a column not
    named is compared as text, exactly; see :func:`differences`)."""

    name: str
    doc: str
    runs: tuple[str, ...]
    render: Callable[[dict], str]
    slow: bool = False  # left out of --fast (and of the default test run)
    tolerance: tuple[tuple, ...] = ()


#: how far the numbers of the checked tables may move (:func:`differences`). tools/spread.py
#: measured Experiment 1 the same under this machine's OpenBLAS kernels, Prescott's, Nehalem's
#: and with the markers moved by 1e-12, to 1e-6 (docs/reproducibility.md, since the skull band
#: and the contacts stepped on their own): the bounds are issue 32's, activity correlations and
#: the lowest 3-D correlation +-0.02 (the 3-D counts exactly), median and largest errors 10 %
#: (at least 0.0005 mm, half the printed digit), frame steps 5 %, the synthetic movement 1 %
E1_TOLERANCE = ((2, 0.02, 0.0), (3, 0.02, 0.0), (4, 0.0005, 0.10), (5, 0.0, 0.05),
                (6, 0.0, 0.01))
#: the viseme targets: lip gap, protrusion and width by up to 0.09 mm (a bilabial's closure)
VISEMES_TOLERANCE = tuple((c, 0.15, 0.0) for c in (4, 5, 6, 7))
#: the lags: 6 ms and 0.12 mm; /m/ between two /u:/ with the leads sits at the closure's
#: threshold (a gap of 0.54 to 0.77 mm at its centre), its closure found anywhere from -147 to
#: +20 ms
VISEMES_LAG_TOLERANCE = ((1, 0.15, 0.10), (2, 0.15, 0.10), (2, 250.0, 0.0, "u: m u:"))

TABLES: tuple[Table, ...] = (
    Table("experiment1", "docs/inversion.md", ("e1-anatomical", "e1-lucero1999"), experiment1,
          tolerance=E1_TOLERANCE),
    Table("experiment1-slow", "docs/inversion.md", ("e1-powell", "e1-calibrated"),
          experiment1_slow, slow=True),
    Table("experiment3", "docs/inversion.md", ("e3-anatomical", "e3-lucero1999",
                                               "e3-calibrated"), experiment3, slow=True),
    Table("gestures", "docs/model.md", ("realism",), gestures, slow=True),
    Table("resolutions", "docs/model.md", ("realism",), resolutions, slow=True),
    Table("dynamics", "docs/model.md", ("realism",), dynamics, slow=True),
    Table("visemes", "docs/stimuli.md", ("visemes",), visemes, tolerance=VISEMES_TOLERANCE),
    Table("visemes-lag", "docs/stimuli.md", ("visemes",), visemes_lag,
          tolerance=VISEMES_LAG_TOLERANCE),
)


#: how the line naming a block's numerical environment starts: provenance (library versions,
#: the CPU numba compiled for, OpenBLAS's kernels), which differs from machine to machine and is
#: therefore never compared by :func:`differences`
ENV_PREFIX = "<sub>Made with "

_ENVIRONMENT: dict[str, str] = {}


def environment_line() -> str:
    """The line naming the numerical environment the tables are made in, read once from a child
    process of the commands' own environment (``facemech.io.results.numerics_attrs``, as every
    results file records it). Cached JSON (``--cache``) made elsewhere keeps this machine's line:
    keep a cache to one machine."""
    if "line" not in _ENVIRONMENT:
        code = ("import json; from facemech.io.results import numerics_attrs; "
                "print(json.dumps(numerics_attrs()))")
        try:
            proc = subprocess.run([sys.executable, "-c", code], env=_child_env(), text=True,
                                  capture_output=True, timeout=300, check=True)
            a = json.loads(proc.stdout)
            _ENVIRONMENT["line"] = (
                f"{ENV_PREFIX}Python {a['python_version']}, numpy {a['numpy_version']}, scipy "
                f"{a['scipy_version']}, numba {a['numba_version']} (kernels compiled for "
                f"{a['numba_cpu']}), OpenBLAS kernels {a['blas_core']}, on {a['cpu_model']} "
                f"({a['machine']}).</sub>")
        except (OSError, subprocess.SubprocessError, ValueError, KeyError) as e:
            _ENVIRONMENT["line"] = f"{ENV_PREFIX}an environment that could not be read ({e}).</sub>"
    return _ENVIRONMENT["line"]


def block(t: Table, outputs: dict[str, dict]) -> str:
    """The generated block: the table (from ``outputs``, run name -> JSON), one line naming
    its commands and one naming the numerical environment (:func:`environment_line`)."""
    cmds = "; ".join(f"`{RUNS[r].shown}`" for r in t.runs)
    return (f"{t.render(outputs)}\n\n"
            f"<sub>Generated by `make docs` (tools/docs_tables.py, checked by "
            f"tests/docs/test_docs_tables.py) from {cmds}.</sub>\n{environment_line()}")

# ---- markdown ------------------------------------------------------------------------------

MARKER = re.compile(r"(<!-- table: ([\w-]+) -->\n)(.*?)(<!-- /table -->)", re.S)


#: a number in a table's cell: not part of a word (a marker name as R11), e.g. .77, -0.02, +5.38
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?![\w.])")


def differences(doc: str, new: str, tolerance=()) -> list[str]:
    """Where a table in the docs (``doc``) and the same table generated anew (``new``) differ
    by more than ``tolerance`` allows: one line per cell that differs (none: they match).

    ``tolerance`` holds (column, absolute, relative) triples, or (column, absolute, relative,
    row) quadruples for the rows whose first cell starts with ``row`` (these take precedence):
    in a table row, the numbers of such a column (:data:`NUMBER`) match when each pair differs
    by at most ``max(absolute, relative * |docs' value|)``, and the words between them are not
    compared (the marker with the lowest correlation may change with the numbers). Every other
    cell and line is compared as text. The last bits of the inversions' and simulations'
    numbers depend on the BLAS kernels, threads and CPU (docs/reproducibility.md): the
    tolerances of :data:`TABLES` come from that spread.
    """
    general = {t[0]: (t[1], t[2]) for t in tolerance if len(t) == 3}
    by_row = [(t[3], t[0], (t[1], t[2])) for t in tolerance if len(t) == 4]
    old_lines, new_lines = doc.strip("\n").splitlines(), new.strip("\n").splitlines()
    if len(old_lines) != len(new_lines):
        return [f"{len(old_lines)} lines in the docs, {len(new_lines)} generated"]
    out = []
    for n, (a, b) in enumerate(zip(old_lines, new_lines, strict=True)):
        if a == b or (a.startswith(ENV_PREFIX) and b.startswith(ENV_PREFIX)):
            continue
        if not (a.startswith("|") and b.startswith("|")):
            out.append(f"line {n + 1}: {a!r} != {b!r}")
            continue
        ca, cb = a.strip().strip("|").split("|"), b.strip().strip("|").split("|")
        if len(ca) != len(cb):
            out.append(f"line {n + 1}: {len(ca)} cells in the docs, {len(cb)} generated")
            continue
        tol = dict(general)
        tol.update({c: t for row, c, t in by_row if ca[0].strip().startswith(row)})
        for c, (x, y) in enumerate(zip(ca, cb, strict=True)):
            if x == y:
                continue
            if c not in tol:
                out.append(f"line {n + 1}, column {c + 1}: {x.strip()!r} != {y.strip()!r}")
                continue
            nx, ny = NUMBER.findall(x), NUMBER.findall(y)
            absolute, relative = tol[c]
            if len(nx) != len(ny) or any(
                    abs(float(v) - float(u)) > max(absolute, relative * abs(float(u))) + 1e-12
                    for u, v in zip(nx, ny, strict=True)):
                out.append(f"line {n + 1}, column {c + 1}: {x.strip()!r} != {y.strip()!r} "
                           f"(beyond {absolute:g} or {relative:.0%})")
    return out


def find_tables(text: str) -> dict[str, str]:
    """Every marked table of a markdown text: name -> the text between the markers."""
    return {m.group(2): m.group(3) for m in MARKER.finditer(text)}


def replace_tables(text: str, blocks: dict[str, str]) -> str:
    """The text with the marked tables named in ``blocks`` replaced (others kept)."""
    def sub(m: re.Match) -> str:
        name = m.group(2)
        if name not in blocks:
            return m.group(0)
        return m.group(1) + blocks[name].rstrip("\n") + "\n" + m.group(4)
    return MARKER.sub(sub, text)


def write_atomic(path: Path, text: str) -> None:
    """Write through a temporary file in the same folder, then rename."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


# ---- running -------------------------------------------------------------------------------

def log(msg: str) -> None:
    print(f"docs: {msg}", file=sys.stderr, flush=True)


def select(only: list[str] | None = None, fast: bool = False) -> list[Table]:
    names = {t.name for t in TABLES}
    for n in only or ():
        if n not in names:
            raise SystemExit(f"docs: no table {n!r} (have: {', '.join(sorted(names))})")
    return [t for t in TABLES if (not only or t.name in only) and not (fast and t.slow)]


def generate(tables: list[Table], jobs: int = 2,
             runner: Callable[[Run], dict] | None = None) -> dict[str, str]:
    """Run the commands the tables need (each once, ``jobs`` at a time; ``runner`` defaults to
    :func:`run_command`) and format the tables: name -> generated block. Prints a line per
    command and per table with elapsed times."""
    runner = runner or run_command
    t0 = time.perf_counter()
    wanted = {r for t in tables for r in t.runs}
    needed = [r for r in RUNS if r in wanted]
    results: dict[str, dict] = {}
    took: dict[str, float] = {}
    done: dict[str, threading.Event] = {r: threading.Event() for r in needed}

    def one(name: str) -> None:
        start = time.perf_counter()
        log(f"run {name}: {RUNS[name].shown}")
        try:
            results[name] = runner(RUNS[name])
        finally:
            took[name] = time.perf_counter() - start
            log(f"run {name}: {took[name]:.1f} s (elapsed {time.perf_counter() - t0:.1f} s)")
            done[name].set()

    blocks: dict[str, str] = {}
    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = [pool.submit(one, n) for n in needed]
        for t in tables:
            for r in t.runs:
                done[r].wait()
            for f in futures:  # a failed command ends the run with its error
                if f.done() and f.exception() is not None:
                    raise f.exception()
            blocks[t.name] = block(t, results)
            log(f"table {t.name} ({t.doc}): commands {sum(took[r] for r in t.runs):.1f} s "
                f"(elapsed {time.perf_counter() - t0:.1f} s)")
    return blocks


def apply(blocks: dict[str, str], tables: list[Table], check: bool) -> list[str]:
    """Write the blocks into their files (or only compare, ``check``): the tables that differ."""
    differ = []
    for doc in dict.fromkeys(t.doc for t in tables):
        path = ROOT / doc
        text = path.read_text(encoding="utf-8")
        present = find_tables(text)
        mine = {t.name: blocks[t.name] for t in tables if t.doc == doc}
        for name, new in mine.items():
            if name not in present:
                raise SystemExit(f"docs: {doc} has no marker <!-- table: {name} -->")
            table_of = next(t for t in tables if t.name == name)
            if (differences(present[name], new, table_of.tolerance) if check
                    else present[name].rstrip("\n") != new.rstrip("\n")):
                differ.append(f"{doc}: {name}")
                if check:
                    sys.stderr.writelines(difflib.unified_diff(
                        present[name].splitlines(True), (new + "\n").splitlines(True),
                        f"{doc} ({name}, now)", f"{name} (generated)"))
        if not check:
            new_text = replace_tables(text, mine)
            if new_text != text:
                write_atomic(path, new_text)
    return differ


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 if any differs")
    ap.add_argument("--fast", action="store_true", help="only the tables with quick commands")
    ap.add_argument("--only", help="comma-separated table names")
    ap.add_argument("--jobs", type=int, default=2, help="commands run at once (default 2)")
    ap.add_argument("--list", action="store_true", help="list the tables and their commands")
    ap.add_argument("--cache", type=Path, help="keep each command's JSON in this folder and "
                    "reuse what is there (default: always run the commands)")
    args = ap.parse_args(argv)
    tables = select(args.only.split(",") if args.only else None, args.fast)
    if args.list:
        for t in tables:
            print(f"{t.name}{' (slow)' if t.slow else ''}: {t.doc}: "
                  + "; ".join(RUNS[r].shown for r in t.runs))
        return 0
    blocks = generate(tables, jobs=args.jobs,
                      runner=cached(run_command, args.cache) if args.cache else None)
    differ = apply(blocks, tables, check=args.check)
    verb = "differ" if args.check else "updated"
    log(f"{len(differ)} of {len(tables)} tables {verb}" + "".join(f"\n  {d}" for d in differ))
    return 1 if args.check and differ else 0


if __name__ == "__main__":
    sys.exit(main())
