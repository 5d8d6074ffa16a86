"""The ``facemech`` command line: each command parses its options, makes one call into the
library (:mod:`facemech.workflows`) and prints what it did; bad input: one line, exit 2."""

from __future__ import annotations

import contextlib
import importlib
import json
import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console

from .errors import FacemechError, InputError

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Physics and kinematics of the speaking face.")
face_app, emg_app, markers_app, experiment_app = _subs = [typer.Typer(
    no_args_is_help=True, help=h) for h in ("Build and inspect face models.", "Process EMG "
    "recordings.", "Read, convert and clean marker data.", "The seeds' experiments, reproduced.")]
for _sub, _name in zip(_subs, ("face", "emg", "markers", "experiment"), strict=True):
    app.add_typer(_sub, name=_name)
err, out = Console(stderr=True), Console(soft_wrap=True)


def opt(default, help: str, *names: str, **kw):
    """A typer option: its default (``...``: required), help and names."""
    return typer.Option(default, *names, help=help, **kw)


class _Workflows:
    """``wf.markers`` is :mod:`facemech.workflows.markers`, imported on first use."""

    def __getattr__(self, name: str):
        return importlib.import_module(f"facemech.workflows.{name}")


wf, progress = _Workflows(), importlib.import_module("facemech.progress")
_log: list = []  # the running command's log lines (output not a terminal)


def _version(value: bool) -> None:
    if value:
        print(f"facemech {importlib.import_module('facemech._version').__version__}")
        raise typer.Exit()


@app.callback()
def _root(ctx: typer.Context, version: bool = opt(False, "print the version", "--version",
                                                  callback=_version, is_eager=True)) -> None:
    """Physics and kinematics of the speaking face."""
    if not err.is_terminal:  # log lines, and a heartbeat for the whole command
        _log[:] = [ctx.with_resource(progress.LogProgress(ctx.invoked_subcommand or "facemech"))]
        ctx.call_on_close(_log.clear)


PresetOpt = Annotated[str, typer.Option(help="anatomical, lucero1999, pitermann2001, calibrated "
                                        "or a preset .json")]
FaceOpt = Annotated[str, typer.Option(help="face .npz, default, default-coarse or default-fine")]
ViewOpt = Annotated[str, typer.Option(help="frontal, profile, three-quarter, mouth, "
                                      "frontal+profile")]
SizeOpt = Annotated[str, typer.Option(help="frame size WIDTHxHEIGHT, pixels")]
BackgroundOpt = Annotated[str, typer.Option(help="'#rrggbb', 'r,g,b' or 'transparent' (PNG)")]
AAOpt = Annotated[int, typer.Option("--aa", help="anti-aliasing: samples per pixel and axis, 1-4")]
UnitsOpt = Annotated[str | None, typer.Option("--units", help="length unit if the file has none")]
JsonOpt = Annotated[bool, typer.Option("--json", help="print JSON")]
IntegratorOpt = Annotated[str | None, typer.Option(help="euler, implicit or rosenbrock")]
RateOpt = Annotated[float | None, typer.Option(help="rate, Hz (default: the frame rate)")]
OutOpt = Annotated[Path, typer.Option("-o", "--output", help="the output (file or folder)")]
Result = Annotated[Path, typer.Argument(help="results file (.nc)")]
Source = Annotated[Path, typer.Argument(help="input marker file")]


def _progress():
    """Bars on a terminal, else the command's log lines with their heartbeat."""
    if not err.is_terminal:
        return _log[-1] if _log else progress.LogProgress()
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/"
                    "{task.total}"), TimeElapsedColumn(), console=err, transient=True)


@contextlib.contextmanager
def _staged_progress():
    """A progress display with one bar per stage; yields report(stage, done, total)."""
    with _progress() as prog:
        yield progress.staged(prog)


def _render_options(view: str, size: str, background: str, aa: int):
    return wf.pictures.render_options(view, size, background, aa)


# ---------------------------------------------------------------------------------------------
@app.command()
def demo(output: OutOpt = Path("demo-output"), integrator: IntegratorOpt = None,
         video: bool = opt(True, "render the MP4"), preset: PresetOpt = "anatomical",
         view: ViewOpt = "frontal+profile", size: SizeOpt = "1280x720",
         background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2):
    """Simulate a synthetic utterance on the built-in face; write results, plots and a movie."""
    with _staged_progress() as report:
        out.print(wf.demo.run(output, integrator=integrator, video=video, preset=preset,
                              progress=report, render=_render_options(view, size, background, aa)))

@face_app.command("build")
def face_build(surface: Path = typer.Argument(..., help="OBJ (+ MTL, texture), PLY or STL"),
               landmarks: Path = typer.Argument(..., help="landmark CSV: name,x,y,z"),
               output: OutOpt = ..., units: str = opt("mm", "length unit of both files"),
               name: str = opt(None, "model name"), tissue: str = opt("anatomical", "or uniform")):
    """Build a three-layer face model from a surface mesh (a textured OBJ or a coloured PLY
    keeps its look) and landmarks."""
    with _staged_progress() as report:
        out.print(wf.faces.build_face_file(surface, landmarks, output, units=units, name=name,
                                           tissue=tissue, progress=report))

