"""The ``facemech`` command line: each command parses its options, makes one call into the
library (:mod:`facemech.workflows`) and prints what it did; bad input: one line, exit 2."""

from __future__ import annotations

import contextlib
import importlib
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from .errors import FacemechError

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


def _o(help: str, *names: str):
    return typer.Option(*names, help=help)


def _staged(run, **options):
    with _staged_progress() as progress:
        return run(**options, progress=progress)


def _say(lines, note: bool = False, **kw) -> None:  # note: on stderr, "facemech: " first
    for line in lines:
        (err if note else out).print(("facemech: " if note else "") + line, **kw)


OutDirOpt = Annotated[Path, _o("output folder", "-o", "--output")]
VideoOpt = Annotated[bool, _o("render the MP4")]
MapOpt = Annotated[Path | None, _o("marker,node CSV (default: closest nodes)", "--map")]
DtOpt = Annotated[float | None, _o("Euler step of every evaluation, s (default: the preset's)")]
TierOpt = Annotated[str | None, _o("TextGrid tier name (default: found by name)")]
LsqWeight = Annotated[float | None, _o("lsq weight, mm/unit: --bend, --smooth (0.3), --effort")]


@app.command()
def speak(text: Annotated[str | None, typer.Argument(help="what to say (or --audio)")] = None,
          output: OutDirOpt = Path("speak-output"),
          audio: Annotated[Path | None, _o("a recorded voice (WAV) to speak with")] = None,
          textgrid: Annotated[Path | None, _o("the recording's Praat TextGrid (MFA)")] = None,
          voice: Annotated[str, _o("eSpeak NG voice, e.g. en-us, en-gb, en-us+f3")] = "en-us",
          rate_wpm: Annotated[int, _o("words per minute (80-450)", "--rate")] = 160,
          word_tier: TierOpt = None, phone_tier: TierOpt = None,
          strength: Annotated[float, _o("scale of the visemes' departure from rest")] = 1.0,
          face: FaceOpt = "default", preset: PresetOpt = "anatomical", video: VideoOpt = True,
          view: ViewOpt = "frontal+profile", size: SizeOpt = "1280x720",
          background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2):
    """Make the face say TEXT (eSpeak NG), or speak in sync with a recorded voice (--audio)."""
    _say(wf.speech.speak_report(_staged(wf.speech.speak, **locals()), output))


@app.command()
def describe(result: Annotated[Path, typer.Argument(help="results file (.nc)")],
             as_json: Annotated[bool, _o("print JSON", "--json")] = False,
             series: Annotated[bool, _o("with --json: the per-frame mouth measures")] = False):
    """Stimulus parameters of a result: lips, jaw, mouth corners, AV offset, settings."""
    text = wf.speech.describe_text(result, as_json=as_json, series=series)
    print(text) if as_json else out.print(text, markup=False, highlight=False)


@app.command()
def stimuli(design: Annotated[Path, typer.Argument(help="design table (.csv or .toml)")],
            output: OutDirOpt, video: VideoOpt = True, view: ViewOpt = "frontal",
            size: SizeOpt = "1280x720", background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2):
    """Make the stimuli of a design table (docs/stimuli.md) as results, WAV, MP4, manifest."""
    made, failed = wf.speech.stimuli_report(_staged(wf.speech.stimuli, **locals()))
    _say(failed, True, markup=False, highlight=False, soft_wrap=True)
    _say(made)
    raise typer.Exit(2 if failed else 0)


@app.command()
def regions(files: Annotated[list[Path], typer.Argument(help="marker files, one per utterance")],
            output: OutDirOpt, units: UnitsOpt = None,
            k: Annotated[int | None, _o("independent markers (default: <= 10)", "-k")] = None,
            eps: Annotated[str | None, _o("data precision, e.g. 0.5mm (default: noise)")] = None,
            neutral: Annotated[str, _o("'first' or a marker file: its first frame")] = "first",
            train: Annotated[str | None, _o("utterances to fit, e.g. 1-30")] = None,
            test: Annotated[str | None, _o("held-out utterances, e.g. 31-40")] = None,
            method: Annotated[str, _o("qrcp or strong")] = "qrcp"):
    """Independent markers and eigenregions by QR with column pivoting (Lucero & Munhall 2008)."""
    _say(wf.regions.report(wf.regions.regions(**locals()), output))


@experiment_app.command("lucero2008")
def experiment_lucero2008(
        output: OutDirOpt = Path("lucero2008"), frames: Annotated[int, _o("per utterance")] = 60,
        utterances: Annotated[int, _o("utterances in the corpus")] = 40,
        k: Annotated[int, _o("markers of the basis", "-k")] = 10, video: VideoOpt = True):
    """Lucero & Munhall (2008) on the embedded corpus, our numbers beside the paper's."""
    res = _staged(wf.experiments.lucero2008, **locals())
    _say(wf.experiments.lucero2008_report(res, output))


