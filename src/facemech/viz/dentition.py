"""The teeth, gums and tongue of the rendered mouth.

Each dental arch is a row of separate crowns along an ellipse in the horizontal plane (the
arch form), from the central incisors back to the second molars: every crown a closed mesh
shaped by its kind (chisel-edged incisors, a pointed canine, rounded premolars and molars),
narrower than its place on the arch so that dark embrasures part the crowns, most at the
rounded incisal corners. The gingiva is a pink band over the crowns' necks whose margin
scallops down between the teeth (the interdental papillae). The tongue is a flattened,
front-tapered ellipsoid with a median groove, its tip resting behind the lower incisors.

The upper arch is fixed to the skull; the lower arch, its gums and the tongue move with the
mandible. The lower incisors' edge stands where :func:`facemech.geometry.teeth.lower_incisor_point`
puts it (:data:`facemech.geometry.teeth.LOWER_EDGE_ABOVE_STOMION` above the stomion,
:data:`facemech.geometry.teeth.LOWER_ARCH_SETBACK` behind the upper incisors' labial face).

Lengths in metres; axes: +x the subject's left, +y up, +z forward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.teeth import LOWER_ARCH_SETBACK, LOWER_EDGE_ABOVE_STOMION
from .look import FaceLook
from .mesh import Part, grid_faces, sphere

ENAMEL = np.array([0.90, 0.87, 0.78])  #: sRGB at the neck (warmer, where the dentine shows)
INCISAL = np.array([0.80, 0.81, 0.80])  #: sRGB at the incisal edge (thin, translucent enamel)
GINGIVA = np.array([0.82, 0.47, 0.49])  #: sRGB, the attached gingiva's coral pink
TONGUE = np.array([0.76, 0.42, 0.43])  #: sRGB
GAP = 0.00035  #: m of each crown's place on the arch left empty (half on each side)
UPPER_EDGE_BELOW_STOMION = 0.003  #: m, the upper incisors' edge below the stomion
TONGUE_TIP_SETBACK = 0.0045  #: m, the resting tongue tip behind the lower incisors' labial face
TONGUE_TIP_BELOW_STOMION = 0.0085  #: m, the resting tongue tip under the stomion
TONGUE_DOME = 0.006  #: m, how far the dorsum's top rises from the blade to its highest point
#: m, how far each kind's edge or cusp tip stands back from the incisal plane, upper arch (the
#: lower's 1.6 times as far)
STEP = {"incisor": 0.0, "canine": 0.0004, "premolar": 0.0008, "molar": 0.0010}


@dataclass(frozen=True)
class Tooth:
    """One crown's shape, m: mesio-distal ``width``, labio-lingual ``thickness`` at the neck,
    ``height`` from the incisal edge (cusp tip) to the neck, and its ``kind`` ('incisor',
    'canine', 'premolar' or 'molar')."""

    kind: str
    width: float
    thickness: float
    height: float


# the permanent teeth from the midline back, one side (adult means, rounded; Wheeler's
# dental anatomy)
UPPER = (Tooth("incisor", 0.0085, 0.0070, 0.0105), Tooth("incisor", 0.0065, 0.0060, 0.0090),
         Tooth("canine", 0.0075, 0.0080, 0.0100), Tooth("premolar", 0.0070, 0.0090, 0.0085),
         Tooth("premolar", 0.0065, 0.0090, 0.0080), Tooth("molar", 0.0100, 0.0110, 0.0075),
         Tooth("molar", 0.0090, 0.0110, 0.0070))
LOWER = (Tooth("incisor", 0.0050, 0.0060, 0.0090), Tooth("incisor", 0.0055, 0.0062, 0.0092),
         Tooth("canine", 0.0070, 0.0075, 0.0105), Tooth("premolar", 0.0070, 0.0080, 0.0082),
         Tooth("premolar", 0.0070, 0.0082, 0.0080), Tooth("molar", 0.0110, 0.0105, 0.0075),
         Tooth("molar", 0.0105, 0.0100, 0.0070))
#: m, half-width and depth of each arch's ellipse (x = a sin p, z = -d (1 - cos p))
UPPER_ARCH = (0.0235, 0.030)
LOWER_ARCH = (0.0210, 0.027)


def _profile(kind: str, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Half-width and half-thickness, as fractions of the crown's, at height ``b`` (0 at the
    incisal edge or cusp tip, 1 at the neck)."""
    b = np.clip(b, 0.0, 1.0)
    if kind == "incisor":  # a chisel: thin edge, corners a little rounded, narrowing neck
        width = (1.0 - 0.28 * b ** 2) * (0.72 + 0.28 * np.sqrt(np.minimum(b / 0.12, 1.0)))
        thick = 0.22 + 0.78 * np.sqrt(b)
    elif kind == "canine":  # a cusp: pointed, widest a third of the way up
        width = np.sqrt(np.minimum(b / 0.35, 1.0)) * (1.0 - 0.3 * np.clip(b - 0.35, 0, 1) ** 2)
        thick = 0.35 + 0.65 * np.sqrt(b)
    else:  # premolars and molars: rounded cusps on a broad occlusal table
        r = 0.25 if kind == "premolar" else 0.18
        width = np.sqrt(np.minimum(b / r, 1.0)) * (1.0 - 0.15 * b ** 2)
        thick = (0.55 + 0.45 * np.sqrt(np.minimum(b / r, 1.0))) * (1.0 - 0.1 * b ** 2)
    return np.maximum(width, 0.05), np.maximum(thick, 0.05)


