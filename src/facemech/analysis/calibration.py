"""Calibration of the anatomical preset's global scales to gestures of real faces.

The anatomical preset takes its constants from physiology and anatomy (params.anatomical); a
few global scales remain that no measurement fixes directly
(:data:`~facemech.params.ANATOMICAL_SCALES`): the force of all muscles (a factor on the specific
tension) and the stiffness of the lips relative to the rest of the face are fitted by default;
the tissue's stiffness and the force of orbicularis oris's chain can be fitted too.
They are fitted, by bounded least squares on their logarithms, to gesture amplitudes:

- the built-in targets (:data:`TARGETS`): a maximal smile and a maximal pucker measured in 3-D,
  the seeds' own Experiment 1 movement, and the minimum amplitudes of single muscles (docs/model.md)
  (as one-sided terms that count only when a gesture falls short);
- a subject's own maximal gestures (:func:`gestures_from_markers`): a marker recording per
  gesture and the muscle groups it uses, measured as the largest displacement of each marker
  from the recording's first frame, against the model's at its mapped nodes.

Each evaluation simulates every gesture (ramp 0.2 s, hold 0.5 s), so a fit takes minutes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, SimulationBlowUp
from ..params import ANATOMICAL_SCALES, MUSCLE_GROUPS, anatomical

#: the fit's variables are log(scale) + OFFSET: scipy's finite differences are relative to the
#: variable, and log(1) = 0 would give them no step (DIFF_STEP x OFFSET = 0.05 in log scale)
OFFSET = 10.0
DIFF_STEP = 0.005
#: weight of a one-sided target's relative shortfall against the log-ratio of a fitted one
HARD = 30.0

#: scales fitted by default, and their bounds (factors on the preset's values)
FITTED = ("force", "lips")
BOUNDS = {"force": (0.3, 3.0), "lips": (0.25, 8.0), "stiffness": (0.2, 5.0),
          "sphincter": (0.2, 5.0)}


@dataclass(frozen=True)
class Target:
    """A gesture amplitude a fit aims at.

    ``measure`` is a key of :func:`facemech.analysis.gestures.measure` (mm); ``value`` the
    amplitude; ``kind`` "equal" (fitted on the log of the ratio), "difference" (fitted on the
    difference, for a subject's marker coordinates), or "at_least" / "at_most" (count only when
    violated).
    """

    name: str
    groups: tuple[str, ...]
    measure: str
    value: float
    kind: str = "equal"
    weight: float = 1.0
    source: str = ""


#: the source of the single-muscle minimum amplitudes (the table in docs/model.md)
_MINIMUM = "minimum of a single muscle (docs/model.md)"
#: the built-in calibration targets (mm)
TARGETS: tuple[Target, ...] = (
    Target("smile, corner up", ("ZYG", "LAO", "RIS"), "corner_up", 5.6,
           source="maximal smile, commissure vertical 5.6 +/- 3.3 mm (Guedat et al. 2021, "
                  "Clin Exp Dent Res, Table 1; 40 children, 3-D tracking)"),
    Target("smile, corner out", ("ZYG", "LAO", "RIS"), "corner_out", 7.75, weight=0.0,
           source="maximal smile, mouth width +15.5 +/- 4.8 mm, half per corner (same); "
                  "reported, not fitted: the generic face's corners move back along its "
                  "curved cheeks more than out (the smile moved them 12.9 mm back too)"),
    Target("pucker, mouth narrower", ("OOS", "OOI"), "mouth_narrower", 14.5,
           source="maximal pucker, mouth width 42.9 -> 28.4 mm (same)"),
    Target("pucker, lips forward", ("OOS", "OOI"), "lips_forward", 2.0, "at_least",
           source=_MINIMUM + "; lips protrude several mm (Popat et al. 2010)"),
    Target("Experiment 1 movement", ("EXPERIMENT1",), "movement", 2.024,
           source="Pitermann & Munhall 2001, Experiment 1: the 8 perioral pairs on the "
                  "triangle sequence move the 11 right-side markers 2.024 mm (2 x RMS 3-D s.d.)"),
    Target("ZYG corner up", ("ZYG",), "corner_up", 4.0, "at_least", source=_MINIMUM),
    Target("ZYG corner out", ("ZYG",), "corner_out", 2.0, "at_least", source=_MINIMUM),
    Target("LAO corner up", ("LAO",), "corner_up", 3.0, "at_least", source=_MINIMUM),
    Target("DAO corner down", ("DAO",), "corner_up", -3.0, "at_most", source=_MINIMUM),
    Target("RIS corner out", ("RIS",), "corner_out", 3.0, "at_least", source=_MINIMUM),
    Target("LLS upper lip up", ("LLS",), "upper_lip_up", 3.0, "at_least", source=_MINIMUM),
    Target("DLI lower lip down", ("DLI",), "lower_lip_down", 3.0, "at_least",
           source=_MINIMUM),
    Target("MEN chin up", ("MEN",), "chin_up", 1.5, "at_least", source=_MINIMUM),
    Target("OO mouth narrower", ("OOS", "OOI"), "mouth_narrower", 10.0, "at_least",
           source=_MINIMUM),
    Target("largest, DLI", ("DLI",), "largest", 20.0, "at_most", source=_MINIMUM),
    Target("largest, LLS", ("LLS",), "largest", 20.0, "at_most", source=_MINIMUM),
)


@dataclass(frozen=True)
class CalibrationRow:
    """A target beside the model's amplitude at the fitted scales.

    Attributes
    ----------
    name, groups, measure : the target's name, its muscle groups ("+"-joined) and measure
    target, model : the target's and the model's amplitude, mm
    kind : "equal", "difference", "at_least" or "at_most" (see :class:`Target`)
    fitted : whether the fit uses it (False: reported only)
    source : where the target comes from
    """

    name: str
    groups: str
    measure: str
    target: float
    kind: str
    model: float
    fitted: bool
    source: str

    def as_dict(self) -> dict:
        return {"name": self.name, "groups": self.groups, "measure": self.measure,
                "target": self.target, "kind": self.kind, "model": self.model,
                "fitted": self.fitted, "source": self.source}


@dataclass(frozen=True)
class CalibrationResult:
    """Fitted scales, the gesture amplitudes they give beside the targets, and the fit's trace.

    Attributes
    ----------
    scales : scale name -> fitted factor (see :data:`~facemech.params.ANATOMICAL_SCALES`)
    rows : :class:`CalibrationRow` per target, at the fitted scales
    cost : half the sum of squared residuals at the fitted scales
    evaluations : gesture sets simulated
    trace : (scales, cost) per evaluation
    status : the optimiser's message
    """

    scales: dict
    rows: tuple
    cost: float
    evaluations: int
    trace: list = field(default_factory=list)
    status: str = ""

    def as_dict(self) -> dict:
        """The fit as the preset file records it: ``cost``, ``evaluations`` and ``rows``."""
        return {"cost": self.cost, "evaluations": self.evaluations,
                "rows": [r.as_dict() for r in self.rows]}

    def table(self) -> str:
        """The targets and the model's amplitudes, one line each."""
        out = []
        for r in self.rows:
            rel = {"equal": "=", "difference": "=", "at_least": ">=", "at_most": "<="}[r.kind]
            note = "" if r.fitted else ", reported only"
            out.append(f"{r.name:28s} {r.model:7.2f} mm  (target {rel} {r.target:.2f}{note})")
        return "\n".join(out)