@face_app.command("info")
def face_info(face: str = typer.Argument("default", help="face file or built-in face"),
              as_json: JsonOpt = False, tissue: str = opt(None, "anatomical or uniform")):
    """Counts of a face model: nodes per layer, springs by kind, prisms, muscles, free fascia."""
    out.print(wf.faces.face_info(face, tissue=tissue).text(as_json), markup=False)

@face_app.command("export-default")
def face_export_default(output: OutOpt):
    """Write the built-in face's surface (OBJ, mm) and landmarks (CSV, mm) as a template."""
    out.print("wrote {} and {}".format(*wf.faces.export_default_face(output)))

@emg_app.command("process")
def emg_process(emg: Path = typer.Argument(..., help="raw EMG: CSV or C3D"), output: OutOpt = ...,
                rate: RateOpt = None, baseline: str = opt(None, "rest interval START,STOP (s)"),
                calibration: Path = opt(None, "recording of maximal gestures"),
                calibration_baseline: str = opt(None, "its rest interval START,STOP (s)")):
    """Rectify, integrate (17-ms trapezoid), downsample and normalise EMG to activity in [0, 1]."""
    out.print(wf.emg.process_emg_file(emg, output, rate=rate, baseline=baseline,
              calibration=calibration, calibration_baseline=calibration_baseline))

@markers_app.command("info")
def markers_info(path: Source, units: UnitsOpt = None, as_json: JsonOpt = False):
    """Rate, units, markers and gaps of a marker file (.c3d, .trc, .csv or .tsv)."""
    out.print(wf.markers.marker_info(path, units=units).text(as_json), markup=False)

@markers_app.command("convert")
def markers_convert(source: Source, target: Path = typer.Argument(None, help="or -o"),
                    output: OutOpt = None, units: UnitsOpt = None,
                    out_units: str = opt(None, "unit of the output (default: the input's)")):
    """Convert between C3D, TRC and CSV (read Qualisys TSV and a results file's markers)."""
    out.print(wf.markers.convert_markers(source, output or target, units=units,
                                         out_units=out_units))

@markers_app.command("head-correct")
def markers_head_correct(source: Source, output: OutOpt, units: UnitsOpt = None,
                         head: str = opt(..., "comma-separated head markers (at least 3)"),
                         reference: int = opt(None, "reference frame (default: first full)"),
                         report: Path = opt(None, "write the per-frame residuals (JSON)")):
    """Remove head motion by a per-frame rigid fit of head markers to a reference frame."""
    res = wf.markers.head_correct_file(source, output, head, reference=reference, units=units,
                                       report=report)
    out.print(res)
    err.print(res.warnings, end="")

@markers_app.command("resample")
def markers_resample(source: Source, output: OutOpt, rate: RateOpt = None, units: UnitsOpt = None):
    """Resample to a new rate with anti-aliasing (gaps stay gaps)."""
    out.print(wf.markers.resample_file(source, output, rate=rate, units=units))

@markers_app.command("frame")
def markers_frame(source: Source, output: OutOpt, right: str = opt(..., "marker on the right"),
                  left: str = opt(..., "marker on the left"), units: UnitsOpt = None,
                  front: str = opt(..., "marker in front, on the same plane"),
                  origin: str = opt(None, "origin marker (default: --front)"),
                  reference: int = opt(0, "frame the axes are taken from")):
    """Express markers in an anatomical frame: +x right->left, +y up, +z forward."""
    out.print(wf.markers.frame_file(source, output, right=right, left=left, front=front,
                                    origin=origin, reference=reference, units=units))

@markers_app.command("fill-gaps")
def markers_fill_gaps(source: Source, output: OutOpt, units: UnitsOpt = None,
                      max_gap: float = opt(0.1, "longest gap to fill, s")):
    """Fill interior gaps up to --max-gap with a cubic spline; filled samples are flagged."""
    res = wf.markers.fill_gaps_file(source, output, max_gap=max_gap, units=units)
    out.print(res)
    err.print(res.warnings, end="")

@app.command()
def simulate(
    output: OutOpt, face: FaceOpt = "default", activity: Path = opt(None, "activity CSV"),
    emg: Path = opt(None, "raw EMG (CSV or C3D), 7 channels"), units: UnitsOpt = None,
    emg_baseline: str = opt(None, "EMG rest interval START,STOP (s)"),
    emg_calibration: Path = opt(None, "EMG of maximal gestures"),
    jaw_chin: Path = opt(None, "marker file with the chin marker"),
    chin_marker: str = opt("R01", "the chin marker"),
    jaw_second_marker: str = opt(None, "a second mandible marker in the --jaw-chin file"),
    jaw_angle: Path = opt(None, "CSV: time, jaw_angle (rad) or jaw_angle_deg"),
    bite_block: bool = opt(False, "hold the jaw at its initial pose"),
    jaw_kinematics: str = opt(None, "hinge or glide"), preset: PresetOpt = "anatomical",
    integrator: IntegratorOpt = None, substeps: int = opt(None, "steps per frame (implicit)"),
    dt: float = opt(None, "explicit Euler step, s"), jaw_drive: str = opt("ramp", "ramp or hold"),
    video: Path = opt(None, "also render an MP4 (or PNG frames into a folder)"),
    audio: Path = opt(None, "WAV to mux into the MP4"), view: ViewOpt = "frontal+profile",
    size: SizeOpt = "1280x720", background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2,
):
    """Simulate the face driven by muscle activity or EMG and a jaw trajectory."""
    sim, movie = wf.simulate, video and (video, audio, _render_options(view, size, background, aa))
    with _staged_progress() as report:
        out.print(sim.simulate_files(
            output, sim.Controls(activity, emg, emg_baseline, emg_calibration),
            sim.JawSource(jaw_angle, jaw_chin, chin_marker, jaw_second_marker, units, bite_block),
            face=face, preset=preset, jaw_kinematics=jaw_kinematics, integrator=integrator,
            substeps=substeps, dt=dt, jaw_drive=jaw_drive, movie=movie, progress=report))

