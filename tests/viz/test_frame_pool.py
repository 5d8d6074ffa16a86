"""A movie's frames drawn on several threads (facemech.viz.frame_pool): the same bytes as on
one thread, written in order, errors and interrupts raised in the caller with no thread left
drawing, the number of threads checked."""

from __future__ import annotations

import threading
from contextlib import closing

import numpy as np
import pytest

from facemech.errors import InputError
from facemech.physics.threads import affinity_cores
from facemech.viz import frame_pool, movie
from facemech.viz.render import FrameMotion, RenderOptions
from facemech.viz.scene import build_scene, look_from_model

FRAMES = 6
OPTIONS = RenderOptions(view="frontal", size=(96, 128), supersample=2)


@pytest.fixture(scope="module")
def scene(face):
    return build_scene(look_from_model(face))


@pytest.fixture(scope="module")
def motion(scene):
    """(positions (T, n, 3) m, jaw poses (T, 3), FrameMotion): every frame different."""
    rest = scene.look.rest
    t = np.linspace(0.0, 1.0, FRAMES)
    lips = np.zeros_like(rest)
    lips[:, 1] = -0.004 * np.exp(-np.sum((rest - scene.look.landmarks["stomion"]) ** 2, axis=1)
                                 / 0.02 ** 2)  # the lower face drops by up to 4 mm
    positions = rest[None] + t[:, None, None] * lips[None]
    jaw = np.stack([np.radians(12.0) * t, 0.001 * t, 0.0 * t], axis=1)
    alive = FrameMotion(blink=np.clip(2 * t - 0.6, 0, 1), gaze=np.stack([0.2 * t, -0.1 * t], 1),
                        head=np.stack([0.05 * t, 0.1 * t, -0.03 * t], 1))
    return positions, jaw, alive


def _reference(scene, motion) -> list[np.ndarray]:
    """Each frame drawn on its own, in the caller's thread, by a fresh renderer."""
    positions, jaw, alive = motion
    out = []
    for k in range(FRAMES):
        blink, gaze, head, tongue = alive.at(k)
        out.append(OPTIONS.renderer(scene)(positions[k], jaw[k], blink=blink, gaze=gaze,
                                           head=head, tongue=tongue))
    return out


def _threads() -> list[str]:
    return [t.name for t in threading.enumerate() if t.name.startswith("facemech-frame")]


def test_png_frames_on_two_threads_are_the_single_thread_bytes_in_order(scene, motion,
                                                                        tmp_path):
    from PIL import Image

    positions, jaw, alive = motion
    ref = _reference(scene, motion)
    assert all(np.any(a != b) for a, b in zip(ref, ref[1:], strict=False))  # order shows
    got = {}
    for workers in (1, 2):
        reports = []
        folder = movie.write_frames(tmp_path / f"w{workers}", scene, positions, jaw,
                                    options=OPTIONS, motion=alive, workers=workers,
                                    progress=lambda d, n, r=reports: r.append((d, n)))
        assert reports == [(k + 1, FRAMES) for k in range(FRAMES)]
        files = sorted(folder.glob("frame_*.png"))
        assert [f.name for f in files] == [f"frame_{k:05d}.png" for k in range(FRAMES)]
        got[workers] = [np.asarray(Image.open(f)) for f in files]
    for k in range(FRAMES):
        assert got[1][k].dtype == np.uint8 and got[1][k].shape == (96, 128, 4)
        np.testing.assert_array_equal(got[1][k], ref[k])
        np.testing.assert_array_equal(got[2][k], ref[k])
    assert not _threads()


