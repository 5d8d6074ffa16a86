"""The ``facemech`` command line: thin wrappers that parse, call one library function, report.

Errors in the input end the command with one line on stderr naming the file and the field, and
exit status 2; nothing is left half-written.
"""

from __future__ import annotations

import contextlib
import json
import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from .errors import FacemechError, InputError

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Physics and kinematics of the speaking face.")
face_app = typer.Typer(no_args_is_help=True, help="Build and inspect face models.")
emg_app = typer.Typer(no_args_is_help=True, help="Process EMG recordings.")
app.add_typer(face_app, name="face")
markers_app = typer.Typer(no_args_is_help=True, help="Read, convert and clean marker data.")
experiment_app = typer.Typer(no_args_is_help=True, help="The seeds' experiments, reproduced.")
app.add_typer(experiment_app, name="experiment")
app.add_typer(emg_app, name="emg")
app.add_typer(markers_app, name="markers")


def _show_version(value: bool) -> None:
    if value:
        from ._version import __version__

        print(f"facemech {__version__}")
        raise typer.Exit()


@app.callback()
def _root(version: Annotated[bool, typer.Option("--version", callback=_show_version,
                                                is_eager=True, help="print the version")]
          = False) -> None:
    """Physics and kinematics of the speaking face."""

PresetOpt = Annotated[str, typer.Option(help="parameter preset: anatomical (the default), "
                                             "lucero1999, pitermann2001, calibrated, or a .json "
                                             "file written by facemech calibrate")]
FaceOpt = Annotated[str, typer.Option(help="face file (.npz), or a built-in face: default, "
                                           "default-coarse or default-fine")]

ViewOpt = Annotated[str, typer.Option(help="view: frontal, profile, three-quarter, mouth or "
                                           "frontal+profile")]
SizeOpt = Annotated[str, typer.Option(help="frame size WIDTHxHEIGHT, pixels (up to 3840x2160)")]
BackgroundOpt = Annotated[str, typer.Option(help="background '#rrggbb', 'r,g,b', or "
                                                 "'transparent' (PNG frames and stills)")]
AAOpt = Annotated[int, typer.Option("--aa", help="anti-aliasing: samples per pixel along each "
                                                 "axis, 1 (off) to 4")]

err = Console(stderr=True)
out = Console(soft_wrap=True)


class _LogProgress:
    """Progress as plain lines on stderr (output piped or logged): the stage, items done and
    the elapsed time, every ``every`` seconds per stage and when a stage completes. A stage
    that fails within its first ``every`` seconds prints no progress, only its error line."""

    def __init__(self, every: float = 5.0):
        import time

        self._clock = time.monotonic
        self.every = every
        self.tasks: dict[int, list] = {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def add_task(self, description: str, total: int | None = None) -> int:
        now = self._clock()
        self.tasks[len(self.tasks)] = [description, total, now, now, -1]
        return len(self.tasks) - 1

    def update(self, task: int, completed: int, total: int | None = None) -> None:
        if total is not None:
            self.tasks[task][1] = total
        desc, total, start, last, done_before = self.tasks[task]
        now = self._clock()
        finished = total is not None and completed >= total and done_before < total
        if finished or now - last >= self.every:
            of = f"/{total}" if total is not None else ""
            print(f"facemech: {desc}: {completed}{of} ({now - start:.0f} s)", file=sys.stderr,
                  flush=True)
            self.tasks[task][3] = now
        self.tasks[task][4] = completed


def _progress():
    if not err.is_terminal:
        return _LogProgress()
    return Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/"
                    "{task.total}"), TimeElapsedColumn(), console=err, transient=True)


@contextlib.contextmanager
def _staged_progress():
    """A progress display with one bar per stage; yields report(stage, done, total)."""
    with _progress() as prog:
        tasks: dict[str, int] = {}

        def report(stage, done, total):
            if stage not in tasks:
                tasks[stage] = prog.add_task(stage, total=total)
            prog.update(tasks[stage], completed=done)

        yield report


def _render_options(view: str, size: str, background: str, aa: int):
    from .viz.camera import parse_size
    from .viz.video import RenderOptions

    return RenderOptions(view=view, size=parse_size(size), background=background,
                         supersample=aa)


def _interval(text: str | None, field: str) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        a, b = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError("expected START,STOP in seconds", field=field) from None
    if not b > a:
        raise InputError("STOP must be after START", field=field)
    return a, b


