"""Photos of a face: read, checked, and the face's 68 iBUG landmarks found in them.

The landmarks come from dlib's face detector (histogram of oriented gradients) and its
68-point shape predictor trained on iBUG 300-W (Kazemi & Sullivan 2014), whose model file
ships in the ``face-recognition-models`` package: ``pip install facemech[photo]``; nothing is
downloaded at run time. Both are imported when first needed.

Detections that overlap are one face; a face smaller than :data:`UPSAMPLE_BELOW` is found
again in its region enlarged. A photo that cannot make a talker is refused with one line naming
the file: no face, more than one face, a face too small to place landmarks within a few
millimetres, a face turned away from the camera, or a profile given where the frontal photo
belongs (dlib's convolutional detector, also in the package, finds a face that the frontal
detector does not: a profile).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, missing_input

#: the smallest face the landmarks are taken from: the detector's box, pixels across, in the
#: photo as given (a smaller face is enlarged first, :data:`UPSAMPLE_BELOW`). Measured by
#: ``benchmarks/photo_small_faces.py`` on four real portraits scaled down, the inner points
#: (iBUG 17-67) against the full-size photo's, mm at a 63.4 mm IPD: from 40 px up the mean of
#: the worst 1.2-2.0 mm (as at 150 px), at 30 px 2.5 (worst 4.5), at 24 px three faces lost
MIN_FACE_PX = 40
#: a face under this many pixels across is found again in its region enlarged to
#: :data:`UPSAMPLE_TO` px across (Lanczos): the predictor places its points on the enlarged
#: face, as on a larger photo
UPSAMPLE_BELOW = 150
UPSAMPLE_TO = 260
#: two detections are one face when their boxes overlap by this share of the smaller box
OVERLAP = 0.3
#: a detection scoring under this share of the best one's is not counted as another face
#: (a weak detection on a badge or a pattern beside a clear face)
RIVAL_SHARE = 0.5
#: the most a frontal face may be turned (yaw, from the nose between the eyes), degrees
MAX_YAW_DEG = 20.0
#: images over this many pixels a side are reduced for detection (the landmarks are found on
#: the full image)
DETECT_SIDE = 1600
#: the frontal detector's score under which a detection is not taken as a face
MIN_SCORE = 0.0
#: the boxes the shape predictor starts from, around the detector's box: its size times each
#: factor, its centre moved by each shift (a share of its width) across and down; the points
#: are the median over them. The detector's box comes from an image pyramid, so where it lies
#: on a face changes with the image's size, and the predictor's points with it. Over nine
#: frontal renders of the built-in face (420-900 px wide, 0.7-2.5 m) the eye centres' distance,
#: which sets the whole face's scale, varied with a standard deviation of 3.1 % (range 10 %)
#: from the detector's box alone and 0.6 % (range 2 %) as the median over these 45 boxes; the
#: fit's worst landmark on twelve photos of two faces went from 1.3-5.2 mm (mean 3.55) to
#: 1.1-2.9 mm (mean 1.86) (``python benchmarks/photo_sizes.py``; docs/photo.md). The mean
#: instead of the median, or boxes within 5 % and 10 % of the detector's, did no better
BOX_SCALES = (0.85, 0.925, 1.0, 1.075, 1.15)
BOX_SHIFTS = (-0.08, 0.0, 0.08)


def read_photo(path: str | Path, *, field: str | None = None) -> np.ndarray:
    """The photo as (h, w, 3) uint8 sRGB, upright (its EXIF orientation applied).

    Raises
    ------
    InputError
        Not a file, not an image, or smaller than 64 pixels a side.
    """
    from PIL import Image, ImageOps, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise missing_input(path, field=field, what="photo")
    try:
        with Image.open(path) as im:
            im = ImageOps.exif_transpose(im)
            rgb = np.asarray(im.convert("RGB"))
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError) as exc:
        raise InputError(f"not an image that can be read ({type(exc).__name__})",
                         source=str(path), field=field) from None
    if min(rgb.shape[:2]) < 64:
        raise InputError(f"image of {rgb.shape[1]}x{rgb.shape[0]} pixels is too small for a "
                         f"face", source=str(path), field=field)
    return np.ascontiguousarray(rgb)


@dataclass(frozen=True)
class Detection:
    """A face found in a photo.

    Attributes
    ----------
    box : (left, top, right, bottom), pixels
    score : the detector's score
    points : (68, 2) iBUG landmarks, pixels (x right, y down; pixel centres at integers + 0.5)
    """

    box: tuple[int, int, int, int]
    score: float
    points: np.ndarray

    @property
    def width(self) -> int:
        return self.box[2] - self.box[0]


def _overlap(a: tuple, b: tuple) -> float:
    """The area two boxes (left, top, right, bottom) share, over the smaller box's area."""
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    if w <= 0 or h <= 0:
        return 0.0
    area = min((a[2] - a[0]) * (a[3] - a[1]), (b[2] - b[0]) * (b[3] - b[1]))
    return w * h / max(area, 1)


