"""A scan-like face for tests: the generic surface re-sampled irregularly and reshaped.

A real scan has an irregular triangulation, its own proportions and its own mesh density. This
one samples the generic surface at jittered points of its (angle, height) parameter plane,
triangulates them (Delaunay), keeps a row of points on the lip line so that the mouth can be
cut, and reshapes the result (wider, shorter, a fuller lower face) like another person.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import Delaunay

from facemech.geometry import generic


def reshape(p):
    """Another person's proportions (metres in, metres out)."""
    p = np.array(p, float)
    out = p.copy()
    out[..., 0] = p[..., 0] * 1.05
    out[..., 1] = p[..., 1] * 0.96
    out[..., 2] = p[..., 2] * 1.03
    return out


def scan_face(spacing_deg: float = 2.4, spacing_mm: float = 3.0, seed: int = 0,
              lip_points: int = 15):
    """Vertices (m), triangles and landmarks (m) of the scan-like face."""
    pts, tri = _parameter_mesh(spacing_deg, spacing_mm, seed, lip_points, generic.Y_BOTTOM)
    theta, y = np.radians(pts[:, 0]), pts[:, 1]
    bx, bz = generic._row_point(theta, y)
    verts = np.column_stack([bx, y, bz + generic.features(bx, y)]) * 1e-3
    tri = _wound(pts, tri, verts)
    lm = {k: v * 1e-3 for k, v in generic.landmarks().items()}
    return reshape(verts), tri.astype(np.int64), {k: reshape(v) for k, v in lm.items()}


def _parameter_mesh(spacing_deg, spacing_mm, seed, lip_points, bottom):
    """Jittered (angle deg, height mm) samples from ``bottom`` to the hairline, with a row on
    the lip line, and their Delaunay triangles."""
    rng = np.random.default_rng(seed)
    th = np.arange(-84.0, 84.01, spacing_deg)
    ys = np.arange(bottom, generic.Y_TOP + 0.01, spacing_mm)
    tt, yy = np.meshgrid(th, ys)
    inner = np.zeros(tt.shape, bool)
    inner[1:-1, 1:-1] = True  # a regular outer ring: no sliver triangles on the hull
    tt = tt + inner * rng.uniform(-0.3, 0.3, tt.shape) * spacing_deg
    yy = yy + inner * rng.uniform(-0.3, 0.3, yy.shape) * spacing_mm
    pts = np.column_stack([tt.ravel(), yy.ravel()])
    pts = pts[np.abs(pts[:, 1] - generic.Y_STOMION) > 0.8]  # keep the lip line clear
    # the lip line: the mouth corners' angle and a row of points between them
    w = float(generic._width(generic.Y_STOMION))
    corner = np.degrees(np.arcsin((generic.MOUTH_HALF_WIDTH / w) ** (generic.SUPERELLIPSE_N / 2)))
    line = np.column_stack([np.linspace(-corner, corner, lip_points),
                            np.full(lip_points, generic.Y_STOMION)])
    pts = np.concatenate([pts, line])
    pts[:, 0] = np.clip(pts[:, 0], -84.0, 84.0)
    pts[:, 1] = np.clip(pts[:, 1], bottom, generic.Y_TOP)
    return pts, Delaunay(pts).simplices


def _wound(pts, tri, verts):
    """Every triangle wound alike in the parameter plane, then so that the front faces +z."""
    tri = tri.copy()
    a, b, c = (pts[tri[:, k]] for k in range(3))
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tri[area2 < 0] = tri[area2 < 0][:, ::-1]
    a, b, c = (verts[tri[:, k]] for k in range(3))
    if np.cross(b - a, c - a)[:, 2].sum() < 0:
        tri = tri[:, ::-1]
    return tri


