"""Single-muscle gestures: what each muscle group does to the face at full activity.

A gesture activates some muscle groups (both sides) with a ramp of ``ramp`` seconds to full
activity, held for ``hold`` seconds; the displacement of the face's landmarks at the end, in the
anatomical directions, is its amplitude. :func:`gesture_table` measures every group;
:data:`TARGETS` are the minimum amplitudes of real faces the default preset must reach (issue
"a face that moves like a face"; sources in docs/model.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import MUSCLE_GROUPS, Parameters

#: measures of a gesture, mm: (description, direction)
MEASURES: dict[str, str] = {
    "corner_up": "mouth corners up (mean of both)",
    "corner_out": "mouth corners outward (mean of both)",
    "corner_forward": "mouth corners forward (mean of both)",
    "upper_lip_up": "upper lip centre up",
    "lower_lip_down": "lower lip centre down",
    "chin_up": "chin up",
    "lower_lip_forward": "lower lip centre forward",
    "upper_lip_forward": "upper lip centre forward",
    "mouth_narrower": "mouth width decrease (corner to corner)",
    "lips_forward": "both lip centres forward (the smaller)",
    "largest": "largest displacement of any landmark or marker",
}

#: (groups, measure, at least mm): the gesture amplitudes the default preset must reach
TARGETS: tuple[tuple[tuple[str, ...], str, float], ...] = (
    (("ZYG",), "corner_up", 4.0),
    (("ZYG",), "corner_out", 2.0),
    (("LAO",), "corner_up", 3.0),
    (("DAO",), "corner_up", -3.0),  # down: at most -3 mm
    (("RIS",), "corner_out", 3.0),
    (("LLS",), "upper_lip_up", 3.0),
    (("DLI",), "lower_lip_down", 3.0),
    (("MEN",), "chin_up", 1.5),  # or lower lip forward 2 mm
    (("OOS", "OOI"), "mouth_narrower", 10.0),
    (("OOS", "OOI"), "lips_forward", 2.0),
)
MAX_DISPLACEMENT_MM = 20.0


def gesture_activity(groups, *, ramp: float = 0.2, hold: float = 0.5, level: float = 1.0,
                     frame_rate: float = Parameters.frame_rate) -> np.ndarray:
    """Activity (frames, groups): the groups ramped linearly to ``level`` over ``ramp`` s, held for
    ``hold`` s (frame 0 at rest)."""
    frames = int(round((ramp + hold) * frame_rate)) + 1
    t = np.arange(frames) / frame_rate
    a = np.zeros((frames, len(MUSCLE_GROUPS)))
    shape = level * np.clip(t / ramp, 0.0, 1.0) if ramp > 0 else np.full(frames, level)
    for g in groups:
        a[:, MUSCLE_GROUPS.index(g)] = shape
    return a


def measure(model, displacement: np.ndarray, rest: np.ndarray | None = None) -> dict:
    """Gesture measures (mm) from displacements (n_surface, 3) m of the epidermal nodes.

    ``rest`` (n_surface, 3) m, the positions the displacement is from (default: the model's).
    """
    lm = model.landmarks
    rest = model.rest_positions[: model.n_surface] if rest is None else rest
    d = np.asarray(displacement) * 1e3

    def dl(name):
        return d[lm[name]]

    cl, cr = dl("mouth_corner_left"), dl("mouth_corner_right")
    width0 = np.linalg.norm(rest[lm["mouth_corner_left"]] - rest[lm["mouth_corner_right"]])
    width1 = np.linalg.norm(rest[lm["mouth_corner_left"]] + cl * 1e-3
                            - rest[lm["mouth_corner_right"]] - cr * 1e-3)
    nodes = [*lm.values(), *model.markers.values()]
    return {
        "corner_up": 0.5 * (cl[1] + cr[1]),
        "corner_out": 0.5 * (cl[0] - cr[0]),
        "corner_forward": 0.5 * (cl[2] + cr[2]),
        "upper_lip_up": dl("upper_lip_center")[1],
        "lower_lip_down": -dl("lower_lip_center")[1],
        "chin_up": dl("chin")[1],
        "lower_lip_forward": dl("lower_lip_center")[2],
        "upper_lip_forward": dl("upper_lip_center")[2],
        "mouth_narrower": (width0 - width1) * 1e3,
        "lips_forward": min(dl("upper_lip_center")[2], dl("lower_lip_center")[2]),
        "largest": float(np.linalg.norm(d[nodes], axis=1).max()),
    }


@dataclass(frozen=True)
class Gesture:
    """A measured gesture: its groups, its measures (mm) and the time course of its landmarks."""

    groups: tuple[str, ...]
    measures: dict
    time: np.ndarray  # (frames,) s
    landmarks: dict  # name -> (frames, 3) m displacement


def run_gesture(model, groups, *, ramp: float = 0.2,
                hold: float = 0.5, level: float = 1.0, jaw_angle: float = 0.0,
                **simulate_kw) -> Gesture:
    """Simulate one gesture on ``model`` (a :class:`~facemech.physics.model.Model`) and
    measure it at its end (see the module doc)."""
    from ..solvers.forward import simulate

    act = gesture_activity(groups, ramp=ramp, hold=hold, level=level,
                           frame_rate=model.params.frame_rate)
    sim = simulate(model, act, np.full(len(act), jaw_angle), **simulate_kw)
    model = sim.model
    disp = sim.positions - sim.positions[0]
    return Gesture(tuple(groups), measure(model, disp[-1], sim.positions[0]), sim.time,
                   {k: disp[:, v] for k, v in model.landmarks.items()})


def gesture_table(model, *, groups=None, **kw) -> dict:
    """Measures (mm) of every muscle group (or of ``groups``) at full activity.

    Keys are group names, and ``"OOS+OOI"`` for the two orbicularis parts together.
    """
    names = list(groups) if groups is not None else [*MUSCLE_GROUPS, "OOS+OOI"]
    out = {}
    for name in names:
        g = tuple(name.split("+"))
        out[name] = run_gesture(model, g, **kw).measures
    return out


def check_targets(table: dict) -> list[str]:
    """The targets of :data:`TARGETS` a gesture table misses (empty when all are met)."""
    misses = []
    for groups, key, need in TARGETS:
        row = table["+".join(groups)]
        got = row[key]
        if key == "chin_up" and row["lower_lip_forward"] >= 2.0:
            continue  # mentalis: chin up 1.5 mm, or lower lip forward 2 mm
        if (need >= 0 and got < need) or (need < 0 and got > need):
            misses.append(f"{'+'.join(groups)} {key} {got:.2f} mm (needs {need:+.1f})")
    for name, row in table.items():
        if row["largest"] > MAX_DISPLACEMENT_MM:
            misses.append(f"{name} moves a landmark {row['largest']:.1f} mm (at most "
                          f"{MAX_DISPLACEMENT_MM:.0f})")
    return misses
