"""The head round a face surface.

For the built-in face, and any face whose skin edge goes once round the back of the head (a
photo talker; a scan cropped to the face), :func:`closed_head`: the closure that makes skin and
head one surface (:mod:`.closure`; a textured face's in its own skin colour), the hair over it
(:mod:`.hair`) and the ears (:mod:`.ears`) where the skin stops in front of them.

For a face whose edge does not allow it, the earlier head: a closed head shell with hair and
neck, the hairline shared with the skin, the ears, and the skirt that joins the skin's moving
edge to the shell. The shell is a radial surface about the head's centre: behind the skin it
follows the skin a little inside it and sinks deep under the face, and where the skin stops it
continues as an adult head (ellipsoid 150 x 230 x 190 mm) and a neck (cylinder of 52 mm radius),
blended so that it meets the skin's edge.
"""

from __future__ import annotations

import numpy as np

from . import textures as T
from .closure import boundary_loops, build_closure
from .cranium import Cranium
from .hair import hair_parts
from .look import FaceLook
from .mesh import Part, grid_faces, skin_depth
from .raster import rasterise

HAIR = T.HAIR
SKIN_GLOSS = (0.10, 16.0)  #: specular strength and exponent of the skin and the head
SKIRT_DEPTH = 0.008  #: m, how far the skirt runs in from the skin's edge


def skirt_part(look: FaceLook) -> Part | None:
    """A strip from the skin's outer edge 8 mm in towards the head's centre, both sides drawn.

    It closes the crack that would open between the moving skin's edge and the fixed head
    shell behind it. Edges within 40 mm of the stomion (the mouth slit) get none.
    """
    f = look.triangles
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    u, counts = np.unique(e, axis=0, return_counts=True)
    edges = u[counts == 1]
    lm = look.landmarks
    if "stomion" in lm:
        far = np.linalg.norm(look.rest[edges].mean(axis=1) - lm["stomion"], axis=1) > 0.04
        edges = edges[far]
    if len(edges) == 0:
        return None
    nodes, local = np.unique(edges, return_inverse=True)
    local = local.reshape(-1, 2)
    m = len(nodes)
    a, b = local[:, 0], local[:, 1]
    quads = np.concatenate([np.column_stack([a, b, b + m]), np.column_stack([a, b + m, a + m])])
    faces = np.concatenate([quads, quads[:, ::-1]])
    c = head_centre(look)[0]
    inward = c - look.rest[nodes]
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    rest = np.concatenate([look.rest[nodes], look.rest[nodes] + SKIRT_DEPTH * inward])
    if look.vertex_colours is not None:
        colour = look.vertex_colours[nodes] / 255.0
    elif look.image is not None:
        colour = np.tile(T.SKIN, (m, 1))
    else:
        h = hair_on_skin(look)(look.rest[nodes, 0], look.rest[nodes, 1])[:, None]
        colour = h * HAIR + (1 - h) * T.SKIN
    return Part("skirt", rest, faces, np.concatenate([colour, colour]), (0.05, 10.0), "skirt",
                skirt_nodes=nodes)


def ear_parts(look: FaceLook) -> list[Part]:
    """Auricles where the skin stops at the sides of the head (a face cut at the ears).

    Each ear is a two-sided flap 62 mm tall and 32 mm wide (adult means, Farkas), attached
    along its front edge at the skin's side edge, flaring to 18 mm off the head at the rim
    (helix), with a hollow concha; it spans from the brow to the nose base.
    """
    r = look.rest
    lm = look.landmarks
    nasion = lm.get("nasion")
    if nasion is None:
        return []
    parts = []
    yc = nasion[1] - 0.024
    stops = skin_stops_at_the_ears(look)
    for side, name in ((1, "ear_left"), (-1, "ear_right")):
        i_max = stops.get(side)
        if i_max is None:
            continue  # the skin goes on round the side: a scan with its own ears
        a = r[i_max].copy()
        a[1] = yc
        out = np.array([side * np.cos(np.radians(20)), 0.0, -np.sin(np.radians(20))])
        back = np.array([side * np.sin(np.radians(20)), 0.0, np.cos(np.radians(20))]) * -1
        up = np.array([0.0, np.cos(np.radians(15)), np.sin(np.radians(15)) * -1])
        ns, nt = 14, 22
        S, Tt = np.meshgrid(np.linspace(0, 1, ns), np.linspace(-1, 1, nt), indexing="ij")
        width = 0.032 * np.sqrt(np.clip(1 - Tt**2, 0, 1)) ** 0.7 * (1 - 0.25 * (Tt < 0) * Tt**2)
        along = S * width
        flare = -0.002 + 0.020 * S**1.5  # the root sunk 2 mm into the head
        curl = 0.004 * np.clip((S - 0.8) / 0.2, 0, 1) ** 2  # the helix rolls forward
        bowl = -0.005 * np.exp(-(((S - 0.35) / 0.18) ** 2) - ((Tt + 0.1) / 0.35) ** 2)
        pts = (a + along[..., None] * back + (Tt * 0.031)[..., None] * up
               + (flare + bowl)[..., None] * out + curl[..., None] * (-back))
        v = pts.reshape(-1, 3)
        f = grid_faces(ns, nt)
        f = f if side < 0 else f[:, ::-1]
        albedo = np.tile(T.EAR, (len(v), 1))
        parts.append(Part(name, v, f, albedo, (0.08, 14.0), "skull"))
        parts.append(Part(name + "_back", v, f[:, ::-1], albedo * 0.9, (0.05, 10.0), "skull",
                          inward=True))
    return parts


