"""Anatomical tissue geometry on the generic face: depth of the soft tissue, where its deep
surface slides, and how much of the jaw's rotation each part of the deep surface takes.

All three are fields over the frontal plane of the generic face (``x, y`` in mm, origin at the
nasion, as in :mod:`generic`); the builder carries them onto any face by the thin-plate-spline
warp between landmarks, so that they are the same on every mesh resolution and every scan.

Soft-tissue depth (skin to bone or teeth, mm). Verified anchors: the thinnest midline point is
the nasal bridge (rhinion, about 3 mm) and the thickest the base of the upper lip (subnasale,
15.6 +/- 2.4 mm), lateral cephalograms of 222 adults (Forensic Sci Int 2018,
doi:10.1016/j.forsciint.2018.10.021); Holdaway (1983, Am J Orthod 84:1) gives 14-16 mm at
A point. The other values are rounded adult means of the forensic soft-tissue depth tables
(Stephan & Simpson 2008, J Forensic Sci 53:1257, the "T-table"; De Greef et al. 2006, Forensic
Sci Int 159:S126) as we read them: forehead and brow 5-6 mm, nasion 6.5, lips 12-14, chin 11,
menton 7, over the zygoma 7, over the teeth in the buccal region 15-18, gonion 12. They set the
lip thickness front to back (13-14 mm at the vermilion), which the realism brief asks for
(10-15 mm).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RBFInterpolator

from .generic import MOUTH_HALF_WIDTH, Y_STOMION

# (|x|, y, depth) in mm on the generic face; mirrored to the other side
_DEPTH_CONTROL = np.array([
    # midline, top to bottom
    (0, 78, 5.5), (0, 45, 5.0), (0, 12, 5.5), (0, 0, 6.5), (0, -20, 3.0), (0, -35, 3.0),
    (0, -46, 4.0), (0, -52, 15.5), (0, -62, 14.0), (0, -70, 13.5), (0, -82, 14.0),
    (0, -94, 11.0), (0, -108, 11.0), (0, -122, 7.0), (0, -136, 7.0),
    # lips and the buccal region over the teeth
    (12, -64, 13.5), (12, -82, 13.5), (22, -73, 14.0), (32, -73, 16.0), (40, -62, 16.0),
    (40, -86, 15.0), (28, -96, 11.0), (14, -104, 10.5),
    # cheek bone, eyes, brows, temples
    (14, -48, 8.0), (24, -40, 10.0), (44, -40, 9.0), (52, -22, 7.0), (32, -3, 6.0),
    (30, 13, 5.5), (52, 30, 5.5), (56, 0, 6.0),
    # side of the face and the lower jaw
    (58, -60, 14.0), (55, -90, 12.0), (50, -100, 12.0), (36, -112, 8.0), (20, -122, 7.0),
    (56, -125, 7.0),
], float)

_depth_rbf = RBFInterpolator(
    np.concatenate([_DEPTH_CONTROL[:, :2], _DEPTH_CONTROL[_DEPTH_CONTROL[:, 0] > 0][:, :2]
                    * np.array([-1.0, 1.0])]),
    np.concatenate([_DEPTH_CONTROL[:, 2], _DEPTH_CONTROL[_DEPTH_CONTROL[:, 0] > 0][:, 2]]),
    kernel="thin_plate_spline", smoothing=2.0, degree=1,
)

DEPTH_RANGE_MM = (3.0, 18.0)


def tissue_depth_mm(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Soft-tissue depth (mm) from skin to bone or teeth at generic frontal (x, y) mm."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    pts = np.column_stack([x.reshape(-1), y.reshape(-1)])
    d = _depth_rbf(pts).reshape(x.shape)
    return np.clip(d, *DEPTH_RANGE_MM)


def lip_ellipse(x: np.ndarray, y: np.ndarray, *, half_width: float = 1.2 * MOUTH_HALF_WIDTH,
                up: float = 19.0, down: float = 17.0) -> np.ndarray:
    """Inside the lips (bool): from the upper to the lower labial sulcus, corner to corner.

    Generic mm; the deep surface of this region is the labial mucosa, which rests on the teeth
    and the alveolar bone and slides on them (the vestibule is about 15-20 mm deep).
    """
    dy = np.asarray(y, float) - Y_STOMION
    dy = np.where(dy > 0, dy / up, -dy / down)
    dx = np.asarray(x, float) / half_width
    return dx**2 + dy**2 < 1.0


def chin_pad(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Inside the chin pad (bool), generic mm: the soft tissue over the mental protuberance.

    Mentalis runs from the incisive fossa down into the chin skin; the pad of fat between them
    glides on the bone, so that mentalis raises the chin boss and pushes the lower lip forward.
    """
    return (np.asarray(x, float) / 17.0) ** 2 + ((np.asarray(y, float) + 105.0) / 13.0) ** 2 < 1


