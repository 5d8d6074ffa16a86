"""The hair colour of a portrait, measured above the forehead.

In the face's frame (the eye line across, ``s``; up from the brows' top, ``t``; both in units of
the jaw's width ``W``, iBUG 0-16), each column ``|s| <= 0.35`` is walked up from ``t = 0.1``:
the first three samples in a row that are far from the skin (CIE76 colour difference over
:data:`SKIN_DE` from the cheeks' median) start the hair, and the samples far from the skin in
the next :data:`BAND` W above that are hair. The hair colour is their median (CIELAB, back to
sRGB). Hair that starts right above the forehead is the hair, not the background, which is why
the band is short. Too few columns with a hairline under :data:`HIGHEST` (a bald head, a photo
cropped at the brows) give no colour: the renderer keeps its own.
"""

from __future__ import annotations

import numpy as np

#: CIE76 difference from the skin over which a sample is not skin
SKIN_DE = 20.0
#: the height of the band of hair above the hairline, a share of the jaw's width
BAND = 0.15
#: the highest hairline (a share of the jaw's width above the brows) taken as hair, not the top
#: of a bald head
HIGHEST = 0.65
#: the share of columns that must find a hairline under :data:`HIGHEST`
MIN_COLUMNS = 0.5

_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                 [0.0193, 0.1192, 0.9505]])
_WHITE = np.array([0.9505, 1.0, 1.089])  # D65


def hair_colour(photo: np.ndarray, points: np.ndarray) -> tuple[np.ndarray | None, str]:
    """The photo's hair colour, sRGB uint8 (3,), or None, and a phrase saying which.

    Parameters
    ----------
    photo : (h, w, 3) uint8 sRGB
    points : (68, 2) the face's iBUG landmarks, px (x right, y down)
    """
    pts = np.asarray(points, float)
    origin, across, up, width = _face_frame(pts)
    skin = np.median(np.concatenate([
        _sample(photo, origin, across, up, width, side * np.linspace(0.12, 0.25, 8),
                -np.linspace(0.3, 0.45, 8))[0].reshape(-1, 3) for side in (-1, 1)]), axis=0)
    s = np.linspace(-0.35, 0.35, 71)
    t = np.arange(0.1, 0.95, 0.005)
    rgb, inside = _sample(photo, origin, across, up, width, s, t)
    lab = _lab(rgb)
    far = (np.linalg.norm(lab - _lab(skin), axis=-1) > SKIN_DE) & inside
    band = int(round(BAND / 0.005))
    picks = []
    for j in range(len(s)):
        start = np.flatnonzero(np.convolve(far[:, j], np.ones(3), "valid") == 3)
        if len(start) and t[start[0]] <= HIGHEST:
            rows = np.arange(start[0], min(start[0] + band, len(t)))
            picks.append(lab[rows[far[rows, j]], j])
    if len(picks) < MIN_COLUMNS * len(s):
        return None, (f"no hair found above the forehead ({len(picks)} of {len(s)} columns): "
                      "the hair keeps the built-in colour")
    colour = _srgb8(np.median(np.concatenate(picks), axis=0))
    return colour, f"hair colour sRGB {tuple(int(c) for c in colour)} from the photo"


def _face_frame(pts: np.ndarray):
    """(origin px, across, up (unit image vectors), the jaw's width px): the origin over the
    jaw's midpoint at the brows' top, ``up`` perpendicular to the eye line."""
    a, b = pts[36:42].mean(axis=0), pts[42:48].mean(axis=0)
    across = (b - a) / np.linalg.norm(b - a)
    up = np.array([across[1], -across[0]])
    if up[1] > 0:
        up = -up
    mid = 0.5 * (pts[0] + pts[16])
    top = float((pts[17:27] - mid).dot(up).max())
    return mid + top * up, across, up, float(np.linalg.norm(pts[16] - pts[0]))


def _sample(photo, origin, across, up, width, s, t):
    """Nearest pixels (len(t), len(s), 3) at face-frame points, and whether each is in the
    photo."""
    S, T = np.meshgrid(np.asarray(s, float), np.asarray(t, float))
    xy = origin + (S[..., None] * across + T[..., None] * up) * width
    h, w = photo.shape[:2]
    x, y = np.floor(xy[..., 0]).astype(int), np.floor(xy[..., 1]).astype(int)
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    return photo[np.clip(y, 0, h - 1), np.clip(x, 0, w - 1), :3], inside


def _lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (..., 3) of sRGB (..., 3) in 0-255 (D65)."""
    c = np.asarray(rgb, float) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = lin @ _XYZ.T / _WHITE
    d = 6.0 / 29.0
    f = np.where(xyz > d ** 3, np.cbrt(xyz), xyz / (3 * d * d) + 4.0 / 29.0)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def _srgb8(lab: np.ndarray) -> np.ndarray:
    """sRGB uint8 (3,) of a CIELAB colour (D65), clipped to the gamut."""
    fy = (lab[0] + 16) / 116
    f = np.array([fy + lab[1] / 500, fy, fy - lab[2] / 200])
    d = 6.0 / 29.0
    xyz = np.where(f > d, f ** 3, 3 * d * d * (f - 4.0 / 29.0)) * _WHITE
    lin = np.clip(np.linalg.solve(_XYZ, xyz), 0.0, 1.0)
    c = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    return np.round(255 * c).astype(np.uint8)
