"""Controls planned for the face's dynamics: per-phone gains learnt on the simulated face.

The dominance blend (:mod:`.coarticulation`) says where each phone's viseme wants the lips and
the jaw; the face may not get there in running speech. Each phone gets a kinematic target at
its middle (:data:`TARGETS`: a bilabial's lips together, a stressed open vowel's lip aperture
12 to 17 mm, a rounded phone's lip centres 3 mm forward, a labiodental's lower lip at the upper
incisors' edge), the utterance a peak lower-lip speed (:data:`SPEED_TARGET`), and iterative
learning control reaches them: simulate, measure each phone as
:mod:`facemech.speech.visible_speech` does, adjust the gestures of the phones that missed
(:class:`~.coarticulation.Gesture`: scale, jaw offset, dominance, neighbours' rates, ``press``,
``shift``; each update the miss times :data:`GAIN`, within :data:`BOUNDS`), simulate again.
An iteration whose cost (misses beyond the tolerances, :data:`PASS_WEIGHT` times misses past
:data:`PASS_LINES`, :data:`SPEED_COST` per mm/s short) exceeds the best is undone with half
the step; the jaw is held to :data:`JAW_SPEED_MAX` (:func:`slew_limited`). At most
``iterations + 1`` simulations; the best iteration's controls are returned with their
simulation. The method in full: docs/stimuli.md, "Controls planned for the face's dynamics".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError
from .alignment import Alignment
from .articulation import Articulation, as_articulation
from .coarticulation import Gesture, controls_from_gestures, gestures
from .phoneclass import PAUSE, phone_classes

__all__ = ["BOUNDS", "CLOSURE_WEIGHT", "GAIN", "JAW_MAX_DEG", "JAW_OPEN_MAX", "JAW_SPEED_MAX",
           "MAX_ITERATIONS", "PASS_LINES", "PASS_WEIGHT", "PLAN_ITERATIONS", "SPEED_COST",
           "SPEED_LINE", "SPEED_TARGET", "SPEED_TOLERANCE", "TARGETS", "Plan",
           "check_iterations", "jaw_open_limit", "jaw_rate_limit", "plan_controls",
           "slew_limited"]

#: iterations of the planner by default (each one forward simulation after the first)
PLAN_ITERATIONS = 8
#: the largest number of iterations accepted
MAX_ITERATIONS = 20
#: the kinematic targets (m) and the tolerances within which a phone is left as it is (m)
TARGETS = {
    "bilabial": {"gap": 0.0, "tolerance": 0.2e-3},
    "open": {"aperture": 12e-3, "tolerance": 1.0e-3, "too_wide": 17e-3},
    "rounded": {"forward": 3e-3, "tolerance": 0.5e-3},
    "labiodental": {"distance": 0.0, "tolerance": 0.5e-3},
    # a bilabial's seal held 70 ms (real closures: 70-120 ms in read speech; the pass line
    # 50 ms), its shortfall weighed :data:`CLOSURE_WEIGHT` m per s (5 ms of tolerance); at
    # 60 ms, two test sentences' seals of "map" came out shorter (40-50 ms against 43-53)
    "closure": {"duration": 0.070, "tolerance": 0.5e-3},
}
#: m of a phone's miss per s that a bilabial's seal falls short of its 70 ms: 10 ms short
#: weigh as a millimetre
CLOSURE_WEIGHT = 0.1
#: bounds of the per-instance adjustments: scale factor, dominance factor, jaw offset (deg),
#: factor on the dominance's rates, a labiodental's own scale factor, a bilabial's press
#: (activity added to OOSM and OOIM, :attr:`~.coarticulation.Gesture.press`) and a bilabial's
#: shift in time (s, :attr:`~.coarticulation.Gesture.shift`; later only, docs/stimuli.md)
BOUNDS = {"scale": (0.5, 1.6), "dominance": (1.0, 30.0), "jaw_deg": (-4.0, 14.0),
          "rate": (0.4, 3.0), "labiodental_scale": (0.0, 2.5), "press": (0.0, 0.8),
          "shift_s": (0.0, 0.04), "jaw_rate": (1.0, 2.5)}
#: deg, the largest jaw target a plan may ask for (the jaw's range is -5 to 35 deg)
JAW_MAX_DEG = 24.0
#: gains: per mm of miss, the jaw offset (deg), the dominance's relative growth, the scale's;
#: ``bilabial_timing``: the share of a missed bilabial's timing error (s) its shift takes
GAIN = {"open_jaw_deg": 0.8, "open_dominance": 0.1, "bilabial_dominance": 1.0,
        "bilabial_scale": 0.15, "bilabial_press": 0.15, "neighbour_rate": 0.1,
        "rounded_scale": 0.2, "rounded_dominance": 0.5, "labiodental_jaw_deg": 0.5,
        "labiodental_dominance": 0.5, "labiodental_scale": 0.2, "bilabial_timing": 0.7,
        "rounded_jaw_deg": 0.5, "speed_jaw_rate": 0.025, "speed_jaw_deg": 0.025,
        "closure_rate": 0.12, "closure_dominance": 0.3, "open_scale": 0.05}
#: what a mm of a miss past the issue's pass line weighs in the plan's cost on top of its mm
#: past the tolerance (:func:`_summary`: the iteration kept): a bilabial's gap beyond 0.5 mm,
#: an open vowel's aperture under 8 mm, a rounded phone's lips under 2 mm forward, a
#: labiodental's lip farther than 1 mm from the incisors (:data:`PASS_LINES`). Without it a
#: short open vowel and its bilabial, competing for the jaw, left the bilabial 1.2-2.6 mm open
#: (the open vowel at 12 mm); with the bilabials' mm alone weighed 4 times, open vowels between
#: two bilabials fell to 2.6 mm
PASS_WEIGHT = 4.0
#: m: the pass lines as the planner's errors (:func:`_measure`) measure them: a
#: bilabial's gap, an open vowel's shortfall from 12 mm (8 mm open), a rounded phone's from
#: 3 mm (2 mm forward), a labiodental's distance (1 mm,
#: :data:`facemech.speech.visible_speech.CONTACT_MM`)
PASS_LINES = {"bilabial": 0.5e-3, "open": 4.0e-3, "rounded": 1.0e-3, "labiodental": 1.0e-3,
              "closure": 0.020 * CLOSURE_WEIGHT}
#: m/s, the peak lower-lip speed an utterance is planned for: the slowest of the real lower
#: lips recorded (115-233 mm/s, docs/visible-speech.md); an utterance whose lower lip stays
#: slower gets a jaw less coarticulated (docs/stimuli.md)
SPEED_TARGET = 0.115
#: m/s, within this of :data:`SPEED_TARGET` the utterance is left as it is (a phone's
#: tolerance, :data:`TARGETS`): its shortfall is counted from 110 mm/s
SPEED_TOLERANCE = 0.005
#: m/s, the pass line for an utterance's peak lower-lip speed (100-250 mm/s in each
#: sentence): a shortfall below it weighs :data:`PASS_WEIGHT` times more, as the phones' do
SPEED_LINE = 0.100
#: mm of the plan's cost per mm/s that the peak lower-lip speed falls short of
#: :data:`SPEED_TARGET` beyond its tolerance (and, :data:`PASS_WEIGHT` times, of
#: :data:`SPEED_LINE`): 50 mm/s short weigh as a phone 1 mm past its tolerance, so that a
#: phone's pass line is not traded for a little speed (a bilabial 1 mm apart costs
#: 0.8 + 4 x 0.5 = 2.8 mm)
SPEED_COST = 0.02
#: the plan stops once every phone meets its pass line and the last two iterations cut the
#: best cost by less than this share (each iteration is one forward simulation)
SETTLED_GAIN = 0.10
#: s, how far beyond a bilabial's interval its closure is looked for (its timing, :func:`_timing`)
TIMING_WINDOW_S = 0.06
#: m/s, the fastest a plan moves the lower incisor's tip: the jaw is a kinematic drive, and the
#: planner, left free, sped it to 400-800 mm/s. 180 mm/s: with the 2 % that central
#: differences of the slew-limited series add, under the fastest jaw of the real recordings
#: (186 mm/s, :data:`facemech.speech.visible_speech.REAL_JAW_PEAK_MM_S`); the lips' own
#: muscles carry the visemes' speed
JAW_SPEED_MAX = 0.180
#: m, the farthest a plan drops the lower incisor's tip below rest: real jaws open 10-20 mm
#: in running speech; the angle is read off the face's jaw kinematics (:func:`jaw_open_limit`)
JAW_OPEN_MAX = 0.018


@dataclass(frozen=True)
class Plan:
    """Planned controls and what the planner did.

    Attributes
    ----------
    time : (frames,) s
    activity : (frames, groups) in [0, 1]
    jaw : (frames,) rad
    simulation : the forward simulation of these controls (:func:`facemech.simulate`)
    gestures : the adjusted gestures (:class:`~.coarticulation.Gesture`)
    record : for manifests: the iterations run, the one kept, the per-group misses of each
        (mm), its peak lower-lip and lower-incisor speeds (mm/s, recorded only), the wall time
        (s)
    """

    time: np.ndarray
    activity: np.ndarray
    jaw: np.ndarray
    simulation: object
    gestures: list = field(default_factory=list)
    record: dict = field(default_factory=dict)


def check_iterations(iterations) -> int:
    """``iterations`` as an int in [0, :data:`MAX_ITERATIONS`]; InputError naming the field
    ``plan_iterations`` otherwise."""
    try:
        n = int(iterations)
        ok = n == float(iterations) and 0 <= n <= MAX_ITERATIONS
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise InputError(f"plan iterations must be a whole number in [0, {MAX_ITERATIONS}], "
                         f"got {iterations!r}", field="plan_iterations")
    return n


def plan_controls(alignment: Alignment, model, *,
                  strength: float | Articulation = 1.0, iterations: int = PLAN_ITERATIONS,
                  jaw_speed: float | None = JAW_SPEED_MAX,
                  progress: Callable[[int, int], None] | None = None) -> Plan:
    """Controls of an alignment planned on the face that will say it (module doc).

    Parameters
    ----------
    alignment : the phones (eSpeak, IPA or ARPABET), times in s
    model : Model, the face simulated and its parameters (:func:`facemech.physics.model.model`);
        its frame rate is the controls'
    strength : a global strength or an :class:`~.articulation.Articulation`, as
        :func:`~.coarticulation.controls_from_alignment`; the plan starts from its gestures
    iterations : updates after the first simulation (0: the blend's controls, simulated once)
    jaw_speed : m/s, the fastest the lower incisor's tip may move (:data:`JAW_SPEED_MAX`; the
        jaw's series slew-limited to it, :func:`slew_limited`); None: no limit
    progress : callable(done, total) over the ``iterations + 1`` simulations

    Returns
    -------
    Plan

    Raises
    ------
    InputError
        Bad iterations (field ``plan_iterations``); what
        :func:`~.coarticulation.controls_from_alignment` rejects.
    """
    import time as _time

    from ..solvers.forward import simulate
    from .coarticulation import controls_from_alignment
    from .visible_speech import incisor_speed, peak_lower_lip_speed

    iterations = check_iterations(iterations)
    if jaw_speed is not None and not (np.isfinite(jaw_speed) and jaw_speed > 0):
        raise InputError(f"the jaw's speed limit must be a positive number of m/s, got "
                         f"{jaw_speed!r}", field="jaw_speed")
    params = model.params
    articulation = as_articulation(strength)
    # the checks of the plain controls (frame rate, strength, duration, labels)
    controls_from_alignment(alignment, frame_rate=params.frame_rate, strength=articulation)
    items = gestures(alignment, articulation)
    phones = _phone_gestures(alignment)
    vowels = _stressed_vowels(alignment)
    jaw_limit = None if jaw_speed is None else jaw_rate_limit(model.face, params, jaw_speed)
    jaw_top = jaw_open_limit(model.face, params, JAW_OPEN_MAX)
    labiodental_jaw = jaw_open_limit(model.face, params, overbite(model.face))
    t0 = _time.perf_counter()
    history, best, turns, step = [], None, {}, 1.0
    for it in range(iterations + 1):
        t, act, jaw = controls_from_gestures(items, alignment.duration,
                                             frame_rate=params.frame_rate,
                                             strength=articulation.strength)
        if jaw_limit is not None:
            jaw = slew_limited(jaw, jaw_limit / params.frame_rate)
        jaw = np.clip(jaw, 0.0, jaw_top)
        sim = simulate(model, act, jaw)
        misses = _measure(alignment, sim, phones)
        speed = peak_lower_lip_speed(sim.time, sim.positions, sim.model)
        summary = _summary(misses, speed)
        summary["peak_lower_lip_speed_mm_s"] = round(1e3 * speed, 1)
        summary["peak_incisor_speed_mm_s"] = round(1e3 * float(incisor_speed(
            sim.time, sim.jaw_pose, sim.model).max()), 1)  # the jaw's; recorded too
        history.append(summary)
        better = best is None or summary["cost"] < best[0]["cost"] - 1e-9
        if better:
            best = (summary, it, t, act, jaw, sim, list(items), misses)
        if progress is not None:
            progress(it + 1, iterations + 1)
        if summary["cost"] == 0.0:
            break  # every phone within its tolerance: nothing to learn
        if _settled(history, best[0]):
            break  # every phone past its pass line, and the last steps gained little
        if it < iterations:
            if not better:  # overshot: back to the best controls, half the step
                step *= 0.5
                misses = best[7]
            items = _update(best[6], misses, turns, step,
                            speed_short=best[0]["speed_short_mm_s"], vowels=vowels,
                            labiodental_jaw=labiodental_jaw)
    if progress is not None and len(history) < iterations + 1:
        progress(iterations + 1, iterations + 1)  # stopped early: done
    summary, kept, t, act, jaw, sim, items, _ = best
    record = {"planned": True, "iterations": iterations, "simulations": len(history),
              "kept_iteration": kept,
              "targets_mm": {g: {k: round(1e3 * v, 2) for k, v in d.items()}
                             for g, d in TARGETS.items()},
              "jaw_speed_limit_mm_s": None if jaw_speed is None else round(1e3 * jaw_speed, 1),
              "speed_target_mm_s": round(1e3 * SPEED_TARGET, 1),
              "speed_tolerance_mm_s": round(1e3 * SPEED_TOLERANCE, 1),
              "misses": history, "final": summary,
              "adjusted_gestures": sum(1 for g in items if _adjusted(g)),
              "wall_s": round(_time.perf_counter() - t0, 2)}
    return Plan(t, act, jaw, sim, items, record)


def jaw_rate_limit(model, params, speed: float) -> float:
    """rad/s: the jaw's angular speed that moves the lower incisor's tip at ``speed`` (m/s) on
    ``model`` under the preset's jaw kinematics (measured between 4 and 8 degrees open)."""
    from ..geometry.teeth import lower_incisor_point
    from ..solvers.jaw import jaw_poses, move_points

    tip = lower_incisor_point(model)
    a = np.radians([4.0, 8.0])
    q = jaw_poses(a, params)
    p = [move_points(tip, pose, model.hinge_point, model.hinge_axis)[0] for pose in q]
    return float(speed * (a[1] - a[0]) / np.linalg.norm(p[1] - p[0]))


def overbite(model) -> float:
    """m, how far the lower incisors' edge stands above the upper incisors' edge at rest (as
    the renderer draws them): the jaw may drop the lower edge this far at a labiodental and
    keep the lower incisors hidden behind the upper ones."""
    from ..geometry.teeth import lower_incisor_point
    from .visible_speech import upper_incisor_edge

    return float(max(lower_incisor_point(model)[1] - upper_incisor_edge(model)[1], 0.0))


def jaw_open_limit(model, params, drop: float) -> float:
    """rad: the jaw angle that drops the lower incisor's tip by ``drop`` (m) below rest on
    ``model`` under the preset's jaw kinematics (interpolated on a 0.25-degree grid up to
    the jaw's 35 degrees)."""
    from ..solvers.jaw import jaw_poses
    from .mouth import incisor_drop

    a = np.radians(np.arange(0.0, 35.01, 0.25))
    d = incisor_drop(model, jaw_poses(a, params))
    k = int(np.argmax(d >= drop)) if np.any(d >= drop) else len(a) - 1
    if k == 0 or d[k] < drop:
        return float(a[k])
    return float(a[k - 1] + (a[k] - a[k - 1]) * (drop - d[k - 1]) / (d[k] - d[k - 1]))


def slew_limited(x: np.ndarray, step: float) -> np.ndarray:
    """``x`` (frames,) with no change between frames larger than ``step``: of all such series,
    the one closest to ``x`` in least squares. A series within the limit is returned as it is;
    a move too fast for it becomes a move at the limit, starting earlier and ending later by the
    same amount when the move is symmetric (a step: a ramp at ``step`` a frame centred on it).

    The solution differs from ``x`` only about the frames that break the limit, so it is solved
    there: each cluster of such frames in a window (:func:`_slew_window`) widened until the
    window's solution meets ``x`` at both of its ends, where it then joins ``x`` (and is the
    whole series' solution there, the problem being strictly convex)."""
    x = np.asarray(x, float)
    y = x.copy()
    if len(x) < 2:
        return y
    fast = np.nonzero(np.abs(np.diff(x)) > step)[0]
    if fast.size == 0:
        return y
    margin = 15
    # clusters of fast frames closer than two margins to each other
    breaks = np.nonzero(np.diff(fast) > 2 * margin)[0]
    starts = np.concatenate([[fast[0]], fast[breaks + 1]])
    ends = np.concatenate([fast[breaks], [fast[-1]]])
    tol = 1e-9 * max(float(np.abs(x).max()), step)
    for a, b in zip(starts, ends, strict=True):
        m = margin
        while True:
            lo, hi = max(a - m, 0), min(b + 1 + m, len(x) - 1)
            z = _slew_window(x[lo:hi + 1], step)
            ok_lo = lo == 0 or abs(z[0] - x[lo]) <= tol
            ok_hi = hi == len(x) - 1 or abs(z[-1] - x[hi]) <= tol
            if (ok_lo and ok_hi) or (lo == 0 and hi == len(x) - 1):
                break
            m *= 2
        y[lo:hi + 1] = z
    return y


def _slew_window(x: np.ndarray, step: float) -> np.ndarray:
    """The least-squares closest series to ``x`` whose changes stay within ``step``: a bounded
    least-squares problem in the first value and the changes
    (:func:`scipy.optimize.lsq_linear`)."""
    from scipy.optimize import lsq_linear

    n = len(x)
    a = np.tril(np.ones((n, n)))  # y = a @ [y0, d1, ..., d(n-1)]
    lo = np.full(n, -step)
    hi = np.full(n, step)
    lo[0], hi[0] = -np.inf, np.inf
    return a @ lsq_linear(a, x, bounds=(lo, hi), method="bvls").x


def _settled(history: list[dict], best: dict) -> bool:
    """The plan has settled: the best iteration leaves no phone short of its pass line
    (:data:`PASS_LINES`) and the lip fast enough, and the best cost of the last two
    iterations is within :data:`SETTLED_GAIN` of the best cost two iterations before."""
    if best["past_mm"] > 0.0 or best["speed_short_mm_s"] > 0.0 or len(history) < 3:
        return False
    before = min(h["cost"] for h in history[:-2])
    return best["cost"] >= (1.0 - SETTLED_GAIN) * before


def _adjusted(g: Gesture) -> bool:
    return (g.jaw != 0.0 or g.lips_dominance != 1.0 or g.jaw_dominance != 1.0
            or g.rate != 1.0 or g.scale != 1.0 or g.press != 0.0 or g.shift != 0.0
            or g.jaw_rate != 1.0)


def _phone_parts(alignment: Alignment):
    """Per phone of the alignment: (its segment, the index in :func:`gestures` of its first
    gesture, its classes), in order."""
    k, voice = 0, alignment.meta.get("voice")
    for seg in alignment.phones:
        parts = phone_classes(seg.label, alignment.notation, source=alignment.source,
                              voice=voice)
        yield seg, k, parts
        k += len(parts)


def _stressed_vowels(alignment: Alignment) -> tuple[int, ...]:
    """The indices in :func:`gestures` of the vowel gestures of stressed phones (eSpeak's
    ``'`` and ``,``, IPA's ``ˈ ˌ``, ARPABET's ``1 2``; every vowel's in an alignment that marks
    no stress): where a slow utterance's jaw opens further (:func:`_update`)."""
    from .phone_labels import phone_stress, reads_stress
    from .phoneclass import VOWEL_CLASSES

    marked = reads_stress(alignment)
    return tuple(k + j for seg, k, parts in _phone_parts(alignment)
                 if not marked or phone_stress(seg.label, alignment.notation) is not None
                 for j, cls in enumerate(parts) if cls in VOWEL_CLASSES)


def _phone_gestures(alignment: Alignment) -> list[list[int]]:
    """Per phone that :func:`facemech.speech.visible_speech.measure_phones` measures (those
    with classes other than a pause), the indices of its gestures in :func:`gestures`."""
    return [list(range(k, k + len(parts))) for _, k, parts in _phone_parts(alignment)
            if parts and parts != (PAUSE,)]


@dataclass(frozen=True)
class _Miss:
    """One phone's miss: its group, the signed error (m; positive: the update's direction),
    its gestures and their classes."""

    group: str
    error: float
    indices: tuple[int, ...]
    classes: tuple[str, ...]
    stressed: bool = False
    #: s, a bilabial's closure centre minus the phone's middle (positive: the lips closed
    #: late; :func:`_timing`)
    timing: float = 0.0


def _measure(alignment: Alignment, sim, phones: list[list[int]]) -> list[_Miss]:
    """Each targeted phone's error on the simulated face (m): bilabial gap minus 0, open
    aperture short of 12 mm (0 up to :data:`TARGETS`'s ``too_wide``, negative beyond), rounded
    forward short of 3 mm, labiodental distance signed (positive: the lip's top above the
    incisors' edge)."""
    from .mouth import mouth_measures
    from .visible_speech import (
        lower_lip_top,
        measure_phones,
        upper_incisor_edge,
    )

    measured = measure_phones(alignment, sim.model, sim.time, sim.positions)
    edge = upper_incisor_edge(sim.model)
    surface = np.asarray(sim.positions)[:, : sim.model.n_surface]
    front, _ = lower_lip_top(sim.model, surface)
    gap = mouth_measures(sim.model, surface)["lip_gap"]
    out = []
    for m, idx in zip(measured, phones, strict=True):
        timing = 0.0
        if m.group == "bilabial":
            err = m.lip_gap_mid - TARGETS["bilabial"]["gap"]
            timing = _timing(sim.time, gap, m.start, m.end)
            short = CLOSURE_WEIGHT * max(TARGETS["closure"]["duration"] - m.closure, 0.0)
            out.append(_Miss("closure", float(short), tuple(idx), m.classes))
        elif m.group == "open":
            if m.stress is None and alignment.notation == "espeak":
                continue
            a = m.aperture_max
            # a miss only outside [aperture, too_wide]: real open vowels open 10-20 mm
            err = max(TARGETS["open"]["aperture"] - a, 0.0)
            if a > TARGETS["open"]["too_wide"]:
                err = TARGETS["open"]["too_wide"] - a
        elif m.group == "rounded":
            err = TARGETS["rounded"]["forward"] - m.forward_max
        elif m.group == "labiodental":
            # the lower lip's visible edge at the incisors' edge, as seen from the front, at
            # the phone's middle, signed (positive: above)
            err = float(np.interp(0.5 * (m.start + m.end), sim.time, front[:, 1]) - edge[1])
        else:
            continue
        out.append(_Miss(m.group, float(err), tuple(idx), m.classes, m.stress is not None,
                         timing))
    return out


def _timing(time: np.ndarray, gap: np.ndarray, start: float, end: float) -> float:
    """s, when a bilabial's lips are closest, against its middle: the centre of the run of
    frames within :data:`TIMING_WINDOW_S` of its interval whose midline gap (m) is within the
    bilabial's tolerance of the smallest there, minus the phone's middle (positive: late)."""
    k = np.nonzero((time >= start - TIMING_WINDOW_S) & (time <= end + TIMING_WINDOW_S))[0]
    if k.size == 0:
        return 0.0
    g = gap[k]
    low = g <= g.min() + TARGETS["bilabial"]["tolerance"]
    j = int(np.argmin(g))
    a = j
    while a > 0 and low[a - 1]:
        a -= 1
    b = j
    while b < len(k) - 1 and low[b + 1]:
        b += 1
    return float(0.5 * (time[k[a]] + time[k[b]]) - 0.5 * (start + end))


def _summary(misses: list[_Miss], speed: float | None = None) -> dict:
    """Per group: n, the median and largest miss beyond the tolerance (mm), the share within
    it; ``cost_mm``: the sum of the misses beyond the tolerances; ``cost``: that sum plus
    :data:`PASS_WEIGHT` times the misses past the pass lines (:data:`PASS_LINES`),
    plus :data:`SPEED_COST` times the mm/s by which ``speed`` (the utterance's peak lower-lip
    speed, m/s; None: not weighed) falls short of :data:`SPEED_TARGET` beyond
    :data:`SPEED_TOLERANCE` (``speed_short_mm_s``) and :data:`PASS_WEIGHT` times that of
    :data:`SPEED_LINE`, what the planner minimises."""
    out: dict = {}
    cost = past = 0.0
    for group, tol in ((g, TARGETS[g]["tolerance"]) for g in TARGETS):
        sel = [m for m in misses if m.group == group]
        if group == "open":
            beyond = [max(abs(m.error) - tol, 0.0) if m.error < 0 else max(m.error - tol, 0.0)
                      for m in sel]
        elif group == "labiodental":
            beyond = [max(abs(m.error) - tol, 0.0) for m in sel]
        else:
            beyond = [max(m.error - tol, 0.0) for m in sel]
        v = 1e3 * np.asarray(beyond)
        cost += float(v.sum())
        past += 1e3 * sum(max((abs(m.error) if group == "labiodental" else m.error)
                              - PASS_LINES[group], 0.0) for m in sel)
        out[group] = {"n": len(sel),
                      "within": round(float(np.mean(v == 0.0)), 3) if v.size else None,
                      "median_miss_mm": round(float(np.median(v)), 2) if v.size else None,
                      "max_miss_mm": round(float(v.max()), 2) if v.size else None}
    short = 0.0 if speed is None else max(1e3 * (SPEED_TARGET - SPEED_TOLERANCE - speed), 0.0)
    below = 0.0 if speed is None else max(1e3 * (SPEED_LINE - speed), 0.0)
    out["speed_short_mm_s"] = round(short, 1)
    out["cost_mm"] = round(cost, 3)
    out["past_mm"] = round(past + below, 3)
    out["cost"] = round(cost + PASS_WEIGHT * past + SPEED_COST * (short + PASS_WEIGHT * below),
                        3)
    return out


def _bounded(x: float, name: str) -> float:
    lo, hi = BOUNDS[name]
    return float(min(max(x, lo), hi))


def _jaw_offset(g: Gesture, add_deg: float) -> float:
    """The gesture's new jaw offset (rad), bounded by :data:`BOUNDS` and :data:`JAW_MAX_DEG`."""
    from .visemes import VISEMES

    deg = _bounded(np.degrees(g.jaw) + add_deg, "jaw_deg")
    deg = min(deg, JAW_MAX_DEG - np.degrees(VISEMES[g.cls].jaw * g.scale))
    return float(np.radians(deg))


def _sharpen(items: list[Gesture], k: int, own: tuple[int, ...], mm: float,
             spare: tuple[str, ...] = ()) -> None:
    """Narrow the dominance of gesture ``k``'s neighbours (not pauses, not its phone's own
    gestures ``own``, not the classes ``spare``) in place: their rates grow with the miss
    ``mm``."""
    factor = 1.0 + GAIN["neighbour_rate"] * min(mm, 8.0)
    for j in (k - 1, k + 1):
        if 0 <= j < len(items) and j not in own and items[j].cls not in (PAUSE, *spare):
            items[j] = replace(items[j], rate=_bounded(items[j].rate * factor, "rate"))


def _update(items: list[Gesture], misses: list[_Miss], turns: dict,
            step: float = 1.0, speed_short: float = 0.0,
            vowels: tuple[int, ...] = (), labiodental_jaw: float | None = None
            ) -> list[Gesture]:
    """The gestures after one step of learning from the misses (module doc), the gains times
    ``step`` (halved after an iteration that did worse than the best). A labiodental's jaw
    and own gesture move in the direction its error's sign says (the lip's top above the
    incisors' edge: open, larger), at half the step each time the sign differs from its last
    update's (``turns``: phone -> (sign, step factor), updated in place). ``speed_short``
    (mm/s by which the peak lower-lip speed fell short of :data:`SPEED_TARGET` beyond its
    tolerance) makes every gesture's jaw less coarticulated, its jaw's dominance rates growing
    by ``GAIN["speed_jaw_rate"]`` per mm/s (:attr:`~.coarticulation.Gesture.jaw_rate`), and
    opens the jaw targets of the gestures ``vowels`` (the stressed vowels',
    :func:`_stressed_vowels`) by ``GAIN["speed_jaw_deg"]`` degrees per mm/s. A labiodental's
    jaw target stays at or under ``labiodental_jaw`` (rad; None: free)."""
    out = list(items)
    if speed_short > 0.0:
        factor = 1.0 + step * GAIN["speed_jaw_rate"] * speed_short
        out = [g if g.cls == PAUSE else
               replace(g, jaw_rate=_bounded(g.jaw_rate * factor, "jaw_rate")) for g in out]
        for k in vowels:
            out[k] = replace(out[k], jaw=_jaw_offset(out[k], step * GAIN["speed_jaw_deg"]
                                                     * speed_short))
    for m in misses:
        tol = TARGETS[m.group]["tolerance"]
        if abs(m.error) <= tol:
            continue
        mm = step * 1e3 * (abs(m.error) - tol)
        for k in m.indices:
            g = out[k]
            if m.group == "open":
                if g.cls not in ("open", "open_rounded") and len(m.indices) > 1:
                    continue  # a diphthong: its open part
                if m.error > 0:
                    grow = 1.0 + GAIN["open_dominance"] * min(mm, 8.0)
                    _sharpen(out, k, m.indices, mm)
                    g = replace(g, lips_dominance=_bounded(g.lips_dominance * grow, "dominance"),
                                jaw_dominance=_bounded(g.jaw_dominance * grow, "dominance"))
                    g = replace(g, jaw=_jaw_offset(g, GAIN["open_jaw_deg"] * mm))
                    # the lips' own opening too, where the jaw is held to its limits
                    g = replace(g, scale=_bounded(g.scale * (1 + GAIN["open_scale"]
                                                             * min(mm, 4.0)), "scale"))
                else:
                    g = replace(g, jaw=_jaw_offset(g, -0.5 * GAIN["open_jaw_deg"] * mm))
            elif m.group == "bilabial":
                if m.error < 0:
                    continue
                grow = 1.0 + GAIN["bilabial_dominance"] * min(mm, 3.0)
                _sharpen(out, k, m.indices, mm, spare=("open", "open_rounded"))
                g = replace(g, scale=_bounded(g.scale * (1 + GAIN["bilabial_scale"]
                                                         * min(mm, 3.0)), "scale"),
                            lips_dominance=_bounded(g.lips_dominance * grow, "dominance"),
                            jaw_dominance=_bounded(g.jaw_dominance * grow, "dominance"),
                            press=_bounded(g.press + GAIN["bilabial_press"] * min(mm, 3.0),
                                           "press"),
                            # its lips closed before its middle: its dominance later
                            shift=_bounded(g.shift - step * GAIN["bilabial_timing"]
                                           * m.timing, "shift_s"))
            elif m.group == "closure":
                # a seal too short: the bilabial's dominance wider in time (its rates
                # lower) and larger, so that it holds the lips and the jaw longer
                g = replace(g, rate=_bounded(g.rate / (1 + GAIN["closure_rate"] * min(mm, 3.0)),
                                             "rate"),
                            lips_dominance=_bounded(
                                g.lips_dominance * (1 + GAIN["closure_dominance"] * min(mm, 3.0)),
                                "dominance"),
                            jaw_dominance=_bounded(
                                g.jaw_dominance * (1 + GAIN["closure_dominance"] * min(mm, 3.0)),
                                "dominance"))
            elif m.group == "rounded":
                if m.error < 0:
                    continue
                g = replace(g, scale=_bounded(g.scale * (1 + GAIN["rounded_scale"] * mm),
                                              "scale"),
                            lips_dominance=_bounded(
                                g.lips_dominance * (1 + GAIN["rounded_dominance"] * mm),
                                "dominance"),
                            jaw_dominance=_bounded(
                                g.jaw_dominance * (1 + GAIN["rounded_dominance"] * mm),
                                "dominance"),
                            jaw=_jaw_offset(g, -GAIN["rounded_jaw_deg"] * mm))
            elif m.group == "labiodental":
                sign = 1.0 if m.error > 0 else -1.0
                last_sign, share = turns.get(m.indices, (sign, 1.0))
                if sign != last_sign:  # passed the edge since the last update: half the step
                    share *= 0.5
                turns[m.indices] = (sign, share)
                grow = 1.0 + GAIN["labiodental_dominance"] * min(mm, 4.0)
                # the lip's own gesture (its depressor and the jaw's small opening) grows
                # while the lip's top is above the edge and shrinks while below; its lips'
                # dominance grows, so that its neighbours' lips give way
                lip = 1.0 + sign * share * GAIN["labiodental_scale"] * min(mm, 4.0)
                jaw = _jaw_offset(g, sign * share * GAIN["labiodental_jaw_deg"] * mm)
                if labiodental_jaw is not None:  # the lower incisors stay behind the upper
                    from .visemes import VISEMES

                    jaw = min(jaw, labiodental_jaw - VISEMES[g.cls].jaw * g.scale)
                g = replace(g, jaw=jaw,
                            jaw_dominance=_bounded(g.jaw_dominance * grow, "dominance"),
                            lips_dominance=_bounded(g.lips_dominance * grow, "dominance"),
                            scale=_bounded(g.scale * max(lip, 0.1), "labiodental_scale"))
            out[k] = g
    return out
