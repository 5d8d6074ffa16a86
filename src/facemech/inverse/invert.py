"""Frame-by-frame dynamic inversion: muscle activity and the jaw from marker trajectories.

Pitermann & Munhall (2001, II.C): for each 60-Hz frame, starting from the current state
(positions, velocities, muscle filter), find the controls that, held for one frame through the
full dynamics, bring the model's marker nodes closest to the next frame's markers; the answer
seeds the next frame, zero seeds the first. Every cost evaluation is one call of the same step
function as the forward simulation, so the accepted states form the re-animation.

The jaw is never silently left at rest. Without a jaw recording it is estimated with the muscle
activity, as one more control (the angle reached at the end of each frame; the condyle's glide
follows the preset's jaw kinematics). A recorded jaw angle (e.g. from a chin marker) is either
held as given or, with ``estimate_jaw=True``, is the estimate's starting point and a weak prior.

Methods (:mod:`facemech.inverse.methods`): :class:`LeastSquares` (default; a receding horizon,
bounded Gauss-Newton, :class:`~facemech.inverse.frame.FrameProblem`) and :class:`Powell` (the
seeds'). Each frame also gives the standard errors and identifiability of its controls
(:mod:`facemech.inverse.uncertainty`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..checks import check_value
from ..errors import InputError
from ..geometry.sites import marker_aliases, shared_points
from ..markerset import MarkerSet
from ..params import EMG_CHANNELS, MUSCLE_GROUPS, Parameters
from ..physics.model import Model
from ..physics.muscle_outputs import MuscleRecorder
from ..solvers.forward import single_threaded_blas
from ..solvers.jaw import MAX_JAW_ANGLE, jaw_poses
from ..solvers.state import State
from ..solvers.step import Stepper
from . import uncertainty as U
from .combinations import determined_combinations
from .determined import full_activity_notes, identifiability_notes
from .frame import JAW_UNIT, FrameProblem
from .methods import LeastSquares, Powell, method_from_options
from .result import Inversion

__all__ = ["SPEECH_CONTROLS", "JawRecording", "control_matrix", "invert"]

ILL_POSED_CONDITION = 1e4  #: Jacobian condition number above which a frame is flagged
#: rad: the estimated jaw stays within [JAW_CLOSE, MAX_JAW_ANGLE] (closing a little past the
#: first frame's pose, which is taken as rest)
JAW_CLOSE = -np.radians(3.0)
#: the default muscle controls: the seeds' seven EMG channels plus the other muscles that
#: move the lips in speech (zygomaticus major apart from LAO, risorius)
SPEECH_CONTROLS = ("LLS", "ZYG", "LAO", "RIS", "DAO", "DLI", "MEN", "OOS", "OOI")


def control_matrix(controls, model=None) -> tuple[tuple[str, ...], np.ndarray]:
    """Names of the inverted muscle controls and the (groups, controls) map to group activity.

    ``"speech"`` (default): :data:`SPEECH_CONTROLS`; ``"emg7"``: the seeds' seven EMG
    channels (ZYG follows LAO); ``"all"``: every group (of ``model`` when given: the seeds'
    faces have no marginal orbicularis); or a list of group names.
    """
    if controls == "emg7":
        names = EMG_CHANNELS
    elif controls == "all":
        present = (set(MUSCLE_GROUPS) if model is None
                   else {MUSCLE_GROUPS[g] for g in model.muscles.group})
        names = tuple(g for g in MUSCLE_GROUPS if g in present)
    elif controls == "speech":
        names = SPEECH_CONTROLS
    else:
        names = tuple(controls)
    g = np.zeros((len(MUSCLE_GROUPS), len(names)))
    for j, n in enumerate(names):
        if n not in MUSCLE_GROUPS:
            raise InputError(f"unknown muscle group (expected {', '.join(MUSCLE_GROUPS)})",
                             field=n)
        g[MUSCLE_GROUPS.index(n), j] = 1.0
    if controls == "emg7":
        g[MUSCLE_GROUPS.index("ZYG"), names.index("LAO")] = 1.0
    return tuple(names), g



@dataclass(frozen=True)
class JawRecording:
    """A recorded jaw for :func:`invert`, with how to use it.

    Attributes
    ----------
    angle : (frames,) rad, or (frames, 3) poses (angle rad, condyle shift y, z m); None: none
    estimate : estimate the jaw angle as one more control (None, the default: True without a
        recording, False with one; with both, the recording is the starting point and a weak
        prior, ``jaw_prior_weight``). A pose series is always held as given.
    source : what the recording is, for the notes (e.g. "chin marker R01")
    """

    angle: np.ndarray | None = None
    estimate: bool | None = None
    source: str | None = None


def invert(
    model: Model,
    markers: MarkerSet,
    mapping: dict[str, int],
    *,
    method: str | LeastSquares | Powell = "lsq",
    positive: bool = True,
    controls="speech",
    jaw_angle: np.ndarray | JawRecording | None = None,
    prior: np.ndarray | None = None,
    noise_mm: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    **options,
) -> Inversion:
    """Recover muscle activity and the jaw frame by frame (see the module doc).

    Parameters
    ----------
    model : Model -- the face, its parameters and physics (:func:`facemech.physics.model.model`);
        its method's ``fast_dt`` is the explicit Euler step of every evaluation (s); the
        implicit presets step at their own frame substeps and another step is an error there
    markers : MarkerSet in the model's frame (metres) at the model's frame rate (60 Hz); the
        first frame is taken as the face at rest
    mapping : marker name -> epidermal node (see :func:`facemech.closest_nodes`)
    method : a :class:`LeastSquares` or :class:`Powell`, or "lsq"/"powell" with the method's
        options as keywords (``window``, ``tol``, ``bend``, ``smooth``, ``effort``,
        ``prior_weight``, ``jaw_prior_weight``, ``max_evaluations``; ``xtol``, ``ftol`` for
        Powell); an option of the other method is an error
    positive : activity kept >= 0 (bounds for lsq, the published penalty for powell)
    controls : "speech" (default), "emg7", "all" or a list of groups
    jaw_angle : (frames,) rad, a recorded jaw (e.g. :func:`jaw_angles_from_marker`), or
        (frames, 3) poses (angle, condyle shift y, z in m) from two jaw markers; or a
        :class:`JawRecording`: such a series, whether the jaw is estimated from it and what it
        is; None: no recording (the jaw is estimated)
    prior : (frames, muscle controls) prior activity (e.g. processed EMG) for ``prior_weight``
    noise_mm : marker noise (mm, per coordinate) for the standard errors (default: estimated
        from the fit's residuals)

    Returns
    -------
    Inversion
    """
    method = _checked_method(method, options, noise_mm)
    face, params, physics = model.face, model.params, model.physics
    dt = model.steps.fast_dt
    src = markers.meta.get("source")
    names = _mapped_names(markers, mapping, params.frame_rate)
    cnames, gmat = control_matrix(controls, face)
    data = markers.select(names).positions
    frames = len(data)
    rec = jaw_angle if isinstance(jaw_angle, JawRecording) else JawRecording(jaw_angle)
    jaw, estimate_jaw, jaw_note = _jaw_plan(rec.angle, rec.estimate, rec.source, frames)
    nc = len(cnames) + (1 if estimate_jaw else 0)
    if 3 * len(names) < nc:
        raise InputError(f"{len(names)} markers give {3 * len(names)} coordinates for {nc} "
                         "controls: use more markers or fewer controls", source=src,
                         field="markers")
    if prior is not None and np.shape(prior) != (frames, len(cnames)):
        raise InputError(f"prior must be (frames, {len(cnames)})", field="prior")
    nodes = np.array([mapping[n] for n in names])
    stepper = Stepper(model, dt=dt)
    problem = _Problem(face, params, stepper, tuple(names), nodes, data, cnames, gmat, jaw,
                       estimate_jaw, jaw_note, method, positive, noise_mm, src)
    lo, hi = _control_bounds(nc, positive, estimate_jaw)
    state, steps = _rest_and_responses(problem, physics.n_muscles, nc)
    distance = U.identifiability(steps)
    run = _Run(frames, nc, face.n_surface)
    muscles = MuscleRecorder(physics, frames)
    muscles.record(0, state)
    run.positions[0] = state.positions[: face.n_surface]
    run.record_error(0, state.positions[nodes], data[0])
    t0 = time.perf_counter()
    with single_threaded_blas():
        _fit_frames(problem, run, muscles, state, (lo, hi), prior, progress)
    wall = time.perf_counter() - t0
    if frames > 1:
        run.controls[-1] = run.controls[-2]
    return _finish(run, problem, (distance, steps), wall, muscles.series())


def _mapped_names(markers: MarkerSet, mapping: dict, frame_rate: float) -> list[str]:
    """The markers that have a node, at the model's frame rate; InputError naming ``rate`` or
    ``mapping``."""
    src = markers.meta.get("source")
    if abs(markers.rate - frame_rate) > 1e-3 * frame_rate:
        raise InputError(f"markers at {markers.rate:g} Hz, the model runs at "
                         f"{frame_rate:g} Hz: resample first (facemech markers resample)",
                         source=src, field="rate")
    names = [n for n in markers.names if n in mapping]
    if not names:
        raise InputError("no marker has a node", source=src, field="mapping")
    return names


def _control_bounds(nc: int, positive: bool, estimate_jaw: bool):
    """(lo, hi) (c,) of the controls: activity in [0, 1] (or [-1, 1] without the positive
    constraint), the jaw's angle between closed and its widest, in :data:`JAW_UNIT`."""
    lo = np.full(nc, 0.0 if positive else -1.0)
    hi = np.ones(nc)
    if estimate_jaw:
        lo[-1], hi[-1] = JAW_CLOSE / JAW_UNIT, MAX_JAW_ANGLE / JAW_UNIT
    return lo, hi


def _rest_and_responses(p, n_muscles: int, nc: int):
    """The state at rest at the jaw's first pose, and the step responses (rows of the axes the
    data vary along, controls), mm per unit."""
    jaw = p.jaw
    pose0 = (jaw_poses(np.atleast_1d(jaw[0] if jaw is not None else 0.0)[:1], p.params)[0]
             if jaw is None or jaw.ndim == 1 else jaw[0])
    state = State.at_rest(p.face.rest_positions, n_muscles, float(pose0[0]),
                          jaw_shift=pose0[1:])
    steps = _fitted_rows(U.step_responses(
        _control_stepper(p.stepper, p.gmat, p.estimate_jaw, float(pose0[0]), jaw), state,
        p.nodes, nc), p.data)
    return state, steps


def _checked_method(method, options: dict, noise_mm):
    """The inversion's method object from a name and its options, or as given; InputError
    naming the option, ``method`` or ``noise``."""
    if isinstance(method, str):
        method = method_from_options(method, **options)
    elif options:
        raise InputError(f"give the options of a method object when making it (got "
                         f"{', '.join(options)})", field=next(iter(options)))
    if not isinstance(method, (LeastSquares, Powell)):
        raise InputError(f"method must be lsq, powell, LeastSquares or Powell (got "
                         f"{method!r})", field="method")
    if noise_mm is not None and not (np.isfinite(noise_mm) and noise_mm > 0):
        raise InputError(f"noise must be > 0 mm (got {noise_mm})", field="noise")
    if noise_mm is not None:  # the command line's interval (facemech.checks)
        check_value("noise_mm", noise_mm)
    return method


def _fit_frames(problem, run, muscles, state, bounds, prior, progress) -> None:
    """The frame loop: each frame's controls fitted (Powell, or least squares over a receding
    window), recorded into ``run`` and ``muscles`` as it goes."""
    p = problem
    method, data, jaw, nodes, estimate_jaw = p.method, p.data, p.jaw, p.nodes, p.estimate_jaw
    lo, hi = bounds
    nc = len(lo)
    frames = len(data)
    c_prev = np.zeros(nc)
    if estimate_jaw and jaw is not None:
        c_prev[-1] = jaw[0] / JAW_UNIT
    fit_prev = None
    x_prev = None
    states_prev: list = []
    for k in range(frames - 1):
        ok = np.all(np.isfinite(data[k + 1]), axis=1)
        if 3 * ok.sum() < nc:
            raise InputError(f"frame {k + 1}: {int(ok.sum())} usable markers for {nc} "
                             "controls", source=p.src, field="markers")
        run.gaps += int((~ok).sum())
        w = method.window if isinstance(method, LeastSquares) else 1
        frame = FrameProblem(p.stepper, state, p.gmat, nodes, data, jaw, k, w,
                             estimate_jaw=estimate_jaw, lo=lo, hi=hi)
        if isinstance(method, Powell):
            c = frame.powell(c_prev, p.positive, method)
            state = frame.state_after(c)
            pos = frame.roll(c[None])[0]
            resid = frame.residual_of(pos)
            jm = frame.jacobian(frame.lag_responses(c[None], pos))
            run.record_fit(k, jm, np.zeros((0, nc)), nc, float(resid @ resid),
                           len(resid) - nc)
        elif frame.horizon < w and x_prev is not None and len(x_prev) > 1:
            # the data end inside the window: the last full window already fitted every
            # frame left, so its controls are kept rather than refitted on ever fewer frames
            c = x_prev[1].copy()
            x_prev = x_prev[1:]
            state = states_prev[1]  # simulated in that window's accepted roll
            states_prev = states_prev[1:]
            run.repeat_fit(k)
        else:
            fit = frame.lsq(c_prev, x_prev, method, prior=prior,
                            jaw_prior=jaw if estimate_jaw else None,
                            lags_prev=None if fit_prev is None else fit_prev.lags,
                            known=states_prev[1:], expected_rms=run.rms[k] * 1e3)
            c, state, x_prev, states_prev = fit.x[0].copy(), fit.state, fit.x, fit.states
            fit_prev = fit
            run.record_fit(k, fit.jm, fit.a_reg, nc, fit.rss, fit.rows - fit.x.size)
        run.controls[k] = c
        c_prev = c
        run.on_bound[k + 1] = (c <= lo + 1e-6) | (c >= hi - 1e-6)
        run.record_error(k + 1, state.positions[nodes], data[k + 1])
        run.evaluations[k + 1] = frame.counter[0]
        run.positions[k + 1] = state.positions[: p.face.n_surface]
        muscles.record(k + 1, state)
        if progress is not None:
            progress(k + 1, frames - 1)


def _fitted_rows(s, data):
    """The step responses' rows (3 markers, c) of the axes the data vary along (midsagittal
    data: y and z; their x is pinned to the model's)."""
    spread = np.nanmax(data, axis=(0, 1)) - np.nanmin(data, axis=(0, 1))
    axes = [a for a in range(3) if spread[a] > 1e-9] or [0, 1, 2]
    return s.reshape(data.shape[1], 3, -1)[:, axes].reshape(-1, s.shape[1])


def _control_stepper(stepper, gmat, estimate_jaw, jaw_rest, jaw):
    """advance(state, controls) over one frame, the jaw as a control or held at its start."""
    nm = gmat.shape[1]
    held = jaw[0] if jaw is not None else jaw_rest

    def advance(state, c):
        target = c[nm] * JAW_UNIT + jaw_rest if estimate_jaw else held
        return stepper.advance(state, gmat @ c[:nm], target)

    return advance


def _jaw_plan(jaw_angle, estimate_jaw, jaw_source, frames):
    """(the recorded jaw or None, whether the jaw is estimated, the note saying so)."""
    if jaw_angle is None:
        if estimate_jaw is False:
            raise InputError("estimate_jaw=False needs a jaw recording (jaw_angle)",
                             field="jaw_angle")
        return None, True, ("jaw: estimated with the muscle activity (no jaw recording); "
                            "the first frame is taken as the jaw at rest")
    jaw = np.asarray(jaw_angle, float)
    if jaw.shape not in ((frames,), (frames, 3)):
        raise InputError(f"jaw series must have shape ({frames},) or ({frames}, 3), got "
                         f"{jaw.shape}", field="jaw_angle")
    if not np.all(np.isfinite(jaw)):
        raise InputError("jaw series has non-finite values", field="jaw_angle")
    what = jaw_source or "a recorded jaw angle"
    if jaw.ndim == 2:
        if estimate_jaw:
            raise InputError("a jaw pose series (three degrees of freedom) is held as given: "
                             "it cannot also be estimated", field="estimate_jaw")
        return jaw, False, f"jaw: driven by {what} (rotation and condyle glide, as given)"
    if estimate_jaw:
        return jaw, True, (f"jaw: estimated with the muscle activity, starting from and weakly "
                           f"drawn towards {what}")
    return jaw, False, f"jaw: driven by {what}, held as given"


class _Run:
    """Per-frame arrays filled by the frame loop."""

    def __init__(self, frames, nc, n_surface):
        self.controls = np.zeros((frames, nc))
        self.rms = np.zeros(frames)
        self.used = np.zeros(frames, int)
        self.on_bound = np.zeros((frames, nc), bool)
        self.condition = np.full(frames, np.nan)
        self.evaluations = np.zeros(frames, int)
        self.se_unit = np.full((frames, nc), np.nan)  # at 1 mm of noise; row k: frame k
        self.rss = np.full(frames, np.nan)
        self.dof = np.zeros(frames)
        self.positions = np.empty((frames, n_surface, 3))
        self.gaps = 0

    def record_error(self, f, model_markers, data_markers):
        ok = np.all(np.isfinite(data_markers), axis=1)
        d = model_markers[ok] - data_markers[ok]
        self.rms[f] = np.sqrt(np.sum(d * d) / max(ok.sum(), 1))
        self.used[f] = int(ok.sum())

    def record_fit(self, k, jm, a_reg, nc, rss, dof):
        own = jm[:, :nc]
        sv = np.linalg.svd(own, compute_uv=False) if own.size else np.zeros(1)
        self.condition[k + 1] = sv[0] / sv[-1] if sv[-1] > 0 else np.inf
        self.se_unit[k] = U.unit_standard_errors(jm, a_reg, nc)
        self.rss[k], self.dof[k] = rss, dof

    def repeat_fit(self, k):
        self.condition[k + 1] = self.condition[k]
        self.se_unit[k] = self.se_unit[k - 1]


@dataclass(frozen=True)
class _Problem:
    """What an inversion was asked, for :func:`_finish`: the face, parameters and stepper, the
    markers used (names, nodes, data (frames, markers, 3) m), the controls (names, the
    (groups, controls) map), the jaw plan, the method and the noise (mm, None: estimated)."""

    face: object
    params: Parameters
    stepper: Stepper
    names: tuple
    nodes: np.ndarray
    data: np.ndarray
    cnames: tuple
    gmat: np.ndarray
    jaw: np.ndarray | None
    estimate_jaw: bool
    jaw_note: str
    method: LeastSquares | Powell
    positive: bool
    noise_mm: float | None
    src: str | None


def _finish(run, p: _Problem, responses, wall, muscles) -> Inversion:
    frames, nc = run.controls.shape
    distance, steps = responses
    nm = len(p.cnames)
    if frames > 1:
        run.se_unit[-1] = run.se_unit[-2]
    notes = [p.jaw_note]
    same = shared_points(p.names, p.nodes, marker_aliases(p.face.landmarks, p.face.markers))
    if same:
        notes.append(f"one point of the model under two names: {'; '.join(same)}; each name "
                     "is fitted, so the point counts once per name")
    if p.noise_mm is None:
        sigma = U.noise_from_residuals(run.rss, run.dof)
        noise_how = "estimated from the residuals"
    else:
        sigma, noise_how = float(p.noise_mm), "given"
    se = run.se_unit * (sigma if np.isfinite(sigma) else np.nan)
    seen = U.identifiable(distance, sigma)
    if p.estimate_jaw:
        jaw_series = np.empty(frames)
        jaw_series[0] = 0.0 if p.jaw is None else p.jaw[0]
        jaw_series[1:] = run.controls[:-1, -1] * JAW_UNIT
        jaw_pose = None
        control_names = (*p.cnames, "jaw")
    else:
        jaw_series = p.jaw[:, 0] if p.jaw.ndim == 2 else p.jaw
        jaw_pose = p.jaw if p.jaw.ndim == 2 else None
        control_names = tuple(p.cnames)
    if run.gaps:
        notes.append(f"{run.gaps} missing marker samples were left out of their frames' costs")
    combos = determined_combinations(steps, control_names,
                                     first=("jaw",) if p.estimate_jaw else ())
    notes += identifiability_notes(combos, seen, run.controls, control_names, sigma)
    notes += full_activity_notes(run.controls[:-1, :nm] if frames > 1 else run.controls[:, :nm],
                                 p.cnames)
    bad = np.nonzero(run.condition > ILL_POSED_CONDITION)[0]
    if len(bad):
        msg = (f"ill-posed: the Jacobian condition number exceeds {ILL_POSED_CONDITION:.0e} in "
               f"{len(bad)} of {frames - 1} frames (median {np.nanmedian(run.condition):.3g}); "
               "some controls are barely identifiable from these markers")
        notes.append(msg)
        warnings.warn(msg, stacklevel=3)
    return Inversion(
        model=p.face, params=p.params, time=np.arange(frames) / p.params.frame_rate,
        positions=run.positions, marker_names=tuple(p.names), marker_nodes=p.nodes,
        data_markers=p.data, activity=run.controls[:, :nm] @ p.gmat.T, jaw_angle=jaw_series,
        jaw_pose=jaw_pose,
        control_names=control_names, controls=run.controls, control_se=se,
        identifiability=distance, identifiable=seen, combinations=tuple(combos),
        noise_mm=sigma, noise_how=noise_how,
        rms_error=run.rms, markers_used=run.used, on_bound=run.on_bound,
        condition=run.condition, evaluations=run.evaluations, method=p.method,
        positive=p.positive, integrator=f"{p.stepper.integrator} (inversion, {p.method.name})",
        dt=p.stepper.dt, wall_seconds=wall, notes=notes, source=p.src, muscles=muscles,
    )
