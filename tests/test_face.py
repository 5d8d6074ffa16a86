"""The built-in face and the model builder."""

import numpy as np
import pytest

from facemech import InputError, build_face
from facemech.geometry import generic
from facemech.geometry.builder import FaceModel, default_surface


def test_generic_face_dimensions(face):
    s = face.summary()
    assert s["nodes_per_layer"]["epidermis"] >= 1500
    lm = face.landmark_positions()
    mouth = np.linalg.norm(lm["mouth_corner_left"] - lm["mouth_corner_right"])
    assert mouth == pytest.approx(0.050, abs=1.5e-3)
    assert lm["nose_tip"][1] - lm["chin"][1] == pytest.approx(0.070, abs=3e-3)
    assert lm["subnasale"][1] - lm["menton"][1] == pytest.approx(0.070, abs=3e-3)
    # hairline to under the chin, ear to ear
    ext = np.ptp(face.rest_positions[: face.n_surface], axis=0)
    assert ext[0] > 0.12 and ext[1] > 0.19
    # axes: nose forward (+z), left landmarks at +x
    assert lm["nose_tip"][2] > lm["cheek_left"][2]
    assert lm["mouth_corner_left"][0] > 0 > lm["mouth_corner_right"][0]


def test_mesh_is_finer_around_the_mouth(face):
    v = face.rest_positions[: face.n_surface]
    e = np.sort(np.concatenate([face.faces[:, [0, 1]], face.faces[:, [1, 2]]]), axis=1)
    mid = 0.5 * (v[e[:, 0]] + v[e[:, 1]])
    length = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    near = np.linalg.norm(mid[:, :2] - np.array([0.0, -0.073]), axis=1) < 0.02
    far = mid[:, 1] > 0.03
    assert np.median(length[near]) < 0.6 * np.median(length[far])


def test_layers_springs_prisms_and_muscles(seeds_face):
    face = seeds_face  # the seeds' uniform tissue
    s = face.summary()
    n = face.n_surface
    rest = face.rest_positions
    # fascia 1.5 mm and skull 4 mm under the epidermis
    d_f = np.linalg.norm(rest[n:2 * n] - rest[:n], axis=1)
    d_s = np.linalg.norm(rest[2 * n:] - rest[:n], axis=1)
    np.testing.assert_allclose(d_f, 1.5e-3, rtol=1e-9)
    np.testing.assert_allclose(d_s, 4.0e-3, rtol=1e-9)
    kinds = s["springs_by_kind"]
    assert kinds["dermal_fatty"] == n and kinds["epidermis"] == kinds["fascia"]
    assert kinds["muscle_layer"] == s["tied_fascia_nodes"]
    assert s["free_fascia_nodes"] > 100
    assert s["prisms"] == len(face.faces) + np.sum(
        np.isin(face.faces + n, face.tied_fascia).all(axis=1))
    groups = set(s["muscle_groups"])
    assert groups == {"DAO", "DLI", "LAO", "ZYG", "LLS", "MEN", "OOS", "OOI", "ZMI", "RIS",
                      "LLSAN", "COR", "CSU", "FRM", "FRL", "FRI"}
    assert len(face.muscles) == 32
    assert all(nm.endswith(("_L", "_R")) for nm in face.muscles.names)


def test_free_fascia_is_around_lips_and_cheeks(seeds_face):
    face = seeds_face  # the seeds' uniform tissue
    n = face.n_surface
    free = face.rest_positions[face.free_fascia]
    lm = face.landmark_positions()
    assert np.all(free[:, 1] < lm["nose_tip"][1]) and np.all(free[:, 1] > lm["chin"][1])
    tied_lip = np.isin(np.array([face.landmarks["upper_lip_center"]]) + n, face.tied_fascia)
    assert not tied_lip.any()


def test_mouth_slit_and_jaw_region(seeds_face):
    face = seeds_face  # the seeds' uniform tissue
    n = face.n_surface
    rest = face.rest_positions
    up, lo = face.lip_pairs[: len(face.lip_pairs) // 2].T
    np.testing.assert_allclose(rest[up], rest[lo])  # closed slit: the twins coincide at rest
    # the two lips share no triangle across the slit
    for tri in face.faces:
        assert not (np.isin(tri, up).any() and np.isin(tri, lo).any())
    jaw = set(face.jaw_nodes.tolist())
    assert all(v + 2 * n in jaw for v in lo)
    assert not any(v + 2 * n in jaw for v in up)
    assert face.landmarks["chin"] + 2 * n in jaw
    assert face.landmarks["nose_tip"] + 2 * n not in jaw
    # mandibular muscles originate on the jaw
    for k, nm in enumerate(face.muscles.names):
        on_jaw = face.muscles.origin[k] in jaw
        assert on_jaw == (nm.split("_")[0] in ("DAO", "DLI", "MEN")), nm


def test_virtual_markers(face):
    right = [m for m in face.markers if m.startswith("R")]
    left = [m for m in face.markers if m.startswith("L")]
    assert len(right) == 11 and len(left) == 8
    pos = face.rest_positions
    assert all(pos[face.markers[m], 0] < 0 for m in right)
    assert all(pos[face.markers[m], 0] > 0 for m in left)
    assert pos[face.markers["R01"], 1] < pos[face.landmarks["lower_lip_center"], 1]


def test_save_load_round_trip(face, tmp_path):
    path = tmp_path / "face.npz"
    face.save(path)
    back = FaceModel.load(path)
    assert back.summary() == face.summary()
    np.testing.assert_array_equal(back.rest_positions, face.rest_positions)
    np.testing.assert_array_equal(back.muscles.nodes, face.muscles.nodes)


def test_builder_on_a_reshaped_face():
    """Another talker: the generic surface stretched and widened, same landmarks moved."""
    v, f, lm = default_surface()
    scale = np.array([1.1, 0.95, 1.05])
    other = build_face(v * scale, f, {k: p * scale for k, p in lm.items()}, name="other")
    assert other.summary()["muscles"] == 32
    mouth = np.linalg.norm(other.rest_positions[other.landmarks["mouth_corner_left"]]
                           - other.rest_positions[other.landmarks["mouth_corner_right"]])
    assert mouth == pytest.approx(0.055, abs=2e-3)


def test_builder_rejects_bad_input():
    v, f, lm = default_surface()
    with pytest.raises(InputError, match="missing landmarks: chin"):
        build_face(v, f, {k: p for k, p in lm.items() if k != "chin"}, source="x.obj")
    mid = len(f) // 2  # an interior edge, then shared by three triangles
    bad = np.concatenate([f, [[f[mid, 1], f[mid, 0], len(v) - 1]]])
    with pytest.raises(InputError, match="non-manifold"):
        build_face(v, bad, lm, source="x.obj")


def test_generic_surface_is_a_graph_over_the_frontal_plane():
    s = generic.make_surface()
    v = s.vertices.reshape(s.rows, s.cols, 3)
    assert np.all(np.diff(v[:, :, 0], axis=1) > 0)  # each row monotone in x
    assert np.all(np.isfinite(s.vertices))