@app.command()
def render(result: Result, output: OutOpt, audio: Path = opt(None, "WAV to mux in"),
           view: ViewOpt = "frontal+profile", size: SizeOpt = "1280x720",
           background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2):
    """Render a results file to an H.264 MP4 or PNG frames (-o a folder), with eyes and teeth."""
    with _staged_progress() as report:
        out.print(wf.pictures.render_movie(result, (output, audio, _render_options(
            view, size, background, aa)), progress=report))

@app.command()
def still(result: Result, output: OutOpt, time: float = opt(None, "time of the frame, s"),
          peak: str = opt(None, "frame of a peak: a muscle group (e.g. OOS), jaw or motion"),
          markers: bool = opt(False, "draw the model's markers"), view: ViewOpt = "frontal",
          labels: bool = opt(False, "name the markers"), size: SizeOpt = "1280x1280",
          background: BackgroundOpt = "#ffffff", aa: AAOpt = 3):
    """A still figure for a paper: one frame at a time or at a gesture's peak (PNG or PDF)."""
    out.print(wf.pictures.still_file(result, output, time=time, peak=peak, markers=markers,
              labels=labels, options=_render_options(view, size, background, aa)))

@app.command()
def export(result: Result, output: OutOpt, units: UnitsOpt = None,
           fmt: str = opt(None, "obj or ply: one mesh per frame in the folder -o", "--format")):
    """Export a result: animated skin as glTF (.glb), a mesh per frame (OBJ/PLY, -o a folder),
    or markers (.trc, .c3d, .csv). --units: meshes m (default) or mm, markers mm (default)."""
    out.print(wf.pictures.export_file(result, output, fmt=fmt, units=units))

@app.command()
def plot(result: Result, output: OutOpt, units: UnitsOpt = None,
         markers: str = opt("R03,R05,R07", "comma-separated marker names"),
         measured: Path = opt(None, "measured markers (same names)")):
    """Plot displacement and acceleration (vertical, protrusion) of markers, like Figs. 4-6."""
    out.print(wf.pictures.plot_file(result, output, markers, measured=measured, units=units))

@app.command()
def view(result: Result, output: OutOpt, units: UnitsOpt = None,
         markers: Path = opt(None, "measured markers in the model's frame, drawn beside its own"),
         title: str = opt(None, "page title")):
    """Write an interactive viewer: one self-contained HTML page (WebGL, works offline)."""
    out.print(wf.pictures.view_file(result, output, markers=markers, units=units, title=title))


@app.command()
def speak(
    text: Annotated[str | None, typer.Argument(help="what to say (or --audio with --textgrid)")]
    = None,
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")]
    = Path("speak-output"),
    audio: Annotated[Path | None, typer.Option(help="a recorded voice (WAV) to speak with")]
    = None,
    textgrid: Annotated[Path | None, typer.Option(
        help="the recording's Praat TextGrid (word and phone tiers, e.g. from MFA)")] = None,
    voice: Annotated[str, typer.Option(help="eSpeak NG voice, e.g. en-us, en-gb, en-us+f3")]
    = "en-us",
    rate: Annotated[int, typer.Option(help="speaking rate, words per minute (80-450)")] = 160,
    word_tier: Annotated[str | None, typer.Option(help="TextGrid word tier name")] = None,
    phone_tier: Annotated[str | None, typer.Option(help="TextGrid phone tier name")] = None,
    strength: Annotated[float, typer.Option(
        help="scale of each viseme's departure from rest (1: the table's; 0 to 2)")] = 1.0,
    face: FaceOpt = "default",
    preset: PresetOpt = "anatomical",
    video: Annotated[bool, typer.Option(help="render the MP4 with the audio")] = True,
    view: ViewOpt = "frontal+profile",
    size: SizeOpt = "1280x720",
    background: BackgroundOpt = "#2a2c33",
    aa: AAOpt = 2,
):
    """Make the face say TEXT (eSpeak NG), or speak in sync with a recorded voice: audio,
    alignment (TextGrid, CSV), muscle activity and jaw, results, MP4 and a manifest."""
    from .speech.speak import speak as run

    opts = _render_options(view, size, background, aa) if video else None
    with _staged_progress() as report:
        res = run(output, text, audio=audio, textgrid=textgrid, voice=voice, rate_wpm=rate,
                  word_tier=word_tier, phone_tier=phone_tier, face=face, preset=preset,
                  strength=strength, video=video, render_options=opts, progress=report)
    words = " ".join(w.label for w in res.alignment.words)
    out.print(f"{len(res.alignment.phones)} phones ({words}), "
              f"{res.alignment.duration:.2f} s -> {output}/")
    for name, path in res.files.items():
        out.print(f"  {name}: {path}")


