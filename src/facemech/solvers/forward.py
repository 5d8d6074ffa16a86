"""Forward simulation: muscle activity and jaw angle per frame -> node trajectories.

Frame k of the output is the state at ``t_k = k / 60`` s; the controls of frame k act over
``[t_k, t_{k+1})`` (the last frame's controls therefore never show). Blow-up is detected after
every frame and raised with the frame and the likely cause; nothing non-finite is returned.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, SimulationBlowUp
from ..geometry.builder import FaceModel
from ..params import MUSCLE_GROUPS, Parameters
from ..physics.assembly import Physics
from ..physics.model import Model
from ..physics.muscle_outputs import MuscleRecorder, MuscleSeries
from ..physics.threads import get_threads
from .state import State
from .step import Stepper

#: displacement (m) from rest beyond which a node is taken to have run away
RUNAWAY_DISPLACEMENT = 0.08
#: speed (m/s) beyond which a node is taken to have run away
RUNAWAY_SPEED = 20.0


@dataclass(frozen=True, eq=False)
class Simulation:
    """Result of a forward simulation.

    Attributes
    ----------
    time : (frames,) s
    positions : (frames, n_surface, 3) m -- epidermal nodes
    markers : (frames, markers, 3) m -- landmarks and virtual markers, named by ``marker_names``
    activity : (frames, groups) in [0, 1], columns :data:`~facemech.params.MUSCLE_GROUPS`
    jaw_angle : (frames,) rad
    jaw_shift : (frames, 2) m -- the condyles' shift (y, z); None: zeros (a hinge)
    final_state : State
    wall_seconds : float
    muscles : MuscleSeries or None
        Per frame and muscle instance: tension (N), length (m), lengthening velocity (m/s) and
        activation state (N) (:mod:`facemech.physics.muscle_outputs`); None where not computed
    """

    model: FaceModel
    params: Parameters
    time: np.ndarray
    positions: np.ndarray
    markers: np.ndarray
    marker_names: tuple[str, ...]
    activity: np.ndarray
    jaw_angle: np.ndarray
    final_state: State
    integrator: str
    dt: float
    wall_seconds: float
    attrs: dict = field(default_factory=dict)
    muscles: MuscleSeries | None = None
    jaw_shift: np.ndarray | None = None

    @property
    def jaw_pose(self) -> np.ndarray:
        """(frames, 3) the jaw's pose per frame: angle (rad), shift_y, shift_z (m)."""
        shift = (np.zeros((len(self.jaw_angle), 2)) if self.jaw_shift is None
                 else self.jaw_shift)
        return np.column_stack([self.jaw_angle, shift])

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        simulated = len(self.time) / self.params.frame_rate
        return simulated / max(self.wall_seconds, 1e-12)

    def marker(self, name: str) -> np.ndarray:
        """Trajectory (frames, 3) of one named landmark or marker, metres."""
        return self.markers[:, self.marker_names.index(name)]


def marker_nodes(model: FaceModel) -> tuple[tuple[str, ...], np.ndarray]:
    """Names and epidermal nodes of every landmark and virtual marker of a face."""
    names = tuple(model.landmarks) + tuple(model.markers)
    nodes = np.array([*model.landmarks.values(), *model.markers.values()], dtype=np.int64)
    return names, nodes


def check_activity(activity: np.ndarray, *, source: str | None = None) -> np.ndarray:
    """Validate an activity array (frames, groups): finite and within [0, 1]."""
    a = np.asarray(activity, float)
    if a.ndim != 2 or a.shape[1] != len(MUSCLE_GROUPS):
        raise InputError(f"activity must have shape (frames, {len(MUSCLE_GROUPS)}), got {a.shape}",
                         source=source, field="activity")
    if len(a) < 2:
        raise InputError("activity needs at least two frames", source=source, field="time")
    bad = ~np.isfinite(a) | (a < 0) | (a > 1)
    if bad.any():
        f, g = np.argwhere(bad)[0]
        raise InputError(f"value {a[f, g]!r} at frame {f} is outside [0, 1]", source=source,
                         field=MUSCLE_GROUPS[g])
    return a


def _check_state(state: State, rest: np.ndarray, frame: int, activity, jaw) -> None:
    pos, vel = state.positions, state.velocities
    if not (np.all(np.isfinite(pos)) and np.all(np.isfinite(vel))):
        cause = "non-finite positions"
    else:
        disp = np.linalg.norm(pos - rest, axis=1).max()
        speed = np.linalg.norm(vel, axis=1).max()
        if disp < RUNAWAY_DISPLACEMENT and speed < RUNAWAY_SPEED:
            return
        cause = f"runaway nodes (displacement {disp * 1e3:.0f} mm, speed {speed:.1f} m/s)"
    hint = ("the time step is too large for the stiffness and damping (try a smaller --dt or "
            "the implicit integrator)")
    if np.max(activity) > 0.999 and abs(jaw) > np.radians(15):
        hint = "full activity with a wide jaw opening stretches the mesh past its range"
    raise SimulationBlowUp(f"{cause}; likely cause: {hint}", frame=frame)


