"""The one jaw drive of every command: the jaw's markers of a recording (model axes, m, one
sample a frame) as a series the simulator takes, with what it is (for the notes).

- a lower-incisor sensor, with or without a molar pellet (points on the bone): sagittal poses
  (frames, 3) = (angle rad, shift_y m, shift_z m)
  (:func:`facemech.solvers.jaw_bone.jaw_poses_from_bone`);
- two mandible markers: their planar rigid motion about the face's hinge, poses (frames, 3)
  (:func:`facemech.solvers.jaw.jaw_poses_from_points`);
- a skin chin marker: its vertical drop, angles (frames,) rad
  (:func:`facemech.solvers.jaw_drive.jaw_angles_from_marker`).

Each is moved ``lead`` frames earlier (the last held): by default 2 (33 ms at 60 Hz, the
skull-to-skin delay) for skin markers, none for bone points.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import InputError
from .inputs import JawMarkers

__all__ = ["SKIN_JAW_LEAD", "default_lead", "jaw_drive"]

#: frames by which a skin jaw marker's drive is moved earlier by default (33 ms at 60 Hz, the
#: seeds' lead); a bone point's drive has none
SKIN_JAW_LEAD = 2


def default_lead(markers: JawMarkers, on_bone: bool) -> int:
    """The drive's lead in frames: the one given, else none on the bone and
    :data:`SKIN_JAW_LEAD` on the skin."""
    if markers.jaw_lead is not None:
        return markers.jaw_lead
    return 0 if on_bone else SKIN_JAW_LEAD


def jaw_drive(points: Mapping[str, np.ndarray], model, markers: JawMarkers, *, lead: int,
              chin_node: int | None = None, source: str | None = None,
              by_role: bool = False) -> tuple[np.ndarray | None, str | None]:
    """The jaw series that the jaw's markers give.

    Parameters
    ----------
    points : marker name -> (frames, 3) positions, m, in the model's axes, one sample a frame
    model : Model -- the face, its parameters and physics (:func:`facemech.physics.model.model`)
    markers : which markers are on the jaw (:class:`~.inputs.JawMarkers`; ``jaw_incisor``:
        the bone's drive; else ``chin_marker`` with or without ``jaw_second_marker``)
    lead : frames by which the series is moved earlier (:func:`default_lead`)
    chin_node : the face's epidermal node under the chin marker (a one-marker drive)
    source, by_role : the recording's name for errors; whether the bone points were found
        by their articulography roles (for the note)

    Returns
    -------
    (jaw, what) : None, (frames,) angles rad or (frames, 3) poses; what drives it (None: none)
    """
    incisor, molar = markers.jaw_incisor, markers.jaw_molar
    chin, second = markers.chin_marker, markers.jaw_second_marker
    if incisor is not None:
        return _from_bone(points, model, (incisor, molar), lead, source, by_role)
    if second is not None:
        from ..solvers.jaw import jaw_poses_from_points

        for name in (chin, second):
            if name not in points:
                raise InputError("jaw marker not in the file", source=source, field=name)
        jaw = jaw_poses_from_points(points[chin], points[second],
                                    hinge_point=model.face.hinge_point, lead=lead,
                                    names=(chin, second), source=source)
        return jaw, f"jaw markers {chin},{second} ({lead}-frame lead)"
    if chin is not None:
        from ..solvers.jaw_drive import jaw_angles_from_marker

        if chin_node is None or chin not in points:
            raise InputError("chin marker has no node (not in the file or not mapped)",
                             source=source, field=chin)
        jaw = jaw_angles_from_marker(model, chin_node, points[chin][:, 1], lead=lead,
                                     source=source)
        return jaw, f"chin marker {chin} ({lead}-frame lead)"
    return None, None


def _from_bone(points, model, names, lead, source, by_role):
    """(poses, what) of the lower incisor and the molar pellet (None: the incisor alone)."""
    from ..solvers.jaw_bone import jaw_poses_from_bone, protrusion_of

    incisor, molar = names
    poses = jaw_poses_from_bone(points[incisor], model.face, model.params,
                                molar=None if molar is None else points[molar],
                                lead=lead, names=(incisor, molar or "molar"), source=source)
    pro = protrusion_of(poses, model.params) * 1e3
    what = (f"the bone point{'s' if molar else ''} {incisor} (lower incisor"
            f"{f') and {molar} (molar' if molar else ''}){' by role' if by_role else ''}: "
            f"angle {np.degrees(poses[:, 0].min()):.1f} to "
            f"{np.degrees(poses[:, 0].max()):.1f} degrees, protrusion {pro.min():.1f} to "
            f"{pro.max():.1f} mm; {lead}-frame lead")
    return poses, what
