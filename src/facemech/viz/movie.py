"""Movies of the shaded skin (frontal and profile side by side), H.264 MP4 at the frame rate.

Encoding uses the ffmpeg that ships with imageio-ffmpeg (``pip install 'facemech[video]'``);
an optional WAV is muxed in as AAC. Files are written atomically.
"""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_path
from .raster import render, view_rotation

VIEWS = ((0.0, 0.0), (90.0, 0.0))  #: (azimuth, elevation) degrees: frontal, right profile


def _ffmpeg() -> str:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InputError("writing MP4 needs imageio-ffmpeg (pip install 'facemech[video]')",
                         field="video") from None
    return imageio_ffmpeg.get_ffmpeg_exe()


def frame_image(vertices: np.ndarray, faces: np.ndarray, *, centre: np.ndarray, extent: float,
                size: tuple[int, int] = (480, 360)) -> np.ndarray:
    """One movie frame: frontal and profile views side by side, (h, 2w, 3) uint8."""
    panels = [render(vertices, faces, rotation=view_rotation(az, el), size=size, extent=extent,
                     centre=centre) for az, el in VIEWS]
    return np.concatenate(panels, axis=1)


def write_movie(
    path: str | Path,
    positions: np.ndarray,
    faces: np.ndarray,
    *,
    fps: float = 60.0,
    audio: str | Path | None = None,
    size: tuple[int, int] = (480, 360),
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Render node trajectories (frames, nodes, 3) to an H.264 MP4.

    Parameters
    ----------
    path : output .mp4
    positions : (frames, nodes, 3) array, any length unit
    faces : (f, 3) int array
    fps : frame rate of the movie (the simulation's 60 Hz)
    audio : optional WAV file muxed in (AAC); the movie is cut to the shorter of the two
    size : (height, width) of each of the two panels, even numbers
    """
    import imageio_ffmpeg

    exe = _ffmpeg()
    if audio is not None and not Path(audio).is_file():
        raise InputError("audio file not found", source=str(audio))
    rest = positions[0]
    centre = 0.5 * (rest.min(axis=0) + rest.max(axis=0))
    extent = 0.55 * np.ptp(rest[:, 1])
    h, w = size
    path = Path(path)
    with atomic_path(path, suffix=".mp4") as video:
        writer = imageio_ffmpeg.write_frames(
            str(video), (2 * w, h), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
            output_params=["-crf", "20"], macro_block_size=8, ffmpeg_log_level="error",
        )
        writer.send(None)
        try:
            for k in range(len(positions)):
                img = frame_image(positions[k], faces, centre=centre, extent=extent, size=size)
                writer.send(np.ascontiguousarray(img))
                if progress is not None:
                    progress(k + 1, len(positions))
        finally:
            writer.close()
        if audio is not None:
            muxed = video.with_name(video.stem + ".mux.mp4")
            try:
                cmd = [exe, "-y", "-loglevel", "error", "-i", str(video), "-i", str(audio),
                       "-c:v", "copy", "-c:a", "aac", "-shortest", str(muxed)]
                run = subprocess.run(cmd, capture_output=True, text=True)
                if run.returncode != 0:
                    last = (run.stderr.strip().splitlines() or ["unknown error"])[-1]
                    raise InputError(f"ffmpeg could not mux the audio: {last}",
                                     source=str(audio))
                muxed.replace(video)
            finally:
                muxed.unlink(missing_ok=True)
    return path


def write_snapshot(path: str | Path, vertices: np.ndarray, faces: np.ndarray,
                   size: tuple[int, int] = (480, 360)) -> Path:
    """A PNG of one configuration (frontal and profile)."""
    import matplotlib.image as mpimg

    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    img = frame_image(vertices, faces, centre=centre, extent=0.55 * np.ptp(vertices[:, 1]),
                      size=size)
    with atomic_path(path, suffix=".png") as tmp:
        mpimg.imsave(tmp, img)
    return Path(path)