def test_movie_frames_reach_the_encoder_in_order_and_identical(scene, motion, tmp_path,
                                                               monkeypatch):
    """What write_movie sends to ffmpeg, caught before it is encoded (H.264 is lossy)."""
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    positions, jaw, alive = motion
    ref = _reference(scene, motion)
    sent: list[np.ndarray] = []

    def fake_writer(path, size, **kw):
        frame = yield
        while frame is not None:
            sent.append(np.array(frame))
            frame = yield
        # the generator is closed at the end: the file appears as ffmpeg's would

    def writer(path, size, **kw):
        gen = fake_writer(path, size, **kw)

        class W:
            def send(self, x):
                return gen.send(x)

            def close(self):
                gen.close()
                open(path, "wb").close()

        return W()

    monkeypatch.setattr(imageio_ffmpeg, "write_frames", writer)
    for workers in (1, 2):
        sent.clear()
        reports = []
        movie.write_movie(tmp_path / f"m{workers}.mp4", scene, positions, jaw, options=OPTIONS,
                          motion=alive, workers=workers,
                          progress=lambda d, n, r=reports: r.append((d, n)))
        assert reports == [(k + 1, FRAMES) for k in range(FRAMES)]
        assert len(sent) == FRAMES
        for k in range(FRAMES):
            np.testing.assert_array_equal(sent[k], ref[k][..., :3])
    assert not _threads()


def test_an_error_in_a_thread_is_raised_in_the_caller_and_stops_the_pool():
    started = []

    def task(render, k):
        started.append(k)
        if k == 3:
            raise ValueError("frame 3 failed")
        return k

    with pytest.raises(ValueError, match="frame 3"):
        list(frame_pool.in_order(object, task, 100, workers=2))
    assert len(started) <= 3 + 1 + 2 * 2  # the frames yielded, the failed one, those queued
    assert not _threads()


def test_an_interrupt_in_the_caller_cancels_the_queued_frames(scene, motion, tmp_path):
    """Ctrl-C while frames are written (here: raised by the progress callback) leaves no
    thread drawing and no frame folder."""
    positions, jaw, alive = motion
    long = np.concatenate([positions] * 4)
    drawn = []
    real = OPTIONS.renderer

    class Counting(RenderOptions):
        def renderer(self, scene):
            r = real(scene)

            def count(*a, **kw):
                drawn.append(1)
                return r(*a, **kw)

            return count

    def interrupt(done, total):
        if done == 2:
            raise KeyboardInterrupt

    opts = Counting(view="frontal", size=(96, 128), supersample=2)
    with pytest.raises(KeyboardInterrupt):
        movie.write_frames(tmp_path / "f", scene, long, np.concatenate([jaw] * 4),
                           options=opts, workers=2, progress=interrupt)
    assert not _threads()
    assert len(drawn) <= 2 + 2 * 2 + 2  # at most 2 x workers ahead, and the ones drawing
    assert not (tmp_path / "f").exists() and not list(tmp_path.iterdir())


def test_closing_the_frames_early_cancels_the_rest():
    started = []

    def task(render, k):
        started.append(k)
        return k

    frames = frame_pool.in_order(object, task, 1000, workers=2)
    with closing(frames):
        assert [next(frames), next(frames)] == [0, 1]
    assert len(started) <= 2 + 2 * 2 + 2
    assert not _threads()


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2", 2000])
def test_bad_numbers_of_workers_are_refused_before_any_frame(scene, motion, tmp_path, bad):
    positions, jaw, _ = motion
    with pytest.raises(InputError) as err:
        movie.write_frames(tmp_path / "f", scene, positions, jaw, options=OPTIONS, workers=bad)
    assert err.value.field == "workers"
    assert not (tmp_path / "f").exists() and not list(tmp_path.iterdir())


def test_default_workers_and_the_kernels_release_the_gil():
    from facemech.viz import raster

    assert frame_pool.check_workers(None) == min(2, affinity_cores())
    assert frame_pool.check_workers(1) == 1
    for kernel in (raster.rasterise_grid, raster.shade_resolve, raster._vertex_light):
        assert kernel.targetoptions.get("nogil") is True


def test_a_command_ended_by_a_signal_stops_the_threads_first():
    """The signal handler of the command line (facemech.interrupts) exits without unwinding:
    the pool's clean-up, registered while frames are drawn, waits for the frames being drawn
    and cancels the rest before the temporary files go."""
    from facemech import interrupts

    started = []
    frames = frame_pool.in_order(object, lambda r, k: started.append(k) or k, 1000, workers=2)
    before = len(interrupts._CLEANUPS)
    with closing(frames):
        next(frames)
        assert len(interrupts._CLEANUPS) == before + 1
        interrupts._CLEANUPS[-1]()  # what the handler runs
        assert not _threads()
        assert len(started) <= 1 + 2 * 2 + 2
    assert len(interrupts._CLEANUPS) == before
