"""The ``facemech`` command line: each command parses its options, makes one call into the
library (:mod:`facemech.workflows`) and prints what it did; bad input: one line, exit 2. Options
are declared as plain parameters; :func:`command` gives them help, names and ranges."""

import functools
import inspect
import os
import sys
from pathlib import Path

import typer
from rich.console import Console

from . import cli_options as opts
from . import progress, warmup, workflows
from ._version import __version__
from .errors import FacemechError
from .inputs import REQUIRED

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Physics and kinematics of the speaking face.")
face_app, emg_app, markers_app, experiment_app = _subs = [typer.Typer(
    no_args_is_help=True, help=h) for h in ("Build and inspect face models.", "Process EMG "
    "recordings.", "Read, convert and clean marker data.", "The seeds' experiments, reproduced.")]
for _sub, _name in zip(_subs, ("face", "emg", "markers", "experiment"), strict=True):
    app.add_typer(_sub, name=_name)
err, out = Console(stderr=True), Console(soft_wrap=True)

def _option(fn, p: inspect.Parameter, args: tuple[str, ...], spec=None) -> inspect.Parameter:
    help = opts.help_for(fn.__name__, p.name, spec)
    if p.default is inspect.Parameter.empty or p.name in args:
        return p.replace(default=typer.Argument(... if p.default is inspect.Parameter.empty
                                                else p.default, help=help))
    flags = spec.flags if spec else opts.NAMES.get(p.name, ())
    if spec and flags == ("--" + p.name.replace("_", "-"),):
        flags = ()  # typer's own (a yes/no option: --x/--no-x)
    return p.replace(default=typer.Option(p.default, *flags, help=help))

def command(group: typer.Typer = app, name: str | None = None, args: tuple[str, ...] = (),
            look: tuple | None = None, groups: tuple[str, ...] = ()):
    """Register the function as the command ``name`` of ``group``: parameters become options
    (:mod:`facemech.cli_options`; no default or in ``args``: arguments; ``...``: required),
    numbers are checked first, what it returns is printed (``warnings`` on stderr); ``look``:
    defaults of ``--view --size --background --aa``, passed as one ``render``; ``groups``: the
    parameters that take an input group of :data:`~facemech.cli_options.GROUPS` (its
    dataclass, made from its options)."""
    specs = {i.key: i for g in groups for i in opts.group_inputs(g)}
    def register(fn):
        @functools.wraps(fn)
        def run(**kw):
            from .inverse.columns import column_workers
            from .physics.threads import set_threads
            set_threads(_threads[0])  # numba's, for this command (--threads, FACEMECH_THREADS)
            column_workers()  # FACEMECH_WORKERS checked before anything runs
            for key, value in kw.items():
                if isinstance(value, int | float) and not isinstance(value, bool):
                    flags = specs[key].flags if key in specs else opts.NAMES.get(
                        key, ("--" + key.replace("_", "-"),))
                    opts.check_number(flags[-1], value, opts.RANGES.get(key))
            kw.update({g: opts.make_group(g, kw) for g in groups})
            if look:
                kw["render"] = workflows.pictures.render_options(*(kw.pop(k) for k in LOOK))
            if isinstance(shown := fn(**kw), list):  # lines, or what it wrote and warnings
                _say(shown)
            elif shown is not None:  # file names and notes are not markup
                out.print(shown, markup=False, highlight=False)
                err.print(getattr(shown, "warnings", ""), end="")
        sig, key = inspect.signature(fn), inspect.Parameter.KEYWORD_ONLY
        extra = [inspect.Parameter(k, key, default=d, annotation=type(d))
                 for k, d in zip(LOOK, look or (), strict=False)]
        extra += [inspect.Parameter(i.key, key, default=... if i.default is REQUIRED else
                                    i.default, annotation=i.type) for i in specs.values()]
        run.__signature__ = sig.replace(parameters=[_option(fn, p, args, specs.get(p.name))
                                                    for p in (*sig.parameters.values(), *extra)
                                                    if p.name not in ("render", *groups)])
        return group.command(name)(run)
    return register