# ---- a head as scanners give it: a neck, ears, a jaw that stands out ---------------------------
#: mm, the scan-like head's ears: tilted fins in front of the tragion (height, half-thickness and
#: half-height of the Gaussian, backward tilt per mm of height, angle of the row, height)
EAR = {"height": 14.0, "thick": 3.0, "tall": 10.0, "tilt": 1.2, "theta_deg": 76.0, "y": -35.0}
#: mm, how far the jaw's lower border stands out of the neck at the angles, the height over
#: which it drops back, and the height of its edge (generic frontal y)
JAW = {"out": 12.0, "drop": 2.0, "edge": -126.0}
#: mm, the neck down to about where a scan is cropped (25 mm under the menton)
NECK_BOTTOM = -150.0


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _head_row_point(theta, y, jaw):
    """(x, z) mm of the generic row at (theta rad, y mm), the jaw widened at the sides."""
    e = 2.0 / generic.SUPERELLIPSE_N
    s, c = np.sin(theta), np.cos(theta)
    w = generic._width(np.clip(y, generic.Y_BOTTOM, generic.Y_TOP))
    if jaw:
        lateral = _smoothstep((np.degrees(np.abs(theta)) - 35.0) / 35.0)
        out = JAW["out"] * _smoothstep((y - JAW["edge"] + JAW["drop"]) / JAW["drop"]) \
            * (1.0 - _smoothstep((y + 85.0) / 20.0))
        w = w + out * lateral
    depth = generic.midline_depth(y) - generic.Z_EAR
    return w * np.sign(s) * np.abs(s) ** e, generic.Z_EAR + depth * np.abs(c) ** e


def scan_head(spacing_deg: float = 3.6, spacing_mm: float = 4.5, seed: int = 0, *,
              ears: bool = True, jaw: bool = True, bottom: float = NECK_BOTTOM):
    """Vertices (m), triangles and landmarks (m) of a scan-like head with the places a real head
    curves more sharply than its tissue is deep.

    The scan-like face (:func:`scan_face`'s sampling and proportions, coarser by default) with
    a neck down to ``bottom`` (the throat turning into the neck under the chin), the jaw's lower
    border standing :data:`JAW` ``out`` mm out of the neck at the angles (a convex edge over a
    concave one), and ears (:data:`EAR`): fins in front of the tragion, tilted backwards, whose
    rim is sharper than the 10 mm of tissue there and whose back faces away from the head.
    """
    from facemech.geometry.mesh import vertex_normals

    pts, tri = _parameter_mesh(spacing_deg, spacing_mm, seed, 15, bottom)
    theta, y = np.radians(pts[:, 0]), pts[:, 1]
    bx, bz = _head_row_point(theta, y, jaw)
    verts = np.column_stack([bx, y, bz + generic.features(bx, y)])
    tri = _wound(pts, tri, verts)
    if ears:
        normal = vertex_normals(verts, tri)
        back = np.array([0.0, 0.0, -1.0])
        for side in (-1.0, 1.0):
            _, z0 = _head_row_point(np.radians(side * EAR["theta_deg"]), np.array(EAR["y"]),
                                    jaw)
            fin = EAR["height"] * np.exp(-0.5 * ((verts[:, 2] - z0) / EAR["thick"]) ** 2) \
                * np.exp(-0.5 * ((verts[:, 1] - EAR["y"]) / EAR["tall"]) ** 2) \
                * (np.sign(verts[:, 0]) == side)
            verts = verts + fin[:, None] * (normal + EAR["tilt"] * back)
    lm = {k: reshape(v * 1e-3) for k, v in generic.landmarks().items()}
    return reshape(verts * 1e-3), tri.astype(np.int64), lm


