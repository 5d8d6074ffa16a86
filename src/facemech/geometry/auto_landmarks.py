"""Landmarks from geometry alone: the generic face registered onto a scan.

The generic face (:func:`facemech.geometry.builder.default_surface`) carries every landmark.
Registering it onto a scan places them there:

1. **Similarity** (scale, rotation, translation): closest-point iterations from the generic
   face's points to the scan (Besl & McKay 1992) with the least-squares similarity of each step
   (Umeyama 1991), started from the 24 axis-aligned rotations at several positions, because a
   scan's axes and units are not known yet. The direction generic -> scan lets the scan hold
   more than a face (hair, ears, neck).
2. **Affine and non-rigid refinement**: affine closest-point iterations (a face wider or longer
   than the generic one, stretches up to 1.3), then a few steps of a smoothed thin-plate-spline
   warp of the generic face onto its closest points on the scan, the smoothing decreasing, so
   that a face whose proportions differ from the generic one still brings each landmark onto
   its own anatomy.
3. **Snapping**: each landmark moves to the nearest point of the scan's surface.

Each landmark gets a confidence in [0, 1] from how well the generic face fits the scan within
15 mm of it: ``exp(-(d / 1 mm)^2)`` of the RMS closest-point distance there after registration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..errors import InputError
from ..kinematics.alignment import Similarity, closest_point_fit

__all__ = ["AutoLandmarks", "auto_landmarks", "surface_points"]

SCALE_RANGE = (0.5, 2.0)  #: the scan's face against the generic one (after the unit check)
SAMPLES = 600  #: generic-face points used for the registration
CONFIDENCE_MM = 1.0  #: local fit RMS (mm) at which the confidence is exp(-1)


@dataclass(frozen=True)
class AutoLandmarks:
    """Landmarks placed on a scan.

    Attributes
    ----------
    positions : name -> (3,) position on the scan, in the scan's coordinates (metres)
    confidence : name -> confidence in [0, 1]
    generic_to_scan : the similarity of step 1 (generic face -> scan)
    rms : RMS closest-point distance (m) of the generic face to the scan after step 2
    """

    positions: dict
    confidence: dict
    generic_to_scan: Similarity
    rms: float


def _affine_icp(points: np.ndarray, extra: np.ndarray, tree: cKDTree, dst: np.ndarray,
                iterations: int = 40, max_stretch: float = 1.3) -> tuple[np.ndarray, np.ndarray]:
    """Affine closest-point iterations from ``points``; ``extra`` points ride along. A step
    whose linear part stretches one direction more than ``max_stretch`` times another ends
    them. Returns the moved ``points`` and ``extra``."""
    for _ in range(iterations):
        _, idx = tree.query(points)
        h = np.c_[points, np.ones(len(points))]
        a, *_ = np.linalg.lstsq(h, dst[idx], rcond=None)  # (4, 3): x' = [x 1] @ a
        sv = np.linalg.svd(a[:3], compute_uv=False)
        if sv[0] / sv[-1] > max_stretch or np.allclose(a[:3], np.eye(3), atol=1e-9):
            break
        points, extra = np.c_[points, np.ones(len(points))] @ a, np.c_[
            extra, np.ones(len(extra))] @ a
    return points, extra


def _starts(generic: np.ndarray, scan: np.ndarray) -> list[Similarity]:
    """The 24 axis-aligned rotations, each placing the generic face's centroid at the scan's
    centroid and 6 cm to either side along each axis, at the scale of the two extents."""
    rots = Rotation.create_group("O").as_matrix()
    scale = float(np.clip(np.ptp(scan, axis=0).max() / np.ptp(generic, axis=0).max(), 0.6, 1.6))
    span = 0.35 * np.ptp(scan, axis=0).max()
    offsets = [np.zeros(3)] + [s * span * e for e in np.eye(3) for s in (-1.0, 1.0)]
    c_g, c_s = generic.mean(axis=0), scan.mean(axis=0)
    return [Similarity(scale, r, c_s + o - scale * r @ c_g, np.inf) for r in rots
            for o in offsets]


def surface_points(vertices: np.ndarray, faces: np.ndarray, spacing: float = 0.0008,
                   seed: int = 0) -> np.ndarray:
    """Points spread over a triangle mesh about ``spacing`` (m) apart (area-weighted random
    barycentric samples, plus the vertices), so that closest points approximate the surface
    rather than its vertices."""
    v, f = np.asarray(vertices, float), np.asarray(faces, np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    n = int(min(area.sum() / spacing**2, 400_000))
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(f), size=n, p=area / area.sum())
    r1, r2 = np.sqrt(rng.random(n)), rng.random(n)
    pts = ((1 - r1)[:, None] * a[tri] + (r1 * (1 - r2))[:, None] * b[tri]
           + (r1 * r2)[:, None] * c[tri])
    return np.concatenate([v, pts])


def auto_landmarks(vertices: np.ndarray, faces: np.ndarray, *,
                   source: str | None = None) -> AutoLandmarks:
    """Place the generic face's landmarks on a scan.

    Parameters
    ----------
    vertices : (n, 3) the scan's vertices, metres (any orientation and position)
    faces : (m, 3) its triangles (vertex indices)
    source : the scan's file, for messages

    Returns
    -------
    AutoLandmarks
    """
    from .builder import default_surface

    scan = np.asarray(vertices, float)
    if len(np.asarray(faces)) == 0:
        raise InputError("a scan needs triangles to be landmarked", source=source, field="faces")
    if scan.ndim != 2 or scan.shape[1] != 3 or len(scan) < 200:
        raise InputError(f"a scan needs at least 200 vertices to be landmarked, got "
                         f"{len(scan)}", source=source, field="vertices")
    gv, _, glm = default_surface("default-coarse")
    rng = np.random.default_rng(0)
    sample = gv[rng.choice(len(gv), size=min(SAMPLES, len(gv)), replace=False)]
    scan = surface_points(scan, faces)
    tree = cKDTree(scan)
    # the starts are scored and roughly fitted on a 4-mm subset of both (far points are slow
    # to look up in the dense tree)
    sparse = scan[np.unique(np.round(scan / 0.004), axis=0, return_index=True)[1]]
    few, sparse_tree = sample[::4], cKDTree(sparse)
    starts = _starts(sample, scan)
    first = [float(np.mean(sparse_tree.query(s(few))[0] ** 2)) for s in starts]
    coarse = [closest_point_fit(few, sparse_tree, sparse, starts[k], 15,
                                scale_range=SCALE_RANGE, tol=1e-9)
              for k in np.argsort(first)[:16]]
    fit = closest_point_fit(sample, tree, scan, min(coarse, key=lambda f: f.rms), 80,
                            scale_range=SCALE_RANGE, tol=1e-9)
    # step 2: an affine fit (a face wider or longer than the generic one), then smoothed
    # thin-plate-spline refinement of the placed generic face
    names = list(glm)
    placed, lm = _affine_icp(fit(sample), fit(np.array([glm[n] for n in names])), tree, scan)
    for smoothing in (1.0, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001):
        d, idx = tree.query(placed)
        keep = d <= max(3.0 * float(np.median(d)), 0.002)
        warp = RBFInterpolator(placed[keep], scan[idx[keep]] - placed[keep],
                               kernel="thin_plate_spline", smoothing=smoothing * len(placed))
        placed, lm = placed + warp(placed), lm + warp(lm)
    d, _ = tree.query(placed)
    rms = float(np.sqrt(np.mean(d * d)))
    positions, confidence = {}, {}
    near_tree = cKDTree(placed)
    for n, p in zip(names, lm, strict=True):
        _, k = tree.query(p)
        positions[n] = scan[k]
        local = near_tree.query_ball_point(p, 0.015)
        local_rms = float(np.sqrt(np.mean(d[local] ** 2))) if local else np.inf
        confidence[n] = float(np.exp(-((local_rms * 1e3 / CONFIDENCE_MM) ** 2)))
    return AutoLandmarks(positions, confidence, fit, rms)
