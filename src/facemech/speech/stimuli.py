"""Manipulations of visible speech for perception experiments: each a pure function of a
results dataset (and its audio) that returns new ones.

- :func:`scale_amplitude`: the motion about rest times a factor, whole face or a region;
- :func:`freeze`: a region held at rest or at one frame;
- :func:`time_scale`: the motion resampled to a new duration (the audio with
  :func:`facemech.speech.audio.time_stretch`);
- :func:`offset_audio`: the audio moved against the video, by whole samples;
- :func:`dub`: one item's face with another item's audio (McGurk-type stimuli).

Regions (:func:`region_weights`: ``lips``, ``jaw``, ``upper_face``, ``face``; several add) are a
smooth partition of unity over the skin nodes, drawn on the rest face from its landmarks
(docs/stimuli.md, "The manipulations"); the jaw, teeth and tongue tip follow ``jaw``. Every
manipulation keeps skin, markers and jaw consistent, records itself in the ``stimulus``
attribute (a JSON list) and drops the muscle outputs; ``activity`` is kept as the source's drive.
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import InputError
from ..waveforms import cosine_ramp
from .audio import Audio, fit_length, shift, time_stretch
from .audio import onset as audio_onset
from .audio import peak as audio_peak

REGIONS = ("face", "lips", "jaw", "upper_face")


# ---- regions ----------------------------------------------------------------------------------
_cosine_step = cosine_ramp


def region_partition(ds, *, source: str | None = None) -> dict[str, np.ndarray]:
    """Weights (node,) of ``lips``, ``jaw`` and ``upper_face``; they add to 1 at every node."""
    from ..analysis.describe import marker_nodes

    nodes = marker_nodes(ds, source=source)
    need = ("upper_lip_center", "lower_lip_center", "mouth_corner_left", "mouth_corner_right",
            "subnasale", "chin")
    for k in need:
        if k not in nodes:
            raise InputError("the results lack a landmark the regions are defined from",
                             source=source, field=f"marker_nodes.{k}")
    rest = ds["rest_positions"].transpose("node", "axis").values
    lm = {k: rest[v] for k, v in nodes.items()}
    st = lm.get("stomion", 0.5 * (lm["upper_lip_center"] + lm["lower_lip_center"]))
    cl, cr = lm["mouth_corner_left"], lm["mouth_corner_right"]
    half_w = 0.5 * abs(cl[0] - cr[0])
    up = max(lm["subnasale"][1] - st[1], 1e-3)
    down = max(st[1] - lm["chin"][1], 1e-3)
    x, y = rest[:, 0], rest[:, 1]
    dx = (x - st[0]) / (1.2 * half_w)
    dy = np.where(y >= st[1], (y - st[1]) / (0.7 * up), (st[1] - y) / (0.6 * down))
    r = np.hypot(dx, dy)
    lips = 1.0 - _cosine_step((r - 1.0) / 0.4)

    ga_l = lm.get("jaw_angle_left", cl + np.array([0.02, -0.03, 0.0]))
    ga_r = lm.get("jaw_angle_right", cr + np.array([-0.02, -0.03, 0.0]))

    def line(xv: np.ndarray) -> np.ndarray:
        inner = np.interp(xv, [cr[0], st[0], cl[0]], [cr[1], st[1], cl[1]])
        left = cl[1] + np.clip((xv - cl[0]) / (ga_l[0] - cl[0]), 0, 1) * (ga_l[1] - cl[1])
        right = cr[1] + np.clip((xv - cr[0]) / (ga_r[0] - cr[0]), 0, 1) * (ga_r[1] - cr[1])
        return np.where(xv > cl[0], left, np.where(xv < cr[0], right, inner))

    band = 0.3 * up
    below = _cosine_step((line(x) - y) / band + 0.5)
    jaw = (1.0 - lips) * below
    return {"lips": lips, "jaw": jaw, "upper_face": 1.0 - lips - jaw}


def parse_regions(region: str, *, field: str = "region") -> tuple[str, ...]:
    """``"lips,jaw"`` -> ``("lips", "jaw")``, each checked against :data:`REGIONS`."""
    names = tuple(r.strip().lower().replace("-", "_").replace(" ", "_")
                  for r in str(region).split(",") if r.strip())
    if not names:
        raise InputError("no region named", field=field)
    for r in names:
        if r not in REGIONS:
            raise InputError(f"unknown region {r!r} (expected {', '.join(REGIONS)})",
                             field=field)
    return names


def region_weights(ds, region: str = "face", *, source: str | None = None) -> np.ndarray:
    """A smooth weight (node,) in [0, 1] of a region or of several (``"lips,jaw"``)."""
    names = parse_regions(region)
    if "face" in names:
        return np.ones(ds.sizes["node"])
    part = region_partition(ds, source=source)
    return np.clip(sum(part[r] for r in names), 0.0, 1.0)


def _moves_jaw(region: str) -> bool:
    names = parse_regions(region)
    return "face" in names or "jaw" in names


# ---- helpers ----------------------------------------------------------------------------------
def _record(ds, step: dict):
    out = ds.drop_vars([v for v in ds.variables if "muscle_instance" in ds[v].dims])
    steps = json.loads(ds.attrs.get("stimulus", "[]"))
    out.attrs = {**ds.attrs, "stimulus": json.dumps([*steps, step])}
    return out


def _with_skin(ds, pos: np.ndarray, angle: np.ndarray | None = None,
               shift_yz: np.ndarray | None = None, tongue: np.ndarray | None = None):
    """``ds`` with new skin positions, the markers re-read at their nodes, the jaw and the
    tongue tip's pose."""
    from ..analysis.describe import marker_nodes

    out = ds.copy(deep=True)
    out["positions"] = (("time", "node", "axis"), pos, ds["positions"].attrs)
    mk = ds["markers"].transpose("time", "marker", "axis").values.copy()
    old = ds["positions"].transpose("time", "node", "axis").values
    nodes = marker_nodes(ds)
    for i, name in enumerate(str(m) for m in ds["marker"].values):
        if name in nodes:
            mk[:, i] = pos[:, nodes[name]]
        else:  # a marker off the nodes moves as the nearest node does
            j = int(np.argmin(np.linalg.norm(old[0] - mk[0, i], axis=1)))
            mk[:, i] += pos[:, j] - old[:, j]
    out["markers"] = (("time", "marker", "axis"), mk, ds["markers"].attrs)
    if angle is not None and "jaw_angle" in ds:
        out["jaw_angle"] = (("time",), angle, ds["jaw_angle"].attrs)
    if shift_yz is not None and "jaw_shift" in ds:
        out["jaw_shift"] = (("time", "shift_axis"), shift_yz, ds["jaw_shift"].attrs)
    if tongue is not None and "tongue_tip" in ds:
        out["tongue_tip"] = (("time", "tongue_axis"), tongue, ds["tongue_tip"].attrs)
    return out


