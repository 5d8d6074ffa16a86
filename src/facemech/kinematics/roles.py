"""Articulography markers by role: which sensor is a lip, which is on the bone, which is unused.

A reader of articulography (EMA, X-ray microbeam) names each sensor's role in the marker set's
``meta["roles"]`` (sensor name -> one of :data:`ROLES`) and marks planar data with
``meta["midsagittal"] = True`` (x = 0, the midsagittal plane; y up, z forward). This module
turns those roles into what the model uses:

- ``lower_incisor`` is the jaw's bone point, ``molar`` (a mandibular molar pellet, as X-ray
  microbeam's) a second one (:mod:`facemech.solvers.jaw_bone`); neither is compared with the
  skin;
- ``upper_lip`` and ``lower_lip`` are the model's midsagittal vermilion points, the landmarks
  :data:`LIP_SITES` (the midline of each lip's vermilion border, where the coils are glued);
- ``upper_incisor``, ``tongue``, ``velum``, ``reference`` and ``other`` are kept in the data and
  not used: the model has no tongue or velum, and the references serve the head correction
  made before.

An articulograph's coordinates are its own, not the face model's: the lips are laid on their
sites by their displacement from the first frame (:func:`on_sites`), which is taken as rest. In
midsagittal data only y and z carry information: :func:`pinned_x` sets each marker's x to its
node's rest x so that x adds nothing to a fit.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..markerset import SENSOR_ROLES as ROLES
from ..markerset import MarkerSet

__all__ = ["BONE_ROLES", "LIP_SITES", "ROLES", "bone_points", "is_midsagittal", "lip_markers",
           "marker_roles", "on_sites", "pinned_x"]

#: role -> the face's landmark of the lip's midsagittal vermilion point
LIP_SITES = {"upper_lip": "upper_lip_center", "lower_lip": "lower_lip_center"}
#: roles of points on the mandible
BONE_ROLES = ("lower_incisor", "molar")


def marker_roles(ms: MarkerSet) -> dict[str, str]:
    """The sensors' roles ({} when the set carries none), checked against the set's names and
    :data:`ROLES` (an :class:`InputError` naming the sensor otherwise)."""
    roles = ms.meta.get("roles") or {}
    src = ms.meta.get("source")
    if not isinstance(roles, dict):
        raise InputError("marker roles must map sensor names to roles", source=src,
                         field="roles")
    out = {}
    for name, role in roles.items():
        if name not in ms.names:
            continue  # a sensor the reader named but that was left out (e.g. by select)
        if role not in ROLES:
            raise InputError(f"unknown role {role!r} (expected one of {', '.join(ROLES)})",
                             source=src, field=str(name))
        out[str(name)] = str(role)
    return out


def is_midsagittal(ms: MarkerSet) -> bool:
    """Whether the set is planar midsagittal data (``meta["midsagittal"]``)."""
    return bool(ms.meta.get("midsagittal", False))


def _with_role(ms: MarkerSet, roles: dict[str, str], role: str) -> list[str]:
    return [n for n in ms.names if roles.get(n) == role]


def bone_points(ms: MarkerSet, *, incisor: str | None = None, molar: str | None = None,
                skin_jaw: str | None = None) -> tuple[str | None, str | None, bool]:
    """The jaw's bone points of a marker set: (incisor, molar, found by role).

    Named points are checked against the set and against the sensors' roles (a named incisor
    whose role is, e.g., ``upper_lip`` is refused, naming the role); without names, and without
    a skin jaw marker (``skin_jaw``, e.g. ``--chin-marker``), the sensor of role
    ``lower_incisor`` is the incisor and the one of role ``molar`` the second point. A molar
    needs an incisor.
    """
    src = ms.meta.get("source")
    if molar is not None and incisor is None:
        raise InputError("a molar point needs the lower incisor too (--jaw-incisor)",
                         source=src, field="jaw-molar")
    if incisor is not None and skin_jaw is not None:
        raise InputError("give one jaw drive: a bone point (--jaw-incisor) or a skin marker "
                         "(--chin-marker)", source=src, field="jaw-incisor")
    for name in (incisor, molar):
        if name is not None and name not in ms.names:
            raise InputError("jaw bone point not in the marker data", source=src, field=name)
    if incisor is not None and incisor == molar:
        raise InputError(f"{incisor!r} is given as both the incisor and the molar point",
                         source=src, field="jaw-molar")
    roles = marker_roles(ms)
    for name, role in ((incisor, "lower_incisor"), (molar, "molar")):
        _check_bone_role(ms, roles, name, role)
    if incisor is not None or skin_jaw is not None:
        return incisor, molar, False
    found = {}
    for role in BONE_ROLES:
        names = _with_role(ms, roles, role)
        if len(names) > 1:
            raise InputError(f"{len(names)} sensors have the role {role}: name the one to use "
                             "(--jaw-incisor, --jaw-molar)", source=src, field=names[1])
        found[role] = names[0] if names else None
    if found["lower_incisor"] is None:
        return None, None, False
    return found["lower_incisor"], found["molar"], True


def _check_bone_role(ms: MarkerSet, roles: dict[str, str], name: str | None,
                     role: str) -> None:
    """Refuse a sensor named as the bone point of ``role`` (``lower_incisor`` for
    ``--jaw-incisor``, ``molar`` for ``--jaw-molar``) whose own role is another one; a sensor
    without a role, or of role ``other``, is taken as named."""
    has = roles.get(name or "")
    if name is None or has in (None, "other", role):
        return
    option = "jaw-incisor" if role == "lower_incisor" else "jaw-molar"
    what = "another point on the jaw bone" if has in BONE_ROLES else "not a point on the jaw bone"
    raise InputError(f"--{option} {name}: the sensor's role is {has}, {what} (--{option} takes "
                     f"the sensor of role {role})", source=ms.meta.get("source"), field=option)


def lip_markers(ms: MarkerSet, model) -> dict[str, int]:
    """name -> epidermal node of the sensors of role ``upper_lip`` or ``lower_lip`` (the
    face's landmarks :data:`LIP_SITES`)."""
    roles = marker_roles(ms)
    out = {}
    for name in ms.names:
        site = LIP_SITES.get(roles.get(name, ""))
        if site is None:
            continue
        if site not in model.landmarks:
            raise InputError(f"the face has no {site} landmark for the {roles[name]} sensor",
                             field=name)
        out[name] = int(model.landmarks[site])
    return out


def on_sites(ms: MarkerSet, model, mapping: dict[str, int]) -> MarkerSet:
    """The set with each mapped marker moved so that its first sample (its first present one,
    if the recording starts in a gap) lies on its node at rest: its displacements (m) are kept,
    its place in the articulograph's frame is not."""
    pos = np.array(ms.positions)
    rest = model.rest_positions
    for j, name in enumerate(ms.names):
        if name not in mapping:
            continue
        pos[:, j] += rest[mapping[name]] - _first_sample(ms, j)
    return ms.with_positions(pos)


def _first_sample(ms: MarkerSet, j: int) -> np.ndarray:
    ok = np.nonzero(np.all(np.isfinite(ms.positions[:, j]), axis=1))[0]
    if len(ok) == 0:
        raise InputError("no sample in the whole recording", source=ms.meta.get("source"),
                         field=ms.names[j])
    return ms.positions[ok[0], j]


def pinned_x(ms: MarkerSet, model, mapping: dict[str, int]) -> MarkerSet:
    """Midsagittal data: each mapped marker's x set to its node's rest x (m), gaps kept, so
    that a fit's x residual is only the model point's own sideways motion (none on a
    symmetric face under its symmetric muscle groups)."""
    pos = np.array(ms.positions)
    rest = model.rest_positions
    for j, name in enumerate(ms.names):
        if name in mapping:
            ok = np.isfinite(pos[:, j, 1]) & np.isfinite(pos[:, j, 2])
            pos[ok, j, 0] = rest[mapping[name], 0]
    return ms.with_positions(pos)
