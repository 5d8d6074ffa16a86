"""Resolution-consistent constants of a spring-and-prism tissue from moduli, density, viscosity.

The seeds give stiffness per 1-cm spring and a mass per node, so the response of their model
changes with the mesh. Here each element passes its share of a continuum's energy to its edges,
so that refining the mesh leaves the response unchanged:

- **volume springs** (Lloyd et al. 2007 and Van Gelder 1998 for the idea): a prism of rest volume
  ``V`` adds ``mu V / |e|^2`` to the stiffness of each of its 15 edges (6 triangle edges, 3 along
  the depth, 6 face diagonals). For an isotropic spread of edge directions this stores the energy
  ``V (mu tr(eps^2) + mu/2 tr(eps)^2)`` of a uniform strain ``eps``: a linear solid of shear
  modulus ``mu`` and, as every central-force lattice, Poisson's ratio 1/4;
- **volume term**: what the springs lack in bulk modulus to reach the tissue's Poisson's ratio
  ``nu``, ``K_x = 2 mu (1 + nu) / (3 (1 - 2 nu)) - 5 mu / 3``, acts as a pressure on each prism,
  energy ``K_x (V - V0)^2 / (2 V0)`` (the resolution-consistent form of eq. 9's first term);
- **skin membrane** (Van Gelder 1998): a surface triangle of area ``A`` adds ``E t A / |e|^2`` to
  each of its edges, which is exact for a membrane of Young's modulus x thickness ``E t`` on an
  equilateral mesh (Poisson's ratio 1/3);
- **masses** lumped from density: each node takes a sixth of the volume of every prism it is a
  corner of;
- **damping** from viscosity: each spring gets a dashpot ``eta / mu`` times its stiffness
  (stiffness-proportional, Rayleigh's beta = ``viscous_time``), so a mode of angular frequency
  ``w`` has a damping ratio ``beta w / 2`` at every resolution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.model import FaceModel
from ..geometry.prism import rest_geometry
from ..params import Parameters

# the 15 edges of a prism (a, b, c) over (d, e, f), as index pairs into its 6 nodes
PRISM_EDGES = np.array([(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5),
                        (0, 4), (1, 3), (1, 5), (2, 4), (2, 3), (0, 5)], dtype=np.int64)


@dataclass(frozen=True, eq=False)
class ContinuumConstants:
    """Per-element constants of the continuum tissue (SI)."""

    spring_k: np.ndarray  # (s,) N/m
    spring_damping: np.ndarray  # (s,) N s/m
    node_mass: np.ndarray  # (nodes,) kg (0 for nodes in no prism)
    prism_bulk: np.ndarray  # (p,) N/m^2 / m^3: K_x / V0 of each prism
    contact_k: np.ndarray  # (lip pairs,) N/m
    tether_k: np.ndarray  # (sliding nodes,) N/m
    bone_k: np.ndarray  # (sliding nodes,) N/m, contact with the teeth and bone


def extra_bulk_modulus(mu, nu: float):
    """Bulk modulus (Pa) the volume term adds to a spring lattice of shear modulus ``mu`` so
    that the tissue has Poisson's ratio ``nu``."""
    target = 2.0 * np.asarray(mu, float) * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu))
    return np.maximum(target - 5.0 * np.asarray(mu, float) / 3.0, 0.0)


def _spring_index(spring_i: np.ndarray, spring_j: np.ndarray, n_nodes: int):
    """A lookup from a node pair to its spring (or -1)."""
    key = np.minimum(spring_i, spring_j) * n_nodes + np.maximum(spring_i, spring_j)
    order = np.argsort(key)
    sorted_keys = key[order]

    def find(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        q = np.minimum(a, b) * n_nodes + np.maximum(a, b)
        pos = np.clip(np.searchsorted(sorted_keys, q), 0, len(sorted_keys) - 1)
        return np.where(sorted_keys[pos] == q, order[pos], -1)

    return find


def prism_shear_modulus(model: FaceModel, params: Parameters) -> np.ndarray:
    """Shear modulus (Pa) of every prism: superficial or deep layer, scaled in the lips."""
    n = model.n_surface
    pn = model.prism_nodes
    mu = np.where(pn[:, 0] < n, params.shear_superficial, params.shear_deep)
    if model.lip_region is not None and params.lip_stiffness_factor != 1.0:
        in_lips = np.asarray(model.lip_region)[pn[:, :3] % n].all(axis=1)
        mu = np.where(in_lips, mu * params.lip_stiffness_factor, mu)
    return mu


def continuum_constants(model: FaceModel, params: Parameters) -> ContinuumConstants:
    """Spring stiffness and damping, node masses, prism bulk terms and lip contact stiffness."""
    rest = model.rest_positions
    n_nodes = model.n_nodes
    pn = model.prism_nodes
    vols, _ = rest_geometry(rest, pn, symmetric=True)
    mu = prism_shear_modulus(model, params)
    find = _spring_index(model.spring_i, model.spring_j, n_nodes)
    k = np.zeros(len(model.spring_i))
    for a, b in PRISM_EDGES:
        i, j = pn[:, a], pn[:, b]
        s = find(i, j)
        length2 = np.sum((rest[j] - rest[i]) ** 2, axis=1)
        ok = s >= 0  # edges between two kinematic nodes carry no spring
        np.add.at(k, s[ok], (mu * vols / length2)[ok])
    # skin membrane on the epidermal triangles
    f = model.faces
    pa, pb, pc = (rest[f[:, q]] for q in range(3))
    area = 0.5 * np.linalg.norm(np.cross(pb - pa, pc - pa), axis=1)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        i, j = f[:, a], f[:, b]
        s = find(i, j)
        length2 = np.sum((rest[j] - rest[i]) ** 2, axis=1)
        np.add.at(k, s[s >= 0], (params.skin_modulus_thickness * area / length2)[s >= 0])
    mass = np.zeros(n_nodes)
    for q in range(6):
        np.add.at(mass, pn[:, q], params.density * vols / 6.0)
    bulk = extra_bulk_modulus(mu, params.poisson) / vols
    # lip contact: a stiffness per length of lip line, shared among the pairs of each layer
    pairs = model.lip_pairs
    contact = np.zeros(len(pairs))
    if len(pairs):
        layer = pairs[:, 0] // model.n_surface
        for lay in np.unique(layer):
            sel = layer == lay
            pts = rest[pairs[sel, 0]]
            order = np.argsort(pts[:, 0])
            line = np.sum(np.linalg.norm(np.diff(pts[order], axis=0), axis=1))
            contact[sel] = params.k_lip_contact * line / max(sel.sum(), 1)
    # tethers: the sliding deep surface is held to the bone by loose areolar tissue, a
    # stiffness per area of the surface (each node's share of the skin area above it)
    n = model.n_surface
    node_area = np.zeros(n)
    for q in range(3):
        np.add.at(node_area, f[:, q], area / 3.0)
    order = np.argsort(np.asarray(model.sliding, np.int64))
    sliding = np.asarray(model.sliding, np.int64)[order]
    held = (np.ones(len(sliding)) if model.sliding_tether is None
            else np.asarray(model.sliding_tether, float)[order])
    tether = params.tether * node_area[sliding - 2 * n] * held
    bone = params.k_bone_contact * node_area[sliding - 2 * n]
    return ContinuumConstants(spring_k=k, spring_damping=params.viscous_time * k,
                              node_mass=mass, prism_bulk=bulk, contact_k=contact,
                              tether_k=tether, bone_k=bone)
