"""Springs and prisms between the three layers (Lucero & Munhall 1999, I.A).

A spring joins two nodes and has a :class:`~.kinds.SpringKind`; a prism is a surface triangle
with the one below it (six nodes, top triangle first).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .kinds import EPIDERMIS, FASCIA, SKULL, SpringKind, layer_nodes
from .layers import Layers
from .mesh import surface_edges


@dataclass(frozen=True)
class Topology:
    """Springs and prisms of a layered face.

    Parameters
    ----------
    spring_i, spring_j : (s,) int64 arrays, the nodes each spring joins
    spring_kind : (s,) int8 array, :class:`SpringKind`
    prism_nodes : (p, 6) int64 array, a top triangle then the one below
    """

    spring_i: np.ndarray
    spring_j: np.ndarray
    spring_kind: np.ndarray
    prism_nodes: np.ndarray


def _springs(groups: list[tuple[np.ndarray, np.ndarray, SpringKind]]) -> tuple[np.ndarray, ...]:
    """(spring_i, spring_j, spring_kind) of groups of (nodes i, nodes j, kind)."""
    spring_i = np.concatenate([i for i, _, _ in groups]).astype(np.int64)
    spring_j = np.concatenate([j for _, j, _ in groups]).astype(np.int64)
    spring_kind = np.concatenate([np.full(len(i), int(k)) for i, _, k in groups]).astype(np.int8)
    return spring_i, spring_j, spring_kind


def _prism_layer(faces: np.ndarray, top: int, n: int) -> np.ndarray:
    """Prisms (f, 6) from the triangles ``faces`` in layer ``top`` to their copies below."""
    return np.concatenate([layer_nodes(faces, top, n), layer_nodes(faces, top + 1, n)], axis=1)


def uniform_topology(faces: np.ndarray, layers: Layers) -> Topology:
    """The seeds' springs and prisms.

    Springs join the epidermis within itself, epidermis to fascia (dermal-fatty), the fascia
    within itself, and fascia to skull (muscle layer) where the fascia is tied; a prism joins
    epidermis and fascia everywhere and fascia and skull where the fascia is tied.
    """
    n = layers.n_surface
    edges = surface_edges(faces)
    idx = np.arange(n)
    tied = layers.tied
    spring_i, spring_j, spring_kind = _springs([
        (edges[:, 0], edges[:, 1], SpringKind.EPIDERMIS),
        (layer_nodes(edges[:, 0], FASCIA, n), layer_nodes(edges[:, 1], FASCIA, n),
         SpringKind.FASCIA),
        (idx, layer_nodes(idx, FASCIA, n), SpringKind.DERMAL_FATTY),
        (layer_nodes(tied, FASCIA, n), layer_nodes(tied, SKULL, n), SpringKind.MUSCLE_LAYER),
    ])
    tied_tri = ~layers.free[faces].any(axis=1)
    prism_nodes = np.concatenate([_prism_layer(faces, EPIDERMIS, n),
                                  _prism_layer(faces[tied_tri], FASCIA, n)]).astype(np.int64)
    return Topology(spring_i, spring_j, spring_kind, prism_nodes)


def anatomical_topology(faces: np.ndarray, layers: Layers) -> Topology:
    """Two prism layers everywhere and a spring on every prism edge, diagonals included.

    The diagonals of the prisms' side faces carry the tissue's shear. Edges between two
    kinematic skull nodes carry no force and are left out: the skull layer's edges are springs
    only where it slides (the fold of the vestibule gives the mucosa slack).
    """
    n = layers.n_surface
    edges = surface_edges(faces)
    idx = np.arange(n)
    a, b = edges[:, 0], edges[:, 1]
    skull_edge = layers.slides[a] & layers.slides[b]
    a_fascia, b_fascia = layer_nodes(a, FASCIA, n), layer_nodes(b, FASCIA, n)
    a_skull, b_skull = layer_nodes(a, SKULL, n), layer_nodes(b, SKULL, n)
    spring_i, spring_j, spring_kind = _springs([
        (a, b, SpringKind.EPIDERMIS),
        (a_fascia, b_fascia, SpringKind.FASCIA),
        (a_skull[skull_edge], b_skull[skull_edge], SpringKind.SKULL),
        (idx, layer_nodes(idx, FASCIA, n), SpringKind.DERMAL_FATTY),
        (layer_nodes(idx, FASCIA, n), layer_nodes(idx, SKULL, n), SpringKind.MUSCLE_LAYER),
        (a, b_fascia, SpringKind.SUPERFICIAL_DIAGONAL),
        (b, a_fascia, SpringKind.SUPERFICIAL_DIAGONAL),
        (a_fascia, b_skull, SpringKind.DEEP_DIAGONAL),
        (b_fascia, a_skull, SpringKind.DEEP_DIAGONAL),
    ])
    prism_nodes = np.concatenate([_prism_layer(faces, EPIDERMIS, n),
                                  _prism_layer(faces, FASCIA, n)]).astype(np.int64)
    return Topology(spring_i, spring_j, spring_kind, prism_nodes)


def check_prisms(rest: np.ndarray, prism_nodes: np.ndarray, source: str | None = None) -> None:
    """Every prism of the thick tissue must have a positive volume (no folded layer).

    Raises
    ------
    InputError
        A prism has no volume (names where): left after :mod:`thinning` has mended what it can,
        this is skin that folds over itself or a rim sharper than 3 mm of tissue.
    """
    from .prism import rest_geometry

    vols, _ = rest_geometry(rest, prism_nodes)
    if np.any(vols <= 0):
        bad = int(np.argmin(vols))
        p = rest[prism_nodes[bad, 0]] * 1e3
        raise InputError("the tissue layers fold (a prism has no volume) near "
                         f"({p[0]:.0f}, {p[1]:.0f}, {p[2]:.0f}) mm even with the tissue thinned "
                         "to 3 mm and its offsets turned there: the skin folds over itself or "
                         "is too sharp there; smooth the scan there", source=source,
                         field="tissue")
