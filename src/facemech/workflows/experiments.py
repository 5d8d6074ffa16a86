"""``facemech experiment ...``: the seeds' experiments, reproduced, written and summarised.

Each function computes the experiment (a frozen dataclass, see
:mod:`facemech.inverse.experiments` and :mod:`facemech.analysis.lucero2008`), draws and writes
it where asked, and returns it; the ``*_report`` functions give the lines the commands print
(console markup), our numbers beside the paper's.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..checks import check_value
from ..errors import InputError

__all__ = ["crosstalker", "crosstalker_report", "dense_animation", "draw_lucero2008",
           "draw_synthetic", "lucero2008", "lucero2008_report", "synthetic", "synthetic_report",
           "write"]

Progress = Callable[[str, int, int], None]


def _check(output: str | Path | None, preset: str | None, *, folder: bool) -> None:
    """Check the output (if any) before the experiment's minutes of work: never the preset
    file, and writable (:func:`facemech.atomic.check_output`)."""
    from ..atomic import check_output

    if output is not None:
        check_output(output, [preset if preset and Path(preset).suffix else None],
                     folder=folder, field="-o")


def _model(preset: str):
    """The built-in face under ``preset``: the experiment's one model."""
    from ..physics.model import model

    return model("default", preset)


def synthetic(output: str | Path | None = None, *, method: str = "lsq", noise_mm: float = 0.0,
              preset: str = "anatomical", dt: float | None = None, figures: bool = True,
              progress: Progress | None = None):
    """Pitermann & Munhall (2001) Experiment 1: Tables I, II and the top of Table III.

    Parameters
    ----------
    output : folder for ``summary.json`` (the tables) and, with ``figures``, one PNG per run
        (inverted against true activity, and the error); None: nothing is written
    method : "lsq", "powell" or "both"
    noise_mm : standard deviation of the Gaussian marker noise, mm
    preset : the parameter preset
    dt : Euler step of synthesis and inversion, s (default: the preset's fast step)
    figures : draw the figures into ``output``
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.inverse.experiments.SyntheticExperiment
    """
    from ..inverse.experiments import run_synthetic

    if method not in ("lsq", "powell", "both"):
        raise InputError("method must be lsq, powell or both", field="method")
    _check(output, preset, folder=True)
    res = run_synthetic(_model(preset),
                        methods=("lsq", "powell") if method == "both" else (method,),
                        noise=noise_mm * 1e-3, dt=dt, progress=progress)
    if output is not None:
        if figures:
            draw_synthetic(res, output)
        write(res, Path(output) / "summary.json")
    return res


def synthetic_report(res, output: str | Path | None = None, *, figures: bool = True
                     ) -> list[str]:
    """What ``facemech experiment pitermann2001-synthetic`` prints."""
    from ..inverse.experiments import figure_name

    paper = res.paper
    lines = ["[bold]Pitermann & Munhall (2001), Experiment 1[/bold] (ours | paper)"]
    for label, r in res.runs.items():
        lines.append(f"[bold]{label}[/bold]: {r.wall_s:.1f} s, {r.evaluations} steps")
        ref = paper["activity_correlations_no_constraint"]
        lines.append("  Table I, activity correlation: " + ", ".join(
            f"{k} {v:.2f}" + (f" | {ref[k]:.2f}" if "no constraint" in label else "")
            for k, v in r.activity_correlation.items()))
        lines.append(f"  Table II, 3-D correlations >= {r.high:g}: {r.corr3d_at_least} of 19; "
                     f"> {r.low:g}: {r.corr3d_above} of 19 | "
                     f"{paper['kinematic_corr_above_0.8']} over both conditions")
        e = r.frame_error_mm
        pe = paper["median_error_mm"]["positive" if r.positive else "no_constraint"]
        lines.append(f"  Table III, per-frame error (mm): min {e['min']:.3f} q1 {e['q1']:.3f} "
                     f"median {e['median']:.3f} | {pe} q3 {e['q3']:.3f} max {e['max']:.3f}; "
                     f"movement {r.movement_mm:.3f} | {paper['movement_mm']} mm")
        if r.vs_noise_free is not None:
            v = r.vs_noise_free
            lines.append(f"  against the noise-free markers: median error "
                         f"{v.frame_error_mm['median']:.3f} mm; 3-D correlations > "
                         f"{v.threshold:g}: {v.corr3d_above} of 19")
    if output is not None:
        if figures:
            lines += [f"figure -> {Path(output) / figure_name(label)}" for label in res.runs]
        lines.append(f"tables -> {Path(output) / 'summary.json'}")
    return lines


