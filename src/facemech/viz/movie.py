"""Movies and frame sequences of the rendered face: H.264 MP4 at the frame rate, or PNG frames.

Encoding uses the ffmpeg that ships with imageio-ffmpeg (``pip install 'facemech[video]'``);
an optional WAV is muxed in as AAC. PNG frames keep an alpha channel, so a transparent
background (``background="transparent"``) gives frames ready to composite. Files are written
atomically; a frame folder is filled in a temporary folder and renamed into place.

Frames are drawn on ``workers`` threads (default: two where two cores are available), each
with its own renderer (:mod:`.frame_pool`), and written in order; the frames are the same
bytes as those drawn on one thread.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from collections.abc import Callable
from contextlib import closing
from pathlib import Path

import numpy as np

from ..atomic import atomic_path, pending_folder
from ..errors import InputError
from ..params import FRAME_RATE_HZ
from .frame_pool import check_workers, in_order
from .render import FrameMotion, RenderOptions
from .scene import Scene


def _ffmpeg() -> str:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InputError("writing MP4 needs imageio-ffmpeg (pip install 'facemech[video]')",
                         field="video") from None
    return imageio_ffmpeg.get_ffmpeg_exe()


def _check(positions: np.ndarray, jaw: np.ndarray | None, scene: Scene,
           source: str | None = None) -> np.ndarray:
    n = len(scene.look.rest)
    if positions.ndim != 3 or positions.shape[1:] != (n, 3):
        raise InputError(f"positions of shape {positions.shape} do not fit a face of {n} nodes",
                         source=source, field="positions")
    if not np.all(np.isfinite(positions)):
        bad = int(np.flatnonzero(~np.isfinite(positions).all(axis=(1, 2)))[0])
        raise InputError(f"positions are not finite (first at frame {bad})", source=source,
                         field="positions")
    if jaw is None:
        return np.zeros(len(positions))
    jaw = np.asarray(jaw, float)
    if jaw.shape not in ((len(positions),), (len(positions), 3)):
        raise InputError(f"jaw series of shape {jaw.shape} does not fit {len(positions)} frames "
                         "(angles (frames,) or poses (frames, 3))", source=source,
                         field="jaw_angle")
    if not np.all(np.isfinite(jaw)):
        raise InputError("jaw angles are not finite", source=source, field="jaw_angle")
    return jaw


def _poses(motion: FrameMotion | None, frames: int, source: str | None):
    """Per frame, the keywords the renderer takes besides skin and jaw."""
    if motion is None:
        return [{}] * frames
    if len(motion) != frames:
        raise InputError(f"the blink, gaze and head series have {len(motion)} frames, the "
                         f"positions {frames}", source=source, field="motion")
    return [dict(zip(("blink", "gaze", "head", "tongue"), motion.at(k), strict=True))
            for k in range(frames)]


def write_movie(
    path: str | Path,
    scene: Scene,
    positions: np.ndarray,
    jaw_angle: np.ndarray | None = None,
    *,
    fps: float = FRAME_RATE_HZ,
    audio: str | Path | None = None,
    options: RenderOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
    source: str | None = None,
    motion: FrameMotion | None = None,
    workers: int | None = None,
) -> Path:
    """Render skin trajectories to an H.264 MP4.

    Parameters
    ----------
    path : output .mp4
    scene : :func:`facemech.viz.scene.build_scene` of the face
    positions : (frames, nodes, 3) skin node positions, m
    jaw_angle : (frames,) rad or (frames, 3) poses (angle rad, shift_y m, shift_z m): moves the
        lower teeth and tongue (None: closed)
    fps : frame rate of the movie (the simulation's)
    audio : optional WAV muxed in (AAC); the movie is cut to the shorter of the two (the frames
        that the audio covers, the last one ending at or after it)
    options : view, size, background and anti-aliasing (default: frontal+profile, 1280x720)
    source : name of the input, for error messages
    motion : blinks, gaze, head pose and the tongue tip's pose per frame
        (:class:`.render.FrameMotion`; None: still eyes, open lids, the head and tongue at rest)
    progress : called with (frames done, frames) after each frame is written, in order
    workers : threads that draw the frames, each with its own renderer, whole number 1 to
        1024 (None: ``min(2, available cores)``; 1: the caller's thread only); the frames
        reach the encoder in order and are the same whatever the number
        (:mod:`.frame_pool`)
    """
    import imageio_ffmpeg

    exe = _ffmpeg()
    opt = options or RenderOptions()
    if opt.transparent:
        raise InputError("an MP4 has no transparency: write PNG frames (--frames DIR) for a "
                         "transparent background", field="background")
    if audio is not None and not Path(audio).is_file():
        raise InputError("audio file not found", source=str(audio))
    jaw = _check(positions, jaw_angle, scene, source)
    poses = _poses(motion, len(positions), source)
    frames = len(positions)
    seconds = None if audio is None else _wav_seconds(audio)
    if seconds is not None:  # the frames the audio covers: the last one ends at or after it
        frames = max(1, min(frames, int(np.ceil(seconds * fps - 1e-6))))
    h, w = opt.size
    path = Path(path)

    def draw(render, k: int) -> np.ndarray:
        return np.ascontiguousarray(render(positions[k], jaw[k], **poses[k])[..., :3])

    drawn = in_order(lambda: opt.renderer(scene), draw, frames, workers)
    with atomic_path(path, suffix=".mp4") as video:
        writer = imageio_ffmpeg.write_frames(
            str(video), (w, h), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
            output_params=["-crf", "18"], macro_block_size=2, ffmpeg_log_level="error",
        )
        writer.send(None)
        try:
            with closing(drawn):
                for k, rgb in enumerate(drawn):
                    writer.send(rgb)
                    if progress is not None:
                        progress(k + 1, frames)
        finally:
            writer.close()
        if audio is not None:
            _mux(exe, video, audio, None if seconds is None else frames / fps)
    return path


def _wav_seconds(audio) -> float | None:
    """s, the length of a WAV file (None: not a WAV that scipy reads; ffmpeg may)."""
    import warnings

    from scipy.io import wavfile

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)
            rate, data = wavfile.read(audio, mmap=True)
        return len(data) / float(rate)
    except Exception:  # noqa: BLE001 - any parser error: leave it to ffmpeg
        return None


def _mux(exe: str, video: Path, audio, seconds: float | None = None) -> None:
    muxed = video.with_name(video.stem + ".mux.mp4")
    with pending_folder(muxed):  # removed if the command is interrupted
        _mux_into(exe, video, audio, muxed, seconds)


def _mux_into(exe: str, video: Path, audio, muxed: Path, seconds: float | None = None) -> None:
    """Mux ``audio`` into ``video`` (copied): cut to ``seconds`` (the video's length, the
    audio's re-encoded exactly), or None: to the shorter stream (ffmpeg's ``-shortest``, which
    cuts a copied video where its packets happen to interleave: a frame or two early)."""
    cut = ["-shortest"] if seconds is None else ["-t", f"{seconds:.6f}"]
    try:
        # -nostdin and no standard input: ffmpeg would otherwise read (and swallow) the
        # caller's input, e.g. the next line of a `while read` loop in a shell script
        cmd = [exe, "-nostdin", "-y", "-loglevel", "error", "-i", str(video), "-i", str(audio),
               "-c:v", "copy", "-c:a", "aac", *cut, str(muxed)]
        run = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
        if run.returncode != 0:
            last = (run.stderr.strip().splitlines() or ["unknown error"])[-1]
            raise InputError(f"ffmpeg could not mux the audio: {last}", source=str(audio))
        muxed.replace(video)
    finally:
        muxed.unlink(missing_ok=True)


def write_frames(
    folder: str | Path,
    scene: Scene,
    positions: np.ndarray,
    jaw_angle: np.ndarray | None = None,
    *,
    options: RenderOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
    source: str | None = None,
    motion: FrameMotion | None = None,
    workers: int | None = None,
) -> Path:
    """Render every frame to ``folder/frame_00000.png`` ... (RGBA PNG).

    The folder must not exist or be empty; it appears complete or not at all. ``motion``:
    blinks, gaze and head pose per frame, ``progress`` and ``workers`` as :func:`write_movie`
    (each thread draws and writes its frames; ``progress`` reports them in order).
    """
    import matplotlib.image as mpimg

    folder = Path(folder)
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise InputError("the frame folder exists and is not empty", source=str(folder),
                         field="frames")
    jaw = _check(positions, jaw_angle, scene, source)
    poses = _poses(motion, len(positions), source)
    check_workers(workers)
    opt = options or RenderOptions()
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))

    def draw(render, k: int) -> None:
        mpimg.imsave(tmp / f"frame_{k:05d}.png", render(positions[k], jaw[k], **poses[k]))

    try:
        with pending_folder(tmp):  # removed whole if the command is interrupted
            drawn = in_order(lambda: opt.renderer(scene), draw, len(positions), workers)
            with closing(drawn):
                for k, _ in enumerate(drawn):
                    if progress is not None:
                        progress(k + 1, len(positions))
            if folder.exists():
                folder.rmdir()
            tmp.rename(folder)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return folder


def write_snapshot(path: str | Path, scene: Scene, skin: np.ndarray, jaw_angle=0.0, *,
                   options: RenderOptions | None = None) -> Path:
    """A PNG of one configuration (default: frontal+profile, 960x540); ``jaw_angle`` (rad) or
    a (3,) jaw pose."""
    import matplotlib.image as mpimg

    img = (options or RenderOptions(size=(540, 960))).renderer(scene)(skin, jaw_angle)
    with atomic_path(path, suffix=".png") as tmp:
        mpimg.imsave(tmp, img)
    return Path(path)
