"""The simulation workflow: muscle input (activity or EMG), a jaw trajectory (a CSV of angles,
a chin marker, two mandible markers, a lower-incisor sensor with or without a molar pellet, or
none; with or without a bite block), the face driven by them, the results written and, if
asked, rendered."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..plausibility import check_jaw_angles
from ..progress import StagedProgress, stage


@dataclass(frozen=True)
class Controls:
    """Where the muscle input comes from: exactly one of ``activity`` (a CSV, time and muscle
    groups in [0, 1]) and ``emg`` (raw EMG, CSV or C3D, the seeds' seven channels), with the
    EMG's rest interval ``emg_baseline`` (start, stop) s and a calibration recording of maximal
    gestures ``emg_calibration`` (its channels those of ``emg``)."""

    activity: Path | None = None
    emg: Path | None = None
    emg_baseline: str | tuple[float, float] | None = None
    emg_calibration: Path | None = None

    def __post_init__(self):
        if (self.activity is None) == (self.emg is None):
            raise InputError("give exactly one of --activity and --emg", field="activity")


@dataclass(frozen=True)
class JawSource:
    """Where the jaw's trajectory comes from: at most one of ``angles`` (a CSV of ``time`` and
    ``jaw_angle`` rad or ``jaw_angle_deg``) and ``markers`` (a marker file; lengths in ``units``
    if the file does not say); neither: the jaw stays closed. In the marker file, either a skin
    chin marker ``chin_marker`` (default ``R01``) and, for a two-marker drive, a second mandible
    marker ``second_marker``; or points on the bone: a lower-incisor sensor ``incisor`` and
    optionally a molar pellet ``molar`` (:func:`facemech.solvers.jaw_bone.jaw_poses_from_bone`;
    without names or a chin marker, a file whose sensors carry articulography roles gives its
    ``lower_incisor`` and ``molar``). ``bite_block`` holds the jaw at its first pose whatever
    the source."""

    angles: Path | None = None
    markers: Path | None = None
    chin_marker: str | None = None
    second_marker: str | None = None
    units: str | None = None
    bite_block: bool = False
    incisor: str | None = None
    molar: str | None = None

    def __post_init__(self):
        if self.markers is not None and self.angles is not None:
            raise InputError("give at most one of --jaw-chin and --jaw-angle", field="jaw")
        for name, opt in ((self.second_marker, "jaw-second-marker"),
                          (self.incisor, "jaw-incisor"), (self.molar, "jaw-molar")):
            if name is not None and self.markers is None:
                raise InputError(f"--{opt} names a marker of the --jaw-chin file: give "
                                 "--jaw-chin too", field=opt)
        if self.incisor is not None and (self.chin_marker or self.second_marker) is not None:
            raise InputError("give one jaw drive: bone points (--jaw-incisor) or skin markers "
                             "(--chin-marker)", field="jaw-incisor")
        if self.molar is not None and self.incisor is None:
            raise InputError("a molar point needs the lower incisor too (--jaw-incisor)",
                             field="jaw-molar")


def read_controls(controls: Controls, frame_rate: float) -> tuple[np.ndarray, np.ndarray, dict]:
    """The muscle activity of ``controls`` at ``frame_rate`` Hz.

    Returns
    -------
    time : (frames,) s
    activity : (frames, groups) in [0, 1], columns :data:`~facemech.params.MUSCLE_GROUPS`
    inputs : input name -> file hash, for the results' provenance
    """
    from ..io.activity import read_activity, seven_channel_control
    from ..io.results import file_hash
    from .emg import emg_activity

    if controls.activity is not None:
        times, act = read_activity(controls.activity, frame_rate=frame_rate)
        return times, act, {"activity": file_hash(controls.activity)}
    res = emg_activity(controls.emg, rate=frame_rate, baseline=controls.emg_baseline,
                       calibration=controls.emg_calibration, baseline_field="emg-baseline")
    act = seven_channel_control(dict(zip(res.channels, res.activity.T, strict=True)))
    inputs = {"emg": file_hash(controls.emg)}
    if controls.emg_calibration is not None:
        inputs["emg_calibration"] = file_hash(controls.emg_calibration)
    return res.time, act, inputs


def jaw_from_csv(path: str | Path, times: np.ndarray) -> np.ndarray:
    """Jaw angles (frames,) rad at ``times`` (s) from a CSV of ``time`` and ``jaw_angle`` (rad)
    or ``jaw_angle_deg``, interpolated linearly; the file must cover ``times``."""
    from ..io.tables import read_table

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
    check_jaw_angles(a, source=str(path),
                     field="jaw_angle" if "jaw_angle" in cols else "jaw_angle_deg")
    if times[0] < t[0] - 1e-6 or times[-1] > t[-1] + 1e-6:
        raise InputError("the jaw series does not cover the activity's time span",
                         source=str(path), field="time")
    return np.interp(times, t, a)


def _marker_node(model, name: str) -> int:
    """The face's epidermal node of marker ``name``, or its chin landmark."""
    return model.markers.get(name, model.landmarks["chin"])


