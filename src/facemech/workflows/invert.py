"""``facemech invert``: a marker file inverted, the results written, the figure drawn."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["draw", "invert", "notes", "report"]


def invert(markers: str | Path, output: str | Path, *, face: str | Path = "default",
           map_file: str | Path | None = None, method: str = "lsq", positive: bool = True,
           controls: str | None = None, chin_marker: str | None = None,
           jaw_second_marker: str | None = None, jaw_incisor: str | None = None,
           jaw_molar: str | None = None, jaw_fixed: bool = False, jaw_lead: int | None = None,
           noise: float | None = None, window: int | None = None, tol: float | None = None,
           bend: float | None = None, smooth: float | None = None, effort: float | None = None,
           max_evaluations: int | None = None, scale_pair: str | None = None,
           preset: str = "anatomical", jaw_kinematics: str | None = None,
           dt: float | None = None, units: str | None = None, figure: str | Path | None = None,
           progress: Callable[[str, int, int], None] | None = None):
    """Recover muscle activity and the jaw frame by frame from a marker file, write the
    results file (re-animated face, controls, standard errors) and, if asked, the figure.

    Parameters
    ----------
    markers : marker file in the model's frame, at the preset's frame rate
    output : results file (.nc), written atomically
    face, map_file : the face (file or built-in name) and a marker,node CSV (default: the
        closest nodes)
    method, positive, controls : "lsq" or "powell"; activity >= 0; "speech", "emg7", "all" or
        comma-separated groups (None: "speech", or the part of it the markers determine)
    chin_marker, jaw_second_marker, jaw_incisor, jaw_molar, jaw_fixed, jaw_lead : a jaw
        recording, on the skin or on the bone (see
        :func:`facemech.inverse.workflow.invert_markers`), lead in frames (None: 2 for a skin
        marker, 0 for bone points)
    noise : marker noise for the standard errors, mm (default: from the residuals)
    window, tol, bend, smooth, effort, max_evaluations : the method's options (None: its
        default; tol in mm, weights in mm per unit)
    scale_pair : "A,B": adapt the markers by per-axis scaling from two markers far apart
    preset, jaw_kinematics, dt : the parameters, "hinge" or "glide", the Euler step (s)
    units : length unit of a marker file that carries none
    figure : PNG of the inverted controls with +-2 SE bands and the per-frame error
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.inverse.result.Inversion
    """
    from ..atomic import check_output
    from ..inverse.workflow import invert_markers
    from ..io.results import file_hash

    inputs = [markers, map_file, face if Path(str(face)).suffix else None]
    check_output(output, inputs, field="-o")  # before the inversion, which takes minutes
    if figure is not None:
        if Path(figure).resolve() == Path(output).resolve():
            raise InputError("the figure and the results file are the same path",
                             source=str(figure), field="--figure")
        check_output(figure, inputs, field="--figure")
    ms = check_markers(markers, units=units, scale_pair=scale_pair)  # before the long work
    label = f"invert ({method})"
    res = invert_markers(
        ms, face=face, map_file=map_file, units=units, scale_pair=scale_pair,
        preset=preset, jaw_kinematics=jaw_kinematics, method=method, positive=positive,
        controls=controls, chin_marker=chin_marker, jaw_second_marker=jaw_second_marker,
        jaw_incisor=jaw_incisor, jaw_molar=jaw_molar, jaw_fixed=jaw_fixed, jaw_lead=jaw_lead,
        noise=noise, dt=dt,
        options=dict(window=window, tol=tol, bend=bend, smooth=smooth, effort=effort,
                     max_evaluations=max_evaluations),
        progress=None if progress is None else (lambda d, n: progress(label, d, n)))
    res.write(output, inputs={"markers": file_hash(markers)})
    if figure is not None:
        draw(res, figure, title=f"{Path(markers).name}: inverted controls ({res.method.name})")
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
        raise InputError(f"frame {k + 1} (t = {ms.time[k]:.3f} s) has no marker at all "
                         f"({int(empty.sum())} such frames): cut them or fill the gaps "
                         "(facemech markers fill-gaps)", source=str(markers), field="frames")
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
                            identifiable=res.identifiable, title=title)


def report(res, output: str | Path, figure: str | Path | None = None) -> list[str]:
    """What ``facemech invert`` prints: the per-frame error, the controls the markers
    determine, and the figure."""
    s = res.error_summary()
    seen = [n for n, ok in zip(res.control_names, res.identifiable, strict=True) if ok]
    lines = [f"{len(res.time)} frames inverted ({res.method.name}) in {res.wall_seconds:.1f} s;"
             f" per-frame error (RMS over {len(res.marker_names)} markers): median "
             f"{s['median_mm']:.3f} mm, max {s['max_mm']:.3f} mm -> {output}",
             f"  determined by the markers (noise {res.noise_mm:.3f} mm, {res.noise_how}): "
             f"{', '.join(seen) or 'none'}"]
    return lines + ([] if figure is None else [f"figure -> {figure}"])


def notes(res) -> list[str]:
    """The inversion's notes and warnings, for stderr ("note: ...", "warning: ...")."""
    return ([f"note: {n}" for n in res.notes]
            + [f"warning: {w}" for w in res.error_summary()["warnings"]])
