"""The mandible's planar rigid motion: numba kernels shared by the stepper and the jaw drives.

A jaw pose is (angle rad, shift_y m, shift_z m): the mandible turns by ``angle`` about the hinge
axis through the hinge point (the condyles; positive opens the mouth) and the hinge itself moves
by (0, shift_y, shift_z) in the sagittal plane (the condyle's glide along the articular
eminence: the glide coupled to the opening, and any free protrusion or retraction,
:mod:`.jaw_bone`). A point of jaw weight ``w`` (1 on the mandible, blending to 0 on the fixed skull)
moves to::

    p = hinge + R(w angle) (p0 - hinge) + w (0, shift_y, shift_z)

and, with the pose changing at rates (angle', shift_y', shift_z'), moves at::

    v = w angle' axis x R(w angle) (p0 - hinge) + w (0, shift_y', shift_z')

Normals turn with R(w angle) only. The kernels are pure: they return new arrays (the jaw
nodes' positions and velocities, the moved anchors) and the caller writes them where it owns
its working arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from ..physics.bundles import Anchors


class JawBundle(NamedTuple):
    """What the mandible carries: its skull nodes and the anchors of the tied nodes.

    Attributes
    ----------
    hinge_point : (3,) m -- a point of the hinge axis (the condyles) at rest
    hinge_axis : (3,) -- unit vector of the hinge axis (positive angles open the mouth)
    nodes : (k,) int64 -- the jaw's skull nodes
    weights : (k,) -- share of the pose of each (1 on the mandible, blending to 0)
    rest_from_hinge : (k, 3) m -- their rest positions less ``hinge_point``
    anchor_weights : (t,) -- share of the pose of each tied node's anchor
    anchor_rest : (t, 3) m -- the anchors with the jaw closed
    anchor_normal : (t, 3) -- the bone's outward unit normals there, jaw closed
    """

    hinge_point: np.ndarray
    hinge_axis: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    rest_from_hinge: np.ndarray
    anchor_weights: np.ndarray
    anchor_rest: np.ndarray
    anchor_normal: np.ndarray


@nb.njit(cache=True)
def rotation_into(angle, ax, ay, az, r):
    """Rotation matrix by ``angle`` (rad) about the unit axis (ax, ay, az), into ``r`` (3, 3)."""
    c = np.cos(angle)
    s = np.sin(angle)
    t = 1.0 - c
    r[0, 0] = c + ax * ax * t
    r[0, 1] = ax * ay * t - az * s
    r[0, 2] = ax * az * t + ay * s
    r[1, 0] = ay * ax * t + az * s
    r[1, 1] = c + ay * ay * t
    r[1, 2] = ay * az * t - ax * s
    r[2, 0] = az * ax * t - ay * s
    r[2, 1] = az * ay * t + ax * s
    r[2, 2] = c + az * az * t


@nb.njit(cache=True)
def moved_anchors(pose, hinge_point, hinge_axis, weight, rest0, normal0):
    """Points and normals (k, 3) moved by the jaw ``pose`` (3,) (angle rad, shift_y m,
    shift_z m), each by its ``weight`` (k,): new arrays ``(points, normals)``."""
    angle, shift_y, shift_z = pose[0], pose[1], pose[2]
    rest = np.empty_like(rest0)
    normal = np.empty_like(normal0)
    r = np.empty((3, 3))
    last = np.nan
    for k in range(rest0.shape[0]):
        w = weight[k]
        if w == 0.0:
            for a in range(3):
                rest[k, a] = rest0[k, a]
                normal[k, a] = normal0[k, a]
            continue
        if w != last:
            rotation_into(w * angle, hinge_axis[0], hinge_axis[1], hinge_axis[2], r)
            last = w
        for a in range(3):
            rest[k, a] = hinge_point[a]
            normal[k, a] = 0.0
            for b in range(3):
                rest[k, a] += r[a, b] * (rest0[k, b] - hinge_point[b])
                normal[k, a] += r[a, b] * normal0[k, b]
        rest[k, 1] += w * shift_y
        rest[k, 2] += w * shift_z
    return rest, normal


@nb.njit(cache=True)
def place_jaw(jaw, pose, rate):
    """The mandible in ``pose`` (3,) (angle rad, shift_y m, shift_z m), moving at ``rate`` (3,)
    (rad/s, m/s, m/s).

    Parameters
    ----------
    jaw : JawBundle
    pose, rate : (3,) arrays

    Returns
    -------
    positions : (k, 3) m -- of the jaw's skull nodes ``jaw.nodes``
    velocities : (k, 3) m/s -- of the same nodes
    anchors : Anchors -- the tied nodes' anchors and the bone's normals there, each moved by its
        own jaw weight

    New arrays; write the first two into a working state with :func:`set_jaw_nodes`.
    """
    hinge_point = jaw.hinge_point
    ax, ay, az = jaw.hinge_axis[0], jaw.hinge_axis[1], jaw.hinge_axis[2]
    angle, shift_y, shift_z = pose[0], pose[1], pose[2]
    jaw_rest = jaw.rest_from_hinge
    n = jaw.nodes.shape[0]
    pos = np.empty((n, 3))
    vel = np.empty((n, 3))
    r = np.empty((3, 3))
    last = np.nan
    for k in range(n):
        w = jaw.weights[k]
        if w != last:
            rotation_into(w * angle, ax, ay, az, r)
            last = w
        dx = r[0, 0] * jaw_rest[k, 0] + r[0, 1] * jaw_rest[k, 1] + r[0, 2] * jaw_rest[k, 2]
        dy = r[1, 0] * jaw_rest[k, 0] + r[1, 1] * jaw_rest[k, 1] + r[1, 2] * jaw_rest[k, 2]
        dz = r[2, 0] * jaw_rest[k, 0] + r[2, 1] * jaw_rest[k, 1] + r[2, 2] * jaw_rest[k, 2]
        pos[k, 0] = hinge_point[0] + dx
        pos[k, 1] = hinge_point[1] + dy + w * shift_y
        pos[k, 2] = hinge_point[2] + dz + w * shift_z
        wr = w * rate[0]
        vel[k, 0] = wr * (ay * dz - az * dy)
        vel[k, 1] = wr * (az * dx - ax * dz) + w * rate[1]
        vel[k, 2] = wr * (ax * dy - ay * dx) + w * rate[2]
    rest, normal = moved_anchors(pose, hinge_point, jaw.hinge_axis, jaw.anchor_weights,
                                 jaw.anchor_rest, jaw.anchor_normal)
    return pos, vel, Anchors(rest, normal)


@nb.njit(cache=True)
def set_jaw_nodes(jaw, jaw_pos, jaw_vel, pos, vel):
    """Write the jaw nodes' positions and velocities (k, 3) from :func:`place_jaw` into the
    working arrays ``pos`` and ``vel`` (nodes, 3), which the caller owns."""
    nodes = jaw.nodes
    for k in range(nodes.shape[0]):
        i = nodes[k]
        for a in range(3):
            pos[i, a] = jaw_pos[k, a]
            vel[i, a] = jaw_vel[k, a]


def jaw_bundle(physics) -> JawBundle:
    """The :class:`JawBundle` of a :class:`~facemech.physics.assembly.Physics` (new arrays)."""
    model = physics.model
    rest = model.rest_positions
    hinge = np.asarray(model.hinge_point, float)
    return JawBundle(
        hinge_point=hinge, hinge_axis=np.asarray(model.hinge_axis, float),
        nodes=physics.jaw_nodes, weights=physics.jaw_weights,
        rest_from_hinge=rest[physics.jaw_nodes] - model.hinge_point,
        anchor_weights=physics.tied_weight,
        anchor_rest=rest[physics.forces.restoration.nodes].copy(),
        anchor_normal=model.skull_normals[physics.forces.restoration.skull].copy())
