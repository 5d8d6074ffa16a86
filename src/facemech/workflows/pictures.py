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
    names = [_as_meant(n, ms.names) for n in names]
    unknown = [n for n in names if n not in ms.names]
    if unknown:
        raise InputError(f"--markers: no marker {unknown[0]!r} in the results (have "
                         f"{', '.join(ms.names[:12])}, ...)", source=str(result), field=unknown[0])
    traj = {n: ms.marker(n) for n in names}
    meas = None
    if measured is not None:
        meas = trajectories(measured, names, units=units, times=ms.time, missing="skip",
                            origin="first")[1]  # results' time 0: the recording's first frame
        for n, xyz in meas.items():
            gap = ~np.isfinite(xyz).all(axis=1)
            if gap.all():
                raise InputError("the marker has no sample at all", source=str(measured),
                                 field=n)
            if gap.any():
                k = int(np.argmax(gap))
                inside = (~gap[:k]).any() and (~gap[k:]).any()
                raise InputError(f"the marker has a gap at t = {ms.time[k]:.3f} s ("
                                 + ("fill it: facemech markers fill-gaps" if inside else
                                    "cut the ends: facemech markers trim") + ")",
                                 source=str(measured), field=n)
    if inverted is not None:  # an inversion: the data it fitted, as measured
        meas = {n: inverted[n] for n in names if n in inverted}
    path = kinematics_figure(output, ms.time, traj, rate=ms.rate, measured=meas,
                             title=str(Path(result).name))
    return Written(Path(path), traj, f"figure -> {output}")


def _as_meant(name: str, names) -> str:
    """The marker the user means by ``name`` (:func:`facemech.markerset.match_name`: ``ul``
    finds ``UL`` where that is unambiguous), else ``name`` itself, refused by the caller with
    the results' names."""
    from ..errors import InputError
    from ..markerset import match_name

    try:
        return match_name(name, names)
    except InputError:
        return name


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
                units: str | None = None, blendshapes: str | None = None,
                face: str | None = None, progress: StagedProgress | None = None) -> Written:
    """Export a results file (:func:`facemech.io.export.export_results`): animated skin as glTF
    (``.glb``), one mesh per frame (``fmt`` ``obj`` or ``ply``, ``output`` a folder), or
    markers (``.trc``, ``.c3d``, ``.csv``); with ``blendshapes="arkit"``, the blendshape export
    of :func:`export_blendshapes` (``face`` its face)."""
    from ..errors import InputError
    from ..io.export import export_results

    if blendshapes is not None:
        if str(blendshapes).lower() != "arkit":
            raise InputError(f"unknown blendshape set {blendshapes!r} (expected arkit)",
                             field="--blendshapes")
        if fmt is not None or units is not None:
            raise InputError("a blendshape export is a .glb in metres: no --format or --units",
                             field="--blendshapes")
        return export_blendshapes(result, output, face=face, progress=progress)
    if face is not None:
        raise InputError("--face goes with --blendshapes", field="--face")
    folder = fmt is not None or Path(output).suffix == "" or Path(output).is_dir()
    check_output(output, [result], folder=folder, field="-o")
    res = export_results(result, output, fmt=fmt, units=units)
    return Written(Path(output), res, res.summary())


def blendshape_outputs(output: str | Path) -> tuple[Path, Path, Path]:
    """The files of a blendshape export to ``output`` (``.glb``): it, and the weights' ``.csv``
    and ``.json`` beside it with the same stem."""
    output = Path(output)
    return output, output.with_suffix(".csv"), output.with_suffix(".json")