def jaw_from_chin(path: str | Path, marker: str, model, times: np.ndarray, *,
                  units: str | None = None) -> np.ndarray:
    """Jaw angles (frames,) rad at ``times`` (s) from the vertical trajectory of a chin marker
    in a marker file (model axes), 33 ms early
    (:func:`facemech.solvers.jaw_drive.jaw_angles_from_marker`); the marker is the face's node of
    that name, or its chin landmark (``model``: a :class:`~facemech.physics.model.Model`). The
    file must cover ``times``."""
    from ..solvers.jaw_drive import jaw_angles_from_marker
    from .markers import trajectories

    y = trajectories(path, [marker], units=units, times=times,
                     cover="the chin trajectory")[1][marker][:, 1]
    return jaw_angles_from_marker(model, _marker_node(model.face, marker), y,
                                  source=str(path))


def jaw_from_two_markers(path: str | Path, first: str, second: str, model, times: np.ndarray,
                         *, units: str | None = None) -> np.ndarray:
    """Jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) at ``times`` from two mandible
    markers of a marker file (model axes).

    The recording is moved so that the first marker's first sample sits on the face's node of
    that name (the chin landmark if the face has none), and the poses are taken about the face's
    hinge (:func:`facemech.solvers.jaw.jaw_poses_from_points`).
    """
    from ..solvers.jaw import jaw_poses_from_points
    from .markers import trajectories

    pts = trajectories(path, [first, second], units=units, times=times,
                       cover="the jaw markers")[1]
    offset = model.rest_positions[_marker_node(model, first)] - pts[first][0]
    return jaw_poses_from_points(pts[first] + offset, pts[second] + offset,
                                 hinge_point=model.hinge_point, names=(first, second),
                                 source=str(path))


def jaw_from_bone(path: str | Path, model, times: np.ndarray, *,
                  incisor: str | None = None, molar: str | None = None,
                  units: str | None = None) -> np.ndarray | None:
    """Jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) at ``times`` from points on the
    bone in a marker file (model axes): the lower-incisor sensor ``incisor`` and the molar
    pellet ``molar``, or, without names, the sensors of roles ``lower_incisor`` and ``molar``
    (:func:`facemech.kinematics.roles.bone_points`); None when there is neither. No lead: the
    points are on the bone (:func:`facemech.solvers.jaw_bone.jaw_poses_from_bone`).
    """
    from ..io.markers import read_markers
    from ..kinematics.roles import bone_points
    from ..solvers.jaw_bone import jaw_poses_from_bone

    ms = read_markers(path, units=units)
    incisor, molar, _ = bone_points(ms, incisor=incisor, molar=molar)
    if incisor is None:
        return None
    if times[0] < ms.time[0] - 1e-6 or times[-1] > ms.time[-1] + 1e-6:
        raise InputError("the jaw's bone points do not cover the activity's time span",
                         source=str(path), field="time")
    pts = {n: np.column_stack([np.interp(times, ms.time, ms.marker(n)[:, a]) for a in range(3)])
           for n in (incisor, molar) if n is not None}
    return jaw_poses_from_bone(pts[incisor], model.face, model.params, molar=pts.get(molar),
                               names=(incisor, molar or "molar"), source=str(path))


