"""The demo as a workflow: :func:`run_demo` (the controls of :mod:`facemech.demo`, simulated,
written and rendered) and the report the command prints."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..demo import DemoSummary, utterance
from ..params import MUSCLE_GROUPS
from ..progress import StagedProgress
from .outcome import Written


def _write_figures(out: Path, sim, t, act, jaw, face, render, report) -> tuple[dict, object]:
    """The demo's results, activity, figures, snapshot and viewer page written into ``out``;
    (the files by kind, the scene drawn)."""
    from ..io.activity import write_activity
    from ..io.results import array_hash, write_results
    from ..viz.movie import write_snapshot
    from ..viz.plots import activity_figure, kinematics_figure
    from ..viz.render import RenderOptions
    from ..viz.scene import build_scene, look_from_model
    from ..viz.viewer import view_file

    files = {}
    report("write results and figures", 0, 5)
    write_activity(out / "activity.csv", t, act)
    files["activity"] = "activity.csv"
    write_results(out / "result.nc", sim, inputs={"activity": array_hash(act),
                                                  "jaw_angle": array_hash(jaw)})
    files["results"] = "result.nc"
    report("write results and figures", 1, 5)
    names = ["R03", "R05", "R07", "R01"]
    kinematics_figure(out / "kinematics.png", sim.time, {n: sim.marker(n) for n in names},
                      title="Synthetic utterance /ba pi ma wu pa/: model markers")
    files["kinematics"] = "kinematics.png"
    activity_figure(out / "activity.png", t, act, MUSCLE_GROUPS, jaw)
    files["activity_plot"] = "activity.png"
    report("write results and figures", 3, 5)
    peak = int(np.argmax(jaw))
    scene = build_scene(look_from_model(face))
    opt = render or RenderOptions()
    still = RenderOptions(view=opt.view, size=(540, 960), background=(
        "#ffffff" if opt.transparent else opt.background))
    write_snapshot(out / "snapshot.png", scene, sim.positions[peak], sim.jaw_pose[peak],
                   options=still)
    files["snapshot"] = "snapshot.png"
    report("write results and figures", 4, 5)
    view_file(out / "result.nc", out / "view.html",
              title="facemech demo: /ba pi ma wu pa/ on the built-in face")
    files["viewer"] = "view.html"
    report("write results and figures", 5, 5)
    return files, scene


def run_demo(out_dir: str | Path, *, integrator: str | None = None, video: bool = True,
             preset: str = "anatomical",
             progress: Callable[[str, int, int], None] | None = None,
             render=None) -> DemoSummary:
    """Build the generic face, simulate the synthetic utterance and write results and pictures.

    Writes ``result.nc``, ``activity.csv``, ``kinematics.png``, ``activity.png``,
    ``snapshot.png``, the viewer page ``view.html``, ``summary.json`` and (with ``video``)
    ``movie.mp4`` into ``out_dir``.
    ``preset`` names the parameter preset (:func:`facemech.params.preset`); ``integrator``
    defaults to the preset's. ``render`` is a :class:`facemech.viz.video.RenderOptions`
    (default: frontal and profile, 1280x720).
    """
    from ..physics.model import model as face_model
    from ..solvers.forward import simulate
    from ..viz.render import RenderOptions

    t0 = time.perf_counter()

    def report(stage, done, total):
        if progress is not None:
            progress(stage, done, total)

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    report("build the face", 0, 1)
    model = face_model("default", preset)
    face, params = model.face, model.params
    report("build the face", 1, 1)
    t, act, jaw = utterance(params.frame_rate)

    def step(stage):
        return None if progress is None else (lambda d, n: progress(stage, d, n))

    sim = simulate(model, act, jaw, integrator=integrator,
                   progress=step("simulate"))
    files, scene = _write_figures(out, sim, t, act, jaw, face, render, report)
    if video:
        from ..viz.movie import write_movie

        write_movie(out / "movie.mp4", scene, sim.positions, sim.jaw_pose,
                    fps=sim.params.frame_rate, options=render or RenderOptions(),
                    progress=step("render"))
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


def summary_text(s, output: str | Path) -> str:
    """Lines on a :class:`facemech.demo.DemoSummary`: frames and rate, simulation time and
    real-time factor, the largest lip displacement (mm), total wall time, the files written
    into ``output``."""
    output = Path(output)
    lines = [f"facemech demo -> {output}/",
             f"  frames: {s.frames} ({s.simulated_seconds:.2f} s at "
             f"{s.frames / s.simulated_seconds:g} Hz)",
             f"  simulation: {s.simulation_seconds:.1f} s wall, real-time factor "
             f"{s.real_time_factor:.2f} ({s.integrator})",
             f"  largest lip displacement: {s.largest_lip_displacement_mm:.2f} mm",
             f"  total wall time: {s.wall_seconds:.1f} s"]
    return "\n".join(lines + [f"  {k}: {output / v}" for k, v in s.output.items()])


def run(output: str | Path, *, integrator: str | None = None, video: bool = True,
        preset: str = "anatomical", render=None,
        progress: StagedProgress | None = None) -> Written:
    """Run the demo (:func:`run_demo`) into the folder ``output``.

    Returns
    -------
    Written : ``data`` the :class:`facemech.demo.DemoSummary`, its line :func:`summary_text`
    """
    from ..atomic import check_output

    check_output(output, [preset if Path(str(preset)).suffix else None], folder=True,
                 field="-o")
    s = run_demo(output, integrator=integrator, video=video, preset=preset, progress=progress,
                 render=render)
    return Written(Path(output), s, summary_text(s, output))
