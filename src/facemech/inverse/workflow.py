"""Inversion of a marker file, as the ``invert`` command runs it: read, map, adapt, drive the
jaw, invert. Kept apart from the command line so that scripts run the same steps."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..errors import InputError
from .result import Inversion

__all__ = ["invert_markers"]


def invert_markers(
    markers: str | Path,
    *,
    face: str | Path = "default",
    map_file: str | Path | None = None,
    units: str | None = None,
    scale_pair: str | None = None,
    preset: str = "anatomical",
    jaw_kinematics: str | None = None,
    method: str = "lsq",
    positive: bool = True,
    controls: str = "speech",
    chin_marker: str | None = None,
    jaw_second_marker: str | None = None,
    jaw_fixed: bool = False,
    jaw_lead: int = 2,
    noise: float | None = None,
    dt: float | None = None,
    options: dict | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Inversion:
    """Invert a marker file on a face (see :func:`facemech.inverse.invert.invert`).

    Parameters
    ----------
    markers : marker file in the model's frame, at the preset's frame rate
    face : face file or built-in face name
    map_file : marker,node CSV (default: the closest nodes)
    units : length unit of a marker file that carries none
    scale_pair : "A,B": adapt the markers by per-axis scaling from two markers far apart
    preset : the parameter preset; ``jaw_kinematics`` ("hinge" or "glide") overrides its
    method, positive : "lsq" or "powell"; activity kept >= 0
    controls : "speech", "emg7", "all" or comma-separated groups
    chin_marker : a jaw recording: its vertical drop gives the jaw angle, ``jaw_lead`` frames
        early, estimated further with the muscles unless ``jaw_fixed``
    jaw_second_marker : a second point on the mandible: the two markers' planar rigid motion
        drives the jaw's three degrees of freedom, held as given
    noise : marker noise for the standard errors, mm (None: from the residuals)
    dt : explicit Euler step of every evaluation, s (None: the preset's fast step)
    options : the method's options (None: not given; an option of the other method is an
        error)
    progress : callable(done, total)

    Returns
    -------
    Inversion
    """
    from .. import params as P
    from ..geometry.builder import load_face
    from ..io.markers import read_markers
    from ..kinematics.mapping import closest_nodes, read_mapping, scale_adapt
    from ..solvers.jaw import jaw_angles_from_marker, jaw_poses_from_points
    from .invert import invert
    from .methods import method_from_options

    src = str(markers)
    solver = method_from_options(method, **(options or {}))
    if jaw_second_marker is not None and chin_marker is None:
        raise InputError("--jaw-second-marker needs --chin-marker (the first jaw marker)",
                         field="jaw-second-marker")
    if jaw_fixed and chin_marker is None:
        raise InputError("--jaw-fixed needs a jaw recording (--chin-marker)", field="jaw-fixed")
    if jaw_lead < 0:
        raise InputError(f"jaw lead must be >= 0 frames (got {jaw_lead})", field="jaw-lead")
    prm = P.preset(preset)
    if jaw_kinematics is not None:
        prm = prm.with_(jaw_kinematics=jaw_kinematics)
    model = load_face(face, tissue=prm.tissue)
    ms = read_markers(markers, units=units)
    mapping = (read_mapping(map_file, ms, model) if map_file is not None
               else closest_nodes(ms, model))
    if scale_pair is not None:
        a, _, b = scale_pair.partition(",")
        ms = scale_adapt(ms, model, mapping, (a.strip(), b.strip())).markers
    jaw = None
    if jaw_second_marker is not None:
        for name in (chin_marker, jaw_second_marker):
            if name not in ms.names:
                raise InputError("jaw marker not in the file", source=src, field=name)
        jaw = jaw_poses_from_points(ms.marker(chin_marker), ms.marker(jaw_second_marker),
                                    hinge_point=model.hinge_point, lead=jaw_lead,
                                    names=(chin_marker, jaw_second_marker), source=src)
        jaw_fixed = True
    elif chin_marker is not None:
        node = mapping.get(chin_marker)
        if node is None:
            raise InputError("chin marker has no node (not in the file or not mapped)",
                             source=src, field=chin_marker)
        jaw = jaw_angles_from_marker(model, prm, node, ms.marker(chin_marker)[:, 1],
                                     lead=jaw_lead, source=src)
    ctrl = controls if controls in ("speech", "emg7", "all") else [
        c.strip().upper() for c in controls.split(",") if c.strip()]
    return invert(model, ms, mapping, method=solver, positive=positive, controls=ctrl,
                  jaw_angle=jaw, estimate_jaw=None if jaw is None else not jaw_fixed,
                  jaw_source=None if chin_marker is None else
                  f"{'jaw markers' if jaw_second_marker else 'chin marker'} {chin_marker}"
                  f"{',' + jaw_second_marker if jaw_second_marker else ''} "
                  f"({jaw_lead}-frame lead)",
                  params=prm, dt=dt, noise_mm=noise, progress=progress)
