"""Anatomical frames for marker data and alignment to the model's frame.

The model frame is +x the subject's left, +y up, +z forward (right-handed). An anatomical frame
is set from three named points on a horizontal plane such as the bite plane: ``right`` and
``left`` give +x (right -> left); ``front`` lies in front of them on the same plane, so the plane's
normal gives +y (up) and +z = x cross y points forward. The origin is a named point (the upper
incisor in the seeds, or a nose marker), or ``front``. The frame is taken at one reference frame
(after head-motion correction the head no longer moves) and applied to all frames.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..markerset import MarkerSet
from .rigid import rigid_fit


def basis_from_points(right: np.ndarray, left: np.ndarray, front: np.ndarray) -> np.ndarray:
    """Rows are the unit x, y, z axes (3, 3) of the frame the three points define."""
    x = left - right
    nx = np.linalg.norm(x)
    if nx < 1e-9:
        raise InputError("the left and right points coincide", field="frame")
    x /= nx
    y = np.cross(front - right, x)
    ny = np.linalg.norm(y)
    if ny < 1e-6 * max(np.linalg.norm(front - right), 1e-12):
        raise InputError("the three frame points lie on a line", field="frame")
    y /= ny
    z = np.cross(x, y)
    return np.stack([x, y, z])


def to_anatomical_frame(ms: MarkerSet, *, right: str, left: str, front: str,
                        origin: str | None = None, reference: int = 0) -> MarkerSet:
    """Express markers in the anatomical frame of three named markers (see module doc)."""
    if not 0 <= reference < ms.n_frames:
        raise InputError(f"reference frame {reference} outside 0..{ms.n_frames - 1}",
                         source=ms.meta.get("source"), field="reference")
    p = {n: ms.marker(n)[reference] for n in (right, left, front, origin or front)}
    for n, v in p.items():
        if not np.all(np.isfinite(v)):
            raise InputError(f"missing at the reference frame {reference}",
                             source=ms.meta.get("source"), field=n)
    basis = basis_from_points(p[right], p[left], p[front])
    o = p[origin or front]
    out = (ms.positions - o) @ basis.T
    return ms.with_positions(out, meta={**ms.meta, "frame": {"right": right, "left": left,
                                                            "front": front,
                                                            "origin": origin or front}})


def align_to_model(ms: MarkerSet, targets: dict[str, np.ndarray], *,
                   reference: int = 0) -> tuple[MarkerSet, float]:
    """Rigidly move markers so that the named ones sit best on model positions (metres).

    Returns the moved marker set and the RMS fit residual (m) at the reference frame.
    """
    names = [n for n in targets if n in ms.names]
    if len(names) < 3:
        raise InputError("aligning to the model needs at least 3 mapped markers",
                         field="mapping")
    src = np.array([ms.marker(n)[reference] for n in names])
    dst = np.array([targets[n] for n in names])
    good = np.all(np.isfinite(src), axis=1)
    if good.sum() < 3:
        raise InputError(f"fewer than 3 mapped markers present at frame {reference}",
                         field="reference")
    r, t = rigid_fit(src[good], dst[good])
    res = float(np.sqrt(np.mean(np.sum((src[good] @ r.T + t - dst[good]) ** 2, axis=1))))
    return ms.with_positions(ms.positions @ r.T + t), res
