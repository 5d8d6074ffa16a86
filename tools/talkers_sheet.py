"""Draw docs/img/talkers-sheet.jpg: the built-in head, a photo talker and a scan talker.

Issue 30's picture: three talkers say the same sentence (``facemech speak``, planned, blinks,
gaze and head motion off so that the views compare), each drawn in the frontal, three-quarter
and profile views at rest and at the sentence's widest lip opening.

- **built-in head**: the built-in face (``default``);
- **photo talker**: ``face from-photo`` on the frontal and profile renders of the test face of
  tests/viz/test_photo.py (the built-in face with a wider mouth, a longer lower face and a nose
  6 mm longer): dlib's landmarks, the IPD given;
- **scan talker**: the scan-like head of tests/scans.py (an irregular triangulation with a neck,
  ears and jaw angles that fold the tissue, reshaped wider and shorter) written as a scanner
  would: an OBJ in mm with a material, its texture image (the photo talker's baked skin, laid on
  the head by the same unrolled angle and height) and its 68 points in menpo's LJSON version 3,
  built through ``facemech face build`` as it comes.

No real photo or scan ships with facemech (none can be downloaded here), so both are
synthetic; a user's own go through the same commands.

Usage::

    PYTHONPATH=src:tests:tests/viz python tools/talkers_sheet.py [docs/img/talkers-sheet.jpg]
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

import test_photo as T  # tests/viz/test_photo.py: the photo's test face, its renders
from facemech.analysis.lipreader import model_aperture
from facemech.geometry import generic
from facemech.geometry.builder import build_face, default_surface, tissue_options
from facemech.geometry.ibug import generic_ibug68
from facemech.io.photo import DlibDetector, frontal_landmarks
from facemech.speech.alive import Liveliness
from facemech.viz.scene import build_scene, look_from_dataset
from facemech.viz.sheet import Block, contact_sheet
from facemech.viz.video import jaw_poses_of
from facemech.workflows.speak import speak
from scans import NECK_BOTTOM, _parameter_mesh, scan_head, write_head_scan

#: what each talker says
SENTENCE = "Bob bought a map of Maine."


def photo_talker(folder: Path) -> tuple[Path, np.ndarray]:
    """The photo talker's face file and its baked texture image."""
    v, f, lm = default_surface()
    lm = {k: T._variant(x) for k, x in lm.items()}
    # the anatomical tissue, whose depth under the lips sets the rendered teeth well behind them
    # (the tests' uniform tissue is thinner there, and the renderer's incisors show through the
    # closed lips of its photos)
    model = build_face(T._variant(v), f, lm, name="variant",
                       options=tissue_options("anatomical"))
    subject = T.Subject(model, lm, T._variant(generic_ibug68()))
    found = frontal_landmarks(subject.front, source="front", detector=DlibDetector())
    made = T._fit(subject, found.points, profile=True)
    path = folder / "photo.npz"
    made.model.save(path)
    return path, made.texture.appearance.image


def scan_talker(folder: Path, texture: np.ndarray) -> Path:
    """The scan talker: the scan-like head as OBJ (mm) + MTL + PNG + LJSON v3, built by
    ``facemech face build``."""
    _, f, _ = scan_head()
    # the head's sample points in (angle deg, height mm), as scan_head made them: their texture
    # coordinates are the photo texture's (photo_texture.grid_uv: the angle over the generic
    # grid's 86 degrees, the height from the throat to the hairline)
    pts, _ = _parameter_mesh(3.6, 4.5, 0, 15, NECK_BOTTOM)
    u = 0.5 + 0.5 * pts[:, 0] / 86.0
    w = (pts[:, 1] - generic.Y_BOTTOM) / (generic.Y_TOP - generic.Y_BOTTOM)
    uv = np.clip(np.column_stack([u, w]), 0.0, 1.0)[f]
    obj, ljson = write_head_scan(folder, uv=uv, texture=texture)
    out = folder / "scan.npz"
    subprocess.run([sys.executable, "-m", "facemech", "face", "build", str(obj), str(ljson),
                    "-o", str(out)], check=True)
    return out


def block(face, title: str, folder: Path) -> Block:
    """A talker's block: rest and the widest lip opening of the sentence."""
    out = folder / title.split()[0]
    ds = speak(out, SENTENCE, face=face, video=False, alive=Liveliness.off()).dataset
    gap = model_aperture(ds)
    k = int(np.argmax(gap))
    jaw = jaw_poses_of(ds)
    frames = [(ds.positions.values[i], 0.0 if jaw is None else jaw[i]) for i in (0, k)]
    labels = ["rest", f"t = {float(ds.time.values[k]):.2f} s, lips {1e3 * gap[k]:.0f} mm apart"]
    return Block(build_scene(look_from_dataset(ds)), frames, labels, title)


def main(path: str = "docs/img/talkers-sheet.jpg") -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        photo, texture = photo_talker(folder)
        scan = scan_talker(folder, texture)
        blocks = [block("default", "built-in head", folder),
                  block(photo, "photo talker (a render of a test face)", folder),
                  block(scan, "scan talker (a scan-like test head, OBJ + texture + LJSON v3)",
                        folder)]
        img = contact_sheet(blocks, panel=(300, 250))
    Image.fromarray(img).save(path, quality=88)
    print(f"wrote {path} ({img.shape[1]}x{img.shape[0]})")


if __name__ == "__main__":
    main(*sys.argv[1:])