def skin_stops_at_the_ears(look: FaceLook) -> dict:
    """Side (1: the subject's left, -1: right) -> the skin node furthest out at ear height (24 mm
    under the nasion, within 20 mm), for each side where that node is on the skin's edge: the
    skin stops in front of the ear there and the renderer adds one. A side whose furthest node
    is inside the skin (a scan with its own ears, which stand out of it) is left out."""
    from ..geometry.mesh import boundary_nodes

    r = look.rest
    nasion = look.landmarks.get("nasion")
    if nasion is None:
        return {}
    edge = set(boundary_nodes(look.triangles).tolist())
    band = np.abs(r[:, 1] - (nasion[1] - 0.024)) < 0.02
    out = {}
    if band.any():
        for side in (1, -1):
            i_max = int(np.flatnonzero(band)[np.argmax(side * r[band, 0])])
            if i_max in edge:
                out[side] = i_max
    return out


def head_centre(look: FaceLook) -> tuple[np.ndarray, float, np.ndarray]:
    """Centre of the head shell, the skin's top height and the nasion (m)."""
    r = look.rest
    top = r[:, 1].max()
    nasion = look.landmarks.get(
        "nasion", np.array([np.median(r[:, 0]), top - 0.075, r[:, 2].max() - 0.02]))
    return np.array([nasion[0], nasion[1] + 0.005, nasion[2] - 0.088]), top, nasion


def hairline(lon_deg: np.ndarray, top: float, nasion_y: float) -> np.ndarray:
    """Height (m) of the hairline at longitude ``lon_deg`` about the head centre (0: front)."""
    return np.interp(np.abs(lon_deg), [0, 35, 60, 88, 112, 135, 180],
                     [top - 0.009, top - 0.013, top - 0.024, top - 0.036,
                      top - 0.042, nasion_y - 0.020, nasion_y - 0.052])


def hair_on_skin(look: FaceLook):
    """Hair coverage (0..1) at frontal (x, y) of the skin: above :func:`hairline` at the
    point's longitude about the head's centre (its depth from the skin's frontal surface)."""
    c, top, nasion = head_centre(look)
    depth = skin_depth(look)

    def cover(x, y):
        z = depth(x, y)
        z = np.where(np.isfinite(z), z, c[2])
        lon = np.degrees(np.arctan2(x - c[0], z - c[2]))
        return np.clip((y - hairline(lon, top, nasion[1])) / 0.003 + 0.5, 0.0, 1.0)
    return cover


def cranium_of(look: FaceLook) -> Cranium:
    """The adult head and neck (:class:`.cranium.Cranium`) about the head's centre, its neck's
    front through the skin's throat (the front-most node of the skin's lowest edge)."""
    c = head_centre(look)[0]
    edge = look.rest[boundary_loops(look.triangles)[0]]
    low = edge[edge[:, 1] < edge[:, 1].min() + 0.003]
    throat = low[np.argmax(low[:, 2])]
    return Cranium(c, throat)


