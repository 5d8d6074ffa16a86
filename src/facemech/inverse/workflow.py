"""Inversion of a marker set on a face, as the ``invert`` command runs it: map, adapt, drive
the jaw, choose the controls, invert (:func:`invert_marker_set`). Reading the marker file, the
face and the map file is the command's wiring: :func:`facemech.workflows.invert.invert_markers`.

Markers are skin markers unless they are named (or, from articulography, given the role) of a
point on the mandible: a lower-incisor sensor and, optionally, a molar pellet. Those drive the
jaw (:func:`facemech.jaw.drive.jaw_drive`) and stay out of the skin's cost. Articulography's lip
sensors are laid on the face's midsagittal vermilion points (:mod:`facemech.kinematics.roles`),
and midsagittal data are fitted in y and z only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..jaw.drive import SKIN_JAW_LEAD, default_lead, jaw_drive
from ..jaw.inputs import JawMarkers
from ..markerset import MarkerSet
from .options import FitOptions, InversionOptions, as_options, inversion_options
from .result import Inversion

if TYPE_CHECKING:
    from ..physics.model import Model

__all__ = ["SKIN_JAW_LEAD", "SIGN_EFFORT", "JawMarkers", "invert_marker_set", "pick_candidates"]

#: s, the longest interior gap of an articulograph's bone point filled before the jaw's drive
MAX_BONE_GAP_S = 0.1



def invert_marker_set(
    ms: MarkerSet,
    model: Model,
    *,
    mapping: dict[str, int] | None = None,
    scale_pair: str | None = None,
    jaw: JawMarkers | None = None,
    inversion: InversionOptions | None = None,
    options: FitOptions | dict | None = None,
    progress: Callable[[int, int], None] | None = None,
    **given,
) -> Inversion:
    """Invert a marker set on a face (see :func:`facemech.inverse.invert.invert`).

    Parameters
    ----------
    ms : the markers (m) in the model's frame, at the preset's frame rate; articulography
        (``meta["roles"]``) in its own frame and at its own rate: its lips are laid on the
        face's vermilion points, and it is resampled
    model : Model -- the face, its parameters and physics (:func:`facemech.physics.model.model`);
        its method's ``fast_dt`` is the explicit Euler step of every evaluation (s)
    mapping : marker name -> node (:func:`facemech.kinematics.mapping.read_mapping`; None: the
        closest nodes, articulography's lips their vermilion points)
    scale_pair : "A,B": adapt the markers by per-axis scaling from two markers far apart
    jaw : the jaw's markers (:class:`JawMarkers`; None: none given, the sensors of roles
        ``lower_incisor`` and ``molar`` where the markers have them)
    inversion : the method, ``positive``, ``controls`` and ``noise``
        (:class:`~facemech.inverse.options.InversionOptions`; None: the defaults; ``given``:
        any of them as keywords). Controls the markers give fewer coordinates for are an
        error; None: "speech", or the part of it the markers determine
        (:mod:`facemech.inverse.control_pick`; when its sign step adds controls, ``effort`` is
        :data:`SIGN_EFFORT` unless given)
    options : the method's options (:class:`~facemech.inverse.options.FitOptions` or a dict;
        None: not given; an option of the other method is an error)
    progress : callable(done, total)

    Returns
    -------
    Inversion
        Its notes also say how articulography roles were used and which controls were held.
    """
    from ..kinematics.mapping import scale_adapt
    from ..kinematics.roles import is_midsagittal
    from .invert import JawRecording, invert
    from .methods import method_from_options

    inv, options = inversion_options(inversion, given), as_options(options)
    solver = method_from_options(inv.method, **options)
    jaw = jaw or JawMarkers()
    src = ms.meta.get("source")
    ms, names, by_role, notes = _jaw_points(ms, jaw, model.params.frame_rate)
    bone = (names.jaw_incisor, names.jaw_molar)
    midsagittal = is_midsagittal(ms)
    skin, mapping, more = _skin_markers(ms, model.face, mapping, bone, midsagittal)
    notes += more
    if scale_pair is not None:
        a, _, b = scale_pair.partition(",")
        skin = scale_adapt(skin, model.face, mapping, (a.strip(), b.strip())).markers
    drive, jaw_source = jaw_drive({n: ms.marker(n) for n in ms.names}, model, names,
                                  lead=default_lead(jaw, bone[0] is not None),
                                  chin_node=mapping.get(jaw.chin_marker), source=src,
                                  by_role=by_role)
    estimate = None if drive is None else (not jaw.jaw_fixed and drive.ndim == 1)
    ctrl, drive, estimate, jaw_source, pick_note, signed = _controls(
        inv.controls, model, skin, mapping, drive, estimate, jaw_source, midsagittal, src)
    solver, pick_note = _picked_fit(solver, options, pick_note, signed)
    res = invert(model, skin, mapping, method=solver, positive=inv.positive, controls=ctrl,
                 jaw_angle=JawRecording(drive, estimate, jaw_source), noise_mm=inv.noise,
                 progress=progress)
    return replace(res, notes=[*res.notes, *notes, *([pick_note] if pick_note else [])])


def _jaw_points(ms, jaw, rate):
    """(the set at the model's frame ``rate`` with its bone points' short gaps filled, the
    jaw's markers with its bone points named, whether they were found by role, notes): the
    bone points named, else found by their articulography roles, a lost molar left out."""
    from ..kinematics.roles import bone_points

    incisor, molar, by_role = bone_points(ms, incisor=jaw.jaw_incisor, molar=jaw.jaw_molar,
                                          skin_jaw=jaw.chin_marker)
    molar, dropped = _usable_molar(ms, molar, by_role)
    ms, resampled = _at_frame_rate(ms, rate)
    ms, filled = _bone_gaps_filled(ms, (incisor, molar), by_role)
    if jaw.jaw_fixed and jaw.chin_marker is None and incisor is None:
        raise InputError("--jaw-fixed needs a jaw recording (--chin-marker or --jaw-incisor)",
                         field="jaw-fixed")
    return (ms, replace(jaw, jaw_incisor=incisor, jaw_molar=molar), by_role,
            resampled + dropped + filled)


def _picked_fit(solver, options, pick_note, signed):
    """(the method, the pick's note): when controls were picked, the fit is paced and, when
    the pick's sign step added controls, weighs effort (:func:`_effort_for_sign`,
    :func:`_pace_for_pick`)."""
    if signed:
        solver, effort_note = _effort_for_sign(solver, options)
        pick_note += effort_note
    if pick_note:
        solver, pace_note = _pace_for_pick(solver, options)
        pick_note += pace_note
    return solver, pick_note


def _at_frame_rate(ms, rate):
    """(the set at the model's frame ``rate``, a note if it was resampled): articulography
    (sensors with roles, recorded at 100-500 Hz) is resampled with anti-aliasing
    (:func:`facemech.kinematics.resample.resample`); other data must come at the rate."""
    from ..kinematics.resample import resample
    from ..kinematics.roles import marker_roles

    if abs(ms.rate - rate) <= 1e-3 * rate or not marker_roles(ms):
        return ms, []
    return resample(ms, rate), [f"articulography at {ms.rate:g} Hz resampled to {rate:g} Hz "
                                "(low-passed, cubic spline)"]


def _usable_molar(ms, molar, by_role):
    """(the molar or None, a note): a molar pellet found by its role is left out when it has a
    gap longer than :data:`MAX_BONE_GAP_S` (X-ray microbeam's molar pellet is often lost for
    whole recordings): the jaw then comes from the incisor alone. A molar named by the user
    is kept, and its gaps are refused by the drive."""
    if not by_role or molar is None:
        return molar, []
    valid = ms.valid[:, ms.index(molar)]
    longest = run = 0
    for ok in valid:
        run = 0 if ok else run + 1
        longest = max(longest, run)
    if longest <= int(MAX_BONE_GAP_S * ms.rate):
        return molar, []
    return None, [f"molar pellet {molar} left out ({int((~valid).sum())} of {len(valid)} "
                  "samples missing): the jaw comes from the lower incisor alone"]


def _bone_gaps_filled(ms, bone, by_role):
    """(the set, a note): articulography's bone points (found by role) with their interior gaps
    of at most :data:`MAX_BONE_GAP_S` filled by a cubic spline (the drive needs every frame;
    a file written to fill them would lose the roles). Others are left for the drive to refuse."""
    from ..kinematics.gaps import fill_gaps

    names = [n for n in bone if n is not None]
    if not by_role or not names or ms.valid[:, [ms.index(n) for n in names]].all():
        return ms, []
    part, done, _ = fill_gaps(ms.select(names), int(MAX_BONE_GAP_S * ms.rate))
    pos, flags = np.array(ms.positions), np.array(ms.filled)
    for j, n in enumerate(names):
        pos[:, ms.index(n)], flags[:, ms.index(n)] = part.positions[:, j], part.filled[:, j]
    if not done:
        return ms, []
    return ms.with_positions(pos, filled=flags), [
        f"filled {len(done)} gaps of the jaw's bone points ({sum(g.length for g in done)} "
        f"frames, each at most {MAX_BONE_GAP_S:g} s) by a cubic spline"]


def _skin_markers(ms, model, given, bone, midsagittal):
    """(the skin markers in the model's frame, name -> node, notes): bone points left out
    (``given``: the mapping read from a map file, or None); articulography's lips on the face's
    vermilion points, by their displacements."""
    from ..kinematics.mapping import closest_nodes
    from ..kinematics.roles import LIP_SITES, lip_markers, marker_roles, on_sites, pinned_x

    src = ms.meta.get("source")
    roles = marker_roles(ms)
    bone = [n for n in bone if n is not None]
    notes = []
    if roles:
        mapping = dict(given) if given is not None else lip_markers(ms, model)
        mapping = {n: v for n, v in mapping.items() if n not in bone}
        if not mapping:
            raise InputError("no sensor has the role upper_lip or lower_lip (nor a node in "
                             "--map): nothing on the skin to fit", source=src, field="roles")
        names = [n for n in ms.names if n in mapping]
        skin = on_sites(ms.select(names), model, mapping)
        lips = ", ".join(f"{n} ({roles.get(n, 'mapped')}) -> node {mapping[n]}"
                         + (f" ({LIP_SITES[roles[n]]})" if roles.get(n) in LIP_SITES
                            and given is None else "") for n in names)
        unused = [f"{n} ({roles.get(n, 'no role')})" for n in ms.names
                  if n not in mapping and n not in bone]
        jaw = f"bone points {', '.join(bone)} drive the jaw" if bone else "no bone point"
        notes.append(f"articulography: {lips}, each laid on its point by its displacement from "
                     f"its first sample; {jaw}; kept but not used: {', '.join(unused) or 'none'}")
    else:
        rest = ms.select([n for n in ms.names if n not in bone])
        mapping = dict(given) if given is not None else closest_nodes(rest, model)
        mapping = {n: v for n, v in mapping.items() if n not in bone}
        skin = rest
    if midsagittal:
        skin = pinned_x(skin, model, mapping)
        notes.append("midsagittal data: fitted in y and z only (each marker's x is set to its "
                     "model point's, on the midline of a symmetric face)")
    return skin, mapping, notes


#: mm per unit: the weight of activity (``effort``) when the sign step of a control pick kept
#: more controls than the markers determine: an opposing pair (MEN lifting the lower lip, DLI
#: lowering it) then has a co-contraction the markers barely see, along which the fit would
#: drift at little cost; this weight draws it back to the least activity at a rate of
#: (0.1 / 0.3)^2 = 11 % a frame against the default ``smooth`` (0.3), and shrinks a control
#: moving a marker 3 mm per unit by (0.1 / 3)^2 = 0.1 % of its activity (measured on the lips'
#: twin of tests/inverse/test_control_pick.py: it halves MEN's unseen activity, 0.66 -> 0.32)
SIGN_EFFORT = 0.1


def _effort_for_sign(solver, options):
    """(the method with :data:`SIGN_EFFORT` unless an effort was given, the note's clause)."""
    from .methods import LeastSquares

    if not isinstance(solver, LeastSquares) or (options or {}).get("effort") is not None:
        return solver, ""
    return (replace(solver, effort=SIGN_EFFORT),
            f"; effort {SIGN_EFFORT} mm per unit, so that an opposing pair does not co-contract "
            "unseen (set --effort to change it)")


#: (mm per unit, 1/s): ``smooth`` and ``max_rate`` of a fit whose controls were picked (the
#: markers determine combinations of them, not each): the change the markers do not fix is held
#: to what the activation can follow. Eq. (4)'s critically damped filter (tau 16.5 ms under the
#: anatomical preset, after Ito et al. 2004) changes its activation at most 1 / (e tau) = 22 per
#: second, for a step of full activity; the drive is bounded to that rate. Measured on MOCHA
#: fsew0_001 in docs/articulography.md (smooth 0.3 and no bound before).
PICK_PACE = (1.0, 22.0)


def _pace_for_pick(solver, options):
    """(the method with :data:`PICK_PACE`'s ``smooth`` and ``max_rate`` where not given, the
    note's clause)."""
    from .methods import LeastSquares

    given = {k for k, v in (options or {}).items() if v is not None}
    if not isinstance(solver, LeastSquares) or {"smooth", "max_rate"} <= given:
        return solver, ""
    smooth, rate = PICK_PACE
    solver = replace(solver, **{k: v for k, v in (("smooth", smooth), ("max_rate", rate))
                                if k not in given})
    return solver, (f"; as the markers determine combinations of these, not each, the change "
                    f"they leave free is paced: smooth {solver.smooth:g} mm per unit, and each "
                    f"muscle changes by at most {solver.max_rate:g} per second (what its "
                    "activation can follow; set --smooth and --max-rate to change it)")


def pick_candidates(model) -> tuple[str, ...]:
    """The groups a control pick chooses from: the speech controls and, on a face that has it,
    orbicularis oris's marginal part (what lowers the upper lip and lifts the lower lip on the
    jaw: the reach of real lips, docs/model.md)."""
    from ..params import MARGINAL_GROUPS, MUSCLE_GROUPS
    from .invert import SPEECH_CONTROLS

    present = {MUSCLE_GROUPS[g] for g in model.muscles.group}
    return SPEECH_CONTROLS + tuple(g for g in MARGINAL_GROUPS if g in present)


def _controls(controls, model, skin, mapping, jaw, estimate, jaw_source, midsagittal, src):
    """(controls for :func:`invert`, jaw series, estimate the jaw, jaw source, the note of
    controls picked or None, whether the pick's sign step added controls) on ``model`` (a
    :class:`~facemech.physics.model.Model`)."""
    from ..solvers.jaw import jaw_poses
    from .control_pick import pick_controls
    from .invert import control_matrix

    given = controls is not None
    ctrl = "speech" if controls is None else (
        controls if controls in ("speech", "emg7", "all")
        else [c.strip().upper() for c in controls.split(",") if c.strip()])
    names = [n for n in skin.names if n in mapping]
    per = 2 if midsagittal else 3
    coords = per * len(names)
    n_controls = len(control_matrix(ctrl, model.face)[0]) + (1 if estimate in (None, True) else 0)
    if coords >= n_controls or not names:
        return ctrl, jaw, estimate, jaw_source, None, False
    if given:
        raise InputError(f"{len(names)} markers give {coords} coordinates"
                         f"{' (y, z: midsagittal)' if midsagittal else ''} for {n_controls} "
                         "controls: use more markers or fewer controls", source=src,
                         field="markers")
    if jaw is None:
        start = np.zeros(3)
    elif jaw.ndim == 2:
        start = jaw[0]
    else:
        start = jaw_poses(np.atleast_1d(jaw[0]), model.params)[0]
    estimated = estimate in (None, True)
    pick = pick_controls(model, np.array([mapping[n] for n in names]),
                         pick_candidates(model.face), estimate_jaw=estimated, jaw_start=start,
                         axes=(1, 2) if midsagittal else (0, 1, 2), labels=names)
    if estimated and not pick.jaw:
        held = np.full(len(skin.positions), start[0]) if jaw is None else jaw
        jaw, estimate = held, False
        jaw_source = f"{jaw_source or 'the jaw at rest'} (held: the markers do not determine it)"
    return (list(pick.muscles), jaw, estimate, jaw_source, pick.note(len(names), midsagittal),
            bool(pick.for_sign))
