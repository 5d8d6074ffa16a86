"""Auricles with relief: helix, scapha, antihelix, concha, tragus and lobe.

Each ear is a sheet 62 mm tall and 32 mm wide (adult means, Farkas), seen from both sides,
spanned between its root (attached along a vertical line on the head, sunk 1.5 mm into it) and
its rim (the helix's outline, an oval that narrows into the lobe). Over that sheet a relief in
millimetres off the head (:func:`relief`) gives:

* the flare: 0 at the root to 16 mm at the rim (the ear stands off the head behind it),
  growing out of the head at the helix's root and the lobe's front (no gap between ear and
  head seen from the front);
* the helix: a 2.5-mm roll along the rim, curled forward;
* the scapha: a 1.5-mm groove inside the helix, in the upper two-thirds;
* the antihelix: a 3-mm ridge inside the scapha, from the upper crus down to the antitragus;
* the concha: the bowl in front of the antihelix, its floor 1 mm off the head;
* the tragus: a 4-mm flap in front of the concha;
* the lobe: the lower fifth, without cartilage: no relief, less flare.

The ear's front (its root) lies 95 mm behind the nasion, its top at the brow (8 mm above the
nasion).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from . import textures as T
from .mesh import Part, grid_faces

HEIGHT, WIDTH = 0.062, 0.032  #: m
BEHIND_NASION = 0.095  #: m from the nasion back to the ear's root
TOP_ABOVE_NASION = 0.008  #: m
N_S, N_T = 12, 36  #: samples root -> rim and round the rim
STAND_OFF = 17.0  #: mm, the rim's largest distance from the head (at Y = :data:`WIDEST_Y`)
WIDEST_Y = 12.0  #: mm above the ear's root's middle: the rim stands off furthest here
ARC_UP, ARC_DOWN = 21.0, 44.0  #: mm, the semi-axes of the stand-off's arcs above and below
T_TOP = 0.16  #: the rim's top (psi = 90 degrees in :func:`outline`)
WIDEST = 0.25  #: rad, the outline's widest (most posterior) point this far above its middle


def _bump(x):
    return np.exp(-0.5 * x * x)


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def outline(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rim (X back, Y up) mm of the ear from its top front (t=0) round the back to the
    lobe's front (t=1); the ear's root is at X = 0."""
    psi = np.radians(130.0 - 250.0 * t)
    x = 14.0 + 16.0 * np.cos(psi - WIDEST)
    y = 2.0 + 29.0 * np.sin(psi)
    lobe = np.clip((-12.0 - y) / 14.0, 0.0, 1.0)  # the lobe: narrower towards its bottom
    x = 14.0 + (x - 14.0) * (1.0 - 0.35 * lobe)
    return x, y


def stand_off(t: np.ndarray) -> np.ndarray:
    """The rim's distance (mm) from the head at ``t`` (before the helix's roll and the
    root's sinking): seen from the front, an arc of an ellipse over the rim's height, largest
    (:data:`STAND_OFF`) at :data:`WIDEST_Y`, falling smoothly to the top of the helix and
    to the lobe (a rounded silhouette, not a point)."""
    _, y = outline(t)
    # in front of the rim's top (towards the helix's root) no more than at the top: the
    # helix's root grows out of the head (the taper of :func:`relief`), with no dip at the top
    y = np.where(t < T_TOP, outline(np.array(T_TOP))[1], y)
    dy = (y - WIDEST_Y) / np.where(y > WIDEST_Y, ARC_UP, ARC_DOWN)
    return STAND_OFF * np.sqrt(np.clip(1.0 - dy * dy, 0.0, 1.0))


