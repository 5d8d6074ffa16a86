"""The face's parts: the skin (its texture, cut-out fissures and inner side), the eyes, and the
mouth (oral cavity, dental arches, tongue, and the seal that closes the lips' slit from
inside)."""

from __future__ import annotations

import numpy as np

from . import dentition
from . import textures as T
from .fissures import Fissures, can_cut, cut_fissures
from .head import HAIR, hair_on_skin
from .lids import lash_fringe, lid_mesh, lid_of, lower_lid_of, margin_mesh
from .look import FaceLook
from .mesh import Part, fit_inside, skin_depth, sphere

CAVITY = np.array([0.50, 0.20, 0.20])  #: sRGB, the mouth's lining where it is lit
SOCKET = np.array([0.55, 0.30, 0.28])
EYE_RADIUS = 0.012  #: m


def skin_part(look: FaceLook, painted_hair: bool = True,
              fissures: Fissures | None = None) -> Part:
    """The skin. ``painted_hair``: paint the scalp hair over the skin's top band (for a head
    without the hair layer of :mod:`.hair`). ``fissures``: a textured face's fissures cut
    from its image (:func:`.fissures.cut_fissures`; its alpha is tested), else its image is
    drawn whole."""
    n = len(look.rest)
    gloss = (0.10, 16.0)
    if look.image is not None and look.uv is not None:
        img = (_fit_texture(look.image).astype(float) / 255.0 if fissures is None
               else fissures.image)
        h, w = img.shape[:2]
        alpha = np.ones((h, w)) if fissures is None else fissures.alpha
        tex = np.concatenate([img[..., :3], alpha[..., None]], axis=-1)
        uv = np.empty((len(look.triangles), 3, 2))
        uv[..., 0] = look.uv[..., 0] * w
        uv[..., 1] = (1.0 - look.uv[..., 1]) * h
        return Part("skin", look.rest, look.triangles, np.tile(T.SKIN, (n, 1)), gloss, "skin",
                    uv, tex, fissures is not None, two_sided=_inner_side(look))
    if look.vertex_colours is not None:
        return Part("skin", look.rest, look.triangles, look.vertex_colours / 255.0, gloss,
                    "skin", two_sided=_inner_side(look))
    xy = look.rest[:, :2]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    hair = hair_on_skin(look) if painted_hair else (lambda x, y: np.zeros(np.shape(x)))
    image, (x0, y0) = T.skin_texture(look.landmarks, (lo[0], hi[0], lo[1], hi[1]),
                                     hair=hair if painted_hair else None,
                                     edge_fade=None if painted_hair else _edge_fade(look))
    corner = xy[look.triangles]  # (f, 3, 2)
    uv = np.empty_like(corner)
    uv[..., 0] = (corner[..., 0] - x0) / T.SKIN_TEXEL
    uv[..., 1] = (y0 - corner[..., 1]) / T.SKIN_TEXEL
    h = hair(look.rest[:, 0], look.rest[:, 1])[:, None]
    albedo = h * HAIR + (1 - h) * T.SKIN
    return Part("skin", look.rest, look.triangles, albedo, _moist_lips(look, gloss), "skin",
                uv, image, True, two_sided=_inner_side(look))


EDGE_FADE = 0.012  #: m (frontal) over which the skin's mottle and cheek colour fade out


def _edge_fade(look: FaceLook):
    """Weight (x, y) -> [0, 1] of the skin texture's mottle and cheek colour: 0 on the skin's
    outer edge, 1 from :data:`EDGE_FADE` inside it (frontal distance), so that the skin meets
    the plain head that goes on from its edge (:mod:`.closure`) in the same colour."""
    from scipy.spatial import cKDTree

    from .closure import boundary_loops

    loop = boundary_loops(look.triangles)[0]
    a = look.rest[loop, :2]
    b = np.roll(a, -1, axis=0)
    k = np.linspace(0.0, 1.0, 12, endpoint=False)[None, :, None]
    tree = cKDTree((a[:, None] + k * (b - a)[:, None]).reshape(-1, 2))

    def fade(x, y):
        # the tree's search stops at EDGE_FADE (farther points get inf): their weight is 1
        # either way, and the search costs a third of an unbounded one
        d, _ = tree.query(np.stack([np.ravel(x), np.ravel(y)], -1),
                          distance_upper_bound=EDGE_FADE)
        return np.clip(d / EDGE_FADE, 0.0, 1.0).reshape(np.shape(x))
    return fade


