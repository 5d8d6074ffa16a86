"""A machine lip-reader on rendered frames: a standard face tracker against the model.

A tracker trained on photos of real faces, knowing nothing of facemech, reads the mouth opening
off each rendered frame, compared with the simulated lip aperture. Trackers: dlib's HOG face
detector and 68-point shape predictor (iBUG 300-W, Kazemi & Sullivan 2014; the ``photo`` extra,
:class:`facemech.io.photo.DlibDetector`), or MediaPipe's face mesh (``tracker="mesh"``,
:mod:`facemech.io.face_mesh`, the ``lipreader`` extra).

- inner-lip distance: the mean vertical distance, px, from the upper inner lip's three middle
  points to the lower's (:data:`UPPER_INNER`, :data:`LOWER_INNER`: iBUG 62-64 against 68-66,
  counted from 1; the mesh's 82, 13, 312 against 87, 14, 317); NaN where no face is found;
- model aperture: the vertical distance (m) between the mouth slit's midline twins
  (:func:`facemech.analysis.describe.lip_facing_nodes`), 0 with the lips closed;
- agreement: Pearson's r over the frames where the face is found (:func:`compare`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["LOWER_INNER", "UPPER_INNER", "Agreement", "LipReading", "compare", "frontal_frames",
           "inner_lip_distance", "model_aperture", "read_lips"]

#: the upper inner lip's middle points, 0-based iBUG indices (62, 63, 64 counted from 1)
UPPER_INNER = (61, 62, 63)
#: the lower inner lip's points below them, in the same order (68, 67, 66 counted from 1)
LOWER_INNER = (67, 66, 65)
#: the fewest frames with a face that :func:`compare` computes a correlation from
MIN_FRAMES = 3


@dataclass(frozen=True)
class LipReading:
    """What the tracker read off a series of frames.

    Attributes
    ----------
    points : (T, 68, 2) or (T, 468, 2) float array
        The iBUG landmarks (dlib) or the face mesh's points per frame, pixels (x right, y down;
        pixel centres at integers + 0.5); NaN in frames without a face.
    distance : (T,) float array
        The inner-lip distance per frame, pixels (module doc); NaN without a face.
    """

    points: np.ndarray
    distance: np.ndarray

    @property
    def found(self) -> np.ndarray:
        """(T,) bool: the frames where a face was found."""
        return np.isfinite(self.distance)


@dataclass(frozen=True)
class Agreement:
    """The tracker's inner-lip distance against the model's lip aperture.

    Attributes
    ----------
    r : Pearson's correlation over the frames with a face (NaN with fewer than
        :data:`MIN_FRAMES` of them, or where either series is constant there)
    found : how many frames had a face
    frames : how many frames there were
    slope : the least-squares line's slope, pixels of inner-lip distance per metre of aperture
        (NaN where ``r`` is)
    intercept : that line's inner-lip distance at zero aperture, pixels
    """

    r: float
    found: int
    frames: int
    slope: float
    intercept: float

    @property
    def found_fraction(self) -> float:
        """The share of frames with a face, 0..1."""
        return self.found / self.frames if self.frames else 0.0

    def to_dict(self) -> dict:
        return {"r": self.r, "found": self.found, "frames": self.frames,
                "found_fraction": self.found_fraction, "slope_px_per_mm": self.slope * 1e-3,
                "intercept_px": self.intercept}


def inner_lip_distance(points: np.ndarray) -> np.ndarray:
    """The inner-lip distance of iBUG landmarks or of the face mesh's points.

    Parameters
    ----------
    points : (..., 68, 2) or (..., 468, 2) array, pixels (y down)

    Returns
    -------
    (...) array, pixels: the mean of lower minus upper y over the pairs of :data:`UPPER_INNER`
    and :data:`LOWER_INNER` (of the mesh's, :mod:`facemech.io.face_mesh`) (positive with the
    mouth open; NaN where the points are)
    """
    from ..io import face_mesh

    p = np.asarray(points, float)
    pairs = {68: (UPPER_INNER, LOWER_INNER),
             468: (face_mesh.UPPER_INNER, face_mesh.LOWER_INNER)}
    if p.ndim < 2 or p.shape[-1] != 2 or p.shape[-2] not in pairs:
        raise InputError(f"points of shape {p.shape}; expected (..., 68, 2) or (..., 468, 2) "
                         "image points", field="points")
    upper, lower = pairs[p.shape[-2]]
    return (p[..., list(lower), 1] - p[..., list(upper), 1]).mean(axis=-1)


def read_lips(frames: Iterable[np.ndarray], *, detector=None, upsample: int = 0,
              boxes: bool = False, tracker: str = "dlib") -> LipReading:
    """Run a face tracker on each frame: dlib's face detector and 68-point predictor, or
    MediaPipe's face mesh.

    Parameters
    ----------
    frames : iterable of (h, w, 3) uint8 RGB arrays (an alpha channel, (h, w, 4), is dropped)
    tracker : ``"dlib"`` (default) or ``"mesh"`` (:class:`facemech.io.face_mesh.
        FaceMeshTracker`, each frame's region from the previous frame's points; ``detector``,
        ``upsample`` and ``boxes`` are dlib's alone)
    detector : a :class:`facemech.io.photo.DlibDetector` to reuse (default: a new one)
    upsample : times the detector doubles each frame before it looks: 0 finds faces from about
        80 px across (the frontal face of a 360-pixel-high frame is about 190 px), 1 from
        about 40 px at about four times the cost
    boxes : each point the median of the predictor's from 45 boxes around the detector's
        (:meth:`~facemech.io.photo.DlibDetector.faces`, as ``face from-photo`` reads a photo);
        False (default): from the detector's box alone, as dlib's examples track a face

    Returns
    -------
    LipReading
        Where several faces are found in a frame, the widest is taken.

    Raises
    ------
    InputError
        dlib or its model is not installed (the ``photo`` extra), LiteRT or the mesh's model
        (the ``lipreader`` extra, ``python -m facemech.io.face_mesh``) for the mesh, a tracker
        of another name, or a frame is not an RGB image.
    """
    if tracker not in ("dlib", "mesh"):
        raise InputError(f"no tracker {tracker!r}; expected 'dlib' or 'mesh'", field="tracker")
    checked = (_rgb(k, frame) for k, frame in enumerate(frames))
    if tracker == "mesh":
        from ..io.face_mesh import FaceMeshTracker

        pts = FaceMeshTracker().points(checked)
        return LipReading(points=pts, distance=inner_lip_distance(pts))
    if detector is None:
        from ..io.photo import DlibDetector

        detector = DlibDetector()
    points = []
    for img in checked:
        faces = detector.faces(img, upsample=upsample, boxes=boxes)
        if faces:
            points.append(max(faces, key=lambda f: f.width).points)
        else:
            points.append(np.full((68, 2), np.nan))
    pts = np.array(points, float).reshape(-1, 68, 2)
    return LipReading(points=pts, distance=inner_lip_distance(pts))


def _rgb(k: int, frame) -> np.ndarray:
    """Frame ``k`` as a contiguous (h, w, 3) uint8 RGB array (an alpha channel dropped), or
    InputError."""
    img = np.asarray(frame)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or img.dtype != np.uint8:
        raise InputError(f"frame {k} of shape {img.shape} and type {img.dtype}; expected "
                         "(h, w, 3) uint8 RGB", field="frames")
    return np.ascontiguousarray(img[..., :3])


def compare(distance: np.ndarray, aperture: np.ndarray) -> Agreement:
    """Correlate the tracker's inner-lip distance with the model's lip aperture.

    Parameters
    ----------
    distance : (T,) inner-lip distance, pixels, NaN where no face was found
        (:attr:`LipReading.distance`)
    aperture : (T,) the model's lip aperture, m, finite (:func:`model_aperture`)

    Returns
    -------
    Agreement
        Pearson's r and the least-squares line over the frames with a finite distance, and
        how many they are.
    """
    d = np.asarray(distance, float)
    a = np.asarray(aperture, float)
    if d.ndim != 1 or a.shape != d.shape:
        raise InputError(f"a distance series of shape {d.shape} and an aperture series of "
                         f"shape {a.shape}; expected two (T,) series", field="aperture")
    if not np.all(np.isfinite(a)):
        raise InputError("the aperture series is not finite", field="aperture")
    ok = np.isfinite(d)
    n = int(ok.sum())
    r = slope = intercept = float("nan")
    if n >= MIN_FRAMES and np.ptp(d[ok]) > 0 and np.ptp(a[ok]) > 0:
        r = float(np.corrcoef(d[ok], a[ok])[0, 1])
        slope, intercept = (float(v) for v in np.polyfit(a[ok], d[ok], 1))
    return Agreement(r=r, found=n, frames=int(len(d)), slope=slope, intercept=intercept)


def model_aperture(ds) -> np.ndarray:
    """The model's lip aperture per frame of a results dataset.

    Parameters
    ----------
    ds : results dataset (:func:`facemech.io.results.read_results`, or ``Spoken.dataset``)

    Returns
    -------
    (T,) array, m: the upper midline twin's height minus the lower's (module doc), the
    measure of :func:`facemech.analysis.describe.describe`'s ``lip_aperture``
    """
    from .describe import lip_facing_nodes

    up, lo, _ = lip_facing_nodes(ds)
    pos = ds["positions"].transpose("time", "node", "axis").values
    return np.asarray(pos[:, up, 1] - pos[:, lo, 1], float)


def frontal_frames(ds, *, size: tuple[int, int] = (360, 640), supersample: int = 2,
                   motion=None) -> Iterator[np.ndarray]:
    """The frontal frames of a results dataset, as the movies draw them.

    Parameters
    ----------
    ds : results dataset (with ``positions`` and, where it has them, the jaw and tongue series)
    size : (height, width) pixels
    supersample : anti-aliasing samples per pixel along each axis (1-4)
    motion : blinks, gaze and head motion per frame (:class:`facemech.viz.render.FrameMotion`;
        None: at rest, with the results' tongue)

    Yields
    ------
    (h, w, 3) uint8 RGB array per frame
    """
    from ..viz.render import RenderOptions
    from ..viz.video import jaw_poses_of, motion_with_tongue, scene_of

    pos = ds["positions"].transpose("time", "node", "axis").values
    jaw = jaw_poses_of(ds)
    motion = motion_with_tongue(motion, ds)
    render = RenderOptions(view="frontal", size=size, supersample=supersample).renderer(
        scene_of(ds))
    for k in range(len(pos)):
        blink, gaze, head, tongue = (0.0, (0.0, 0.0), None, None) if motion is None else \
            motion.at(k)
        yield render(pos[k], 0.0 if jaw is None else jaw[k], blink, gaze, head, tongue)[..., :3]
