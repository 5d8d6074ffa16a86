"""menpo's landmark files (``.ljson``, versions 1 to 3) read into the iBUG-68 order.

menpo keeps a point cloud and labels that each name a part of the face and list (``mask``) its
rows. Version 1: ``groups`` a list of ``{"label", "landmarks": [{"point": [...]}, ...]}``;
version 2: ``landmarks.points`` and ``labels`` (``{"label", "mask"}``); version 3: ``groups`` a
mapping from a group's name (``PTS``, ``face_ibug_68``, ...) to a version-2 body.
:func:`read_ljson_points` puts every part's points at the part's iBUG indices, whether the parts
carry menpo's iBUG-68 names (``jaw`` 0-16, ``left_eyebrow`` 17-21, ``right_eyebrow`` 22-26,
``nose`` 27-35, ``left_eye`` 36-41, ``right_eye`` 42-47, ``mouth`` 48-67; "left" the image's)
or landmarker.io's (``chin``, ``leye``, ``reye``, ``leyebrow``, ``nose``, ``reyebrow``,
``mouth``), in any order. Which eye and brow is which is decided by the points: those on the
side of the jaw line's first point (iBUG 0, the subject's right) go to 36-41 and 17-21; without
a jaw the names decide, in menpo's sense. A group whose labels are not parts of the face
(``all``, ``tri``, none) holds its points in the iBUG order already.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

N_POINTS = 68

#: an iBUG-68 part -> its indices (0-based), in the part's own order
PARTS: dict[str, range] = {
    "jaw": range(0, 17), "brow_a": range(17, 22), "brow_b": range(22, 27),
    "nose": range(27, 36), "nose_bridge": range(27, 31), "nose_base": range(31, 36),
    "eye_a": range(36, 42), "eye_b": range(42, 48),
    "mouth": range(48, 68), "mouth_outer": range(48, 60), "mouth_inner": range(60, 68),
}  # fmt: skip
#: "a" is the image's left (the subject's right, iBUG's lower numbers), as menpo names it

#: the names files give the parts (lower case, letters only) -> the part
PART_NAMES: dict[str, str] = {
    **dict.fromkeys(("jaw", "chin", "jawline", "contour", "facecontour", "outline"), "jaw"),
    **dict.fromkeys(("lefteyebrow", "leyebrow", "leftbrow", "lbrow"), "brow_a"),
    **dict.fromkeys(("righteyebrow", "reyebrow", "rightbrow", "rbrow"), "brow_b"),
    "nose": "nose",
    **dict.fromkeys(("nosebridge", "uppernose", "bridge"), "nose_bridge"),
    **dict.fromkeys(("nosebase", "lowernose", "nosebottom", "nostrils", "nosetip"),
                    "nose_base"),
    **dict.fromkeys(("lefteye", "leye"), "eye_a"),
    **dict.fromkeys(("righteye", "reye"), "eye_b"),
    **dict.fromkeys(("mouth", "lips"), "mouth"),
    **dict.fromkeys(("outermouth", "mouthouter", "outerlips", "outerlip", "lipsouter"),
                    "mouth_outer"),
    **dict.fromkeys(("innermouth", "mouthinner", "innerlips", "innerlip", "lipsinner"),
                    "mouth_inner"),
}


@dataclass(frozen=True)
class LjsonPoints:
    """The iBUG-68 points of a menpo landmark file.

    Attributes
    ----------
    points : (68, d) float array, d = 2 or 3, the file's unit; NaN where the file has ``null``
    rows : (68,) int array, the file's row (in its point list) of each iBUG point
    field : where the points are in the file (``landmarks``, ``groups.PTS.landmarks``, ...)
    version : the file's LJSON version (1, 2 or 3)
    by_labels : the parts' names in the file's order when its labels ordered the points, else
        empty (the file's order is iBUG's)
    """

    points: np.ndarray
    rows: np.ndarray
    field: str
    version: int
    by_labels: tuple[str, ...] = ()


def read_ljson_points(path: str | Path) -> LjsonPoints:
    """The 68 points of a menpo ``.ljson`` file in iBUG order (versions 1, 2 and 3).

    Parameters
    ----------
    path : the file

    Returns
    -------
    LjsonPoints : (68, 2) or (68, 3) points in the file's unit, ``null`` as NaN

    Raises
    ------
    InputError
        One line naming the file and the field: not JSON or not a menpo landmark file, an
        unknown version, no group of 68 points, rows of different lengths or not numbers, a
        label's mask out of range or of the wrong size, parts missing or given twice.
    """
    path = Path(path)
    src = str(path)
    try:
        data = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError):
        raise InputError("not a JSON file", source=src, field="landmarks") from None
    if not isinstance(data, dict):
        raise InputError("not a menpo landmark file (a JSON object with landmarks or groups "
                         "expected)", source=src, field="landmarks")
    version = _version(data, src)
    if version == 3:
        field, raw, labels = _group_v3(data, src)
    elif version == 2:
        body = data.get("landmarks")
        if not isinstance(body, dict) or "points" not in body:
            raise InputError("version 2 keeps its points in landmarks.points", source=src,
                             field="landmarks")
        field, raw, labels = "landmarks", body["points"], data.get("labels", [])
    else:
        field, raw, labels = _groups_v1(data, src)
    points = _rows(raw, src, field)
    masks = _masks(labels, len(points), src, _labels_field(field))
    order, names = _ibug_order(points, masks, src, field)
    return LjsonPoints(points[order], order, field, version, names)


# ---- the versions ----------------------------------------------------------------------------
def _version(data: dict, src: str) -> int:
    """The file's version, from ``version`` or, without one, from its layout."""
    v = data.get("version")
    if v is None:
        if isinstance(data.get("groups"), dict):
            return 3
        if "landmarks" in data:
            return 2
        if isinstance(data.get("groups"), list):
            return 1
        raise InputError("not a menpo landmark file (expected version 3 groups.NAME.landmarks"
                         ".points, version 2 landmarks.points or version 1 "
                         "groups[].landmarks[].point)", source=src, field="landmarks")
    if v not in (1, 2, 3):
        raise InputError(f"LJSON version {v!r}; versions 1, 2 and 3 are read", source=src,
                         field="version")
    return int(v)


