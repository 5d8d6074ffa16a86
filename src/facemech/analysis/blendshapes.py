"""ARKit's 52 blendshapes as the model's own muscle gestures, and weights fitted to a result.

Each shape the model can make is the steady displacement of the epidermal nodes under a
defined gesture (:data:`RECIPES`: muscle groups at an activity, the jaw at an angle or shift),
from the resting posture of a run with no activity; a one-sided shape (``...Left``, ``...Right``)
is the bilateral gesture on that side of the midline (+x is the subject's left, as ARKit's
``Left``), blended across it by a smooth step. The other shapes are kept with zero displacement
and flagged. A result's frames are fitted by bounded least squares, weights in [0, 1]::

    min_w || (x_t - x_rest) - sum_k w_k B_k ||^2,   0 <= w_k <= 1

Names: Apple's ``ARFaceAnchor.BlendShapeLocation``; action units: Ekman & Friesen (1978), FACS.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..params import MUSCLE_GROUPS, Parameters

#: Apple's 52 blendshape locations, in the order of Apple's documentation
ARKIT_SHAPES: tuple[str, ...] = (
    "eyeBlinkLeft", "eyeLookDownLeft", "eyeLookInLeft", "eyeLookOutLeft", "eyeLookUpLeft",
    "eyeSquintLeft", "eyeWideLeft", "eyeBlinkRight", "eyeLookDownRight", "eyeLookInRight",
    "eyeLookOutRight", "eyeLookUpRight", "eyeSquintRight", "eyeWideRight",
    "jawForward", "jawLeft", "jawRight", "jawOpen",
    "mouthClose", "mouthFunnel", "mouthPucker", "mouthLeft", "mouthRight",
    "mouthSmileLeft", "mouthSmileRight", "mouthFrownLeft", "mouthFrownRight",
    "mouthDimpleLeft", "mouthDimpleRight", "mouthStretchLeft", "mouthStretchRight",
    "mouthRollLower", "mouthRollUpper", "mouthShrugLower", "mouthShrugUpper",
    "mouthPressLeft", "mouthPressRight", "mouthLowerDownLeft", "mouthLowerDownRight",
    "mouthUpperUpLeft", "mouthUpperUpRight",
    "browDownLeft", "browDownRight", "browInnerUp", "browOuterUpLeft", "browOuterUpRight",
    "cheekPuff", "cheekSquintLeft", "cheekSquintRight", "noseSneerLeft", "noseSneerRight",
    "tongueOut",
)  # fmt: skip

#: the FACS action unit(s) of each shape (Ekman & Friesen 1978), by the shape's stem
FACS: dict[str, str] = {
    "eyeBlink": "AU45", "eyeLookDown": "AU64", "eyeLookIn": "AU61/62", "eyeLookOut": "AU61/62",
    "eyeLookUp": "AU63", "eyeSquint": "AU7", "eyeWide": "AU5", "jawForward": "AU29",
    "jawLeft": "AU30", "jawRight": "AU30", "jawOpen": "AU26", "mouthClose": "AU24 (jaw open)",
    "mouthFunnel": "AU22", "mouthPucker": "AU18", "mouthLeft": "", "mouthRight": "",
    "mouthSmile": "AU12", "mouthFrown": "AU15", "mouthDimple": "AU14", "mouthStretch": "AU20",
    "mouthRollLower": "AU28", "mouthRollUpper": "AU28", "mouthShrugLower": "AU17",
    "mouthShrugUpper": "AU17", "mouthPress": "AU24", "mouthLowerDown": "AU16",
    "mouthUpperUp": "AU10", "browDown": "AU4", "browInnerUp": "AU1", "browOuterUp": "AU2",
    "cheekPuff": "AU34", "cheekSquint": "AU6", "noseSneer": "AU9", "tongueOut": "AU19",
}


@dataclass(frozen=True)
class Recipe:
    """A gesture: ``muscles`` group -> activity (both sides), the jaw's opening ``jaw_deg``
    (degrees) or forward shift of its condyles ``jaw_forward_mm``, and ``less``: a gesture whose
    posture is the shape's start instead of rest (a corrective shape, as ARKit's mouthClose)."""

    muscles: dict = field(default_factory=dict)
    jaw_deg: float = 0.0
    jaw_forward_mm: float = 0.0
    less: Recipe | None = None


#: the gesture of each shape the model can make, by stem; the others are flagged
RECIPES: dict[str, Recipe] = {
    "jawOpen": Recipe(jaw_deg=20.0),
    "jawForward": Recipe(jaw_forward_mm=3.0),
    "mouthClose": Recipe({"OOSM": 1.0, "OOIM": 1.0}, jaw_deg=10.0, less=Recipe(jaw_deg=10.0)),
    "mouthFunnel": Recipe({"OOS": 0.6, "OOI": 0.6, "LLS": 0.5, "DLI": 0.5}),
    "mouthPucker": Recipe({"OOS": 1.0, "OOI": 1.0}),
    "mouthSmile": Recipe({"ZYG": 1.0, "LAO": 1.0}),
    "mouthFrown": Recipe({"DAO": 1.0}),
    "mouthStretch": Recipe({"RIS": 1.0}),
    "mouthRollLower": Recipe({"OOIM": 1.0}),
    "mouthRollUpper": Recipe({"OOSM": 1.0}),
    "mouthShrugLower": Recipe({"MEN": 1.0}),
    "mouthPress": Recipe({"OOS": 0.3, "OOI": 0.3}),
    "mouthLowerDown": Recipe({"DLI": 1.0}),
    "mouthUpperUp": Recipe({"LLS": 1.0}),
    "browDown": Recipe({"COR": 1.0, "CSU": 1.0}),
    "browInnerUp": Recipe({"FRI": 1.0, "FRM": 1.0}),
    "browOuterUp": Recipe({"FRL": 1.0}),
    "noseSneer": Recipe({"LLSAN": 1.0}),
}

#: why the model cannot make the other shapes, by stem
MISSING: dict[str, str] = {
    "eye": "the eyes and lids are render-only parts, not the skin",
    "jawLeft": "the jaw turns about one hinge in the midsagittal plane",
    "jawRight": "the jaw turns about one hinge in the midsagittal plane",
    "mouthLeft": "both sides of a muscle group share one activity",
    "mouthRight": "both sides of a muscle group share one activity",
    "mouthDimple": "no buccinator in the model",
    "mouthShrugUpper": "no muscle lifts the upper lip with the chin",
    "cheekPuff": "air pressure, not a muscle",
    "cheekSquint": "no orbicularis oculi in the model",
    "tongueOut": "the tongue is a render-only part, not the skin",
}

#: half-width (m) of the smooth step across the midline that splits a one-sided shape
MIDLINE_HALF_WIDTH = 0.006
#: a shape whose largest node displacement is below this (m) counts as not made
MADE_FLOOR = 1e-5


def stem(name: str) -> tuple[str, str | None]:
    """(stem, side) of a shape name: ``("mouthSmile", "Left")``, ``("jawOpen", None)``; a
    shape that moves to a side (``jawLeft``, ``mouthRight``) is its own stem."""
    if name in FACS:
        return name, None
    for side in ("Left", "Right"):
        if name.endswith(side):
            return name[: -len(side)], side
    return name, None


def facs_of(name: str) -> str:
    """The FACS action unit(s) of an ARKit shape ('' where none maps)."""
    return FACS.get(stem(name)[0], "")


def why_missing(name: str) -> str:
    """Why the model cannot make a shape ('' for one it makes)."""
    s = stem(name)[0]
    return MISSING.get(s, MISSING["eye"] if s.startswith("eye") else "")


@dataclass(frozen=True)
class Basis:
    """The 52 shapes on one face.

    Attributes
    ----------
    names : (52,) :data:`ARKIT_SHAPES`
    displacement : (52, n_surface, 3) m, each shape at weight 1 (zero where not made)
    made : (52,) bool, False for a flagged shape
    rest : (n_surface, 3) m, the resting posture the shapes start from
    triangles : (f, 3) epidermal triangles
    lips : (n_surface,) bool, the lips' nodes
    notes : (52,) the gesture of each shape, or why it is not made
    """

    names: tuple[str, ...]
    displacement: np.ndarray
    made: np.ndarray
    rest: np.ndarray
    triangles: np.ndarray
    lips: np.ndarray
    notes: tuple[str, ...]

    def table(self) -> list[dict]:
        """One row per shape: name, FACS, made, the gesture or why not, largest
        displacement (mm)."""
        peak = np.linalg.norm(self.displacement, axis=2).max(axis=1) * 1e3
        return [{"name": n, "facs": facs_of(n), "made": bool(m), "gesture": note,
                 "largest_mm": round(float(p), 3)}
                for n, m, note, p in zip(self.names, self.made, self.notes, peak, strict=True)]


def describe_recipe(r: Recipe) -> str:
    """A recipe in words: ``ZYG 1.0 + LAO 1.0``, ``jaw 20 deg``, ``... minus jawOpen``."""
    parts = [f"{g} {a:g}" for g, a in r.muscles.items()]
    if r.jaw_deg:
        parts.append(f"jaw {r.jaw_deg:g} deg")
    if r.jaw_forward_mm:
        parts.append(f"jaw forward {r.jaw_forward_mm:g} mm")
    return " + ".join(parts) + (f", minus {describe_recipe(r.less)}" if r.less else "")


def _gesture_controls(r: Recipe, frames: int, ramp_frames: int, params: Parameters):
    """Activity (frames, groups) and jaw poses (frames, 3) of a recipe, ramped then held; the
    jaw opens with the preset's condylar glide, and ``jaw_forward_mm`` shifts it further."""
    from ..solvers.jaw import jaw_poses

    shape = np.clip(np.arange(frames) / max(ramp_frames, 1), 0.0, 1.0)
    act = np.zeros((frames, len(MUSCLE_GROUPS)))
    for g, a in r.muscles.items():
        act[:, MUSCLE_GROUPS.index(g)] = a * shape
    pose = jaw_poses(np.radians(r.jaw_deg) * shape, params)
    pose[:, 2] += r.jaw_forward_mm * 1e-3 * shape
    return act, pose