def _arch_frame(half_width: float, depth: float, front_z: float, n: int = 301):
    """Arc length s (k,) m from the midline along the arch, and the arch's points (k, 2) and
    unit outward normals (k, 2) in (x, z), the labial face of the incisors at ``front_z``.

    The arch is half an ellipse (x = a sin p, z = -d (1 - cos p)) in front, going straight
    back 40 mm from its widest, where the molars stand."""
    p = np.linspace(-np.pi / 2, np.pi / 2, 2 * n + 1)  # p = 0, the midline, at index n
    xs, zs = half_width * np.sin(p), front_z - depth * (1 - np.cos(p))
    nx, nz = np.sin(p) / half_width, np.cos(p) / depth
    nn = np.hypot(nx, nz)
    back = np.linspace(0.0, 0.04, 81)[1:]
    xs = np.concatenate([np.full_like(back, -half_width), xs, np.full_like(back, half_width)])
    zs = np.concatenate([zs[0] - back[::-1], zs, zs[-1] - back])
    nx = np.concatenate([-np.ones_like(back), nx / nn, np.ones_like(back)])
    nz = np.concatenate([np.zeros_like(back), nz / nn, np.zeros_like(back)])
    s = np.concatenate([[0], np.cumsum(np.hypot(np.diff(xs), np.diff(zs)))])
    s -= s[len(back) + n]
    return s, np.stack([xs, zs], -1), np.stack([nx, nz], -1)


def _at(s_query, s, values):
    return np.stack([np.interp(s_query, s, values[:, k]) for k in range(values.shape[1])], -1)