def simulate(
    model: Model,
    activity: np.ndarray,
    jaw_angle: np.ndarray | None = None,
    *,
    integrator: str | None = None,
    substeps: int | None = None,
    dt: float | None = None,
    jaw_drive: str = "ramp",
    initial_state: State | None = None,
    progress: Callable[[int, int], None] | None = None,
    source: str | None = None,
) -> Simulation:
    """Simulate the face driven by muscle activity and jaw angles at the frame rate (60 Hz).

    Parameters
    ----------
    model : Model -- the face, its parameters and physics (:func:`facemech.physics.model.model`);
        ``Simulation.model`` is its face, ``Simulation.params`` its parameters
    activity : (frames, groups) array in [0, 1], columns :data:`~facemech.params.MUSCLE_GROUPS`
    jaw_angle : (frames,) rad or (frames, 3) poses, optional (default: jaw closed)
        The jaw's angle per frame, its condyles' shift then following the preset's
        ``jaw_kinematics`` (the coupled glide of the anatomical preset, none for the seeds'
        hinge), or its whole pose per frame: angle (rad), shift_y (m), shift_z (m).
    integrator : {"euler", "implicit", "rosenbrock"}, optional (default: the preset's)
    substeps : steps per frame of the implicit integrators (default: the preset's)
    dt : step of the explicit integrator (default: the preset's, 0.33 ms for the seeds')
    jaw_drive : {"ramp", "hold"}
        ``ramp`` moves the jaw steadily from each frame's pose to the next; ``hold`` sets each
        frame's pose at the frame's start and holds it (the paper).
    initial_state : State to start from (default: rest)
    progress : callable(done_frames, total_frames), optional

    Returns
    -------
    Simulation
    """
    run = _setup(model, activity, jaw_angle, integrator=integrator,
                 substeps=substeps, dt=dt, jaw_drive=jaw_drive, initial_state=initial_state,
                 source=source)
    frames = len(run.activity)
    positions = np.empty((frames, run.model.n_surface, 3))
    recorder = MuscleRecorder(run.physics, frames)
    t0 = _time.perf_counter()
    with single_threaded_blas():
        state = _run(run.stepper, run.state, run.activity, run.poses, jaw_drive, positions,
                     run.rest, progress, recorder)
    return run.block(0, positions, recorder.series(), state, _time.perf_counter() - t0)


#: frames per block of :func:`simulate_blocks` (10 s at 60 Hz, about 30 MB)
BLOCK_FRAMES = 600


@dataclass(frozen=True, eq=False)
class RunSummary:
    """What :func:`simulate_blocks` returns: the run without its frames (they went to the sink).

    Attributes
    ----------
    time : (frames,) s
    final_state : State
    integrator : str
    dt : float, s
    wall_seconds : float
    frame_rate : float, Hz
    """

    time: np.ndarray
    final_state: State
    integrator: str
    dt: float
    wall_seconds: float
    frame_rate: float

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return len(self.time) / self.frame_rate / max(self.wall_seconds, 1e-12)


