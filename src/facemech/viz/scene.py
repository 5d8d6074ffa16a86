"""The rendered scene: the moving skin plus render-only anatomy that the physics does not carry.

* **skin**: the epidermal surface of the results, coloured by the scan's own texture or vertex
  colours when it has them, else by a procedural texture drawn from its landmarks (vermilion,
  brows, lashes), with the palpebral fissures cut out;
* **eyes**: eyeballs (sclera, iris, pupil) set behind the fissures, as deep as the lids allow;
* **mouth**: a dark oral cavity, the upper dental arch fixed to the skull, the lower arch and
  the tongue turning with the mandible (the results' jaw angle about the model's hinge);
* **head**: a closed head shell (cranium with hair, back of the head, neck) that joins the
  edges of a face surface which stops at the hairline, the ears or the throat.

The head shell is a radial surface about the head's centre: behind the skin it follows the skin
a little inside it and sinks deep under the face, and where the skin stops it continues as an
adult head (ellipsoid 150 x 230 x 190 mm) and a neck (cylinder of 52 mm radius), blended so that
it meets the skin's edge.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ..geometry.builder import vertex_normals
from ..io.results import TEETH_DEPTH_DEFAULT, render_attrs
from ..solvers.jaw import rotation_matrix
from . import textures as T
from .raster import rasterise, srgb_to_linear

HAIR = T.HAIR
CAVITY = np.array([0.20, 0.07, 0.07])
SOCKET = np.array([0.55, 0.30, 0.28])
TONGUE = np.array([0.74, 0.40, 0.40])
EYE_RADIUS = 0.012  #: m
SKIRT_DEPTH = 0.008  #: m, how far the skirt runs in from the skin's edge


@dataclass(frozen=True)
class FaceLook:
    """What the renderer needs to know of a face (metres, model axes).

    Attributes
    ----------
    rest : (n, 3) rest positions of the skin nodes
    triangles : (f, 3) int skin triangles
    landmarks : name -> (3,) rest position
    hinge_point, hinge_axis : (3,) the jaw hinge (positive angles open the mouth)
    teeth_depth : m from the upper lip's surface back to the incisors
    uv : (f, 3, 2) per-corner texture coordinates in [0, 1] (v up), or None
    image : (h, w, 3) uint8 texture, or None
    vertex_colours : (n, 3) uint8, or None
    """

    rest: np.ndarray
    triangles: np.ndarray
    landmarks: dict
    hinge_point: np.ndarray
    hinge_axis: np.ndarray
    teeth_depth: float = TEETH_DEPTH_DEFAULT
    uv: np.ndarray | None = None
    image: np.ndarray | None = None
    vertex_colours: np.ndarray | None = None

    @property
    def textured(self) -> bool:
        return self.image is not None or self.vertex_colours is not None


def _hinge_guess(lm: dict) -> tuple[np.ndarray, np.ndarray]:
    if "jaw_angle_left" in lm and "jaw_angle_right" in lm:
        g = 0.5 * (lm["jaw_angle_left"] + lm["jaw_angle_right"])
        return g + np.array([0.0, 0.054, -0.029]), np.array([1.0, 0.0, 0.0])
    return np.array([0.0, -0.046, -0.073]), np.array([1.0, 0.0, 0.0])


def look_from_dataset(ds) -> FaceLook:
    """The :class:`FaceLook` of a results dataset (:func:`facemech.io.results.read_results`)."""
    rest = (ds["rest_positions"].values if "rest_positions" in ds
            else ds["positions"].values[0])
    tri = ds["triangles"].values.astype(np.int64)
    nodes = json.loads(ds.attrs.get("marker_nodes", "{}"))
    lm = {k: rest[int(v)] for k, v in nodes.items() if 0 <= int(v) < len(rest)}
    if "hinge_point_m" in ds.attrs:
        hp = np.array(json.loads(ds.attrs["hinge_point_m"]), float)
        ha = np.array(json.loads(ds.attrs["hinge_axis"]), float)
    else:
        hp, ha = _hinge_guess(lm)
    depth = float(ds.attrs.get("teeth_depth_m", TEETH_DEPTH_DEFAULT))
    app = _appearance(ds)
    return FaceLook(rest, tri, lm, hp, ha, depth, *app)


def look_from_model(model) -> FaceLook:
    """The :class:`FaceLook` of a :class:`~facemech.geometry.model.FaceModel`."""
    n = model.n_surface
    rest = model.rest_positions[:n]
    lm = {k: rest[v] for k, v in {**model.landmarks, **model.markers}.items()}
    attrs = render_attrs(model)
    app = _appearance(model)
    return FaceLook(rest, np.asarray(model.faces, np.int64), lm, model.hinge_point,
                    model.hinge_axis, attrs["teeth_depth_m"], *app)


def _appearance(source):
    """(uv, image, vertex colours) of a model or dataset carrying a scan's appearance."""
    try:
        from ..geometry import appearance as A
    except ImportError:
        return None, None, None
    if hasattr(source, "attrs") and hasattr(source, "data_vars"):
        app = A.appearance_from_dataset(source)
    else:
        app = getattr(source, "appearance", None)
    if app is None:
        return None, None, None
    return app.uv, app.image, app.vertex_colours


# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Part:
    """A mesh of the scene. ``motion``: 'skin' (the results' nodes), 'skull' or 'jaw'."""

    name: str
    rest: np.ndarray  # (n, 3) m
    faces: np.ndarray  # (f, 3)
    albedo: np.ndarray  # (n, 3) sRGB
    gloss: tuple[float, float]  # specular strength, Blinn-Phong exponent
    motion: str = "skull"
    uv: np.ndarray | None = None  # (f, 3, 2) texel coordinates in ``texture``
    texture: np.ndarray | None = None  # (h, w, 4) sRGB + alpha
    alpha_test: bool = False
    inward: bool = False  # normals point inward (an interior seen from inside)
    tex_mask: np.ndarray | None = None  # (f,) bool: which triangles use the texture
    two_sided: np.ndarray | None = None  # (f,) bool: also draw the inner side (dark)
    skirt_nodes: np.ndarray | None = None  # motion 'skirt': the skin's edge nodes


@dataclass(frozen=True)
class Scene:
    """All parts packed for the rasteriser; :meth:`frame` places them for one time step."""

    parts: tuple[Part, ...]
    look: FaceLook
    tris: np.ndarray  # (F, 3) int32
    uv: np.ndarray  # (F, 3, 2) float32 atlas texels
    tex: np.ndarray  # (F,) int8
    alpha_test: np.ndarray  # (F,) bool
    two_sided: np.ndarray  # (F,) bool
    atlas: np.ndarray  # (H, W, 4) float32 linear
    albedo: np.ndarray  # (N, 3) float32 linear
    gloss: np.ndarray  # (N, 2) float32
    offsets: np.ndarray  # (parts + 1,) vertex offsets
    rest_normals: tuple = ()  # per part, (n, 3) unit normals at rest
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))  # of the head, m
    framing: dict = field(default_factory=dict)

    def frame(self, skin: np.ndarray, jaw_angle: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Vertices (N, 3) and unit normals (N, 3) of every part for one frame (model axes)."""
        look = self.look
        rot = rotation_matrix(look.hinge_axis, float(jaw_angle))
        verts, norms = [], []
        skin = np.asarray(skin, float)
        skin_normals = None
        for p, n_rest in zip(self.parts, self.rest_normals, strict=True):
            if p.motion == "skin":
                v = skin
                n = skin_normals = vertex_normals(v, p.faces)
            elif p.motion == "skirt":  # from the skin's edge nodes in towards the head's centre
                nodes = p.skirt_nodes
                edge = skin[nodes]
                inward = self.centre - edge
                inward /= np.linalg.norm(inward, axis=1, keepdims=True)
                v = np.concatenate([edge, edge + SKIRT_DEPTH * inward])
                n = np.concatenate([skin_normals[nodes]] * 2)
            else:
                v = p.rest
                n = n_rest
                if p.motion == "jaw" and jaw_angle != 0.0:
                    v = (v - look.hinge_point) @ rot.T + look.hinge_point
                    n = n @ rot.T
            verts.append(v)
            norms.append(-n if p.inward else n)
        return np.concatenate(verts), np.concatenate(norms)


# ---- the parts ------------------------------------------------------------------------------
def _skin_part(look: FaceLook) -> Part:
    n = len(look.rest)
    gloss = (0.10, 16.0)
    if look.image is not None and look.uv is not None:
        img = _fit_texture(look.image).astype(float) / 255.0
        h, w = img.shape[:2]
        tex = np.concatenate([img, np.ones((h, w, 1))], axis=-1)
        uv = np.empty((len(look.triangles), 3, 2))
        uv[..., 0] = look.uv[..., 0] * w
        uv[..., 1] = (1.0 - look.uv[..., 1]) * h
        return Part("skin", look.rest, look.triangles, np.tile(T.SKIN, (n, 1)), gloss, "skin",
                    uv, tex, False, two_sided=_inner_side(look))
    if look.vertex_colours is not None:
        return Part("skin", look.rest, look.triangles, look.vertex_colours / 255.0, gloss,
                    "skin", two_sided=_inner_side(look))
    xy = look.rest[:, :2]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    hair = _hair_on_skin(look)
    image, (x0, y0) = T.skin_texture(look.landmarks, (lo[0], hi[0], lo[1], hi[1]), hair=hair)
    corner = xy[look.triangles]  # (f, 3, 2)
    uv = np.empty_like(corner)
    uv[..., 0] = (corner[..., 0] - x0) / T.SKIN_TEXEL
    uv[..., 1] = (y0 - corner[..., 1]) / T.SKIN_TEXEL
    h = hair(look.rest[:, 0], look.rest[:, 1])[:, None]
    albedo = h * HAIR + (1 - h) * T.SKIN
    return Part("skin", look.rest, look.triangles, albedo, gloss, "skin", uv, image, True,
                two_sided=_inner_side(look))


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
    """Skin triangles whose inner side is drawn (dark): all but those within 15 mm of the
    skin's edge. The inner side shows only through the parted lips and the palpebral fissures;
    near the edges the head shell stands behind the skin instead."""
    from scipy.spatial import cKDTree

    from ..geometry.builder import _boundary_nodes

    edge = look.rest[_boundary_nodes(look.triangles)]
    centroid = look.rest[look.triangles].mean(axis=1)
    if len(edge) == 0:
        return np.ones(len(centroid), bool)
    dist, _ = cKDTree(edge).query(centroid)
    return dist > 0.015


def _sphere(n_lat: int, n_lon: int):
    """Unit UV sphere: vertices (n, 3) and outward triangles."""
    lat = np.linspace(-np.pi / 2, np.pi / 2, n_lat)
    lon = np.linspace(-np.pi, np.pi, n_lon, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    v = np.stack([np.cos(la) * np.sin(lo), np.sin(la), np.cos(la) * np.cos(lo)], -1)
    return v.reshape(-1, 3), _grid_faces(n_lat, n_lon, wrap=True)


def _grid_faces(rows: int, cols: int, wrap: bool = False) -> np.ndarray:
    """Triangles of a (rows, cols) vertex grid, counter-clockwise seen from outside.

    Rows go up (increasing latitude), columns go round (increasing longitude = towards +x from
    the front), which makes (a, b, c) with a=(r,c), b=(r,c+1), c=(r+1,c) outward.
    """
    faces = []
    cmax = cols if wrap else cols - 1
    for r in range(rows - 1):
        for c in range(cmax):
            a = r * cols + c
            b = r * cols + (c + 1) % cols
            d = (r + 1) * cols + c
            e = (r + 1) * cols + (c + 1) % cols
            faces += [(a, b, e), (a, e, d)]
    return np.asarray(faces, np.int64)


def _skin_depth(look: FaceLook):
    """z of the rest skin at frontal (x, y) (the frontal sheet only), m; NaN off the face."""
    from scipy.interpolate import LinearNDInterpolator

    r = look.rest
    front = r[:, 2] > np.percentile(r[:, 2], 30)
    return LinearNDInterpolator(r[front, :2], r[front, 2])


def _fit_inside(centre, unit, radii, depth, margin: float) -> np.ndarray:
    """An ellipsoid's vertices, shrunk (x and z) until it lies ``margin`` m inside the skin.

    Only the inner far wall of these linings is drawn; a part of it outside the skin would
    show on the face.
    """
    radii = np.asarray(radii, float)
    for _ in range(40):
        v = centre + unit * radii
        zs = depth(v[:, 0], v[:, 1])
        if not np.any(np.isfinite(zs) & (v[:, 2] > zs - margin)):
            break
        radii = radii * np.array([0.95, 0.98, 0.95])
    return v


def _eye_parts(look: FaceLook) -> list[Part]:
    depth = _skin_depth(look)
    parts = []
    iris = T.iris_texture()
    ni = iris.shape[0]
    for side, name in ((1, "eye_left"), (-1, "eye_right")):
        if name not in look.landmarks:
            continue
        e = look.landmarks[name]
        unit, faces = _sphere(24, 36)
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
        parts.append(Part(name, v, faces, albedo, (0.7, 90.0), "skull", uvv, iris,
                          tex_mask=front))
        # the socket's lining (conjunctiva), seen past the eyeball from the side
        lining = _fit_inside(centre + np.array([0, 0, 0.003]), unit,
                             radii * np.array([1.5, 1.35, 1.7]), depth, 0.0005)
        parts.append(Part(name + "_socket", lining, faces[:, ::-1],
                          np.tile(SOCKET, (len(v), 1)), (0.1, 20.0), "skull", inward=True))
    return parts


def _arch(look: FaceLook, upper: bool):
    """A dental arch (incisal edge, crowns, gum) as a textured ribbon with a lingual side."""
    lm = look.landmarks
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    ul = lm["upper_lip_center"]
    front_z = ul[2] - look.teeth_depth
    widths = T.UPPER_TEETH_MM if upper else T.LOWER_TEETH_MM
    crown, gum = (0.0105, 0.006) if upper else (0.009, 0.006)
    tex, half = T.arch_texture(widths, crown, gum)
    a_x, a_z = 0.0235, 0.030  # half-width and depth of the arch ellipse (m)
    if not upper:
        a_x, a_z, front_z = 0.021, 0.027, front_z - 0.0025
    edge_y = st[1] - 0.0015 if upper else st[1] + 0.0005
    sign = 1.0 if upper else -1.0
    # arc-length parametrisation of the ellipse x = a sin p, z = -a_z (1 - cos p)
    p = np.linspace(-1.45, 1.45, 400)
    xs, zs = a_x * np.sin(p), -a_z * (1 - np.cos(p))
    arc = np.concatenate([[0], np.cumsum(np.hypot(np.diff(xs), np.diff(zs)))])
    arc -= np.interp(0.0, p, arc)
    s = np.linspace(-min(half, arc[-1]), min(half, arc[-1]), 41)
    pp = np.interp(s, arc, p)
    x, z = a_x * np.sin(pp), front_z - a_z * (1 - np.cos(pp))
    nx, nz = np.sin(pp) / a_x, np.cos(pp) / a_z  # outward normal direction in xz
    nn = np.hypot(nx, nz)
    nx, nz = nx / nn, nz / nn
    heights = np.array([0.0, 0.0015, crown, crown + gum])
    rows = []
    for hgt in heights:  # labial face
        bulge = 0.0008 * np.sin(np.pi * min(hgt / crown, 1.0))
        rows.append(np.stack([x + nx * bulge, np.full_like(x, edge_y + sign * hgt),
                              z + nz * bulge], -1))
    thick = 0.006
    for hgt in (0.0, crown + gum):  # lingual face, from the edge back up
        rows.append(np.stack([x - nx * thick, np.full_like(x, edge_y + sign * hgt),
                              z - nz * thick], -1))
    order = [3, 2, 1, 0, 4, 5] if upper else [0, 1, 2, 3, 5, 4]
    grid = np.stack([rows[k] for k in order])  # rows stacked so that faces point outward
    nr, nc = grid.shape[:2]
    verts = grid.reshape(-1, 3)
    faces = _grid_faces(nr, nc)
    faces = faces if upper else faces[:, ::-1]
    hrow = np.array([heights[k] if k < 4 else 0.0 for k in order])
    u = (np.tile(s, nr) + half) / (2 * half) * tex.shape[1]
    v = (1.0 - np.repeat(hrow, nc) / (crown + gum)) * tex.shape[0]
    uv = np.stack([u, v], -1)[faces]
    labial = np.repeat(np.arange(nr - 1) < 3, 2 * (nc - 1))
    if upper:
        labial = np.repeat(np.arange(nr - 1) < 3, 2 * (nc - 1))
    albedo = np.tile(T.TOOTH * 0.9, (len(verts), 1))
    return Part("upper_teeth" if upper else "lower_teeth", verts, faces, albedo, (0.35, 40.0),
                "skull" if upper else "jaw", uv, tex, tex_mask=labial)


def _mouth_parts(look: FaceLook) -> list[Part]:
    lm = look.landmarks
    need = ("upper_lip_center", "lower_lip_center", "mouth_corner_left", "mouth_corner_right")
    if not all(k in lm for k in need):
        return []
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    front_z = lm["upper_lip_center"][2] - look.teeth_depth
    half_w = 0.5 * np.linalg.norm(lm["mouth_corner_left"] - lm["mouth_corner_right"])
    unit, faces = _sphere(20, 32)
    # only the inner far wall is drawn (seen through the lips); it holds the teeth and tongue
    centre = np.array([st[0], st[1] - 0.006, front_z - 0.014])
    cav = _fit_inside(centre, unit, np.array([half_w + 0.009, 0.030, 0.030]),
                      _skin_depth(look), 0.001)
    cavity = Part("cavity", cav, faces[:, ::-1], np.tile(CAVITY, (len(cav), 1)), (0.0, 1.0),
                  "skull", inward=True)
    tr = np.array([0.018, 0.0065, 0.019])
    tongue = Part("tongue", np.array([st[0], st[1] - 0.0085, front_z - 0.021]) + unit * tr,
                  faces, np.tile(TONGUE, (len(unit), 1)), (0.25, 30.0), "jaw")
    return [cavity, _arch(look, True), _arch(look, False), tongue]


def _skirt(look: FaceLook) -> Part | None:
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
    c = _head_centre(look)[0]
    inward = c - look.rest[nodes]
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    rest = np.concatenate([look.rest[nodes], look.rest[nodes] + SKIRT_DEPTH * inward])
    if look.vertex_colours is not None:
        colour = look.vertex_colours[nodes] / 255.0
    elif look.image is not None:
        colour = np.tile(T.SKIN, (m, 1))
    else:
        h = _hair_on_skin(look)(look.rest[nodes, 0], look.rest[nodes, 1])[:, None]
        colour = h * HAIR + (1 - h) * T.SKIN
    return Part("skirt", rest, faces, np.concatenate([colour, colour]), (0.05, 10.0), "skirt",
                skirt_nodes=nodes)


def _ear_parts(look: FaceLook) -> list[Part]:
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
    from ..geometry.builder import _boundary_nodes

    edge = _boundary_nodes(look.triangles)
    parts = []
    yc = nasion[1] - 0.024
    for side, name in ((1, "ear_left"), (-1, "ear_right")):
        band = np.abs(r[:, 1] - yc) < 0.02
        xs = side * r[band, 0]
        if not band.any():
            continue
        i_max = np.flatnonzero(band)[np.argmax(xs)]
        if i_max not in set(edge.tolist()):
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
        f = _grid_faces(ns, nt)
        f = f if side < 0 else f[:, ::-1]
        albedo = np.tile(T.EAR, (len(v), 1))
        parts.append(Part(name, v, f, albedo, (0.08, 14.0), "skull"))
        parts.append(Part(name + "_back", v, f[:, ::-1], albedo * 0.9, (0.05, 10.0), "skull",
                          inward=True))
    return parts


def _head_centre(look: FaceLook) -> tuple[np.ndarray, float, np.ndarray]:
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
                      top - 0.042, nasion_y - 0.020, nasion_y - 0.070])


def _hair_on_skin(look: FaceLook):
    """Hair coverage (0..1) at frontal (x, y) of the skin: above :func:`hairline` at the
    point's longitude about the head's centre (its depth from the skin's frontal surface)."""
    c, top, nasion = _head_centre(look)
    depth = _skin_depth(look)

    def cover(x, y):
        z = depth(x, y)
        z = np.where(np.isfinite(z), z, c[2])
        lon = np.degrees(np.arctan2(x - c[0], z - c[2]))
        return np.clip((y - hairline(lon, top, nasion[1])) / 0.003 + 0.5, 0.0, 1.0)
    return cover


def _head_shell(look: FaceLook) -> Part | None:
    """A closed head and neck that meet the skin's edges (see the module text)."""
    from scipy import ndimage

    r = look.rest
    c, top, nasion = _head_centre(look)
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
    faces = _grid_faces(n_lat, n_lon + 1)[:, ::-1]  # columns run towards -x at lon = 0
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


def build_scene(look: FaceLook, *, eyes: bool = True, mouth: bool = True,
                head: bool = True) -> Scene:
    """Assemble and pack the parts of a face's scene."""
    parts = [_skin_part(look)]
    if eyes and not look.textured:
        parts += _eye_parts(look)
    if mouth:
        parts += _mouth_parts(look)
    if head:
        shell = _head_shell(look)
        if shell is not None:
            parts.append(shell)
            skirt = _skirt(look)
            if skirt is not None:
                parts.append(skirt)
            parts += _ear_parts(look)
    return _pack(parts, look)


def _pack(parts: list[Part], look: FaceLook) -> Scene:
    textures = [p.texture for p in parts if p.texture is not None]
    width = max([t.shape[1] for t in textures] + [1])
    rows, offsets_tex, y = [], {}, 0
    for p in parts:
        if p.texture is not None:
            t = p.texture
            pad = np.zeros((t.shape[0], width, 4))
            pad[:, : t.shape[1]] = t
            pad[:, t.shape[1]:] = t[:, -1:]
            offsets_tex[p.name] = y
            rows.append(pad)
            rows.append(pad[-1:].repeat(2, axis=0))  # a guard band against bleeding
            y += t.shape[0] + 2
    atlas = np.concatenate(rows) if rows else np.ones((1, 1, 4))
    atlas = atlas.astype(np.float32)
    atlas[..., :3] = srgb_to_linear(atlas[..., :3])
    tris, uv, tex, alpha, albedo, gloss, offs = [], [], [], [], [], [], [0]
    two = []
    for p in parts:
        base = offs[-1]
        f = np.asarray(p.faces, np.int64) + base
        tris.append(f)
        if p.uv is not None:
            q = np.array(p.uv, np.float32)
            q[..., 1] += offsets_tex[p.name]
            mask = np.ones(len(f), bool) if p.tex_mask is None else p.tex_mask
            tex.append(mask.astype(np.int8))
        else:
            q = np.zeros((len(f), 3, 2), np.float32)
            tex.append(np.zeros(len(f), np.int8))
        uv.append(q)
        cut = (tex[-1] > 0) & p.alpha_test
        if cut.any():  # test alpha only where the triangle's texels hold a cut-out
            cut &= _touches_cutout(q, atlas)
        alpha.append(cut)
        two.append(np.zeros(len(f), bool) if p.two_sided is None else p.two_sided)
        albedo.append(srgb_to_linear(np.clip(p.albedo, 0, 1)))
        gloss.append(np.tile(np.array(p.gloss, np.float32), (len(p.rest), 1)))
        offs.append(base + len(p.rest))
    scene = Scene(tuple(parts), look, np.concatenate(tris).astype(np.int32),
                  np.concatenate(uv).astype(np.float32), np.concatenate(tex),
                  np.concatenate(alpha), np.concatenate(two), atlas,
                  np.concatenate(albedo).astype(np.float32),
                  np.concatenate(gloss).astype(np.float32), np.array(offs),
                  tuple(vertex_normals(p.rest, p.faces) for p in parts),
                  _head_centre(look)[0])
    object.__setattr__(scene, "framing", _framing(scene))
    return scene


def _touches_cutout(uv: np.ndarray, atlas: np.ndarray) -> np.ndarray:
    """(f,) bool: whether a texel of alpha < 0.5 lies in each triangle's texel bounding box."""
    holes = (atlas[..., 3] < 0.5).astype(np.int64)
    sat = np.zeros((holes.shape[0] + 1, holes.shape[1] + 1), np.int64)
    sat[1:, 1:] = holes.cumsum(0).cumsum(1)
    h, w = holes.shape
    u0 = np.clip(np.floor(uv[..., 0].min(axis=1)).astype(int) - 1, 0, w)
    u1 = np.clip(np.ceil(uv[..., 0].max(axis=1)).astype(int) + 1, 0, w)
    v0 = np.clip(np.floor(uv[..., 1].min(axis=1)).astype(int) - 1, 0, h)
    v1 = np.clip(np.ceil(uv[..., 1].max(axis=1)).astype(int) + 1, 0, h)
    return (sat[v1, u1] - sat[v0, u1] - sat[v1, u0] + sat[v0, u0]) > 0


def _framing(scene: Scene) -> dict:
    """What the views frame: the head from its top to 35 mm under the menton, and the mouth."""
    look = scene.look
    allv = np.concatenate([p.rest for p in scene.parts if p.name in ("skin", "head")])
    top = allv[:, 1].max()
    lm = look.landmarks
    bottom = (lm["menton"][1] if "menton" in lm else look.rest[:, 1].min()) - 0.035
    st = lm.get("stomion", lm.get("upper_lip_center", np.median(look.rest, axis=0)))
    return {"points": allv[(allv[:, 1] >= bottom) & (allv[:, 1] <= top)],
            "mouth": np.asarray(st, float), "mouth_half_height": 0.032}