def experiment1_movement(model) -> float:
    """The movement (mm) of Experiment 1 of Pitermann & Munhall (2001) on ``model`` (a
    :class:`~facemech.physics.model.Model`): 2 x the RMS
    over the 11 right-side markers of their 3-D standard deviation, the 8 perioral pairs driven
    by the triangle sequence."""
    from ..inverse.experiments import PERIORAL, triangle_sequence
    from ..kinematics import stats
    from ..solvers.forward import simulate

    tri = triangle_sequence()
    act = np.zeros((len(tri), len(MUSCLE_GROUPS)))
    for g in PERIORAL:
        act[:, MUSCLE_GROUPS.index(g)] = tri
    sim = simulate(model, act)
    names = [n for n in sim.model.markers if n.startswith("R")]
    return float(stats.movement(sim.positions[:, [sim.model.markers[n] for n in names]]) * 1e3)


def _evaluate(face, scales: dict, targets, run) -> tuple[np.ndarray, list]:
    from ..physics.model import model as face_model
    from .gestures import run_gesture

    model = face_model(face, anatomical(scales))  # one model per set of scales
    cache: dict = {}
    rows = []
    for t in targets:
        key = t.groups
        if key not in cache:
            if key == ("EXPERIMENT1",):
                cache[key] = {"movement": experiment1_movement(model)}
            else:
                cache[key] = (run(model, key) if run else run_gesture(model, key).measures)
        got = cache[key][t.measure]
        rows.append(CalibrationRow(t.name, "+".join(t.groups), t.measure, t.value, t.kind,
                                   float(got), t.weight > 0, t.source))
    res = []
    for t, r in zip(targets, rows, strict=True):
        got = r.model
        if t.weight == 0.0:
            continue  # reported only
        if t.kind == "equal":
            # relative error, symmetric in scale: log of the ratio of magnitudes
            res.append(t.weight * np.log(max(abs(got), 1e-3) / abs(t.value)))
        elif t.kind == "difference":  # a marker coordinate (mm), weighted by 1 / its scale
            res.append(t.weight * (got - t.value))
        elif t.kind == "at_least":
            res.append(t.weight * HARD * min(0.0, (got - t.value) / abs(t.value)))
        else:
            res.append(t.weight * HARD * max(0.0, (got - t.value) / abs(t.value)))
    return np.asarray(res), rows