def _side_weight(x: np.ndarray, side: str | None) -> np.ndarray:
    """(n,) share of a bilateral shape on ``side`` (+x Left): a smooth step across x = 0."""
    if side is None:
        return np.ones_like(x)
    u = np.clip((x / MIDLINE_HALF_WIDTH + 1.0) / 2.0, 0.0, 1.0)
    left = u * u * (3.0 - 2.0 * u)
    return left if side == "Left" else 1.0 - left


def arkit_basis(model, *, ramp: float = 0.2,
                hold: float = 0.6, progress=None) -> Basis:
    """Make the 52 shapes on ``face`` by simulating each gesture of :data:`RECIPES`.

    Parameters
    ----------
    model : Model -- the face and the preset (:func:`facemech.physics.model.model`)
    ramp, hold : s, the gesture's ramp to its level and the hold before it is taken
    progress : callable(done, total), optional, once per gesture simulated
    """
    params = model.params
    rate = params.frame_rate
    frames = int(round((ramp + hold) * rate)) + 1
    recipes = [Recipe(), *(RECIPES[s] for s in dict.fromkeys(
        stem(n)[0] for n in ARKIT_SHAPES if stem(n)[0] in RECIPES))]
    recipes += [r.less for r in recipes if r.less is not None]
    posture = {}
    for k, r in enumerate(recipes):
        posture[describe_recipe(r)] = _posture(model, r, frames, int(round(ramp * rate)))
        if progress is not None:
            progress(k + 1, len(recipes))
    rest = posture[""]
    if isinstance(rest, str):
        raise InputError(f"the face does not rest: {rest}", field="face")
    face = model.face
    skin_x = face.rest_positions[: face.n_surface, 0]
    x = skin_x - np.median(skin_x)
    disp = np.zeros((len(ARKIT_SHAPES), face.n_surface, 3))
    notes = []
    for i, name in enumerate(ARKIT_SHAPES):
        s, side = stem(name)
        r = RECIPES.get(s)
        if r is None:
            notes.append(why_missing(name))
            continue
        end, start = posture[describe_recipe(r)], posture[describe_recipe(r.less or Recipe())]
        if isinstance(end, str) or isinstance(start, str):  # the gesture ran away
            notes.append(f"{describe_recipe(r)}: {end if isinstance(end, str) else start}")
            continue
        disp[i] = (end - start) * _side_weight(x, side)[:, None]
        notes.append(describe_recipe(r))
    made = np.linalg.norm(disp, axis=2).max(axis=1) > MADE_FLOOR
    notes = [f"{n} (no such muscle on this face)" if RECIPES.get(stem(nm)[0]) and not m
             and "ran away" not in n else n for nm, n, m in zip(ARKIT_SHAPES, notes, made,
                                                                strict=True)]
    lips = (np.asarray(face.lip_region, bool) if face.lip_region is not None
            else np.zeros(face.n_surface, bool))
    return Basis(ARKIT_SHAPES, disp, made, rest, np.asarray(face.faces), lips, tuple(notes))