LOOK = ("view", "size", "background", "aa")
# the running command's log lines (output not a terminal); --threads (None: default_threads())
_log, _threads = [], [None]
def _version(value: bool) -> None:
    if value:
        print(f"facemech {__version__}")
        raise typer.Exit()
@app.callback()
def _root(ctx: typer.Context, version: bool = typer.Option(
        False, "--version", help="print the version", callback=_version, is_eager=True),
          threads: int | None = typer.Option(None, help=opts.HELP["threads"])) -> None:
    """Physics and kinematics of the speaking face."""
    _threads[0] = threads
    if not err.is_terminal:  # log lines, and a heartbeat for the whole command
        _log[:] = [ctx.with_resource(progress.LogProgress(ctx.invoked_subcommand or "facemech"))]
        ctx.call_on_close(_log.clear)

def _staged(run, **options):
    """Call ``run(**options, progress=report)``: bars on a terminal, else the command's log
    lines with their heartbeat; one bar per stage; first the kernels' warm-up if needed."""
    if err.is_terminal:
        import rich.progress as r
        shown = r.Progress(r.TextColumn("{task.description}"), r.BarColumn(), r.MofNCompleteColumn(
            ), r.TimeElapsedColumn(), r.TimeRemainingColumn(), console=err, transient=True)
    else:
        shown = _log[-1] if _log else progress.LogProgress()
    with shown as prog:
        warmup.warm_up_if_needed(progress.staged(prog), skip=run is warmup.warm_up)
        return run(**options, progress=progress.staged(prog))

def _say(lines, note: bool = False, **kw) -> None:  # note: on stderr, "facemech: " first
    for line in lines:
        (err if note else out).print(("facemech: " if note else "") + line, **kw)

def _finish(made: list[str], failed: list[str], code: int):  # a batch's lines, then its status
    _say(failed, True, markup=False, highlight=False, soft_wrap=True)
    _say(made)
    raise typer.Exit(code)

@command(look=("frontal+profile", "1280x720", "#2a2c33", 2))
def demo(output: Path = Path("demo-output"), integrator: str | None = None, video: bool = True,
         preset: str = "anatomical", render=None):
    """Simulate a synthetic utterance on the built-in face; write results, plots and a movie."""
    return _staged(workflows.demo.run, **locals())

@command(app, "warmup")
def warm_up_kernels():
    """Compile and cache the physics and rendering kernels now (make's install step does it)."""
    return f"kernels compiled and cached in {_staged(warmup.warm_up):.0f} s"

@command(face_app, "build")
def face_build(surface: Path, landmarks: Path, output: Path = ..., units: str = "mm",
               axes: str | None = None, name: str | None = None, tissue: str = "anatomical"):
    """Build a three-layer face model from a surface mesh (a textured OBJ or a coloured PLY
    keeps its look) and landmarks; notes (unit inferred, axes turned) on stderr."""
    return _staged(workflows.faces.build_face_file, **locals())

@command(face_app, "from-photo")
def face_from_photo(front: Path, output: Path = ..., profile: Path | None = None, ipd: float | None
                    = None, distance: float = 1.0, name: str | None = None, tissue="anatomical"):
    """A talker from a frontal photo (and a profile), the photo as its skin (docs/photo.md)."""
    return _staged(workflows.photo.face_from_photo_file, **locals())

@command(face_app, "info", args=("face",))
def face_info(face: str = "default", as_json: bool = False, tissue: str | None = None):
    """Counts of a face model: nodes per layer, springs by kind, prisms, muscles, free fascia."""
    out.print(workflows.faces.face_info(face, tissue=tissue).text(as_json), markup=False)

@command(face_app, "landmarks")
def face_landmarks(surface: Path, output: Path = ..., units: str = "mm"):
    """Place landmarks on a scan from its geometry alone; write the CSV and a picture."""
    return workflows.landmarks.landmarks_file(**locals())

