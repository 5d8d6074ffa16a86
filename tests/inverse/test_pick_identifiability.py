"""The control pick and the identifiability agree (issue 54, item 3): on twins of 3 and 37
markers (markers synthesised from known activity on the model; the 2-marker twin is
tests/inverse/test_control_pick.py's),
the combinations the inversion reports as determined at the noise
floor are led by exactly the controls the pick kept by rank, and a control is called regularised
exactly when it is not determined alone."""

import json

import numpy as np
import pytest

from facemech import MUSCLE_GROUPS
from facemech.inverse.combinations import from_json
from facemech.inverse.control_pick import MIN_NEW_MOTION_MM, pick_controls
from facemech.inverse.workflow import invert_marker_set, pick_candidates
from facemech.markerset import MarkerSet
from facemech.params import preset
from facemech.physics.model import model as face_model
from facemech.solvers.forward import simulate

FRAMES = 6


def _twin(face, names):
    """Markers at the model's sites ``names`` (frames, markers, 3) m, from LLS and DLI rising
    on a still jaw."""
    act = np.zeros((FRAMES, len(MUSCLE_GROUPS)))
    ramp = np.linspace(0.0, 0.2, FRAMES)
    act[:, MUSCLE_GROUPS.index("LLS")] = ramp
    act[:, MUSCLE_GROUPS.index("DLI")] = ramp[::-1] * 0.5
    sim = simulate(face_model(face), act, np.zeros(FRAMES))
    sites = {**face.landmarks, **face.markers}
    nodes = [sites[n] for n in names]
    return MarkerSet(sim.positions[:, nodes], tuple(names), 60.0), dict(zip(names, nodes,
                                                                             strict=True))


def _consistent(res):
    """The agreements every inversion keeps: regularised == not determined alone; each control
    determined alone leads a combination determined at the noise."""
    attrs = res.attrs
    reg = [n for n in attrs["regularised"].split(",") if n]
    alone = [n for n, ok in zip(res.control_names, res.identifiable, strict=True) if ok]
    assert set(reg) == set(res.control_names) - set(alone)
    determined = {c.lead for c in res.combinations if c.determined(res.noise_mm)}
    assert set(alone) <= determined | {n for n in alone if n == "jaw"}
    notes = " | ".join(res.notes)
    assert "not determined by these markers" not in notes
    if reg:
        assert "determined by these markers: " in notes and "regularised" in notes
    return json.loads(json.dumps(attrs["combinations"]))


def test_three_markers_the_pick_and_the_combinations_agree(face):
    names = ("R03", "R05", "R07")
    ms, mapping = _twin(face, names)
    res = invert_marker_set(ms, face_model(face), mapping=mapping)
    pick = pick_controls(face_model(face, preset("anatomical")), [mapping[n] for n in names],
                         pick_candidates(face), estimate_jaw=True, labels=list(names))
    rank = [c for c in pick.order if c not in {s for s, _, _ in pick.for_sign}]
    assert set(res.control_names) == set(pick.muscles) | ({"jaw"} if pick.jaw else set())
    combos = from_json(_consistent(res))
    floor = [c.lead for c in combos if c.motion_mm >= MIN_NEW_MOTION_MM]
    assert floor == rank  # the same controls, in the same pivot order
    for c, r in zip(combos, rank, strict=False):
        assert c.motion_mm == pytest.approx(pick.new_motion[r], rel=1e-6, abs=1e-9)
    assert f"so that the markers determine {len(rank)} combinations" in pick.note(3)


def test_thirty_seven_markers_determine_single_controls_and_say_the_rest(face):
    names = tuple({**face.landmarks, **face.markers})
    assert len(names) == 37
    ms, mapping = _twin(face, names)
    res = invert_marker_set(ms, face_model(face), mapping=mapping)
    assert "controls: " not in " ".join(res.notes)  # no pick: 111 coordinates for 10 controls
    combos = from_json(_consistent(res))
    assert len(combos) == len(res.control_names)  # full rank: one combination per control
    # each control determined alone leads a combination determined at the floor
    floor = {c.lead for c in combos if c.motion_mm >= MIN_NEW_MOTION_MM}
    alone = {n for n, ok in zip(res.control_names, res.identifiable, strict=True) if ok}
    assert alone <= floor, (alone, floor)
    assert {"LLS", "DLI"} <= alone