def _posture(model, r: Recipe, frames: int, ramp_frames: int):
    """The epidermal nodes' positions (n_surface, 3) m at the end of the gesture ``r`` on
    ``model`` (a :class:`~facemech.physics.model.Model`), or the reason it ran away."""
    from ..errors import SimulationBlowUp
    from ..solvers.forward import simulate

    if not set(r.muscles) <= set(MUSCLE_GROUPS):
        raise InputError(f"unknown muscle group in {r.muscles}", field="muscles")
    act, pose = _gesture_controls(r, frames, ramp_frames, model.params)
    try:
        sim = simulate(model, act, pose)
    except SimulationBlowUp as exc:
        return f"the gesture ran away ({exc})"
    return sim.positions[-1]


@dataclass(frozen=True)
class Fit:
    """Blendshape weights fitted to a motion.

    Attributes
    ----------
    weights : (frames, 52) in [0, 1], columns :attr:`Basis.names`
    rms_lips_mm, rms_face_mm : (frames,) RMS over the lips' nodes and over every epidermal node
        of the distance between the motion and the weighted shapes, mm
    """

    weights: np.ndarray
    rms_lips_mm: np.ndarray
    rms_face_mm: np.ndarray

    def summary(self) -> dict:
        """RMS over all frames (and the worst frame's) for the lips and the face, mm."""
        def rms(a):
            return float(np.sqrt(np.mean(np.square(a)))) if a.size else float("nan")

        return {"rms_lips_mm": rms(self.rms_lips_mm), "rms_face_mm": rms(self.rms_face_mm),
                "max_frame_rms_lips_mm": float(np.max(self.rms_lips_mm, initial=0.0)),
                "max_frame_rms_face_mm": float(np.max(self.rms_face_mm, initial=0.0))}