@command(face_app, "export-default")
def face_export_default(output: Path = ...):
    """Write the built-in face's surface (OBJ, mm) and landmarks (CSV, mm) as a template."""
    out.print("wrote {} and {}".format(*workflows.faces.export_default_face(output)))

@command(emg_app, "process")
def emg_process(emg: Path, output: Path = ..., rate: float | None = None,
                baseline: str | None = None, calibration: Path | None = None,
                calibration_baseline: str | None = None):
    """Rectify, integrate (17-ms trapezoid), downsample and normalise EMG to activity in [0, 1]."""
    return workflows.emg.process_emg_file(**locals())

@command(markers_app, "info", groups=("reader",))
def markers_info(source: Path, units: str | None = None, as_json: bool = False, reader=None):
    """Rate, units, markers and gaps of a marker file (.c3d .trc .csv .tsv .ema .txy .pos)."""
    out.print(workflows.markers.marker_info(source, units=units, reader=reader).text(as_json),
              markup=False)

@command(markers_app, "convert", args=("target",), groups=("reader",))
def markers_convert(source: Path, target: Path | None = None, output: Path | None = None,
                    units: str | None = None, out_units: str | None = None, reader=None):
    """Convert to C3D, TRC or CSV (from any marker file, articulography or results)."""
    return workflows.markers.convert_markers(source, output or target, units=units,
                                             out_units=out_units, reader=reader)

@command(markers_app, "head-correct")
def markers_head_correct(source: Path, output: Path = ..., units: str | None = None,
                         head: str = ..., reference: int | None = None, report: Path | None = None):
    """Remove head motion by a per-frame rigid fit of head markers to a reference frame."""
    return workflows.markers.head_correct_file(**locals())

@command(markers_app, "resample")
def markers_resample(source: Path, output: Path = ..., rate: float | None = None,
                     units: str | None = None):
    """Resample to a new rate with anti-aliasing (gaps stay gaps)."""
    return workflows.markers.resample_file(**locals())

@command(markers_app, "frame")
def markers_frame(source: Path, output: Path = ..., right: str = ..., left: str = ...,
                  front: str = ..., origin: str | None = None, reference: int = 0,
                  units: str | None = None):
    """Express markers in an anatomical frame: +x right->left, +y up, +z forward."""
    return workflows.markers.frame_file(**locals())

@command(markers_app, "fill-gaps")
def markers_fill_gaps(source: Path, output: Path = ..., units: str | None = None,
                      max_gap: float = 0.1):
    """Fill interior gaps up to --max-gap with a cubic spline; filled samples are flagged."""
    return workflows.markers.fill_gaps_file(**locals())

@command(markers_app, "trim", groups=("bounds", "reader"))
def markers_trim(source: Path, output: Path = ..., units: str | None = None, bounds=None,
                 reader=None):
    """Keep the frames between two times or frame numbers (none: drop the empty ends)."""
    return workflows.markers.trim_file(source, output, units=units, bounds=bounds, reader=reader)
@command(look=("frontal+profile", "1280x720", "#2a2c33", 2), groups=(
    "controls", "jaw_source", "stepping"))
def simulate(output: Path = ..., face: str = "default", preset: str = "anatomical",
             video: Path | None = None, audio: Path | None = None, render=None,
             controls=None, jaw_source=None, stepping=None):
    """Simulate the face driven by muscle activity or EMG and a jaw trajectory."""
    return _staged(workflows.simulate.simulate_files, output=output, controls=controls,
                   jaw=jaw_source, face=face, preset=preset, stepping=stepping,
                   movie=video and (video, audio, render))

@command(look=("frontal+profile", "1280x720", "#2a2c33", 2))
def render(result: Path, output: Path = ..., audio: Path | None = None, render=None):
    """Render a results file to an H.264 MP4 or PNG frames (-o a folder), with eyes and teeth."""
    return _staged(workflows.pictures.render_movie, results=result, movie=(output, audio, render))

@command(look=("frontal", "1280x1280", "#ffffff", 3))
def still(result: Path, output: Path = ..., time: float | None = None, peak: str | None = None,
          markers: bool = False, labels: bool = False, render=None):
    """A still figure for a paper: one frame at a time or at a gesture's peak (PNG or PDF)."""
    return workflows.pictures.still_file(**locals())

