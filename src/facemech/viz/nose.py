"""The nose's base, render-only: a relief patch carried by the skin (:mod:`.attach`).

Over the physics' smooth wedge at the nose's base the renderer lays a patch (0.65-mm grid on
the frontal plane, from 3 mm under the subnasale to 14 mm over it, 22 mm either side), each
vertex a height h(x, y) off the skin along its normal: each ala a lobe 9 x 11 mm rising 2 mm,
13 mm off the midline (al-al about 35 mm: Farkas' adult male mean 34.9, SD 2.1), with the
alar groove's shadow round it; the columella a ridge 4 mm wide fading into the lip; each
nostril a dark oval (4.4 x 9.6 mm on the nasal base, raised rim, long axes converging towards
the tip) between them, seen from below and, the base tilting up, from the front. The patch
takes the skin texture's colour under it and, where it is flat, the skin's normals (no seam);
where it is flat in the skin's colour it is left out.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..geometry.builder import vertex_normals
from .attach import closest_on_skin, on_skin
from .look import FaceLook
from .mesh import Part, grid_faces, skin_depth

GRID = 0.00065  #: m, the patch's grid step
ALA = (0.013, 0.0045, 0.0055, 0.0020)  #: m: centre off the midline, semi-axes x, y, height
ALA_ABOVE_SN = 0.0050  #: m, the lobe's centre over the subnasale
COLUMELLA = (0.002, 0.0010)  #: m: half-width, height
NOSTRIL = (0.0060, 0.0022, 0.0048)  #: m: centre off the midline, semi-axes across, along
NOSTRIL_AT = 0.42  #: the nostril's centre, as a fraction of the way from subnasale to tip
NOSTRIL_DARK = np.array([0.09, 0.04, 0.035])  #: sRGB, the opening's core
LIFT = 0.00008  #: m, the patch over the skin where it is flat


def nose_parts(look: FaceLook, skin: Part) -> list[Part]:
    """The nasal base's patch (one part 'nostrils', motion 'attached') of a face with
    subnasale and nose-tip landmarks; ``skin``: its skin part (the colour under it)."""
    lm = look.landmarks
    if "subnasale" not in lm or "nose_tip" not in lm:
        return []
    sn, tip = np.asarray(lm["subnasale"], float), np.asarray(lm["nose_tip"], float)
    xs = np.arange(-0.022, 0.022 + 1e-9, GRID)
    ys = np.arange(sn[1] - 0.003, sn[1] + 0.014 + 1e-9, GRID)
    X, Y = np.meshgrid(xs, ys)  # rows go up, columns towards +x
    Z = skin_depth(look)(X, Y)
    if not np.all(np.isfinite(Z)):
        return []
    h, dark, groove = relief(X, Y, sn, tip)
    pts = np.stack([X, Y, Z], -1).reshape(-1, 3)
    normals = vertex_normals(look.rest, look.triangles)
    # where the patch lies flat on the skin in the skin's own colour it is left out (the skin
    # under it shows the same): only its relief, openings and groove are drawn; the drawn
    # part's rim lies on the skin itself (no lift), so that no sliver opens under its edge at
    # the skin's silhouette
    busy = (h > 2e-5) | (dark > 0) | (groove > 0.02)
    inner = ndimage.binary_erosion(busy, np.ones((3, 3), bool), border_value=0)
    fit = on_skin(pts, look.rest, look.triangles, normals, 0.0)
    fit.offset[:, 2] += h.ravel() + LIFT * inner.ravel()
    blend = np.clip(h.ravel() / 0.0004, 0.0, 1.0)
    fit = fit.with_blend(blend)
    base = _skin_colour(pts, look, skin)
    shade = (1.0 - 0.12 * groove.ravel())[:, None]
    d = dark.ravel()[:, None]
    albedo = (1 - d) * base * shade + d * NOSTRIL_DARK
    faces = grid_faces(len(ys), len(xs))
    faces = faces[busy.ravel()[faces].any(axis=1)]
    return [Part("nostrils", pts, faces, np.clip(albedo, 0, 1), (0.08, 14.0), "attached",
                 follow=fit)]


def relief(X, Y, sn: np.ndarray, tip: np.ndarray):
    """Height (m), nostril darkness (0..1) and alar-groove shadow (0..1) at frontal (X, Y)."""
    ax = np.abs(X)
    # the ala: a smooth lobe (its height falls as (1 - r^2)^2 to its rim)
    cx, rx, ry, top = ALA
    r2 = ((ax - cx) / rx) ** 2 + ((Y - sn[1] - ALA_ABOVE_SN) / ry) ** 2
    ala = top * np.clip(1.0 - r2, 0.0, None) ** 1.5
    groove = np.exp(-((np.sqrt(r2) - 1.1) / 0.2) ** 2) * (ax > cx - 0.3 * rx)
    # the nostril on the base's plane: across (x) and along the subnasale-tip line, seen in
    # the frontal projection (y scaled by the line's vertical share)
    down = abs(tip[1] - sn[1]) / np.linalg.norm(tip - sn)
    ny, nx = sn[1] + NOSTRIL_AT * (tip[1] - sn[1]), NOSTRIL[0]
    turn = np.radians(12.0)
    u = (ax - nx) * np.cos(turn) + (Y - ny) / down * np.sin(turn)
    v = -(ax - nx) * np.sin(turn) + (Y - ny) / down * np.cos(turn)
    q = np.sqrt((u / NOSTRIL[1]) ** 2 + (v / NOSTRIL[2]) ** 2)
    dark = np.clip((1.0 - q) / 0.5, 0.0, 1.0)
    rim = 0.0006 * np.exp(-((q - 1.1) / 0.18) ** 2)
    under = np.clip((tip[1] - 0.002 - Y) / 0.002, 0.0, 1.0)  # the nasal base, not the tip
    # the columella fades into the lip at the subnasale (no step at the patch's lower edge)
    into_lip = np.clip((Y - sn[1] + 0.001) / 0.003, 0.0, 1.0) ** 2
    col = COLUMELLA[1] * np.exp(-(X / COLUMELLA[0]) ** 2) * under * into_lip
    h = np.maximum(np.maximum(ala, col), rim * under)
    return h, dark * under, groove * (ala < 0.3 * top)


def _skin_colour(points: np.ndarray, look: FaceLook, skin: Part) -> np.ndarray:
    """(m, 3) sRGB: the skin's colour at the foot points of ``points`` (its texture's texel,
    or its vertex albedo)."""
    t, w = closest_on_skin(points, look.rest, look.triangles)
    if skin.texture is None or skin.uv is None:
        return np.einsum("mk,mkj->mj", w, skin.albedo[look.triangles[t]])
    uv = np.einsum("mk,mkj->mj", w, skin.uv[t])
    h, wd = skin.texture.shape[:2]
    col = np.clip(uv[:, 0].astype(int), 0, wd - 1)
    row = np.clip(uv[:, 1].astype(int), 0, h - 1)
    return skin.texture[row, col, :3]
