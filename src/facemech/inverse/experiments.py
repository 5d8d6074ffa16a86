"""Pitermann & Munhall (2001), Experiment 1: inverting synthetic data.

All 16 muscles of the seeds' EMG model (the 8 perioral pairs of Lucero & Munhall 1999, Table II:
DAO, DLI, LAO, ZYG, LLS, MEN, OOS, OOI, left and right) follow the triangle sequence
0, 1/6, ..., 1, ..., 1/6 three times (36 frames at 60 Hz); the face moves accordingly (jaw
closed). The 11 right-side markers (R01-R11) are used for the inversion, the 8 left-side ones
(L01-L08) are held out. The inversion recovers the seven EMG controls, with and without the
positive constraint. Synthesis and inversion use the same explicit Euler step (1 ms by default).

Each experiment returns a frozen dataclass (:class:`SyntheticExperiment`,
:class:`CrossTalkerExperiment`) whose ``as_dict()`` is the JSON the command writes; drawing and
writing are the command's (:func:`facemech.workflows.experiments.draw_synthetic`,
:func:`facemech.workflows.experiments.write`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..kinematics import stats
from ..markerset import MarkerSet
from ..params import MUSCLE_GROUPS, Parameters
from ..waveforms import cosine_bump
from .invert import invert

__all__ = ["CrossTalkerExperiment", "CrossTalkerRun", "NoiseFreeScore", "SyntheticExperiment",
           "SyntheticRun", "figure_name", "run_crosstalker", "run_synthetic", "synthetic_data"]

PERIORAL = ("DAO", "DLI", "LAO", "ZYG", "LLS", "MEN", "OOS", "OOI")

PAPER = {
    "activity_correlations_no_constraint": {"LLS": 0.28, "LAO": 0.43, "DAO": -0.02,
                                            "DLI": 0.14, "MEN": 0.38, "OOS": 0.65, "OOI": 0.14},
    "kinematic_corr_above_0.8": "33 of 38",
    "kinematic_corr_above_0.9": "16 of 38",
    "median_error_mm": {"no_constraint": 0.293, "positive": 0.339},
    "movement_mm": 2.024,
}


#: the settings of the published reproductions: the seeds' seven EMG controls, and the
#: receding horizon as its tables in docs/inversion.md were measured (window 3, no smoothing,
#: 1-um stopping rule)
EXPERIMENT_SETTINGS = {"controls": "emg7", "window": 3, "smooth": 0.0, "tol": 1e-3}


def _invert_quietly(model, data, used, label, progress, **kw):
    """invert() with its ill-posedness warning kept for the tables, progress under a label."""
    kw = {**EXPERIMENT_SETTINGS, **kw}
    if kw.get("method", "lsq") == "powell":
        kw = {k: v for k, v in kw.items() if k not in ("window", "smooth", "tol")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return invert(model, data, used, **kw, progress=None if progress is None else
                      (lambda d, n: progress(label, d, n)))


def triangle_sequence(repeats: int = 3) -> np.ndarray:
    """0, 1/6, ..., 1, 5/6, ..., 1/6, repeated: (12 * repeats,) activity."""
    one = np.concatenate([np.arange(0, 7) / 6, np.arange(5, 0, -1) / 6])
    return np.tile(one, repeats)


def synthetic_data(model, *, dt: float | None = None, noise: float = 0.0, seed: int = 0):
    """The synthetic markers (MarkerSet, metres), the true group activity (36, groups).

    ``model`` is a :class:`~facemech.physics.model.Model`; ``dt`` (s) defaults to its
    method's ``fast_dt`` (used by the explicit integrator of the seeds' presets); ``noise``
    (m) is the standard deviation of Gaussian noise added to every coordinate (seeded by
    ``seed``).
    """
    from ..solvers.forward import simulate

    tri = triangle_sequence()
    act = np.zeros((len(tri), len(MUSCLE_GROUPS)))
    for g in PERIORAL:
        act[:, MUSCLE_GROUPS.index(g)] = tri
    params = model.params
    sim = simulate(model, act, dt=model.steps.fast_dt if dt is None else dt)
    face = sim.model
    names = [n for n in face.markers if n[0] in "RL"]
    pos = sim.positions[:, [face.markers[n] for n in names]]
    if noise > 0:
        pos = pos + np.random.default_rng(seed).normal(0.0, noise, pos.shape)
    return MarkerSet(pos, tuple(names), params.frame_rate), act


#: 3-D correlations at least this high count as good in Table II ...
CORR_HIGH = 0.95
#: ... and above this one as acceptable (the paper's "33 of 38")
CORR_LOW = 0.8


@dataclass(frozen=True)
class NoiseFreeScore:
    """A re-animation of noisy markers scored against the noise-free ones (the true motion).

    Attributes
    ----------
    corr3d : marker -> 3-D correlation with the true motion
    corr3d_above : markers whose correlation exceeds ``threshold``
    frame_error_mm : five-number summary of the per-frame error against the true motion, mm
    threshold : the correlation ``corr3d_above`` counts above
    """

    corr3d: dict
    corr3d_above: int
    frame_error_mm: dict
    threshold: float = CORR_LOW

    def as_dict(self) -> dict:
        return {"corr3d": self.corr3d, f"corr3d_above_{self.threshold:g}": self.corr3d_above,
                "frame_error_mm": self.frame_error_mm}


@dataclass(frozen=True)
class SyntheticRun:
    """One inversion of Experiment 1 (a method, with or without the positive constraint).

    Attributes
    ----------
    method, positive : the inversion's method ("lsq" or "powell") and constraint
    wall_s, evaluations : wall time (s) and model frame steps of the inversion
    activity_correlation : control -> correlation with the true activity (Table I)
    corr3d : marker -> {"published", "unbiased"} 3-D correlation (Table II), all 19 markers
    corr3d_at_least, corr3d_above : markers with a correlation >= ``high`` and > ``low``
    frame_error_mm : five-number summary of the per-frame error, mm (Table III)
    movement_mm : movement of the markers used, mm (Table III)
    condition_median : median Jacobian condition number (None: none finite)
    control_names : the inverted controls
    controls, true_controls : (frames, controls) recovered and true activity
    rms_error_m : (frames,) per-frame error, m
    vs_noise_free : the score against the noise-free markers (noisy data only)
    high, low : the thresholds of ``corr3d_at_least`` and ``corr3d_above``
    """

    method: str
    positive: bool
    wall_s: float
    evaluations: int
    activity_correlation: dict
    corr3d: dict
    corr3d_at_least: int
    corr3d_above: int
    frame_error_mm: dict
    movement_mm: float
    condition_median: float | None
    control_names: tuple
    controls: np.ndarray
    true_controls: np.ndarray
    rms_error_m: np.ndarray
    vs_noise_free: NoiseFreeScore | None = None
    high: float = CORR_HIGH
    low: float = CORR_LOW

    def as_dict(self) -> dict:
        out = {"method": self.method, "positive": self.positive, "wall_s": self.wall_s,
               "evaluations": self.evaluations,
               "table1_activity_correlation": self.activity_correlation,
               "table2_corr3d": self.corr3d,
               f"corr3d_at_least_{self.high:g}": self.corr3d_at_least,
               f"corr3d_above_{self.low:g}": self.corr3d_above,
               "table3_frame_error_mm": self.frame_error_mm, "movement_mm": self.movement_mm,
               "condition_median": self.condition_median,
               "control_names": list(self.control_names), "controls": self.controls.tolist(),
               "true_controls": self.true_controls.tolist(),
               "rms_error_m": self.rms_error_m.tolist()}
        if self.vs_noise_free is not None:
            out["vs_noise_free"] = self.vs_noise_free.as_dict()
        return out


@dataclass(frozen=True)
class SyntheticExperiment:
    """Experiment 1 of Pitermann & Munhall (2001): Tables I, II and the top of Table III.

    Attributes
    ----------
    frames : frames of the synthetic markers
    noise_mm : standard deviation of the marker noise, mm
    dt_s : Euler step of synthesis and inversion, s
    markers_used, held_out : the inverted (right-side) and held-out (left-side) markers
    runs : label (e.g. "lsq, positive") -> :class:`SyntheticRun`
    paper : what the paper reports (:data:`PAPER`)
    frame_rate_hz : the markers' frame rate (the parameters'), Hz
    preset : the parameters' name
    """

    frames: int
    noise_mm: float
    dt_s: float
    markers_used: tuple
    held_out: tuple
    runs: dict
    paper: dict
    frame_rate_hz: float
    preset: str = ""

    @property
    def time(self) -> np.ndarray:
        """(frames,) s, the frames' times."""
        return np.arange(self.frames) / self.frame_rate_hz

    def as_dict(self) -> dict:
        """The tables as the command writes them (JSON-ready)."""
        return {"frames": self.frames, "noise_mm": self.noise_mm, "dt_s": self.dt_s,
                "markers_used": list(self.markers_used), "held_out": list(self.held_out),
                "runs": {k: r.as_dict() for k, r in self.runs.items()}, "paper": self.paper}


