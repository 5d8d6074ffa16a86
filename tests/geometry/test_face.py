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


# ---- the builder's steps ---------------------------------------------------------------------
def test_old_import_paths_name_the_new_homes():
    from facemech.geometry import builder, face_file, kinds, mesh, model, options

    assert builder.FaceModel is model.FaceModel and builder.Muscles is model.Muscles
    assert builder.BuildOptions is options.BuildOptions
    assert builder.tissue_options is options.tissue_options
    assert builder.vertex_normals is mesh.vertex_normals
    assert builder._boundary_nodes is mesh.boundary_nodes
    assert builder.SPHINCTER is model.SPHINCTER is kinds.MuscleKind.SPHINCTER
    assert FaceModel.load.__func__.__module__ == "facemech.geometry.model"
    assert face_file.read_face.__module__ == "facemech.geometry.face_file"


def test_spring_and_layer_codes_are_the_face_files(seeds_face, face):
    from facemech.geometry.kinds import LAYER_NAMES, SPRING_KINDS, Layer, SpringKind

    # the integers are stored in face files: they never change
    assert [int(k) for k in SpringKind] == list(range(7))
    assert SPRING_KINDS == ("epidermis", "dermal_fatty", "fascia", "muscle_layer", "skull",
                            "superficial_diagonal", "deep_diagonal")
    assert LAYER_NAMES == ("epidermis", "fascia", "skull") and Layer.SKULL == 2
    for model in (seeds_face, face):
        n = model.n_surface
        layer = model.layer
        kind = model.spring_kind
        between = {SpringKind.EPIDERMIS: (0, 0), SpringKind.DERMAL_FATTY: (0, 1),
                   SpringKind.FASCIA: (1, 1), SpringKind.MUSCLE_LAYER: (1, 2),
                   SpringKind.SKULL: (2, 2), SpringKind.SUPERFICIAL_DIAGONAL: (0, 1),
                   SpringKind.DEEP_DIAGONAL: (1, 2)}
        for k, (li, lj) in between.items():
            sel = kind == k
            assert np.all(layer[model.spring_i[sel]] == li), k.name
            assert np.all(layer[model.spring_j[sel]] == lj), k.name
        vertical = (kind == SpringKind.DERMAL_FATTY) | (kind == SpringKind.MUSCLE_LAYER)
        assert np.all(model.spring_j[vertical] - model.spring_i[vertical] == n)
    assert not np.isin(seeds_face.spring_kind, [4, 5, 6]).any()


def test_topology_of_two_triangles():
    from facemech.geometry.kinds import SpringKind
    from facemech.geometry.layers import Layers
    from facemech.geometry.topology import anatomical_topology, uniform_topology

    faces = np.array([[0, 1, 2], [1, 3, 2]])
    rest = np.zeros((12, 3))
    layers = Layers(rest=rest, skull_normals=rest, lip_region=np.zeros(4, bool),
                    free=np.array([False, False, False, True]),
                    slides=np.array([True, True, False, False]))
    seeds = uniform_topology(faces, layers)
    counts = np.bincount(seeds.spring_kind, minlength=7)
    # 5 edges per surface layer, 4 dermal-fatty, 3 tied fascia nodes
    assert counts.tolist() == [5, 4, 5, 3, 0, 0, 0]
    np.testing.assert_array_equal(seeds.prism_nodes, [[0, 1, 2, 4, 5, 6], [1, 3, 2, 5, 7, 6],
                                                      [4, 5, 6, 8, 9, 10]])
    anat = anatomical_topology(faces, layers)
    counts = np.bincount(anat.spring_kind, minlength=7)
    assert counts.tolist() == [5, 4, 5, 4, 1, 10, 10]  # one skull edge: (0, 1) slides
    skull = anat.spring_kind == SpringKind.SKULL
    assert (anat.spring_i[skull].tolist(), anat.spring_j[skull].tolist()) == ([8], [9])
    assert anat.prism_nodes.shape == (4, 6) and anat.prism_nodes.dtype == np.int64