def _group_v3(data: dict, src: str) -> tuple[str, list, list]:
    """(field, point rows, labels) of the first group of 68 points of a version-3 file."""
    groups = data.get("groups")
    if not isinstance(groups, dict) or not groups:
        raise InputError("version 3 keeps its landmarks in groups, a mapping from a group's "
                         "name to its landmarks.points", source=src, field="groups")
    sizes = {}
    for key, group in groups.items():
        field = f"groups.{key}.landmarks"
        if not isinstance(group, dict) or not isinstance(group.get("landmarks"), dict) \
                or not isinstance(group["landmarks"].get("points"), list):
            raise InputError("a group without landmarks.points", source=src, field=field)
        sizes[key] = len(group["landmarks"]["points"])
        if sizes[key] == N_POINTS:
            return field, group["landmarks"]["points"], group.get("labels") or []
    have = ", ".join(f"{k} ({n} points)" for k, n in sizes.items())
    raise InputError(f"no group of {N_POINTS} points (iBUG-68): {have}", source=src,
                     field="groups")


def _groups_v1(data: dict, src: str) -> tuple[str, list, list]:
    """(field, point rows, labels) of a version-1 file: its groups one after another."""
    raw: list = []
    labels: list = []
    groups = data.get("groups")
    if not isinstance(groups, list):
        raise InputError("version 1 keeps its landmarks in groups, a list", source=src,
                         field="groups")
    for k, group in enumerate(groups):
        try:
            rows = [p["point"] for p in group["landmarks"]]
        except (KeyError, TypeError):
            raise InputError("a group without landmarks[].point", source=src,
                             field=f"groups[{k}].landmarks") from None
        labels.append({"label": group.get("label", ""),
                       "mask": list(range(len(raw), len(raw) + len(rows)))})
        raw.extend(rows)
    return "groups", raw, labels


# ---- points and labels -----------------------------------------------------------------------
def _rows(raw, src: str, field: str) -> np.ndarray:
    """(n, d) floats of a list of rows of 2 or 3 numbers or nulls (NaN)."""
    if not isinstance(raw, list) or not all(isinstance(r, list) for r in raw):
        raise InputError("points must be a list of rows [x, y] or [x, y, z]", source=src,
                         field=field)
    dims = {len(r) for r in raw}
    if len(dims) > 1:
        raise InputError(f"rows with different numbers of coordinates ({sorted(dims)})",
                         source=src, field=field)
    try:
        points = np.array([[np.nan if c is None else float(c) for c in r] for r in raw], float)
    except (TypeError, ValueError):
        raise InputError("coordinates are not numbers", source=src, field=field) from None
    return points.reshape(len(raw), dims.pop() if dims else 0)


