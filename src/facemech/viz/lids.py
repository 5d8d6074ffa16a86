"""Blinks and gaze: the eyeballs turn, the lids close over them and follow their pitch.

The skin's palpebral fissure is a cut-out of its texture (:mod:`.textures`); behind it sits
the eyeball. An upper lid is a skin-coloured cap just outside the eyeball (0.4 mm), spanning
the fissure's width, from 2 degrees above the fissure's upper margin (behind the skin) down to
its edge, which carries the lashes. Open and looking straight ahead the edge is at the cap's
top: the lid has no area and nothing changes. It comes down

* with the blink closure ``b`` (0 open .. 1 closed): to the closed line, 0.5 mm under the
  lower margin, tucked behind the lower lid (the upper lid makes nearly all of a blink's
  travel);
* with the gaze's pitch when the eye looks down: the upper lid follows the eye by 0.8 of its
  angle (lid-eye coordination; the lid does not rise above its open position looking up).

A lower lid is the same kind of cap, 0.1 mm further out (the closed upper lid's edge tucks
behind it), from 2 degrees below the fissure's lower margin up to its edge, which carries the
lower lashes. Open and looking straight ahead it has no area. It rises

* with the blink: 1.2 mm at its middle when closed (the lower lid's small share of a blink),
  in front of the closed upper lid's edge;
* with the gaze's pitch when the eye looks up: by 0.35 of the eye's angle (it stays at the
  fissure's margin looking down: the fissure is cut in the skin and cannot open further);

and never above the open upper lid's margin.

Gaze (yaw, pitch) in radians turns each eyeball about its centre: yaw > 0 towards the
subject's left (+x), pitch > 0 up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import textures as T
from .mesh import grid_faces

CLEARANCE = 0.0004  #: m between the eyeball and the lid
LID_FOLLOW = 0.8  #: of the eye's downward pitch taken by the upper lid
LOWER_FOLLOW = 0.35  #: of the eye's upward pitch taken by the lower lid
LOWER_BLINK_RISE = 0.0012  #: m, the lower lid's rise in a full blink
LOWER_CLEARANCE = 0.0005  #: m between the eyeball and the lower lid (outside the upper)
ROWS, COLS = 7, 25  #: the lid cap's grid


def gaze_rotation(yaw: float, pitch: float) -> np.ndarray:
    """(3, 3) rotation turning the forward axis (+z) to the gaze (yaw > 0 to +x, pitch > 0
    up)."""
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cp, sp], [0.0, -sp, cp]])
    return ry @ rx


@dataclass(frozen=True)
class Lid:
    """A lid over an eyeball (m, rad).

    Attributes
    ----------
    centre : (3,) the eyeball's centre
    radii : (3,) the cap's semi-axes (the eyeball's plus the clearance)
    azimuth : (COLS,) rad, the cap's columns about the centre (0 forward, > 0 to +x)
    top : (COLS,) rad, elevation of the cap's fixed side: above the fissure's upper margin
        (an upper lid) or below its lower margin (a lower lid)
    closed : (COLS,) rad, elevation of the edge of a closed lid
    upper : (COLS,) rad, for a lower lid: the open upper lid's cap top, the highest its edge
        may go (None for an upper lid)
    """

    centre: np.ndarray
    radii: np.ndarray
    azimuth: np.ndarray
    top: np.ndarray
    closed: np.ndarray
    upper: Lid | None = None

    @property
    def lower(self) -> bool:
        return self.upper is not None

    def edge(self, blink: float, pitch: float) -> np.ndarray:
        """Elevation (COLS,) rad of the lid's edge."""
        b = float(np.clip(blink, 0.0, 1.0))
        if self.lower:
            if blink <= 0.0 and pitch <= 0.0:
                return self.top
            # from the margin (the cap's fixed side lies 2 degrees under it, behind the skin)
            margin = self.top + np.radians(2.0)
            edge = margin + LOWER_FOLLOW * max(pitch, 0.0) + b * (self.closed - margin)
            # never above the open upper lid's fixed side
            return np.minimum(edge, self.upper.top - np.radians(2.0))
        open_ = np.minimum(self.top, self.top + LID_FOLLOW * min(pitch, 0.0))
        return np.minimum(open_ + b * (self.closed - open_), open_)

    def at_rest(self, blink: float, pitch: float) -> bool:
        """Whether the lid is open (no area) for this blink and pitch."""
        return blink == 0.0 and (pitch <= 0.0 if self.lower else pitch >= 0.0)

    def place(self, blink: float = 0.0, pitch: float = 0.0) -> np.ndarray:
        """Vertices (ROWS * COLS, 3) m: rows from the cap's fixed side to the edge."""
        edge = self.edge(blink, pitch)
        k = np.linspace(0.0, 1.0, ROWS)[:, None]
        el = self.top[None, :] + k * (edge - self.top)[None, :]
        az = np.broadcast_to(self.azimuth[None, :], el.shape)
        d = np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], -1)
        return (self.centre + d * self.radii).reshape(-1, 3)


