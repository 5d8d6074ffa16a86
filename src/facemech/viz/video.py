"""Library entry points for pictures of results: movies, PNG frame sequences and still figures.

:class:`RenderOptions` gathers what a user chooses (view, size, background, anti-aliasing,
camera distance) and validates it once; :func:`render_results` turns a results file (or a
simulation) into a movie or frames; :func:`still` draws one frame, at a time or at the peak of a
gesture, optionally with the markers as dots and their names, as PNG or PDF.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..checks import check_value
from ..errors import InputError
from ..params import FRAME_RATE_HZ
from .render import FrameMotion, Renderer, RenderOptions
from .scene import Scene, build_scene, look_from_dataset, look_from_model

__all__ = ["FrameMotion", "RenderOptions", "peak_frame", "render_results", "scene_of", "still"]




def scene_of(source) -> Scene:
    """The scene of a results dataset or a face model."""
    if hasattr(source, "data_vars"):
        return build_scene(look_from_dataset(source))
    return build_scene(look_from_model(source))


def render_results(ds, output: str | Path, *, options: RenderOptions | None = None,
                   audio: str | Path | None = None, fps: float | None = None,
                   progress: Callable[[int, int], None] | None = None,
                   source: str | None = None, motion: FrameMotion | None = None,
                   workers: int | None = None) -> Path:
    """Render a results dataset to ``output``: an ``.mp4`` movie, or a folder of PNG frames.

    Parameters
    ----------
    ds : results (:func:`facemech.io.results.read_results`) or its path
    output : ``*.mp4`` or a folder path (no suffix) that does not exist or is empty
    options : :class:`RenderOptions` (default: frontal+profile, 1280x720)
    audio : WAV muxed into a movie
    fps : frame rate (default: the results')
    source : name of the results, for error messages (default: the path, when given one)
    motion : blinks, gaze and head pose per frame (:class:`FrameMotion`; None: at rest); the
        tongue tip's pose is the results' ``tongue_tip`` where ``motion`` carries none
        (:func:`motion_with_tongue`)
    workers : threads drawing the frames, 1 to 1024 (None: ``min(2, available cores)``);
        the frames are the same whatever the number (:func:`.movie.write_movie`)
    """
    from .movie import write_frames, write_movie

    source = source or (str(ds) if isinstance(ds, (str, Path)) else None)
    ds = _dataset(ds)
    opt = options or RenderOptions()
    scene = scene_of(ds)
    pos = ds["positions"].values
    jaw = jaw_poses_of(ds)
    fps = float(fps or ds.attrs.get("frame_rate_hz", FRAME_RATE_HZ))
    motion = motion_with_tongue(motion, ds)
    output = Path(output)
    if output.suffix.lower() == ".mp4":
        return write_movie(output, scene, pos, jaw, fps=fps, audio=audio, options=opt,
                           progress=progress, source=source, motion=motion, workers=workers)
    if output.suffix:
        raise InputError(f"output {output.name!r}: give a .mp4 file or a folder for PNG frames",
                         field="output")
    if audio is not None:
        raise InputError("audio goes into a movie, not into PNG frames", field="audio")
    return write_frames(output, scene, pos, jaw, options=opt, progress=progress,
                        source=source, motion=motion, workers=workers)


def motion_with_tongue(motion: FrameMotion | None, ds) -> FrameMotion | None:
    """``motion`` with the results' tongue tip series (:func:`facemech.io.results.results_tongue`)
    where it has none of its own: a still face with that tongue when ``motion`` is None; as
    given when the results have no tongue series (the tongue at rest)."""
    from ..io.results import results_tongue

    tongue = results_tongue(ds)
    if tongue is None or (motion is not None and motion.tongue is not None):
        return motion
    if motion is None:
        return FrameMotion.rest(len(tongue), tongue)
    return motion.with_tongue(tongue) if len(motion) == len(tongue) else motion


def jaw_poses_of(ds) -> np.ndarray | None:
    """The jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) of a results dataset: its
    ``jaw_angle`` and ``jaw_shift`` (zeros where the file has none); None without a jaw."""
    if "jaw_angle" not in ds:
        return None
    angle = np.asarray(ds["jaw_angle"].values, float)
    if "jaw_shift" in ds:
        shift = np.asarray(ds["jaw_shift"].transpose("time", "shift_axis").values, float)
    else:
        shift = np.zeros((len(angle), 2))
    return np.column_stack([angle, shift])


def _dataset(ds):
    if isinstance(ds, (str, Path)):
        from ..io.results import read_results

        return read_results(ds)
    return ds


def peak_frame(ds, peak: str, source: str | None = None) -> int:
    """The frame of a gesture's peak: a muscle group's activity, ``jaw`` or ``motion``.

    ``motion`` is the frame where the lip landmarks are farthest from their first position.
    """
    import json

    key = peak.strip()
    if key.lower() == "jaw":
        return int(np.argmax(ds["jaw_angle"].values))
    if key.lower() == "motion":
        nodes = json.loads(ds.attrs.get("marker_nodes", "{}"))
        lips = [nodes[k] for k in ("upper_lip_center", "lower_lip_center",
                                   "mouth_corner_left", "mouth_corner_right") if k in nodes]
        p = ds["positions"].values
        sel = p[:, lips] if lips else p
        return int(np.argmax(np.linalg.norm(sel - sel[0], axis=2).max(axis=1)))
    muscles = [str(m) for m in ds["muscle"].values]
    if key.upper() not in muscles:
        raise InputError(f"--peak {peak!r}: give jaw, motion or a muscle group "
                         f"({', '.join(muscles)})", source=source, field="peak")
    return int(np.argmax(ds["activity"].values[:, muscles.index(key.upper())]))


def still(ds, output: str | Path, *, time: float | None = None, peak: str | None = None,
          options: RenderOptions | None = None, markers: bool = False,
          labels: bool = False, title: str | None = None, source: str | None = None,
          motion: FrameMotion | None = None) -> dict:
    """A still figure of one frame as PNG or PDF, optionally with marker dots and names.

    Parameters
    ----------
    ds : results dataset or its path
    output : ``.png`` or ``.pdf``
    time : s, the frame nearest this time; or
    peak : the frame of a gesture's peak (:func:`peak_frame`); neither: the first frame
    options : :class:`RenderOptions` (default here: frontal, 1280x1280)
    markers, labels : draw the model's markers as dots, and their names beside them
    source : name of the results, for error messages (default: the path, when given one)
    motion : blinks, gaze and head pose per frame of the results (:class:`FrameMotion`; None:
        at rest); the markers turn with the head; the tongue as :func:`render_results`

    Returns
    -------
    dict with ``frame``, ``time`` (s) and ``output``
    """
    import matplotlib.figure as mfig

    source = source or (str(ds) if isinstance(ds, (str, Path)) else None)
    if time is not None:
        check_value("time", time, source=source)  # the command line's interval
    ds = _dataset(ds)
    output = Path(output)
    if output.suffix.lower() not in (".png", ".pdf"):
        raise InputError(f"output {output.name!r}: a still is .png or .pdf", field="output")
    if time is not None and peak is not None:
        raise InputError("give --time or --peak, not both", field="time")
    t = ds["time"].values
    if time is not None:
        if not t[0] - 1e-9 <= time <= t[-1] + 1e-9:
            raise InputError(f"time {time} s is outside the results ({t[0]:.3f} to "
                             f"{t[-1]:.3f} s)", source=source, field="time")
        k = int(np.argmin(np.abs(t - time)))
    elif peak is not None:
        k = peak_frame(ds, peak, source=source)
    else:
        k = 0
    opt = options or RenderOptions(view="frontal", size=(1280, 1280))
    scene = scene_of(ds)
    rend = opt.renderer(scene)
    poses = jaw_poses_of(ds)
    jaw = np.zeros(3) if poses is None else poses[k]
    skin = ds["positions"].values[k]
    if not np.all(np.isfinite(skin)) or not np.all(np.isfinite(jaw)):
        raise InputError(f"frame {k} holds non-finite positions or jaw angle", source=source,
                         field="positions")
    if motion is not None and len(motion) != len(t):
        raise InputError(f"the blink, gaze and head series have {len(motion)} frames, the "
                         f"results {len(t)}", source=source, field="motion")
    motion = motion_with_tongue(motion, ds)
    blink, gaze, head, tongue = (motion.at(k) if motion is not None
                                 else (0.0, (0.0, 0.0), None, None))
    img = rend(skin, jaw, blink, gaze, head, tongue)
    h, w = opt.size
    fig = mfig.Figure(figsize=(w / 200, h / 200), dpi=200)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(img, interpolation="lanczos")
    ax.set_axis_off()
    if markers or labels:
        _draw_markers(ax, ds, k, rend, labels, head)
    if title:
        ax.text(0.02, 0.98, title, transform=ax.transAxes, va="top", color="white",
                fontsize=9)
    with atomic_path(output, suffix=output.suffix) as tmp:
        fig.savefig(tmp, dpi=200, transparent=opt.transparent,
                    format=output.suffix[1:].lower())
    return {"frame": k, "time": float(t[k]), "output": str(output)}


def _draw_markers(ax, ds, k: int, rend: Renderer, labels: bool, head=None) -> None:
    """Marker dots (and names) on the panels where they face the camera; ``head``: the head's
    pose (3,) rad, which turns them with the face."""
    from ..geometry.builder import vertex_normals
    from .scene import head_pivot, head_rotation

    pos = ds["positions"].values[k]
    names = [str(n) for n in ds["marker"].values]
    mk = ds["markers"].values[k]
    import json

    nodes = json.loads(ds.attrs.get("marker_nodes", "{}"))
    normals = vertex_normals(pos, ds["triangles"].values)
    if head is not None:
        r, pivot = head_rotation(head), head_pivot(rend.scene)
        mk = (mk - pivot) @ r.T + pivot
        normals = normals @ r.T
    x_off = 0
    for cam in rend.cameras:
        p = cam.project(mk)
        facing = np.ones(len(names), bool)
        for i, n in enumerate(names):
            if n in nodes:
                nrm = normals[int(nodes[n])] @ cam.rotation.T
                facing[i] = nrm[2] > 0.05
        inside = ((p[:, 0] >= 0) & (p[:, 0] < cam.size[1]) & (p[:, 1] >= 0)
                  & (p[:, 1] < cam.size[0]) & facing)
        ax.scatter(p[inside, 0] + x_off, p[inside, 1], s=9, c="#ffd400", edgecolors="black",
                   linewidths=0.4, zorder=3)
        if labels:
            for i in np.flatnonzero(inside):
                ax.annotate(names[i], (p[i, 0] + x_off, p[i, 1]), xytext=(3, 3),
                            textcoords="offset points", fontsize=4.5, color="white",
                            zorder=4)
        x_off += cam.size[1]