def bite_block(jaw: np.ndarray) -> np.ndarray:
    """A jaw series (frames,) or (frames, 3) held at its first value: a bite block."""
    jaw = np.asarray(jaw, float)
    return np.repeat(jaw[:1], len(jaw), axis=0)


def jaw_series(source: JawSource, model, times: np.ndarray) -> tuple[np.ndarray, dict]:
    """The jaw of ``source`` at ``times`` (s) for ``model`` (a
    :class:`~facemech.physics.model.Model`).

    Returns
    -------
    jaw : (frames,) angles rad, or (frames, 3) poses for a two-marker or bone-point drive;
        zeros without a source; held at the first value under a bite block (the one place it
        is applied)
    inputs : input name -> file hash
    """
    from ..io.results import file_hash

    chin = source.chin_marker or "R01"
    bone = None
    if source.markers is not None and source.chin_marker is None and source.second_marker is None:
        bone = jaw_from_bone(source.markers, model, times, incisor=source.incisor,
                             molar=source.molar, units=source.units)
    if bone is not None:
        jaw = bone
    elif source.markers is not None and source.second_marker is not None:
        jaw = jaw_from_two_markers(source.markers, chin, source.second_marker,
                                   model.face, times, units=source.units)
    elif source.markers is not None:
        jaw = jaw_from_chin(source.markers, chin, model, times, units=source.units)
    elif source.angles is not None:
        jaw = jaw_from_csv(source.angles, times)
    else:
        return np.zeros(len(times)), {}
    path = source.markers if source.markers is not None else source.angles
    inputs = {"jaw_chin" if source.markers is not None else "jaw_angle": file_hash(path)}
    return (bite_block(jaw) if source.bite_block else jaw), inputs


@dataclass(frozen=True)
class SimulationRun:
    """What :func:`simulate_files` did: the run (its frames went to the file), the results
    file, the input hashes and the movie written (or None)."""

    simulation: object  # facemech.solvers.forward.RunSummary (or a Simulation)
    output: Path
    inputs: dict = field(default_factory=dict)
    movie: object | None = None  # outcome.Written
    notes: tuple = ()  # what was assumed: EMG without calibration, a jaw held at rest

    @property
    def warnings(self) -> str:
        """The notes, for stderr ("facemech: note: ..." lines)."""
        return "".join(f"facemech: note: {n}\n" for n in self.notes)

    def __str__(self) -> str:
        sim = self.simulation
        text = (f"{len(sim.time)} frames, {sim.wall_seconds:.1f} s wall (real-time factor "
                f"{sim.real_time_factor:.2f}) -> {self.output}")
        return text if self.movie is None else f"{text}\n{self.movie}"

    __rich__ = __str__


def simulate_files(output: str | Path, controls: Controls, jaw: JawSource = JawSource(), *,
                   face: str | Path = "default", preset: str = "anatomical",
                   jaw_kinematics: str | None = None, integrator: str | None = None,
                   substeps: int | None = None, dt: float | None = None,
                   jaw_drive: str = "ramp", movie=None,
                   progress: StagedProgress | None = None) -> SimulationRun:
    """Simulate a face driven by muscle input and a jaw trajectory; write the results.

    Parameters
    ----------
    output : results file (``.nc``), written atomically
    controls : the muscle input, :class:`Controls`
    jaw : the jaw's trajectory, :class:`JawSource` (default: closed)
    face : face file (``.npz``) or a built-in face (``default``, ``default-coarse``,
        ``default-fine``)
    preset : parameter preset name or a preset ``.json`` file
    jaw_kinematics : ``hinge`` or ``glide`` (default: the preset's)
    integrator, substeps, dt : as :func:`facemech.solvers.forward.simulate` (default: the
        preset's)
    jaw_drive : ``ramp`` or ``hold``
    movie : a :class:`facemech.workflows.pictures.Movie` (or its fields as a tuple) to render
        from the results; None for none
    progress : staged callback: ``simulate (INTEGRATOR)`` (frames), then ``render`` (frames)

    Returns
    -------
    SimulationRun
    """
    from ..atomic import check_output
    from ..params import preset_pair
    from ..physics.model import model as face_model

    params, steps = preset_pair(preset)
    if jaw_kinematics is not None:
        params = params.with_(jaw_kinematics=jaw_kinematics)

    given = [controls.activity, controls.emg, controls.emg_calibration, jaw.angles, jaw.markers,
             face if Path(str(face)).suffix else None]
    check_output(output, given, field="-o")
    if movie is not None:
        from .pictures import check_movie

        movie = check_movie(movie, [*given, output], field="video")
    times, act, inputs = read_controls(controls, params.frame_rate)  # before the slow face
    notes = input_notes(controls, jaw)
    model = face_model(face, params, steps=steps)
    jaw_angles, jaw_inputs = jaw_series(jaw, model, times)
    inputs.update(jaw_inputs)
    src = str(controls.activity if controls.activity is not None else controls.emg)
    run = simulate_to_file(output, model, act, jaw_angles, inputs=inputs,
                           integrator=integrator, substeps=substeps, dt=dt, jaw_drive=jaw_drive,
                           source=src, progress=stage(
                               progress, f"simulate ({integrator or model.steps.integrator})"))
    written = None
    if movie:  # from the file: the whole run in memory (rendering does not stream)
        from .pictures import render_movie

        written = render_movie(output, movie, progress=progress)
    return SimulationRun(run, Path(output), inputs, written, notes)


