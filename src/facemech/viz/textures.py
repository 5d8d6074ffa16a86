"""Procedural textures of the face's render-only parts, drawn from its landmarks (sRGB, RGBA).

* the skin of a face without its own texture: skin tone, cheek colour, lip vermilion, brows
  (hair-like strokes), upper-lid lashes and crease, and the palpebral fissures cut out
  (alpha 0);
* the front of an eyeball: sclera, iris, limbus and pupil;
* a dental arch: crowns with their interproximal lines and a scalloped gum line.

Dimensions are those of an adult (ANATOMY.md; Farkas' norms): palpebral fissure 28 mm long
and 10 mm high with the lateral canthus 2 mm above the medial, iris 11.8 mm across, pupil
4 mm; crown widths of the permanent teeth after Wheeler's tables (upper 8.5, 6.5, 7.5, 7, 6.5,
10 mm; lower 5, 5.5, 7, 7, 7, 11 mm from the midline).
"""

from __future__ import annotations

import numpy as np

SKIN = np.array([0.86, 0.66, 0.55])
CHEEK = np.array([0.85, 0.57, 0.50])
EAR = np.array([0.85, 0.63, 0.54])
VERMILION = np.array([0.72, 0.40, 0.40])
BROW = np.array([0.27, 0.19, 0.14])
HAIR = np.array([0.20, 0.14, 0.10])
LASH = np.array([0.12, 0.08, 0.07])
LID_CREASE = np.array([0.70, 0.52, 0.45])
SCLERA = np.array([0.90, 0.86, 0.82])  #: a little grey and pink, never white
SCLERA_CORNER = np.array([0.86, 0.66, 0.62])  #: the injected conjunctiva at the corners
IRIS = np.array([0.36, 0.25, 0.16])

SKIN_TEXEL = 2.5e-4  #: m per texel of the skin texture
FISSURE_HALF_LENGTH = 0.014  #: m


def _smooth(d: np.ndarray, width: float) -> np.ndarray:
    """0 outside, 1 inside, a linear ramp of ``width`` across the edge (d > 0 inside)."""
    return np.clip(0.5 + d / width, 0.0, 1.0)


