"""MediaPipe's face mesh, a second standard face tracker: 468 points, run with LiteRT.

The model is the face-landmark network of MediaPipe's Face Mesh (Kartynnik et al. 2019,
"Real-time facial surface geometry from monocular video on mobile GPUs", CVPR workshop on
computer vision for augmented and virtual reality), the file
``mediapipe/modules/face_landmark/face_landmark.tflite`` of the ``mediapipe`` 0.10.21 wheel on
PyPI (Apache 2.0; later wheels ship no models). That wheel pins numpy below 2, so it is not
installed: :func:`install_model` downloads it with pip and keeps the model file alone, under
``<prefix>/share/facemech/`` (``python -m facemech.io.face_mesh``; ``make`` does it). The
network runs in LiteRT (``ai-edge-litert``, the ``lipreader`` extra), one thread.

Tracking follows MediaPipe's own graph for video: the first frame's region of interest is the
face detector's box (dlib's, :mod:`facemech.io.photo`) scaled by :data:`ROI_SCALE` to a square;
each later frame's is the square about the previous frame's landmarks, scaled the same, turned
by the line through the eyes' outer corners (mesh points 33 and 263), as MediaPipe derives it;
a frame whose face-presence score falls under :data:`PRESENCE_MIN` returns to the detector. The
square is resampled to the network's 192 x 192 input, RGB in [0, 1], and the 468 points
(x, y in the input's pixels) mapped back to the frame.
"""

from __future__ import annotations

import os
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

#: the mediapipe wheel whose model file is used
MEDIAPIPE_VERSION = "0.10.21"
#: the model's path inside that wheel
MODEL_MEMBER = "mediapipe/modules/face_landmark/face_landmark.tflite"
#: the model's file name where it is kept
MODEL_NAME = "face_landmark.tflite"
#: an environment variable naming the model file, tried first
MODEL_ENV = "FACEMECH_FACE_MESH_MODEL"
#: the network's input side, pixels
INPUT_SIZE = 192
#: the region of interest's side over the face box's longer side, and over the landmarks' extent
#: (MediaPipe's face landmark graph: 1.5)
ROI_SCALE = 1.5
#: the face-presence probability under which a frame has no face (MediaPipe's: 0.5)
PRESENCE_MIN = 0.5
#: the mesh points of the eyes' outer corners (subject's right, left): the region's turn
EYE_CORNERS = (33, 263)
#: the mesh's inner-lip points in the middle, upper and the lower below each (the midline 13 and
#: 14 and one either side)
UPPER_INNER = (82, 13, 312)
LOWER_INNER = (87, 14, 317)


def _kept_path() -> Path:
    return Path(sys.prefix) / "share" / "facemech" / MODEL_NAME


def model_path() -> Path:
    """The face-mesh model file: :data:`MODEL_ENV` if set, else the copy
    :func:`install_model` keeps under ``<prefix>/share/facemech``, else that of an installed
    ``mediapipe`` package.

    Raises
    ------
    InputError
        None of them exists (one line saying how to install it).
    """
    given = os.environ.get(MODEL_ENV)
    if given:
        if not Path(given).is_file():
            raise InputError(f"{MODEL_ENV}={given}: no such model file", field=MODEL_ENV)
        return Path(given)
    if _kept_path().is_file():
        return _kept_path()
    import importlib.util

    spec = importlib.util.find_spec("mediapipe")
    if spec is not None and spec.submodule_search_locations:
        for root in spec.submodule_search_locations:
            p = Path(root).parent / MODEL_MEMBER
            if p.is_file():
                return p
    raise InputError("the face-mesh model is not installed: run `python -m "
                     "facemech.io.face_mesh` (it downloads the mediapipe "
                     f"{MEDIAPIPE_VERSION} wheel with pip and keeps its model)", field="model")


def install_model(dest: Path | None = None) -> Path:
    """Download the mediapipe wheel (pip, no dependencies) and keep its face-landmark model.

    Parameters
    ----------
    dest : the file to write (default ``<prefix>/share/facemech/face_landmark.tflite``); written
        through a temporary file and renamed, so never half-written

    Returns
    -------
    The model file's path (unchanged when it is there already).
    """
    import subprocess

    dest = _kept_path() if dest is None else Path(dest)
    if dest.is_file():
        return dest
    dest.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "pip", "download", "-q", "--no-deps",
                        "--only-binary=:all:", "-d", tmp, f"mediapipe=={MEDIAPIPE_VERSION}"],
                       check=True)
        wheels = sorted(Path(tmp).glob("mediapipe-*.whl"))
        if not wheels:
            raise InputError(f"pip gave no mediapipe {MEDIAPIPE_VERSION} wheel", field="model")
        with zipfile.ZipFile(wheels[0]) as z:
            data = z.read(MODEL_MEMBER)
        part = dest.with_name(dest.name + ".part")
        part.write_bytes(data)
        part.replace(dest)
    return dest


