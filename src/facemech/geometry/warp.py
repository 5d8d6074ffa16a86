"""The landmark warp between the generic face and any other face.

Fields and sites defined on the generic face (:mod:`generic`, :mod:`tissue`, :mod:`anatomy`) are
carried onto a face by the thin-plate-spline map that takes the generic landmarks onto that
face's landmarks, and a face's nodes back onto the generic face by the inverse map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RBFInterpolator

from . import generic


@dataclass(frozen=True)
class LandmarkWarp:
    """A thin-plate-spline map of 3-D points (metres) fitted to landmark pairs.

    ``displacement`` is None for the identity (the two faces' landmarks coincide).
    """

    displacement: RBFInterpolator | None

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """The warped points, same shape as ``points`` ((3,) or (k, 3), metres)."""
        if self.displacement is None:
            return np.asarray(points, float)
        return (np.asarray(points, float)
                + self.displacement(np.atleast_2d(points)).reshape(np.shape(points)))


def landmark_warp(source: dict[str, np.ndarray], target: dict[str, np.ndarray]) -> LandmarkWarp:
    """The warp taking ``source`` landmarks onto ``target`` ones (the names both have; metres)."""
    names = [n for n in source if n in target]
    src = np.array([source[n] for n in names])
    dst = np.array([target[n] for n in names])
    if np.allclose(src, dst, atol=1e-9):
        return LandmarkWarp(None)
    return LandmarkWarp(RBFInterpolator(src, dst - src, kernel="thin_plate_spline", degree=1))


def generic_landmarks() -> dict[str, np.ndarray]:
    """The generic face's landmarks, name -> (3,) metres."""
    return {k: v * 1e-3 for k, v in generic.landmarks().items()}


def generic_frontal_mm(vertices: np.ndarray, landmarks: dict[str, np.ndarray]) -> np.ndarray:
    """Generic frontal coordinates (n, 2), mm, of a face's nodes (the fields of :mod:`tissue`).

    Parameters
    ----------
    vertices : (n, 3) array, metres
    landmarks : name -> (3,) metres, the face's
    """
    return landmark_warp(landmarks, generic_landmarks())(vertices)[:, :2] * 1e3
