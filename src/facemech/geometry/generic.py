"""The built-in generic adult face, made by facemech's own parametric sculpting.

The surface is swept from ear to ear: each horizontal row (constant height ``y``) is a
super-ellipse from one ear (``x = -W``) through the face midline to the other ear, and local
features (nose, lips, chin, eyes, brows, cheeks) are added along the depth axis. Every row is
monotone in ``x``, so the surface is a graph ``z(x, y)`` over the frontal plane; anatomical sites
are given by their frontal ``(x, y)`` and found on the surface by that graph.

Dimensions (mm) follow the North American adult norms of Farkas as gathered in ANATOMY.md, an
adult of mixed sex: mouth width (cheilion-cheilion) 50, lower face height (subnasale-menton) 70,
nasion-subnasale 52, subnasale-stomion 21, nose protrusion (subnasale-pronasale) about 20,
biocular width about 92, face width at the zygomatic arches about 136, mandible width (gonion)
about 100.  Origin: nasion (the node just below the top of the nose, as in the seeds' model);
+x the subject's left, +y up, +z forward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

# --- profile and width knots (mm), midline, without the local features --------------------------
_Y_KNOTS = np.array([78, 45, 15, 0, -30, -52, -73, -95, -110, -122, -128, -136], float)
_Z_BASE = np.array([-16, -5, 0, -3, -3, -2, -4, -7, -6, -16, -38, -62], float)
_W_KNOTS_Y = np.array([78, 40, 10, -20, -45, -73, -100, -115, -125, -136], float)
_W_KNOTS = np.array([57, 63, 66, 68, 66, 62, 55, 50, 46, 44], float)
Z_EAR = -85.0  #: mm, depth of the ear plane (tragion) behind the nasion
SUPERELLIPSE_N = 2.2  #: exponent of the row cross-section (2 = ellipse; larger = flatter front)

Y_TOP, Y_BOTTOM = 78.0, -136.0  #: mm, hairline and throat rows
Y_STOMION = -73.0  #: mm, the row on which the mouth slit lies
MOUTH_HALF_WIDTH = 25.0  #: mm, cheilion at x = +-25


def _gauss(u: np.ndarray, s: float) -> np.ndarray:
    return np.exp(-0.5 * (u / s) ** 2)


_z_base = PchipInterpolator(_Y_KNOTS[::-1], _Z_BASE[::-1])
_width = PchipInterpolator(_W_KNOTS_Y[::-1], _W_KNOTS[::-1])
# nose protrusion above the base (mm) and its half-width (mm) against height
_nose_height = PchipInterpolator(
    np.array([-56, -52, -47, -41, -36, -20, -6, 2]),
    np.array([0, 4, 14, 22, 20, 11, 3, 0]),
)
_nose_width = PchipInterpolator(np.array([-56, -48, -40, -25, -5, 2]),
                                np.array([14, 15, 10, 7, 6, 6]))
# lip protrusion (mm) against height: upper lip from subnasale to stomion, lower lip to the fold
_lip_height = PchipInterpolator(
    np.array([-95, -91, -83, -77, -73, -69, -63, -56, -50]),
    np.array([0, 2.5, 8.0, 6.5, 4.5, 6.0, 8.0, 4.5, 0]),
)


def midline_depth(y: np.ndarray) -> np.ndarray:
    """Depth of the base profile (mm) at heights ``y`` (mm), before local features."""
    return _z_base(np.clip(y, Y_BOTTOM, Y_TOP))


def features(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Local relief (mm along +z) added to the base surface at frontal coordinates (x, y) mm."""
    ax = np.abs(x)
    yn = np.clip(y, -56, 2)
    nose = np.where((y > -56) & (y < 2), _nose_height(yn), 0.0)
    nose = nose * np.exp(-0.5 * (x / (0.55 * _nose_width(yn))) ** 2)
    alae = 4.0 * _gauss(ax - 14.0, 4.5) * _gauss(y + 48.0, 4.0)
    yl = np.clip(y, -95, -50)
    lips = np.where((y > -95) & (y < -50), _lip_height(yl), 0.0)
    # the vermilion narrows away from the stomion, which rounds the lips towards the corners
    lip_half_width = np.clip(MOUTH_HALF_WIDTH - 0.55 * np.abs(y - Y_STOMION), 9.0, None)
    lips = lips / (1.0 + (ax / lip_half_width) ** 6)
    lips = lips - 2.0 * _gauss(ax - MOUTH_HALF_WIDTH, 3.0) * _gauss(y - Y_STOMION, 3.0)
    chin = 7.0 * _gauss(x, 17.0) * _gauss(y + 107.0, 8.0)
    eyes = -7.0 * _gauss(ax - 32.0, 11.0) * _gauss(y + 3.0, 7.0) + 3.0 * _gauss(
        ax - 32.0, 5.5
    ) * _gauss(y + 3.0, 4.5)
    brow_window = 1.0 / (1.0 + ((ax - 30.0) / 20.0) ** 6)
    brows = 3.0 * brow_window * _gauss(y - 12.0, 5.0)
    cheeks = 5.0 * _gauss(ax - 42.0, 15.0) * _gauss(y + 35.0, 15.0)
    return nose + alae + lips + chin + eyes + brows + cheeks