# ---------------------------------------------------------------------------------------------
@app.command()
def demo(
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")] = Path(
        "demo-output"),
    integrator: Annotated[str | None, typer.Option(
        help="euler, implicit or rosenbrock (default: the preset's)")] = None,
    video: Annotated[bool, typer.Option(help="render the MP4")] = True,
    preset: PresetOpt = "anatomical",
    view: ViewOpt = "frontal+profile",
    size: SizeOpt = "1280x720",
    background: BackgroundOpt = "#2a2c33",
    aa: AAOpt = 2,
):
    """Simulate a synthetic utterance on the built-in face; write results, plots and a movie."""
    from .demo import run_demo

    opts = _render_options(view, size, background, aa)
    with _staged_progress() as report:
        err.print(f"facemech demo: building the face and simulating ({preset} preset) ...")
        s = run_demo(output, integrator=integrator, video=video, preset=preset, progress=report,
                     render=opts)
    out.print(f"[bold]facemech demo[/bold] -> {output}/")
    out.print(f"  frames: {s.frames} ({s.simulated_seconds:.2f} s at 60 Hz)")
    out.print(f"  simulation: {s.simulation_seconds:.1f} s wall, real-time factor "
              f"{s.real_time_factor:.2f} ({s.integrator})")
    out.print(f"  largest lip displacement: {s.largest_lip_displacement_mm:.2f} mm")
    out.print(f"  total wall time: {s.wall_seconds:.1f} s")
    for k, v in s.output.items():
        out.print(f"  {k}: {output / v}")


# ---------------------------------------------------------------------------------------------
@face_app.command("build")
def face_build(
    surface: Annotated[Path, typer.Argument(help="OBJ (with its MTL and texture image beside "
                                                 "it), PLY or STL surface of the face")],
    landmarks: Annotated[Path, typer.Argument(help="landmark CSV: name,x,y,z")],
    output: Annotated[Path, typer.Option("-o", "--output", help="face model file (.npz)")],
    units: Annotated[str, typer.Option(help="length unit of both files")] = "mm",
    name: Annotated[str | None, typer.Option(help="model name")] = None,
    tissue: Annotated[str, typer.Option(help="tissue geometry: anatomical (the default "
                                             "preset's) or uniform (the seeds'); a face is "
                                             "rebuilt for a preset that needs the other")]
    = "anatomical",
):
    """Build a three-layer face model from a surface mesh and landmarks.

    A textured OBJ (MTL with map_Kd) or a PLY with vertex colours keeps its look in the model.
    """
    from .geometry.builder import build_face, tissue_options
    from .geometry.surface_io import read_landmarks, read_surface_with_appearance

    opts = tissue_options(tissue)
    v, f, look = read_surface_with_appearance(surface, units=units)
    lm = read_landmarks(landmarks, units=units)
    model = build_face(v, f, lm, name=name or surface.stem, source=str(surface), options=opts,
                       appearance=look)
    model.save(output)
    s = model.summary()
    out.print(f"built {s['name']}: {s['nodes_per_layer']['epidermis']} nodes per layer, "
              f"{s['springs']} springs, {s['prisms']} prisms, {s['muscles']} muscles, "
              f"appearance: {s['appearance']} -> {output}")


@face_app.command("info")
def face_info(
    face: Annotated[str, typer.Argument(help="face file, or default, default-coarse, "
                                             "default-fine")] = "default",
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
    tissue: Annotated[str | None, typer.Option(help="show it with this tissue geometry "
                                                    "(anatomical or uniform)")] = None,
):
    """Counts of a face model: nodes per layer, springs by kind, prisms, muscles, free fascia."""
    from .geometry.builder import load_face

    s = load_face(face, tissue=tissue).summary()
    if as_json:
        print(json.dumps(s, indent=2))
        return
    out.print_json(json.dumps(s))


@face_app.command("export-default")
def face_export_default(
    output: Annotated[Path, typer.Option("-o", "--output", help="output folder")],
):
    """Write the built-in face's surface (OBJ, mm) and landmarks (CSV, mm) as a template."""
    import trimesh

    from .geometry.builder import default_surface
    from .geometry.surface_io import write_landmarks
    from .io.atomic import atomic_path

    v, f, lm = default_surface()
    output.mkdir(parents=True, exist_ok=True)
    with atomic_path(output / "generic_face.obj", suffix=".obj") as tmp:
        trimesh.Trimesh(v * 1e3, f, process=False).export(tmp, file_type="obj")
    write_landmarks(output / "generic_face_landmarks.csv", lm)
    out.print(f"wrote {output / 'generic_face.obj'} and {output / 'generic_face_landmarks.csv'}")


