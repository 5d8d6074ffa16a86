"""The jaw: which skull-layer nodes turn with the mandible, how much, and about which axis.

``uniform`` (the seeds')
    the skull nodes below the lip line and below the line from each mouth corner to the jaw
    angle turn fully with the mandible (weight 1); the rest are fixed.
``anatomical``
    a weight from 0 to 1 per node (:func:`tissue.jaw_weight`): 1 below the lip line between the
    mouth corners, blending to the fixed skull across a band lateral to the corners
    (``jaw_band``, widening over ``jaw_taper``). Sliding nodes are not kinematic: they take the
    weight of the bone under them instead (``FaceModel.sliding_weights``).

The hinge axis is parallel to x, at the height of the nasal base (halfway between nose tip and
subnasale) and ``hinge_behind_jaw_angle`` (25 mm) behind the skin jaw-angle landmarks: the
condyles lie about 10-12 mm in front of the tragus, near its height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import tissue
from .kinds import SKULL, layer_nodes
from .mouth import LOWER_LIP, LipLine, MouthCut
from .options import BuildOptions

#: a jaw weight above this makes a skull node kinematic with the mandible
JAW_WEIGHT_MIN = 1e-6


@dataclass(frozen=True)
class JawAttachment:
    """The skull nodes the mandible carries, and its hinge.

    Parameters
    ----------
    bone_weight : (n,) array in [0, 1]
        Share of the jaw's rotation of the bone under every epidermal node.
    nodes : (k,) int array
        Skull nodes that turn with the mandible (kinematic).
    weights : (k,) array in (0, 1]
        Their share of the jaw's rotation.
    hinge_point : (3,) array, metres
        A point on the hinge axis.
    hinge_axis : (3,) unit array
        +x: positive angles open the mouth.
    """

    bone_weight: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    hinge_point: np.ndarray
    hinge_axis: np.ndarray


def jaw_line_y(x: float, line: LipLine, landmarks: dict[str, np.ndarray]) -> float:
    """Height (m) of the jaw's edge at ``x`` (m): the lip line, then corner to jaw angle."""
    cr, cl = line.corner_right, line.corner_left
    if cr[0] <= x <= cl[0]:
        return line.y(x)
    c, g = ((cl, landmarks["jaw_angle_left"]) if x > cl[0]
            else (cr, landmarks["jaw_angle_right"]))
    t = np.clip((x - c[0]) / (g[0] - c[0]) if g[0] != c[0] else 1.0, 0.0, 1.0)
    return float(c[1] + t * (g[1] - c[1]))


def uniform_bone_weight(mouth: MouthCut, landmarks: dict[str, np.ndarray]) -> np.ndarray:
    """The seeds' jaw: 1 below the jaw line (the cut's lower twins included), else 0; (n,)."""
    v = mouth.vertices
    below_line = v[:, 1] < np.array([jaw_line_y(x, mouth.line, landmarks) for x in v[:, 0]])
    below_line[mouth.pairs[:, 1]] = True
    below_line[mouth.pairs[:, 0]] = False
    return below_line.astype(float)


def anatomical_bone_weight(side: np.ndarray, generic_xy: np.ndarray,
                           opt: BuildOptions) -> np.ndarray:
    """The anatomical jaw weight (n,) of every node (generic frontal ``generic_xy``, mm)."""
    return tissue.jaw_weight(generic_xy[:, 0], generic_xy[:, 1], side == LOWER_LIP,
                             band_mm=opt.jaw_band * 1e3, taper_mm=opt.jaw_taper * 1e3)


def hinge(landmarks: dict[str, np.ndarray], behind_jaw_angle: float) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """The jaw's hinge: a point (3,) m on the axis, and the unit axis (3,) (+x)."""
    jaw_angle = 0.5 * (landmarks["jaw_angle_left"] + landmarks["jaw_angle_right"])
    hinge_y = 0.5 * (landmarks["nose_tip"][1] + landmarks["subnasale"][1])  # the nasal base
    return (np.array([0.0, hinge_y, jaw_angle[2] - behind_jaw_angle]),
            np.array([1.0, 0.0, 0.0]))


def attach_jaw(bone_weight: np.ndarray, slides: np.ndarray, landmarks: dict[str, np.ndarray],
               opt: BuildOptions) -> JawAttachment:
    """The kinematic jaw nodes of a bone weight (n,); the sliding nodes ``slides`` are left out."""
    on_jaw = np.nonzero((bone_weight > JAW_WEIGHT_MIN) & ~slides)[0]
    hinge_point, hinge_axis = hinge(landmarks, opt.hinge_behind_jaw_angle)
    return JawAttachment(bone_weight=bone_weight,
                         nodes=layer_nodes(on_jaw, SKULL, len(bone_weight)),
                         weights=bone_weight[on_jaw], hinge_point=hinge_point,
                         hinge_axis=hinge_axis)


def rotation_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def rotate_about(points: np.ndarray, point: np.ndarray, axis: np.ndarray,
                 angle: float) -> np.ndarray:
    """Points (..., 3) rotated by ``angle`` about the line through ``point`` along ``axis``."""
    r = rotation_matrix(axis, angle)
    return (np.asarray(points) - point) @ r.T + point