@command()
def export(result: Path, output: Path = ..., units: str | None = None, fmt: str | None = None,
           blendshapes: str | None = None, face: str | None = None):
    """Export a result: animated skin as glTF (.glb), a mesh per frame (OBJ/PLY, -o a folder),
    or markers (.trc, .c3d, .csv). --units: meshes m (default) or mm, markers mm (default).
    --blendshapes arkit: ARKit's 52 shapes and their fitted weights (.glb, .csv, .json)."""
    return _staged(workflows.pictures.export_file, result=result, output=output, fmt=fmt,
                   units=units, blendshapes=blendshapes, face=face)

@command()
def plot(result: Path, output: Path = ..., units: str | None = None,
         markers: str = "R03,R05,R07", measured: Path | None = None):
    """Plot displacement and acceleration (vertical, protrusion) of markers, like Figs. 4-6."""
    return workflows.pictures.plot_file(result, output, markers, measured=measured, units=units)

@command()
def view(result: Path, output: Path = ..., units: str | None = None,
         markers: Path | None = None, title: str | None = None):
    """Write an interactive viewer: one self-contained HTML page (WebGL, works offline)."""
    return workflows.pictures.view_file(result, output, markers=markers, units=units, title=title)

@command(args=("text",), look=("frontal+profile", "1280x720", "#2a2c33", 2),
         groups=("speaking", "recording", "alive"))
def speak(text: str | None = None, output: Path = Path("speak-output"), face: str = "default",
          preset: str = "anatomical", render=None, speaking=None, recording=None, alive=None):
    """Make the face say TEXT (eSpeak NG) or speak with a recorded voice (docs/stimuli.md)."""
    _say(workflows.speech.speak_report(_staged(workflows.speech.speak, **locals()), output))

@command()
def describe(result: Path, as_json: bool = False, series: bool = False):
    """Stimulus parameters of a result: lips, jaw, mouth corners, AV offset, settings."""
    text = workflows.speech.describe_text(result, as_json=as_json, series=series)
    print(text) if as_json else out.print(text, markup=False, highlight=False)

@command()
def lipread(result: Path, tracker: str = "mesh", size: str = "640x360", aa: int = 2,
            output: Path | None = None, as_json: bool = False):
    """A machine lip-reader on RESULT's frontal movie: r of its inner lips and the aperture."""
    return _staged(workflows.lipread.lines, **locals())

@command()
def stimuli(design: Path, output: Path = ..., video: bool = True, view: str = "frontal",
            size: str = "1280x720", background: str = "#2a2c33", aa: int = 2):
    """Make the stimuli of a design table (docs/stimuli.md) as results, WAV, MP4, manifest."""
    made, failed = workflows.speech.stimuli_report(_staged(workflows.speech.stimuli, **locals()))
    _finish(made, failed, 2 if failed else 0)

@command()
def regions(files: list[Path], output: Path = ..., units: str | None = None,
            k: int | None = None, eps: str | None = None, neutral: str = "first",
            train: str | None = None, test: str | None = None, method: str = "qrcp"):
    """Independent markers and eigenregions by QR with column pivoting (Lucero & Munhall 2008)."""
    _say(workflows.regions.report(workflows.regions.regions(**locals()), output))

@command(experiment_app, "lucero2008")
def experiment_lucero2008(output: Path = Path("lucero2008"), frames: int = 60,
                          utterances: int = 40, k: int = 10, video: bool = True):
    """Lucero & Munhall (2008) on the embedded corpus, our numbers beside the paper's."""
    res = _staged(workflows.experiments.lucero2008, **locals())
    _say(workflows.experiments.lucero2008_report(res, output))

