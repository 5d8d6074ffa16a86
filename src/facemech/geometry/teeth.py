"""The teeth's place in a face: how deep the incisors stand behind the lips.

The renderer draws the dental arches (:mod:`facemech.viz.face_parts`) from these numbers, the
results file keeps the depth (:func:`facemech.io.results.render_attrs`), and the jaw drives that
read a lower-incisor sensor move :func:`lower_incisor_point` (:mod:`facemech.solvers.jaw_bone`).
Pure geometry of a :class:`~facemech.geometry.model.FaceModel` at rest (m).
"""

from __future__ import annotations

import numpy as np

#: m, lip surface to the incisors where a file does not say, and the least taken: the adult
#: upper lip is 11-15 mm thick from its vermilion to the incisors' labial face (cephalometric
#: soft-tissue norms, e.g. Holdaway 1983)
TEETH_DEPTH_DEFAULT = 0.012
#: the lower arch of the renderer (:mod:`facemech.viz.face_parts`): the incisal edge this far
#: above the stomion (m) and this far behind the upper incisors (m)
LOWER_EDGE_ABOVE_STOMION = 0.0005
LOWER_ARCH_SETBACK = 0.0025


def teeth_depth(model) -> float:
    """Depth (m) of the upper incisors behind the upper lip's surface: the tissue's depth under
    the upper lip's centre (skin to skull node), at least :data:`TEETH_DEPTH_DEFAULT`; that
    for a face without the landmark.

    The seeds' uniform tissue is 4 mm deep under the lip; incisors that close behind it stood
    through the closed lips in renders (and the gums through the skin above and below them).
    The anatomical tissue is 13.8 mm deep there on the built-in face."""
    n = model.n_surface
    ul = model.landmarks.get("upper_lip_center")
    if ul is None:
        return TEETH_DEPTH_DEFAULT
    depth = float(np.linalg.norm(model.rest_positions[ul] - model.rest_positions[ul + 2 * n]))
    return max(depth, TEETH_DEPTH_DEFAULT)


def lower_incisor_point(model) -> np.ndarray:
    """Rest position (3,) m of the tip of the lower incisors, midline, as the renderer draws it.

    The renderer's lower arch (:mod:`facemech.viz.face_parts`) has its incisal edge
    :data:`LOWER_EDGE_ABOVE_STOMION` above the stomion and its front
    :data:`LOWER_ARCH_SETBACK` behind the upper incisors, which stand :func:`teeth_depth`
    behind the upper lip's surface. It moves with the mandible (jaw weight 1).
    """
    rest = model.rest_positions
    lm = model.landmarks
    ul = rest[lm["upper_lip_center"]]
    st = (rest[lm["stomion"]] if "stomion" in lm
          else 0.5 * (ul + rest[lm["lower_lip_center"]]))
    depth = teeth_depth(model)
    return np.array([st[0], st[1] + LOWER_EDGE_ABOVE_STOMION,
                     ul[2] - depth - LOWER_ARCH_SETBACK])