# ---------------------------------------------------------------------------------------------
@emg_app.command("process")
def emg_process(
    emg: Annotated[Path, typer.Argument(help="raw EMG: CSV (time + channels) or C3D")],
    output: Annotated[Path, typer.Option("-o", "--output", help="activity CSV")],
    rate: Annotated[float, typer.Option(help="output rate, Hz")] = 60.0,
    baseline: Annotated[str | None, typer.Option(help="rest interval START,STOP (s)")] = None,
    calibration: Annotated[Path | None, typer.Option(help="recording of maximal gestures")] = None,
    calibration_baseline: Annotated[str | None, typer.Option(
        help="rest interval in the calibration recording START,STOP (s)")] = None,
):
    """Rectify, integrate (17-ms trapezoid), downsample and normalise EMG to activity in [0, 1]."""
    from .emg import process_emg
    from .io.activity import write_activity
    from .io.emg import read_emg

    sig, fs, names = read_emg(emg)
    cal = cal_fs = None
    if calibration is not None:
        cal, cal_fs, cal_names = read_emg(calibration)
        if tuple(n.upper() for n in cal_names) != tuple(n.upper() for n in names):
            raise InputError("calibration channels differ from the recording's",
                             source=str(calibration), field="header")
    res = process_emg(sig, fs, names, out_rate=rate, baseline=_interval(baseline, "baseline"),
                      calibration=cal, calibration_rate=cal_fs,
                      calibration_baseline=_interval(calibration_baseline, "calibration-baseline"),
                      source=str(emg))
    write_activity(output, res.time, res.activity, res.channels)
    out.print(f"{len(res.time)} frames at {rate:g} Hz, channels {', '.join(res.channels)} "
              f"-> {output}")


# ---------------------------------------------------------------------------------------------
UnitsOpt = Annotated[str | None, typer.Option("--units", help="length unit if the file has none")]


@markers_app.command("info")
def markers_info(
    path: Annotated[Path, typer.Argument(help="marker file: .c3d, .trc, .csv or .tsv")],
    units: UnitsOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
):
    """Rate, units, markers and gaps of a marker file."""
    from .io.markers import read_markers
    from .kinematics.gaps import find_gaps

    ms = read_markers(path, units=units)
    gaps = find_gaps(ms)
    info = {
        "file": str(path), "format": ms.meta.get("format"), "rate_hz": ms.rate,
        "frames": ms.n_frames, "duration_s": float(ms.time[-1] - ms.time[0]),
        "units": ms.source_units, "markers": list(ms.names),
        "missing_samples": int((~ms.valid).sum()),
        "gaps": [{"marker": g.marker, "start": g.start, "frames": g.length,
                  "interior": g.interior} for g in gaps],
    }
    if as_json:
        print(json.dumps(info, indent=2))
        return
    out.print(f"{path}: {info['format']}, {ms.rate:g} Hz, {ms.n_frames} frames "
              f"({info['duration_s']:.2f} s), unit {ms.source_units}, {ms.n_markers} markers")
    out.print("markers: " + ", ".join(ms.names))
    out.print(f"gaps: {len(gaps)} ({info['missing_samples']} missing samples)")
    for g in gaps[:50]:
        out.print(f"  {g.marker}: frames {g.start}-{g.stop - 1} ({g.length})"
                  + ("" if g.interior else " at an end"))


@markers_app.command("convert")
def markers_convert(
    source: Annotated[Path, typer.Argument(help="input marker file (or a results .nc file: "
                                                "its model markers)")],
    target: Annotated[Path, typer.Argument(help="output: .c3d, .trc or .csv")],
    units: UnitsOpt = None,
    out_units: Annotated[str | None, typer.Option(help="unit of the output (default: input's)")]
    = None,
):
    """Convert between C3D, TRC, CSV (and read Qualisys TSV or a results file's markers)."""
    from .io.markers import read_markers, write_markers

    ms = read_markers(source, units=units)
    write_markers(target, ms, units=out_units)
    out.print(f"{ms.n_markers} markers, {ms.n_frames} frames -> {target}")