def closed_head(look: FaceLook) -> list[Part] | None:
    """The head that closes the skin into one surface (:mod:`.closure`, skin-coloured, its
    inner side drawn dark) and the hair over it (:mod:`.hair`); None where the skin's edge
    does not allow it (the caller falls back to :func:`head_shell`)."""
    closure = build_closure(look.rest, look.triangles, cranium_of(look))
    if closure is None:
        return None
    c, top, nasion = head_centre(look)
    albedo = np.tile(T.SKIN, (len(closure.rest), 1))
    if look.textured:
        # a scan's or a photo's own skin: each vertex takes the colour of the edge node its ray
        # leaves from, fading into the edge's mean colour away from it, so that the head goes
        # on from the skin's edge in the skin's colour
        edge = skin_colours(look)
        tone = edge[closure.loop].mean(axis=0)
        w = closure.weights[:, None]
        albedo = w * edge[closure.nodes] + (1.0 - w) * tone
    # its inner side is drawn dark, as the skin's: a line of sight through a palpebral fissure
    # or the parted lips ends on the inside of the head
    head = Part("head", closure.rest, closure.faces, albedo, SKIN_GLOSS, "follow",
                follow=closure, two_sided=np.ones(len(closure.faces), bool))
    n = len(look.rest)
    verts = np.concatenate([look.rest, closure.rest])
    faces = np.concatenate([look.triangles, closure.joint_faces(n)])
    hair = hair_parts(verts, faces, c, lambda lon: hairline(lon, top, nasion[1]), look.hair)
    if look.textured:
        # the strip under the fringe takes the colour of the skin or head nearest it, as the
        # plain skin's strip has the plain skin's (it shows below the strands' ends)
        from dataclasses import replace

        from scipy.spatial import cKDTree

        colours = np.concatenate([edge, albedo])
        hair = [replace(p, albedo=colours[cKDTree(verts).query(p.rest)[1]])
                if p.name == "hair_under" else p for p in hair]
    from ..geometry.mesh import vertex_normals
    from .ears import ear_parts as auricles

    # the renderer's ears only where the skin stops in front of them (a scan's own stay alone)
    sides = {"ear_left": 1, "ear_right": -1}
    stops = skin_stops_at_the_ears(look)
    ears = [p for p in auricles(verts, vertex_normals(verts, faces), nasion)
            if sides[p.name.removesuffix("_back")] in stops]
    if look.textured:
        # a textured face's ears in its own skin tone: the built-in ear's colour (and its
        # hollows' shading) scaled by the tone over the built-in skin's, channel by channel
        from dataclasses import replace

        ears = [replace(p, albedo=np.clip(p.albedo * tone / T.SKIN, 0.0, 1.0)) for p in ears]
    return [head, *hair, *ears]


def skin_colours(look: FaceLook) -> np.ndarray:
    """(n, 3) in [0, 1]: each skin node's colour (sRGB) from a textured face's vertex colours
    or texture (the texel at one of its triangle corners); the plain skin's without either."""
    n = len(look.rest)
    if look.vertex_colours is not None:
        return look.vertex_colours[:n] / 255.0
    if look.image is None or look.uv is None:
        return np.tile(T.SKIN, (n, 1))
    corner_uv = np.zeros((n, 2))
    corner_uv[look.triangles.reshape(-1)] = look.uv.reshape(-1, 2)
    h, w = look.image.shape[:2]
    col = np.clip((corner_uv[:, 0] * w).astype(int), 0, w - 1)
    row = np.clip(((1.0 - corner_uv[:, 1]) * h).astype(int), 0, h - 1)
    return look.image[row, col, :3] / 255.0


