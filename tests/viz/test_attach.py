"""Render-only meshes carried by the skin (facemech.viz.attach): bound once at rest, they move
rigidly with a rigidly moved skin and lie on it where they were bound with no offset."""

from __future__ import annotations

import numpy as np

from facemech.geometry.builder import vertex_normals
from facemech.viz.attach import attach, on_skin
from facemech.viz.scene import look_from_model


def test_attached_points_follow_a_rigid_motion_of_the_skin(face):
    look = look_from_model(face)
    skin, tris = look.rest, look.triangles
    normals = vertex_normals(skin, tris)
    rng = np.random.default_rng(0)
    pts = skin[rng.choice(len(skin), 40, replace=False)] + rng.normal(0, 0.002, (40, 3))
    bound = attach(pts, skin, tris, normals)
    np.testing.assert_allclose(bound.place(skin, normals), pts, atol=1e-9)
    a = 0.4
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    shift = np.array([0.01, -0.02, 0.005])
    moved = skin @ rot.T + shift
    np.testing.assert_allclose(bound.place(moved, normals @ rot.T), pts @ rot.T + shift,
                               atol=1e-9)


def test_a_decal_lies_on_the_skin_at_its_lift(face):
    look = look_from_model(face)
    skin, tris = look.rest, look.triangles
    normals = vertex_normals(skin, tris)
    front = skin[skin[:, 2] > np.percentile(skin[:, 2], 80)][:30]
    decal = on_skin(front + 0.003 * np.array([0.0, 0.0, 1.0]), skin, tris, normals, 0.0005)
    p = decal.place(skin, normals)
    # 0.5 mm out along the blended normal from a foot point on the skin's triangles
    foot = np.einsum("mk,mkj->mj", decal.weights, skin[decal.corners])
    assert np.allclose(np.linalg.norm(p - foot, axis=1), 0.0005)
    blended = np.einsum("mk,mkj->mj", decal.weights, normals[decal.corners])
    assert np.all(np.einsum("ij,ij->i", p - foot, blended) > 0)
