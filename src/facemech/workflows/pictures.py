"""Picture workflows of a results file: a movie or PNG frames, a still figure, a kinematics plot,
an interactive viewer page, and exports (glTF, meshes, markers)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..atomic import check_output
from ..progress import StagedProgress, stage
from .outcome import Written


def render_options(view: str = "frontal+profile", size: str = "1280x720",
                   background: str = "#2a2c33", aa: int = 2):
    """:class:`facemech.viz.video.RenderOptions` from their text forms: the ``view``, the frame
    ``size`` ``WIDTHxHEIGHT`` (pixels), the ``background`` (``#rrggbb``, ``r,g,b`` or
    ``transparent``) and ``aa``, the samples per pixel along each axis (1 to 4)."""
    from ..viz.camera import parse_size
    from ..viz.video import RenderOptions

    return RenderOptions(view=view, size=parse_size(size), background=background,
                         supersample=aa)


@dataclass(frozen=True)
class Movie:
    """A movie to render: ``path`` an ``.mp4`` or a folder for PNG frames, ``audio`` a WAV
    muxed into the MP4, ``options`` a :class:`facemech.viz.video.RenderOptions` (default:
    frontal and profile, 1280x720)."""

    path: Path
    audio: Path | None = None
    options: object | None = None


def check_movie(movie: Movie | tuple, inputs=(), field: str = "-o") -> Movie:
    """Check a :class:`Movie` (or its fields as a tuple) before any long work: its output
    (never one of ``inputs``, writable; ``field`` the option that gave it) and its audio (a
    readable WAV with some sound, and only for an MP4). Returns the :class:`Movie`."""
    from ..errors import InputError
    from ..speech.wav import check_audio

    movie = movie if isinstance(movie, Movie) else Movie(*movie)
    frames = Path(movie.path).suffix == ""
    check_output(movie.path, [*inputs, movie.audio], folder=frames, field=field)
    if movie.audio is not None:
        if frames:
            raise InputError("audio goes into a movie, not into PNG frames",
                             source=str(movie.audio), field="audio")
        check_audio(movie.audio, field="audio")
    return movie


def render_movie(results, movie: Movie | tuple, *, source: str | None = None,
                 progress: StagedProgress | None = None) -> Written:
    """Render a results dataset (or file) to ``movie`` (a :class:`Movie`, or its fields as a
    tuple): an H.264 MP4 or PNG frames, with eyes, teeth and tongue, at the results' frame rate.
    Reports the stage ``render`` (frames). The output is checked first (never an input, and
    writable: :func:`facemech.atomic.check_output`)."""
    from ..viz.video import render_results

    movie = check_movie(movie, [results if isinstance(results, (str, Path)) else source])
    if isinstance(results, (str, Path)):
        from ..io.results import read_results

        source, results = source or str(results), read_results(results)
    path = render_results(results, Path(movie.path), options=movie.options, audio=movie.audio,
                          source=source, progress=stage(progress, "render"))
    return Written(path, None, f"{'movie' if Path(movie.path).suffix else 'frames'} -> "
                   f"{movie.path}")


def still_file(result: str | Path, output: str | Path, *, time: float | None = None,
               peak: str | None = None, render=None, markers: bool = False,
               labels: bool = False) -> Written:
    """A still figure (PNG or PDF) of one frame of a results file: at ``time`` (s), at the peak
    of ``peak`` (a muscle group, ``jaw`` or ``motion``), or the first; with the model's markers
    as dots (``markers``) and their names (``labels``, which implies ``markers``); ``render``
    the :func:`render_options` (default: theirs).

    Returns
    -------
    Written : ``data`` a dict with ``frame``, ``time`` (s) and ``output``
    """
    from ..io.results import read_results
    from ..viz.video import still

    check_output(output, [result], field="-o")
    r = still(read_results(result), output, time=time, peak=peak, options=render,
              markers=markers or labels, labels=labels, source=str(result))
    return Written(Path(output), r, f"frame {r['frame']} (t = {r['time']:.3f} s) -> {output}")


#: the markers ``plot`` draws unless told
DEFAULT_PLOT_MARKERS = "R03,R05,R07"


def inverted_markers(result) -> dict | None:
    """An inversion's fitted data, name -> (frames, 3) m (None: the results are not an
    inversion's)."""
    from ..io.results import read_results

    ds = read_results(result)
    if "data_markers" not in ds:
        return None
    data = ds["data_markers"].transpose("time", "marker", "axis").values
    return {str(n): data[:, k] for k, n in enumerate(ds["marker"].values)}


