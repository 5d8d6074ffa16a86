"""One jaw drive for both commands (facemech.jaw): ``simulate``'s jaw from a marker file and
``invert``'s from the recording's own markers are the same drive, with the same lead."""

from __future__ import annotations

import numpy as np
import pytest

from facemech import InputError, preset, write_marker_csv
from facemech.jaw.drive import SKIN_JAW_LEAD, default_lead, jaw_drive
from facemech.jaw.inputs import JawMarkers, JawSource
from facemech.jaw.series import jaw_series
from facemech.markerset import MarkerSet
from facemech.physics.model import model as face_model
from facemech.solvers.jaw import move_points

FRAMES = 24


def _opening(face):
    """R01 and a point 30 mm behind it carried about the hinge to 0..8 degrees, m."""
    first = face.rest_positions[face.markers["R01"]]
    pts = np.stack([first, first + [0.0, 0.0, -0.03]])
    angles = np.radians(np.linspace(0.0, 8.0, FRAMES))
    moved = np.stack([move_points(pts, (a, 0.0, 0.0), face.hinge_point, face.hinge_axis)
                      for a in angles])
    return angles, moved[:, 0], moved[:, 1]


def test_simulate_and_invert_drive_the_jaw_alike_from_two_mandible_markers(tmp_path,
                                                                           seeds_face):
    model = face_model(seeds_face, preset("lucero1999"))
    angles, p1, p2 = _opening(seeds_face)
    write_marker_csv(tmp_path / "jaw.csv", MarkerSet(np.stack([p1, p2], axis=1),
                                                     ("R01", "M2"), 60.0, source_units="mm"))
    times = np.arange(FRAMES) / 60.0
    sim, inputs = jaw_series(JawSource(markers=tmp_path / "jaw.csv", second_marker="M2"), model,
                             times)
    names = JawMarkers("R01", "M2")
    inv, what = jaw_drive({"R01": p1, "M2": p2}, model, names,
                          lead=default_lead(names, on_bone=False))
    assert set(inputs) == {"jaw_chin"} and what == "jaw markers R01,M2 (2-frame lead)"
    np.testing.assert_allclose(sim, inv, atol=1e-5)  # the file holds mm to a few decimals
    # the imposed opening, two frames early (the skin's lead), the last held; no shift
    np.testing.assert_allclose(inv[:-SKIN_JAW_LEAD, 0], angles[SKIN_JAW_LEAD:], atol=1e-9)
    np.testing.assert_allclose(inv[-SKIN_JAW_LEAD:, 0], angles[-1], atol=1e-9)
    np.testing.assert_allclose(inv[:, 1:], 0.0, atol=1e-9)


def test_the_lead_is_the_given_one_else_by_where_the_markers_sit():
    assert default_lead(JawMarkers("R01"), on_bone=False) == SKIN_JAW_LEAD == 2
    assert default_lead(JawMarkers(jaw_incisor="LI"), on_bone=True) == 0
    assert default_lead(JawMarkers("R01", jaw_lead=5), on_bone=False) == 5


def test_a_chin_marker_without_a_node_or_a_second_marker_missing_is_refused(seeds_face):
    model = face_model(seeds_face, preset("lucero1999"))
    _, p1, p2 = _opening(seeds_face)
    with pytest.raises(InputError) as e:
        jaw_drive({"R01": p1}, model, JawMarkers("R01"), lead=2, source="rec.c3d")
    assert e.value.field == "R01" and "no node" in e.value.message
    with pytest.raises(InputError) as e:
        jaw_drive({"R01": p1}, model, JawMarkers("R01", "M2"), lead=2, source="rec.c3d")
    assert e.value.field == "M2" and e.value.source == "rec.c3d"
    assert jaw_drive({"R01": p1, "M2": p2}, model, JawMarkers(), lead=2) == (None, None)