@app.command()
def describe(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
    series: Annotated[bool, typer.Option(help="with --json: add the per-frame lip aperture "
                                              "and mouth width")] = False,
):
    """Stimulus parameters of a result: displacement and speed of lips, jaw and mouth corners,
    lip aperture and mouth width, the audio-visual offset, settings and input hashes."""
    from .analysis.describe import describe as measure
    from .io.results import read_results

    d = measure(read_results(result), source=str(result))
    if as_json:
        print(json.dumps(d.to_dict(series=series), indent=2))
    else:
        out.print(d.table(), markup=False, highlight=False)


@app.command()
def stimuli(
    design: Annotated[Path, typer.Argument(help="design table (.csv or .toml), one row per "
                                                "stimulus (see docs/stimuli.md)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")],
    video: Annotated[bool, typer.Option(help="render the MP4s")] = True,
    view: ViewOpt = "frontal",
    size: SizeOpt = "1280x720",
    background: BackgroundOpt = "#2a2c33",
    aa: AAOpt = 2,
):
    """Make the stimuli of a design table (amplitude, time scale, AV offset, dubbing, freezing),
    each as results, WAV and MP4, with a manifest of their measured parameters."""
    from .speech.design import run_design
    from .speech.speak import text_items

    opts = _render_options(view, size, background, aa)
    with _staged_progress() as report:
        rep = run_design(design, output, text_items(Path(output) / "items"), options=opts,
                         video=video, progress=report)
    for e in rep.failed:
        err.print(f"facemech: error: {e.one_line()}", highlight=False, markup=False,
                  soft_wrap=True)
    out.print(rep.summary())
    if rep.failed:
        raise typer.Exit(2)


def _ranges(text: str | None, n: int, field: str) -> list[int] | None:
    """'1-30' or '1,3,5-7' (1-based, inclusive) -> 0-based indices."""
    if text is None:
        return None
    out: list[int] = []
    try:
        for part in text.split(","):
            a, _, b = part.strip().partition("-")
            lo, hi = int(a), int(b or a)
            out.extend(range(lo - 1, hi))
    except ValueError:
        raise InputError("expected ranges such as 1-30 or 1,3,5-7", field=field) from None
    if any(i < 0 or i >= n for i in out):
        raise InputError(f"utterance numbers must lie in 1..{n}", field=field)
    return out


def _length(text: str | None, field: str) -> float | None:
    """'0.5mm', '0.05cm' or '0.0005' (metres) -> metres; None or 'auto' -> None."""
    if text is None or text == "auto":
        return None
    from .units import LENGTH_TO_M

    t = text.strip().lower()
    for unit in sorted(LENGTH_TO_M, key=len, reverse=True):
        if t.endswith(unit):
            try:
                return float(t[: -len(unit)]) * LENGTH_TO_M[unit]
            except ValueError:
                break
    try:
        return float(t)
    except ValueError:
        raise InputError(f"not a length: {text!r} (e.g. 0.5mm)", field=field) from None


