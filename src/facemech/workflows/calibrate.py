"""``facemech calibrate``: the anatomical preset's global scales fitted to maximal gestures,
written as a preset file that every ``--preset`` option accepts."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from ..errors import InputError

__all__ = ["calibrate", "parse_gesture", "report"]


def parse_gesture(spec: str) -> tuple[Path, list[str]]:
    """``"FILE:GROUPS"`` (e.g. ``"smile.c3d:ZYG,LAO"``) as the file and its muscle groups."""
    path, sep, groups = spec.rpartition(":")
    if not sep or not path or not groups:
        raise InputError("expected FILE:GROUPS, e.g. smile.c3d:ZYG,LAO", field=spec)
    return Path(path), groups.split(",")


def calibrate(gestures: Sequence[str] | None, output: str | Path, *,
              face: str | Path = "default", builtin: bool = False, fit: str = "force,lips",
              map_file: str | Path | None = None, max_evaluations: int = 30,
              units: str | None = None, name: str | None = None,
              progress: Callable[[str, int, int], None] | None = None):
    """Fit the anatomical preset's global scales and write the preset file ``output``.

    Parameters
    ----------
    gestures : maximal gestures, each "FILE:GROUPS" (a marker file in the model's frame and the
        muscle groups it uses); or None with ``builtin``
    output : preset file (.json), written atomically
    face : the face (file or built-in name)
    builtin : fit the built-in targets (gestures of real faces) instead
    fit : the scales to fit, comma-separated (force, lips, stiffness, sphincter)
    map_file : marker,node CSV (default: the closest nodes)
    max_evaluations : gesture sets simulated at most (at least 2)
    units : length unit of marker files that carry none
    name : the preset's name (default: the file's stem)
    progress : callable(stage, done, total)

    Returns
    -------
    facemech.analysis.calibration.CalibrationResult
    """
    from ..analysis.calibration import check_fit, fit_scales, fit_subject, recorded_gesture
    from ..geometry.builder import load_face
    from ..io.markers import read_markers
    from ..kinematics.mapping import closest_nodes, read_mapping
    from ..params import anatomical, write_preset

    output = Path(output)
    scales = tuple(x.strip() for x in fit.split(",") if x.strip())
    check_fit(scales)
    if max_evaluations < 2:
        raise InputError("max-evaluations must be at least 2", field="max-evaluations")
    if builtin == bool(gestures):
        raise InputError("give gestures (FILE:GROUPS ...) or --builtin", field="gestures")
    if output.suffix.lower() != ".json":
        raise InputError("the preset file must end in .json", source=str(output),
                         field="output")
    from ..atomic import check_output

    specs = [parse_gesture(spec) for spec in gestures or ()]
    check_output(output, [*(path for path, _ in specs), map_file,
                          face if Path(str(face)).suffix else None], field="-o")
    model = load_face(face, tissue=anatomical().tissue)
    step = None if progress is None else (lambda d, n: progress("fit", d, n))
    if builtin:
        res = fit_scales(model, fit=scales, max_evaluations=max_evaluations, progress=step)
        fitted_to = "built-in targets"
    else:
        recs, mapping = [], None
        for path, groups in specs:
            ms = read_markers(path, units=units)
            if mapping is None:
                mapping = (read_mapping(map_file, ms, model) if map_file is not None
                           else closest_nodes(ms, model))
            recs.append(recorded_gesture(ms, groups, name=path.stem))
        res = fit_subject(model, recs, mapping, fit=scales, max_evaluations=max_evaluations,
                          progress=step)
        fitted_to = [r.source for r in recs]
    write_preset(output, name or output.stem, res.scales,
                 extra={"fitted_to": fitted_to, "face": model.name, **res.as_dict()})
    return res


def report(res, output: str | Path, *, builtin: bool = False) -> list[str]:
    """What ``facemech calibrate`` prints: the fitted scales, (built-in) the targets' table,
    and where the preset went."""
    lines = [f"[bold]fitted[/bold] {', '.join(f'{k} {v:.3g}' for k, v in res.scales.items())} "
             f"({res.evaluations} evaluations, cost {res.cost:.4g})"]
    if builtin:
        lines.append(res.table())
    return lines + [f"preset -> {output} (use it as --preset {output})"]