def run_synthetic(model, *, methods=("lsq",), dt: float | None = None, noise: float = 0.0,
                  progress: Callable[[str, int, int], None] | None = None) -> SyntheticExperiment:
    """Experiment 1 for each method, with and without the positive constraint.

    Table I: correlation of each recovered control with the true activity; Table II: 3-D
    correlations (published and unbiased) of every marker, the 8 held-out ones included;
    Table III (top): per-frame error summary and movement. Each run also carries its recovered
    and true controls and per-frame RMS error (for figures). With ``noise`` (m) the
    re-animation is also compared with the noise-free markers (``vs_noise_free``).

    Parameters
    ----------
    model : Model -- the face and its preset (:func:`facemech.physics.model.model`)
    methods : inversion methods, each of "lsq" and "powell"
    dt : Euler step of synthesis and inversion, s (default: the preset's ``fast_dt``)
    noise : standard deviation of the Gaussian marker noise, m
    progress : callable(stage, done, total)

    Returns
    -------
    SyntheticExperiment
    """
    params, face = model.params, model.face
    dt = model.steps.fast_dt if dt is None else dt
    data, truth = synthetic_data(model, dt=dt, noise=noise)
    # with noise, the re-animation is also compared with the noise-free markers (the true motion)
    clean = synthetic_data(model, dt=dt)[0] if noise > 0 else None
    stepped = model.with_steps(fast_dt=dt)
    used = {n: face.markers[n] for n in data.names if n.startswith("R")}
    all_nodes = [face.markers[n] for n in data.names]
    runs: dict = {}
    for method in methods:
        for positive in (False, True):
            label = f"{method}, {'positive' if positive else 'no constraint'}"
            t0 = time.perf_counter()
            res = _invert_quietly(stepped, data, used, label, progress, method=method,
                                  positive=positive,
                                  jaw_angle=np.zeros(data.n_frames))  # the jaw at rest
            wall = time.perf_counter() - t0
            model = res.positions[:, all_nodes]
            table1 = {}
            for j, c in enumerate(res.control_names):
                a = res.controls[:-1, j]
                b = truth[:-1, MUSCLE_GROUPS.index(c)]
                table1[c] = (float(np.corrcoef(a, b)[0, 1]) if np.std(a) > 0 else float("nan"))
            table2 = {n: {"published": float(stats.corr3d(model[:, m], data.positions[:, m])),
                          "unbiased": float(stats.corr3d(model[:, m], data.positions[:, m],
                                                         published=False))}
                      for m, n in enumerate(data.names)}
            err = stats.frame_errors(model[1:, :len(used)], data.positions[1:, :len(used)])
            corr = np.array([v["published"] for v in table2.values()])
            vs_true = None
            if clean is not None:
                true = clean.positions
                c_true = np.array([stats.corr3d(model[:, m], true[:, m])
                                   for m in range(len(all_nodes))])
                e_true = stats.frame_errors(model[1:, :len(used)], true[1:, :len(used)])
                vs_true = NoiseFreeScore(
                    corr3d=dict(zip(data.names, c_true.tolist(), strict=True)),
                    corr3d_above=int(np.sum(c_true > CORR_LOW)),
                    frame_error_mm=stats.summary5(e_true * 1e3))
            runs[label] = SyntheticRun(
                method=method, positive=positive, wall_s=wall,
                evaluations=int(res.evaluations.sum()), activity_correlation=table1,
                corr3d=table2, corr3d_at_least=int(np.sum(corr >= CORR_HIGH)),
                corr3d_above=int(np.sum(corr > CORR_LOW)),
                frame_error_mm=stats.summary5(err * 1e3),
                movement_mm=stats.movement(data.positions[:, :len(used)]) * 1e3,
                condition_median=float(np.nanmedian(res.condition))
                if np.isfinite(res.condition).any() else None,
                control_names=tuple(res.control_names), controls=res.controls,
                true_controls=truth[:, [MUSCLE_GROUPS.index(c) for c in res.control_names]],
                rms_error_m=res.rms_error, vs_noise_free=vs_true)
    return SyntheticExperiment(
        frames=data.n_frames, noise_mm=noise * 1e3, dt_s=dt, markers_used=tuple(used),
        held_out=tuple(n for n in data.names if n.startswith("L")), runs=runs, paper=PAPER,
        frame_rate_hz=float(params.frame_rate), preset=params.name)