# ---- the generic face written as scans come: other units, axes, seams, fragments -------------
def write_obj(path, vertices, faces, *, uv=None, material=None):
    """An OBJ of ``vertices`` (written as given: the file's numbers) and 0-based ``faces``.

    With ``uv`` (f, 3, 2) per-corner texture coordinates, one ``v`` line per (vertex, UV) pair
    as exporters write them: every position on a texture seam appears twice.
    """
    with open(path, "w") as fh:
        if material:
            fh.write(f"mtllib {material}.mtl\nusemtl skin\n")
        if uv is None:
            fh.writelines("v {:.6f} {:.6f} {:.6f}\n".format(*p) for p in vertices)
            fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
            return len(vertices)
        keys: dict = {}
        corner = np.zeros(faces.shape, np.int64)
        for t in range(len(faces)):
            for k in range(3):
                key = (int(faces[t, k]), round(float(uv[t, k, 0]), 6),
                       round(float(uv[t, k, 1]), 6))
                corner[t, k] = keys.setdefault(key, len(keys))
        fh.writelines("v {:.6f} {:.6f} {:.6f}\n".format(*vertices[v]) for v, _, _ in keys)
        fh.writelines(f"vt {u:.6f} {w:.6f}\n" for _, u, w in keys)
        fh.writelines("f " + " ".join(f"{i}/{i}" for i in tri) + "\n" for tri in corner + 1)
        return len(keys)


def write_landmark_csv(path, landmarks, scale=1e3):
    """A facemech landmark CSV, the positions (m) times ``scale`` (the file's numbers)."""
    with open(path, "w") as fh:
        fh.write("name,x,y,z\n")
        fh.writelines(f"{n},{p[0] * scale:.6f},{p[1] * scale:.6f},{p[2] * scale:.6f}\n"
                      for n, p in landmarks.items())


def write_head_scan(folder, *, uv=None, texture=None):
    """The scan-like head (:func:`scan_head`) written as a scanner would: ``head.obj`` in mm
    (with ``uv``, (f, 3, 2) per-corner texture coordinates, and ``texture``, (h, w, 3) uint8:
    its material ``head.mtl`` and image ``head.png``) and its 68 points in menpo's LJSON
    version 3 (``head.ljson``). Returns the OBJ's and the landmarks' paths."""
    import json
    from pathlib import Path

    from facemech.geometry.ibug import generic_ibug68

    folder = Path(folder)
    v, f, _ = scan_head()
    write_obj(folder / "head.obj", v * 1e3, f, uv=uv,
              material=None if texture is None else "head")
    if texture is not None:
        from PIL import Image

        (folder / "head.mtl").write_text("newmtl skin\nmap_Kd head.png\n")
        Image.fromarray(texture).save(folder / "head.png")
    (folder / "head.ljson").write_text(json.dumps(v3(reshape(generic_ibug68()) * 1e3)))
    return folder / "head.obj", folder / "head.ljson"


# menpo's LJSON (versions 2 and 3), as tests/geometry/test_ljson.py and the scan heads write it
#: a landmarker.io-style template: the parts in another order than iBUG's, as real scans have
SCAN_ORDER = [("chin", range(0, 17)), ("leye", range(36, 42)), ("reye", range(42, 48)),
              ("leyebrow", range(17, 22)), ("nose", range(27, 36)), ("reyebrow", range(22, 27)),
              ("mouth", range(48, 68))]


def group(points, order, *, shuffle=None):
    """A version-2/3 body: the parts' points one after another (or in a shuffled row order),
    each label's mask listing its rows."""
    rows, labels = [], []
    for name, r in order:
        labels.append({"label": name, "mask": list(range(len(rows), len(rows) + len(r)))})
        rows.extend(np.asarray(points)[list(r)].tolist())
    if shuffle is not None:
        perm = np.random.default_rng(shuffle).permutation(len(rows))  # new row of each old
        new = [None] * len(rows)
        for old, k in enumerate(perm):
            new[k] = rows[old]
        rows = new
        for lab in labels:
            lab["mask"] = [int(perm[m]) for m in lab["mask"]]
    return {"landmarks": {"points": rows, "connectivity": []}, "labels": labels}


def v3(points, order=SCAN_ORDER, key="PTS", **kw):
    return {"version": 3, "groups": {key: group(points, order, **kw)}}
