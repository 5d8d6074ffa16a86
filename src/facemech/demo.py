"""The one-command demo: a synthetic utterance on the built-in face, simulated and shown.

The utterance is a string of CV syllables, /ba pi ma wu pa/, 0.42 s apart, built from smooth
(raised-cosine) bursts: bilabial closures bring in OOS and OOI and close the jaw, /a/ opens the
jaw with DLI and DAO, /i/ spreads the lips with ZYG, LAO and RIS, /u/ rounds them with OOS, OOI
and MEN. Activity levels are plausible fractions of maximal effort, not measured data.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .params import FRAME_RATE_HZ, MUSCLE_GROUPS
from .waveforms import cosine_bump

SYLLABLES = ("ba", "pi", "ma", "wu", "pa")
SYLLABLE_S = 0.42
LEAD_S = 0.25

# vowel targets: jaw angle (deg) and muscle activity
_VOWELS = {
    "a": (9.0, {"DLI": 0.35, "DAO": 0.25}),
    "i": (3.0, {"ZYG": 0.55, "LAO": 0.45, "RIS": 0.6, "LLS": 0.2}),
    "u": (4.0, {"OOS": 0.55, "OOI": 0.55, "MEN": 0.4}),
}
# consonant targets: muscle activity at the closure (the jaw closes towards 0.5 deg)
_CONSONANTS = {
    "b": {"OOS": 0.6, "OOI": 0.7, "MEN": 0.3},
    "p": {"OOS": 0.8, "OOI": 0.85, "MEN": 0.4},
    "m": {"OOS": 0.45, "OOI": 0.5},
    "w": {"OOS": 0.6, "OOI": 0.6, "MEN": 0.2},
}


_bump = cosine_bump


def utterance(frame_rate: float = FRAME_RATE_HZ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Synthetic speech-like controls.

    Returns
    -------
    time : (frames,) s
    activity : (frames, groups) in [0, 1]
    jaw_angle : (frames,) rad
    """
    duration = 2 * LEAD_S + SYLLABLE_S * len(SYLLABLES)
    t = np.arange(int(round(duration * frame_rate))) / frame_rate
    act = np.zeros((len(t), len(MUSCLE_GROUPS)))
    jaw = np.zeros(len(t))
    for k, syl in enumerate(SYLLABLES):
        onset = LEAD_S + k * SYLLABLE_S
        cons, vow = syl[0], syl[1]
        closure = _bump(t, onset + 0.06, 0.20)
        vowel = _bump(t, onset + 0.24, 0.30)
        for g, a in _CONSONANTS[cons].items():
            act[:, MUSCLE_GROUPS.index(g)] += a * closure
        angle, muscles = _VOWELS[vow]
        for g, a in muscles.items():
            act[:, MUSCLE_GROUPS.index(g)] += a * vowel
        jaw += np.radians(angle) * vowel
    return t, np.clip(act, 0.0, 1.0), jaw


@dataclass(frozen=True)
class DemoSummary:
    frames: int
    simulated_seconds: float
    wall_seconds: float
    simulation_seconds: float
    real_time_factor: float
    largest_lip_displacement_mm: float
    integrator: str
    output: dict
    preset: str = "anatomical"

    def as_dict(self) -> dict:
        return self.__dict__.copy()


def run_demo(out_dir: str | Path, *, integrator: str | None = None, video: bool = True,
             preset: str = "anatomical",
             progress: Callable[[str, int, int], None] | None = None,
             render=None) -> DemoSummary:
    """Build the generic face, simulate the synthetic utterance and write results and pictures.

    Writes ``result.nc``, ``activity.csv``, ``kinematics.png``, ``activity.png``,
    ``snapshot.png``, ``summary.json`` and (with ``video``) ``movie.mp4`` into ``out_dir``.
    ``preset`` names the parameter preset (:func:`facemech.params.preset`); ``integrator``
    defaults to the preset's. ``render`` is a :class:`facemech.viz.video.RenderOptions`
    (default: frontal and profile, 1280x720).
    """
    from .geometry.builder import default_face
    from .io.activity import write_activity
    from .io.results import array_hash, write_results
    from .params import preset as get_preset
    from .solvers.forward import simulate
    from .viz.movie import write_movie, write_snapshot
    from .viz.plots import activity_figure, kinematics_figure
    from .viz.render import RenderOptions
    from .viz.scene import build_scene, look_from_model

    t0 = time.perf_counter()

    def report(stage, done, total):
        if progress is not None:
            progress(stage, done, total)

    params = get_preset(preset)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    report("build the face", 0, 1)
    face = default_face(tissue=params.tissue)
    report("build the face", 1, 1)
    t, act, jaw = utterance(params.frame_rate)

    def step(stage):
        return None if progress is None else (lambda d, n: progress(stage, d, n))

    sim = simulate(face, act, jaw, params=params, integrator=integrator,
                   progress=step("simulate"))
    files = {}
    report("write results and figures", 0, 4)
    write_activity(out / "activity.csv", t, act)
    files["activity"] = "activity.csv"
    write_results(out / "result.nc", sim, inputs={"activity": array_hash(act),
                                                  "jaw_angle": array_hash(jaw)})
    files["results"] = "result.nc"
    report("write results and figures", 1, 4)
    names = ["R03", "R05", "R07", "R01"]
    kinematics_figure(out / "kinematics.png", sim.time, {n: sim.marker(n) for n in names},
                      title="Synthetic utterance /ba pi ma wu pa/: model markers")
    files["kinematics"] = "kinematics.png"
    activity_figure(out / "activity.png", t, act, MUSCLE_GROUPS, jaw)
    files["activity_plot"] = "activity.png"
    report("write results and figures", 3, 4)
    peak = int(np.argmax(jaw))
    scene = build_scene(look_from_model(face))
    opt = render or RenderOptions()
    still = RenderOptions(view=opt.view, size=(540, 960), background=(
        "#ffffff" if opt.transparent else opt.background))
    write_snapshot(out / "snapshot.png", scene, sim.positions[peak], sim.jaw_pose[peak],
                   options=still)
    files["snapshot"] = "snapshot.png"
    report("write results and figures", 4, 4)
    if video:
        write_movie(out / "movie.mp4", scene, sim.positions, sim.jaw_pose,
                    fps=sim.params.frame_rate, options=opt, progress=step("render"))
        files["movie"] = "movie.mp4"
    lips = [face.landmarks[k] for k in ("upper_lip_center", "lower_lip_center",
                                        "mouth_corner_left", "mouth_corner_right")]
    disp = np.linalg.norm(sim.positions[:, lips] - sim.positions[0, lips], axis=2)
    summary = DemoSummary(
        frames=len(t), simulated_seconds=len(t) / sim.params.frame_rate,
        wall_seconds=time.perf_counter() - t0, simulation_seconds=sim.wall_seconds,
        real_time_factor=sim.real_time_factor,
        largest_lip_displacement_mm=float(disp.max() * 1e3), integrator=sim.integrator,
        preset=preset,
        output=files,
    )
    (out / "summary.json").write_text(json.dumps(summary.as_dict(), indent=2))
    return summary