def _skin(ds) -> tuple[np.ndarray, np.ndarray]:
    return (ds["positions"].transpose("time", "node", "axis").values,
            ds["rest_positions"].transpose("node", "axis").values)


def _jaw(ds) -> tuple[np.ndarray | None, np.ndarray | None]:
    angle = ds["jaw_angle"].values.astype(float) if "jaw_angle" in ds else None
    sh = (ds["jaw_shift"].transpose("time", "shift_axis").values.astype(float)
          if "jaw_shift" in ds else None)
    return angle, sh


def _tongue(ds) -> np.ndarray | None:
    """(frames, 2) m, the tongue tip's pose of the results, or None."""
    if "tongue_tip" not in ds:
        return None
    return ds["tongue_tip"].transpose("time", "tongue_axis").values.astype(float)


# ---- manipulations ------------------------------------------------------------------------------
def scale_amplitude(ds, factor: float, region: str = "face"):
    """The visible motion about rest times ``factor`` in a region.

    Each skin node moves to ``rest + (1 + w (factor - 1)) (p - rest)``, w its region weight
    (:func:`region_weights`); the markers follow their nodes; the jaw angle and shift are
    multiplied by ``factor`` when the region holds the jaw (``jaw`` or ``face``).

    Parameters
    ----------
    ds : results dataset
    factor : amplitude, 1 = unchanged, 0 = held at rest, 0.5 = half as far from rest
    region : ``face``, ``lips``, ``jaw``, ``upper_face`` or several, comma-separated

    Returns
    -------
    xarray.Dataset
    """
    factor = float(factor)
    if not np.isfinite(factor) or factor < 0:
        raise InputError(f"amplitude {factor} must be a finite number >= 0", field="amplitude")
    w = region_weights(ds, region)
    pos, rest = _skin(ds)
    new = pos + (w * (factor - 1.0))[None, :, None] * (pos - rest)  # exact where w = 0
    angle, sh = _jaw(ds)
    tongue = None
    if _moves_jaw(region):
        angle = None if angle is None else angle * factor
        sh = None if sh is None else sh * factor
        tongue = _tongue(ds)
        tongue = None if tongue is None else tongue * factor
    return _record(_with_skin(ds, new, angle, sh, tongue),
                   {"manipulation": "amplitude", "factor": factor, "region": region})