def plot_file(result: str | Path, output: str | Path,
              markers: str | Sequence[str] = DEFAULT_PLOT_MARKERS, *,
              measured: str | Path | None = None, units: str | None = None) -> Written:
    """Displacement and acceleration (vertical, protrusion) of model markers, like Figs. 4-6 of
    Lucero & Munhall (1999), with measured markers of the same names (dashed) if given.

    Parameters
    ----------
    result : results file (``.nc``); the rate is its ``frame_rate_hz``
    output : the figure (``.png``)
    markers : marker names (a sequence or comma-separated text); each must be in the results
    measured : marker file with measured markers (those of the same names are drawn),
        interpolated onto the results' times; for an inversion's results, by default the data
        it fitted (and, by default, its sensors rather than ``R03,R05,R07``)
    units : length unit of ``measured`` if it does not say
    """
    from ..errors import InputError
    from ..io.markers import read_markers
    from ..viz.plots import kinematics_figure
    from .markers import names_of, trajectories

    check_output(output, [result, measured], field="-o")
    names = names_of(markers)
    if not names:
        raise InputError(f"no marker name in {markers!r} (e.g. R03,R05)", field="--markers")
    ms = read_markers(result)
    inverted = inverted_markers(result) if measured is None else None
    if inverted is not None and markers == DEFAULT_PLOT_MARKERS:
        names = [n for n in ms.names if n in inverted]  # an inversion: its sensors
    unknown = [n for n in names if n not in ms.names]
    if unknown:
        raise InputError(f"--markers: no marker {unknown[0]!r} in the results (have "
                         f"{', '.join(ms.names[:12])}, ...)", source=str(result), field=unknown[0])
    traj = {n: ms.marker(n) for n in names}
    meas = None
    if measured is not None:
        meas = trajectories(measured, names, units=units, times=ms.time, missing="skip")[1]
        for n, xyz in meas.items():
            gap = ~np.isfinite(xyz).all(axis=1)
            if gap.all():
                raise InputError("the marker has no sample at all", source=str(measured),
                                 field=n)
            if gap.any():
                k = int(np.argmax(gap))
                raise InputError(f"the marker has a gap at t = {ms.time[k]:.3f} s (fill it: "
                                 "facemech markers fill-gaps)", source=str(measured), field=n)
    if inverted is not None:  # an inversion: the data it fitted, as measured
        meas = {n: inverted[n] for n in names if n in inverted}
    path = kinematics_figure(output, ms.time, traj, rate=ms.rate, measured=meas,
                             title=str(Path(result).name))
    return Written(Path(path), traj, f"figure -> {output}")


def view_file(result: str | Path, output: str | Path, *, markers: str | Path | None = None,
              units: str | None = None, title: str | None = None) -> Written:
    """An interactive viewer of a results file (and measured markers in the model's frame):
    one self-contained HTML page (:func:`facemech.viz.viewer.view_file`)."""
    from ..io.results import read_results
    from ..viz.viewer import undetermined_muscles
    from ..viz.viewer import view_file as write_page

    check_output(output, [result, markers], field="-o")
    path = write_page(result, output, markers=markers, units=units, title=title)
    warning = undetermined_muscles(read_results(result))[1]
    return Written(path, None, f"viewer -> {path} ({path.stat().st_size / 1e6:.1f} MB)",
                   "" if warning is None else f"facemech: warning: {warning}\n")


def export_file(result: str | Path, output: str | Path, *, fmt: str | None = None,
                units: str | None = None) -> Written:
    """Export a results file (:func:`facemech.io.export.export_results`): animated skin as glTF
    (``.glb``), one mesh per frame (``fmt`` ``obj`` or ``ply``, ``output`` a folder), or
    markers (``.trc``, ``.c3d``, ``.csv``)."""
    from ..io.export import export_results

    folder = fmt is not None or Path(output).suffix == "" or Path(output).is_dir()
    check_output(output, [result], folder=folder, field="-o")
    res = export_results(result, output, fmt=fmt, units=units)
    return Written(Path(output), res, res.summary())
