"""The shape of an adult head and neck where the face surface stops: an implicit solid.

A smooth union of a head ellipsoid (150 x 230 x 214 mm about the head's centre, 88 mm
behind the nasion: a glabella-opisthocranion length of 197 mm, Farkas' adult male mean) and a
neck: a cylinder of superelliptic section (exponent 3: flatter in front than an ellipse),
112 mm wide and 116 mm deep, leaning 15 degrees forward as it goes down, whose front passes
through the throat where the face surface stops, from 50 mm under the head's centre (so that
its back stays under the occiput, not behind it) to 300 mm under it.
The head surface that closes the skin (:mod:`.closure`) takes its radius from here away from
the skin's edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HEAD_RADII = np.array([0.075, 0.115, 0.107])  #: m, half-width, half-height, half-depth
NECK_RADII = np.array([0.056, 0.058])  #: m, half-width and half-depth of the neck
NECK_POWER = 3.0  #: superellipse exponent of the neck's section (2: an ellipse; flatter in front)
NECK_LEAN = np.tan(np.radians(15.0))  #: forward lean of the neck's axis per metre down
NECK_DROP = 0.30  #: m, the neck's cut under the head's centre
NECK_TOP = 0.05  #: m, the neck's top under the head's centre
BLEND = 10.0  #: sharpness of the smooth union (per unit of the normalised distances)


@dataclass(frozen=True)
class Cranium:
    """An implicit head and neck (m, model axes).

    Attributes
    ----------
    centre : (3,) the head ellipsoid's centre
    throat : (3,) the front of the neck at the top of its cylinder (the skin's throat edge)
    """

    centre: np.ndarray
    throat: np.ndarray

    def field(self, p: np.ndarray) -> np.ndarray:
        """Signed, roughly normalised distance (..., ) of points ``p`` (..., 3): < 0 inside."""
        c = self.centre
        q = (p - c) / HEAD_RADII
        f_head = np.sqrt((q ** 2).sum(-1)) - 1.0
        y = p[..., 1]
        axis_z = self.throat[2] - NECK_RADII[1] + NECK_LEAN * (self.throat[1] - y)
        f_neck = (np.abs((p[..., 0] - c[0]) / NECK_RADII[0]) ** NECK_POWER
                  + np.abs((p[..., 2] - axis_z) / NECK_RADII[1]) ** NECK_POWER
                  ) ** (1.0 / NECK_POWER) - 1.0
        f_neck = np.maximum(f_neck, (y - c[1] + NECK_TOP) / 0.05)  # it stops inside the head
        f_neck = np.maximum(f_neck, (c[1] - NECK_DROP - y) / 0.05)
        k = BLEND
        m = np.minimum(f_head, f_neck)
        return m - np.log(np.exp(-k * (f_head - m)) + np.exp(-k * (f_neck - m))) / k

    def radius(self, d: np.ndarray, origin: np.ndarray | None = None,
               r_max: float = 0.45) -> np.ndarray:
        """Distance (n,) m from ``origin`` (default :attr:`centre`) to the surface along unit
        directions ``d`` (n, 3): the outermost crossing (2-mm steps, then bisected)."""
        d = np.asarray(d, float)
        o = self.centre if origin is None else np.asarray(origin, float)
        t = np.arange(0.002, r_max, 0.002)
        f = self.field(o + d[:, None, :] * t[None, :, None])  # (n, steps)
        inside = f < 0
        last = np.where(inside.any(axis=1),
                        inside.shape[1] - 1 - np.argmax(inside[:, ::-1], axis=1), 0)
        lo = t[last]
        hi = lo + 0.002
        for _ in range(12):
            mid = 0.5 * (lo + hi)
            out = self.field(o + d * mid[:, None]) >= 0
            hi = np.where(out, mid, hi)
            lo = np.where(out, lo, mid)
        return 0.5 * (lo + hi)