LIP_GLOSS = (0.18, 40.0)  #: specular strength and exponent of the moist vermilion


def _moist_lips(look: FaceLook, gloss) -> np.ndarray:
    """Per-vertex gloss (n, 2): the skin's, and on the vermilion (:func:`.textures.
    vermilion_mask` at rest) the sharper, stronger highlight of a moist lip."""
    g = np.tile(np.asarray(gloss, float), (len(look.rest), 1))
    lm = look.landmarks
    need = ("mouth_corner_left", "mouth_corner_right", "upper_lip_center", "lower_lip_center")
    if not all(k in lm for k in need):
        return g
    m = T.vermilion_mask(look.rest[:, 0], look.rest[:, 1], lm)[:, None]
    return (1 - m) * g + m * np.asarray(LIP_GLOSS)


MAX_TEXTURE = 2048  #: texels along a scan texture's longer side in the renderer's atlas


def _fit_texture(image: np.ndarray) -> np.ndarray:
    """A scan's texture, reduced (area filter) to at most :data:`MAX_TEXTURE` texels a side.

    A face fills at most a few hundred texels per centimetre of a 1080p frame; a larger image
    only costs memory (the atlas holds float32 RGBA) and cache.
    """
    h, w = image.shape[:2]
    k = max(h, w) / MAX_TEXTURE
    if k <= 1:
        return image
    from PIL import Image

    size = (max(int(round(w / k)), 1), max(int(round(h / k)), 1))
    return np.asarray(Image.fromarray(np.ascontiguousarray(image)).resize(size, Image.BOX))


def _inner_side(look: FaceLook) -> np.ndarray:
    """Skin triangles whose inner side is drawn (dark): all of them.

    The inner side is seen only from inside the head: through the parted lips (the lips' own
    inner side, the cheeks' from an oblique view, out to the skin's edge at the side of the
    face) and through the palpebral fissures. From outside the skin, the head shell and the
    skirt stand in front of it.
    """
    return np.ones(len(look.triangles), bool)


def textured_fissures(look: FaceLook) -> Fissures | None:
    """A textured face's fissures cut from its image as the renderer uses it (None for a face
    without a texture image, or without both eye landmarks)."""
    if look.image is None or look.uv is None or not can_cut(look):
        return None
    return cut_fissures(look, _fit_texture(look.image).astype(float) / 255.0)