@app.command()
def regions(
    files: Annotated[list[Path], typer.Argument(help="marker files, one utterance each")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")],
    k: Annotated[int | None, typer.Option("-k", help="independent markers (default: "
                                                     "min(epsilon-rank, 10))")] = None,
    eps: Annotated[str | None, typer.Option(help="data precision, e.g. 0.5mm (default: "
                                                 "estimated noise floor)")] = None,
    neutral: Annotated[str, typer.Option(help="'first' or a marker file whose first frame is "
                                              "the neutral")] = "first",
    train: Annotated[str | None, typer.Option(help="utterances to fit, e.g. 1-30")] = None,
    test: Annotated[str | None, typer.Option(help="held-out utterances, e.g. 31-40")] = None,
    method: Annotated[str, typer.Option(help="qrcp or strong")] = "qrcp",
    units: UnitsOpt = None,
):
    """Independent markers and eigenregions by QR with column pivoting (Lucero & Munhall 2008)."""
    from .analysis.lucero2008 import analyse
    from .io.markers import read_markers

    sets = [read_markers(f, units=units) for f in files]
    names = sets[0].names
    for f, ms in zip(files, sets, strict=True):
        if ms.names != names:
            missing = sorted(set(names) ^ set(ms.names))
            raise InputError("markers differ from the first file's", source=str(f),
                             field=missing[0] if missing else "order")
    neutral_pos: str | np.ndarray = "first"
    if neutral != "first":
        nm = read_markers(Path(neutral), units=units)
        neutral_pos = nm.select(names).positions[0]
    s = analyse([ms.positions for ms in sets], names, output, k=k, eps=_length(eps, "eps"),
                method=method, train=_ranges(train, len(sets), "train"),
                test=_ranges(test, len(sets), "test"), neutral=neutral_pos, rate=sets[0].rate)
    s.pop("_model", None)
    out.print(f"epsilon {s['eps_mm']:.3f} mm, rank {s['rank']} of {s['markers']}; k = {s['k']}")
    out.print("independent markers: " + ", ".join(s["selected"]))
    out.print(f"summary and figures -> {output}/")


@experiment_app.command("lucero2008")
def experiment_lucero2008(
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")] = Path(
        "lucero2008"),
    utterances: Annotated[int, typer.Option(help="utterances in the corpus")] = 40,
    frames: Annotated[int, typer.Option(help="frames per utterance (60 Hz)")] = 60,
    k: Annotated[int, typer.Option("-k", help="independent markers of the basis")] = 10,
    video: Annotated[bool, typer.Option(help="render the animation from k markers")] = True,
):
    """Lucero & Munhall (2008) on the embedded corpus, our numbers beside the paper's."""
    from .analysis.lucero2008 import run_lucero2008

    if utterances < 8:
        raise InputError("needs at least 8 utterances", field="utterances")
    with _staged_progress() as report:
        s = run_lucero2008(output, n_utterances=utterances, frames=frames, k=k, video=video,
                           progress=report)
    p, a = s["paper"], s["all_utterances"]
    out.print("[bold]Lucero & Munhall (2008) on the embedded corpus[/bold]  (ours | paper, S1)")
    out.print(f"  epsilon-rank: {a['rank']} of 57 | {p['rank']} of 57")
    out.print(f"  last two R values: {a['r_before_last_mm']:.2f}, {a['r_last_mm']:.4f} mm | "
              f"{p['r_56_mm']:.2f}, {p['r_57_mm']:.2f} mm")
    out.print(f"  last selected: {a['last_selected']} (copied pair {', '.join(s['copied_pair'])})"
              f" | {p['copied_marker_selected']}")
    out.print(f"  first selected: {', '.join(s['order'][:4])} | {p['first_selected']}")
    if "trajectory" in s:
        e = s["trajectory"]["max_error_xyz_mm"]
        q = p["jaw_marker_max_error_k10_mm"]
        out.print(f"  jaw marker max error, k = {s['k']} (x, y, z): "
                  f"{e[0]:.2f}, {e[1]:.2f}, {e[2]:.2f} mm | {q[0]}, {q[1]}, {q[2]} mm")
    for row in s.get("held_out_error", [])[:: max(1, len(s.get("held_out_error", [])) // 6)]:
        out.print(f"  k = {row['k']:2d}: held-out error {row['mean_abs_error_mm']:.3f} mm "
                  f"(relative {row['relative_error']:.2f}; PCA {row['pca_mean_abs_error_mm']:.3f})")
    sr = s["strong_rrqr"]
    out.print(f"  max |X|: QRCP {sr['qrcp_max_abs_coefficient']:.2f}, strong RRQR "
              f"{sr['max_abs_coefficient']:.2f} (bound {sr['bound']})")
    mi = s["muscle_insertions"]
    out.print(f"  first 10 selected markers lie {mi['selected_mean_mm']:.1f} mm from the nearest "
              f"muscle insertion; random markers {mi['random_mean_mm']:.1f} mm "
              f"(p = {mi['random_p_value']:.3f})")
    out.print(f"  summary and figures -> {output}/")


@app.command()
def invert(
    markers: Annotated[Path, typer.Option(help="marker file in the model's frame, 60 Hz")],
    output: Annotated[Path, typer.Option("-o", "--output", help="results file (.nc)")],
    face: FaceOpt = "default",
    map_file: Annotated[Path | None, typer.Option("--map", help="marker,node CSV (default: "
                                                                "closest nodes)")] = None,
    method: Annotated[str, typer.Option(help="lsq (fast) or powell (the seeds')")] = "lsq",
    positive: Annotated[bool, typer.Option(help="keep activity >= 0")] = True,
    controls: Annotated[str, typer.Option(help="speech, emg7, all, or comma-separated groups")]
    = "speech",
    chin_marker: Annotated[str | None, typer.Option(
        help="a jaw recording: this marker's drop gives the jaw angle (33-ms lead)")] = None,
    jaw_second_marker: Annotated[str | None, typer.Option(
        help="a second mandible marker: with --chin-marker, drives rotation and condyle glide")]
    = None,
    jaw_fixed: Annotated[bool, typer.Option(
        help="hold the recorded jaw as given (default: estimate the jaw, starting from it)")]
    = False,
    jaw_lead: Annotated[int, typer.Option(help="frames the recorded jaw leads the skin")] = 2,
    noise: Annotated[float | None, typer.Option(
        help="marker noise for the standard errors, mm (default: from the residuals)")] = None,
    window: Annotated[int | None, typer.Option(
        help="frames fitted per frame, first kept (lsq; default 2)")] = None,
    tol: Annotated[float | None, typer.Option(
        help="stop a frame's fit when the RMS error improves by less than this, mm (lsq; "
             "default 0.01)")] = None,
    bend: Annotated[float | None, typer.Option(
        help="weight of second differences across the window, mm per unit (lsq)")] = None,
    smooth: Annotated[float | None, typer.Option(
        help="weight of frame-to-frame changes, mm per unit (lsq; default 0.3)")] = None,
    effort: Annotated[float | None, typer.Option(help="effort weight, mm per unit (lsq)")]
    = None,
    max_evaluations: Annotated[int | None, typer.Option(
        help="model frame steps per frame, at most (default 400)")] = None,
    scale_pair: Annotated[str | None, typer.Option(help="A,B: adapt the markers by per-axis "
                                                        "scaling from two markers far apart")]
    = None,
    preset: PresetOpt = "anatomical",
    jaw_kinematics: Annotated[str | None, typer.Option(
        help="hinge or glide (the condyle glides as the jaw opens; default: the preset's)")]
    = None,
    dt: Annotated[float | None, typer.Option(help="explicit Euler step of every evaluation, s "
                                                  "(default: the preset's fast step)")] = None,
    units: UnitsOpt = None,
    figure: Annotated[Path | None, typer.Option(help="PNG of the inverted controls with +-2 SE "
                                                     "bands and the per-frame error")] = None,
):
    """Recover muscle activity and the jaw frame by frame from markers; re-animate the face."""
    from .inverse.workflow import invert_markers
    from .io.results import file_hash

    with _progress() as prog:
        task = prog.add_task(f"invert ({method})", total=None)
        res = invert_markers(
            markers, face=face, map_file=map_file, units=units, scale_pair=scale_pair,
            preset=preset, jaw_kinematics=jaw_kinematics, method=method, positive=positive,
            controls=controls,
            chin_marker=chin_marker, jaw_second_marker=jaw_second_marker, jaw_fixed=jaw_fixed,
            jaw_lead=jaw_lead, noise=noise,
            dt=dt, options=dict(window=window, tol=tol, bend=bend, smooth=smooth,
                                effort=effort, max_evaluations=max_evaluations),
            progress=lambda d, n: prog.update(task, completed=d, total=n))
    res.write(output, inputs={"markers": file_hash(markers)})
    s = res.error_summary()
    out.print(f"{len(res.time)} frames inverted ({res.method.name}) in {res.wall_seconds:.1f} s;"
              f" per-frame error (RMS over {len(res.marker_names)} markers): median "
              f"{s['median_mm']:.3f} mm, max {s['max_mm']:.3f} mm -> {output}")
    seen = [n for n, ok in zip(res.control_names, res.identifiable, strict=True) if ok]
    out.print(f"  determined by the markers (noise {res.noise_mm:.3f} mm, {res.noise_how}): "
              f"{', '.join(seen) or 'none'}")
    if figure is not None:
        from .viz.plots import inversion_figure

        inversion_figure(figure, res.time, res.controls, res.control_names,
                         rms_error=res.rms_error, se=res.control_se,
                         identifiable=res.identifiable,
                         title=f"{markers.name}: inverted controls ({res.method.name})")
        out.print(f"figure -> {figure}")
    for note in res.notes:
        err.print(f"facemech: note: {note}")
    for warning in s["warnings"]:
        err.print(f"facemech: warning: {warning}")


def _json_safe(obj):
    """A copy of nested dicts and lists with NaN and infinities as null (strict JSON)."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


@app.command()
def compare(
    a: Annotated[Path, typer.Argument(help="results (.nc) or marker file: the model")],
    b: Annotated[Path, typer.Argument(help="results (.nc) or marker file: the data")],
    markers: Annotated[str | None, typer.Option(help="comma-separated markers (default: all "
                                                     "shared)")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
    units: UnitsOpt = None,
):
    """3-D statistics, per-axis correlations and per-frame errors of A against B.

    The per-frame error is the RMS over the markers present in both (mm); its median and
    maximum are reported, with a warning when the maximum exceeds 1 mm or 5 x the median.
    """
    from .inverse.stats import compare as run

    def load(p: Path):
        if p.suffix.lower() == ".nc":
            from .io.results import read_results

            ds = read_results(p)
            return [str(m) for m in ds["marker"].values], ds["markers"].values, float(
                ds.attrs.get("frame_rate_hz", 60.0))
        from .io.markers import read_markers

        ms = read_markers(p, units=units)
        return list(ms.names), ms.positions, ms.rate

    na, pa, ra = load(a)
    nb, pb, rb = load(b)
    if abs(ra - rb) > 1e-3 * ra or len(pa) != len(pb):
        raise InputError(f"A has {len(pa)} frames at {ra:g} Hz, B {len(pb)} at {rb:g} Hz",
                         source=str(b), field="time")
    names = ([m.strip() for m in markers.split(",")] if markers
             else [n for n in na if n in nb])
    for n in names:
        if n not in na or n not in nb:
            raise InputError("marker not in both inputs", field=n)
    if not names:
        raise InputError("no marker names shared by the inputs", field="markers")
    res = run(pa[:, [na.index(n) for n in names]], pb[:, [nb.index(n) for n in names]], names,
              ra)
    for w in res["error"]["warnings"]:
        err.print(f"facemech: warning: {w}", markup=False, highlight=False)
    if as_json:
        print(json.dumps(_json_safe(res), indent=2))
        return
    e, s = res["error"], res["frame_error_mm"]
    out.print(f"{res['frames']} frames, {len(names)} markers; per-frame error (RMS over the "
              f"markers, mm): median {e['median_mm']:.3f}, max {e['max_mm']:.3f} at "
              f"{e['max_time_s']:.2f} s (min {s['min']:.3f} q1 {s['q1']:.3f} q3 {s['q3']:.3f}); "
              f"movement {res['movement_mm']:.3f} mm")
    for n, v in res["markers"].items():
        out.print(f"  {n}: 3-D r {v['corr3d_published']:.3f}")


@experiment_app.command("pitermann2001-synthetic")
def experiment_pitermann_synthetic(
    method: Annotated[str, typer.Option(help="lsq, powell or both")] = "lsq",
    noise: Annotated[float, typer.Option(help="Gaussian marker noise, mm")] = 0.0,
    preset: PresetOpt = "anatomical",
    dt: Annotated[float | None, typer.Option(help="Euler step of synthesis and inversion, s "
                                                  "(default: the preset's fast step)")] = None,
    output: Annotated[Path | None, typer.Option("-o", "--output", help="JSON file")] = None,
    figures: Annotated[Path | None, typer.Option(help="folder for one PNG per run: inverted "
                                                      "against true activity, and the error")]
    = None,
):
    """Pitermann & Munhall (2001) Experiment 1: Tables I, II and the top of Table III."""
    from .geometry.builder import default_face
    from .inverse.experiments import run_synthetic
    from .params import preset as get_preset

    if method not in ("lsq", "powell", "both"):
        raise InputError("method must be lsq, powell or both", field="method")
    methods = ("lsq", "powell") if method == "both" else (method,)
    with _staged_progress() as report:
        prm = get_preset(preset)
        res = run_synthetic(default_face(tissue=prm.tissue), methods=methods, noise=noise * 1e-3,
                            params=prm, dt=dt, progress=report)
    paper = res["paper"]
    out.print("[bold]Pitermann & Munhall (2001), Experiment 1[/bold] (ours | paper)")
    for label, r in res["runs"].items():
        out.print(f"[bold]{label}[/bold]: {r['wall_s']:.1f} s, {r['evaluations']} steps")
        t1 = r["table1_activity_correlation"]
        ref = paper["activity_correlations_no_constraint"]
        out.print("  Table I, activity correlation: " + ", ".join(
            f"{k} {v:.2f}" + (f" | {ref[k]:.2f}" if "no constraint" in label else "")
            for k, v in t1.items()))
        out.print(f"  Table II, 3-D correlations >= 0.95: {r['corr3d_at_least_0.95']} of 19; "
                  f"> 0.8: {r['corr3d_above_0.8']} of 19 | {paper['kinematic_corr_above_0.8']} "
                  "over both conditions")
        e = r["table3_frame_error_mm"]
        pe = paper["median_error_mm"]["positive" if "positive" in label else "no_constraint"]
        out.print(f"  Table III, per-frame error (mm): min {e['min']:.3f} q1 {e['q1']:.3f} "
                  f"median {e['median']:.3f} | {pe} q3 {e['q3']:.3f} max {e['max']:.3f}; "
                  f"movement {r['movement_mm']:.3f} | {paper['movement_mm']} mm")
        if "vs_noise_free" in r:
            v = r["vs_noise_free"]
            out.print(f"  against the noise-free markers: median error "
                      f"{v['frame_error_mm']['median']:.3f} mm; 3-D correlations > 0.8: "
                      f"{v['corr3d_above_0.8']} of 19")
    if figures is not None:
        from .viz.plots import inversion_figure

        figures.mkdir(parents=True, exist_ok=True)
        for label, r in res["runs"].items():
            path = figures / f"experiment1_{label.replace(', ', '_').replace(' ', '-')}.png"
            t = np.arange(res["frames"]) / 60.0
            inversion_figure(path, t, np.array(r["controls"]), tuple(r["control_names"]),
                             truth=np.array(r["true_controls"]),
                             rms_error=np.array(r["rms_error_m"]),
                             title=f"Experiment 1, {label} ({preset})")
            out.print(f"figure -> {path}")
    if output is not None:
        from .io.atomic import atomic_path

        with atomic_path(output, suffix=".json") as tmp:
            tmp.write_text(json.dumps(res, indent=2))
        out.print(f"tables -> {output}")


@experiment_app.command("pitermann2001-crosstalker")
def experiment_pitermann_crosstalker(
    frames: Annotated[int, typer.Option(help="frames of the gesture sequence (60 Hz)")] = 120,
    preset: PresetOpt = "anatomical",
    dt: Annotated[float | None, typer.Option(help="Euler step of synthesis and inversion, s "
                                                  "(default: the preset's fast step)")] = None,
    output: Annotated[Path | None, typer.Option("-o", "--output", help="JSON file")] = None,
):
    """Experiment 3 analogue: another talker inverted on the default face (Table VI)."""
    from .geometry.builder import default_face
    from .inverse.experiments import run_crosstalker
    from .params import preset as get_preset

    if frames < 8:
        raise InputError("needs at least 8 frames", field="frames")
    with _staged_progress() as report:
        prm = get_preset(preset)
        res = run_crosstalker(default_face(tissue=prm.tissue), frames=frames, params=prm, dt=dt,
                              progress=report)
    out.print("[bold]Pitermann & Munhall (2001), Experiment 3 analogue[/bold] (paper, Table VI: "
              "3-D correlations mostly 0.75-0.97, upper lip centre poor)")
    for label, r in res["runs"].items():
        e = r["frame_error_mm"]
        out.print(f"[bold]{label}[/bold]: {r['wall_s']:.1f} s; per-frame error (mm) median "
                  f"{e['median']:.3f} max {e['max']:.3f}; movement {r['movement_mm']:.3f} mm")
        out.print("  Table VI: " + ", ".join(
            f"{n}{'*' if n in res['held_out'] else ''} {v:.2f}"
            for n, v in r["table6_corr3d"].items()))
    out.print("  (* held out)")
    if output is not None:
        from .io.atomic import atomic_path

        with atomic_path(output, suffix=".json") as tmp:
            tmp.write_text(json.dumps(res, indent=2))
        out.print(f"tables -> {output}")


@app.command()
def calibrate(
    gestures: Annotated[list[str] | None, typer.Argument(
        help="maximal gestures, each FILE:GROUPS (a marker file in the model's frame and the "
             "muscle groups it uses), e.g. smile.c3d:ZYG,LAO,RIS pucker.trc:OOS,OOI")] = None,
    output: Annotated[Path, typer.Option("-o", "--output", help="preset file (.json)")]
    = Path("calibrated-preset.json"),
    face: FaceOpt = "default",
    builtin: Annotated[bool, typer.Option("--builtin", help="refit the built-in targets "
                                                            "(gestures of real faces, docs)")]
    = False,
    fit: Annotated[str, typer.Option(help="scales to fit, comma-separated (force, lips, "
                                          "stiffness, sphincter)")]
    = "force,lips",
    map_file: Annotated[Path | None, typer.Option("--map", help="marker,node CSV (default: "
                                                                "closest nodes)")] = None,
    max_evaluations: Annotated[int, typer.Option(help="gesture sets simulated at most")] = 30,
    units: UnitsOpt = None,
    name: Annotated[str | None, typer.Option(help="preset name (default: the file's)")] = None,
):
    """Fit the anatomical preset's global scales to a subject's maximal gestures (or to the
    built-in targets) and write a preset file that every --preset option accepts."""
    from .analysis.calibration import check_fit, fit_scales, fit_subject, recorded_gesture
    from .geometry.builder import load_face
    from .io.markers import read_markers
    from .kinematics.mapping import closest_nodes, read_mapping
    from .params import anatomical, write_preset

    scales = tuple(x.strip() for x in fit.split(",") if x.strip())
    check_fit(scales)
    if max_evaluations < 2:
        raise InputError("max-evaluations must be at least 2", field="max-evaluations")
    if builtin == bool(gestures):
        raise InputError("give gestures (FILE:GROUPS ...) or --builtin", field="gestures")
    if output.suffix.lower() != ".json":
        raise InputError("the preset file must end in .json", source=str(output),
                         field="output")
    model = load_face(face, tissue=anatomical().tissue)
    with _staged_progress() as report:
        if builtin:
            res = fit_scales(model, fit=scales, max_evaluations=max_evaluations,
                             progress=lambda d, n: report("fit", d, n))
            fitted_to = "built-in targets"
        else:
            recs, mapping = [], None
            for spec in gestures:
                path, sep, groups = spec.rpartition(":")
                if not sep or not path or not groups:
                    raise InputError("expected FILE:GROUPS, e.g. smile.c3d:ZYG,LAO", field=spec)
                ms = read_markers(Path(path), units=units)
                if mapping is None:
                    mapping = (read_mapping(map_file, ms, model) if map_file is not None
                               else closest_nodes(ms, model))
                recs.append(recorded_gesture(ms, groups.split(","), name=Path(path).stem))
            res = fit_subject(model, recs, mapping, fit=scales, max_evaluations=max_evaluations,
                              progress=lambda d, n: report("fit", d, n))
            fitted_to = [r.source for r in recs]
    write_preset(output, name or output.stem, res.scales,
                 extra={"fitted_to": fitted_to, "face": model.name, "cost": res.cost,
                        "evaluations": res.evaluations, "rows": res.rows})
    out.print(f"[bold]fitted[/bold] {', '.join(f'{k} {v:.3g}' for k, v in res.scales.items())} "
              f"({res.evaluations} evaluations, cost {res.cost:.4g})")
    if builtin:
        out.print(res.table(), markup=False)
    out.print(f"preset -> {output} (use it as --preset {output})")


def main() -> None:
    """Entry point: run the app; a FacemechError becomes one line on stderr and exit 2."""
    try:
        app()
    except FacemechError as exc:
        err.print(f"facemech: error: {exc.one_line()}", highlight=False, markup=False,
                  soft_wrap=True)
        sys.exit(2)
    except KeyboardInterrupt:
        err.print("facemech: interrupted")
        sys.exit(130)


if __name__ == "__main__":
    main()