def one_per_face(found: list[Detection]) -> list[Detection]:
    """The detections with each group of overlapping ones (:data:`OVERLAP`) reduced to its
    best-scoring member, best first."""
    kept: list[Detection] = []
    for d in sorted(found, key=lambda d: -d.score):
        if all(_overlap(d.box, k.box) < OVERLAP for k in kept):
            kept.append(d)
    return kept


class DlibDetector:
    """dlib's frontal face detector and 68-point shape predictor (the ``photo`` extra)."""

    def __init__(self):
        try:
            import dlib
        except ImportError:
            dlib = None
        models = _models_folder()
        if dlib is None or models is None:
            raise InputError("finding a face in a photo needs dlib and its models: "
                             "pip install 'facemech[photo]'", field="photo") from None
        self._dlib = dlib
        self._models = models
        self._detector = dlib.get_frontal_face_detector()
        self._predictor = dlib.shape_predictor(str(models / PREDICTOR_FILE))
        self._cnn = None

    def faces(self, image: np.ndarray, *, upsample: int = 1,
              boxes: bool = True) -> list[Detection]:
        """Every frontal face in an RGB image, with its landmarks.

        ``upsample``: how many times the detector doubles the image before it looks (1 finds
        faces from about 40 px across; 0 from about 80 px, about four times faster).
        ``boxes``: the landmarks are the median of the predictor's from the boxes of
        :data:`BOX_SCALES` and :data:`BOX_SHIFTS` around the detector's (45 runs); False: from
        the detector's box alone, as dlib's examples do (the lip-reader's tracker).
        """
        small, k = _reduced(image, DETECT_SIDE)
        rects, scores, _ = self._detector.run(small, int(upsample), MIN_SCORE)
        out = []
        for r, s in zip(rects, scores, strict=True):
            box = self._dlib.rectangle(*(int(round(c * k)) for c in (r.left(), r.top(),
                                                                      r.right(), r.bottom())))
            out.append(self._landmarked(image, box, float(s), boxes))
        return out

    def _landmarked(self, image: np.ndarray, box, score: float, boxes: bool) -> Detection:
        """The detection of ``box`` with its points; a face under :data:`UPSAMPLE_BELOW` px
        is found again in its region enlarged, its points scaled back."""
        own = (box.left(), box.top(), box.right(), box.bottom())
        width = box.right() - box.left()
        if boxes and 0 < width < UPSAMPLE_BELOW:
            region = _enlarged_region(image, own, UPSAMPLE_TO / width)
            if region is not None:
                big, origin, k = region
                rects, _, _ = self._detector.run(big, 0, MIN_SCORE)
                if len(rects):
                    centre = np.array([0.5 * (own[0] + own[2]), 0.5 * (own[1] + own[3])])
                    near = min(rects, key=lambda r: np.hypot(
                        *(np.array([r.center().x, r.center().y]) / k + origin - centre)))
                    pts = np.median([self._points(big, b) for b in self._around(near)], axis=0)
                    return Detection(own, score, pts / k + origin)
        pts = self._points(image, box) if not boxes else np.median(
            [self._points(image, b) for b in self._around(box)], axis=0)
        return Detection(own, score, pts)

    def _points(self, image: np.ndarray, box) -> np.ndarray:
        """(68, 2) the predictor's points from one box, px (pixel centres at integers + 0.5)."""
        shape = self._predictor(image, box)
        return np.array([[p.x + 0.5, p.y + 0.5] for p in shape.parts()], float)

    def _around(self, box) -> list:
        """The boxes of :data:`BOX_SCALES` and :data:`BOX_SHIFTS` around ``box``."""
        w = box.right() - box.left()
        cx, cy = 0.5 * (box.left() + box.right()), 0.5 * (box.top() + box.bottom())
        out = []
        for s in BOX_SCALES:
            half = 0.5 * s * w
            for dx in BOX_SHIFTS:
                for dy in BOX_SHIFTS:
                    x, y = cx + dx * w, cy + dy * w
                    out.append(self._dlib.rectangle(*(int(round(c)) for c in (
                        x - half, y - half, x + half, y + half))))
        return out

    def any_face(self, image: np.ndarray) -> bool:
        """Whether the convolutional detector finds a face (in any pose, profiles too)."""
        if self._cnn is None:
            self._cnn = self._dlib.cnn_face_detection_model_v1(
                str(self._models / "mmod_human_face_detector.dat"))
        small, _ = _reduced(image, 480)
        return len(self._cnn(small, 0)) > 0