@markers_app.command("head-correct")
def markers_head_correct(
    source: Annotated[Path, typer.Argument(help="input marker file")],
    head: Annotated[str, typer.Option(help="comma-separated head markers (at least 3)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output marker file")],
    reference: Annotated[int | None, typer.Option(help="reference frame (default: first "
                                                        "with every head marker)")] = None,
    units: UnitsOpt = None,
    report: Annotated[Path | None, typer.Option(help="write the per-frame residuals (JSON)")]
    = None,
):
    """Remove head motion by a per-frame rigid fit of head markers to a reference frame."""
    from .io.atomic import atomic_path
    from .io.markers import read_markers, write_markers
    from .kinematics.rigid import head_correct

    ms = read_markers(source, units=units)
    names = [h.strip() for h in head.split(",") if h.strip()]
    res = head_correct(ms, names, reference=reference)
    write_markers(output, res.markers)
    if report is not None:
        data = {**res.summary(), "residual_mm": (res.residual * 1e3).tolist(),
                "head_markers_used": res.head_markers_used.tolist()}
        with atomic_path(report, suffix=".json") as tmp:
            tmp.write_text(json.dumps(data, allow_nan=True))
    s = res.summary()
    out.print(f"head-corrected {ms.n_frames} frames against frame {s['reference_frame']}: "
              f"median residual {s['residual_mm']['median']:.3f} mm, max "
              f"{s['residual_mm']['max']:.3f} mm -> {output}")
    if len(res.unfixed_frames):
        err.print(f"facemech: warning: {len(res.unfixed_frames)} frames had fewer than 3 usable "
                  f"head markers and are left empty: {res.unfixed_frames[:20].tolist()}")


