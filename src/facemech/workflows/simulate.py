"""The simulation workflow: muscle input (activity or EMG, :class:`Controls`), a jaw trajectory
(:class:`~facemech.jaw.inputs.JawSource`, :func:`facemech.jaw.series.jaw_series`), the face
driven by them as :class:`Stepping` says, the results written and, if asked, rendered."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..jaw.inputs import JawSource
from ..jaw.series import (  # noqa: F401 (re-exported)
    bite_block,
    jaw_from_bone,
    jaw_from_chin,
    jaw_from_csv,
    jaw_from_two_markers,
    jaw_series,
)
from ..progress import StagedProgress, stage
from .inputs import Controls, Stepping

__all__ = ["Controls", "JawSource", "SimulationRun", "Stepping", "input_notes", "jaw_series",
           "read_controls", "simulate_files", "simulate_to_file"]


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
                   stepping: Stepping = Stepping(), movie=None,
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
    stepping : the jaw's kinematics, the integrator, its substeps and ``dt`` (None: the
        preset's) and the jaw's drive within a frame (:class:`Stepping`)
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
    if stepping.jaw_kinematics is not None:
        params = params.with_(jaw_kinematics=stepping.jaw_kinematics)

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
    label = f"simulate ({stepping.integrator or model.steps.integrator})"
    run = simulate_to_file(output, model, act, jaw_angles, inputs=inputs, source=src,
                           progress=stage(progress, label), **stepping.solver_options())
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