@app.command()
def invert(markers: Annotated[Path, _o("marker file in the model's frame and frame rate")],
           output: Annotated[Path, _o("results file (.nc)", "-o", "--output")],
           face: FaceOpt = "default", map_file: MapOpt = None, preset: PresetOpt = "anatomical",
           method: Annotated[str, _o("lsq (fast) or powell (the seeds')")] = "lsq",
           positive: Annotated[bool, _o("keep activity >= 0")] = True,
           controls: Annotated[str, _o("speech, emg7, all, or listed groups")] = "speech",
           chin_marker: Annotated[str | None, _o("a jaw marker: its drop gives the jaw")] = None,
           jaw_second_marker: Annotated[str | None, _o("another: rotation and glide")] = None,
           jaw_fixed: Annotated[bool, _o("hold the recorded jaw as given")] = False,
           jaw_lead: Annotated[int, _o("frames the recorded jaw leads the skin")] = 2,
           noise: Annotated[float | None, _o("marker noise for the SEs, mm (or fit)")] = None,
           window: Annotated[int | None, _o("lsq: frames fitted per frame (2)")] = None,
           tol: Annotated[float | None, _o("lsq: stop at RMS gains below this, mm")] = None,
           bend: LsqWeight = None, smooth: LsqWeight = None, effort: LsqWeight = None,
           max_evaluations: Annotated[int | None, _o("model steps per frame (400)")] = None,
           scale_pair: Annotated[str | None, _o("A,B: scale the markers per axis")] = None,
           jaw_kinematics: Annotated[str | None, _o("hinge or glide (or the preset's)")] = None,
           dt: DtOpt = None, units: UnitsOpt = None,
           figure: Annotated[Path | None, _o("PNG of the controls (+-2 SE) and error")] = None):
    """Recover muscle activity and the jaw frame by frame from markers; re-animate the face."""
    res = _staged(wf.invert.invert, **locals())
    _say(wf.invert.report(res, output, figure))
    _say(wf.invert.notes(res), True)


@app.command()
def compare(a: Annotated[Path, typer.Argument(help="results or marker file: the model")],
            b: Annotated[Path, typer.Argument(help="results or marker file: the data")],
            markers: Annotated[str | None, _o("comma-separated (default: all shared)")] = None,
            as_json: Annotated[bool, _o("print JSON", "--json")] = False, units: UnitsOpt = None):
    """3-D statistics, per-axis correlations and per-frame errors (RMS, mm) of A against B."""
    res = wf.compare.compare_files(a, b, markers=markers, units=units)
    _say([f"warning: {w}" for w in res.warnings], True, markup=False, highlight=False)
    (print if as_json else out.print)("\n".join(wf.compare.report(res, as_json=as_json)))


@experiment_app.command("pitermann2001-synthetic")
def experiment_pitermann_synthetic(
        method: Annotated[str, _o("lsq, powell or both")] = "lsq", dt: DtOpt = None,
        noise_mm: Annotated[float, _o("Gaussian marker noise, mm", "--noise")] = 0.0,
        preset: PresetOpt = "anatomical", figures: Annotated[bool, _o("with -o: PNGs")] = True,
        output: Annotated[Path | None, _o("folder: summary.json, PNGs", "-o", "--output")] = None):
    """Pitermann & Munhall (2001) Experiment 1: Tables I, II and the top of Table III."""
    res = _staged(wf.experiments.synthetic, **locals())
    _say(wf.experiments.synthetic_report(res, output, figures=figures))


@experiment_app.command("pitermann2001-crosstalker")
def experiment_pitermann_crosstalker(
        frames: Annotated[int, _o("frames of the gesture sequence")] = 120, dt: DtOpt = None,
        preset: PresetOpt = "anatomical",
        output: Annotated[Path | None, _o("JSON file of the table", "-o", "--output")] = None):
    """Experiment 3 analogue: another talker inverted on the default face (Table VI)."""
    res = _staged(wf.experiments.crosstalker, **locals())
    _say(wf.experiments.crosstalker_report(res, output))


@app.command()
def calibrate(gestures: Annotated[list[str] | None, typer.Argument(
              help="maximal gestures, each FILE:GROUPS, e.g. smile.c3d:ZYG,LAO,RIS")] = None,
              output: Annotated[Path, _o("preset file (.json)", "-o", "--output")]
              = Path("calibrated-preset.json"),
              face: FaceOpt = "default", map_file: MapOpt = None, units: UnitsOpt = None,
              builtin: Annotated[bool, _o("refit the built-in targets", "--builtin")] = False,
              fit: Annotated[str, _o("scales: force, lips, stiffness, sphincter")] = "force,lips",
              max_evaluations: Annotated[int, _o("gesture sets simulated at most")] = 30,
              name: Annotated[str | None, _o("preset name (default: the file's)")] = None):
    """Fit the anatomical preset's scales to maximal gestures; write a preset file (--preset)."""
    res = _staged(wf.calibrate.calibrate, **locals())
    _say(wf.calibrate.report(res, output, builtin=builtin))


def main() -> None:
    """Entry point: run the app; a FacemechError becomes one line on stderr and exit 2; SIGINT
    and SIGTERM remove temporary files and exit 130 and 143 (:mod:`facemech.interrupts`)."""
    restore = importlib.import_module("facemech.interrupts").install()
    try:
        app()
    except FacemechError as exc:
        err.print(f"facemech: error: {exc.one_line()}", highlight=False, markup=False,
                  soft_wrap=True)
        sys.exit(2)
    finally:
        restore()


if __name__ == "__main__":
    main()