@markers_app.command("resample")
def markers_resample(
    source: Annotated[Path, typer.Argument(help="input marker file")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output marker file")],
    rate: Annotated[float, typer.Option(help="new rate, Hz")] = 60.0,
    units: UnitsOpt = None,
):
    """Resample to a new rate with anti-aliasing (gaps stay gaps)."""
    from .io.markers import read_markers, write_markers
    from .kinematics.resample import resample as run

    ms = read_markers(source, units=units)
    res = run(ms, rate)
    write_markers(output, res)
    out.print(f"{ms.rate:g} Hz -> {rate:g} Hz, {res.n_frames} frames -> {output}")


@markers_app.command("frame")
def markers_frame(
    source: Annotated[Path, typer.Argument(help="input marker file (head-corrected)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output marker file")],
    right: Annotated[str, typer.Option(help="marker on the subject's right (sets +x)")],
    left: Annotated[str, typer.Option(help="marker on the subject's left")],
    front: Annotated[str, typer.Option(help="marker in front of them on the same plane")],
    origin: Annotated[str | None, typer.Option(help="origin marker (default: --front)")] = None,
    reference: Annotated[int, typer.Option(help="frame the axes are taken from")] = 0,
    units: UnitsOpt = None,
):
    """Express markers in an anatomical frame: +x right->left, +y up, +z forward."""
    from .io.markers import read_markers, write_markers
    from .kinematics.frames import to_anatomical_frame

    ms = read_markers(source, units=units)
    res = to_anatomical_frame(ms, right=right, left=left, front=front, origin=origin,
                              reference=reference)
    write_markers(output, res)
    out.print(f"markers in the frame of {right}, {left}, {front} (origin {origin or front}) "
              f"-> {output}")


@markers_app.command("fill-gaps")
def markers_fill_gaps(
    source: Annotated[Path, typer.Argument(help="input marker file")],
    output: Annotated[Path, typer.Option("-o", "--output", help="output marker file")],
    max_gap: Annotated[float, typer.Option(help="longest gap to fill, seconds")] = 0.1,
    units: UnitsOpt = None,
):
    """Fill interior gaps up to --max-gap with a cubic spline; filled samples are flagged."""
    from .io.markers import read_markers, write_markers
    from .kinematics.gaps import fill_gaps

    ms = read_markers(source, units=units)
    res, done, left = fill_gaps(ms, int(round(max_gap * ms.rate)))
    write_markers(output, res)
    out.print(f"filled {len(done)} gaps ({sum(g.length for g in done)} samples); "
              f"{len(left)} left -> {output}")
    for g in left[:20]:
        err.print(f"  not filled: {g.marker} frames {g.start}-{g.stop - 1} ({g.length})"
                  + ("" if g.interior else " at an end"))


# ---------------------------------------------------------------------------------------------
def _jaw_from_chin(path: Path, marker: str, model, times: np.ndarray, bite_block: bool,
                   units: str | None, params):
    from .io.markers import read_markers
    from .solvers.jaw import jaw_angles_from_marker

    table = read_markers(path, units=units)
    y = table.marker(marker)[:, 1]
    if times[0] < table.time[0] - 1e-6 or times[-1] > table.time[-1] + 1e-6:
        raise InputError("the chin trajectory does not cover the activity's time span",
                         source=str(path), field="time")
    y = np.interp(times, table.time, y)
    node = model.markers.get(marker, model.landmarks["chin"])
    return jaw_angles_from_marker(model, params, node, y, bite_block=bite_block,
                                  source=str(path))


def _jaw_from_two_markers(path: Path, first: str, second: str, model, times: np.ndarray,
                          bite_block: bool, units: str | None) -> np.ndarray:
    """Jaw poses (frames, 3) from two mandible markers of a marker file (model axes): the
    recording is moved so that the first marker's first sample sits on the face's node of that
    name (the chin landmark if the face has none), and the poses are taken about the face's
    hinge (:func:`facemech.solvers.jaw.jaw_poses_from_points`)."""
    from .io.markers import read_markers
    from .solvers.jaw import jaw_poses_from_points

    table = read_markers(path, units=units)
    if times[0] < table.time[0] - 1e-6 or times[-1] > table.time[-1] + 1e-6:
        raise InputError("the jaw markers do not cover the activity's time span",
                         source=str(path), field="time")
    pts = [np.stack([np.interp(times, table.time, table.marker(m)[:, a]) for a in range(3)],
                    axis=1) for m in (first, second)]
    node = model.markers.get(first, model.landmarks["chin"])
    offset = model.rest_positions[node] - pts[0][0]
    return jaw_poses_from_points(pts[0] + offset, pts[1] + offset,
                                 hinge_point=model.hinge_point, bite_block=bite_block,
                                 names=(first, second), source=str(path))


def _jaw_from_csv(path: Path, times: np.ndarray) -> np.ndarray:
    from .io.tables import read_table

    t, cols = read_table(path)
    cols.pop("__meta__")
    if "jaw_angle" in cols:
        a = cols["jaw_angle"]
    elif "jaw_angle_deg" in cols:
        a = np.radians(cols["jaw_angle_deg"])
    else:
        raise InputError("needs a jaw_angle (rad) or jaw_angle_deg column", source=str(path),
                         field="jaw_angle")
    if not np.all(np.isfinite(a)):
        raise InputError("empty or NaN values", source=str(path), field="jaw_angle")
    if times[0] < t[0] - 1e-6 or times[-1] > t[-1] + 1e-6:
        raise InputError("the jaw series does not cover the activity's time span",
                         source=str(path), field="time")
    return np.interp(times, t, a)


@app.command()
def simulate(
    output: Annotated[Path, typer.Option("-o", "--output", help="results file (.nc)")],
    face: FaceOpt = "default",
    activity: Annotated[Path | None, typer.Option(help="activity CSV (time + groups)")] = None,
    emg: Annotated[Path | None, typer.Option(help="raw EMG (CSV or C3D), 7-channel control")]
    = None,
    emg_baseline: Annotated[str | None, typer.Option(help="EMG rest interval START,STOP (s)")]
    = None,
    emg_calibration: Annotated[Path | None, typer.Option(help="EMG of maximal gestures")] = None,
    jaw_chin: Annotated[Path | None, typer.Option(help="marker file with the chin marker")]
    = None,
    chin_marker: Annotated[str, typer.Option(help="name of the chin marker")] = "R01",
    jaw_second_marker: Annotated[str | None, typer.Option(
        help="a second mandible marker in the --jaw-chin file (e.g. a molar): the two drive "
             "the jaw's rotation and condyle shift")] = None,
    marker_units: Annotated[str | None, typer.Option(
        help="length unit of the marker file if it does not say")] = None,
    jaw_angle: Annotated[Path | None, typer.Option(help="CSV: time, jaw_angle (rad) or "
                                                        "jaw_angle_deg")] = None,
    bite_block: Annotated[bool, typer.Option(help="hold the jaw at its initial angle")] = False,
    jaw_kinematics: Annotated[str | None, typer.Option(
        help="hinge or glide: how a jaw angle moves the mandible (default: the preset's)")]
    = None,
    preset: PresetOpt = "anatomical",
    integrator: Annotated[str | None, typer.Option(
        help="euler, implicit or rosenbrock (default: the preset's)")] = None,
    substeps: Annotated[int | None, typer.Option(
        help="steps per frame of the implicit integrators (default: the preset's)")] = None,
    dt: Annotated[float | None, typer.Option(help="explicit Euler step, s (default: the "
                                                  "preset's; implicit integrators: --substeps)")]
    = None,
    jaw_drive: Annotated[str, typer.Option(help="ramp or hold")] = "ramp",
    video: Annotated[Path | None, typer.Option(help="also render an MP4, or PNG frames into "
                                                    "a folder")] = None,
    audio: Annotated[Path | None, typer.Option(help="WAV to mux into the MP4")] = None,
    view: ViewOpt = "frontal+profile",
    size: SizeOpt = "1280x720",
    background: BackgroundOpt = "#2a2c33",
    aa: AAOpt = 2,
):
    """Simulate the face driven by muscle activity or EMG and a jaw trajectory."""
    from . import params as P
    from .emg import process_emg
    from .geometry.builder import load_face
    from .io.activity import read_activity, seven_channel_control
    from .io.emg import read_emg
    from .io.results import file_hash, write_results
    from .solvers.forward import simulate as run

    if (activity is None) == (emg is None):
        raise InputError("give exactly one of --activity and --emg", field="activity")
    if jaw_chin is not None and jaw_angle is not None:
        raise InputError("give at most one of --jaw-chin and --jaw-angle", field="jaw")
    if jaw_second_marker is not None and jaw_chin is None:
        raise InputError("--jaw-second-marker names a marker of the --jaw-chin file: give "
                         "--jaw-chin too", field="jaw-second-marker")
    prm = P.preset(preset)
    if jaw_kinematics is not None:
        prm = prm.with_(jaw_kinematics=jaw_kinematics)
    opts = _render_options(view, size, background, aa) if video is not None else None
    model = load_face(face, tissue=prm.tissue)
    inputs = {}
    if activity is not None:
        times, act = read_activity(activity, frame_rate=prm.frame_rate)
        inputs["activity"] = file_hash(activity)
        src = str(activity)
    else:
        sig, fs, names = read_emg(emg)
        cal = cal_fs = None
        if emg_calibration is not None:
            cal, cal_fs, _ = read_emg(emg_calibration)
            inputs["emg_calibration"] = file_hash(emg_calibration)
        res = process_emg(sig, fs, names, out_rate=prm.frame_rate,
                          baseline=_interval(emg_baseline, "emg-baseline"), calibration=cal,
                          calibration_rate=cal_fs, source=str(emg))
        times = res.time
        act = seven_channel_control(dict(zip(res.channels, res.activity.T, strict=True)))
        inputs["emg"] = file_hash(emg)
        src = str(emg)
    if jaw_chin is not None and jaw_second_marker is not None:
        jaw = _jaw_from_two_markers(jaw_chin, chin_marker, jaw_second_marker, model, times,
                                    bite_block, marker_units)
        inputs["jaw_chin"] = file_hash(jaw_chin)
    elif jaw_chin is not None:
        jaw = _jaw_from_chin(jaw_chin, chin_marker, model, times, bite_block, marker_units, prm)
        inputs["jaw_chin"] = file_hash(jaw_chin)
    elif jaw_angle is not None:
        jaw = _jaw_from_csv(jaw_angle, times)
        if bite_block:
            jaw = np.full_like(jaw, jaw[0])
        inputs["jaw_angle"] = file_hash(jaw_angle)
    else:
        jaw = np.zeros(len(times))
    with _progress() as prog:
        task = prog.add_task(f"simulate ({integrator or prm.integrator})", total=len(times) - 1)
        sim = run(model, act, jaw, params=prm, integrator=integrator, substeps=substeps, dt=dt,
                  jaw_drive=jaw_drive, source=src,
                  progress=lambda d, n: prog.update(task, completed=d))
    write_results(output, sim, inputs=inputs)
    out.print(f"{len(times)} frames, {sim.wall_seconds:.1f} s wall "
              f"(real-time factor {sim.real_time_factor:.2f}) -> {output}")
    if video is not None:
        from .io.results import to_dataset

        _render(to_dataset(sim), video, audio, opts)


def _render(ds, path, audio, opts, source=None):
    from .viz.video import render_results

    with _progress() as prog:
        task = prog.add_task("render", total=ds.sizes["time"])
        render_results(ds, path, options=opts, audio=audio, source=source,
                       progress=lambda d, n: prog.update(task, completed=d))
    out.print(f"{'movie' if path.suffix else 'frames'} -> {path}")


@app.command()
def render(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="movie (.mp4), or a folder for "
                                                               "PNG frames")],
    audio: Annotated[Path | None, typer.Option(help="WAV to mux in")] = None,
    view: ViewOpt = "frontal+profile",
    size: SizeOpt = "1280x720",
    background: BackgroundOpt = "#2a2c33",
    aa: AAOpt = 2,
):
    """Render a results file to an H.264 MP4 or PNG frames, with eyes, teeth and tongue."""
    from .io.results import read_results

    opts = _render_options(view, size, background, aa)
    _render(read_results(result), output, audio, opts, source=str(result))