def _masks(labels, n: int, src: str, field: str) -> list[tuple[str, np.ndarray]]:
    """[(label, rows)] of a labels list; a mask is a list of rows or of n booleans."""
    if not isinstance(labels, list):
        raise InputError("labels must be a list of {label, mask}", source=src, field=field)
    out = []
    for k, item in enumerate(labels):
        where = f"{field}[{k}]"
        if not isinstance(item, dict) or not isinstance(item.get("mask"), list):
            raise InputError("a label without a mask (the list of its rows)", source=src,
                             field=where)
        mask = item["mask"]
        if len(mask) == n and mask and all(isinstance(m, bool) for m in mask):
            rows = np.nonzero(mask)[0]
        elif all(isinstance(m, int) and not isinstance(m, bool) for m in mask):
            rows = np.array(mask, np.int64)
        else:
            raise InputError("a mask must list row numbers (or hold one true/false a row)",
                             source=src, field=f"{where}.mask")
        if len(rows) and (rows.min() < 0 or rows.max() >= n):
            raise InputError(f"a mask row out of range (the group has {n} points)",
                             source=src, field=f"{where}.mask")
        out.append((str(item.get("label", "")), rows))
    return out


def _labels_field(field: str) -> str:
    """Where the labels are beside the points at ``field``."""
    if field.endswith(".landmarks"):
        return field[: -len("landmarks")] + "labels"
    return "groups" if field == "groups" else "labels"


def _part(label: str) -> str | None:
    return PART_NAMES.get(re.sub(r"[^a-z]", "", label.lower()))


def _ibug_order(points: np.ndarray, masks: list[tuple[str, np.ndarray]], src: str,
                field: str) -> tuple[np.ndarray, tuple[str, ...]]:
    """The file's row of each iBUG point (68,), and the parts' names if the labels set it."""
    n = len(points)
    if n != N_POINTS:
        raise InputError(f"{n} points; the iBUG convention has {N_POINTS}", source=src,
                         field=field)
    identity = np.arange(N_POINTS)
    parts = [(label, _part(label), rows) for label, rows in masks]
    if not parts or any(len(rows) == n for *_, rows in parts) \
            or all(p is None for _, p, _ in parts):
        return identity, ()  # menpo's own order: the points as stored
    unknown = [label for label, p, _ in parts if p is None]
    label_field = _labels_field(field)
    if unknown:
        raise InputError(f"label {unknown[0]!r} is not a part of the iBUG-68 face (expected "
                         "jaw or chin, left/right eye and eyebrow, nose, mouth)", source=src,
                         field=label_field)
    order = np.full(N_POINTS, -1)
    for label, part, rows in parts:
        target = np.array(PARTS[part])
        if len(rows) != len(target):
            raise InputError(f"label {label!r} has {len(rows)} points; the iBUG-68 part has "
                             f"{len(target)}", source=src, field=label_field)
        if np.any(order[target] >= 0):
            raise InputError(f"label {label!r} gives iBUG points already given by another "
                             "label", source=src, field=label_field)
        order[target] = rows
    if np.any(order < 0):
        k = int(np.argmax(order < 0))
        raise InputError(f"no label gives iBUG point {k} (0-based): the labels must cover "
                         "the jaw, both eyes and eyebrows, the nose and the mouth", source=src,
                         field=label_field)
    if len(np.unique(order)) != N_POINTS:
        raise InputError("two labels share a row", source=src, field=label_field)
    order = _sides_by_position(points, order)
    return order, tuple(label for label, _, _ in parts)


def _sides_by_position(points: np.ndarray, order: np.ndarray) -> np.ndarray:
    """``order`` with the eyes (and, apart, the brows) swapped if the one put at 36-41 (17-21)
    lies nearer the jaw line's end (iBUG 9-16, the subject's left) than its start (0-7)."""
    p = points[order]
    start, end = p[0:8], p[9:17]
    if not (np.isfinite(start).all(axis=1).any() and np.isfinite(end).all(axis=1).any()):
        return order
    a = np.nanmean(np.where(np.isfinite(start).all(axis=1)[:, None], start, np.nan), axis=0)
    b = np.nanmean(np.where(np.isfinite(end).all(axis=1)[:, None], end, np.nan), axis=0)
    out = order.copy()
    for first, second in (("eye_a", "eye_b"), ("brow_a", "brow_b")):
        i, j = np.array(PARTS[first]), np.array(PARTS[second])
        ci, cj = np.nanmean(p[i], axis=0), np.nanmean(p[j], axis=0)
        if not (np.isfinite(ci).all() and np.isfinite(cj).all()):
            continue
        # the part at 36-41 (17-21) belongs on the jaw's start side; its partner on the end's
        if np.linalg.norm(ci - a) + np.linalg.norm(cj - b) \
                > np.linalg.norm(ci - b) + np.linalg.norm(cj - a):
            out[i], out[j] = order[j], order[i]
    return out