#: the 68-point shape predictor's file in ``face_recognition_models``' models folder
PREDICTOR_FILE = "shape_predictor_68_face_landmarks.dat"


def _models_folder() -> Path | None:
    """The models folder of the ``face_recognition_models`` package, found without importing
    it (its import loads ``pkg_resources``, slow to start); None when not installed."""
    from importlib.util import find_spec

    spec = find_spec("face_recognition_models")
    if spec is None or not spec.submodule_search_locations:
        return None
    folder = Path(next(iter(spec.submodule_search_locations))) / "models"
    return folder if (folder / PREDICTOR_FILE).is_file() else None


def _enlarged_region(image: np.ndarray, box: tuple, factor: float):
    """The region of ``box`` with a box's width around it, enlarged ``factor`` times (Lanczos):
    (image, (2,) its origin in the photo px, the factor); None for a factor under 1."""
    from PIL import Image

    if factor <= 1.0:
        return None
    h, w = image.shape[:2]
    bw = box[2] - box[0]
    x0, y0 = max(box[0] - bw, 0), max(box[1] - bw, 0)
    x1, y1 = min(box[2] + bw, w), min(box[3] + bw, h)
    crop = Image.fromarray(np.ascontiguousarray(image[y0:y1, x0:x1]))
    size = (int(round((x1 - x0) * factor)), int(round((y1 - y0) * factor)))
    big = np.asarray(crop.resize(size, Image.LANCZOS))
    return big, np.array([x0, y0], float), size[0] / (x1 - x0)


def _reduced(image: np.ndarray, side: int) -> tuple[np.ndarray, float]:
    """The image with its longer side at most ``side`` pixels, and the factor back."""
    h, w = image.shape[:2]
    k = max(h, w) / side
    if k <= 1:
        return np.ascontiguousarray(image), 1.0
    from PIL import Image

    size = (max(int(round(w / k)), 1), max(int(round(h / k)), 1))
    small = np.asarray(Image.fromarray(image).resize(size, Image.BILINEAR))
    return small, w / size[0]