@app.command()
def still(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="figure (.png or .pdf)")],
    time: Annotated[float | None, typer.Option(help="time of the frame, s")] = None,
    peak: Annotated[str | None, typer.Option(help="the frame of a peak: a muscle group "
                                                  "(e.g. OOS), jaw, or motion")] = None,
    markers: Annotated[bool, typer.Option(help="draw the model's markers as dots")] = False,
    labels: Annotated[bool, typer.Option(help="name the markers")] = False,
    view: ViewOpt = "frontal",
    size: SizeOpt = "1280x1280",
    background: BackgroundOpt = "#ffffff",
    aa: AAOpt = 3,
):
    """A still figure for a paper: one frame at a time or at a gesture's peak (PNG or PDF)."""
    from .io.results import read_results
    from .viz.video import still as draw

    opts = _render_options(view, size, background, aa)
    r = draw(read_results(result), output, time=time, peak=peak, options=opts,
             markers=markers or labels, labels=labels, source=str(result))
    out.print(f"frame {r['frame']} (t = {r['time']:.3f} s) -> {output}")


@app.command()
def export(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    output: Annotated[Path, typer.Option("-o", "--output", help=".glb (animated glTF), .trc, "
                                         ".c3d or .csv (markers), or a folder (mesh sequence)")],
    fmt: Annotated[str | None, typer.Option("--format", help="obj or ply: one mesh per frame in "
                                            "the folder -o")] = None,
    units: Annotated[str | None, typer.Option(help="length unit: meshes m (default) or mm, "
                                              "markers mm (default); glTF is always m")] = None,
):
    """Export a result: animated skin as glTF, a mesh per frame (OBJ/PLY), or markers."""
    from .io.export import export_results

    out.print(export_results(result, output, fmt=fmt, units=units).summary())


