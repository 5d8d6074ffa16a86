"""A real textured head scan as it comes (menpo3d's, tests/data/scans): OBJ + MTL + JPEG with
menpo LJSON v3 landmarks builds, rests still and keeps its texture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

SCANS = Path(__file__).parents[1] / "data" / "scans"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from facemech.workflows.faces import build_face_file

    out = tmp_path_factory.mktemp("scan") / "james.npz"
    return build_face_file(SCANS / "james.obj", SCANS / "james.ljson", out, units=None)


def test_the_menpo3d_head_scan_builds_with_notes_on_what_was_mended(built):
    notes = built.warnings
    assert "cropped to the face" in notes and "trimmed" in notes
    assert "smoothed there" in notes  # the skin where no tissue fits, with where and how much
    model = built.data
    assert model.appearance is not None and model.appearance.uv is not None
    assert model.appearance.image.shape[:2] == (800, 1200)


def test_the_scan_talker_rests_still(built):
    """No activity, the jaw closed: no node moves by more than 0.1 mm over 0.1 s."""
    from facemech.params import MUSCLE_GROUPS
    from facemech.physics.model import model as face_model
    from facemech.solvers.forward import simulate

    model = built.data
    sim = simulate(face_model(model), np.zeros((6, len(MUSCLE_GROUPS))))
    moved = np.linalg.norm(sim.positions - model.rest_positions[None, :sim.positions.shape[1]],
                           axis=-1)
    assert moved.max() < 1e-4


def test_no_prism_of_the_scan_is_folded(built):
    from facemech.geometry.prism import rest_geometry

    model = built.data
    vols, _ = rest_geometry(model.rest_positions, model.prism_nodes)
    assert vols.min() > 0
