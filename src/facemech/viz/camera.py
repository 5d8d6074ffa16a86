"""Cameras and the named views of a face: frontal, profile, three-quarter, mouth close-up.

A camera looks along its -z axis at ``target`` from ``distance`` metres (a pinhole; ``None``
is orthographic) and frames ``half_height`` metres above and below the target. Image
coordinates are x right, y down; the subject's left (+x) appears on the image's right in the
frontal view, as a camera facing the subject sees it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

#: named views: (azimuth deg, elevation deg); azimuth 90 shows the subject's right profile
VIEWS: dict[str, tuple[float, float]] = {
    "frontal": (0.0, 0.0),
    "profile": (90.0, 0.0),
    "three-quarter": (35.0, 4.0),
    "mouth": (0.0, 0.0),
}
#: views that are several panels side by side
COMPOSITE_VIEWS: dict[str, tuple[str, ...]] = {"frontal+profile": ("frontal", "profile")}
MAX_SIZE = (2160, 3840)  #: (height, width) limit, pixels


def view_rotation(azimuth_deg: float, elevation_deg: float = 0.0) -> np.ndarray:
    """Rotation taking model coordinates to camera coordinates (camera looks along -z).

    ``azimuth_deg = 0`` is the frontal view; ``90`` looks at the subject's right profile;
    positive elevations look from above.
    """
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    ry = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
    return rx @ ry


@dataclass(frozen=True)
class Camera:
    """A pinhole (or orthographic) camera.

    Attributes
    ----------
    rotation : (3, 3) model-to-camera rotation
    target : (3,) m, model point at the image centre
    half_height : m, half the height of the view at the target's depth
    size : (height, width) pixels
    distance : m from the camera to the target; None for an orthographic view
    """

    rotation: np.ndarray
    target: np.ndarray
    half_height: float
    size: tuple[int, int]
    distance: float | None = 1.2

    def project(self, points: np.ndarray, supersample: int = 1) -> np.ndarray:
        """(n, 3) model points (m) to (n, 3) float32 (x, y, depth) in sample coordinates.

        Depth grows towards the camera. With ``supersample`` s, the image is s times larger.
        """
        h, w = self.size
        cam = (np.asarray(points, float) - self.target) @ self.rotation.T
        scale = 0.5 * h * supersample / self.half_height
        if self.distance is None:
            k = np.ones(len(cam))
        else:
            k = self.distance / np.maximum(self.distance - cam[:, 2], 1e-3)
        out = np.empty((len(cam), 3), np.float32)
        out[:, 0] = 0.5 * w * supersample + cam[:, 0] * k * scale
        out[:, 1] = 0.5 * h * supersample - cam[:, 1] * k * scale
        out[:, 2] = cam[:, 2]
        return out


def parse_size(text: str, *, field: str = "size") -> tuple[int, int]:
    """``"1280x720"`` (width x height) to (height, width); even numbers for H.264."""
    try:
        w, h = (int(v) for v in text.lower().replace("*", "x").split("x"))
    except ValueError:
        raise InputError(f"size {text!r} is not WIDTHxHEIGHT, e.g. 1280x720",
                         field=field) from None
    if not (16 <= w <= MAX_SIZE[1] and 16 <= h <= MAX_SIZE[0]):
        raise InputError(f"size {w}x{h} is outside 16x16 .. {MAX_SIZE[1]}x{MAX_SIZE[0]}",
                         field=field)
    return h - h % 2, w - w % 2


def panels(view: str) -> tuple[str, ...]:
    """The single views a (possibly composite) view is made of."""
    if view in COMPOSITE_VIEWS:
        return COMPOSITE_VIEWS[view]
    if view not in VIEWS:
        raise InputError(f"unknown view {view!r} (one of {', '.join(all_views())})",
                         field="view")
    return (view,)


def all_views() -> tuple[str, ...]:
    """Every view name accepted by ``--view``."""
    return (*VIEWS, *COMPOSITE_VIEWS)


def view_camera(view: str, framing: dict, size: tuple[int, int],
                distance: float | None = 1.2) -> Camera:
    """The camera of a single named view.

    Parameters
    ----------
    view : one of :data:`VIEWS`
    framing : ``{"points": (n, 3), "mouth": (3,), "mouth_half_height": float}`` in metres:
        the points every face view fits in its panel (4 % margin), and what the mouth close-up
        frames
    size : (height, width) pixels of this panel
    distance : camera distance, m (None: orthographic)
    """
    az, el = VIEWS[view]
    rot = view_rotation(az, el)
    if view == "mouth":
        return Camera(rot, np.asarray(framing["mouth"], float), framing["mouth_half_height"],
                      size, distance)
    pts = np.asarray(framing["points"], float)
    cam = pts @ rot.T
    lo, hi = cam.min(axis=0), cam.max(axis=0)
    centre = 0.5 * (lo + hi)
    h, w = size
    half = 1.04 * max(0.5 * (hi[1] - lo[1]), 0.5 * (hi[0] - lo[0]) * h / w)
    # the camera target: the box centre, at the depth of the box centre (model coordinates)
    target = centre @ rot
    return Camera(rot, target, half, size, distance)