def test_lip_line_sides_and_contact_pairs():
    from facemech.geometry.mouth import LOWER_LIP, UPPER_LIP, LipLine, lip_contact

    line = LipLine(np.array([-0.025, -0.070, 0.0]), np.array([0.0, -0.072, 0.01]),
                   np.array([0.025, -0.070, 0.0]))
    assert line.half_width == pytest.approx(0.025, abs=1e-15)
    assert line.y(-0.025) == -0.070 and line.y(0.0) == -0.072
    assert line.y(0.0125) == pytest.approx(-0.071, abs=1e-15)
    assert line.y(0.05) == -0.070 and line.y(-0.05) == -0.070  # level beyond the corners
    assert line.side_of(np.array([0.01, -0.0705, 0.0])) == UPPER_LIP
    assert line.side_of(np.array([0.01, -0.0720, 0.0])) == LOWER_LIP
    assert line.side_of(np.array([0.03, -0.0720, 0.0])) is None  # beyond 1.1 half widths
    pairs, normals = lip_contact(np.array([[1, 2], [3, 4]]), 10, deep=True)
    assert pairs.tolist() == [[1, 2], [3, 4], [11, 12], [13, 14], [21, 22], [23, 24]]
    np.testing.assert_array_equal(normals, np.tile([0.0, 1.0, 0.0], (6, 1)))
    assert len(lip_contact(np.array([[1, 2]]), 10, deep=False)[0]) == 2


def test_landmark_warp_and_jaw_line():
    from facemech.geometry.jaw import hinge, jaw_line_y
    from facemech.geometry.mouth import LipLine, stomion
    from facemech.geometry.warp import generic_landmarks, landmark_warp

    gen = generic_landmarks()
    other = {k: v * np.array([1.1, 0.95, 1.05]) + 0.002 for k, v in gen.items()}
    warp = landmark_warp(gen, other)
    moved = warp(np.array([gen[k] for k in other]))
    np.testing.assert_allclose(moved, np.array(list(other.values())), atol=1e-9)
    assert landmark_warp(gen, gen).displacement is None
    line = LipLine(other["mouth_corner_right"], stomion(other), other["mouth_corner_left"])
    ga = other["jaw_angle_left"]
    assert jaw_line_y(ga[0], line, other) == pytest.approx(ga[1], abs=1e-15)
    assert jaw_line_y(ga[0] + 0.01, line, other) == pytest.approx(ga[1], abs=1e-15)
    assert jaw_line_y(0.0, line, other) == line.y(0.0)
    point, axis = hinge(other, 25e-3)
    assert point[2] == pytest.approx(0.5 * (ga[2] + other["jaw_angle_right"][2]) - 25e-3)
    assert axis.tolist() == [1.0, 0.0, 0.0]


def test_muscles_are_assembled_in_csr_form(face):
    from facemech.geometry.muscle_sites import bump_weights

    m = face.muscles
    assert m.ptr[0] == 0 and m.ptr[-1] == len(m.nodes) == len(m.weights) == len(m.bead)
    for k in range(len(m)):
        w, b = m.weights[m.ptr[k]:m.ptr[k + 1]], m.bead[m.ptr[k]:m.ptr[k + 1]]
        for bead in np.unique(b):  # each bead's weights share its force
            assert w[b == bead].sum() == pytest.approx(1.0, abs=1e-12)
    names = list(m.names)
    assert names[-8:] == ["OOS_R", "OOS_L", "OOI_R", "OOI_L",
                          "OOSM_R", "OOSM_L", "OOIM_R", "OOIM_L"]
    assert names[:2] == ["ZYG_R", "ZYG_L"]
    np.testing.assert_allclose(bump_weights(np.array([0.0, 0.5, 1.0, 2.0]), np.full(4, 2.0)),
                               [2.0, 2.0 * 0.75**2, 2.0 * 0.05**2, 2.0 * 0.05**2])