@command(groups=("marker_file", "model", "jaw_markers", "inversion", "fit"))
def invert(output: Path = ..., face: str = "default", figure: Path | None = None,
           marker_file=None, model=None, jaw_markers=None, inversion=None, fit=None):
    """Recover muscle activity and the jaw frame by frame from markers; re-animate the face."""
    res = _staged(workflows.invert.invert, markers=marker_file, output=output, face=face,
                  params=model, jaw=jaw_markers, inversion=inversion, options=fit,
                  figure=figure)
    _say(workflows.invert.report(res, output, figure))
    _say(workflows.invert.notes(res), True)

@command()
def compare(a: Path, b: Path, markers: str | None = None, as_json: bool = False,
            units: str | None = None):
    """3-D statistics, per-axis correlations and per-frame errors (RMS, mm) of A against B."""
    res = workflows.compare.compare_files(a, b, markers=markers, units=units)
    _say(workflows.compare.stderr_lines(res), True, markup=False, highlight=False)
    (print if as_json else out.print)("\n".join(workflows.compare.report(res, as_json=as_json)))

@command(experiment_app, "pitermann2001-synthetic")
def experiment_pitermann_synthetic(method: str = "lsq", dt: float | None = None,
                                   noise_mm: float = 0.0, preset: str = "anatomical",
                                   figures: bool = True, output: Path | None = None):
    """Pitermann & Munhall (2001) Experiment 1: Tables I, II and the top of Table III."""
    res = _staged(workflows.experiments.synthetic, **locals())
    _say(workflows.experiments.synthetic_report(res, output, figures=figures))

@command(experiment_app, "pitermann2001-crosstalker")
def experiment_pitermann_crosstalker(frames: int = 120, dt: float | None = None,
                                     preset: str = "anatomical", output: Path | None = None):
    """Experiment 3 analogue: another talker inverted on the default face (Table VI)."""
    res = _staged(workflows.experiments.crosstalker, **locals())
    return workflows.experiments.crosstalker_report(res, output)

@command(args=("gestures",))
def calibrate(gestures: list[str] | None = None, output: Path = Path("calibrated-preset.json"),
              face: str = "default", map_file: Path | None = None, units: str | None = None,
              builtin: bool = False, fit: str = "force,lips", max_evaluations: int = 30,
              name: str | None = None):
    """Fit the anatomical preset's scales to maximal gestures; write a preset file (--preset)."""
    res = _staged(workflows.calibrate.calibrate, **locals())
    return workflows.calibrate.report(res, output, builtin=builtin)

@command()
def subject(face: str, markers: Path = ..., output: Path = ..., head: str | None = None,
            frame: str | None = None, landmarks: Path | None = None, units: str | None = None,
            rest: str | None = None, chin_marker: str | None = None,
            jaw_second_marker: str | None = None, warp: bool | None = None):
    """Make a subject folder: a face (built-in, face file or scan) fitted to rest markers."""
    return _staged(workflows.subject.make_subject, **locals())

@command(groups=("analysis", "preparation"))
def analyse(subject: Path, recording: Path, output: Path = ..., preset: str = "anatomical",
            analysis=None, preparation=None):
    """A recording against a subject: head motion, frame, gaps, inversion, statistics, movie."""
    return _staged(workflows.subject.analyse, **locals())

@command()
def batch(manifest: Path, output: Path = ..., workers: int | None = None,
          scheduler: str | None = None):
    """Run a manifest of simulate/invert/speak/stimuli/regions items on dask (docs/batch.md)."""
    rep = workflows.batch.run_batch(
        manifest, output, workers=workers, scheduler=scheduler, on_item=lambda o, n, t: _say(
            [f"[{n}/{t}] {o.line()}"], True, markup=False, highlight=False, soft_wrap=True))
    _finish(*workflows.batch.report(rep), rep.exit_code)

def main() -> None:
    """Run the app: a FacemechError is one line on stderr, exit 2; SIGINT/SIGTERM: 130/143."""
    from . import _numba_cache_dir, interrupts
    cache = _numba_cache_dir(os.path.dirname(__file__), os.environ,
                             lambda d: os.access(d, os.W_OK))
    os.environ.update({} if cache is None else {"NUMBA_CACHE_DIR": cache})  # before numba starts
    restore = interrupts.install()
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