#: the note of a simulation with no jaw drive
JAW_AT_REST_NOTE = ("jaw: held at rest (closed) for the whole run, as no jaw drive was given "
                    "(--jaw-angle, --jaw-chin with --chin-marker, or --jaw-incisor)")


def input_notes(controls: Controls, jaw: JawSource) -> tuple[str, ...]:
    """The defaults a simulation takes silently otherwise: EMG scaled without a calibration
    recording, and the jaw held at rest when no drive is given."""
    notes = []
    if controls.emg is not None and controls.emg_calibration is None:
        notes.append("EMG scaled without a calibration recording: each channel's activity 1 is "
                     "its own maximum in this recording, so a channel that barely moves reaches "
                     "full activity; give a recording of maximal gestures (--emg-calibration)")
    if jaw.markers is None and jaw.angles is None:
        notes.append(JAW_AT_REST_NOTE)
    return tuple(notes)


def simulate_to_file(output: str | Path, model, activity: np.ndarray,
                     jaw_angle: np.ndarray | None = None, *, inputs: dict | None = None,
                     block_frames: int | None = None, **options):
    """Simulate and write the results file as the run goes, a block of frames at a time.

    Memory stays bounded whatever the run's length (a 10-minute utterance at 60 Hz is 36,000
    frames, about 1.8 GB held whole); the file reads exactly as the one
    :func:`~facemech.io.results.write_results` writes from :func:`~facemech.solvers.forward.
    simulate` (same variables, dimensions, attributes and values, bit for bit), ``time`` being
    an unlimited dimension. It is written atomically: an error or an interruption leaves
    neither ``output`` nor a temporary file.

    Parameters
    ----------
    output : results file (``.nc``)
    model : Model -- the face, its parameters and physics
        (:func:`facemech.physics.model.model`)
    activity : (frames, groups) array in [0, 1], columns :data:`~facemech.params.MUSCLE_GROUPS`
    jaw_angle : (frames,) rad or (frames, 3) poses, optional (default: jaw closed)
    inputs : input name -> file hash, for the results' provenance
    block_frames : frames held in memory at a time (default
        :data:`~facemech.solvers.forward.BLOCK_FRAMES`, 600: 10 s, about 30 MB)
    **options : ``integrator``, ``substeps``, ``dt``, ``jaw_drive``,
        ``initial_state``, ``progress``, ``source``, as :func:`~facemech.solvers.forward.
        simulate`

    Returns
    -------
    RunSummary
        The run without its frames (:class:`facemech.solvers.forward.RunSummary`): ``time``,
        ``final_state``, ``integrator``, ``dt``, ``wall_seconds``, ``real_time_factor``.
    """
    from ..io.results_stream import stream_results
    from ..solvers.forward import BLOCK_FRAMES, simulate_blocks

    with stream_results(output, inputs) as sink:
        return simulate_blocks(model, activity, jaw_angle, sink=sink,
                               block_frames=BLOCK_FRAMES if block_frames is None else block_frames,
                               **options)