def _crown(tooth: Tooth, centre_s: float, frame, edge_y: float, sign: float, slant: float):
    """Vertices (m, 3), faces and albedo (m, 3) of one crown centred at arc length
    ``centre_s``; ``sign`` +1 for the upper arch (the neck above the edge), -1 for the lower."""
    s, pts, nrm = frame
    # the front teeth, seen close, with finer meshes than the back ones
    unit, faces = sphere(9, 16) if tooth.kind in ("incisor", "canine") else sphere(7, 10)
    lat = np.arcsin(np.clip(unit[:, 1], -1, 1))
    # b: 0 at the incisal pole, 1 at the neck's pole
    b = (unit[:, 1] + 1) / 2 if sign > 0 else (1 - unit[:, 1]) / 2
    # boxy ends: the rings keep their size near the poles (an incisor's edge is straight)
    ring = np.abs(np.cos(lat)) ** (0.12 if tooth.kind == "incisor" else 0.35)
    width_frac, thick_frac = _profile(tooth.kind, b)
    e = 0.6  # a superellipse: flatter labial and lingual faces than an ellipse
    lon = np.arctan2(unit[:, 0], unit[:, 2])
    sl, cl = np.sin(lon), np.cos(lon)
    along = np.sign(sl) * np.abs(sl) ** e * width_frac * ring * (0.5 * tooth.width - 0.5 * GAP)
    along *= 1.0 - 0.3 * np.clip(-cl, 0.0, 1.0)  # narrower lingually: the arch converges there
    out = np.sign(cl) * np.abs(cl) ** e * thick_frac * ring * 0.5 * tooth.thickness
    # the crown bent along the arch: each vertex on the normal through its own place on the
    # arch, so that neighbours' lingual sides, where the arch converges, never meet
    where = centre_s + along
    c = _at(where, s, pts)
    n = _at(where, s, nrm)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    # the labial face on the arch at the edge; the crown leans lingually towards its neck
    depth = out - 0.5 * thick_frac * tooth.thickness - slant * b * tooth.height
    verts = np.stack([c[:, 0] + n[:, 0] * depth, edge_y + sign * b * tooth.height,
                      c[:, 1] + n[:, 1] * depth], -1)
    shade = np.clip(b / 0.5, 0.0, 1.0)[:, None]
    albedo = INCISAL + (ENAMEL - INCISAL) * shade
    if tooth.kind != "incisor":
        albedo = ENAMEL * (0.97 - 0.05 * (1 - shade))
    return verts, faces, albedo


def _slots(teeth: tuple[Tooth, ...]) -> list[tuple[Tooth, float]]:
    """Each tooth of both sides and the arc length of its centre (right side negative)."""
    out, edge = [], 0.0
    for tooth in teeth:
        mid = edge + 0.5 * tooth.width
        out += [(tooth, mid), (tooth, -mid)]
        edge += tooth.width
    return out


def _placement(look: FaceLook, upper: bool):
    """Where one arch stands: its frame (:func:`_arch_frame`, the incisors' labial face
    ``teeth_depth`` behind the upper lip, the lower arch set back by LOWER_ARCH_SETBACK) and the
    incisal edges' height (m) relative to the stomion."""
    lm = look.landmarks
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    front_z = lm["upper_lip_center"][2] - look.teeth_depth
    half_width, depth = UPPER_ARCH if upper else LOWER_ARCH
    if not upper:
        front_z -= LOWER_ARCH_SETBACK
    edge_y = st[1] - UPPER_EDGE_BELOW_STOMION if upper else st[1] + LOWER_EDGE_ABOVE_STOMION
    return _arch_frame(half_width, depth, front_z), edge_y


def crowns(look: FaceLook, upper: bool) -> list[tuple[Tooth, np.ndarray, np.ndarray,
                                                        np.ndarray]]:
    """Each crown of one arch as (tooth, vertices (m, 3) m, faces (k, 3), albedo (m, 3) sRGB),
    the central incisors first, then outwards, the subject's left and right in turn."""
    frame, edge_y = _placement(look, upper)
    out = []
    sign = 1.0 if upper else -1.0
    for tooth, centre_s in _slots(UPPER if upper else LOWER):
        slant = 0.12 if tooth.kind == "incisor" else 0.04
        # the cusps behind the incisors stand back from the incisal plane (the curve of Spee)
        step = STEP[tooth.kind] * (1.0 if upper else 1.6)
        out.append((tooth, *_crown(tooth, centre_s, frame, edge_y + sign * step, sign,
                                   slant)))
    return out