def vestibule(x: np.ndarray, y: np.ndarray, *, half_width: float = 44.0,
              half_height: float = 16.0) -> np.ndarray:
    """Inside the buccal vestibule (bool), generic mm: the cheeks' inner surface (buccal mucosa
    over buccinator) lies on the teeth and gums from the mouth corner back to the molars and
    about 15 mm above and below the occlusal plane; the modiolus slides on it."""
    return (np.asarray(x, float) / half_width) ** 2 + (
        (np.asarray(y, float) - Y_STOMION) / half_height) ** 2 < 1.0


def sliding_region(x: np.ndarray, y: np.ndarray, *, buccal: bool = False) -> np.ndarray:
    """Where the deep surface slides on bone and teeth: lips and chin pad (and, with
    ``buccal``, the buccal vestibule)."""
    out = lip_ellipse(x, y) | chin_pad(x, y)
    return out | vestibule(x, y) if buccal else out


#: how much more firmly the deep surface is held at the edge of a sliding region than inside it
EDGE_TETHER = 30.0


def tether_weight(x: np.ndarray, y: np.ndarray, *, free_mm: float = 7.0,
                  ramp_mm: float = 9.0) -> np.ndarray:
    """How firmly the sliding deep surface is held to the bone at generic (x, y) mm (a factor
    on the preset's tether stiffness).

    The labial mucosa is attached to the alveolar bone at the fold of the vestibule (the sulcus)
    and free over the teeth; the chin pad is held by the fibres of mentalis and the mandibular
    ligament. The weight is 0 within ``free_mm`` of the lip line between the corners and rises
    smoothly to 1 over ``ramp_mm`` beyond; towards the edge of each sliding region (the outer
    third of its normalised radius) it rises smoothly on to :data:`EDGE_TETHER`, so that the
    deep surface passes from free to fixed without a step (a step creases the skin above it).
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    dy = np.abs(y - Y_STOMION)
    dx = np.maximum(np.abs(x) - MOUTH_HALF_WIDTH, 0.0)
    dist = np.hypot(dx, dy)
    inner = _smoothstep((dist - free_mm) / ramp_mm)
    up = np.where(y > Y_STOMION, 19.0, 17.0)
    rho_lips = np.hypot(x / (1.2 * MOUTH_HALF_WIDTH), (y - Y_STOMION) / up)
    rho_chin = np.hypot(x / 17.0, (y + 105.0) / 13.0)
    rho_vest = np.hypot(x / 44.0, (y - Y_STOMION) / 16.0)
    rho = np.minimum(np.where(lip_ellipse(x, y), rho_lips, rho_chin), 1.0)
    rho = np.where(vestibule(x, y) & ~lip_ellipse(x, y), rho_vest, rho)
    edge = _smoothstep((rho - 0.67) / 0.33)
    return np.maximum(inner, EDGE_TETHER * edge)


#: generic (|x|, y) mm of the jaw line lateral to the mouth corner: corner -> jaw angle
_JAW_LINE = np.array([(MOUTH_HALF_WIDTH, Y_STOMION), (50.0, -100.0), (70.0, -100.0)])


def jaw_line_y(x: np.ndarray) -> np.ndarray:
    """Height (mm) of the line from each mouth corner to the jaw angle, then level to the ear."""
    ax = np.abs(np.asarray(x, float))
    return np.interp(ax, _JAW_LINE[:, 0], _JAW_LINE[:, 1])


def jaw_weight(x: np.ndarray, y: np.ndarray, lower_lip: np.ndarray, *,
               band_mm: float = 24.0, taper_mm: float = 15.0,
               corner_fraction: float = 0.35) -> np.ndarray:
    """Share of the jaw's rotation (0 to 1) that the deep surface takes at generic (x, y) mm.

    Between the mouth corners the lip line separates the upper teeth (0) from the lower teeth
    (1): ``lower_lip`` says on which side a node lies. Lateral to the corners the weight falls
    smoothly (a cubic smoothstep) across a band centred on the line from the corner to the jaw
    angle; the band widens from ``corner_fraction`` of ``band_mm`` at the corner to ``band_mm``
    over ``taper_mm``, so that opening the jaw bends the skin of the cheek gently instead of
    creasing it along the line, next to the mouth corner included.
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    ax = np.abs(x)
    between = ax < MOUTH_HALF_WIDTH - 1e-3  # the corner column itself takes the band (mm)
    width = band_mm * np.clip((ax - MOUTH_HALF_WIDTH) / taper_mm, corner_fraction, 1.0)
    u = (jaw_line_y(x) - y) / width + 0.5
    return np.where(between, np.asarray(lower_lip, float), _smoothstep(u))


def _smoothstep(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)