def crosstalker(output: str | Path | None = None, *, frames: int = 120,
                preset: str = "anatomical", dt: float | None = None,
                progress: Progress | None = None):
    """The Experiment 3 analogue: another talker inverted on the default face (Table VI).

    Parameters
    ----------
    output : JSON file for the table (None: nothing is written)
    frames : frames of the gesture sequence (at least 8), at the preset's frame rate
    preset : the parameter preset
    dt : Euler step of synthesis and inversion, s (default: the preset's fast step)
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.inverse.experiments.CrossTalkerExperiment
    """
    from ..inverse.experiments import run_crosstalker

    check_value("frames", frames)  # the command line's interval (facemech.checks)
    if frames < 8:
        raise InputError("needs at least 8 frames", field="frames")
    _check(output, preset, folder=False)
    res = run_crosstalker(_model(preset), frames=frames, dt=dt, progress=progress)
    if output is not None:
        write(res, output)
    return res


def crosstalker_report(res, output: str | Path | None = None) -> list[str]:
    """What ``facemech experiment pitermann2001-crosstalker`` prints."""
    lines = ["[bold]Pitermann & Munhall (2001), Experiment 3 analogue[/bold] (paper, Table VI: "
             "3-D correlations mostly 0.75-0.97, upper lip centre poor)"]
    for label, r in res.runs.items():
        e = r.frame_error_mm
        lines.append(f"[bold]{label}[/bold]: {r.wall_s:.1f} s; per-frame error (mm) median "
                     f"{e['median']:.3f} max {e['max']:.3f}; movement {r.movement_mm:.3f} mm")
        lines.append("  Table VI: " + ", ".join(
            f"{n}{'*' if n in res.held_out else ''} {v:.2f}" for n, v in r.corr3d.items()))
    lines.append("  (* held out)")
    if output is not None:
        lines.append(f"tables -> {output}")
    return lines


def lucero2008(output: str | Path, *, utterances: int = 40, frames: int = 60, k: int = 10,
               video: bool = True, progress: Progress | None = None):
    """Lucero & Munhall (2008) on the embedded corpus, written into the folder ``output``:
    ``summary.json``, the figures and, with ``video``, ``animation.mp4``.

    Parameters
    ----------
    output : folder
    utterances : utterances in the corpus (at least 8); ``frames`` per utterance
    k : independent markers of the basis
    video : render the animation from k markers
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.analysis.lucero2008.Lucero2008, with its figures
    """
    from ..analysis.lucero2008 import run_lucero2008
    from .regions import write

    for name, value in (("utterances", utterances), ("frames", frames), ("k", k)):
        check_value(name, value)  # the command line's intervals (facemech.checks)
    _check(output, None, folder=True)
    res = run_lucero2008(n_utterances=utterances, frames=frames, k=k, progress=progress)
    res = draw_lucero2008(res, output, video=video, progress=progress)
    write(res, Path(output) / "summary.json")
    return res