def arch(look: FaceLook, upper: bool) -> tuple[Part, Part]:
    """The crowns (one part, :func:`crowns`) and the gingiva of one dental arch."""
    frame, edge_y = _placement(look, upper)
    each = crowns(look, upper)
    base = np.cumsum([0] + [len(v) for _, v, _, _ in each])
    teeth = Part("upper_teeth" if upper else "lower_teeth",
                 np.concatenate([v for _, v, _, _ in each]),
                 np.concatenate([c[2] + b for c, b in zip(each, base[:-1], strict=True)]),
                 np.concatenate([a for _, _, _, a in each]), (0.45, 45.0),
                 "skull" if upper else "jaw")
    gum = _gingiva(_slots(UPPER if upper else LOWER), frame, edge_y, 1.0 if upper else -1.0,
                   upper)
    return teeth, gum


def _gingiva(slots, frame, edge_y: float, sign: float, upper: bool) -> Part:
    """The gum over the crowns' necks: a band along the arch, its margin scalloped."""
    s, pts, nrm = frame
    reach = max(abs(c) + 0.5 * t.width for t, c in slots)
    cols = np.linspace(-reach, reach, 161)
    # the margin's height above the edge: over each crown 78 % of its height, coming down
    # 2.2 mm between crowns (the papillae)
    margin = np.empty_like(cols)
    for i, q in enumerate(cols):
        tooth, c = min(slots, key=lambda tc: abs(q - tc[1]))
        d = abs(q - c) / (0.5 * tooth.width)  # 0 at the crown's middle, 1 at its side
        step = STEP[tooth.kind] * (1.0 if upper else 1.6)
        margin[i] = step + 0.78 * tooth.height - 0.0022 * np.clip(d, 0, 1) ** 3
    # rows from the margin up: a rounded margin (tucked in), the attached gingiva, and the
    # fold into the lip (the vestibule), turning outwards to meet the lip's inside
    heights = [0.0, 0.0004, 0.0012, 0.003, 0.008, 0.012, 0.015]
    outward = [-0.0002, 0.0004, 0.0007, 0.0008, 0.0006, 0.0016, 0.0045]
    if not upper:  # the chin's skin presses in over it (the mentalis): no fold outwards,
        # which showed as pink specks through the skin under the lower lip
        outward = [-0.0002, 0.0004, 0.0007, 0.0008, 0.0004, 0.0, -0.0005]
    p = _at(cols, s, pts)
    n = _at(cols, s, nrm)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rows = []
    for hgt, off in zip(heights, outward, strict=True):
        y = edge_y + sign * (margin + hgt)
        rows.append(np.stack([p[:, 0] + n[:, 0] * off, y, p[:, 1] + n[:, 1] * off], -1))
    grid = np.stack(rows)  # rows go up for the upper arch, down for the lower
    verts = grid.reshape(-1, 3)
    # grid_faces' triangles face +z for rows going up and columns going to +x (the subject's
    # left, the frontal view's right): the upper band's labial face; flip for the lower
    faces = grid_faces(len(heights), len(cols))
    faces = faces if upper else faces[:, ::-1]
    tint = np.array([1.0 - 0.12 * (k == 0) for k in range(len(heights))])
    albedo = np.repeat(tint, len(cols))[:, None] * GINGIVA
    return Part("upper_gum" if upper else "lower_gum", verts, faces, albedo, (0.35, 30.0),
                "skull" if upper else "jaw")


