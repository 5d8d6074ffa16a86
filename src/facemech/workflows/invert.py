"""``facemech invert``: a marker file inverted, the results written, the figure drawn.

The files are read here (the markers, the face, the map file); the inversion of the marker
set on the face is :func:`facemech.inverse.workflow.invert_marker_set`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..inverse.options import FitOptions, InversionOptions, inversion_options
from ..jaw.inputs import JawMarkers
from ..markerset import MarkerSet
from .inputs import MarkerFile, PresetChoice

__all__ = ["FitOptions", "InversionOptions", "JawMarkers", "MarkerFile", "PresetChoice", "draw",
           "invert", "invert_markers", "notes", "parameters", "report"]


def parameters(preset: str | Path = "anatomical", jaw_kinematics: str | None = None,
               dt: float | None = None):
    """The :class:`~facemech.params.Preset` of a preset (name or file) with a command's
    overrides: the jaw's kinematics ("hinge" or "glide") and the inversion's explicit Euler
    step ``dt`` (s; its method's ``fast_dt``): :meth:`PresetChoice.resolve`."""
    return PresetChoice(str(preset), jaw_kinematics, dt).resolve()


def invert_markers(
    markers: str | Path | MarkerSet,
    *,
    face: str | Path = "default",
    map_file: str | Path | None = None,
    scale_pair: str | None = None,
    params=None,
    jaw: JawMarkers | None = None,
    inversion: InversionOptions | None = None,
    options: FitOptions | dict | None = None,
    progress: Callable[[int, int], None] | None = None,
    **given,
):
    """Invert a marker file on a face: the files read, then
    :func:`facemech.inverse.workflow.invert_marker_set` (its parameters, but these three).

    Parameters
    ----------
    markers : marker file (read in its own units; or a :class:`~facemech.markerset.MarkerSet`)
    face : face file or built-in face name, loaded with the preset's tissue
    map_file : marker,node CSV (default: the closest nodes; articulography's lips: their
        vermilion points)
    params : the preset (:func:`facemech.physics.model.model`'s ``preset``; None: the default)
    scale_pair, jaw, inversion, options, progress, given : as
        :func:`~facemech.inverse.workflow.invert_marker_set` (``given``: ``method=``,
        ``positive=``, ``controls=``, ``noise=``)

    Returns
    -------
    facemech.inverse.result.Inversion
    """
    from ..inverse.methods import method_from_options
    from ..inverse.options import as_options, inversion_options
    from ..inverse.workflow import invert_marker_set
    from ..io.markers import read_markers
    from ..kinematics.mapping import read_mapping
    from ..physics.model import model as face_model

    inversion = inversion_options(inversion, given)
    method_from_options(inversion.method, **as_options(options))  # before any file is read
    ms = markers if isinstance(markers, MarkerSet) else read_markers(markers)
    model = face_model(face, params)  # the command's one model (None: the default preset)
    mapping = None if map_file is None else read_mapping(map_file, ms, model.face)
    return invert_marker_set(ms, model, mapping=mapping, scale_pair=scale_pair, jaw=jaw,
                             inversion=inversion, options=options, progress=progress)


def invert(markers: MarkerFile | str | Path, output: str | Path, *,
           face: str | Path = "default", params=None, jaw: JawMarkers | None = None,
           inversion: InversionOptions | None = None, options: FitOptions | dict | None = None,
           figure: str | Path | None = None,
           progress: Callable[[str, int, int], None] | None = None, **given):
    """Recover muscle activity and the jaw frame by frame from a marker file, write the
    results file (re-animated face, controls, standard errors) and, if asked, the figure.

    Parameters
    ----------
    markers : the marker file (:class:`MarkerFile`, or its path: its own units, the closest
        nodes)
    output : results file (.nc), written atomically
    face : the face (file or built-in name)
    params : the preset: a :class:`PresetChoice`, a :class:`~facemech.params.Preset`, a
        :class:`~facemech.params.Parameters` or a preset's name (None: the default preset)
    jaw : the jaw's markers, on the skin or on the bone
        (:class:`~facemech.jaw.inputs.JawMarkers`; None: none)
    inversion : the method ("lsq" or "powell"), activity >= 0, the controls ("speech", "emg7",
        "all" or comma-separated groups; None: "speech", or the part of it the markers
        determine) and the marker noise for the standard errors, mm (None: from the residuals):
        :class:`InversionOptions` (None: the defaults; ``given``: any of them as keywords)
    options : the method's options (:class:`FitOptions`, or a dict of ``window``, ``tol``,
        ``bend``, ``smooth``, ``effort``, ``max_evaluations``, ``max_rate``; None: its default;
        tol in mm, weights in mm per unit; ``max_rate`` 1/s;
        :func:`~facemech.inverse.methods.method_from_options`)
    figure : PNG of the inverted controls with +-2 SE bands and the per-frame error
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.inverse.result.Inversion
    """
    from ..atomic import check_output
    from ..io.results import file_hash

    src = markers if isinstance(markers, MarkerFile) else MarkerFile(Path(markers))
    params = params.resolve() if isinstance(params, PresetChoice) else params
    inputs = [src.path, src.map_file, face if Path(str(face)).suffix else None]
    check_output(output, inputs, field="-o")  # before the inversion, which takes minutes
    if figure is not None:
        if Path(figure).resolve() == Path(output).resolve():
            raise InputError("the figure and the results file are the same path",
                             source=str(figure), field="--figure")
        check_output(figure, inputs, field="--figure")
    ms = check_markers(src.path, units=src.units, scale_pair=src.scale_pair)  # before the work
    inversion = inversion_options(inversion, given)
    label = f"invert ({inversion.method})"
    res = invert_markers(
        ms, face=face, map_file=src.map_file, scale_pair=src.scale_pair, params=params, jaw=jaw,
        inversion=inversion, options=options,
        progress=None if progress is None else (lambda d, n: progress(label, d, n)))
    dropped = [n for n in ms.meta.get("notes", []) if n.startswith("dropped")]
    if dropped:  # the reader's: empty leading or trailing frames left out
        from dataclasses import replace

        res = replace(res, notes=[f"{Path(src.path).name}: {n}" for n in dropped] + list(res.notes))
    res = _write(res, ms, output, {"markers": file_hash(src.path)})
    if figure is not None:
        draw(res, figure, title=f"{Path(src.path).name}: inverted controls ({res.method.name})")
    return res


def _write(res, ms, output, inputs: dict):
    """Write the results and return them; with a tongue-tip coil in the recording, its pose
    drives the rendered tongue tip (``tongue_tip``; :mod:`facemech.kinematics.tongue_coils`),
    noted."""
    from dataclasses import replace

    from ..io.results import with_tongue, write_dataset
    from ..kinematics.tongue_coils import tongue_tip_pose
    from .markers import on_times

    if not (ms.meta.get("roles") or {}):
        res.write(output, inputs=inputs)
        return res
    on = on_times(ms, ms.time[0] + res.time - res.time[0], label=res.time)[0]
    found = tongue_tip_pose(on)
    if found is None:
        res.write(output, inputs=inputs)
        return res
    pose, coil = found
    res = replace(res, notes=[*res.notes, f"the rendered tongue tip follows the coil {coil} "
                              "(its displacement less the lower incisor's; protrusion "
                              f"{pose[:, 0].min() * 1e3:.1f} to {pose[:, 0].max() * 1e3:.1f} mm, "
                              f"elevation {pose[:, 1].min() * 1e3:.1f} to "
                              f"{pose[:, 1].max() * 1e3:.1f} mm)"])
    write_dataset(output, with_tongue(res.to_dataset(inputs), pose))
    return res


def check_markers(markers: str | Path, *, units: str | None = None,
                  scale_pair: str | None = None):
    """Read the marker file of an inversion and refuse, before the inversion starts, what would
    stop it later: a frame where every marker is missing, and a ``--scale-pair`` that is not
    two different markers of the file. Returns the :class:`~facemech.markerset.MarkerSet`."""
    from ..io.markers import read_markers

    return check_marker_set(read_markers(markers, units=units), markers, scale_pair=scale_pair)


def check_marker_set(ms, markers: str | Path, *, scale_pair: str | None = None):
    """:func:`check_markers` of a marker set read from the file ``markers``; returns it."""
    empty = ~ms.valid.any(axis=1)
    if empty.any():
        k = int(np.argmax(empty))
        from .markers import gap_hint

        raise InputError(f"frame {k + 1} (t = {ms.time[k]:.3f} s) has no marker at all "
                         f"({int(empty.sum())} such frames): {gap_hint(ms, k)}",
                         source=str(markers), field="frames")
    if scale_pair is not None:
        pair = [p.strip() for p in str(scale_pair).split(",")]
        if len(pair) != 2 or not all(pair) or pair[0] == pair[1]:
            raise InputError(f"{scale_pair!r}: give two different markers far apart, A,B "
                             "(e.g. R01,L01)", field="--scale-pair")
        for name in pair:
            if name not in ms.names:
                raise InputError(f"{scale_pair!r}: no marker {name!r} in {markers}",
                                 field="--scale-pair")
            if not ms.valid[0, ms.index(name)]:
                raise InputError(f"{scale_pair!r}: marker {name!r} is missing in the first "
                                 f"frame of {markers} (the scaling's reference)",
                                 field="--scale-pair")
    return ms


def draw(res, path: str | Path, *, title: str = "") -> Path:
    """PNG of an inversion's controls with +-2 SE bands and its per-frame error."""
    from ..viz.plots import inversion_figure

    return inversion_figure(path, res.time, res.controls, res.control_names,
                            rms_error=res.rms_error, se=res.control_se,
                            identifiable=res.identifiable, title=title,
                            fit=(res.marker_names, res.markers, res.data_markers),
                            combinations=res.combinations, noise_mm=res.noise_mm)


def report(res, output: str | Path, figure: str | Path | None = None) -> list[str]:
    """What ``facemech invert`` prints: the per-frame error, the fit per sensor and axis, the
    controls (or combinations of controls) the markers determine, and the figure."""
    from ..inverse.sensor_fit import fit_lines

    s = res.error_summary()
    seen = [n for n, ok in zip(res.control_names, res.identifiable, strict=True) if ok]
    combos = [c.name for c in res.combinations if c.determined(res.noise_mm)]
    lines = [f"{len(res.time)} frames inverted ({res.method.name}) in {res.wall_seconds:.1f} s;"
             f" per-frame error (RMS over {len(res.marker_names)} markers): median "
             f"{s['median_mm']:.3f} mm, max {s['max_mm']:.3f} mm -> {output}",
             "  fit per sensor and axis (model against measured: RMS, largest error, "
             "correlation, the model's share of the recorded range):",
             *(f"    {line}" for line in fit_lines(res.sensor_fit)),
             f"  determined by the markers (noise {res.noise_mm:.3f} mm, {res.noise_how}): "
             f"{', '.join(seen) or 'no single control'}"
             + ("" if len(seen) == len(res.control_names) else
                f"; combinations of controls within 0.1: {'; '.join(combos) or 'none'} (see "
                "the note)")]
    return lines + ([] if figure is None else [f"figure -> {figure}"])


def notes(res) -> list[str]:
    """The inversion's notes and warnings, for stderr ("note: ...", "warning: ...")."""
    return ([f"note: {n}" for n in res.notes]
            + [f"warning: {w}" for w in res.error_summary()["warnings"]])
