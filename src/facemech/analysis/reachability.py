"""Can the face reach the lip positions of real speech? Synthetic targets and their inversion.

The targets are not made by the model: they are marker trajectories laid out by hand from the
ranges of real speech (from X-ray microbeam and EMA recordings, docs/model.md: the upper lip
3 mm down and 3 mm front to back, the lower lip 9 mm vertical and 4.5 mm front to back, 6 mm of
it relative to the jaw), as a string of postures (bilabial closure, /a/, /u/, /i/) joined by
smooth (raised-cosine) transitions: the lower lip's 9 mm in 120 ms peaks at 118 mm/s, the
speeds of real lips (60-120 mm/s). The jaw is a bone point, the lower incisor's sensor as
articulography has it (``incisor``, 4.5 mm down in /a/ and 0.8 mm back), and drives the jaw
(:func:`facemech.solvers.jaw_bone.jaw_poses_from_incisor`); the inversion fits the lip and
corner markers with the speech controls and orbicularis oris's marginal part
(:data:`REACH_CONTROLS`); :func:`reach` reports the RMS error. A chin skin marker (``chin``)
is kept in the targets for the older drive (``jaw="chin"``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..markerset import MarkerSet
from ..params import Parameters
from ..waveforms import cosine_ramp

#: displacements (mm) of each marker group in each posture: (dx, dy, dz); "out" for the corners
#: is lateral (its sign follows the side). Ranges over the postures: upper lip y 3.0 (-3.0 to
#: 0), z 3.0 (-1.2 to +1.8); lower lip y 9.0 (-9.0 to 0), z 4.5 (-1.5 to +3.0), and relative to
#: the incisor y 6.0 (-4.5 to +1.5); the incisor y 4.5 (-4.5 to 0) and z 0.8; chin y 4.5.
POSTURES_MM: dict[str, dict[str, tuple[float, float, float]]] = {
    "rest": {"upper": (0, 0, 0), "lower": (0, 0, 0), "corner": (0, 0, 0), "chin": (0, 0, 0),
             "incisor": (0, 0, 0)},
    "p": {"upper": (0, -3.0, 0.6), "lower": (0, 0.0, 0.8), "corner": (-1.0, 0, 0.3),
          "chin": (0, -1.0, -0.5), "incisor": (0, -1.5, -0.2)},
    "a": {"upper": (0, 0.0, -1.2), "lower": (0, -9.0, -1.5), "corner": (0.5, -2.5, -1.0),
          "chin": (0, -4.5, -2.5), "incisor": (0, -4.5, -0.8)},
    "u": {"upper": (0, -0.6, 1.8), "lower": (0, -2.0, 3.0), "corner": (-3.0, -0.5, 0.8),
          "chin": (0, -1.5, -0.8), "incisor": (0, -1.5, -0.3)},
    "i": {"upper": (0, -0.2, -1.2), "lower": (0, -1.5, -1.5), "corner": (2.0, 1.2, -1.2),
          "chin": (0, -1.0, -0.5), "incisor": (0, -1.0, -0.2)},
}
SEQUENCE = ("rest", "p", "a", "p", "u", "p", "i", "rest")
#: markers of the built-in face per group (right side first)
GROUPS = {"upper": ("R05", "L04"), "lower": ("R03", "L02"), "corner": ("R07", "L06"),
          "chin": ("R01",), "incisor": ("LI",)}
#: the controls of the reachability inversion: the speech set and orbicularis oris's marginal
#: part (the two that lower the upper lip and lift the lower lip on the jaw)
REACH_CONTROLS = ("LLS", "ZYG", "LAO", "RIS", "DAO", "DLI", "MEN", "OOS", "OOI", "OOSM", "OOIM")


def speech_targets(face, *, posture_s: float = 0.16, transition_s: float = 0.12,
                   frame_rate: float = Parameters.frame_rate, sequence=SEQUENCE) -> MarkerSet:
    """Marker trajectories (metres, the face's frame) of the synthetic utterance.

    Each posture is held ``posture_s`` and joined to the next by a raised-cosine transition of
    ``transition_s``; the markers start at the face's rest positions of their nodes.
    """
    keys = []
    for k, name in enumerate(sequence):
        keys.append((name, posture_s))
        if k < len(sequence) - 1:
            keys.append(("->", transition_s))
    total = sum(d for _, d in keys)
    t = np.arange(int(round(total * frame_rate)) + 1) / frame_rate
    names = [m for g in GROUPS.values() for m in g]
    disp = np.zeros((len(t), len(names), 3))
    # piecewise: hold, then blend from the posture before to the one after
    edges = np.cumsum([0.0] + [d for _, d in keys])
    seq = list(sequence)
    for i, (what, _) in enumerate(keys):
        a, b = edges[i], edges[i + 1]
        sel = (t >= a - 1e-12) & (t < b - 1e-12) if i < len(keys) - 1 else (t >= a - 1e-12)
        if what == "->":
            before, after = seq[i // 2], seq[i // 2 + 1]
            u = cosine_ramp((t[sel] - a) / (b - a))
        else:
            before = after = what
            u = np.zeros(sel.sum())
        for m, name in enumerate(names):
            group = next(g for g, ms in GROUPS.items() if name in ms)
            side = -1.0 if name.startswith("R") else 1.0
            p0 = np.array(POSTURES_MM[before][group], float)
            p1 = np.array(POSTURES_MM[after][group], float)
            if group == "corner":
                p0[0] *= side
                p1[0] *= side
            disp[sel, m] = (p0 + (p1 - p0) * u[:, None]) * 1e-3
    rest = np.array([_rest_point(face, n) for n in names])
    return MarkerSet(rest[None] + disp, tuple(names), frame_rate,
                     meta={"source": "synthetic speech targets",
                           "roles": {"LI": "lower_incisor"}})


def _rest_point(face, name: str) -> np.ndarray:
    """Rest position (3,) m of a target: a marker's node, or the lower incisor's tip."""
    if name == "LI":
        from ..geometry.teeth import lower_incisor_point

        return lower_incisor_point(face)
    return face.rest_positions[face.markers[name]]


#: the components of :attr:`Reach.components`: (marker group, axis)
COMPONENTS = {"upper_lip_vertical": ("upper", 1), "upper_lip_front_back": ("upper", 2),
              "lower_lip_vertical": ("lower", 1), "lower_lip_front_back": ("lower", 2),
              "corner_lateral": ("corner", 0), "corner_vertical": ("corner", 1),
              "corner_front_back": ("corner", 2)}


@dataclass(frozen=True)
class Reach:
    """The result of :func:`reach`: RMS error (m) over frames and fitted markers, per frame.

    ``components`` (m): the RMS error of one coordinate of one marker group over the frames
    after the first (:data:`COMPONENTS`), and ``lower_lip_on_jaw_vertical``, the lower lip's
    vertical error relative to the lower incisor (the model's incisor against the target's).
    ``share``: each component's share of the summed squared error (the lips' and corners'
    lateral coordinates make the rest).
    """

    rms: float
    frame_rms: np.ndarray  # (frames,) m
    largest: float  # m, the largest single-marker error
    wall_seconds: float
    activity_on_bound: float  # share of control values at 0 or 1
    components: dict = None
    share: dict = None


def reach(model, *, markers: MarkerSet | None = None, jaw: str = "incisor",
          controls=REACH_CONTROLS, **invert_kw) -> Reach:
    """Invert the speech targets with the jaw from the lower incisor (``jaw="incisor"``, a bone
    point) or from the chin skin marker (``"chin"``); the fit's errors over the lip and corner
    markers. ``model``: a :class:`~facemech.physics.model.Model`."""
    from ..inverse.invert import invert

    face, params = model.face, model.params
    ms = markers if markers is not None else speech_targets(face, frame_rate=params.frame_rate)
    if jaw == "incisor":
        from ..solvers.jaw_bone import jaw_poses_from_incisor

        drive = jaw_poses_from_incisor(ms.marker("LI"), face, params)
    elif jaw == "chin":
        from ..solvers.jaw_drive import jaw_angles_from_marker

        drive = jaw_angles_from_marker(model, face.markers["R01"], ms.marker("R01")[:, 1])
    else:
        raise ValueError(f"jaw must be 'incisor' or 'chin', not {jaw!r}")
    fitted = {n: face.markers[n] for n in ms.names if n not in ("R01", "LI")}
    res = invert(model, ms.select(list(fitted)), fitted, jaw_angle=drive,
                 controls=controls, **invert_kw)
    d = res.model_markers[1:] - res.data_markers[1:]
    err = np.linalg.norm(d, axis=2)
    frame = np.sqrt(np.mean(err**2, axis=1))
    on = np.mean((res.controls <= 1e-6) | (res.controls >= 1 - 1e-6))
    names = list(fitted)
    comps, share = {}, {}
    total = float(np.sum(d**2))
    for key, (group, axis) in COMPONENTS.items():
        v = d[:, [names.index(n) for n in GROUPS[group]], axis]
        comps[key] = float(np.sqrt(np.mean(v**2)))
        share[key] = float(np.sum(v**2) / total) if total > 0 else 0.0
    from ..geometry.teeth import lower_incisor_point
    from ..solvers.jaw import move_points

    tip = lower_incisor_point(face)
    poses = res.jaw_pose if res.jaw_pose is not None else None
    if poses is not None:
        inc = np.stack([move_points(tip, q, face.hinge_point, face.hinge_axis)[0]
                        for q in poses])[1:, 1]
        lower = [names.index(n) for n in GROUPS["lower"]]
        rel = d[:, lower, 1] - (inc - ms.marker("LI")[1:, 1])[:, None]
        comps["lower_lip_on_jaw_vertical"] = float(np.sqrt(np.mean(rel**2)))
    return Reach(float(np.sqrt(np.mean(err**2))), frame, float(err.max()), res.wall_seconds,
                 float(on), comps, share)