def _nose_shift(points: np.ndarray) -> np.ndarray:
    """The nose line's shift (iBUG 27-30) from the outer eye corners' midpoint (36, 45), along
    the eye line, over half the corners' distance; points (..., 68, 2)."""
    p = np.asarray(points, float)
    a, b = p[..., 36, :], p[..., 45, :]
    axis = (b - a) / np.linalg.norm(b - a, axis=-1, keepdims=True)
    nose = p[..., 27:31, :].mean(axis=-2) - 0.5 * (a + b)
    return (nose * axis).sum(axis=-1) / (0.5 * np.linalg.norm(b - a, axis=-1))


def yaw_degrees(points: np.ndarray) -> float:
    """How far a face is turned from the camera, degrees (positive: to the subject's left).

    A face turned by ``a`` shifts its nose line (iBUG 27-30) from the outer eye corners'
    midpoint along the eye line; the shift, over half the corners' distance, is read against
    the generic face's iBUG points turned by -60 to 60 degrees (seen from far).

    Parameters
    ----------
    points : (68, 2) image points, px (x right, y down)
    """
    from ..geometry.ibug import generic_ibug68

    g = generic_ibug68()
    angles = np.linspace(-60.0, 60.0, 121)
    r = np.radians(angles)
    # the subject turned to its left by a: +z (forward) towards +x (its left), seen from +z;
    # its left is the image's right (x right) and +y up is the image's up (y down)
    x = g[:, 0][None] * np.cos(r)[:, None] + g[:, 2][None] * np.sin(r)[:, None]
    turned = np.stack([x, -np.broadcast_to(g[:, 1], x.shape)], axis=-1)
    shift = _nose_shift(turned)
    return float(np.interp(_nose_shift(points), shift, angles))


def frontal_landmarks(image: np.ndarray, *, source: str, field: str | None = None,
                      detector: DlibDetector | None = None) -> Detection:
    """The one frontal face of a photo, checked; its 68 landmarks.

    Raises
    ------
    InputError
        No face; a profile (a face only the any-pose detector finds, or turned more than
        :data:`MAX_YAW_DEG`); two faces or more (overlapping detections are one face, and
        one scoring under :data:`RIVAL_SHARE` of the best is none); a face under
        :data:`MIN_FACE_PX` across.
    """
    det = detector or DlibDetector()
    faces = one_per_face(det.faces(image))
    faces = [f for f in faces if f.score >= RIVAL_SHARE * faces[0].score] if faces else faces
    if not faces:
        if det.any_face(image):
            raise InputError("the face is in profile, not facing the camera: give a frontal "
                             "photo (a profile goes with --profile)", source=source, field=field)
        raise InputError("no face found", source=source, field=field)
    if len(faces) > 1:
        raise InputError(f"{len(faces)} faces found; crop the photo to one face", source=source,
                         field=field)
    face = faces[0]
    if face.width < MIN_FACE_PX:
        raise InputError(f"the face is {face.width} px across, under the {MIN_FACE_PX} px "
                         "needed to place its landmarks within a few millimetres (even "
                         "enlarged)", source=source, field=field)
    yaw = yaw_degrees(face.points)
    if abs(yaw) > MAX_YAW_DEG:
        raise InputError(f"the face is turned {abs(yaw):.0f} degrees from the camera (at most "
                         f"{MAX_YAW_DEG:.0f}): give a frontal photo (a profile goes with "
                         "--profile)", source=source, field=field)
    return face


def check_profile(image: np.ndarray, *, source: str, field: str = "--profile",
                  detector: DlibDetector | None = None) -> None:
    """Refuse a frontal photo given as the profile (the frontal detector finds a face looking
    within :data:`MAX_YAW_DEG` of the camera)."""
    det = detector or DlibDetector()
    for face in det.faces(image):
        if abs(yaw_degrees(face.points)) <= MAX_YAW_DEG:
            raise InputError("this is a frontal photo, not a profile", source=source,
                             field=field)
