"""The controls a set of markers determines, picked when they cannot determine the default set.

Two lip sensors of midsagittal articulography give 4 coordinates per frame; three markers give
9; the default controls are 9 muscle groups, and the jaw when it is estimated. A frame's fit
cannot determine more controls than it has coordinates, so the default set is cut down to the
controls these markers determine best, and the rest are held at rest (a muscle at 0, the jaw at
its first pose).

The markers' step responses S (coordinates, controls), each control held at 0.2 for 100 ms
from rest (:func:`facemech.inverse.uncertainty.step_responses`, mm per unit; the responses that
judge identifiability), are factorised by QR with column pivoting, ``S P = Q R`` (Businger &
Golub 1965; the method of the marker regions, Lucero & Munhall 2008,
:mod:`facemech.analysis.regions`). The pivot order takes first the control that moves the
markers most, then at each step the one that adds the most motion the controls already taken
cannot make; ``|R_kk|`` is that new motion (mm per unit). Controls are taken in that order
while ``|R_kk|`` is at least :data:`MIN_NEW_MOTION_MM` (the identifiability threshold of
:mod:`~facemech.inverse.uncertainty`: at 0.1 mm of marker noise such a control is fixed to a
tenth of full activity), and no more than there are coordinates. An estimated jaw that moves
the markers at least that much is taken first, whatever the muscles could mimic of it: it is
the largest mover of the face in speech, and the inversion never leaves it silently at rest.

The pick depends on the markers' places and the model, not on the recording: every utterance
of one sensor layout is inverted with the same controls. For two lip points it takes, for each
lip, the strongest muscle each way (on the current anatomical preset: LLS, DLI, OOS, OOI).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError
from . import uncertainty as U

__all__ = ["MIN_NEW_MOTION_MM", "ControlPick", "pick_controls", "step_response_matrix"]

#: mm per unit of control: the least new marker motion of a kept control
MIN_NEW_MOTION_MM = U.NOISE_FLOOR_MM / U.IDENTIFIABLE_SE


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
    """

    muscles: tuple[str, ...]
    jaw: bool
    held: tuple[str, ...]
    order: tuple[str, ...]
    new_motion: dict
    coordinates: int

    def note(self, n_markers: int, midsagittal: bool = False) -> str:
        """One line: what was kept and held, and why."""
        k = len(self.order)
        axes = " (y and z: midsagittal)" if midsagittal else ""
        kept = ", ".join(f"{c} {self.new_motion[c]:.1f}" for c in self.order)
        held = ", ".join(f"{c} {self.new_motion[c]:.1f}" for c in self.held)
        why = ("the kept span every coordinate, so each of these moves the markers only as a "
               "combination of them" if k == self.coordinates else
               f"each of these adds less than {MIN_NEW_MOTION_MM:.0f} mm per unit to them")
        return (f"controls: {n_markers} markers give {self.coordinates} coordinates{axes} for "
                f"the {k + len(self.held)} candidate controls (the default set, and "
                f"orbicularis oris's marginal part where the face has it); kept the {k} they "
                f"determine best "
                f"(QR with column pivoting of their 100-ms step responses; new marker motion, "
                f"mm per unit): {kept}; held at rest: {held} ({why})")


def step_response_matrix(face, params, nodes, gmat, *, estimate_jaw: bool,
                         jaw_start=(0.0, 0.0, 0.0), dt: float | None = None) -> np.ndarray:
    """Step responses (3 markers, controls), mm per unit, from rest at the jaw's first pose
    (:func:`facemech.inverse.uncertainty.step_responses`): the muscle controls ``gmat``
    (groups, controls) and, with ``estimate_jaw``, the jaw angle in units of
    :data:`~facemech.inverse.frame.JAW_UNIT` rad; a jaw that is not estimated is held at
    ``jaw_start`` (angle rad, shift_y m, shift_z m)."""
    from ..physics.assembly import Physics
    from ..solvers.forward import single_threaded_blas
    from ..solvers.state import State
    from ..solvers.step import Stepper
    from .frame import JAW_UNIT

    physics = Physics.build(face, params)
    stepper = Stepper(physics, dt=params.fast_dt if dt is None else dt)
    nm = gmat.shape[1]
    start = np.asarray(jaw_start, float)

    def advance(state, c):
        jaw = c[nm] * JAW_UNIT + start[0] if estimate_jaw else start
        return stepper.advance(state, gmat @ c[:nm], jaw)

    rest = State.at_rest(physics.model.rest_positions, physics.n_muscles, float(start[0]),
                         jaw_shift=start[1:])
    with single_threaded_blas():
        return U.step_responses(advance, rest, np.asarray(nodes), nm + (1 if estimate_jaw else 0))


def pick_controls(face, params, nodes, candidates, *, estimate_jaw: bool,
                  jaw_start=(0.0, 0.0, 0.0), axes=(0, 1, 2), dt: float | None = None,
                  responses: np.ndarray | None = None) -> ControlPick:
    """Pick the controls that markers at ``nodes`` determine (see the module doc).

    Parameters
    ----------
    face : FaceModel
    params : Parameters (the inversion's preset)
    nodes : (markers,) epidermal nodes of the markers
    candidates : muscle groups to pick from (the default set), or ``"speech"``
    estimate_jaw : the jaw is a candidate (estimated as one more control)
    jaw_start : (3,) the jaw's first pose (angle rad, shift_y m, shift_z m), where the
        responses start and where a jaw that is not estimated is held
    axes : the coordinates the fit uses (``(1, 2)``: midsagittal data)
    dt : the inversion's step (s; None: the preset's ``fast_dt``)
    responses : (3 markers, controls) step responses, mm per unit, instead of simulating them
        (:func:`step_response_matrix`)

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
    s = (step_response_matrix(face, params, nodes, gmat, estimate_jaw=estimate_jaw,
                              jaw_start=jaw_start, dt=dt)
         if responses is None else np.asarray(responses, float))
    s = s.reshape(len(nodes), 3, len(cols))[:, list(axes)].reshape(-1, len(cols))
    coords = s.shape[0]
    first: list[int] = []
    rest = s
    jaw = len(names)
    if estimate_jaw and np.linalg.norm(s[:, jaw]) >= MIN_NEW_MOTION_MM:
        # the jaw first, whatever the muscles could mimic of it: it moves the face most in
        # speech, and a jaw held at rest would be a silent error (see inverse.invert)
        first = [jaw]
        u = s[:, jaw] / np.linalg.norm(s[:, jaw])
        rest = s - np.outer(u, u @ s)
    muscles = np.arange(len(names))
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
    return ControlPick(muscles=tuple(c for j, c in enumerate(names) if j in kept),
                       jaw=estimate_jaw and len(names) in kept,
                       held=tuple(c for j, c in enumerate(cols) if j not in kept),
                       order=tuple(cols[j] for j in kept), new_motion=new, coordinates=coords)
