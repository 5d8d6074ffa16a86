"""Markers to a face: a similarity transform (scale, rotation, translation) from the lab's frame
to the model's, fitted either to named correspondences or to the skin itself.

A subject's rest markers lie on the skin. When they are named as the face's landmarks or
markers, the least-squares similarity of Umeyama (1991, IEEE PAMI 13:376, eqs. 40-42) takes
them onto those nodes. Otherwise the rotation comes from an anatomical frame of three markers
(:func:`facemech.kinematics.frames.basis_from_points`), and iterated closest points (Besl &
McKay 1992) refine rotation and translation (rigidly: the warp of the face to the markers
absorbs a difference in size) against the skin's nodes, started from a grid of translations so
that the fit does not stop in the first local minimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError

__all__ = ["Similarity", "closest_point_fit", "fit_to_skin", "similarity_fit"]

OUTLIER_M = 0.003  #: m, markers farther from the skin are left out of the final fit
PITCHES_DEG = (-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0)  #: the frame's pitches tried

@dataclass(frozen=True)
class Similarity:
    """``x_model = scale * rotation @ x_lab + translation`` (metres).

    Attributes
    ----------
    scale : dimensionless
    rotation : (3, 3), det +1
    translation : (3,) m
    rms : RMS distance (m) of the fitted points to their targets
    """

    scale: float
    rotation: np.ndarray
    translation: np.ndarray
    rms: float = 0.0

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """The points (..., 3) moved into the model's frame."""
        return self.scale * np.asarray(points, float) @ self.rotation.T + self.translation

    def as_dict(self) -> dict:
        return {"scale": self.scale, "rotation": self.rotation.tolist(),
                "translation_m": self.translation.tolist(), "rms_mm": self.rms * 1e3}

    @classmethod
    def from_dict(cls, d: dict) -> Similarity:
        return cls(float(d["scale"]), np.array(d["rotation"], float),
                   np.array(d["translation_m"], float), float(d.get("rms_mm", 0.0)) * 1e-3)


def similarity_fit(source: np.ndarray, target: np.ndarray, *,
                   with_scale: bool = True) -> Similarity:
    """The least-squares similarity taking ``source`` (n, 3) onto ``target`` (n, 3), n >= 3
    (Umeyama 1991, eqs. 40-42); det(R) = +1. ``with_scale=False`` keeps the scale at 1."""
    s, d = np.asarray(source, float), np.asarray(target, float)
    cs, cd = s.mean(axis=0), d.mean(axis=0)
    a, b = s - cs, d - cd
    u, sv, vt = np.linalg.svd(b.T @ a / len(s))
    e = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt)) or 1.0])
    r = u @ e @ vt
    var = np.mean(np.sum(a * a, axis=1))
    c = float(np.trace(np.diag(sv) @ e) / var) if with_scale and var > 0 else 1.0
    t = cd - c * r @ cs
    rms = float(np.sqrt(np.mean(np.sum((c * s @ r.T + t - d) ** 2, axis=1))))
    return Similarity(c, r, t, rms)


def closest_point_fit(points: np.ndarray, tree: cKDTree, targets: np.ndarray,
                      start: Similarity, iterations: int, *,
                      scale_range: tuple[float, float] | None = None,
                      tol: float = 1e-8) -> Similarity:
    """Closest-point iterations (Besl & McKay 1992): ``points`` (n, 3) moved by the fit onto
    their nearest ``targets`` (``tree`` is their KD-tree), refitted until the RMS changes by
    less than ``tol`` (m).

    ``scale_range`` None: rigid (scale kept at the start's; on a skin, a free scale would shrink
    the markers into its concavities, closest points being biased inward). Else the scale is
    free, and a step that would leave the range ends the iterations (the fit so far returned).
    """
    fit = start
    for _ in range(iterations):
        _, idx = tree.query(fit(points))
        new = similarity_fit(points, targets[idx], with_scale=scale_range is not None)
        if scale_range is not None and not scale_range[0] <= new.scale <= scale_range[1]:
            return fit
        if abs(new.rms - fit.rms) < tol:
            return new
        fit = new
    return fit


def fit_to_skin(points: np.ndarray, skin: np.ndarray, rotation: np.ndarray, *,
                spacing: float = 0.008, iterations: int = 60, source: str | None = None
                ) -> Similarity:
    """The rigid motion (a similarity of scale 1) that lays marker positions on the skin, by
    closest points.

    Parameters
    ----------
    points : (n, 3) rest marker positions in the lab, metres, n >= 6
    skin : (m, 3) the face's epidermal nodes at rest, metres
    rotation : (3, 3) lab -> model rotation of the markers' anatomical frame (rows: x, y, z)
    spacing : m, grid of starting translations over the skin
    iterations : closest-point iterations per start

    Returns
    -------
    Similarity : the start with the smallest RMS marker-to-skin distance, refined; then,
        while a marker lies more than 3 mm from the skin, the farthest is left out and the fit
        refined again, so that markers off the skin (a headband not named as such) do not pull
        it
    """
    pts = np.asarray(points, float)
    if len(pts) < 6:
        raise InputError(f"fitting markers to the skin needs at least 6 markers, got {len(pts)}",
                         source=source, field="markers")
    tree = cKDTree(skin)
    # starts: the markers' centroid placed at grid points of the skin, pushed 10 mm inside, and
    # the frame pitched by up to 45 degrees (a "front" marker above the plane of the others);
    # the 24 starts whose markers lie closest to the skin are refined, the best one fully
    grid = np.unique(np.round(skin / spacing), axis=0) * spacing
    _, near = tree.query(grid)
    centres = skin[np.unique(near)] - np.array([0.0, 0.0, 0.010])
    starts = [Similarity(1.0, r, c - r @ pts.mean(axis=0), np.inf)
              for r in (_pitch(a) @ rotation for a in np.deg2rad(PITCHES_DEG)) for c in centres]
    first = [float(np.mean(tree.query(s(pts))[0] ** 2)) for s in starts]
    refined = [closest_point_fit(pts, tree, skin, starts[k], 8) for k in np.argsort(first)[:24]]
    fit = closest_point_fit(pts, tree, skin, min(refined, key=lambda f: f.rms), iterations)
    while len(pts) > 6:  # markers off the skin leave the fit one at a time, the farthest first
        d = tree.query(fit(pts))[0]
        if d.max() <= OUTLIER_M:
            break
        pts = np.delete(pts, np.argmax(d), axis=0)
        fit = closest_point_fit(pts, tree, skin, fit, iterations)
    return fit


def _pitch(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
