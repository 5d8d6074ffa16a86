"""The controls a set of markers determines, picked when they cannot determine the default set.

A frame's fit cannot determine more controls than its markers have coordinates (two
midsagittal lip sensors: 4), so the default set (9 muscle groups, and the jaw when estimated)
is cut down to the controls that move the markers in the most independent ways; the rest are
held at rest. The markers' step responses S (coordinates, controls; each control held at 0.2
for 100 ms, :func:`facemech.inverse.uncertainty.step_responses`, mm per unit) are factorised by
QR with column pivoting, ``S P = Q R`` (Businger & Golub 1965); controls are taken in pivot
order while the new motion ``|R_kk|`` is at least :data:`MIN_NEW_MOTION_MM`, an estimated jaw
that moves the markers that much first. Activity is bounded to [0, 1], so the pick is then
completed for sign (:func:`cover_signs`): each coordinate some candidate moves each way must be
moved each way by a kept control (by :data:`COVER_SHARE` of the most any candidate does), the
coordinate-wise form of a positive spanning set (Davis 1954; Kolda, Lewis & Torczon 2003).
At most 3 controls per marker; the pick depends on the layout and the model, not on the
recording. The method and the measured table: docs/inversion.md, "Controls the markers determine".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError
from . import uncertainty as U

__all__ = ["MIN_NEW_MOTION_MM", "ControlPick", "cover_signs", "pick_controls",
           "signed_motion", "step_response_matrix"]

#: mm per unit of control: the least new marker motion of a kept control
MIN_NEW_MOTION_MM = U.NOISE_FLOOR_MM / U.IDENTIFIABLE_SE

#: the least share of the best candidate's motion along a signed coordinate that a kept control
#: must make to cover it (:func:`cover_signs`). A kept control that moves a coordinate a little
#: that way (over the 1-mm threshold) reaches it only near full activity and with its own large
#: motions elsewhere, which the bounded fit cannot cancel: with the contacts stepped on their own
#: OOS lifts the lower lip 1.3 mm per unit beside 4.0 mm of the upper lip forward,
#: while mentalis lifts it 3.1 mm; counting OOS as the lifter left a twin of closing lips 0.38 mm
#: RMS off (tests/inverse/test_control_pick.py). Half: the weaker of two comparable movers
#: still counts.
COVER_SHARE = 0.5


@dataclass(frozen=True)
class ControlPick:
    """Controls picked for a set of markers.

    Attributes
    ----------
    muscles : the muscle controls kept, in the candidates' order
    jaw : whether the estimated jaw is kept (False also when it was not a candidate)
    held : the candidates held at rest, in the candidates' order
    order : the kept controls in pivot order
    new_motion : control -> mm per unit: for a kept control, the motion it adds to those
        before it in pivot order (``|R_kk|``); for a held one, what it adds to all the kept
    coordinates : coordinates per frame the markers give
    for_sign : (control, signed coordinates it was added for, their motion mm per unit) of the
        controls the sign step added, in the order added (part of ``order``, after the rank's)
    one_way : (signed coordinate, best candidate, its motion mm per unit) of the coordinates
        every candidate moves one way only (by :data:`MIN_NEW_MOTION_MM` per unit); empty when
        each coordinate the candidates move is moved both ways by the kept
    """

    muscles: tuple[str, ...]
    jaw: bool
    held: tuple[str, ...]
    order: tuple[str, ...]
    new_motion: dict
    coordinates: int
    for_sign: tuple = ()
    one_way: tuple = ()

    def note(self, n_markers: int, midsagittal: bool = False) -> str:
        """One line: what was kept and held, and why."""
        k = len(self.order)
        signed = [c for c, _, _ in self.for_sign]
        rank = [c for c in self.order if c not in signed]
        axes = " (y and z: midsagittal)" if midsagittal else ""
        kept = ", ".join(f"{c} {self.new_motion[c]:.1f}" for c in rank)
        held = ", ".join(f"{c} {self.new_motion[c]:.1f}" for c in self.held)
        why = ("the kept span every coordinate, so each of these moves the markers only as a "
               "combination of them" if len(rank) == self.coordinates else
               f"each of these adds less than {MIN_NEW_MOTION_MM:.0f} mm per unit to them")
        sign = ""
        if self.for_sign:
            added = ", ".join(
                f"{c} ({', '.join(f'{d} {v:.1f}' for d, v in zip(dirs, mm, strict=True))})"
                for c, dirs, mm in self.for_sign)
            sign = (f"; and, as activity only pulls, for a coordinate those move one way only "
                    f"(motion that way, mm per unit): {added}")
        one = ""
        if self.one_way:
            one = (f"; no candidate moves {MIN_NEW_MOTION_MM:.0f} mm per unit (the best, mm per "
                   "unit): " + ", ".join(f"{d} ({c} {m:.1f})" for d, c, m in self.one_way))
        return (f"controls: {n_markers} markers give {self.coordinates} coordinates{axes} for "
                f"the {k + len(self.held)} candidate controls (the default set, and "
                f"orbicularis oris's marginal part where the face has it); kept {k}: the "
                f"{len(rank)} that move them in the most independent ways, each adding at least "
                f"{MIN_NEW_MOTION_MM:.0f} mm per unit to those before it, so that the markers "
                f"determine {len(rank)} combinations of the kept (QR with column pivoting of "
                f"their 100-ms step responses; new marker motion, mm per unit): "
                f"{kept}{sign}{one}; held at rest: {held} ({why})")


def step_response_matrix(model, nodes, gmat, *, estimate_jaw: bool,
                         jaw_start=(0.0, 0.0, 0.0), dt: float | None = None) -> np.ndarray:
    """Step responses (3 markers, controls), mm per unit, from rest at the jaw's first pose
    (:func:`facemech.inverse.uncertainty.step_responses`): the muscle controls ``gmat``
    (groups, controls) and, with ``estimate_jaw``, the jaw angle in units of
    :data:`~facemech.inverse.frame.JAW_UNIT` rad; a jaw that is not estimated is held at
    ``jaw_start`` (angle rad, shift_y m, shift_z m). ``model``: a
    :class:`~facemech.physics.model.Model`."""
    from ..solvers.forward import single_threaded_blas
    from ..solvers.state import State
    from ..solvers.step import Stepper
    from .frame import JAW_UNIT

    physics = model.physics
    stepper = Stepper(model, dt=model.steps.fast_dt if dt is None else dt)
    nm = gmat.shape[1]
    start = np.asarray(jaw_start, float)

    def advance(state, c):
        jaw = c[nm] * JAW_UNIT + start[0] if estimate_jaw else start
        return stepper.advance(state, gmat @ c[:nm], jaw)

    rest = State.at_rest(physics.model.rest_positions, physics.n_muscles, float(start[0]),
                         jaw_shift=start[1:])
    with single_threaded_blas():
        return U.step_responses(advance, rest, np.asarray(nodes), nm + (1 if estimate_jaw else 0))


def signed_motion(s: np.ndarray, two_way=()) -> np.ndarray:
    """Motion of each signed coordinate under each control (2 coordinates, controls), mm per
    unit, >= 0: row ``2 i`` is how far a control moves coordinate ``i`` up (``s[i] > 0``), row
    ``2 i + 1`` how far down; the controls in ``two_way`` (indices: the jaw) move both ways.

    Parameters
    ----------
    s : (coordinates, controls) step responses, mm per unit
    two_way : columns whose control is bounded on both sides of its start
    """
    s = np.asarray(s, float)
    up, down = np.maximum(s, 0.0), np.maximum(-s, 0.0)
    for j in two_way:
        up[:, j] = down[:, j] = np.abs(s[:, j])
    out = np.empty((2 * s.shape[0], s.shape[1]))
    out[0::2], out[1::2] = up, down
    return out


def cover_signs(s: np.ndarray, kept, *, two_way=(), limit: int | None = None,
                threshold: float = MIN_NEW_MOTION_MM,
                share: float = COVER_SHARE) -> tuple[list, list, list]:
    """Complete a pick so that every two-way coordinate is moved each way by a kept control.

    A signed coordinate is *covered* by a control that moves it that way at least ``threshold``
    (mm per unit) and at least ``share`` of the most any candidate moves it that way; a
    coordinate is *two-way* when the candidates cover both of its signs.
    While a signed coordinate of a two-way coordinate is not covered by the kept, the candidate
    covering the most such signed coordinates is added (ties: the largest summed motion on
    them, then the first column). Greedy set cover (Chvatal 1979: within a factor
    ``1 + ln(2 coordinates)`` of the fewest controls).

    Parameters
    ----------
    s : (coordinates, controls) step responses, mm per unit
    kept : columns already kept (the rank's pick)
    two_way : columns moving both ways (:func:`signed_motion`)
    limit : the most columns kept in all (None: no limit)
    threshold : mm per unit
    share : the least share of the best candidate's motion that covers (see
        :data:`COVER_SHARE`)

    Returns
    -------
    added : the columns added, in order
    covers : for each added column, the signed-coordinate rows it was added for
    one_way : signed-coordinate rows no candidate covers whose opposite a candidate covers
    """
    m = signed_motion(s, two_way)
    # a signed coordinate is covered by a control moving it at least the threshold and at
    # least ``share`` of what the best candidate moves it that way
    best_motion = m.max(axis=1, keepdims=True) if m.size else m
    can = m >= np.maximum(threshold, share * best_motion)
    coverable = can.any(axis=1)
    opposite = coverable.reshape(-1, 2)[:, ::-1].ravel()
    want = coverable & opposite  # the signed coordinates of the two-way coordinates
    kept = list(kept)
    added, covers = [], []
    while limit is None or len(kept) < limit:
        open_ = want & ~can[:, kept].any(axis=1) if kept else want.copy()
        if not open_.any():
            break
        gain = can[open_].sum(axis=0)
        gain[kept] = 0
        if gain.max() == 0:
            break
        score = np.where(gain == gain.max(), np.where(can, m, 0.0)[open_].sum(axis=0), -1.0)
        best = int(np.argmax(score))
        kept.append(best)
        added.append(best)
        covers.append([int(i) for i in np.flatnonzero(open_ & can[:, best])])
    one_way = [int(i) for i in np.flatnonzero(~coverable & opposite)]
    return added, covers, one_way


def _rank_pick(s, cols, n_muscles: int, estimate_jaw: bool) -> tuple[list[int], dict]:
    """The rank step on the step responses ``s`` (coordinates, controls): the jaw first where
    it moves the markers, then the muscles by QR with column pivoting, each kept while it adds
    at least :data:`MIN_NEW_MOTION_MM` per unit; (the kept columns, each control's new motion,
    mm per unit, beyond the kept ones)."""
    coords = s.shape[0]
    first: list[int] = []
    rest = s
    jaw = n_muscles
    if estimate_jaw and np.linalg.norm(s[:, jaw]) >= MIN_NEW_MOTION_MM:
        # the jaw first, whatever the muscles could mimic of it: it moves the face most in
        # speech, and a jaw held at rest would be a silent error (see inverse.invert)
        first = [jaw]
        u = s[:, jaw] / np.linalg.norm(s[:, jaw])
        rest = s - np.outer(u, u @ s)
    muscles = np.arange(n_muscles)
    _, r, perm = sla.qr(rest[:, muscles], mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    k = int(min(coords - len(first), np.sum(diag >= MIN_NEW_MOTION_MM)))
    if k + len(first) == 0:
        raise InputError(f"the markers move less than {MIN_NEW_MOTION_MM:.0f} mm per unit of "
                         "every control: nothing to invert", field="markers")
    kept = first + [int(muscles[j]) for j in perm[:k]]
    new = {cols[j]: float(diag[i]) for i, j in enumerate(kept[len(first):])}
    if first:
        new["jaw"] = float(np.linalg.norm(s[:, jaw]))
    q, _ = np.linalg.qr(s[:, kept])
    for j in (j for j in range(len(cols)) if j not in kept):
        new[cols[j]] = float(np.linalg.norm(s[:, j] - q @ (q.T @ s[:, j])))
    return kept, new


def pick_controls(model, nodes, candidates, *, estimate_jaw: bool,
                  jaw_start=(0.0, 0.0, 0.0), axes=(0, 1, 2), dt: float | None = None,
                  responses: np.ndarray | None = None, labels=None) -> ControlPick:
    """Pick the controls that markers at ``nodes`` determine (see the module doc).

    Parameters
    ----------
    model : Model -- the face and the inversion's preset (:func:`facemech.physics.model.model`);
        None with ``responses``
    nodes : (markers,) epidermal nodes of the markers
    candidates : muscle groups to pick from (the default set), or ``"speech"``
    estimate_jaw : the jaw is a candidate (estimated as one more control)
    jaw_start : (3,) the jaw's first pose (angle rad, shift_y m, shift_z m), where the
        responses start and where a jaw that is not estimated is held
    axes : the coordinates the fit uses (``(1, 2)``: midsagittal data)
    dt : the inversion's step (s; None: the preset's ``fast_dt``)
    responses : (3 markers, controls) step responses, mm per unit, instead of simulating them
        (:func:`step_response_matrix`)
    labels : (markers,) the markers' names, for the note (None: "marker 1", ...)

    Returns
    -------
    ControlPick

    Raises
    ------
    InputError
        When the markers move less than :data:`MIN_NEW_MOTION_MM` per unit of every control.
    """
    from .invert import control_matrix

    names, gmat = control_matrix(candidates)
    cols = list(names) + (["jaw"] if estimate_jaw else [])
    nodes = np.asarray(nodes)
    s = (step_response_matrix(model, nodes, gmat, estimate_jaw=estimate_jaw,
                              jaw_start=jaw_start, dt=dt)
         if responses is None else np.asarray(responses, float))
    s = s.reshape(len(nodes), 3, len(cols))[:, list(axes)].reshape(-1, len(cols))
    kept, new = _rank_pick(s, cols, len(names), estimate_jaw)
    # the sign step: what the rank kept moves some coordinates one way only
    jaw = len(names)
    coords = s.shape[0]
    added, covers, one_way = cover_signs(s, kept, two_way=[jaw] if estimate_jaw else [],
                                         limit=3 * len(nodes))
    kept += added
    m = signed_motion(s, [jaw] if estimate_jaw else [])
    names_ = labels if labels is not None else [f"marker {i + 1}" for i in range(len(nodes))]
    coord = [f"{names_[i // len(axes)]} {'xyz'[axes[i % len(axes)]]}" for i in range(coords)]

    def signed(row):
        return coord[row // 2] + ("+" if row % 2 == 0 else "-")

    for_sign = tuple((cols[j], tuple(signed(r) for r in rows),
                      tuple(float(m[r, j]) for r in rows))
                     for j, rows in zip(added, covers, strict=True))
    one = tuple((signed(r), cols[int(np.argmax(m[r]))], float(m[r].max())) for r in one_way)
    return ControlPick(muscles=tuple(c for j, c in enumerate(names) if j in kept),
                       jaw=estimate_jaw and len(names) in kept,
                       held=tuple(c for j, c in enumerate(cols) if j not in kept),
                       order=tuple(cols[j] for j in kept), new_motion=new, coordinates=coords,
                       for_sign=for_sign, one_way=one)