def eye_parts(look: FaceLook, fissures: Fissures | None = None) -> list[Part]:
    """Eyeballs, lids, lid margins and socket linings behind the fissures. A textured face's
    (``fissures``, :func:`textured_fissures`) take its lids' skin and its iris colour."""
    depth = skin_depth(look)
    parts = []
    for side, name in ((1, "eye_left"), (-1, "eye_right")):
        if name not in look.landmarks:
            continue
        colours = None if fissures is None else fissures.colours.get(name)
        e = look.landmarks[name] if fissures is None else fissures.eyes.get(
            name, look.landmarks[name])
        iris = T.iris_texture(colour=T.IRIS if colours is None else colours.iris)
        ni = iris.shape[0]
        # a textured face's lids in the skin it has round the eye: the generic albedo scaled
        tint = np.ones(3) if colours is None else colours.lid / T.SKIN
        unit, faces = sphere(24, 36)
        radii = np.array([EYE_RADIUS * 1.22, EYE_RADIUS, EYE_RADIUS])
        # as far forward as the lids allow: behind the skin on a ring round the fissure
        s = np.linspace(-1.3, 1.3, 53)
        hh = np.linspace(-0.012, 0.012, 49)
        S, H = np.meshgrid(s, hh)
        gx = e[0] + side * S * T.FISSURE_HALF_LENGTH
        gy = e[1] + H
        mask = T.eye_mask(gx, gy, e, side)
        dx, dy = gx - e[0], gy - e[1]
        q = 1.0 - (dx / radii[0]) ** 2 - (dy / radii[1]) ** 2
        ok = (mask < -2e-4) & (mask > -0.004) & (q > 0)  # a 4-mm ring round the fissure
        z_skin = depth(gx, gy)
        cz = np.nanmin((z_skin - radii[2] * np.sqrt(np.where(q > 0, q, 0.0)))[ok]) - 6e-4
        centre = np.array([e[0], e[1], cz])
        v = centre + unit * radii
        uvv = np.empty((len(faces), 3, 2))
        loc = unit[faces]  # planar projection of the front onto the iris image
        uvv[..., 0] = (loc[..., 0] * 0.5 + 0.5) * ni
        uvv[..., 1] = (0.5 - loc[..., 1] * 0.5) * ni
        front = unit[faces][..., 2].min(axis=1) > 0
        albedo = np.tile(T.SCLERA, (len(v), 1))
        parts.append(Part(name, v, faces, albedo, (0.7, 90.0), "eye", uvv, iris,
                          tex_mask=front, pivot=centre))
        lid = lid_of(e, centre, radii, side, depth)
        lv, lf, lalb = lid_mesh(lid)
        parts.append(Part(name.replace("eye", "lid"), lv, lf, np.clip(lalb * tint, 0, 1),
                          (0.10, 16.0), "lid", follow=lid, pivot=centre))
        fringe, ff, fuv, ftex = lash_fringe(lid, side)
        fv = fringe.place()
        parts.append(Part(name.replace("eye", "lashes"), fv, ff, np.tile(T.LASH, (len(fv), 1)),
                          (0.15, 20.0), "lid", fuv, ftex, True, follow=fringe,
                          two_sided=np.ones(len(ff), bool), pivot=centre))
        parts.append(caruncle(e, side, depth))
        lower = lower_lid_of(lid)
        lv, lf, lalb = lid_mesh(lower)
        parts.append(Part(name.replace("eye", "lower_lid"), lv, lf, np.clip(lalb * tint, 0, 1),
                          (0.10, 16.0), "lid", follow=lower, pivot=centre))
        mv, mf, malb = margin_mesh(e, centre, radii, side, depth)
        parts.append(Part(name.replace("eye", "lid_margin"), mv, mf, np.clip(malb * tint, 0, 1),
                          (0.12, 24.0), "skull"))
        # the socket's lining (conjunctiva), seen past the eyeball from the side
        lining = fit_inside(centre + np.array([0, 0, 0.003]), unit,
                             radii * np.array([1.5, 1.35, 1.7]), depth, 0.0005)
        parts.append(Part(name + "_socket", lining, faces[:, ::-1],
                          np.tile(SOCKET, (len(v), 1)), (0.1, 20.0), "skull", inward=True))
    return parts


CARUNCLE = np.array([0.82, 0.56, 0.53])  #: sRGB, the caruncle's moist pink
CARUNCLE_RADII = np.array([0.0011, 0.0010, 0.0007])  #: m


def caruncle(eye: np.ndarray, side: int, depth) -> Part:
    """The lacrimal caruncle: a moist pink mound in the medial canthus, 2.2 mm behind the
    skin at the fissure's medial end (seen through the cut, in front of the globe)."""
    x = eye[0] - side * 0.92 * T.FISSURE_HALF_LENGTH
    y = eye[1] - 0.0014
    z = float(depth(np.array([x]), np.array([y]))[0]) - 0.0022
    unit, faces = sphere(10, 16)
    v = np.array([x, y, z]) + unit * CARUNCLE_RADII
    name = "caruncle_left" if side > 0 else "caruncle_right"
    return Part(name, v, faces, np.tile(CARUNCLE, (len(v), 1)), (0.5, 60.0), "skull")


def mouth_parts(look: FaceLook) -> list[Part]:
    lm = look.landmarks
    need = ("upper_lip_center", "lower_lip_center", "mouth_corner_left", "mouth_corner_right")
    if not all(k in lm for k in need):
        return []
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    front_z = lm["upper_lip_center"][2] - look.teeth_depth
    half_w = 0.5 * np.linalg.norm(lm["mouth_corner_left"] - lm["mouth_corner_right"])
    unit, faces = sphere(20, 32)
    # only the inner far wall is drawn (seen through the lips); it holds the teeth and tongue
    centre = np.array([st[0], st[1] - 0.006, front_z - 0.014])
    cav = fit_inside(centre, unit, np.array([half_w + 0.009, 0.030, 0.030]),
                      skin_depth(look), 0.001)
    # the oral mucosa: lit near the opening, darker deep in the mouth and up under the palate
    deep = np.clip((front_z - cav[:, 2]) / 0.04, 0.0, 1.0)
    high = np.clip((cav[:, 1] - st[1]) / 0.02, 0.0, 1.0)
    shade = 1.0 - 0.55 * deep - 0.25 * high
    cavity = Part("cavity", cav, faces[:, ::-1], CAVITY * shade[:, None], (0.05, 8.0),
                  "skull", inward=True)
    upper_teeth, upper_gum = dentition.arch(look, True)
    lower_teeth, lower_gum = dentition.arch(look, False)
    parts = [cavity, upper_teeth, lower_teeth, dentition.tongue(look), upper_gum, lower_gum]
    seal = mouth_seal(look)
    return parts if seal is None else [*parts, seal]


