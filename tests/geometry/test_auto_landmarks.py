"""Issue 14: landmarks from geometry alone, on the generic face and on moved, rescaled and
stretched copies of it (within 3 mm of the true ones), and `facemech face landmarks`."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from conftest import run_cli
from facemech.geometry.auto_landmarks import auto_landmarks, surface_points
from facemech.geometry.builder import default_surface
from facemech.geometry.surface_io import read_landmarks

ROT = Rotation.from_euler("xyz", [20.0, -35.0, 110.0], degrees=True).as_matrix()
COPIES = {
    "as it is": lambda p: np.asarray(p),
    "turned, 1.15x, moved": lambda p: 1.15 * np.asarray(p) @ ROT.T + [0.3, -1.2, 0.5],
    "wider and shorter": lambda p: np.asarray(p) * [1.08, 0.95, 1.0],
}


@pytest.mark.parametrize("copy", list(COPIES))
def test_landmarks_land_within_3_mm(copy):
    v, f, truth = default_surface()
    move = COPIES[copy]
    found = auto_landmarks(move(v), f)
    err = {n: float(np.linalg.norm(found.positions[n] - move(truth[n]))) for n in truth}
    assert max(err.values()) < 3e-3, {n: round(e * 1e3, 2) for n, e in err.items()}
    assert min(found.confidence.values()) > 0.5
    if copy.startswith("turned"):
        assert found.generic_to_scan.scale == pytest.approx(1.15, rel=0.01)
        np.testing.assert_allclose(found.generic_to_scan.rotation, ROT, atol=0.01)


def test_a_sphere_gets_low_confidence():
    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=4, radius=0.08)
    found = auto_landmarks(ball.vertices, ball.faces)
    assert max(found.confidence.values()) < 0.5


def test_surface_points_lie_on_the_triangles():
    v = np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0]], float)
    pts = surface_points(v, np.array([[0, 1, 2]]), spacing=0.0005)
    assert len(pts) > 150 and np.all(pts[:, 2] == 0)
    assert np.all(pts[:, :2] >= -1e-15) and np.all(pts[:, 0] + pts[:, 1] <= 0.01 + 1e-12)


def test_the_command_writes_landmarks_that_build_a_face(tmp_path, monkeypatch, capsys):
    code, _, err = run_cli(monkeypatch, capsys, "face", "export-default", "-o", tmp_path)
    assert code == 0, err
    scan = tmp_path / "generic_face.obj"
    code, out, err = run_cli(monkeypatch, capsys, "face", "landmarks", scan, "-o",
                             tmp_path / "auto.csv")
    assert code == 0, err
    assert "18 landmarks" in out and "low confidence: none" in out
    assert (tmp_path / "auto.png").stat().st_size > 10_000
    auto = read_landmarks(tmp_path / "auto.csv")
    own = read_landmarks(tmp_path / "generic_face_landmarks.csv")
    assert max(np.linalg.norm(auto[n] - own[n]) for n in own) < 3e-3
    code, out, err = run_cli(monkeypatch, capsys, "face", "build", scan, tmp_path / "auto.csv",
                             "-o", tmp_path / "face.npz")
    assert code == 0, err
    code, _, err = run_cli(monkeypatch, capsys, "face", "landmarks", scan, "-o", scan)
    assert code == 2 and "refusing to overwrite an input" in err