def fissure_heights(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower lid margins above the canthal line (m) at s in [-1 medial, 1 lateral]."""
    s = np.clip(s, -1.0, 1.0)
    base = np.sqrt(np.clip(1.0 - s**2, 0.0, 1.0))
    upper = 0.0052 * base ** 0.9 * (1.0 - 0.18 * s)
    lower = -0.0038 * base ** 1.1 * (1.0 + 0.15 * s)
    return upper, lower


def eye_frame(x, y, eye, side):
    """Coordinates along the canthal line (s, -1 medial .. 1 lateral) and height above it (m)."""
    s = side * (x - eye[0]) / FISSURE_HALF_LENGTH
    tilt = 0.001 * np.clip(s, -1.5, 1.5)  # the lateral canthus 2 mm above the medial
    return s, y - eye[1] + 0.0005 - tilt


def eye_mask(x: np.ndarray, y: np.ndarray, eye: np.ndarray, side: int) -> np.ndarray:
    """Signed distance-like depth inside the palpebral fissure (m; > 0 inside)."""
    s, h = eye_frame(x, y, eye, side)
    up, lo = fissure_heights(s)
    inside = np.minimum(up - h, h - lo)
    return np.where(np.abs(s) < 1.0, inside, -np.abs(s) + 1.0 - 1e-3)


def _lip_frame(x, y, lm):
    cr, cl = lm["mouth_corner_right"][:2], lm["mouth_corner_left"][:2]
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))[:2]
    axis = (cl - cr) / np.linalg.norm(cl - cr)
    half = 0.5 * np.linalg.norm(cl - cr)
    rx, ry = x - st[0], y - st[1]
    t = (rx * axis[0] + ry * axis[1]) / half
    up = -rx * axis[1] + ry * axis[0]
    return t, up, st


def vermilion_mask(x: np.ndarray, y: np.ndarray, lm: dict) -> np.ndarray:
    """Coverage (0..1) of the lip vermilion at frontal points (x, y) m, from the landmarks."""
    t, h, st = _lip_frame(x, y, lm)
    hu = lm["upper_lip_center"][1] - st[1]
    hl = st[1] - lm["lower_lip_center"][1]
    a = np.clip(np.abs(t), 0.0, 1.0)
    bow = 1.0 - 0.10 * np.exp(-(a / 0.09) ** 2) + 0.07 * np.exp(-((a - 0.22) / 0.09) ** 2)
    upper = hu * np.clip(1.0 - a ** 2.4, 0.0, 1.0) ** 0.85 * bow
    lower = hl * np.clip(1.0 - a ** 2.0, 0.0, 1.0) ** 0.7
    d = np.minimum(upper - h, h + lower)
    d = np.where(np.abs(t) < 1.0, d, -1.0)
    return _smooth(d, 1.1e-3)  # a soft border: the vermilion fades into the skin over 1 mm


def skin_texture(landmarks: dict, bounds: tuple[float, float, float, float], hair=None,
                 edge_fade=None):
    """The RGBA skin texture of a face without its own, and its texel mapping.

    Parameters
    ----------
    landmarks : name -> (3,) m rest positions (lip, eye and brow landmarks are used if present)
    bounds : (xmin, xmax, ymin, ymax) m of the frontal region the texture covers
    hair : optional function (x, y) -> hair coverage in [0, 1] (scalp hair over the forehead)
    edge_fade : optional function (x, y) -> weight in [0, 1] of the mottle and cheek colour
        (0 where the skin must be plain skin tone: at its edge, where a plain head goes on)

    Returns
    -------
    image : (h, w, 4) float sRGB + alpha in [0, 1]; alpha 0 inside the eye fissures
    origin : (x0, y0) m of the texel (0, 0) corner; texel (u, v) = ((x - x0), (y0 - y)) / SKIN_TEXEL
    """
    x0, x1, y0, y1 = bounds
    w = int(np.ceil((x1 - x0) / SKIN_TEXEL)) + 2
    h = int(np.ceil((y1 - y0) / SKIN_TEXEL)) + 2
    xs = x0 + (np.arange(w) + 0.5) * SKIN_TEXEL
    ys = y1 - (np.arange(h) + 0.5) * SKIN_TEXEL
    x, y = np.meshgrid(xs, ys)
    rgb = np.broadcast_to(SKIN, (h, w, 3)).copy()
    alpha = np.ones((h, w))
    rng = np.random.default_rng(7)
    # pores and mottling, fading out towards the sides, where the frontal mapping stretches
    fade = np.clip(1.0 - (np.abs(x - 0.5 * (x0 + x1)) - 0.04) / 0.015, 0.0, 1.0)
    rgb *= 1.0 + 0.018 * (fade * rng.standard_normal((h, w)))[..., None]
    rgb *= (1.0 - 0.07 * fade * _pores(h, w, rng))[..., None]
    # blood under the skin: redder round the nose's tip and alae and on the chin
    for name, sx, sy, k in (("nose_tip", 0.012, 0.010, 0.35), ("subnasale", 0.016, 0.006, 0.25),
                            ("chin", 0.014, 0.010, 0.22)):
        if name in landmarks:
            c = landmarks[name]
            g = k * np.exp(-0.5 * (((x - c[0]) / sx) ** 2 + ((y - c[1]) / sy) ** 2))
            rgb += g[..., None] * (CHEEK - SKIN)
    for name in ("cheek_left", "cheek_right"):
        if name in landmarks:
            c = landmarks[name]
            k = 0.55 * np.exp(-0.5 * (((x - c[0]) / 0.016) ** 2 + ((y - c[1]) / 0.013) ** 2))
            rgb += k[..., None] * (CHEEK - SKIN)
    if edge_fade is not None:
        rgb = SKIN + (rgb - SKIN) * edge_fade(x, y)[..., None]
    if all(k in landmarks for k in ("mouth_corner_left", "mouth_corner_right",
                                    "upper_lip_center", "lower_lip_center")):
        m = vermilion_mask(x, y, landmarks)[..., None]
        rgb = rgb * (1 - m) + m * VERMILION * (1.0 + 0.03 * rng.standard_normal((h, w, 1)))
        _, hl, _ = _lip_frame(x, y, landmarks)  # the line where the lips meet, a shade
        # darker (not dark: sealed lips showed a black hairline)
        rgb *= (1.0 - 0.10 * m * np.exp(-0.5 * (hl / 3.0e-4) ** 2)[..., None])
    hairs = _brow_hairs(h, w, rng)
    for side, eye_name, brow_name in ((1, "eye_left", "brow_left"),
                                      (-1, "eye_right", "brow_right")):
        if brow_name in landmarks:
            b = landmarks[brow_name]
            s = (side * (x - b[0]) - 0.001) / 0.018  # -1 medial head .. 1 lateral tail
            centre = b[1] + 0.0012 - 0.0035 * (s - 0.2) ** 2
            half = 0.0024 * (1.0 - 0.5 * (s + 1) / 2)
            d = np.minimum(half - np.abs(y - centre), 0.004 * (1.0 - np.abs(s)))
            m = (_smooth(d + 4e-4 * hairs, 6e-4) * np.clip(0.75 + 0.45 * hairs, 0, 1))
            m = m[..., None] * 0.95
            rgb = rgb * (1 - m) + m * BROW
        if eye_name in landmarks:
            e = landmarks[eye_name]
            s, hh = eye_frame(x, y, e, side)
            up, lo = fissure_heights(s)
            inside = np.abs(s) < 1.0
            crease = np.exp(-0.5 * ((hh - up - 0.0035) / 0.0009) ** 2) * np.clip(
                1.0 - s**2, 0, 1)
            rgb += (0.45 * crease)[..., None] * (LID_CREASE - SKIN)
            # the lash lines ramp over a texel and the cut over two (no staircase of
            # texels): the cut's alpha crosses one half on the margin, and the bilinear alpha
            # test (:mod:`.raster`) follows that contour between the texels
            along = np.clip(1.0 - s**2, 0.0, 1.0) > 0.0
            lash = along * np.minimum(_smooth(hh - up + 1e-4, SKIN_TEXEL),
                                      _smooth(up + 0.0007 * (1 - 0.5 * s**2) - hh, SKIN_TEXEL))
            lower_lash = 0.5 * along * np.minimum(_smooth(lo + 1e-4 - hh, SKIN_TEXEL),
                                                  _smooth(hh - lo + 0.00025, SKIN_TEXEL))
            rgb += (lash + lower_lash)[..., None] * (LASH - rgb)
            cut = np.where(inside, np.minimum(up - hh, hh - lo), -1.0)
            alpha = np.minimum(alpha, np.clip(0.5 - cut / (2 * SKIN_TEXEL), 0.0, 1.0))
    if hair is not None:
        m = hair(x, y)[..., None]
        rgb = rgb * (1 - m) + m * HAIR * (0.85 + 0.3 * rng.random((h, w, 1)))
    image = np.concatenate([np.clip(rgb, 0, 1), alpha[..., None]], axis=-1)
    return image, (x0, y1)


def _pores(h: int, w: int, rng) -> np.ndarray:
    """0..1: sparse pores (about 0.2 mm, one in 25 texels) over a faint blotchy variation
    (about 3 mm), the fine grain of skin at 720p and up."""
    from scipy import ndimage

    pores = ndimage.gaussian_filter((rng.random((h, w)) < 0.04).astype(float), 0.6)
    blotch = ndimage.gaussian_filter(rng.standard_normal((h, w)), 6.0)
    blotch = 0.5 + 0.5 * np.tanh(blotch / (blotch.std() + 1e-12))
    return np.clip(pores / (pores.max() + 1e-12) + 0.3 * blotch, 0.0, 1.0)


def _brow_hairs(h: int, w: int, rng) -> np.ndarray:
    """Unit-variance noise (h, w) drawn out into hairs: 1.5 mm along x, 0.15 mm across, at the
    skin texture's texel (:data:`SKIN_TEXEL`); the brows are these strokes, not a smooth
    band, and their edges break up along them."""
    from scipy.ndimage import gaussian_filter

    n = gaussian_filter(rng.standard_normal((h, w)), (0.6, 6.0))
    return n / max(float(n.std()), 1e-12)


def _vessels(x: np.ndarray, y: np.ndarray, rng, count: int = 16) -> np.ndarray:
    """0..1: thin wavy conjunctival vessels running in from the nasal and temporal sides of
    the globe towards the limbus, fading out before it (m, at texel centres x, y)."""
    out = np.zeros(x.shape)
    r, ang = np.hypot(x, y), np.arctan2(y, np.abs(x))
    for _ in range(count):
        a0 = rng.uniform(-0.6, 0.6)
        wave = 0.06 * np.sin(r / 0.0011 + rng.uniform(0, 6.3))
        on = np.exp(-((ang - a0 - wave) * r / 6e-5) ** 2)  # about 0.1 mm wide
        side = (x > 0) if rng.random() < 0.5 else (x < 0)
        out = np.maximum(out, on * side * np.clip((r - 0.0068) / 0.003, 0.0, 1.0))
    return out


def iris_texture(n: int = 192, colour=IRIS) -> np.ndarray:
    """RGBA front of an eyeball over [-R, R]^2 (R = 12 mm), row 0 at the top; ``colour`` (3,)
    sRGB the iris's mean (its fibres 0.75-1.25 of it, its limbus darker)."""
    r_eye = 0.012
    c = (np.arange(n) + 0.5) / n * 2 * r_eye - r_eye
    x, y = np.meshgrid(c, -c)
    r = np.hypot(x, y)
    ang = np.arctan2(y, x)
    rng = np.random.default_rng(3)
    spokes = np.interp(ang, np.linspace(-np.pi, np.pi, 97), rng.random(97))
    rgb = np.broadcast_to(SCLERA, (n, n, 3)).copy()
    # redder towards the canthi (the conjunctiva's vessels show most there), with vessels
    corner = np.clip((np.abs(x) - 0.0065) / 0.005, 0.0, 1.0)[..., None] ** 1.5
    rgb += 0.7 * corner * (SCLERA_CORNER - SCLERA)
    rgb += 0.45 * _vessels(x, y, rng)[..., None] * (np.array([0.72, 0.30, 0.30]) - rgb)
    rgb *= (1.0 - 0.08 * np.clip(r / r_eye, 0, 1) ** 2)[..., None]
    iris = np.asarray(colour, float) * (0.75 + 0.5 * spokes[..., None])
    limbus = np.clip((r - 0.0052) / 0.0007, 0, 1)[..., None]
    iris = iris * (1 - 0.55 * limbus)
    m = _smooth(0.0059 - r, 2.5e-4)[..., None]
    rgb = rgb * (1 - m) + m * iris
    p = _smooth(0.0020 - r, 2.5e-4)[..., None]
    rgb = rgb * (1 - p) + p * np.array([0.02, 0.02, 0.02])
    return np.concatenate([np.clip(rgb, 0, 1), np.ones((n, n, 1))], axis=-1)

