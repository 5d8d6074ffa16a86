"""The mandible's planar rigid motion: numba kernels shared by the stepper and the jaw drives.

A jaw pose is (angle rad, shift_y m, shift_z m): the mandible turns by ``angle`` about the hinge
axis through the hinge point (the condyles; positive opens the mouth) and the hinge itself moves
by (0, shift_y, shift_z) in the sagittal plane (the condyle's glide along the articular
eminence). A point of jaw weight ``w`` (1 on the mandible, blending to 0 on the fixed skull)
moves to::

    p = hinge + R(w angle) (p0 - hinge) + w (0, shift_y, shift_z)

and, with the pose changing at rates (angle', shift_y', shift_z'), moves at::

    v = w angle' axis x R(w angle) (p0 - hinge) + w (0, shift_y', shift_z')

Normals turn with R(w angle) only. The kernels write into arrays given to them: nothing is
allocated per call beyond a 3 x 3 rotation.
"""

from __future__ import annotations

import numba as nb
import numpy as np


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
def move_anchors(angle, shift_y, shift_z, hinge_point, hinge_axis, weight, rest0, normal0,
                 rest, normal):
    """Points and normals (k, 3) moved by the jaw pose, each by its weight, into ``rest`` and
    ``normal`` (in place)."""
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


@nb.njit(cache=True)
def place_jaw(pos, vel, angle, shift_y, shift_z, rate, rate_y, rate_z, hinge_point, hinge_axis,
              jaw_nodes, jaw_weights, jaw_rest, tied_weight, tied_rest0, tied_normal0, tied_rest,
              tied_normal):
    """Put the mandible in the pose (angle, shift_y, shift_z) moving at (rate, rate_y, rate_z)
    (rad/s, m/s), in place.

    Sets the positions and velocities of the jaw's skull nodes (``jaw_rest``: their rest
    positions less the hinge point), and the moved anchors and normals of the tied nodes
    (``tied_*``: the rest positions and skull normals under the seeds' tied fascia, the bone
    under the continuum's sliding nodes), each by its own jaw weight.
    """
    ax, ay, az = hinge_axis[0], hinge_axis[1], hinge_axis[2]
    r = np.empty((3, 3))
    last = np.nan
    for k in range(jaw_nodes.shape[0]):
        i = jaw_nodes[k]
        w = jaw_weights[k]
        if w != last:
            rotation_into(w * angle, ax, ay, az, r)
            last = w
        dx = r[0, 0] * jaw_rest[k, 0] + r[0, 1] * jaw_rest[k, 1] + r[0, 2] * jaw_rest[k, 2]
        dy = r[1, 0] * jaw_rest[k, 0] + r[1, 1] * jaw_rest[k, 1] + r[1, 2] * jaw_rest[k, 2]
        dz = r[2, 0] * jaw_rest[k, 0] + r[2, 1] * jaw_rest[k, 1] + r[2, 2] * jaw_rest[k, 2]
        pos[i, 0] = hinge_point[0] + dx
        pos[i, 1] = hinge_point[1] + dy + w * shift_y
        pos[i, 2] = hinge_point[2] + dz + w * shift_z
        wr = w * rate
        vel[i, 0] = wr * (ay * dz - az * dy)
        vel[i, 1] = wr * (az * dx - ax * dz) + w * rate_y
        vel[i, 2] = wr * (ax * dy - ay * dx) + w * rate_z
    move_anchors(angle, shift_y, shift_z, hinge_point, hinge_axis, tied_weight, tied_rest0,
                 tied_normal0, tied_rest, tied_normal)
