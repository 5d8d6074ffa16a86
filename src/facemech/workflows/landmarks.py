"""``facemech face landmarks``: landmarks placed on a scan from its geometry alone
(:mod:`facemech.geometry.auto_landmarks`), written as the landmark CSV ``face build`` reads,
with a confidence column and a picture to check them by eye."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path, check_output
from .outcome import Written

__all__ = ["landmarks_file"]


def landmarks_file(surface: str | Path, output: str | Path, *, units: str = "mm",
                   picture: str | Path | None = None) -> Written:
    """Place landmarks on a scan and write them.

    Parameters
    ----------
    surface : OBJ, PLY or STL of a face (any orientation)
    output : landmark CSV ``name,x,y,z,confidence`` in ``units``, the scan's coordinates
    units : length unit of the scan (and of the CSV)
    picture : PNG of the scan with its landmarks (default: ``output`` with ``.png``)

    Returns
    -------
    Written : ``data`` the :class:`~facemech.geometry.auto_landmarks.AutoLandmarks`
    """
    from ..geometry.auto_landmarks import auto_landmarks
    from ..geometry.surface_io import read_surface_with_appearance
    from ..plausibility import check_face_size
    from ..units import length_scale

    surface, output = Path(surface), Path(output)
    picture = Path(picture) if picture is not None else output.with_suffix(".png")
    check_output(output, [surface], field="-o")
    check_output(picture, [surface, output], field="picture")
    v, f, _ = read_surface_with_appearance(surface, units=units)
    check_face_size(float(np.ptp(v, axis=0).max()), unit=units, source=str(surface))
    found = auto_landmarks(v, f, source=str(surface))
    scale = length_scale(units)
    with atomic_path(output) as tmp:
        tmp.write_text("name,x,y,z,confidence\n" + "".join(
            f"{n},{p[0] / scale:.4f},{p[1] / scale:.4f},{p[2] / scale:.4f},"
            f"{found.confidence[n]:.3f}\n" for n, p in found.positions.items()))
    from ..viz.subject import landmarks_figure

    landmarks_figure(picture, v, found.positions, found.confidence, found.generic_to_scan,
                     title=f"{surface.name}: landmarks from geometry (colour: confidence)")
    low = [n for n, c in found.confidence.items() if c < 0.5]
    return Written(output, found, f"{len(found.positions)} landmarks on {surface.name} (fit "
                   f"{found.rms * 1e3:.2f} mm RMS; low confidence: {', '.join(low) or 'none'})"
                   f" -> {output}, picture {picture}")
