"""Frames of a face: a scene at one time step, through one or several cameras.

``Renderer(scene, view, size)`` keeps the cameras and buffers of a movie; ``renderer(skin,
jaw_angle)`` returns an (h, w, 4) sRGB uint8 frame. Work is confined to the face's bounding box
in each panel; the rest of the frame is background.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..checks import check_value
from ..errors import InputError
from .camera import MAX_SIZE, Camera, panels, view_camera
from .raster import (
    GROUND,
    LIGHTS,
    LINEAR_TO_SRGB_LUT,
    SKY,
    WRAP,
    rasterise_grid,
    shade_resolve,
    srgb_to_linear,
    vertex_light,
)
from .scene import Scene

BACKGROUND = "#2a2c33"  #: default background (dark slate), sRGB
_LIGHTS = np.concatenate([LIGHTS[:, :3] / np.linalg.norm(LIGHTS[:, :3], axis=1, keepdims=True),
                          LIGHTS[:, 3:]], axis=1).astype(np.float32)


def parse_background(text: str) -> np.ndarray:
    """``'#rrggbb'``, ``'r,g,b'`` (0-255) or ``'transparent'`` to linear RGBA (4,) float32."""
    t = text.strip().lower()
    if t in ("transparent", "none"):
        return np.zeros(4, np.float32)
    try:
        if t.startswith("#") and len(t) == 7:
            rgb = [int(t[i:i + 2], 16) for i in (1, 3, 5)]
        else:
            rgb = [int(v) for v in t.split(",")]
            if len(rgb) != 3 or not all(0 <= v <= 255 for v in rgb):
                raise ValueError
    except ValueError:
        raise InputError(f"background {text!r} is not '#rrggbb', 'r,g,b' or 'transparent'",
                         field="background") from None
    lin = srgb_to_linear(np.array(rgb) / 255.0)
    return np.array([*lin, 1.0], np.float32)


def render_panel(scene: Scene, verts: np.ndarray, norms: np.ndarray, camera: Camera, *,
                 background: np.ndarray, supersample: int = 2, out: np.ndarray | None = None,
                 scratch: dict | None = None) -> np.ndarray:
    """One camera's view of placed scene vertices: (h, w, 4) uint8 sRGB + alpha.

    ``out``: an (h, w, 4) uint8 array (or view) to draw into, returned; ``scratch``: a dict
    that keeps the visibility buffers from one call to the next (a movie's frames), where
    fresh ones would cost their pages every frame.
    """
    h, w = camera.size
    s = int(supersample)
    p = camera.project(verts, s)
    img = np.empty((h, w, 4), np.uint8) if out is None else out
    bg = resolve_background(background)
    img[:] = bg
    x0 = max(int(np.floor(p[:, 0].min() / s)) - 1, 0)
    x1 = min(int(np.ceil(p[:, 0].max() / s)) + 1, w)
    y0 = max(int(np.floor(p[:, 1].min() / s)) - 1, 0)
    y1 = min(int(np.ceil(p[:, 1].max() / s)) + 1, h)
    if x1 <= x0 or y1 <= y0:
        return img
    bh, bw = (y1 - y0) * s, (x1 - x0) * s
    px = p[:, 0] - x0 * s
    py = p[:, 1] - y0 * s
    zbuf, tid, bary = _buffers(scratch, bh, bw)
    rasterise_grid(px, py, p[:, 2], scene.tris, scene.uv, scene.tex, scene.alpha_test,
                   scene.two_sided, scene.atlas, (zbuf, tid, bary), s)
    light = vertex_light(norms @ camera.rotation.T, scene.gloss, _LIGHTS, SKY, GROUND, WRAP)
    sub = np.empty((y1 - y0, x1 - x0, 4), np.uint8)
    shade_resolve(tid, bary, s, scene.tris, light, scene.albedo, scene.uv, scene.tex,
                  scene.atlas, background.astype(np.float32), LINEAR_TO_SRGB_LUT, sub)
    img[y0:y1, x0:x1] = sub
    return img


def part_labels(scene: Scene, verts: np.ndarray, camera: Camera,
                supersample: int = 1) -> np.ndarray:
    """(h * s, w * s) int32: per sample, the index into ``scene.parts`` of the part seen
    there (-1: background, ``len(scene.parts)``: the inner side of a surface), for placed
    vertices (N, 3) m (:meth:`.scene.Scene.frame`) through ``camera``."""
    h, w = camera.size
    s = int(supersample)
    p = camera.project(verts, s)
    zbuf = np.full((h * s, w * s), -np.inf, np.float32)
    tid = np.full((h * s, w * s), -1, np.int32)
    bary = np.empty((h * s, w * s, 2), np.float32)
    rasterise_grid(p[:, 0], p[:, 1], p[:, 2], scene.tris, scene.uv, scene.tex,
                   scene.alpha_test, scene.two_sided, scene.atlas, (zbuf, tid, bary), s)
    nt = len(scene.tris)
    part_of = np.repeat(np.arange(len(scene.parts), dtype=np.int32),
                        [len(q.faces) for q in scene.parts])
    return np.where(tid < 0, -1, np.where(tid >= nt, len(scene.parts),
                                          part_of[np.clip(tid, 0, nt - 1)]))


def class_pixels(scene: Scene, skin: np.ndarray, view: str = "frontal",
                 size: tuple[int, int] = (720, 1280), jaw_angle=0.0,
                 blink: float = 0.0) -> dict[str, int]:
    """Pixels (one sample each) per part name in a frame of skin nodes (n, 3) m through a
    single named view: what the renderer shows of each part (``'inside'``: inner sides)."""
    verts, _ = scene.frame(skin, jaw_angle, blink)
    labels = part_labels(scene, verts, view_camera(view, scene.framing, size))
    counts = np.bincount(labels[labels >= 0].ravel(), minlength=len(scene.parts) + 1)
    names = [p.name for p in scene.parts] + ["inside"]
    out: dict[str, int] = {}
    for name, c in zip(names, counts, strict=True):
        out[name] = out.get(name, 0) + int(c)
    return out


def _buffers(scratch: dict | None, bh: int, bw: int):
    """Empty visibility buffers (depth -inf, triangle -1, weights unset) of bh x bw samples:
    new ones, or views of ``scratch``'s, grown when too small."""
    n = bh * bw
    if scratch is None or scratch.get("n", 0) < n:
        flat = (np.empty(n, np.float32), np.empty(n, np.int32), np.empty(2 * n, np.float32))
        if scratch is not None:
            scratch["n"], scratch["flat"] = n, flat
    else:
        flat = scratch["flat"]
    zbuf = flat[0][:n].reshape(bh, bw)
    tid = flat[1][:n].reshape(bh, bw)
    zbuf.fill(-np.inf)
    tid.fill(-1)
    return zbuf, tid, flat[2][:2 * n].reshape(bh, bw, 2)


def resolve_background(background: np.ndarray) -> np.ndarray:
    """The uint8 RGBA pixel of an empty background."""
    m = len(LINEAR_TO_SRGB_LUT) - 1
    rgb = [LINEAR_TO_SRGB_LUT[int(np.clip(c, 0, 1) * m + 0.5)] for c in background[:3]]
    return np.array([*rgb, int(background[3] * 255 + 0.5)], np.uint8)


class Renderer:
    """The frames of one scene through a named (possibly composite) view.

    Parameters
    ----------
    scene : :class:`facemech.viz.scene.Scene`
    view : a name of :func:`facemech.viz.camera.all_views`
    size : (height, width) of the whole frame, pixels; composite views split the width
    background : linear RGBA from :func:`parse_background`
    supersample : samples per pixel along each axis (anti-aliasing; 1 turns it off)
    distance : camera distance, m (None: orthographic)
    """

    def __init__(self, scene: Scene, view: str = "frontal", size: tuple[int, int] = (720, 1280),
                 *, background: np.ndarray | str = BACKGROUND, supersample: int = 2,
                 distance: float | None = 1.2):
        names = panels(view)
        h, w = size
        k = len(names)
        widths = [w // k + (1 if i < w % k else 0) for i in range(k)]
        self.scene = scene
        self.size = size
        self.cameras = [view_camera(n, scene.framing, (h, wi), distance)
                        for n, wi in zip(names, widths, strict=True)]
        self.background = (parse_background(background) if isinstance(background, str)
                           else np.asarray(background, np.float32))
        if supersample < 1 or supersample > 4:
            raise InputError("supersample must be 1 to 4", field="supersample")
        self.supersample = supersample
        self._scratch = [{} for _ in self.cameras]  # each panel's visibility buffers

    def __call__(self, skin: np.ndarray, jaw_angle=0.0, blink: float = 0.0,
                 gaze=(0.0, 0.0), head=None, tongue=None) -> np.ndarray:
        """(h, w, 4) uint8 frame of skin node positions (n, 3) m and a jaw angle (rad) or pose
        (3,) (angle rad, shift_y m, shift_z m); ``blink`` 0 (open) .. 1 (closed) and ``gaze``
        (yaw, pitch) rad move the eyes and lids; ``head`` (pitch, yaw, roll) rad turns the
        whole head; ``tongue`` (protrusion, elevation) m bends the tongue's tip
        (:meth:`.scene.Scene.frame`)."""
        verts, norms = self.scene.frame(skin, jaw_angle, blink, gaze, head, tongue)
        img = np.empty((*self.size, 4), np.uint8)
        x = 0
        for cam, scratch in zip(self.cameras, self._scratch, strict=True):
            w = cam.size[1]
            render_panel(self.scene, verts, norms, cam, background=self.background,
                         supersample=self.supersample, out=img[:, x:x + w], scratch=scratch)
            x += w
        return img


@dataclass(frozen=True)
class FrameMotion:
    """What moves the face besides its skin and jaw, per frame (e.g. from
    :func:`facemech.speech.alive.liveliness`).

    Attributes
    ----------
    blink : (T,) lid closure, 0 open .. 1 closed
    gaze : (T, 2) rad, (yaw, pitch) of both eyes
    head : (T, 3) rad, the head's (pitch, yaw, roll) (:func:`.scene.head_rotation`)
    tongue : (T, 2) m, the tongue tip's (protrusion, elevation) from rest
        (:mod:`facemech.speech.tongue`), or None: at rest
    """

    blink: np.ndarray
    gaze: np.ndarray
    head: np.ndarray
    tongue: np.ndarray | None = None

    @classmethod
    def rest(cls, frames: int, tongue: np.ndarray | None = None) -> FrameMotion:
        """Open lids, the eyes ahead and the head still for ``frames`` frames, with a tongue
        series (T, 2) m or None."""
        return cls(np.zeros(frames), np.zeros((frames, 2)), np.zeros((frames, 3)), tongue)

    def with_tongue(self, tongue: np.ndarray | None) -> FrameMotion:
        """The same motion with the tongue series ``tongue`` (T, 2) m (None: this one's)."""
        if tongue is None:
            return self
        return FrameMotion(self.blink, self.gaze, self.head, tongue)

    def __post_init__(self):
        shapes = {"blink": (None,), "gaze": (None, 2), "head": (None, 3), "tongue": (None, 2)}
        frames = len(np.asarray(self.blink))
        for name, shape in shapes.items():
            if getattr(self, name) is None:
                continue
            a = np.asarray(getattr(self, name), float)
            if a.ndim != len(shape) or a.shape[1:] != shape[1:] or len(a) != frames:
                raise InputError(f"{name} series of shape {a.shape} does not fit {frames} "
                                 f"frames", field=name)
            if not np.all(np.isfinite(a)):
                raise InputError(f"{name} series is not finite", field=name)
            object.__setattr__(self, name, a)
        if np.any((self.blink < 0) | (self.blink > 1)):
            raise InputError("blink closure must lie in 0..1", field="blink")

    def __len__(self) -> int:
        return len(self.blink)

    def at(self, k: int) -> tuple[float, np.ndarray, np.ndarray, np.ndarray | None]:
        """(blink, gaze (2,), head (3,), tongue (2,) or None) of frame ``k``."""
        return (float(self.blink[k]), self.gaze[k], self.head[k],
                None if self.tongue is None else self.tongue[k])


@dataclass(frozen=True)
class RenderOptions:
    """How frames are drawn.

    Attributes
    ----------
    view : frontal, profile, three-quarter, mouth or frontal+profile
    size : (height, width) pixels of a whole frame (composite views split the width)
    background : '#rrggbb', 'r,g,b' or 'transparent' (PNG frames and stills only)
    supersample : anti-aliasing samples per pixel along each axis (1-4)
    distance : camera distance, m; None for an orthographic view
    """

    view: str = "frontal+profile"
    size: tuple[int, int] = (720, 1280)
    background: str = BACKGROUND
    supersample: int = 2
    distance: float | None = 1.2

    def __post_init__(self):
        panels(self.view)  # raises on an unknown view
        h, w = self.size
        if not (16 <= h <= MAX_SIZE[0] and 16 <= w <= MAX_SIZE[1]):
            raise InputError(f"size {w}x{h} is outside 16x16 .. {MAX_SIZE[1]}x{MAX_SIZE[0]}",
                             field="size")
        parse_background(self.background)
        check_value("aa", self.supersample)  # 1 to 4 samples per axis (facemech.checks)
        if self.distance is not None and not 0.2 <= self.distance <= 20.0:
            raise InputError("camera distance must be 0.2 to 20 m", field="distance")

    @property
    def transparent(self) -> bool:
        return parse_background(self.background)[3] == 0.0

    def renderer(self, scene: Scene) -> Renderer:
        return Renderer(scene, self.view, self.size, background=self.background,
                        supersample=self.supersample, distance=self.distance)
