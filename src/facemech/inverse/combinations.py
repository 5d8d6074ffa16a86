"""The combinations of controls that markers determine, when they cannot determine each control.

Two midsagittal lip sensors give 4 coordinates a frame; 5 controls moving them leave one
direction of the controls unseen, so no single control is fixed by the data, but 4
combinations are. The markers' step responses S (coordinates, controls; mm per unit,
:func:`facemech.inverse.uncertainty.step_responses`) are factorised by QR with column pivoting,
``S P = Q R`` (Businger & Golub 1965), the jaw, when estimated, taken first as in the control
pick (:mod:`facemech.inverse.control_pick`). The rotated data ``Q^T d = R P^T c + Q^T e`` are
independent measurements, each with the markers' noise sigma (mm), of the rows of ``R``: row k,
divided by ``R_kk``, is the combination

    c_(k) + sum_{j > k} (R_kj / R_kk) c_(j),      SE = sigma / |R_kk|,

of the k-th control in pivot order and those after it. A combination is *determined* when its
SE at ``max(sigma, NOISE_FLOOR_MM)`` is at most :data:`~facemech.inverse.uncertainty
.IDENTIFIABLE_SE`: at the noise floor exactly the rows whose ``|R_kk|`` passes the control
pick's :data:`~facemech.inverse.control_pick.MIN_NEW_MOTION_MM`, so the pick and this report
agree by construction. Controls that lead no determined combination follow the
regularisation, not the data. With as many independent coordinates as controls each
combination's leading control is fixed as well (the single controls are then determined).
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from . import uncertainty as U

__all__ = ["Combination", "combination_lines", "determined_combinations"]

#: weights smaller than this (relative to the leading control's 1) are left out of the names
SHOWN_WEIGHT = 0.05


@dataclass(frozen=True)
class Combination:
    """One combination of controls the markers measure.

    Attributes
    ----------
    lead : the leading control (weight 1)
    weights : control -> weight (the lead's 1 first, then the others in pivot order)
    motion_mm : ``|R_kk|``, mm of marker motion per unit of the combination
    """

    lead: str
    weights: dict
    motion_mm: float

    def se(self, sigma_mm: float) -> float:
        """Standard error (control units) at marker noise ``sigma_mm`` (mm per coordinate)."""
        return float(sigma_mm) / self.motion_mm if self.motion_mm > 0 else float("inf")

    def determined(self, sigma_mm: float) -> bool:
        """SE at ``max(sigma, NOISE_FLOOR_MM)`` within ``IDENTIFIABLE_SE``."""
        s = max(float(sigma_mm), U.NOISE_FLOOR_MM) if np.isfinite(sigma_mm) else U.NOISE_FLOOR_MM
        return self.se(s) <= U.IDENTIFIABLE_SE * (1 + 1e-9)

    @property
    def name(self) -> str:
        """E.g. ``DLI + 0.31 MEN - 0.12 OOS`` (weights under :data:`SHOWN_WEIGHT` left out)."""
        out = self.lead
        for c, w in self.weights.items():
            if c != self.lead and abs(w) >= SHOWN_WEIGHT:
                out += f" {'-' if w < 0 else '+'} {abs(w):.2f} {c}"
        return out

    def of(self, controls: np.ndarray, names) -> np.ndarray:
        """The combination's value per frame from ``controls`` (frames, c) named ``names``."""
        idx = {n: j for j, n in enumerate(names)}
        return sum(w * np.asarray(controls)[:, idx[c]] for c, w in self.weights.items())


def determined_combinations(s: np.ndarray, names, *, first=()) -> list[Combination]:
    """The combinations measured by the markers, in pivot order (see the module doc).

    Parameters
    ----------
    s : (coordinates, controls) step responses, mm per unit
    names : (controls,) control names
    first : names taken first, unpivoted (the estimated jaw)

    Returns
    -------
    list of Combination, one per independent row of ``R`` (``|R_kk|`` above 1e-9 of the
    largest), the most marker motion first within the pivoted part
    """
    s = np.asarray(s, float)
    names = list(names)
    lead = [names.index(n) for n in first if n in names]
    rest = [j for j in range(len(names)) if j not in lead]
    rows, order = [], list(lead)
    resid = s
    if lead:
        q1, r1 = np.linalg.qr(s[:, lead])
        rows.append(q1.T @ s)
        resid = s - q1 @ (q1.T @ s)
    if rest:
        _, r, perm = sla.qr(resid[:, rest], mode="economic", pivoting=True)
        order += [rest[j] for j in perm]
        full = np.zeros((r.shape[0], s.shape[1]))
        full[:, [rest[j] for j in perm]] = r
        rows.append(full)
    big = np.vstack(rows) if rows else np.zeros((0, s.shape[1]))
    diag = np.array([big[k, order[k]] for k in range(min(len(big), len(order)))])
    top = np.abs(diag).max(initial=0.0)
    out = []
    for k, d in enumerate(diag):
        if abs(d) <= 1e-9 * top or top == 0:
            continue
        w = {names[order[k]]: 1.0}
        for j in order[k + 1:]:
            w[names[j]] = float(big[k, j] / d)
        out.append(Combination(names[order[k]], w, float(abs(d))))
    return out


def combination_lines(combos, controls, names, sigma_mm: float) -> list[str]:
    """Per combination: its name, its value over the frames (mean, range) and SE at
    ``sigma_mm``, and whether it is determined."""
    lines = []
    for c in combos:
        v = c.of(controls, names)
        lines.append(f"{c.name}: mean {np.mean(v):.2f} ({np.min(v):.2f} to {np.max(v):.2f}), "
                     f"SE {c.se(max(sigma_mm, U.NOISE_FLOOR_MM)):.2f}"
                     f"{'' if c.determined(sigma_mm) else ' (not within 0.1 at this noise)'}")
    return lines


def to_json(combos) -> str:
    """The combinations as JSON (the results' ``combinations`` attribute)."""
    return json.dumps([{"lead": c.lead, "weights": c.weights, "motion_mm": c.motion_mm}
                       for c in combos])


def from_json(text: str) -> list[Combination]:
    """The combinations from :func:`to_json`'s text."""
    return [Combination(r["lead"], dict(r["weights"]), float(r["motion_mm"]))
            for r in json.loads(text)]