def figure_name(label: str) -> str:
    """The PNG file name of a run's figure, e.g. ``experiment1_lsq_no-constraint.png``."""
    return f"experiment1_{label.replace(', ', '_').replace(' ', '-')}.png"


# ---- Experiment 3 analogue: another talker ---------------------------------------------------
CROSS_HELD_OUT = ("L03", "L05", "L07", "L08")
CROSS_EXTRA = ("upper_lip_center", "lower_lip_center", "nose_tip")


def second_talker():
    """A second talker: the generic surface reshaped (wider and shorter, a fuller lower face)."""
    from ..geometry.builder import build_face, default_surface

    v, f, lm = default_surface()

    def reshape(p):
        p = np.array(p, float)
        y = p[..., 1]
        x_scale = 1.06 + 0.05 * np.tanh((-0.07 - y) / 0.03)  # wider jaw than forehead
        out = p.copy()
        out[..., 0] = p[..., 0] * x_scale
        out[..., 1] = 0.93 * y
        out[..., 2] = 1.04 * p[..., 2] + 0.002 * np.exp(-(((y + 0.09) / 0.02) ** 2))
        return out

    return build_face(reshape(v), f, {k: reshape(p) for k, p in lm.items()}, name="talker-2")


def gesture_controls(frames: int = 120, frame_rate: float = Parameters.frame_rate):
    """Activity (frames, groups) and jaw angles (frames,) rad of /baeb beb daed ded/-like gestures
    at ``frame_rate`` (Hz)."""
    t = np.arange(frames) / frame_rate
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    jaw = np.zeros(frames)
    seg = t[-1] / 4 if frames > 1 else 1.0

    def bump(c, w):
        return cosine_bump(t, c, w)

    for k, (vowel_deg, bilabial) in enumerate(((9.0, True), (5.0, True), (9.0, False),
                                               (5.0, False))):
        start = k * seg
        jaw += np.radians(vowel_deg) * bump(start + 0.5 * seg, 0.8 * seg)
        for edge in (start + 0.1 * seg, start + 0.9 * seg):
            close = bump(edge, 0.4 * seg)
            if bilabial:
                act[:, MUSCLE_GROUPS.index("OOS")] += 0.7 * close
                act[:, MUSCLE_GROUPS.index("OOI")] += 0.8 * close
            else:
                act[:, MUSCLE_GROUPS.index("LLS")] += 0.3 * close
        act[:, MUSCLE_GROUPS.index("DLI")] += 0.4 * bump(start + 0.5 * seg, 0.6 * seg)
        if vowel_deg < 7:  # /e/: some spreading
            act[:, MUSCLE_GROUPS.index("ZYG")] += 0.3 * bump(start + 0.5 * seg, 0.6 * seg)
            act[:, MUSCLE_GROUPS.index("LAO")] += 0.3 * bump(start + 0.5 * seg, 0.6 * seg)
    return np.clip(act, 0, 1), jaw