def relief(s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Height (mm) off the head at (s: 0 root .. 1 rim, t: 0 top front .. 1 lobe)."""
    lobe = np.clip((t - 0.72) / 0.12, 0.0, 1.0)
    cart = 1.0 - lobe  # cartilage
    # the helix's root (t = 0) and the lobe's front (t = 1) grow out of the head
    taper = _smoothstep(t / 0.15) * _smoothstep((1.0 - t) / 0.12)
    flare = -1.5 + stand_off(t) * s ** 1.2 * (1.0 - 0.4 * lobe) * taper
    upper = np.clip((0.62 - t) / 0.1, 0.0, 1.0)
    helix = 2.5 * _bump((s - 0.93) / 0.05)
    scapha = -1.5 * _bump((s - 0.76) / 0.06) * upper
    antihelix = 3.0 * _bump((s - 0.58) / 0.08) * np.clip((t - 0.08) / 0.1, 0, 1) * cart
    concha_w = (np.clip((0.45 - s) / 0.1, 0.0, 1.0) * np.clip((t - 0.28) / 0.08, 0, 1)
                * np.clip((0.74 - t) / 0.06, 0, 1))
    h = flare + cart * (helix + scapha) + antihelix
    h = h * (1.0 - concha_w) + 1.0 * concha_w  # the concha's floor
    tragus = 4.5 * _bump((s - 0.1) / 0.06) * _bump((t - 0.66) / 0.05)
    return h + tragus


def ear_parts(rest: np.ndarray, normals: np.ndarray, nasion: np.ndarray) -> list[Part]:
    """Both ears, attached to a closed head's surface.

    Parameters
    ----------
    rest : (n, 3) m, the head's surface vertices at rest (skin and closure)
    normals : (n, 3) their unit normals
    nasion : (3,) m
    """
    parts = []
    y_top = nasion[1] + TOP_ABOVE_NASION
    y_mid = y_top - 0.5 * HEIGHT
    z_root = nasion[2] - BEHIND_NASION
    for side, name in ((1, "ear_left"), (-1, "ear_right")):
        near = (side * rest[:, 0] > 0.03) & (np.hypot(rest[:, 1] - y_mid,
                                                      rest[:, 2] - z_root) < 0.008)
        if not near.any():
            continue
        k = np.flatnonzero(near)[np.argmax(side * rest[near, 0])]
        a = np.array([rest[k, 0], y_mid, z_root])
        out = normals[near].mean(axis=0)
        out[1] = 0.0
        out /= np.linalg.norm(out)
        back = np.array([0.0, 0.0, -1.0]) - out[2] * out
        back /= np.linalg.norm(back)
        up = np.array([0.0, 1.0, 0.0])
        s, t = np.meshgrid(np.linspace(0, 1, N_S), np.linspace(0, 1, N_T), indexing="ij")
        rx, ry = outline(t)
        root_y = 20.0 - 38.0 * t
        x_mm = s * rx
        y_mm = root_y + s * (ry - root_y)
        h = relief(s, t)
        # the root follows the head's side (it narrows towards the jaw): each line from the
        # root to the rim moves out or in by the head's lateral offset at its root
        root = a + 1e-3 * (root_y[0] - 2.0)[:, None] * up  # (N_T, 3) at s = 0
        lateral = np.empty(N_T)
        for j, q in enumerate(root):
            ring = (side * rest[:, 0] > 0.03) & (np.hypot(rest[:, 1] - q[1],
                                                          rest[:, 2] - q[2]) < 0.006)
            lateral[j] = (side * rest[ring, 0].max() - side * a[0]) if ring.any() else 0.0
        # smoothed along the rim: the largest of a few vertices jumps from one line to the next
        lateral = gaussian_filter1d(lateral, 4.0, mode="nearest")
        shift = lateral[None, :] / max(abs(out[0]), 0.5)
        pts = (a + 1e-3 * (x_mm[..., None] * back + (y_mm - 2.0)[..., None] * up
                           + h[..., None] * out) + shift[..., None] * out)
        # the helix's roll curls forward over the scapha
        pts += 1e-3 * (-1.5 * _bump((s - 0.97) / 0.04))[..., None] * back
        # a strip from the root 4 mm further into the head seals the sulcus behind the ear
        pts = np.concatenate([pts[:1] - 0.004 * out, pts])
        h = np.concatenate([h[:1] - 4.0, h])
        v = pts.reshape(-1, 3)
        f = grid_faces(N_S + 1, N_T)
        # outward (lateral) faces: flip for the subject's right, whose lateral side is -x
        lateral = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]) @ out
        f = f if np.median(lateral) > 0 else f[:, ::-1]
        hollow = np.clip(1.0 - (h.ravel() + 3.0) / 12.0, 0.0, 1.0)  # deep parts darker
        albedo = (T.EAR * (1.0 - 0.25 * hollow[:, None])
                  + 0.15 * hollow[:, None] * (T.CHEEK - T.EAR))
        parts.append(Part(name, v, f, albedo, (0.08, 14.0), "skull"))
        parts.append(Part(name + "_back", v, f[:, ::-1], albedo * 0.9, (0.05, 10.0), "skull",
                          inward=True))
    return parts