def simulate_blocks(
    model: Model,
    activity: np.ndarray,
    jaw_angle: np.ndarray | None = None,
    *,
    sink: Callable[[Simulation], None],
    block_frames: int = BLOCK_FRAMES,
    jaw_drive: str = "ramp",
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> RunSummary:
    """:func:`simulate`, its frames handed to ``sink`` block by block instead of being held.

    The frames are the very numbers :func:`simulate` returns (the same steps in the same
    order); only ``block_frames`` of them are in memory at a time, so memory does not grow with
    the run's length.

    Parameters
    ----------
    model, activity, jaw_angle, jaw_drive, progress : as :func:`simulate`
    sink : callable(Simulation)
        Called with each block of consecutive frames, in order, as a :class:`Simulation` of
        those frames: ``time`` (block,) s (absolute), ``positions`` (block, n_surface, 3) m,
        ``markers``, ``activity``, ``jaw_angle``, ``jaw_shift``, ``muscles`` of the block's
        frames; ``final_state`` the state of its last frame, ``wall_seconds`` the time spent
        so far. The arrays are the sink's to keep.
    block_frames : frames per block (the last block may be shorter)
    **options : ``integrator``, ``substeps``, ``dt``, ``initial_state``, ``source``, as
        :func:`simulate`

    Returns
    -------
    RunSummary
    """
    if int(block_frames) < 1:
        raise InputError(f"block_frames must be at least 1, got {block_frames}",
                         field="block_frames")
    unknown = set(options) - {"integrator", "substeps", "dt", "initial_state", "source"}
    if unknown:
        raise TypeError(f"simulate_blocks() got unexpected options {sorted(unknown)}")
    run = _setup(model, activity, jaw_angle, **{"integrator": None,
                                                "substeps": None, "dt": None,
                                                "initial_state": None, "source": None,
                                                **options}, jaw_drive=jaw_drive)
    frames = len(run.activity)
    state = run.state
    t0 = _time.perf_counter()
    with single_threaded_blas():
        for start in range(0, frames, int(block_frames)):
            m = min(int(block_frames), frames - start)
            positions = np.empty((m, run.model.n_surface, 3))
            recorder = MuscleRecorder(run.physics, m)
            state = _run(run.stepper, state, run.activity, run.poses, jaw_drive, positions,
                         run.rest, progress, recorder, start=start)
            sink(run.block(start, positions, recorder.series(), state,
                           _time.perf_counter() - t0))
    return RunSummary(time=np.arange(frames) / run.params.frame_rate, final_state=state,
                      integrator=run.stepper.integrator, dt=run.stepper.dt,
                      wall_seconds=_time.perf_counter() - t0, frame_rate=run.params.frame_rate)


@dataclass(frozen=True, eq=False)
class _Setup:
    """A checked run of :func:`simulate` ready to step: its inputs, physics and first state."""

    model: FaceModel
    params: Parameters
    physics: Physics
    stepper: Stepper
    activity: np.ndarray
    poses: np.ndarray
    state: State
    names: tuple[str, ...]
    nodes: np.ndarray
    attrs: dict

    @property
    def rest(self) -> np.ndarray:
        return self.model.rest_positions

    def block(self, start: int, positions: np.ndarray, muscles: MuscleSeries, state: State,
              wall: float) -> Simulation:
        """The :class:`Simulation` of frames ``start .. start + len(positions) - 1``."""
        sl = slice(start, start + len(positions))
        return Simulation(
            model=self.model, params=self.params,
            time=np.arange(sl.start, sl.stop) / self.params.frame_rate,
            positions=positions, markers=positions[:, self.nodes], marker_names=self.names,
            activity=self.activity[sl], jaw_angle=self.poses[sl, 0].copy(),
            final_state=state, integrator=self.stepper.integrator, dt=self.stepper.dt,
            wall_seconds=wall, attrs=dict(self.attrs), jaw_shift=self.poses[sl, 1:].copy(),
            muscles=muscles)


def _setup(model, activity, jaw_angle, *, integrator, substeps, dt, jaw_drive,
           initial_state, source) -> _Setup:
    """Check the inputs of :func:`simulate` and make its stepper and first state."""
    if not isinstance(model, Model):
        raise TypeError("simulate takes a Model (facemech.model(face, preset)), got "
                        f"{type(model).__name__}")
    params, physics = model.params, model.physics
    activity = check_activity(activity, source=source)
    frames = len(activity)
    if jaw_angle is None:
        jaw_angle = np.zeros(frames)
    jaw_angle = np.asarray(jaw_angle, float)
    if jaw_angle.ndim not in (1, 2) or (jaw_angle.ndim == 2 and jaw_angle.shape[1] != 3):
        raise InputError(f"jaw series must be (frames,) angles or (frames, 3) poses, got shape "
                         f"{jaw_angle.shape}", source=source, field="jaw_angle")
    if len(jaw_angle) != frames:
        raise InputError(f"jaw series has {len(jaw_angle)} frames, activity has {frames}",
                         source=source, field="jaw_angle")
    if not np.all(np.isfinite(jaw_angle)):
        raise InputError("jaw series has non-finite values", source=source,
                         field="jaw_angle")
    from .jaw import jaw_poses

    poses = jaw_poses(jaw_angle, params) if jaw_angle.ndim == 1 else jaw_angle.copy()
    stepper = Stepper(model, integrator=integrator, substeps=substeps, dt=dt,
                      jaw_drive=jaw_drive)
    model = model.face
    names, nodes = marker_nodes(model)
    state = initial_state or State.at_rest(model.rest_positions, physics.n_muscles,
                                           float(poses[0, 0]), jaw_shift=poses[0, 1:])
    attrs = {"steps_per_frame": stepper.n_steps, "jaw_drive": jaw_drive,
             "force_threads": get_threads(),
             "jaw_kinematics": (params.jaw_kinematics if jaw_angle.ndim == 1 else "pose")}
    return _Setup(model, params, physics, stepper, activity, poses, state, names, nodes, attrs)


def _run(stepper, state, activity, poses, jaw_drive, positions, rest, progress,
         recorder=None, start=0):
    """The frame loop of :func:`simulate`: fills ``positions`` (and the muscle outputs of
    ``recorder``) with frames ``start .. start + len(positions) - 1`` of the run, ``state``
    being frame ``start``'s; returns the state of the frame after them (the next to fill), or
    of the run's last frame once it is filled."""
    frames = len(activity)
    n = positions.shape[1]
    for i in range(len(positions)):
        k = start + i
        positions[i] = state.positions[:n]
        if recorder is not None:
            recorder.record(i, state)
        if k == frames - 1:
            break
        target = poses[k] if jaw_drive == "hold" else poses[k + 1]
        state = stepper.advance(state, activity[k], target)
        _check_state(state, rest, k + 1, activity[k], poses[k, 0])
        if progress is not None:
            progress(k + 1, frames - 1)
    return state


def single_threaded_blas():
    """A context in which BLAS uses one thread: the implicit step's small dense systems are far
    slower when OpenBLAS spreads them over the cores of a busy machine."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")