def lucero2008_report(res, output: str | Path) -> list[str]:
    """What ``facemech experiment lucero2008`` prints: ours | the paper's (subject S1)."""
    s, p, a = res.analysis, res.paper, res.all_utterances
    lines = ["[bold]Lucero & Munhall (2008) on the embedded corpus[/bold]  (ours | paper, S1)",
             f"  epsilon-rank: {a['rank']} of 57 | {p['rank']} of 57",
             f"  last two R values: {a['r_before_last_mm']:.2f}, {a['r_last_mm']:.4f} mm | "
             f"{p['r_56_mm']:.2f}, {p['r_57_mm']:.2f} mm",
             f"  last selected: {a['last_selected']} (copied pair {', '.join(res.copied_pair)})"
             f" | {p['copied_marker_selected']}",
             f"  first selected: {', '.join(s.order[:4])} | {p['first_selected']}"]
    if s.trajectory is not None:
        e, q = s.trajectory.max_error_xyz_mm, p["jaw_marker_max_error_k10_mm"]
        lines.append(f"  jaw marker max error, k = {s.k} (x, y, z): "
                     f"{e[0]:.2f}, {e[1]:.2f}, {e[2]:.2f} mm | {q[0]}, {q[1]}, {q[2]} mm")
    rows = s.held_out_error or ()
    for row in rows[:: max(1, len(rows) // 6)]:
        lines.append(f"  k = {row.k:2d}: held-out error {row.mean_abs_error_mm:.3f} mm "
                     f"(relative {row.relative_error:.2f}; PCA {row.pca_mean_abs_error_mm:.3f})")
    sr, mi = res.strong_rrqr, res.muscle_insertions
    lines.append(f"  max |X|: QRCP {sr['qrcp_max_abs_coefficient']:.2f}, strong RRQR "
                 f"{sr['max_abs_coefficient']:.2f} (bound {sr['bound']})")
    lines.append(f"  first 10 selected markers lie {mi.selected_mean_mm:.1f} mm from the nearest "
                 f"muscle insertion; random markers {mi.random_mean_mm:.1f} mm "
                 f"(p = {mi.random_p_value:.3f})")
    lines.append(f"  summary and figures -> {output}/")
    return lines


def dense_animation(path, face, site_nodes: dict[str, int], displacements: np.ndarray,
                    progress: Callable[[int, int], None] | None = None) -> Path:
    """MP4 of the face surface moved by marker displacements (frames, 57, 3) m, interpolated
    over all epidermal nodes with a thin-plate spline on the rest positions."""
    from scipy.interpolate import RBFInterpolator

    from ..viz.movie import write_movie
    from ..viz.scene import build_scene, look_from_model

    names = list(site_nodes)
    rest = face.rest_positions[: face.n_surface]
    src = rest[[site_nodes[n] for n in names]]
    frames = []
    for d in displacements:
        rbf = RBFInterpolator(src, d, kernel="thin_plate_spline", smoothing=0.0)
        frames.append(rest + rbf(rest))
    return write_movie(path, build_scene(look_from_model(face)), np.array(frames),
                       progress=progress)


def draw_lucero2008(result, folder: str | Path, *, video: bool = True,
                    progress: Callable[[str, int, int], None] | None = None):
    """The :class:`~facemech.analysis.lucero2008.Lucero2008` analysis' figures
    (:func:`facemech.workflows.regions.draw`) and, with ``video``, ``animation.mp4``: the first
    held-out utterance predicted from the k independent markers over the whole face.

    Returns the result with its figures recorded."""
    from ..geometry.builder import default_face
    from .regions import draw

    analysis = draw(result.analysis, folder)
    if video:
        model, corpus = analysis.model, result.corpus
        u = corpus.utterances[result.n_train]
        pred = model.predict((u - u[0])[:, model.selected_])
        dense_animation(Path(folder) / "animation.mp4", default_face(), corpus.nodes, pred,
                        progress=None if progress is None else
                        (lambda d, n: progress("render", d, n)))
        analysis = replace(analysis, figures={**analysis.figures, "animation": "animation.mp4"})
    return replace(result, analysis=analysis)


def draw_synthetic(result, folder: str | Path) -> list[Path]:
    """One PNG per run of a :class:`~facemech.inverse.experiments.SyntheticExperiment` in
    ``folder``: the inverted against the true activity, and the error.

    Files are named ``experiment1_<method>_<constraint>.png``; returns their paths.
    """
    from ..inverse.experiments import figure_name
    from ..viz.plots import inversion_figure

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for label, r in result.runs.items():
        path = folder / figure_name(label)
        paths.append(inversion_figure(path, result.time, r.controls, r.control_names,
                                      truth=r.true_controls, rms_error=r.rms_error_m,
                                      title=f"Experiment 1, {label} ({result.preset})"))
    return paths


def write(result, path: str | Path) -> Path:
    """Write an experiment's tables (``result.as_dict()``: a ``SyntheticExperiment`` or
    ``CrossTalkerExperiment`` of :mod:`facemech.inverse.experiments`) as JSON, atomically."""
    from ..atomic import atomic_path

    with atomic_path(path, suffix=".json") as tmp:
        tmp.write_text(json.dumps(result.as_dict(), indent=2))
    return Path(path)
