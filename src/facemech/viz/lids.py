"""Blinks and gaze: the eyeballs turn, the lids close over them and follow their pitch.

The skin's palpebral fissure is a cut-out of its texture (:mod:`.textures`); behind it sits
the eyeball. Each lid is a skin-coloured cap just outside the eyeball (upper 0.4 mm, lower 0.1
mm further out) whose edge carries the lashes; open and looking ahead it has no area. The upper
lid comes down with the blink closure ``b`` (0 open .. 1 closed; to 0.5 mm under the lower
margin) and follows the eye down by 0.8 of its pitch; the lower lid rises 1.2 mm in a blink and
by 0.35 of the pitch looking up, never above the open upper lid's margin. Gaze (yaw, pitch) rad
turns each eyeball about its centre: yaw > 0 towards the subject's left (+x), pitch > 0 up.
Where the eyeball lies deeper than :data:`LID_RIM` behind the skin, a lid lies at that depth
instead (``Lid.front``) and a wall (:func:`margin_mesh`) closes the gap from the skin's cut to
the globe. Details: docs/rendering.md, "Blinks, gaze and head motion".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import textures as T
from .mesh import grid_faces

CLEARANCE = 0.0004  #: m between the eyeball and the lid
LID_FOLLOW = 0.8  #: of the eye's downward pitch taken by the upper lid
LOWER_FOLLOW = 0.35  #: of the eye's upward pitch taken by the lower lid
LOWER_BLINK_RISE = 0.0012  #: m, the lower lid's rise in a full blink
LOWER_CLEARANCE = 0.0005  #: m between the eyeball and the lower lid (outside the upper)
ROWS, COLS = 7, 25  #: the lid cap's grid
LID_RIM = 0.0016  #: m, the lids' margin: how far behind the skin the lids close the fissure
BLEND = 0.0006  #: m, the smooth maximum's width where a lid passes from the globe to its rim
LOWER_FRONT = 0.0003  #: m, the lower lid's rim in front of the upper's


def gaze_rotation(yaw: float, pitch: float) -> np.ndarray:
    """(3, 3) rotation turning the forward axis (+z) to the gaze (yaw > 0 to +x, pitch > 0
    up)."""
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cp, sp], [0.0, -sp, cp]])
    return ry @ rx


@dataclass(frozen=True)
class Lid:
    """A lid over an eyeball (m, rad).

    Attributes
    ----------
    centre : (3,) the eyeball's centre
    radii : (3,) the cap's semi-axes (the eyeball's plus the clearance)
    azimuth : (COLS,) rad, the cap's columns about the centre (0 forward, > 0 to +x)
    top : (COLS,) rad, elevation of the cap's fixed side: above the fissure's upper margin
        (an upper lid) or below its lower margin (a lower lid)
    closed : (COLS,) rad, elevation of the edge of a closed lid
    upper : (COLS,) rad, for a lower lid: the open upper lid's cap top, the highest its edge
        may go (None for an upper lid)
    front : (6,) or None, the quadratic ``z = c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2``
        (m, model axes) of the surface the lid lies on where the eyeball is further back: the
        skin round the fissure, :data:`LID_RIM` behind it (:func:`skin_front`)
    """

    centre: np.ndarray
    radii: np.ndarray
    azimuth: np.ndarray
    top: np.ndarray
    closed: np.ndarray
    upper: Lid | None = None
    front: np.ndarray | None = None

    @property
    def lower(self) -> bool:
        return self.upper is not None

    def edge(self, blink: float, pitch: float) -> np.ndarray:
        """Elevation (COLS,) rad of the lid's edge."""
        b = float(np.clip(blink, 0.0, 1.0))
        if self.lower:
            if blink <= 0.0 and pitch <= 0.0:
                return self.top
            # from the margin (the cap's fixed side lies 2 degrees under it, behind the skin)
            margin = self.top + np.radians(2.0)
            edge = margin + LOWER_FOLLOW * max(pitch, 0.0) + b * (self.closed - margin)
            # never above the open upper lid's fixed side
            return np.minimum(edge, self.upper.top - np.radians(2.0))
        open_ = np.minimum(self.top, self.top + LID_FOLLOW * min(pitch, 0.0))
        return np.minimum(open_ + b * (self.closed - open_), open_)

    def at_rest(self, blink: float, pitch: float) -> bool:
        """Whether the lid is open (no area) for this blink and pitch."""
        return blink == 0.0 and (pitch <= 0.0 if self.lower else pitch >= 0.0)

    def place(self, blink: float = 0.0, pitch: float = 0.0) -> np.ndarray:
        """Vertices (ROWS * COLS, 3) m: rows from the cap's fixed side to the edge."""
        edge = self.edge(blink, pitch)
        k = np.linspace(0.0, 1.0, ROWS)[:, None]
        el = self.top[None, :] + k * (edge - self.top)[None, :]
        az = np.broadcast_to(self.azimuth[None, :], el.shape)
        d = np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], -1)
        v = (self.centre + d * self.radii).reshape(-1, 3)
        if self.front is not None:  # wrap the globe, and cover the fissure where it is deep
            v[:, 2] = soft_max(v[:, 2], quadratic(self.front, v[:, 0], v[:, 1]), BLEND)
        return v


