"""``facemech lipread``: a machine lip-reader on a result's frontal movie (docs/lipreader.md).

The results file's frontal frames are drawn as ``facemech render`` draws them (in memory, no
movie file), a standard face tracker reads the inner-lip distance off each
(:func:`facemech.analysis.lipreader.read_lips`: MediaPipe's face mesh or dlib's 68 points), and
that is correlated with the lip aperture the simulation computed
(:func:`~facemech.analysis.lipreader.compare`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

#: the trackers :func:`lipread` takes
TRACKERS = ("mesh", "dlib")


@dataclass(frozen=True)
class LipReadReport:
    """What :func:`lipread` measured.

    Attributes
    ----------
    source : the results file
    tracker : ``mesh`` or ``dlib``
    size : (width, height) of the frames, pixels
    time : (T,) s
    aperture : (T,) m, the model's lip aperture
    distance : (T,) px, the tracker's inner-lip distance (NaN without a face)
    agreement : :class:`facemech.analysis.lipreader.Agreement`
    output : the CSV written, or None
    """

    source: str
    tracker: str
    size: tuple[int, int]
    time: np.ndarray
    aperture: np.ndarray
    distance: np.ndarray
    agreement: object
    output: Path | None = None

    def to_dict(self) -> dict:
        return {"source": self.source, "tracker": self.tracker, "size": list(self.size),
                **self.agreement.to_dict(),
                "aperture_max_mm": float(np.max(self.aperture)) * 1e3,
                "output": None if self.output is None else str(self.output)}


def lipread(result: str | Path, *, tracker: str = "mesh", size: str = "640x360", aa: int = 2,
            output: str | Path | None = None, progress=None) -> LipReadReport:
    """Read the lips of a results file's frontal movie with a face tracker.

    Parameters
    ----------
    result : a results file (``.nc``: ``simulate``, ``speak``, ``invert``)
    tracker : ``"mesh"`` (MediaPipe's face mesh; the ``lipreader`` extra and its model,
        ``python -m facemech.io.face_mesh``) or ``"dlib"`` (the ``photo`` extra)
    size : the frames' ``WIDTHxHEIGHT``, pixels (the frontal camera frames the head by the
        height)
    aa : anti-aliasing samples per pixel along each axis (1-4)
    output : a CSV of the series per frame (``time_s, aperture_mm, inner_lip_px``), written
        through a temporary file; never the results file
    progress : callable(stage, done, total), or None

    Returns
    -------
    LipReadReport

    Raises
    ------
    InputError
        An unreadable results file, a tracker of another name, a bad size, a missing extra
        or model, an output that is an input.
    """
    from ..analysis.lipreader import compare, frontal_frames, model_aperture, read_lips
    from ..atomic import atomic_path, check_output
    from ..io.results import read_results
    from ..viz.camera import parse_size

    if tracker not in TRACKERS:
        raise InputError(f"no tracker {tracker!r}; expected one of {', '.join(TRACKERS)}",
                         field="--tracker")
    height, width = parse_size(size, field="--size")
    if output is not None:
        check_output(output, [result], field="-o")
    ds = read_results(result)
    n = int(ds.sizes["time"])

    def frames():  # drawn as they are read, one frame in memory at a time
        for k, frame in enumerate(frontal_frames(ds, size=(height, width), supersample=aa)):
            yield frame
            if progress is not None:
                progress("render and read", k + 1, n)

    reading = read_lips(frames(), tracker=tracker)
    aperture = model_aperture(ds)
    time = np.asarray(ds["time"].values, float)
    written = None
    if output is not None:
        written = Path(output)
        with atomic_path(written) as tmp:
            rows = np.column_stack([time, aperture * 1e3, reading.distance])
            np.savetxt(tmp, rows, delimiter=",", fmt="%.6g",
                       header="time_s,aperture_mm,inner_lip_px", comments="")
    return LipReadReport(str(result), tracker, (width, height), time, aperture,
                         reading.distance, compare(reading.distance, aperture), written)


def lines(result: str | Path, *, tracker: str = "mesh", size: str = "640x360", aa: int = 2,
          output: str | Path | None = None, as_json: bool = False,
          progress=None) -> list[str]:
    """What ``facemech lipread`` prints: :func:`lipread`, then :func:`report`."""
    return report(lipread(result, tracker=tracker, size=size, aa=aa, output=output,
                          progress=progress), as_json=as_json)


def report(rep: LipReadReport, *, as_json: bool = False) -> list[str]:
    """The lines ``facemech lipread`` prints."""
    if as_json:
        return [json.dumps(rep.to_dict())]
    a = rep.agreement
    name = {"mesh": "MediaPipe's face mesh", "dlib": "dlib's 68 points"}[rep.tracker]
    lines = [f"{rep.source}: {name} on the frontal movie, {rep.size[0]}x{rep.size[1]} px",
             f"  face found in {a.found} of {a.frames} frames",
             f"  Pearson r, inner-lip distance against the model's lip aperture: {a.r:.3f} "
             "(the pass line is 0.9)",
             f"  line: {a.slope * 1e-3:.2f} px per mm, {a.intercept:.1f} px at 0 mm; the "
             f"largest aperture {np.max(rep.aperture) * 1e3:.1f} mm"]
    if rep.output is not None:
        lines.append(f"  series -> {rep.output}")
    return lines