def lid_of(eye: np.ndarray, centre: np.ndarray, radii: np.ndarray, side: int) -> Lid:
    """The upper lid of the eye whose fissure is centred at ``eye`` (landmark, m), with its
    eyeball at ``centre`` of semi-axes ``radii`` (m); ``side`` +1 left, -1 right."""
    r = np.asarray(radii, float) + CLEARANCE
    s = np.linspace(-1.15, 1.15, COLS)  # along the fissure, medial -1 .. lateral 1
    x = eye[0] + side * s * T.FISSURE_HALF_LENGTH
    up, lo = T.fissure_heights(s)
    tilt = 0.001 * np.clip(s, -1.5, 1.5)
    y_up = eye[1] - 0.0005 + tilt + up  # margins in model y (textures._eye_frame)
    y_lo = eye[1] - 0.0005 + tilt + lo
    az = np.arcsin(np.clip((x - centre[0]) / r[0], -0.99, 0.99))
    if side < 0:
        az = az[::-1]
        y_up, y_lo = y_up[::-1], y_lo[::-1]

    def elevation(y):
        return np.arcsin(np.clip((y - centre[1]) / r[1], -0.99, 0.99))

    top = elevation(y_up) + np.radians(2.0)
    closed = elevation(y_lo - 0.0005)
    return Lid(np.asarray(centre, float), r, az, top, np.minimum(closed, top))


def lower_lid_of(upper: Lid) -> Lid:
    """The lower lid under an upper lid (:func:`lid_of`'s), on the same eyeball."""
    r = upper.radii - CLEARANCE + LOWER_CLEARANCE
    # the lower margin's elevation is where the closed upper lid's edge sits, 0.5 mm above
    y_lo = upper.centre[1] + (upper.radii[1]) * np.sin(upper.closed) + 0.0005
    margin = np.arcsin(np.clip((y_lo - upper.centre[1]) / r[1], -0.99, 0.99))
    rise = np.arcsin(np.clip((y_lo + LOWER_BLINK_RISE * _middle(upper.azimuth) - upper.centre[1])
                             / r[1], -0.99, 0.99))
    bottom = margin - np.radians(2.0)
    return Lid(upper.centre, r, upper.azimuth, bottom, rise, upper=upper)


def _middle(azimuth: np.ndarray) -> np.ndarray:
    """1 at the middle of the fissure's columns, falling to 0.3 at its corners."""
    a = (azimuth - azimuth.mean()) / (0.5 * np.ptp(azimuth))
    return 0.3 + 0.7 * np.clip(1.0 - a ** 2, 0.0, 1.0)


def lid_mesh(lid: Lid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices at rest (open), outward faces, and albedo (sRGB): skin, the edge's lashes."""
    v = lid.place()
    f = grid_faces(ROWS, COLS)
    albedo = np.tile(T.SKIN, (ROWS, COLS, 1))
    if lid.lower:  # rows run up, columns towards +x: outward as they are
        albedo[-1] = 0.5 * T.SKIN + 0.5 * T.LASH  # the lower lashes: sparse, short
        return v, f, albedo.reshape(-1, 3)
    # rows run down (decreasing elevation), columns towards +x: flip to face outward
    f = f[:, ::-1]
    albedo[-1] = T.LASH
    albedo[-2] = 0.6 * T.SKIN + 0.4 * T.LID_CREASE
    return v, f, albedo.reshape(-1, 3)
