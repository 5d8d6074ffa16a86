"""Least-squares rigid fits and head-motion correction.

Each frame's head markers are fitted to their reference positions by the rotation and
translation that minimise the summed squared distance (no scaling; the SVD solution of Kabsch
with the determinant guard, so a reflection is never returned). The inverse motion is applied to
every marker of the frame. Frames with fewer than three usable head markers (or three nearly on
a line) cannot be fixed: they are reported and set to NaN, never guessed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..markerset import MarkerSet


def rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation R (3, 3) and translation t (3,) minimising sum |R s_i + t - t_i|^2.

    ``source`` and ``target`` are (n, 3) with n >= 3; det(R) = +1 always.
    """
    s = np.asarray(source, float)
    d = np.asarray(target, float)
    cs, cd = s.mean(axis=0), d.mean(axis=0)
    h = (s - cs).T @ (d - cd)
    u, _, vt = np.linalg.svd(h)
    sign = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, sign]) @ u.T
    return r, cd - r @ cs


@dataclass(frozen=True, eq=False)
class HeadCorrection:
    """Result of :func:`head_correct`.

    Attributes
    ----------
    markers : the corrected marker set (frames that could not be fixed are NaN)
    rotation : (frames, 3, 3) rotation applied to each frame (NaN where not fixed)
    translation : (frames, 3) m
    residual : (frames,) m, RMS distance of the head markers to their reference after the fit
    head_markers_used : (frames,) number of head markers in each frame's fit
    unfixed_frames : frames with fewer than three usable head markers
    reference_frame : index of the reference frame
    """

    markers: MarkerSet
    rotation: np.ndarray
    translation: np.ndarray
    residual: np.ndarray
    head_markers_used: np.ndarray
    unfixed_frames: np.ndarray
    reference_frame: int

    def summary(self) -> dict:
        ok = np.isfinite(self.residual)
        return {
            "frames": int(len(self.residual)),
            "unfixed_frames": self.unfixed_frames.tolist(),
            "reference_frame": self.reference_frame,
            "residual_mm": {"median": float(np.median(self.residual[ok]) * 1e3) if ok.any()
                            else None,
                            "max": float(np.max(self.residual[ok]) * 1e3) if ok.any() else None},
        }


def _usable(points: np.ndarray, min_spread: float = 1e-3) -> bool:
    """Three or more points not all near one line (second singular value above 1 mm)."""
    if len(points) < 3:
        return False
    sv = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    return sv[1] > min_spread


def head_correct(ms: MarkerSet, head: list[str] | tuple[str, ...], *,
                 reference: int | None = None, refine: bool = True) -> HeadCorrection:
    """Remove head motion using at least three head markers.

    Parameters
    ----------
    ms : marker set
    head : names of markers fixed to the head (at least 3)
    reference : frame whose head-marker positions are the reference (default: the first frame
        in which every head marker is present)
    refine : after the first pass, replace the reference by the mean of the corrected head
        markers over all fixed frames and fit again, so that the noise of one reference frame
        does not tilt every frame (a one-step generalised Procrustes average)
    """
    if len(set(head)) < 3:
        raise InputError(f"head-motion correction needs at least 3 head markers, got "
                         f"{len(set(head))}", source=ms.meta.get("source"), field="head")
    idx = [ms.index(h) for h in head]
    hp = ms.positions[:, idx]
    ok = np.all(np.isfinite(hp), axis=2)
    if reference is None:
        full = np.nonzero(ok.all(axis=1))[0]
        if len(full) == 0:
            raise InputError("no frame has every head marker: pass a reference frame",
                             source=ms.meta.get("source"), field="reference")
        reference = int(full[0])
    if not 0 <= reference < ms.n_frames:
        raise InputError(f"reference frame {reference} outside 0..{ms.n_frames - 1}",
                         field="reference")
    ref = hp[reference]
    ref_ok = ok[reference]
    if not _usable(ref[ref_ok]):
        raise InputError(f"the head markers {', '.join(head)} lie on one line (within 1 mm) at "
                         f"the reference frame {reference}: a rigid fit needs three spread "
                         "markers", source=ms.meta.get("source"), field="head")
    first = _fit_all(ms, hp, ok, ref, ref_ok)
    if len(first[5]) == ms.n_frames:
        raise InputError("no frame has three usable head markers (present and not on one line)",
                         source=ms.meta.get("source"), field="head")
    if refine:
        corrected_head = first[4][:, idx]
        counts = np.sum(np.all(np.isfinite(corrected_head), axis=2), axis=0)
        if np.all(counts > 0):
            ref = np.nanmean(corrected_head, axis=0)
            ref_ok = np.ones(len(idx), bool)
            first = _fit_all(ms, hp, ok, ref, ref_ok)
    rot, trans, resid, used, out, unfixed = first
    corrected = ms.with_positions(out, meta={**ms.meta, "head_corrected": list(head)})
    return HeadCorrection(corrected, rot, trans, resid, used, np.asarray(unfixed, int),
                          reference)


def _fit_all(ms, hp, ok, ref, ref_ok):
    n = ms.n_frames
    rot = np.full((n, 3, 3), np.nan)
    trans = np.full((n, 3), np.nan)
    resid = np.full(n, np.nan)
    used = np.zeros(n, int)
    out = np.full_like(ms.positions, np.nan)
    unfixed = []
    for k in range(n):
        sel = ok[k] & ref_ok
        used[k] = int(sel.sum())
        if not _usable(hp[k, sel]):
            unfixed.append(k)
            continue
        r, t = rigid_fit(hp[k, sel], ref[sel])
        rot[k], trans[k] = r, t
        fitted = hp[k, sel] @ r.T + t
        resid[k] = np.sqrt(np.mean(np.sum((fitted - ref[sel]) ** 2, axis=1)))
        out[k] = ms.positions[k] @ r.T + t
    return rot, trans, resid, used, out, unfixed
