"""What an inversion's notes say of the controls the markers determine and of those at full
activity (the words of :mod:`facemech.inverse.combinations` and of the activity's bounds)."""

from __future__ import annotations

import numpy as np

from . import uncertainty as U
from .combinations import combination_lines

__all__ = ["FULL_ACTIVITY", "FULL_SHARE", "full_activity_notes", "identifiability_notes",
           "regularised"]

#: activity at or above this counts as full (the bound 1, within the solver's tolerance)
FULL_ACTIVITY = 0.99
#: share of the frames at full activity above which a control gets a note
FULL_SHARE = 0.10


def regularised(combos, seen, names) -> list[str]:
    """The controls the data do not fix: those not determined alone (``seen`` False) that
    lead no combination, then those that lead one but are not determined alone."""
    leads = {c.lead for c in combos}
    alone = [n for n, ok in zip(names, seen, strict=True) if not ok]
    return [n for n in alone if n not in leads] + [n for n in alone if n in leads]


def identifiability_notes(combos, seen, controls, names, sigma_mm) -> list[str]:
    """The note on what the markers determine: nothing when each control is determined alone;
    else the combinations they measure (value and SE) and the controls left to the
    regularisation."""
    if all(seen):
        return []
    lines = combination_lines(combos, controls, names, sigma_mm)
    leads = {c.lead for c in combos}
    none = [n for n in names if n not in leads]
    det = [c.name for c in combos if c.determined(sigma_mm)]
    alone = [n for n, ok in zip(names, seen, strict=True) if ok]
    s = max(float(sigma_mm), U.NOISE_FLOOR_MM) if np.isfinite(sigma_mm) else U.NOISE_FLOOR_MM
    return [f"determined by these markers: {len(combos)} combinations of the {len(names)} "
            f"controls (QR with column pivoting of their 100-ms step responses; mean, range and "
            f"standard error at {s:.2f} mm of noise): {'; '.join(lines)}; within "
            f"{U.IDENTIFIABLE_SE:g} at this noise: {', '.join(det) or 'none'}; single controls "
            f"determined: {', '.join(alone) or 'none'}; regularised (their values follow the "
            f"regularisation, not the data): {', '.join(n for n in names if n not in alone)}"
            + (f" ({', '.join(none)} in no combination but as a follower)" if none else "")]


def full_activity_notes(controls: np.ndarray, names) -> list[str]:
    """A note per muscle control at full activity in more than :data:`FULL_SHARE` of the
    frames (``controls`` (frames, muscle controls))."""
    out = []
    controls = np.asarray(controls)
    for j, n in enumerate(names):
        share = float(np.mean(controls[:, j] >= FULL_ACTIVITY)) if len(controls) else 0.0
        if share > FULL_SHARE:
            out.append(f"{n} at full activity (>= {FULL_ACTIVITY}) in {100 * share:.0f} % of the "
                       "frames: the model lacks the reach to follow the markers there, and this "
                       "activity is not a measurement")
    return out