def freeze(ds, region: str, at: str | int | float = "rest"):
    """A region held still: at rest (``at="rest"``), at a frame (an int) or at a time (a float,
    s, the nearest frame).

    Each node moves to ``p + w (ref - p)``, w its region weight; the jaw is held too when the
    region holds it.
    """
    w = region_weights(ds, region)
    pos, rest = _skin(ds)
    angle, sh = _jaw(ds)
    t = ds["time"].values
    if isinstance(at, str) and at.strip().lower() == "rest":
        ref, a_ref, s_ref, where = rest, 0.0, 0.0, "rest"
    else:
        k = int(at) if isinstance(at, (int, np.integer)) else int(
            np.argmin(np.abs(t - float(at))))
        if not 0 <= k < len(t):
            raise InputError(f"frame {k} is outside the results (0 to {len(t) - 1})",
                             field="freeze_at")
        ref = pos[k]
        a_ref = None if angle is None else angle[k]
        s_ref = None if sh is None else sh[k]
        where = k
    new = pos + w[None, :, None] * (ref - pos)
    still = 1e-9  # m: below this the region's nodes do not move (rounding of p + (ref - p))
    if np.ptp(pos, axis=0).max() > still and not np.ptp(new, axis=0).max() > still and (
            angle is None or _moves_jaw(region) or np.ptp(angle) == 0):
        raise InputError(f"freezing {region!r} leaves no motion at all", field="freeze_region")
    tongue = None
    if _moves_jaw(region):
        angle = None if angle is None else np.full_like(angle, a_ref)
        sh = None if sh is None else np.broadcast_to(s_ref, sh.shape).astype(float)
        tongue = _tongue(ds)
        if tongue is not None:
            tongue = np.broadcast_to(0.0 if where == "rest" else tongue[where],
                                     tongue.shape).astype(float)
    return _record(_with_skin(ds, new, angle, sh, tongue),
                   {"manipulation": "freeze", "region": region, "at": where})


def time_scale(ds, factor: float, *, rate: float = 60.0):
    """The motion made ``factor`` times as long, resampled at ``rate`` Hz.

    Output frame k at time k / rate shows the input at frame ``k / (factor rate / rate_in)``:
    skin, markers, jaw angle and shift (and the tongue tip's pose) by a cubic spline through
    the input frames (exact on them: a factor 2 at 60 Hz keeps every input frame, so peaks keep
    their height), activity linearly. The new length is
    ``round(frames x factor x rate / rate_in)`` frames. Speeds divide by the factor.
    """
    from scipy.interpolate import CubicSpline

    factor = float(factor)
    if not np.isfinite(factor) or factor <= 0:
        raise InputError(f"time scale {factor} must be a positive number", field="time_scale")
    rate_in = float(ds.attrs.get("frame_rate_hz", 60.0))
    n_in = ds.sizes["time"]
    n = max(1, int(round(n_in * factor * rate / rate_in)))
    u = np.clip(np.arange(n) * rate_in / (rate * factor), 0.0, n_in - 1)
    frames = np.arange(n_in)

    def resampled(values: np.ndarray) -> np.ndarray:
        if n_in < 2:
            return np.repeat(values[:1], n, axis=0)
        return CubicSpline(frames, values, axis=0)(u)

    t0 = float(ds["time"].values[0]) if n_in else 0.0
    keep = [v for v in ds.data_vars if "time" not in ds[v].dims]
    out = ds[keep].drop_dims("time", errors="ignore").assign_coords(
        time=("time", t0 + np.arange(n) / rate, ds["time"].attrs))
    for name in ("positions", "markers", "jaw_angle", "jaw_shift", "tongue_tip"):
        if name in ds:
            var = ds[name]
            out[name] = (var.dims, resampled(var.values), var.attrs)
    if "activity" in ds:
        act = ds["activity"].transpose("time", "muscle").values
        lin = np.stack([np.interp(u, frames, act[:, j]) for j in range(act.shape[1])], axis=1)
        out["activity"] = (("time", "muscle"), lin, ds["activity"].attrs)
    out.attrs = {**ds.attrs, "frame_rate_hz": float(rate)}
    return _record(out, {"manipulation": "time_scale", "factor": factor, "rate_hz": rate})


def offset_audio(ds, audio: Audio, offset_ms: float):
    """Move the audio against the video by ``offset_ms`` (positive: the audio later).

    The sound is shifted by ``round(offset_ms x rate / 1000)`` samples (:func:`audio.shift`):
    silence before it and its end cut (later), or its start cut and silence after it
    (earlier); its length is unchanged. The dataset's ``audio_offset_ms`` attribute adds the
    shift actually made (whole samples), which :func:`facemech.analysis.describe.describe`
    reports.

    Returns
    -------
    (xarray.Dataset, Audio)
    """
    offset_ms = float(offset_ms)
    if not np.isfinite(offset_ms):
        raise InputError("the audio-visual offset must be a number", field="av_offset_ms")
    moved, k = shift(audio, offset_ms / 1e3)
    if np.any(audio.samples) and not np.any(moved.samples):
        raise InputError(f"an offset of {offset_ms:g} ms moves the whole sound "
                         f"({1e3 * audio.duration:.0f} ms) out of the stimulus",
                         field="av_offset_ms")
    made = 1e3 * k / audio.rate
    out = ds.copy()
    out.attrs = {**ds.attrs, "audio_offset_ms": float(ds.attrs.get("audio_offset_ms", 0.0))
                 + made}
    steps = json.loads(ds.attrs.get("stimulus", "[]"))
    out.attrs["stimulus"] = json.dumps([*steps, {"manipulation": "av_offset",
                                                 "requested_ms": offset_ms, "samples": k,
                                                 "made_ms": made}])
    return out, moved


