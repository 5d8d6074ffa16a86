"""How small a face the photo path can take: real portraits scaled down, their landmarks
against those found on the full-size photo.

Each portrait of tests/data/portraits (faces 90-300 px across) is reduced so that its face is
:data:`WIDTHS` px across, and :meth:`facemech.io.photo.DlibDetector.faces` finds its 68 points
there twice: with the enlargement of small faces (the default) and without (the predictor on the
photo as given). Each way's points, scaled back, are compared with the full-size photo's; the
error is in mm at the adult interpupillary distance (63.4 mm between the eye centres). Reported
per width: the worst of the inner points (brows, eyes, nose, lips: iBUG 17-67) and their median,
over the portraits. A face that is not found counts as missing.

``python benchmarks/photo_small_faces.py``  (needs the ``photo`` extra; about a minute)
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

PORTRAITS = Path(__file__).resolve().parents[1] / "tests" / "data" / "portraits"
#: face widths tried, px (the detector's box)
WIDTHS = (24, 30, 36, 40, 50, 60, 70, 80, 100, 120, 150)


def main() -> int:
    from PIL import Image

    from facemech import io as _io  # noqa: F401
    from facemech.io import photo
    from facemech.io.photo import DlibDetector, read_photo

    det = DlibDetector()
    rows = {w: {"enlarged": [], "as given": [], "missing": 0} for w in WIDTHS}
    for path in sorted(PORTRAITS.glob("*.jpg")):
        image = read_photo(path)
        ref = photo.one_per_face(det.faces(image))[0]
        ipd = np.linalg.norm(ref.points[36:42].mean(0) - ref.points[42:48].mean(0))
        for w in WIDTHS:
            k = w / ref.width
            if k >= 1.0:
                continue
            size = (int(round(image.shape[1] * k)), int(round(image.shape[0] * k)))
            small = np.asarray(Image.fromarray(image).resize(size, Image.LANCZOS))
            for way, below in (("enlarged", photo.UPSAMPLE_BELOW), ("as given", 0)):
                photo.UPSAMPLE_BELOW = below
                try:
                    found = photo.one_per_face(det.faces(small))
                finally:
                    photo.UPSAMPLE_BELOW = 150
                if not found:
                    rows[w]["missing"] += way == "enlarged"
                    continue
                err = np.linalg.norm(found[0].points / k - ref.points, axis=1)[17:] / ipd * 63.4
                rows[w][way].append((float(err.max()), float(np.median(err))))
    out = {}
    for w, r in rows.items():
        out[w] = {"missing": r["missing"]}
        for way in ("enlarged", "as given"):
            if r[way]:
                a = np.array(r[way])
                out[w][way] = {"worst_mm": round(float(a[:, 0].max()), 2),
                               "mean_worst_mm": round(float(a[:, 0].mean()), 2),
                               "median_mm": round(float(np.median(a[:, 1])), 2), "n": len(a)}
    for w, r in out.items():
        print(json.dumps({"width_px": w, **r}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