def check_fit(fit) -> None:
    """Raise unless ``fit`` names known scales of the anatomical preset (at least one)."""
    if not fit:
        raise InputError("name at least one scale to fit", field="fit")
    unknown = [k for k in fit if k not in ANATOMICAL_SCALES]
    if unknown:
        raise InputError(f"unknown scale {unknown[0]!r} (expected "
                         f"{', '.join(ANATOMICAL_SCALES)})", field="fit")


def fit_scales(face, *, targets=TARGETS, fit=FITTED, start: dict | None = None,
               run: Callable | None = None, max_evaluations: int = 40,
               progress: Callable[[int, int], None] | None = None) -> CalibrationResult:
    """Fit the global scales ``fit`` of the anatomical preset to ``targets``.

    Parameters
    ----------
    face : FaceModel (the built-in face for the preset's own calibration)
    targets : sequence of :class:`Target`
    fit : names of the scales to fit (the others keep ``start``'s values or 1)
    start : initial scales (default: the preset's)
    run : optional callable(face, groups, params) -> measures (for subject gestures)
    max_evaluations : budget of gesture sets simulated
    """
    from scipy.optimize import least_squares

    check_fit(fit)
    base = {**ANATOMICAL_SCALES, **(start or {})}
    lo = np.log([BOUNDS[k][0] for k in fit]) + OFFSET
    hi = np.log([BOUNDS[k][1] for k in fit]) + OFFSET
    x0 = np.clip(np.log([base[k] for k in fit]) + OFFSET, lo + 1e-9, hi - 1e-9)
    trace: list = []
    cache: dict = {}

    def scales_of(x):
        return {**base, **{k: float(np.exp(v - OFFSET)) for k, v in zip(fit, x, strict=True)}}

    def residuals(x):
        key = tuple(np.round(x, 10))
        if key in cache:
            return cache[key][0]
        s = scales_of(x)
        try:
            r, rows = _evaluate(face, s, targets, run)
        except SimulationBlowUp:
            r, rows = np.full(len(targets), 10.0), []
        cache[key] = (r, rows)
        trace.append((s, float(0.5 * r @ r)))
        if progress is not None:
            progress(len(trace), max_evaluations)
        return r

    sol = least_squares(residuals, x0, bounds=(lo, hi), diff_step=DIFF_STEP,
                        max_nfev=max(2, max_evaluations // (len(fit) + 1)), method="trf")
    best = min(cache.items(), key=lambda kv: float(kv[1][0] @ kv[1][0]))
    x_best = np.array(best[0])
    r, rows = cache[tuple(np.round(x_best, 10))]
    return CalibrationResult(scales=scales_of(x_best), rows=tuple(rows), cost=float(0.5 * r @ r),
                             evaluations=len(trace), trace=trace, status=str(sol.message))


# ---- a subject's own gestures ------------------------------------------------------------------
@dataclass(frozen=True)
class RecordedGesture:
    """A maximal gesture recorded with markers: its groups and the markers' peak displacement.

    ``displacement`` (markers, 3) m: each marker's displacement from the recording's first frame
    at the frame where the markers moved most (their RMS displacement is largest).
    """

    name: str
    groups: tuple[str, ...]
    markers: tuple[str, ...]
    displacement: np.ndarray
    source: str = ""


def recorded_gesture(markerset, groups, *, name: str | None = None) -> RecordedGesture:
    """Peak displacement of a marker recording of one maximal gesture (see the class)."""
    groups = tuple(g.strip().upper() for g in groups)
    for g in groups:
        if g not in MUSCLE_GROUPS:
            raise InputError(f"unknown muscle group {g!r} (expected {', '.join(MUSCLE_GROUPS)})",
                             source=markerset.meta.get("source"), field="groups")
    pos = markerset.positions
    ok = np.all(np.isfinite(pos), axis=(0, 2))
    if not ok.any():
        raise InputError("no marker is present in every frame", source=markerset.meta.get(
            "source"), field="markers")
    names = tuple(n for n, k in zip(markerset.names, ok, strict=True) if k)
    p = pos[:, ok]
    disp = p - p[0]
    k = int(np.argmax(np.sqrt(np.mean(np.sum(disp**2, axis=2), axis=1))))
    return RecordedGesture(name or "+".join(groups), groups, names, disp[k],
                           source=str(markerset.meta.get("source", "")))


def subject_targets(face, recordings, mapping: dict[str, int]):
    """Targets and a runner that compare the model's marker displacements with a subject's.

    Every recorded marker that has a node in ``mapping`` gives three residual terms (x, y, z,
    relative to the gesture's RMS marker displacement); the runner simulates each gesture and
    reads the same nodes.
    """
    from .gestures import gesture_activity

    targets, specs = [], {}
    for rec in recordings:
        use = [i for i, n in enumerate(rec.markers) if n in mapping]
        if not use:
            raise InputError("no marker of the gesture has a node on the face", source=rec.source,
                             field="markers")
        nodes = np.array([mapping[rec.markers[i]] for i in use])
        d = rec.displacement[use]
        scale = float(np.sqrt(np.mean(np.sum(d**2, axis=1)))) or 1e-3
        specs[rec.groups] = nodes
        for j, i in enumerate(use):
            for a, ax in enumerate("xyz"):
                targets.append(Target(f"{rec.name} {rec.markers[i]} {ax}", rec.groups,
                                      f"node{j}_{a}", float(d[j, a] * 1e3),
                                      weight=1.0 / (scale * 1e3), source=rec.source))

    def run(model, groups):
        from ..solvers.forward import simulate

        act = gesture_activity(groups, frame_rate=model.params.frame_rate)
        sim = simulate(model, act)
        disp = (sim.positions[-1] - sim.positions[0])[specs[groups]] * 1e3
        return {f"node{j}_{a}": float(disp[j, a]) for j in range(len(disp)) for a in range(3)}

    # subject residuals are absolute differences (mm) weighted by 1 / gesture RMS
    return [Target(t.name, t.groups, t.measure, t.value, "difference", t.weight, t.source)
            for t in targets], run


def fit_subject(face, recordings, mapping, *, fit=FITTED, max_evaluations: int = 30,
                progress=None) -> CalibrationResult:
    """Fit the anatomical preset's scales to a subject's recorded maximal gestures."""
    targets, run = subject_targets(face, recordings, mapping)
    return fit_scales(face, targets=targets, fit=fit, run=run, max_evaluations=max_evaluations,
                      progress=progress)