ANCHORS = ("start", "onset", "peak")


def anchor_time(audio: Audio, anchor: str | float) -> float:
    """An anchor of a sound, s: ``start`` (0), ``onset`` (:func:`audio.onset`), ``peak``
    (:func:`audio.peak`) or a time given in seconds."""
    if isinstance(anchor, (int, float, np.floating)):
        return float(anchor)
    a = str(anchor).strip().lower()
    if a == "start":
        return 0.0
    if a == "onset":
        return audio_onset(audio)
    if a == "peak":
        return audio_peak(audio)
    try:
        return float(a.removesuffix("s"))
    except ValueError:
        raise InputError(f"unknown anchor {anchor!r} (start, onset, peak or a time in s)",
                         field="dub_align") from None


def dub(ds, face_audio: Audio | None, audio: Audio, *, align: str = "start",
        face_anchor: str | float | None = None, audio_anchor: str | float | None = None):
    """Another item's audio on this item's face: McGurk-type stimuli.

    The new sound is ``audio`` moved so that its anchor falls where the face's own sound
    (``face_audio``) has its anchor, then cut or padded to the face's own sound's length (the
    movie's length, frames / rate, without one).

    Parameters
    ----------
    ds : the face's results
    face_audio : the face's own sound (needed for anchors other than ``start``)
    audio : the sound dubbed on
    align : ``start`` (both sounds start with the movie), ``onset`` (their acoustic onsets,
        e.g. the release bursts, coincide) or ``peak`` (their loudest moments coincide)
    face_anchor, audio_anchor : override the anchor's time in either sound, s (e.g. a
        phone's start from an alignment)

    Returns
    -------
    (xarray.Dataset, Audio)
    """
    align_l = str(align).strip().lower()
    if align_l not in ANCHORS:
        raise InputError(f"unknown alignment {align!r} (expected {', '.join(ANCHORS)})",
                         field="dub_align")
    if audio.rate != (face_audio.rate if face_audio is not None else audio.rate):
        from scipy.signal import resample_poly

        y = resample_poly(audio.samples.astype(float), face_audio.rate, audio.rate, axis=0)
        from .audio import _to_dtype

        audio = Audio(_to_dtype(y, audio.samples.dtype), face_audio.rate, audio.source)
    if face_anchor is None and align_l != "start" and face_audio is None:
        raise InputError(f"aligning by {align_l} needs the face's own audio", field="dub_align")
    fa = anchor_time(face_audio, face_anchor if face_anchor is not None else align_l) if (
        face_audio is not None or face_anchor is not None) else 0.0
    aa = anchor_time(audio, audio_anchor if audio_anchor is not None else align_l)
    length = (len(face_audio.samples) if face_audio is not None
              else int(round(ds.sizes["time"] / float(ds.attrs.get("frame_rate_hz", 60.0))
                             * audio.rate)))
    moved, k = shift(audio, fa - aa, length=length)
    out = ds.copy()
    steps = json.loads(ds.attrs.get("stimulus", "[]"))
    out.attrs = {**ds.attrs, "stimulus": json.dumps([*steps, {
        "manipulation": "dub", "audio": audio.source, "align": align_l,
        "face_anchor_s": fa, "audio_anchor_s": aa, "shift_samples": k,
        "shift_ms": 1e3 * k / audio.rate}])}
    return out, moved


def time_scale_with_audio(ds, audio: Audio | None, factor: float, *, audio_method: str = "stretch",
                          rate: float = 60.0):
    """:func:`time_scale` of the face and the same factor on the sound.

    ``audio_method``: ``stretch`` (WSOLA, pitch kept), ``resample`` (varispeed, pitch moves) or
    ``none`` (the sound unchanged, cut or padded to the new movie's length: face only).
    """
    out = time_scale(ds, factor, rate=rate)
    if audio is None:
        return out, None
    method = str(audio_method).strip().lower()
    if method == "none":
        new = fit_length(audio, out.sizes["time"] / rate)
    else:
        new = time_stretch(audio, factor, method=method)
    steps = json.loads(out.attrs["stimulus"])
    steps[-1]["audio"] = method
    out.attrs["stimulus"] = json.dumps(steps)
    return out, new
