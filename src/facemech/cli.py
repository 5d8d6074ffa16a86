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