def _o(help: str, *names: str):
    return typer.Option(*names, help=help)


def _wf(name: str):  # facemech.workflows.NAME, imported when its command runs: a light CLI
    from importlib import import_module
    return import_module(f"{__package__}.workflows.{name}")


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
    _say(_wf("speech").speak_report(_staged(_wf("speech").speak, **locals()), output))


@app.command()
def describe(result: Annotated[Path, typer.Argument(help="results file (.nc)")],
             as_json: Annotated[bool, _o("print JSON", "--json")] = False,
             series: Annotated[bool, _o("with --json: the per-frame mouth measures")] = False):
    """Stimulus parameters of a result: lips, jaw, mouth corners, AV offset, settings."""
    text = _wf("speech").describe_text(result, as_json=as_json, series=series)
    print(text) if as_json else out.print(text, markup=False, highlight=False)


@app.command()
def stimuli(design: Annotated[Path, typer.Argument(help="design table (.csv or .toml)")],
            output: OutDirOpt, video: VideoOpt = True, view: ViewOpt = "frontal",
            size: SizeOpt = "1280x720", background: BackgroundOpt = "#2a2c33", aa: AAOpt = 2):
    """Make the stimuli of a design table (docs/stimuli.md) as results, WAV, MP4, manifest."""
    made, failed = _wf("speech").stimuli_report(_staged(_wf("speech").stimuli, **locals()))
    _say(failed, True, markup=False, highlight=False, soft_wrap=True)
    _say(made)
    raise typer.Exit(2 if failed else 0)


