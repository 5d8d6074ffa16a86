"""Measures of the visible mouth: lip gap, lip protrusion, mouth width and jaw drop.

The lip gap is the true opening between the lips, not the distance between the landmarks
``upper_lip_center`` and ``lower_lip_center`` (those sit on the front of the vermilion, about
20 mm apart with the lips closed). The built face's mouth slit is a cut: every node of the lip
line has a twin, one in the upper lip and one in the lower lip, coinciding at rest (the lip
contact pairs, ``model.lip_pairs``). The gap is the separation of the midline twins of the
epidermis along their contact normal (upper minus lower, m): 0 at rest and with the lips
pressed together, positive when the lips part (slightly negative where the contact penalty
lets them press into each other).
"""

from __future__ import annotations

import numpy as np


def midline_lip_pair(model) -> tuple[int, int, np.ndarray]:
    """The epidermal lip contact pair nearest the midline of a face.

    Returns
    -------
    (upper node, lower node, contact normal (3,) from the lower to the upper lip)
    """
    up, lo = model.lip_pairs.T
    skin = np.nonzero(up < model.n_surface)[0]
    x_mid = model.rest_positions[model.landmarks["stomion"], 0] \
        if "stomion" in model.landmarks else 0.0
    k = skin[np.argmin(np.abs(model.rest_positions[up[skin], 0] - x_mid))]
    return int(up[k]), int(lo[k]), np.asarray(model.lip_normals[k], float)


def mouth_measures(model, positions: np.ndarray) -> dict[str, np.ndarray]:
    """Lip gap, lip protrusion and mouth width of epidermal positions against rest.

    Parameters
    ----------
    model : FaceModel
        The face the positions are of (``sim.model`` of a simulation).
    positions : (frames, n_surface, 3) or (n_surface, 3) array, m

    Returns
    -------
    dict of (frames,) arrays (floats for one frame), m
        ``lip_gap``: the midline opening between the lips (module doc);
        ``upper_forward``, ``lower_forward``: +z displacement of the landmarks
        ``upper_lip_center`` and ``lower_lip_center`` from rest;
        ``lips_forward``: the smaller of the two;
        ``width_change``: corner-to-corner distance (``mouth_corner_left`` to
        ``mouth_corner_right``) minus its rest value (positive: wider).
    """
    p = np.asarray(positions, float)
    single = p.ndim == 2
    if single:
        p = p[None]
    rest = model.rest_positions[: model.n_surface]
    lm = model.landmarks
    u, lo, normal = midline_lip_pair(model)
    gap = (p[:, u] - p[:, lo]) @ normal - (rest[u] - rest[lo]) @ normal
    upper = p[:, lm["upper_lip_center"], 2] - rest[lm["upper_lip_center"], 2]
    lower = p[:, lm["lower_lip_center"], 2] - rest[lm["lower_lip_center"], 2]
    cl, cr = lm["mouth_corner_left"], lm["mouth_corner_right"]
    width = np.linalg.norm(p[:, cl] - p[:, cr], axis=1) - np.linalg.norm(rest[cl] - rest[cr])
    out = {"lip_gap": gap, "upper_forward": upper, "lower_forward": lower,
           "lips_forward": np.minimum(upper, lower), "width_change": width}
    if single:
        return {k: float(v[0]) for k, v in out.items()}
    return out


def incisor_drop(model, jaw_pose) -> np.ndarray:
    """How far (m) the lower incisor tip drops for jaw poses (angle rad, shift_y m, shift_z m).

    ``jaw_pose`` : (3,) or (frames, 3); returns a float or (frames,) of downward displacement of
    :func:`facemech.geometry.teeth.lower_incisor_point`.
    """
    from ..geometry.teeth import lower_incisor_point
    from ..solvers.jaw import move_points

    poses = np.atleast_2d(np.asarray(jaw_pose, float))
    tip = lower_incisor_point(model)
    drop = np.array([tip[1] - move_points(tip, p, model.hinge_point, model.hinge_axis)[0, 1]
                     for p in poses])
    return float(drop[0]) if np.ndim(jaw_pose) == 1 else drop


#: m: the lips count as apart where their contact twins are this far from each other (the
#: bilabials' seal, :data:`facemech.speech.visible_speech.CRITERIA`)
APART_M = 0.5e-3


def opening_width(model, positions: np.ndarray, apart: float = APART_M) -> np.ndarray:
    """Width (m) of the opening between the lips as seen from the front: the extent across the
    face (x, where the twins are now: the midpoint of each pair) of the lip contact pairs of
    the epidermis that are more than ``apart`` apart along their contact normals, the ends
    interpolated to where the separation crosses ``apart``; 0 with the lips sealed. A mouth
    narrowed by rounding gives the narrowed width, not the rest width.

    ``positions`` : (frames, n_surface, 3) or (n_surface, 3) m; returns (frames,) or a float.
    """
    p = np.asarray(positions, float)
    single = p.ndim == 2
    if single:
        p = p[None]
    up, lo = model.lip_pairs.T
    skin = np.nonzero(up < model.n_surface)[0]
    rest = model.rest_positions
    skin = skin[np.argsort(rest[up[skin], 0])]  # along the lip line, right to left
    normals = np.asarray(model.lip_normals, float)[skin]
    sep = np.einsum("fkj,kj->fk", p[:, up[skin]] - p[:, lo[skin]], normals) - \
        np.einsum("kj,kj->k", rest[up[skin]] - rest[lo[skin]], normals)
    across = 0.5 * (p[:, up[skin], 0] + p[:, lo[skin], 0])  # (frames, pairs) x now
    out = np.zeros(len(p))
    for f, s in enumerate(sep):
        x = across[f]
        k = np.nonzero(s > apart)[0]
        if k.size == 0:
            continue
        a, b = k[0], k[-1]
        xa, xb = x[a], x[b]
        if a > 0:  # where the separation crosses ``apart`` between a - 1 and a
            xa = x[a - 1] + (x[a] - x[a - 1]) * (apart - s[a - 1]) / (s[a] - s[a - 1])
        if b < len(x) - 1:
            xb = x[b] + (x[b + 1] - x[b]) * (s[b] - apart) / (s[b] - s[b + 1])
        out[f] = xb - xa
    return float(out[0]) if single else out