def synthesise(basis: Basis, weights: np.ndarray) -> np.ndarray:
    """Positions (frames, n_surface, 3) m of weights (frames, 52): rest plus the weighted
    shapes."""
    return basis.rest + np.einsum("fk,knc->fnc", np.asarray(weights, float), basis.displacement)


def fit_weights(basis: Basis, positions: np.ndarray) -> Fit:
    """Fit weights in [0, 1] to positions (frames, n_surface, 3) m by bounded least squares
    (``scipy.optimize.lsq_linear``) on every epidermal node; flagged shapes get weight 0.

    The problem is reduced once by a QR factorisation of the made shapes (A = QR, then
    min ||R w - Q^T b|| per frame), which leaves its solution unchanged.
    """
    from scipy.optimize import lsq_linear

    positions = np.asarray(positions, float)
    if positions.ndim != 3 or positions.shape[1:] != basis.rest.shape:
        raise InputError(f"positions {positions.shape} do not match the basis's face "
                         f"({basis.rest.shape[0]} nodes)", field="positions")
    cols = np.flatnonzero(basis.made)
    a = basis.displacement[cols].reshape(len(cols), -1).T
    q, r = np.linalg.qr(a)
    target = (positions - basis.rest).reshape(len(positions), -1)
    weights = np.zeros((len(positions), len(basis.names)))
    for t, b in enumerate(target):
        sol = lsq_linear(r, q.T @ b, bounds=(0.0, 1.0), method="bvls", tol=1e-12)
        weights[t, cols] = np.clip(sol.x, 0.0, 1.0)  # bvls may step past a bound by ~1e-16
    resid = np.linalg.norm(positions - synthesise(basis, weights), axis=2) * 1e3
    lips = resid[:, basis.lips] if basis.lips.any() else np.full((len(resid), 0), np.nan)
    return Fit(weights, np.sqrt(np.mean(lips ** 2, axis=1)) if lips.size else
               np.full(len(resid), np.nan), np.sqrt(np.mean(resid ** 2, axis=1)))