@dataclass(frozen=True)
class CrossTalkerRun:
    """One inversion of the Experiment 3 analogue (an adaptation of the face to the talker).

    Attributes
    ----------
    wall_s : wall time of the inversion, s
    corr3d : marker -> 3-D correlation of the re-animation with the data (Table VI)
    frame_error_mm : five-number summary of the per-frame error, mm
    movement_mm : movement of the adapted markers, mm
    """

    wall_s: float
    corr3d: dict
    frame_error_mm: dict
    movement_mm: float

    def as_dict(self) -> dict:
        return {"wall_s": self.wall_s, "table6_corr3d": self.corr3d,
                "frame_error_mm": self.frame_error_mm, "movement_mm": self.movement_mm}


@dataclass(frozen=True)
class CrossTalkerExperiment:
    """The Experiment 3 analogue: another talker inverted on the default face (Table VI).

    Attributes
    ----------
    frames : frames of the gesture sequence
    markers : the talker's markers (held-out ones included)
    held_out : markers left out of the inversion
    runs : label (e.g. "lsq, positive, warp") -> :class:`CrossTalkerRun`
    """

    frames: int
    markers: tuple
    held_out: tuple
    runs: dict

    def as_dict(self) -> dict:
        """The table as the command writes it (JSON-ready)."""
        return {"frames": self.frames, "markers": list(self.markers),
                "held_out": list(self.held_out),
                "runs": {k: r.as_dict() for k, r in self.runs.items()}}