def head_shell(look: FaceLook) -> Part | None:
    """A closed head and neck that meet the skin's edges (see the module text)."""
    from scipy import ndimage

    r = look.rest
    c, top, nasion = head_centre(look)
    radii_head = np.array([0.075, 0.115, 0.095])
    n_lat, n_lon = 61, 120
    lat = np.radians(np.linspace(-89.5, 89.5, n_lat))
    lon = np.radians(np.linspace(-180.0, 180.0, n_lon, endpoint=False))
    LA, LO = np.meshgrid(lat, lon, indexing="ij")
    d = np.stack([np.cos(LA) * np.sin(LO), np.sin(LA), np.cos(LA) * np.cos(LO)], -1)
    # prior: ellipsoid head and a neck cylinder below the centre
    r_ell = 1.0 / np.sqrt(((d / radii_head) ** 2).sum(-1))
    neck_c = np.array([c[0], c[2] - 0.012])
    rn = 0.052
    dxz = np.hypot(d[..., 0], d[..., 2])
    # exit distance of the ray from c through the cylinder |(x, z) - neck_c| = rn, y < c_y
    ox, oz = c[0] - neck_c[0], c[2] - neck_c[1]
    a = np.maximum(dxz ** 2, 1e-12)
    b = 2 * (ox * d[..., 0] + oz * d[..., 2])
    cc = ox * ox + oz * oz - rn * rn
    t_cyl = (-b + np.sqrt(np.maximum(b * b - 4 * a * cc, 0))) / (2 * a)
    t_cyl = np.minimum(t_cyl, (0.30) / np.maximum(-d[..., 1], 1e-6))
    t_cyl = np.where(d[..., 1] < -0.2, t_cyl, 0.0)
    r_prior = np.maximum(r_ell, t_cyl)
    # where the skin covers: its distance from c along each direction (nearest surface)
    rel = r - c
    dist = np.linalg.norm(rel, axis=1)
    vlat = np.degrees(np.arcsin(np.clip(rel[:, 1] / dist, -1, 1)))
    vlon = np.degrees(np.arctan2(rel[:, 0], rel[:, 2]))
    px = ((vlon + 180.0) / 360.0 * n_lon).astype(np.float32)
    py = ((vlat + 90.0) / 180.0 * n_lat).astype(np.float32)
    tris = look.triangles.astype(np.int32)
    # a triangle behind the head may straddle lon = +-180: it would smear across the map
    tris = tris[np.ptp(px[tris], axis=1) < 0.5 * n_lon]
    both = np.concatenate([tris, tris[:, ::-1]]).astype(np.int32)
    z = np.full((n_lat, n_lon), -np.inf, np.float32)
    tid = np.full((n_lat, n_lon), -1, np.int32)
    bary = np.zeros((n_lat, n_lon, 2), np.float32)
    dummy_uv = np.zeros((len(both), 3, 2), np.float32)
    rasterise(px, py, (-dist).astype(np.float32), both, dummy_uv,
              np.zeros(len(both), np.int8), np.zeros(len(both), bool),
              np.zeros(len(both), bool), np.ones((1, 1, 4), np.float32), z, tid, bary)
    covered = tid >= 0
    if not covered.any():
        return None
    r_skin = np.where(covered, -z, np.nan)
    inside_deg = ndimage.distance_transform_edt(covered) * 3.0  # ~3 degrees per cell
    g = np.clip(inside_deg / 20.0, 0.0, 1.0) ** 2
    target = np.where(covered, r_skin - 0.002 - g * np.maximum(r_skin - 0.016, 0), 0.0)
    # off the skin: the prior, shifted to meet the skin's edge and relaxing with distance
    idx = ndimage.distance_transform_edt(~covered, return_distances=False, return_indices=True)
    out_deg = ndimage.distance_transform_edt(~covered) * 3.0
    edge_offset = (r_skin - 0.002 - r_prior)[idx[0], idx[1]]
    ext = r_prior + edge_offset * np.exp(-out_deg / 25.0)
    rad = np.where(covered, target, ext)
    rad = ndimage.gaussian_filter(rad, 1.0, mode=("nearest", "wrap"))
    # hair above a hairline that runs from the forehead's top to the nape (the skin's texture
    # carries the same hair over its top edge, which hides that edge)
    rad = np.where(covered, np.minimum(rad, r_skin - 0.0015), rad)
    # the grid closes on itself at lon = 180 through a repeated column, so that the texture
    # coordinates need not wrap
    rad = np.concatenate([rad, rad[:, :1]], axis=1)
    d = np.concatenate([d, d[:, :1]], axis=1)
    hidden = np.concatenate([inside_deg, inside_deg[:, :1]], axis=1) > 9.0
    verts = (c + d * rad[..., None]).reshape(-1, 3)
    faces = grid_faces(n_lat, n_lon + 1)[:, ::-1]  # columns run towards -x at lon = 0
    # under the face the shell is never seen (the skin covers it and the cavity, the eye
    # sockets and the skin's inner side fill the openings): leave those triangles out
    faces = faces[~hidden.ravel()[faces].all(axis=1)]
    # hair as a texture over (lon, lat): a smooth hairline whatever the grid
    tex, (tw, th) = _hair_texture(c, rad, d, top, nasion[1])
    u = np.tile(np.linspace(0, tw, n_lon + 1), n_lat)
    v = np.repeat(np.linspace(th, 0, n_lat), n_lon + 1)
    uv = np.stack([u, v], -1)[faces]
    albedo = np.tile(T.SKIN, (len(verts), 1))
    return Part("head", verts, faces, albedo, (0.06, 10.0), "skull", uv, tex)


def _hair_texture(c, rad, d, top: float, nasion_y: float, per_degree: int = 2):
    """RGBA texture over the shell's (lon, lat) grid: hair above :func:`hairline`, skin below.

    Returns the image, row 0 at lat +90, and its (width, height) in texels.
    """
    from scipy.ndimage import map_coordinates

    n_lat, n_cols = rad.shape
    th, tw = 180 * per_degree, 360 * per_degree
    la = np.linspace(n_lat - 1, 0, th)  # grid rows from the top
    lo = np.linspace(0, n_cols - 1, tw)
    LA, LO = np.meshgrid(la, lo, indexing="ij")
    y = c[1] + map_coordinates(rad * d[..., 1], [LA, LO], order=1)
    lon = np.linspace(-180.0, 180.0, tw)[None, :]
    rng = np.random.default_rng(11)
    strands = 0.85 + 0.3 * rng.random((th, tw))
    m = np.clip((y - hairline(lon, top, nasion_y)) / 0.003 + 0.5, 0.0, 1.0)[..., None]
    rgb = (1 - m) * T.SKIN + m * HAIR * strands[..., None]
    return np.concatenate([np.clip(rgb, 0, 1), np.ones((th, tw, 1))], axis=-1), (tw, th)