def slit_bridge(rest: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Triangles (k, 3) that close the mouth slit between the lips' edge nodes.

    The mouth cut (:func:`facemech.geometry.builder.build_face`) leaves the lips' edges as two
    boundary paths whose nodes coincide at rest (the corners are shared). Each boundary edge
    of the upper lip and its twin on the lower lip make a quad, two triangles wound so that
    they face into the mouth: seen from outside they are culled, seen from inside (a line of
    sight that entered between the lips and leaves between them again) they are drawn. At rest
    the strip has no area; it follows the lips as they part.

    Parameters
    ----------
    rest : (n, 3) rest positions of the skin nodes, m
    triangles : (f, 3) skin triangles, counter-clockwise seen from outside

    Returns
    -------
    (k, 3) int64 node indices; empty when the skin has no cut slit
    """
    tri = np.asarray(triangles, np.int64)
    directed = np.concatenate([tri[:, [0, 1, 2]], tri[:, [1, 2, 0]], tri[:, [2, 0, 1]]])
    key = np.sort(directed[:, :2], axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    edges = directed[count[inv.ravel()] == 1]  # boundary edges (a, b) with the third corner
    nodes = np.unique(edges[:, :2])
    # twins: boundary nodes at the same rest position (the cut's pairs); others are their own
    q = np.round(rest[nodes] / 1e-7).astype(np.int64)
    _, group, size = np.unique(q, axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    twin = {int(n): int(n) for n in nodes}
    for g in np.flatnonzero(size == 2):
        a, b = nodes[group == g]
        twin[int(a)], twin[int(b)] = int(b), int(a)
    paired = {int(n) for n in nodes if twin[int(n)] != int(n)}
    by_edge = {(int(a), int(b)): int(c) for a, b, c in edges}
    out = []
    for a, b, c in edges:
        a, b, c = int(a), int(b), int(c)
        if not ({a, b} & paired):
            continue
        other = by_edge.get((twin[b], twin[a]))
        # each quad once, from the lip whose edge triangle lies above (the upper lip)
        if other is None or rest[c, 1] <= rest[other, 1]:
            continue
        for t in ((a, b, twin[b]), (a, twin[b], twin[a])):
            if len(set(t)) == 3:
                out.append(t)
    return np.asarray(out, np.int64).reshape(-1, 3)


def mouth_seal(look: FaceLook) -> Part | None:
    """The slit between the lips closed from inside (:func:`slit_bridge`), dark.

    A line of sight that enters between the parted lips and would leave the mouth between them
    again (from the side, in front of the teeth or past the cavity, even through lips a hair
    apart) ends on it; from outside it is culled, so it never shows in front of the skin. Its
    nodes are the lips' edge nodes: it moves with the skin. Only the cut between the mouth
    corners is closed (a scan's other seams are left alone).
    """
    lm = look.landmarks
    faces = slit_bridge(look.rest, look.triangles)
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    ends = np.array([lm["mouth_corner_right"], lm["mouth_corner_left"], st])
    lo = ends.min(axis=0) - np.array([0.002, 0.006, 0.0])
    hi = ends.max(axis=0) + np.array([0.002, 0.006, 0.0])
    xy = look.rest[faces][..., :2]  # (k, 3, 2)
    faces = faces[np.all((xy >= lo[:2]) & (xy <= hi[:2]), axis=(1, 2))]
    if len(faces) == 0:
        return None
    n = len(look.rest)
    return Part("mouth_seal", look.rest, faces, np.tile(CAVITY, (n, 1)), (0.0, 1.0), "skin",
                inward=True)
