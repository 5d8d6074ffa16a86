"""The jaw from points on the bone: a lower-incisor sensor, alone or with a molar pellet.

An articulograph's jaw sensor sits on the lower incisors and moves exactly as the mandible does
(a chin marker slides over the bone). The pose (angle, shift_y, shift_z) splits the shift into
the glide coupled to the opening (:func:`~facemech.solvers.jaw.condyle_glide`) and a free
protrusion along the same eminence path (Ostry, Vatikiotis-Bateson & Gribble 1997)::

    travel = glide_rate * max(angle, 0) + protrusion          (m, along the eminence)
    shift  = travel * (-sin glide_slope, cos glide_slope)     (y, z)

One bone point gives the angle and the protrusion in closed form
(:func:`jaw_poses_from_incisor`); two points give the planar rigid motion
(:func:`jaw_poses_from_bone`). The recording's first frame is the jaw's rest and its incisor is
laid on the model's (:func:`~facemech.geometry.teeth.lower_incisor_point`); no lead is applied.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..geometry.teeth import lower_incisor_point
from .jaw import (
    MAX_JAW_ANGLE,
    MAX_JAW_SHIFT,
    _lead,
    checked_trajectory,
    jaw_poses_from_points,
)

__all__ = ["MAX_BONE_STRETCH", "bone_stretch", "eminence_direction", "glide_rate_of",
           "jaw_poses_from_bone", "jaw_poses_from_incisor", "poses_with_protrusion",
           "protrusion_of"]

#: m, the most the sagittal distance between two bone points may change over a recording
#: before they are taken as not on one rigid bone (EMA coils are placed and tracked to about
#: 0.5-1 mm; a molar pellet mistracked or on the maxilla changes it by far more)
MAX_BONE_STRETCH = 0.003


def eminence_direction(params) -> np.ndarray:
    """Unit (y, z) direction of the condyles' path, ``params.glide_slope`` below the
    horizontal, forward: (-sin slope, cos slope)."""
    s = float(params.glide_slope)
    return np.array([-np.sin(s), np.cos(s)])


def glide_rate_of(params) -> float:
    """m/rad of the coupled glide: the preset's ``glide_rate`` under ``"glide"``, 0 for the
    hinge."""
    return float(params.glide_rate) if params.jaw_kinematics == "glide" else 0.0


def poses_with_protrusion(angles, protrusion, params) -> np.ndarray:
    """Jaw poses (..., 3) (angle rad, shift_y m, shift_z m) of angles (rad) and protrusions
    (m, the condyles' travel along the eminence beyond the coupled glide; > 0 forward), shapes
    broadcast."""
    a, p = np.broadcast_arrays(np.asarray(angles, float), np.asarray(protrusion, float))
    travel = glide_rate_of(params) * np.maximum(a, 0.0) + p
    e = eminence_direction(params)
    return np.stack([a, travel * e[0], travel * e[1]], axis=-1)


def protrusion_of(poses, params) -> np.ndarray:
    """The protrusion (m, (...,)) of jaw poses (..., 3): the shift's component along the
    eminence less the glide coupled to the angle (the inverse of
    :func:`poses_with_protrusion` for its poses)."""
    poses = np.asarray(poses, float)
    e = eminence_direction(params)
    along = poses[..., 1] * e[0] + poses[..., 2] * e[1]
    return along - glide_rate_of(params) * np.maximum(poses[..., 0], 0.0)


def _trajectory(p, name, source) -> np.ndarray:
    """A bone point's (frames, 3) trajectory, checked: no gaps."""
    return checked_trajectory(p, name, source,
                              hint=": fill it first (facemech markers fill-gaps)")


def _sagittal_axis(model) -> None:
    if not np.allclose(np.asarray(model.hinge_axis, float), [1.0, 0.0, 0.0], atol=1e-9):
        raise ValueError("the bone-point drive needs the face's hinge axis along +x")


def jaw_poses_from_incisor(incisor, model, params, *, lead: int = 0, bite_block: bool = False,
                           name: str = "lower incisor", source: str | None = None) -> np.ndarray:
    """Jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) from a lower-incisor sensor.

    Each frame's angle and protrusion are the ones that move the model's lower incisor tip
    (:func:`~facemech.geometry.teeth.lower_incisor_point`) by the sensor's sagittal displacement
    from its first sample, with the preset's coupled glide (see the module doc). Write the tip
    relative to the hinge h as r0, the eminence direction e and its normal n = (cos s, sin s)
    (y, z). The glide and the protrusion move the tip along e only, so the angle solves
    ``n . R(angle) r0 = n . (target - h)``, that is ``rho cos(angle - phi) = k``, of which the
    root nearer 0 is taken; the protrusion is then ``e . (target - h - R(angle) r0)`` less
    the coupled glide. Exact to rounding: the kernel of the stepper puts the tip on the target.

    Parameters
    ----------
    incisor : (frames, 3) m, the sensor in model axes (+y up, +z forward); x is not used
    model : FaceModel (its hinge and its lower incisor)
    params : Parameters: ``jaw_kinematics``, ``glide_rate``, ``glide_slope``
    lead : samples by which the poses are moved earlier (the last held); 0: none (a bone point)
    bite_block : hold the first pose throughout
    name, source : the sensor's name and its file, for messages

    Returns
    -------
    (frames, 3) poses; the first is (0, 0, 0)

    Raises
    ------
    InputError
        For a gap, or a displacement the jaw cannot make (beyond 30 degrees of opening or a
        20-mm shift of the condyles), naming the sensor.
    """
    _sagittal_axis(model)
    p = _trajectory(incisor, name, source)
    h = np.asarray(model.hinge_point, float)[1:]
    tip = lower_incisor_point(model)[1:]
    r0 = tip - h
    target = tip + (p[:, 1:] - p[0, 1:])  # (frames, 2) y, z
    e = eminence_direction(params)
    n = np.array([e[1], -e[0]])
    # n . R(a) r0 = C cos a + S sin a, with R(a) (y, z) = (y c - z s, y s + z c)
    big_c = n @ r0
    big_s = n[0] * (-r0[1]) + n[1] * r0[0]
    rho, phi = np.hypot(big_c, big_s), np.arctan2(big_s, big_c)
    k = (target - h) @ n
    ratio = k / rho
    if np.any(np.abs(ratio) > 1.0):
        f = int(np.argmax(np.abs(ratio) > 1.0))
        raise InputError(f"sample {f}: no jaw pose moves the incisor by "
                         f"{np.linalg.norm(target[f] - tip) * 1e3:.1f} mm", source=source,
                         field=name)
    delta = np.arccos(ratio)
    roots = np.stack([phi + delta, phi - delta])
    roots = (roots + np.pi) % (2 * np.pi) - np.pi
    angle = roots[np.argmin(np.abs(roots), axis=0), np.arange(len(p))]
    c, s = np.cos(angle), np.sin(angle)
    turned = np.stack([r0[0] * c - r0[1] * s, r0[0] * s + r0[1] * c], axis=-1)
    protrusion = (target - h - turned) @ e - glide_rate_of(params) * np.maximum(angle, 0.0)
    poses = poses_with_protrusion(angle, protrusion, params)
    _check_range(poses, name, source)
    poses = _lead(poses, lead)
    if bite_block:
        poses = np.repeat(poses[:1], len(poses), axis=0)
    return poses


def _check_range(poses, name, source) -> None:
    too_far = ((np.abs(poses[:, 0]) > MAX_JAW_ANGLE)
               | (np.hypot(poses[:, 1], poses[:, 2]) > MAX_JAW_SHIFT))
    if too_far.any():
        f = int(np.argmax(too_far))
        raise InputError(f"sample {f}: {name} needs a jaw angle of "
                         f"{np.degrees(poses[f, 0]):.1f} degrees and a condyle shift of "
                         f"{np.hypot(*poses[f, 1:]) * 1e3:.1f} mm, beyond the jaw's range "
                         f"({np.degrees(MAX_JAW_ANGLE):.0f} degrees, "
                         f"{MAX_JAW_SHIFT * 1e3:.0f} mm)", source=source, field=name)


def bone_stretch(incisor, molar) -> float:
    """The largest change (m) of the sagittal (y, z) distance between two points over a
    recording, from its first sample: 0 for two points on one rigid bone."""
    d = np.hypot(*(np.asarray(incisor, float)[:, 1:] - np.asarray(molar, float)[:, 1:]).T)
    return float(np.max(np.abs(d - d[0])))


def jaw_poses_from_bone(incisor, model, params, *, molar=None, lead: int = 0,
                        bite_block: bool = False,
                        names: tuple[str, str] = ("lower incisor", "molar"),
                        source: str | None = None) -> np.ndarray:
    """Jaw poses (frames, 3) (angle rad, shift_y m, shift_z m) from bone points.

    The lower incisor alone gives the angle and the protrusion, the glide coupled to the angle
    (:func:`jaw_poses_from_incisor`). With a ``molar`` pellet as well, the pair's planar rigid
    motion gives all three degrees of freedom (:func:`~facemech.solvers.jaw.
    jaw_poses_from_points`), the recording moved so that the incisor's first sample lies on the
    model's lower incisor tip (the molar keeps its place relative to the incisor).

    Parameters
    ----------
    incisor, molar : (frames, 3) m, model axes; molar optional
    model, params : the face and the preset (see :func:`jaw_poses_from_incisor`)
    lead, bite_block : as :func:`jaw_poses_from_incisor` (default no lead: bone points)
    names : the two points' names, for messages
    source : their file, for messages

    Raises
    ------
    InputError
        For a gap, a pose beyond the jaw's range, points under 10 mm apart, or points whose
        distance changes by more than :data:`MAX_BONE_STRETCH` (not on one bone), naming the
        point.
    """
    if molar is None:
        return jaw_poses_from_incisor(incisor, model, params, lead=lead,
                                      bite_block=bite_block, name=names[0], source=source)
    _sagittal_axis(model)
    inc = _trajectory(incisor, names[0], source)
    mol = _trajectory(molar, names[1], source)
    if len(inc) != len(mol):
        raise InputError(f"the bone points have {len(inc)} and {len(mol)} samples",
                         source=source, field=names[1])
    stretch = bone_stretch(inc, mol)
    if stretch > MAX_BONE_STRETCH:
        raise InputError(f"{names[0]} and {names[1]} change their distance by "
                         f"{stretch * 1e3:.1f} mm (at most {MAX_BONE_STRETCH * 1e3:.0f} mm for "
                         "two points on the mandible)", source=source, field=names[1])
    offset = lower_incisor_point(model) - inc[0]
    return jaw_poses_from_points(inc + offset, mol + offset, hinge_point=model.hinge_point,
                                 lead=lead, bite_block=bite_block, names=names, source=source)
