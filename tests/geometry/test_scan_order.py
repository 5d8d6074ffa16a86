"""A scan's vertices numbered from the top of the face down (facemech.geometry.scan_order): the
same surface and look, and two threads' bands of the face in runs of consecutive nodes, however
the scanner ordered its vertices."""

from __future__ import annotations

import numpy as np

from facemech.geometry.appearance import Appearance
from facemech.geometry.builder import build_face, default_surface, tissue_options
from facemech.geometry.scan import load_scan
from facemech.geometry.scan_order import top_down
from facemech.params import preset
from facemech.physics.assembly import Physics
from facemech.physics.slabs import interleaving
from scans import write_landmark_csv, write_obj


def shuffled_surface(seed=3):
    """The generic surface (m) with its vertices in a random order, and the permutation."""
    v, f, lm = default_surface()
    perm = np.random.default_rng(seed).permutation(len(v))
    new = np.empty(len(v), np.int64)
    new[perm] = np.arange(len(v))
    return v[perm], new[f], lm, perm


def triangles(v, f):
    """Each triangle as its corners' positions, starting at its smallest corner index's
    position in lexicographic order (so a renumbering that keeps the winding compares equal)."""
    out = []
    for tri in v[f]:
        k = min(range(3), key=lambda c: tuple(tri[c]))
        out.append(tuple(np.roll(tri, -k, axis=0).ravel()))
    return sorted(out)


def test_top_down_numbers_by_height_and_keeps_the_triangles_and_colours():
    v, f, _, _ = shuffled_surface()
    colours = np.random.default_rng(0).integers(0, 256, (len(v), 3)).astype(np.uint8)
    look = Appearance(vertex_colours=colours, source="scan.ply")
    v2, f2, look2 = top_down(v, f, look)
    assert np.all(np.diff(v2[:, 1]) <= 0)
    assert sorted(map(tuple, v2)) == sorted(map(tuple, v))
    assert triangles(v2, f2) == triangles(v, f)  # the same triangles, windings kept
    key = {tuple(p): tuple(c) for p, c in zip(v, colours, strict=True)}
    assert all(key[tuple(p)] == tuple(c) for p, c in zip(v2, look2.vertex_colours, strict=True))
    same = top_down(v2, f2, look2)  # already in order: nothing moves
    assert same[0] is v2 and np.array_equal(same[1], f2) and same[2] is look2


def test_a_shuffled_scan_is_read_top_down_and_its_threads_bands_stay_apart(tmp_path):
    """The generic surface with its vertices shuffled, read as a scan: its two threads' bands
    change places in memory a few times per layer, as the built-in face's (10), not the
    shuffled order's thousands."""
    v, f, lm, _ = shuffled_surface()
    write_obj(tmp_path / "scan.obj", v * 1e3, f)
    write_landmark_csv(tmp_path / "lm.csv", lm)
    scan = load_scan(tmp_path / "scan.obj", tmp_path / "lm.csv", units="mm")
    assert np.all(np.diff(scan.vertices[:, 1]) <= 0)
    opt = tissue_options("anatomical")
    prm = preset("anatomical")

    def changes(vertices, faces):
        ph = Physics.build(build_face(vertices, faces, scan.landmarks, options=opt), prm)
        b = ph.forces
        return interleaving(b.springs, b.prisms, ph.model.rest_positions, "y")

    built_in = changes(*default_surface()[:2])
    assert built_in <= 20
    assert changes(scan.vertices, scan.faces) <= 2 * built_in
    assert changes(v, f) > 50 * built_in  # as the scanner wrote them