@dataclass(frozen=True)
class Region:
    """A square region of interest in a frame: centre (x, y) px, side px, and ``angle`` rad, the
    angle of the square's x axis in the image (x right, y down: positive turns it towards +y,
    as the line through the eyes' outer corners of a face whose left eye is lower)."""

    centre: np.ndarray
    side: float
    angle: float

    def axes(self) -> np.ndarray:
        """(2, 2): the square's unit x and y axes in the image (columns)."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        return np.array([[c, -s], [s, c]])

    def to_image(self, p: np.ndarray) -> np.ndarray:
        """Input pixels (n, 2) of the network to frame pixels (n, 2)."""
        q = (np.asarray(p, float) / INPUT_SIZE - 0.5) * self.side
        return self.centre + q @ self.axes().T


def region_of_box(left: float, top: float, right: float, bottom: float) -> Region:
    """The region of a face detector's box: its centre, :data:`ROI_SCALE` times its longer
    side, not turned."""
    return Region(np.array([0.5 * (left + right), 0.5 * (top + bottom)]),
                  ROI_SCALE * max(right - left, bottom - top), 0.0)


def region_of_points(points: np.ndarray) -> Region:
    """The region of a frame's 468 mesh points (n, 2) px: turned by the eye line (from point 33
    to 263), the points' extent in that frame, its centre and :data:`ROI_SCALE` times its
    longer side (MediaPipe's landmarks-to-region)."""
    p = np.asarray(points, float)
    a, b = p[EYE_CORNERS[0]], p[EYE_CORNERS[1]]
    angle = float(np.arctan2(b[1] - a[1], b[0] - a[0]))
    reg = Region(np.zeros(2), 1.0, angle)
    local = p @ reg.axes()  # coordinates along the turned axes
    lo, hi = local.min(axis=0), local.max(axis=0)
    centre = reg.axes() @ (0.5 * (lo + hi))
    return Region(centre, ROI_SCALE * float(np.max(hi - lo)), angle)


def crop(frame: np.ndarray, reg: Region) -> np.ndarray:
    """The region of a frame (h, w, 3) uint8 resampled (bilinear) to the network's input,
    (:data:`INPUT_SIZE`, :data:`INPUT_SIZE`, 3) uint8: its pixel (u, v) is the frame's at
    ``reg.to_image`` of (u, v) + 0.5 (PIL's affine map takes output coordinates to input ones,
    pixel corners at integers)."""
    from PIL import Image

    k = reg.side / INPUT_SIZE
    ax = reg.axes() * k
    origin = reg.centre - ax @ np.array([0.5 * INPUT_SIZE, 0.5 * INPUT_SIZE])
    img = Image.fromarray(np.ascontiguousarray(frame)).transform(
        (INPUT_SIZE, INPUT_SIZE), Image.Transform.AFFINE,
        (ax[0, 0], ax[0, 1], origin[0], ax[1, 0], ax[1, 1], origin[1]),
        resample=Image.Resampling.BILINEAR)
    return np.asarray(img)


class FaceMeshTracker:
    """MediaPipe's face-landmark network on a sequence of frames (see the module doc).

    Parameters
    ----------
    model : the ``.tflite`` file (default: :func:`model_path`)
    track : each frame's region from the previous frame's points (MediaPipe's video mode);
        False: from the face detector's box in every frame

    Raises
    ------
    InputError
        LiteRT (the ``lipreader`` extra), dlib (the ``photo`` extra) or the model missing.
    """

    def __init__(self, model: str | Path | None = None, *, track: bool = True):
        try:
            from ai_edge_litert.interpreter import Interpreter
        except ImportError:
            raise InputError("the face mesh needs LiteRT: pip install 'facemech[lipreader]'",
                             field="tracker") from None
        try:
            import dlib
        except ImportError:
            raise InputError("the face mesh finds the face with dlib: pip install "
                             "'facemech[photo]'", field="tracker") from None
        path = model_path() if model is None else Path(model)
        self._net = Interpreter(model_path=str(path), num_threads=1)
        self._net.allocate_tensors()
        self._input = self._net.get_input_details()[0]["index"]
        outs = {int(np.prod(d["shape"])): d["index"] for d in self._net.get_output_details()}
        self._points, self._presence = outs[468 * 3], outs[1]
        self._detect = dlib.get_frontal_face_detector()
        self.track = bool(track)

    def _run(self, frame: np.ndarray, reg: Region) -> tuple[np.ndarray, float]:
        x = crop(frame, reg).astype(np.float32)[None] / 255.0
        self._net.set_tensor(self._input, x)
        self._net.invoke()
        pts = self._net.get_tensor(self._points).reshape(468, 3)[:, :2]
        logit = float(self._net.get_tensor(self._presence).reshape(-1)[0])
        return reg.to_image(pts), 1.0 / (1.0 + np.exp(-logit))

    def _detected(self, frame: np.ndarray) -> Region | None:
        boxes = self._detect(frame, 0)
        if len(boxes) == 0:
            return None
        b = max(boxes, key=lambda r: r.width())
        return region_of_box(b.left(), b.top(), b.right() + 1, b.bottom() + 1)

    def points(self, frames) -> np.ndarray:
        """The 468 points (T, 468, 2) px of each frame (x right, y down; NaN without a face).

        Frames are (h, w, 3) uint8 RGB arrays (:func:`facemech.analysis.lipreader.read_lips`
        checks them)."""
        out, reg = [], None
        for frame in frames:
            img = np.ascontiguousarray(frame)
            if reg is None or not self.track:
                reg = self._detected(img)
            pts, presence = (None, 0.0) if reg is None else self._run(img, reg)
            if pts is None or presence < PRESENCE_MIN:
                out.append(np.full((468, 2), np.nan))
                reg = None
                continue
            out.append(pts)
            reg = region_of_points(pts)
        return np.array(out, float).reshape(-1, 468, 2)


def main(argv=None) -> int:
    """``python -m facemech.io.face_mesh``: install the model (:func:`install_model`)."""
    path = install_model()
    print(f"face-mesh model: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