def _row_point(theta: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Base (x, z) of the super-ellipse row at angle theta (rad) and height y (mm)."""
    e = 2.0 / SUPERELLIPSE_N
    s, c = np.sin(theta), np.cos(theta)
    w = _width(np.clip(y, Y_BOTTOM, Y_TOP))
    depth = midline_depth(y) - Z_EAR
    x = w * np.sign(s) * np.abs(s) ** e
    z = Z_EAR + depth * np.abs(c) ** e
    return x, z


def surface_point(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Points (..., 3) mm of the generic surface at frontal coordinates (x, y) mm.

    ``|x|`` must be below the row's half-width (the ear); it is clipped just inside it.
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    w = _width(np.clip(y, Y_BOTTOM, Y_TOP))
    u = np.clip(x / w, -0.999, 0.999)
    e = 2.0 / SUPERELLIPSE_N
    s = np.sign(u) * np.abs(u) ** (1.0 / e)
    theta = np.arcsin(s)
    bx, bz = _row_point(theta, y)
    return np.stack([bx, y + 0 * bx, bz + features(bx, y)], axis=-1)


def _density_samples(lo: float, hi: float, n: int, density) -> np.ndarray:
    """n samples on [lo, hi] spaced by the inverse CDF of a density."""
    grid = np.linspace(lo, hi, 4001)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density(grid[1:]) + density(grid[:-1]))
                                           * np.diff(grid))])
    cdf /= cdf[-1]
    return np.interp(np.linspace(0.0, 1.0, n), cdf, grid)


@dataclass(frozen=True)
class GenericSurface:
    """The generic face surface.

    Attributes
    ----------
    vertices : (n, 3) float array, mm
    faces : (f, 3) int array, counter-clockwise seen from outside
    rows, cols : int
        Grid shape (the vertex of row r, column c is ``r * cols + c``).
    """

    vertices: np.ndarray
    faces: np.ndarray
    rows: int
    cols: int


def make_surface(rows: int = 48, cols: int = 41, theta_max_deg: float = 86.0) -> GenericSurface:
    """Sweep the generic face into a triangulated grid.

    Rows are denser around the mouth, columns denser around the midline, so that the perioral
    spacing is about 1.5-2 mm and the lateral spacing about 6 mm. One row lies exactly on the
    stomion (the mouth slit) and one column on the midline.
    """
    if cols % 2 == 0:
        cols += 1
    ys = _density_samples(
        Y_BOTTOM, Y_TOP, rows, lambda y: 1.0 + 2.6 * np.exp(-0.5 * ((y - Y_STOMION) / 16.0) ** 2)
    )[::-1]
    k = int(np.argmin(np.abs(ys - Y_STOMION)))
    ys[k] = Y_STOMION
    tmax = np.radians(theta_max_deg)
    half = _density_samples(0.0, tmax, cols // 2 + 1,
                            lambda t: 1.0 + 3.0 * np.exp(-0.5 * (t / 0.42) ** 2))
    thetas = np.concatenate([-half[:0:-1], half])
    th, yy = np.meshgrid(thetas, ys)
    bx, bz = _row_point(th, yy)
    z = bz + features(bx, yy)
    vertices = np.stack([bx, yy, z], axis=-1).reshape(-1, 3)
    faces = []
    for r in range(rows - 1):
        for c in range(cols - 1):
            a, b = r * cols + c, r * cols + c + 1
            d, e = (r + 1) * cols + c, (r + 1) * cols + c + 1
            # rows go downwards and columns to the subject's left: (a, d, b) faces +z
            # the shorter diagonal; a tie (cells symmetric about their own axis) is broken in
            # mirror image on the two sides, so that the face is symmetric to the last triangle
            diag_ae = np.linalg.norm(vertices[a] - vertices[e])
            diag_bd = np.linalg.norm(vertices[b] - vertices[d])
            tie = abs(diag_ae - diag_bd) <= 1e-9 * max(diag_ae, diag_bd)
            if (diag_ae < diag_bd and not tie) or (tie and 2 * c < cols - 1):
                faces += [(a, d, e), (a, e, b)]
            else:
                faces += [(a, d, b), (b, d, e)]
    return GenericSurface(vertices, np.asarray(faces, dtype=np.int64), rows, cols)


# Landmarks of the generic face, as frontal (x, y) mm; depth comes from the surface.
LANDMARK_XY: dict[str, tuple[float, float]] = {
    "nasion": (0.0, 0.0),
    "nose_tip": (0.0, -40.0),
    "subnasale": (0.0, -52.0),
    "upper_lip_center": (0.0, -64.0),
    "stomion": (0.0, Y_STOMION),
    "lower_lip_center": (0.0, -82.0),
    "mouth_corner_left": (MOUTH_HALF_WIDTH, Y_STOMION),
    "mouth_corner_right": (-MOUTH_HALF_WIDTH, Y_STOMION),
    "chin": (0.0, -108.0),
    "menton": (0.0, -122.0),
    "cheek_left": (45.0, -45.0),
    "cheek_right": (-45.0, -45.0),
    "jaw_angle_left": (50.0, -100.0),
    "jaw_angle_right": (-50.0, -100.0),
    "brow_left": (30.0, 13.0),
    "brow_right": (-30.0, 13.0),
    "eye_left": (32.0, -3.0),
    "eye_right": (-32.0, -3.0),
}


def landmarks() -> dict[str, np.ndarray]:
    """Named landmarks of the generic face, (3,) arrays in mm."""
    names = list(LANDMARK_XY)
    xy = np.array([LANDMARK_XY[n] for n in names])
    pts = surface_point(xy[:, 0], xy[:, 1])
    return {n: pts[i] for i, n in enumerate(names)}
