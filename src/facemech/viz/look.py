"""What the renderer knows of a face: rest skin, landmarks, jaw hinge, teeth depth, appearance.

A :class:`FaceLook` comes from a results file (:func:`look_from_dataset`, which needs no face
model: the file keeps the hinge and the teeth depth) or from a face model
(:func:`look_from_model`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from ..io.results import TEETH_DEPTH_DEFAULT, render_attrs


@dataclass(frozen=True)
class FaceLook:
    """What the renderer needs to know of a face (metres, model axes).

    Attributes
    ----------
    rest : (n, 3) rest positions of the skin nodes
    triangles : (f, 3) int skin triangles
    landmarks : name -> (3,) rest position
    hinge_point, hinge_axis : (3,) the jaw hinge (positive angles open the mouth)
    teeth_depth : m from the upper lip's surface back to the incisors
    uv : (f, 3, 2) per-corner texture coordinates in [0, 1] (v up), or None
    image : (h, w, 3) uint8 texture, or None
    vertex_colours : (n, 3) uint8, or None
    hair : (3,) uint8 sRGB, the hair's colour measured on a photo, or None (the renderer's)
    """

    rest: np.ndarray
    triangles: np.ndarray
    landmarks: dict
    hinge_point: np.ndarray
    hinge_axis: np.ndarray
    teeth_depth: float = TEETH_DEPTH_DEFAULT
    uv: np.ndarray | None = None
    image: np.ndarray | None = None
    vertex_colours: np.ndarray | None = None
    hair: np.ndarray | None = None

    @property
    def textured(self) -> bool:
        return self.image is not None or self.vertex_colours is not None


def _hinge_guess(lm: dict) -> tuple[np.ndarray, np.ndarray]:
    if "jaw_angle_left" in lm and "jaw_angle_right" in lm:
        g = 0.5 * (lm["jaw_angle_left"] + lm["jaw_angle_right"])
        return g + np.array([0.0, 0.054, -0.029]), np.array([1.0, 0.0, 0.0])
    return np.array([0.0, -0.046, -0.073]), np.array([1.0, 0.0, 0.0])


def look_from_dataset(ds) -> FaceLook:
    """The :class:`FaceLook` of a results dataset (:func:`facemech.io.results.read_results`)."""
    rest = (ds["rest_positions"].values if "rest_positions" in ds
            else ds["positions"].values[0])
    tri = ds["triangles"].values.astype(np.int64)
    nodes = json.loads(ds.attrs.get("marker_nodes", "{}"))
    lm = {k: rest[int(v)] for k, v in nodes.items() if 0 <= int(v) < len(rest)}
    if "hinge_point_m" in ds.attrs:
        hp = np.array(json.loads(ds.attrs["hinge_point_m"]), float)
        ha = np.array(json.loads(ds.attrs["hinge_axis"]), float)
    else:
        hp, ha = _hinge_guess(lm)
    depth = float(ds.attrs.get("teeth_depth_m", TEETH_DEPTH_DEFAULT))
    app = _appearance(ds)
    return FaceLook(rest, tri, lm, hp, ha, depth, *app)


def look_from_model(model) -> FaceLook:
    """The :class:`FaceLook` of a :class:`~facemech.geometry.model.FaceModel`."""
    n = model.n_surface
    rest = model.rest_positions[:n]
    lm = {k: rest[v] for k, v in {**model.landmarks, **model.markers}.items()}
    attrs = render_attrs(model)
    app = _appearance(model)
    return FaceLook(rest, np.asarray(model.faces, np.int64), lm, model.hinge_point,
                    model.hinge_axis, attrs["teeth_depth_m"], *app)


def _appearance(source):
    """(uv, image, vertex colours, hair) of a model or dataset carrying a scan's appearance."""
    try:
        from ..geometry import appearance as A
    except ImportError:
        return None, None, None, None
    if hasattr(source, "attrs") and hasattr(source, "data_vars"):
        app = A.appearance_from_dataset(source)
    else:
        app = getattr(source, "appearance", None)
    if app is None:
        return None, None, None, None
    return app.uv, app.image, app.vertex_colours, app.hair