def tongue(look: FaceLook) -> Part:
    """The tongue (see the module text): its tip behind the lower incisors, just under their
    edge, its dorsum below the occlusal plane."""
    lm = look.landmarks
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    front_z = lm["upper_lip_center"][2] - look.teeth_depth - LOWER_ARCH_SETBACK
    unit, faces = sphere(20, 32)
    half = np.array([0.020, 0.0075, 0.024])  # m: half-width, half-height, half-length
    tip_z = front_z - TONGUE_TIP_SETBACK  # behind the lower incisors' lingual face
    centre = np.array([st[0], st[1] - TONGUE_TIP_BELOW_STOMION, tip_z - half[2]])
    fwd = np.clip(unit[:, 2], 0, 1)
    x = unit[:, 0] * half[0] * (1.0 - 0.45 * fwd ** 2)  # narrowing to the tip
    y = unit[:, 1] * half[1] * np.where(unit[:, 1] > 0, 1.0, 1.3)
    # the dorsum rises from the blade to its highest point about two thirds back (the
    # tongue's body under the palate), so that an open mouth shows its top behind the teeth
    along = 0.5 * (1.0 - unit[:, 2])  # 0 at the tip, 1 at the back
    y += np.where(unit[:, 1] > 0, 1.0, 0.3) * TONGUE_DOME * np.sin(
        np.pi * np.clip(along / 0.7, 0.0, 1.0) * 0.5) ** 2
    # the median sulcus: a shallow groove along the dorsum's middle
    y -= 0.0012 * np.exp(-0.5 * (x / 0.003) ** 2) * (unit[:, 1] > 0.3)
    z = unit[:, 2] * half[2]
    verts = centre + np.stack([x, y, z], -1)
    albedo = np.tile(TONGUE, (len(verts), 1)) * (0.92 + 0.08 * np.clip(unit[:, 1], 0, 1))[:, None]
    return Part("tongue", verts, faces, albedo, (0.35, 25.0), "jaw")


#: m, the length of the tongue's front, from the tip back, that bends with the tip's pose
TONGUE_BEND_LENGTH = 0.030


def tongue_modes(rest: np.ndarray) -> np.ndarray:
    """(n, 2, 3) m per m: how each vertex of the resting tongue (:func:`tongue`, ``rest`` (n, 3)
    m) moves per metre of the tip's protrusion (forward) and elevation (up); a pose (2,) m bends
    it to ``rest + pose @ modes`` (:func:`bend_tongue`), linear so that the viewer applies it as
    the renderer does.

    The front :data:`TONGUE_BEND_LENGTH` follows the tip with a smooth fall-off along the length
    (a smoothstep weight w, 1 at the tip, 0 at the front's back end), the rest of the body stays:
    elevation lifts each section by w times the tip's, protrusion moves it forward by w times
    the tip's and narrows and thins it where it stretches (its cross-section scaled by 1 - w',
    w' the weight's slope per metre times the protrusion: the volume kept to first order).
    """
    rest = np.asarray(rest, float)
    tip_z = rest[:, 2].max()
    s = np.clip(1.0 - (tip_z - rest[:, 2]) / TONGUE_BEND_LENGTH, 0.0, 1.0)
    w = s * s * (3.0 - 2.0 * s)
    slope = 6.0 * s * (1.0 - s) / TONGUE_BEND_LENGTH  # dw/dz, 1/m
    mid_x = 0.5 * (rest[:, 0].max() + rest[:, 0].min())
    mid_y = 0.5 * (rest[:, 1].max() + rest[:, 1].min())
    modes = np.zeros((len(rest), 2, 3))
    modes[:, 0, 2] = w
    # thinning: per metre of protrusion, the section shrinks by 0.5 w' about the midline in each
    # of x and y (area by w', the length grows by w')
    modes[:, 0, 0] = -0.5 * slope * (rest[:, 0] - mid_x)
    modes[:, 0, 1] = -0.5 * slope * (rest[:, 1] - mid_y)
    modes[:, 1, 1] = w
    return modes


def bend_tongue(rest: np.ndarray, modes: np.ndarray, pose) -> np.ndarray:
    """(n, 3) m, the tongue's vertices bent by a tip pose (2,) m (protrusion, elevation):
    ``rest + pose @ modes`` (:func:`tongue_modes`)."""
    p = np.asarray(pose, float).reshape(2)
    return np.asarray(rest, float) + p[0] * modes[:, 0] + p[1] * modes[:, 1]
