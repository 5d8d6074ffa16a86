"""A scan's vertices numbered from the top of the face down.

A scanner writes its vertices in whatever order its reconstruction made them: by camera, by
patch, or shuffled by a decimation. The built face keeps that order for its nodes, and the force
kernel reads the nodes in it: on two threads (:mod:`facemech.physics.slabs`) each thread takes
a band of the face, and when the nodes of the two bands alternate in memory the cores fetch each
other's lines at every step. Measured on the built-in face's surface exported as a scan
(``benchmarks/forward.py --face``): with its vertices shuffled, two threads took 552 µs a step
against 444 on one (0.8x); numbered top-down, 247 against 415 (1.68x), as the built-in face.

Numbering the vertices by height (descending y, ties in the file's order) makes every
horizontal band of the face one run of consecutive nodes in each layer. The geometry, the
triangles and the look are unchanged; only the numbers move.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .appearance import Appearance


def top_down(vertices: np.ndarray, faces: np.ndarray,
             appearance: Appearance | None = None
             ) -> tuple[np.ndarray, np.ndarray, Appearance | None]:
    """The surface with its vertices numbered by descending height.

    Parameters
    ----------
    vertices : (n, 3) m, facemech's axes (+y up)
    faces : (f, 3) int -- each triangle's corners, in its winding
    appearance : vertex colours follow their vertices; texture coordinates, given per
        triangle corner, stay as they are

    Returns
    -------
    vertices : (n, 3) -- ``vertices[order]``, the highest first (ties in the given order)
    faces : (f, 3) int64 -- the same triangles, corners renumbered, windings kept
    appearance : the same look
    """
    vertices = np.asarray(vertices, float)
    order = np.argsort(-vertices[:, 1], kind="stable")
    if np.array_equal(order, np.arange(len(order))):
        return vertices, np.asarray(faces, np.int64), appearance
    new = np.empty(len(order), np.int64)
    new[order] = np.arange(len(order))
    if appearance is not None and appearance.vertex_colours is not None:
        appearance = replace(appearance, vertex_colours=appearance.vertex_colours[order])
    return vertices[order], new[np.asarray(faces, np.int64)], appearance


__all__ = ["top_down"]