def _result_face(ds, face: str | None, source: str):
    """The face and preset a result was made with (``face`` overrides the result's own name),
    checked against the result's rest positions."""
    from ..errors import FacemechError, InputError
    from ..geometry.builder import load_face
    from ..params import preset

    name = face or str(ds.attrs.get("face", ""))
    if name.startswith("generic-adult"):  # a built-in face's own name (geometry.builder)
        name = "default" + name[len("generic-adult"):]
    try:
        params = preset(str(ds.attrs.get("preset", "anatomical")))
    except FacemechError as exc:
        raise InputError(f"the result's preset cannot be loaded ({exc})", source=source,
                         field="preset") from None
    try:
        model = load_face(name, tissue=params.tissue)
    except FacemechError as exc:
        raise InputError(f"the result's face {name!r} cannot be loaded ({exc}); give it with "
                         "--face", source=source, field="--face") from None
    rest = np.asarray(ds["rest_positions"].values, float)
    skin = model.rest_positions[: model.n_surface]
    if skin.shape != rest.shape or np.abs(skin - rest).max() > 1e-6:
        raise InputError(f"the result was not made on the face {name!r} ({len(rest)} nodes, "
                         f"the face {len(skin)}); give its face with --face", source=source,
                         field="--face")
    return model, params


def export_blendshapes(result: str | Path, output: str | Path, *, face: str | None = None,
                       progress: StagedProgress | None = None) -> Written:
    """ARKit's 52 blendshapes made from the result's own face
    (:func:`facemech.analysis.blendshapes.arkit_basis`), weights fitted to every frame
    (:func:`~facemech.analysis.blendshapes.fit_weights`), written as a glTF with the named
    morph targets and their weight animation (``output``, ``.glb``) and the weights as CSV and
    JSON beside it (:func:`blendshape_outputs`).

    Parameters
    ----------
    result : results file (``.nc``)
    output : the ``.glb``
    face : the face the result was made on (a name or ``.npz``; default: the result's own)
    progress : staged progress; stages ``gestures`` and ``fit``

    Returns
    -------
    Written : ``data`` a dict with the fit's error (mm), the shapes' table and the files
    """
    from ..analysis.blendshapes import ARKIT_SHAPES, arkit_basis, fit_weights
    from ..errors import InputError
    from ..io import blendshapes as out
    from ..io.results import read_results

    paths = blendshape_outputs(output)
    if paths[0].suffix.lower() != ".glb":
        raise InputError("a blendshape export is a binary glTF: -o must end in .glb",
                         source=str(output), field="-o")
    for p in paths:
        check_output(p, [result], field="-o")
    ds = read_results(result)
    from ..physics.model import model as face_model

    model, params = _result_face(ds, face, str(result))
    basis = arkit_basis(face_model(model, params), progress=stage(progress, "gestures"))
    positions = ds["positions"].transpose("time", "node", "axis").values.astype(float)
    fit = fit_weights(basis, positions)
    if progress is not None:
        progress("fit", 1, 1)
    times = np.asarray(ds["time"].values, float)
    error = {k: round(v, 4) for k, v in fit.summary().items()}
    info = {"format": "facemech-blendshapes", "set": "arkit", "units": "1 (weights in [0, 1])",
            "source": Path(result).name, "face": model.name, "preset": params.name,
            "fit_error": error, "lips_nodes": int(basis.lips.sum()),
            "frame_error": {"rms_lips_mm": np.round(fit.rms_lips_mm, 4).tolist(),
                            "rms_face_mm": np.round(fit.rms_face_mm, 4).tolist()},
            "shapes": basis.table()}
    out.write_blendshape_gltf(paths[0], basis.rest, basis.triangles, ARKIT_SHAPES,
                              basis.displacement, times, fit.weights,
                              {**{k: v for k, v in info.items()
                                  if k not in ("shapes", "frame_error")},
                               "flagged": [r["name"] for r in info["shapes"] if not r["made"]]})
    out.write_weights_csv(paths[1], ARKIT_SHAPES, times, fit.weights)
    out.write_weights_json(paths[2], ARKIT_SHAPES, times, fit.weights, info)
    made = int(basis.made.sum())
    return Written(paths[0], {**info, "files": paths},
                   f"blendshapes (ARKit, {made} of 52 made, {52 - made} flagged): "
                   f"{len(times)} frames -> {paths[0]}, {paths[1].name}, {paths[2].name}\n"
                   f"fit error (RMS): lips {error['rms_lips_mm']:.3f} mm, face "
                   f"{error['rms_face_mm']:.3f} mm (worst frame: lips "
                   f"{error['max_frame_rms_lips_mm']:.3f} mm, face "
                   f"{error['max_frame_rms_face_mm']:.3f} mm)")