def run_crosstalker(model, *, frames: int = 120, dt: float | None = None,
                    progress: Callable[[str, int, int], None] | None = None
                    ) -> CrossTalkerExperiment:
    """Experiment 3 analogue: markers of a second talker, inverted on the default face after
    per-axis scaling, and separately after a thin-plate-spline warp of the face (Table VI).

    Parameters
    ----------
    model : Model -- the default face and the preset (:func:`facemech.physics.model.model`)
    frames : frames of the gesture sequence (at the parameters' frame rate)
    dt : Euler step of synthesis and inversion, s (default: the preset's ``fast_dt``)
    progress : callable(stage, done, total)
    """
    from ..kinematics.mapping import scale_adapt, warp_face
    from ..physics.model import model as face_model
    from ..solvers.forward import simulate
    from ..solvers.jaw_drive import jaw_angles_from_marker

    params, face = model.params, model.face
    dt = model.steps.fast_dt if dt is None else dt
    talker = face_model(second_talker(), params, steps=model.steps)
    other = talker.face
    act, jaw = gesture_controls(frames, params.frame_rate)
    sim = simulate(talker, act, jaw, dt=dt)
    names = [*other.markers, *CROSS_EXTRA]
    nodes_other = [other.markers.get(n, other.landmarks.get(n)) for n in names]
    data = MarkerSet(sim.positions[:, nodes_other], tuple(names), params.frame_rate)
    mapping_all = {n: face.markers.get(n, face.landmarks.get(n)) for n in names}
    used = {n: v for n, v in mapping_all.items() if n not in CROSS_HELD_OUT}
    runs: dict = {}
    for adaptation in ("scaling", "warp"):
        if adaptation == "scaling":
            adapted = scale_adapt(data, face, mapping_all, ("R02", "L07")).markers
            on = model.with_steps(fast_dt=dt)
        else:
            adapted = data
            on = face_model(warp_face(face, data, mapping_all), params,
                            steps=model.steps.with_(fast_dt=dt))
        jaw_est = jaw_angles_from_marker(on, mapping_all["R01"], adapted.marker("R01")[:, 1])
        label = f"lsq, positive, {adaptation}"
        t0 = time.perf_counter()
        res = _invert_quietly(on, adapted, used, label, progress, positive=True,
                              jaw_angle=jaw_est)
        idx = [mapping_all[n] for n in names]
        mod = res.positions[:, idx]
        table6 = {n: float(stats.corr3d(mod[:, m], adapted.positions[:, m]))
                  for m, n in enumerate(names)}
        err = stats.frame_errors(mod[1:], adapted.positions[1:])
        runs[label] = CrossTalkerRun(wall_s=time.perf_counter() - t0, corr3d=table6,
                                     frame_error_mm=stats.summary5(err * 1e3),
                                     movement_mm=stats.movement(adapted.positions) * 1e3)
    return CrossTalkerExperiment(frames=frames, markers=tuple(names),
                                 held_out=CROSS_HELD_OUT, runs=runs)
