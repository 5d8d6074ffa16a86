"""Markers to model nodes, and the per-axis scaling adaptation of Pitermann & Munhall (2001).

A marker's node is the epidermal node closest to it at rest, or the one a mapping file names.
The mapping CSV has columns ``marker,node`` where ``node`` is an epidermal node index or the
name of a landmark or virtual marker of the face.

Scaling adaptation (P&M 2001, Experiment 3): two markers far apart give per-axis scale factors,
the ratio of their nodes' separation to the markers' separation on each axis; the markers are
scaled by them, then each is shifted so that it sits on its node at rest.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..markerset import MarkerSet

MAX_MARKER_DISTANCE = 0.010  #: m, a marker farther than this from every node is an error


def closest_nodes(ms: MarkerSet, model, *, reference: int = 0,
                  max_distance: float = MAX_MARKER_DISTANCE) -> dict[str, int]:
    """The closest epidermal node to each marker at the reference frame."""
    tree = cKDTree(model.rest_positions[: model.n_surface])
    out = {}
    for m, name in enumerate(ms.names):
        p = ms.positions[reference, m]
        if not np.all(np.isfinite(p)):
            raise InputError(f"missing at the reference frame {reference}",
                             source=ms.meta.get("source"), field=name)
        d, node = tree.query(p)
        if d > max_distance:
            raise InputError(f"{d * 1e3:.1f} mm from the nearest node of the face (limit "
                             f"{max_distance * 1e3:.0f} mm): align the data to the model first",
                             source=ms.meta.get("source"), field=name)
        out[name] = int(node)
    return out


def read_mapping(path: str | Path, ms: MarkerSet, model) -> dict[str, int]:
    """Read a ``marker,node`` mapping CSV against a marker set and a face."""
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", source=str(path))
    sites = {**model.landmarks, **model.markers}
    out = {}
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        if not reader.fieldnames or {"marker", "node"} - {f.strip() for f in reader.fieldnames}:
            raise InputError("needs columns marker,node", source=str(path), field="header")
        for row in reader:
            name, node = row["marker"].strip(), row["node"].strip()
            if name not in ms.names:
                raise InputError("unknown marker name (not in the marker data)",
                                 source=str(path), field=name)
            if node in sites:
                out[name] = int(sites[node])
            elif node.isdigit() and int(node) < model.n_surface:
                out[name] = int(node)
            else:
                raise InputError(f"unknown node {node!r} (an epidermal node index or a site "
                                 "name of the face)", source=str(path), field=name)
    return out


@dataclass(frozen=True, eq=False)
class ScalingAdaptation:
    """Per-axis scale factors (3,) and per-marker offsets (markers, 3) in metres."""

    factors: np.ndarray
    offsets: np.ndarray
    markers: MarkerSet


def scale_adapt(ms: MarkerSet, model, mapping: dict[str, int], far_pair: tuple[str, str], *,
                reference: int = 0) -> ScalingAdaptation:
    """Adapt markers to the model by per-axis scaling and a rest-position shift (P&M 2001)."""
    a, b = far_pair
    for n in (a, b):
        if n not in mapping:
            raise InputError(f"scaling marker {n!r} (--scale-pair {a},{b}) has no node on the "
                             "face: choose two skin markers", field="scale-pair")
    rest = model.rest_positions
    dn = np.abs(rest[mapping[a]] - rest[mapping[b]])
    dm = np.abs(ms.marker(a)[reference] - ms.marker(b)[reference])
    if np.any(dm < 1e-4) or np.any(dn < 1e-4):
        raise InputError(f"markers {a} and {b} are less than 0.1 mm apart on some axis: choose "
                         "two markers far apart on every axis", field="far_pair")
    factors = dn / dm
    scaled = ms.positions * factors
    offsets = np.zeros((ms.n_markers, 3))
    for name, node in mapping.items():
        m = ms.index(name)
        offsets[m] = rest[node] - scaled[reference, m]
    out = ms.with_positions(scaled + offsets, meta={**ms.meta, "scale_factors": factors.tolist()})
    return ScalingAdaptation(factors, offsets, out)


def warp_face(model, ms: MarkerSet, mapping: dict[str, int], *, reference: int = 0,
              smoothing: float = 0.0):
    """Adapt the face to a talker: a thin-plate-spline warp of every node (all three layers, the
    hinge) that carries the mapped marker nodes onto the talker's rest markers.

    Returns a new :class:`~facemech.geometry.builder.FaceModel`; the markers stay as measured.
    """
    from dataclasses import replace

    from scipy.interpolate import RBFInterpolator

    names = [n for n in ms.names if n in mapping]
    if len(names) < 5:
        raise InputError("the warp needs at least 5 mapped markers", field="mapping")
    src = model.rest_positions[[mapping[n] for n in names]]
    dst = np.array([ms.marker(n)[reference] for n in names])
    if not np.all(np.isfinite(dst)):
        raise InputError(f"mapped markers missing at the reference frame {reference}",
                         field="reference")
    rbf = RBFInterpolator(src, dst - src, kernel="thin_plate_spline", degree=1,
                          smoothing=smoothing)
    rest = model.rest_positions + rbf(model.rest_positions)
    hinge = model.hinge_point + rbf(model.hinge_point[None])[0]
    surface = None
    if model.surface is not None:  # so that the warped face can be rebuilt for another tissue
        sv = np.asarray(model.surface["vertices"], float)
        lms = {k: np.asarray(v, float) + rbf(np.asarray(v, float)[None])[0]
               for k, v in model.surface["landmarks"].items()}
        surface = {"vertices": sv + rbf(sv), "faces": model.surface["faces"], "landmarks": lms}
    return replace(model, rest_positions=rest, hinge_point=hinge, name=f"{model.name}-warped",
                   surface=surface)