def soft_max(a: np.ndarray, b: np.ndarray, width: float) -> np.ndarray:
    """A smooth maximum of ``a`` and ``b`` (m): never below either, at most ``width`` x ln 2
    above, with no kink where they cross (a lid's shading would show one)."""
    m = np.maximum(a, b)
    return m + width * np.log(np.exp((a - m) / width) + np.exp((b - m) / width))


def quadratic(c: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2``."""
    return c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y


def skin_front(eye: np.ndarray, side: int, depth, behind: float) -> np.ndarray:
    """(6,) the least-squares quadratic (:func:`quadratic`) of the rest skin's depth over the
    fissure and 4 mm round it, moved ``behind`` m back (m; ``depth``: :func:`.mesh.skin_depth`)."""
    s, h = np.meshgrid(np.linspace(-1.3, 1.3, 27), np.linspace(-0.009, 0.009, 19))
    x = eye[0] + side * s.ravel() * T.FISSURE_HALF_LENGTH
    y = eye[1] + h.ravel()
    z = np.asarray(depth(x, y), float)
    ok = np.isfinite(z)
    a = np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], -1)[ok]
    return np.linalg.lstsq(a, z[ok] - behind, rcond=None)[0]


def lid_of(eye: np.ndarray, centre: np.ndarray, radii: np.ndarray, side: int,
           depth=None) -> Lid:
    """The upper lid of the eye whose fissure is centred at ``eye`` (landmark, m), with its
    eyeball at ``centre`` of semi-axes ``radii`` (m); ``side`` +1 left, -1 right. With the
    skin's ``depth`` (:func:`.mesh.skin_depth`) the lid lies on the globe or, where the globe
    is further back, :data:`LID_RIM` behind the skin (``front``)."""
    r = np.asarray(radii, float) + CLEARANCE
    s = np.linspace(-1.15, 1.15, COLS)  # along the fissure, medial -1 .. lateral 1
    x = eye[0] + side * s * T.FISSURE_HALF_LENGTH
    up, lo = T.fissure_heights(s)
    tilt = 0.001 * np.clip(s, -1.5, 1.5)
    y_up = eye[1] - 0.0005 + tilt + up  # margins in model y (textures.eye_frame)
    y_lo = eye[1] - 0.0005 + tilt + lo
    az = np.arcsin(np.clip((x - centre[0]) / r[0], -0.99, 0.99))
    if side < 0:
        az = az[::-1]
        y_up, y_lo = y_up[::-1], y_lo[::-1]

    def elevation(y):
        return np.arcsin(np.clip((y - centre[1]) / r[1], -0.99, 0.99))

    top = elevation(y_up) + np.radians(2.0)
    closed = elevation(y_lo - 0.0005)
    front = None if depth is None else skin_front(eye, side, depth, LID_RIM)
    return Lid(np.asarray(centre, float), r, az, top, np.minimum(closed, top), front=front)


def lower_lid_of(upper: Lid) -> Lid:
    """The lower lid under an upper lid (:func:`lid_of`'s), on the same eyeball."""
    r = upper.radii - CLEARANCE + LOWER_CLEARANCE
    # the lower margin's elevation is where the closed upper lid's edge sits, 0.5 mm above
    y_lo = upper.centre[1] + (upper.radii[1]) * np.sin(upper.closed) + 0.0005
    margin = np.arcsin(np.clip((y_lo - upper.centre[1]) / r[1], -0.99, 0.99))
    rise = np.arcsin(np.clip((y_lo + LOWER_BLINK_RISE * _middle(upper.azimuth) - upper.centre[1])
                             / r[1], -0.99, 0.99))
    bottom = margin - np.radians(2.0)
    front = None if upper.front is None else upper.front + np.array(
        [LOWER_FRONT, 0, 0, 0, 0, 0])  # in front of the closed upper lid
    return Lid(upper.centre, r, upper.azimuth, bottom, rise, upper=upper, front=front)


def _middle(azimuth: np.ndarray) -> np.ndarray:
    """1 at the middle of the fissure's columns, falling to 0.3 at its corners."""
    a = (azimuth - azimuth.mean()) / (0.5 * np.ptp(azimuth))
    return 0.3 + 0.7 * np.clip(1.0 - a ** 2, 0.0, 1.0)


def lid_mesh(lid: Lid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices at rest (open), outward faces, and albedo (sRGB): skin, the edge's lashes."""
    v = lid.place()
    f = grid_faces(ROWS, COLS)
    albedo = np.tile(T.SKIN, (ROWS, COLS, 1))
    if lid.lower:  # rows run up, columns towards +x: outward as they are
        albedo[-1] = 0.5 * T.SKIN + 0.5 * T.LASH  # the lower lashes: sparse, short
        return v, f, albedo.reshape(-1, 3)
    # rows run down (decreasing elevation), columns towards +x: flip to face outward
    f = f[:, ::-1]
    albedo[-1] = T.LASH
    albedo[-2] = 0.6 * T.SKIN + 0.4 * T.LID_CREASE
    return v, f, albedo.reshape(-1, 3)


MARGIN_COLS = 25  #: points along each lid margin of the lid-margin wall
MARGIN_DEPTHS = (0.0, 0.0008, 0.0016, 0.0024, 0.0032)  #: m, first rows
MARGIN_OUTSET = 0.0008  #: m, the wall's front rim outside the fissure's cut (under the skin)
MARGIN_BEHIND = 0.0004  #: m, the wall's front rim behind the skin
MARGIN_INTO_GLOBE = 0.001  #: m, the wall's back rim inside the eyeball (under the lids)
CONJUNCTIVA = np.array([0.80, 0.52, 0.48])  #: sRGB, the palpebral conjunctiva
BULBAR = np.array([0.86, 0.80, 0.77])  #: sRGB, the bulbar conjunctiva over the sclera


def fissure_outline(eye: np.ndarray, side: int, n: int = MARGIN_COLS) -> np.ndarray:
    """(2 n - 2, 2) m: the fissure's outline in frontal (x, y), a closed loop along the upper
    margin from the medial to the lateral canthus and back along the lower margin (the
    skin texture's cut, :func:`.textures.eye_mask`)."""
    s = np.concatenate([np.linspace(-1.0, 1.0, n), np.linspace(1.0, -1.0, n)[1:-1]])
    up, lo = T.fissure_heights(s)
    h = np.where(np.arange(len(s)) < n, up, lo)
    tilt = 0.001 * s
    return np.stack([eye[0] + side * s * T.FISSURE_HALF_LENGTH,
                     eye[1] - 0.0005 + tilt + h], -1)


def margin_mesh(eye: np.ndarray, centre: np.ndarray, radii: np.ndarray, side: int,
                depth) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lids' margins and the canthi: a wall round the fissure from the skin back onto the
    eyeball (vertices m, faces facing into the fissure, albedo sRGB).

    The skin's fissure is a cut in its texture, and the skin round the eye slopes back
    laterally (about 30 degrees on the built-in face), so seen from the side a line of sight
    through the cut passes in front of the eyeball into the head. Real lids are 2 mm thick at
    their margins, and the fissure's corners (the canthi) and the conjunctival fornices close
    the space between skin and globe. This wall stands for them: for each point of the cut's
    outline, a line straight back (along -z, so that the frontal view sees it edge-on and is
    unchanged) from :data:`MARGIN_BEHIND` behind the skin, :data:`MARGIN_OUTSET` outside the
    cut (hidden by the skin round the cut), to :data:`MARGIN_INTO_GLOBE` inside the eyeball
    (hidden by it and by the lids' caps, which lie outside it). Skin-coloured at the front,
    conjunctiva-pink deeper in.

    Parameters
    ----------
    eye : (3,) m, the fissure's centre (landmark)
    centre, radii : (3,) m, the eyeball's centre and semi-axes
    side : +1 left, -1 right
    depth : callable (x, y) -> z of the rest skin (:func:`.mesh.skin_depth`)
    """
    loop = fissure_outline(eye, side)
    m = len(loop)
    mid = loop.mean(axis=0)
    tangent = np.roll(loop, -1, axis=0) - np.roll(loop, 1, axis=0)
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], -1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    normal *= np.sign(np.sum(normal * (loop - mid), axis=1))[:, None]  # outward
    rim = loop + MARGIN_OUTSET * normal
    z_front = np.asarray(depth(rim[:, 0], rim[:, 1]), float)
    z_cut = np.asarray(depth(loop[:, 0], loop[:, 1]), float)
    z_front = np.where(np.isfinite(z_front), z_front, z_cut) - MARGIN_BEHIND
    q = (1.0 - ((loop[:, 0] - centre[0]) / radii[0]) ** 2
         - ((loop[:, 1] - centre[1]) / radii[1]) ** 2)
    z_globe = centre[2] + radii[2] * np.sqrt(np.clip(q, 0.0, 1.0)) - MARGIN_INTO_GLOBE
    z_back = np.minimum(z_globe, z_front - 0.0002)
    # row 0 outside the cut, then straight back from the cut's outline: the first rows at
    # fixed depths (the lid's rim, skin-coloured, then the conjunctiva), the rest spread
    total = z_front - z_back
    d = [np.zeros(m)]
    for fixed in MARGIN_DEPTHS[1:]:
        d.append(np.maximum(np.minimum(fixed, total), d[-1]))
    for frac in (0.5, 1.0):
        d.append(np.maximum(frac * total, d[-1]))
    d = np.stack(d)
    rows = len(d) + 1
    xy = np.concatenate([rim[None], np.broadcast_to(loop, (rows - 1, m, 2))])
    z = np.concatenate([z_front[None], z_front[None] - d])
    v = np.concatenate([xy, z[..., None]], -1)
    albedo = np.concatenate([[np.zeros(m)], d])[..., None]
    # a closed band: rows x m columns, the last column joined to the first
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(m), indexing="ij")
    a = r * m + c
    b = r * m + (c + 1) % m
    f = np.concatenate([np.stack([a, b, a + m], -1).reshape(-1, 3),
                        np.stack([b, b + m, a + m], -1).reshape(-1, 3)])
    v = v.reshape(-1, 3)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    inward = np.concatenate([mid, [0.0]]) - v[f[:, 0]]
    inward[:, 2] = 0.0
    if np.sum(np.sum(n * inward, axis=1)) < 0:
        f = f[:, ::-1]
    return v, f, margin_colour(albedo).reshape(-1, 3)


def margin_colour(d: np.ndarray) -> np.ndarray:
    """sRGB (..., 3) of the margin wall at depth ``d`` (..., 1) m behind its front rim: skin
    over the lid's rim (:data:`LID_RIM` deep), turning over 0.6 mm into the palpebral
    conjunctiva's pink, which turns from 0.8 to 2 mm past the rim into the white of the bulbar
    conjunctiva over the sclera (what a line of sight from the side past the lids meets on a
    real eye)."""
    a = np.clip((d - LID_RIM) / 0.0006, 0.0, 1.0)
    b = np.clip((d - LID_RIM - 0.0008) / 0.0012, 0.0, 1.0)
    return (1 - a) * T.SKIN + a * ((1 - b) * CONJUNCTIVA + b * BULBAR)


LASH_LENGTH = 0.0085  #: m, the upper lashes at the middle of the lid (shorter to the corners)
LASH_ROWS = 4  #: rows of the fringe from root to tip
LASH_TEXELS = (12, 360)  #: the strand texture's (rows, columns)
LASH_SPLAY = 0.3  #: of the globe's outward (lateral) direction in the lashes' first direction
LASH_CURL = 0.45  #: the tips' rise (of a lash's length) over a straight lash
LASH_DROP = np.radians(2.0)  #: rad, the roots under the lid's edge (its cap top lies this above
#: the fissure's margin)


@dataclass(frozen=True)
class LashFringe:
    """The upper lashes: a fringe of strand cards rooted on the upper lid's margin at the
    skin's front, leaving it forward (splayed a little outward from the globe) and curling
    up, carried by the lid through blink and gaze."""

    lid: Lid
    length: np.ndarray  # (COLS,) m, each column's lash length

    def at_rest(self, blink: float, pitch: float) -> bool:
        return self.lid.at_rest(blink, pitch)

    def place(self, blink: float = 0.0, pitch: float = 0.0) -> np.ndarray:
        """Vertices (LASH_ROWS * COLS, 3) m: rows from the root (the lid's margin) to the tips.

        A root is the lid's edge taken down :data:`LASH_DROP` (onto the fissure's margin) and
        forward by :data:`LID_RIM` (the lid's thickness, to the skin's front); a lash runs
        along ``(s_x, 0, 1)`` normalised (``s_x``: :data:`LASH_SPLAY` of the globe's outward
        x) and rises :data:`LASH_CURL` of its length as the square of the way along it."""
        lid = self.lid
        edge = lid.edge(blink, pitch) - LASH_DROP
        d = np.stack([np.cos(edge) * np.sin(lid.azimuth), np.sin(edge),
                      np.cos(edge) * np.cos(lid.azimuth)], -1)
        root = lid.centre + d * lid.radii
        if lid.front is not None:
            root[:, 2] = soft_max(root[:, 2], quadratic(lid.front, root[:, 0], root[:, 1]),
                                  BLEND)
        root[:, 2] += LID_RIM
        ahead = np.stack([LASH_SPLAY * d[:, 0], np.zeros(len(d)), np.ones(len(d))], -1)
        ahead /= np.linalg.norm(ahead, axis=1, keepdims=True)
        up = np.array([0.0, 1.0, 0.0])
        k = np.linspace(0.0, 1.0, LASH_ROWS)[:, None, None]
        path = k * ahead + k ** 2 * LASH_CURL * up
        return (root + path * self.length[None, :, None]).reshape(-1, 3)


def lash_fringe(lid: Lid, side: int) -> tuple[LashFringe, np.ndarray, np.ndarray, np.ndarray]:
    """An upper lid's lashes: (fringe, faces, texel coordinates (f, 3, 2), RGBA strand texture
    (sRGB, alpha 0 between strands))."""
    s = np.linspace(-1.15, 1.15, COLS)
    s = s if side > 0 else s[::-1]  # the lid's columns run towards +x
    medial = np.where(s < 0, 1.0 - 0.35 * np.clip(-s, 0, 1), 1.0)
    length = LASH_LENGTH * np.clip(1.0 - np.abs(s) ** 4, 0.0, 1.0) ** 0.5 * medial
    fringe = LashFringe(lid, np.maximum(length, 1e-4))
    faces = grid_faces(LASH_ROWS, COLS)
    th, tw = LASH_TEXELS
    col = np.tile(np.linspace(0.0, tw, COLS), LASH_ROWS)
    row = np.repeat(np.linspace(th, 0.0, LASH_ROWS), COLS)
    uv = np.stack([col, row], -1)[faces]
    return fringe, faces, uv, lash_texture(th, tw)


def lash_texture(rows: int, cols: int, seed: int = 5) -> np.ndarray:
    """RGBA strands (sRGB): about a third of the columns a lash, each from the root (the last
    row) to its own random length; alpha 0 between them."""
    rng = np.random.default_rng(seed)
    present = rng.random(cols) < 0.3
    reach = rows * (0.55 + 0.45 * rng.random(cols))  # each strand's length in rows
    height = np.arange(rows)[::-1][:, None] + 0.5  # rows above the root
    a = (present[None, :] & (height < reach[None, :])).astype(float)
    rgb = np.broadcast_to(T.LASH, (rows, cols, 3))
    return np.concatenate([rgb, a[..., None]], axis=-1)