@app.command()
def plot(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="figure (.png)")],
    markers: Annotated[str, typer.Option(help="comma-separated marker names")] = "R03,R05,R07",
    measured: Annotated[Path | None, typer.Option(help="measured markers CSV (same names)")]
    = None,
    marker_units: Annotated[str | None, typer.Option(help="unit of the measured file")] = None,
):
    """Plot displacement and acceleration (vertical, protrusion) of markers, like Figs. 4-6."""
    from .io.markers import read_markers
    from .io.results import read_results
    from .viz.plots import kinematics_figure

    ds = read_results(result)
    names = [m.strip() for m in markers.split(",") if m.strip()]
    have = list(ds["marker"].values)
    for n in names:
        if n not in have:
            raise InputError(f"no such marker in the results (have {', '.join(have[:20])})",
                             source=str(result), field=n)
    time = ds["time"].values
    traj = {n: ds["markers"].sel(marker=n).values for n in names}
    meas = None
    if measured is not None:
        table = read_markers(measured, units=marker_units)
        meas = {}
        for n in names:
            if n in table.names:
                m = table.marker(n)
                meas[n] = np.column_stack([np.interp(time, table.time, m[:, a])
                                           for a in range(3)])
    kinematics_figure(output, time, traj, rate=float(ds.attrs.get("frame_rate_hz", 60.0)),
                      measured=meas, title=str(result.name))
    out.print(f"figure -> {output}")


@app.command()
def view(
    result: Annotated[Path, typer.Argument(help="results file (.nc)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="page (.html)")],
    markers: Annotated[Path | None, typer.Option(
        help="measured markers (.csv .trc .c3d .tsv) in the model's frame, drawn beside the "
             "model's markers of the same name")] = None,
    units: UnitsOpt = None,
    title: Annotated[str | None, typer.Option(help="page title")] = None,
):
    """Write an interactive viewer: one self-contained HTML page (WebGL, works offline)."""
    from .viz.viewer import view_file

    path = view_file(result, output, markers=markers, units=units, title=title)
    out.print(f"viewer -> {path} ({path.stat().st_size / 1e6:.1f} MB)")


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
    _say(_wf("regions").report(_wf("regions").regions(**locals()), output))


@experiment_app.command("lucero2008")
def experiment_lucero2008(
        output: OutDirOpt = Path("lucero2008"), frames: Annotated[int, _o("per utterance")] = 60,
        utterances: Annotated[int, _o("utterances in the corpus")] = 40,
        k: Annotated[int, _o("markers of the basis", "-k")] = 10, video: VideoOpt = True):
    """Lucero & Munhall (2008) on the embedded corpus, our numbers beside the paper's."""
    res = _staged(_wf("experiments").lucero2008, **locals())
    _say(_wf("experiments").lucero2008_report(res, output))


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
    res = _staged(_wf("invert").invert, **locals())
    _say(_wf("invert").report(res, output, figure))
    _say(_wf("invert").notes(res), True)


@app.command()
def compare(a: Annotated[Path, typer.Argument(help="results or marker file: the model")],
            b: Annotated[Path, typer.Argument(help="results or marker file: the data")],
            markers: Annotated[str | None, _o("comma-separated (default: all shared)")] = None,
            as_json: Annotated[bool, _o("print JSON", "--json")] = False, units: UnitsOpt = None):
    """3-D statistics, per-axis correlations and per-frame errors (RMS, mm) of A against B."""
    res = _wf("compare").compare_files(a, b, markers=markers, units=units)
    _say([f"warning: {w}" for w in res.warnings], True, markup=False, highlight=False)
    (print if as_json else out.print)("\n".join(_wf("compare").report(res, as_json=as_json)))


@experiment_app.command("pitermann2001-synthetic")
def experiment_pitermann_synthetic(
        method: Annotated[str, _o("lsq, powell or both")] = "lsq", dt: DtOpt = None,
        noise_mm: Annotated[float, _o("Gaussian marker noise, mm", "--noise")] = 0.0,
        preset: PresetOpt = "anatomical", figures: Annotated[bool, _o("with -o: PNGs")] = True,
        output: Annotated[Path | None, _o("folder: summary.json, PNGs", "-o", "--output")] = None):
    """Pitermann & Munhall (2001) Experiment 1: Tables I, II and the top of Table III."""
    res = _staged(_wf("experiments").synthetic, **locals())
    _say(_wf("experiments").synthetic_report(res, output, figures=figures))


@experiment_app.command("pitermann2001-crosstalker")
def experiment_pitermann_crosstalker(
        frames: Annotated[int, _o("frames of the gesture sequence")] = 120, dt: DtOpt = None,
        preset: PresetOpt = "anatomical",
        output: Annotated[Path | None, _o("JSON file of the table", "-o", "--output")] = None):
    """Experiment 3 analogue: another talker inverted on the default face (Table VI)."""
    res = _staged(_wf("experiments").crosstalker, **locals())
    _say(_wf("experiments").crosstalker_report(res, output))


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
    res = _staged(_wf("calibrate").calibrate, **locals())
    _say(_wf("calibrate").report(res, output, builtin=builtin))


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
