"""The numbers that describe a stimulus' visible motion: displacement, speed, aperture, width.

:func:`describe` measures from a results dataset what a methods section needs: how far and how
fast the lips, the jaw and the mouth corners move, how wide the mouth opens, the audio-visual
offset, and the settings and input hashes the file records; mm, mm/s, degrees or ms (converted
here, at the output; the dataset is SI).

- displacement: 3-D distance of a landmark's node from ``rest_positions`` per frame (``peak``,
  ``rms``);
- speed: the velocity's norm from Savitzky-Golay derivatives (50-ms window, cubic); NaN for
  series shorter than the window;
- lip aperture: vertical distance between the lips' facing midline nodes (the mouth slit's
  twins), else the lip-centre landmarks (noted in ``aperture_points``);
- mouth width: 3-D distance between the mouth-corner nodes;
- jaw angle: ``jaw_angle`` in degrees, opening positive (rest 0).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import InputError
from ..params import Parameters

#: the landmarks measured, by part
PARTS: dict[str, tuple[str, ...]] = {
    "lips": ("upper_lip_center", "lower_lip_center"),
    "jaw": ("chin",),
    "mouth_corners": ("mouth_corner_left", "mouth_corner_right"),
}

#: results attributes copied into the description as settings
SETTING_ATTRS = ("face", "preset", "integrator", "dt_s", "frame_rate_hz", "facemech_version")


@dataclass(frozen=True)
class Motion:
    """Peak and RMS displacement from rest (mm, or deg for an angle) and peak speed (mm/s or
    deg/s) of one point or angle."""

    peak_displacement: float
    rms_displacement: float
    peak_speed: float


@dataclass(frozen=True)
class Range:
    """Minimum, maximum and mean of a series over time (mm), and its rest value (mm)."""

    min: float
    max: float
    mean: float
    rest: float


@dataclass(frozen=True)
class Description:
    """What :func:`describe` measures.

    Attributes
    ----------
    duration_s, frames, frame_rate_hz : the motion's extent (duration = frames / rate, s:
        the movie's length)
    landmarks : name -> :class:`Motion` (mm, mm/s) of every landmark of :data:`PARTS`
    jaw_angle : :class:`Motion` of the jaw angle (deg, deg/s)
    lip_aperture, mouth_width : :class:`Range` (mm)
    aperture_points : the two nodes the aperture is measured between
    audio_offset_ms : audio against video, positive = audio later (ms)
    settings : the results' settings (face, preset, integrator, ...)
    inputs : input name -> hash, as the file records them
    stimulus : the manipulations a stimulus was made with (empty for a plain simulation)
    series : per-frame ``time`` (s), ``lip_aperture_mm`` and ``mouth_width_mm`` (not in
        :meth:`to_dict` unless asked)
    sensor_fit : of an inversion, the fit per sensor and axis
        (:class:`~facemech.inverse.sensor_fit.AxisFit`; empty otherwise)
    combinations : of an inversion, the combinations of controls the markers measure: name,
        mean, min, max, se, determined (at the inversion's noise)
    regularised : of an inversion, the controls the markers do not determine alone
    """

    duration_s: float
    frames: int
    frame_rate_hz: float
    landmarks: dict[str, Motion]
    jaw_angle: Motion
    lip_aperture: Range
    mouth_width: Range
    aperture_points: tuple[int, int]
    audio_offset_ms: float
    settings: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    stimulus: list = field(default_factory=list)
    series: dict = field(default_factory=dict, repr=False)
    sensor_fit: list = field(default_factory=list)
    combinations: list = field(default_factory=list)
    regularised: list = field(default_factory=list)

    def part(self, name: str) -> dict[str, Motion]:
        """The landmarks of one part of :data:`PARTS` (``lips``, ``jaw``, ``mouth_corners``)."""
        return {k: self.landmarks[k] for k in PARTS[name] if k in self.landmarks}

    def to_dict(self, *, series: bool = False) -> dict:
        """A JSON-ready dict (NaN becomes None); ``series=True`` adds the per-frame series."""
        d = asdict(self)
        d["aperture_points"] = list(self.aperture_points)
        if series:
            d["series"] = {k: [float(x) for x in v] for k, v in self.series.items()}
        else:
            d.pop("series")
        return _clean(d)

    def flat(self) -> dict[str, float]:
        """One level of ``name: value`` numbers (for a CSV manifest): e.g.
        ``upper_lip_center_peak_displacement_mm``, ``lip_aperture_max_mm``."""
        row: dict[str, float] = {}
        for name, m in self.landmarks.items():
            row[f"{name}_peak_displacement_mm"] = m.peak_displacement
            row[f"{name}_rms_displacement_mm"] = m.rms_displacement
            row[f"{name}_peak_speed_mm_s"] = m.peak_speed
        row["jaw_angle_peak_deg"] = self.jaw_angle.peak_displacement
        row["jaw_angle_rms_deg"] = self.jaw_angle.rms_displacement
        row["jaw_angle_peak_speed_deg_s"] = self.jaw_angle.peak_speed
        for name, r in (("lip_aperture", self.lip_aperture), ("mouth_width", self.mouth_width)):
            for k in ("min", "max", "mean", "rest"):
                row[f"{name}_{k}_mm"] = getattr(r, k)
        for f in self.sensor_fit:
            for k in ("rms_mm", "largest_mm", "corr", "range_share"):
                row[f"fit_{f.sensor}_{f.axis}_{k}"] = getattr(f, k)
        row["audio_offset_ms"] = self.audio_offset_ms
        row["duration_s"] = self.duration_s
        return {k: (None if v is None or not np.isfinite(v) else round(float(v), 6))
                for k, v in row.items()}

    def table(self) -> str:
        """A plain-text table for the terminal."""
        lines = [f"duration {self.duration_s:.3f} s, {self.frames} frames at "
                 f"{self.frame_rate_hz:g} Hz; audio-visual offset {self.audio_offset_ms:+.1f} ms "
                 "(positive: audio later)",
                 f"{'':20s} {'peak disp':>10s} {'RMS disp':>10s} {'peak speed':>11s}"]
        for part in PARTS:
            lines.append(f"{part}:")
            for name, m in self.part(part).items():
                lines.append(f"  {name:18s} {_f(m.peak_displacement)} mm "
                             f"{_f(m.rms_displacement)} mm {_f(m.peak_speed)} mm/s")
            if part == "jaw":
                m = self.jaw_angle
                lines.append(f"  {'jaw_angle':18s} {_f(m.peak_displacement)} deg"
                             f"{_f(m.rms_displacement)} deg{_f(m.peak_speed)} deg/s")
        lines.append(f"{'':20s} {'min':>10s} {'max':>10s} {'mean':>10s} {'rest':>10s}")
        for name, r in (("lip aperture", self.lip_aperture),
                        ("mouth width", self.mouth_width)):
            lines.append(f"{name:20s} {_f(r.min)} {_f(r.max)} {_f(r.mean)} {_f(r.rest)}  mm")
        if self.settings:
            lines.append("settings: " + ", ".join(f"{k} {v}" for k, v in self.settings.items()))
        if self.inputs:
            lines.append("inputs: " + ", ".join(f"{k} {v}" for k, v in self.inputs.items()))
        for step in self.stimulus:
            lines.append(f"manipulation: {json.dumps(step, sort_keys=True)}")
        return "\n".join(lines + self._inversion_lines())

    def _inversion_lines(self) -> list[str]:
        from ..inverse.sensor_fit import fit_lines

        lines = []
        if self.sensor_fit:
            lines.append("fit per sensor and axis (model against measured: RMS, largest error, "
                         "correlation, the model's share of the recorded range):")
            lines += [f"  {line}" for line in fit_lines(self.sensor_fit)]
        if self.combinations:
            lines.append("combinations of controls the markers measure (mean, range, SE):")
            lines += [f"  {c['name']}: mean {c['mean']:.2f} ({c['min']:.2f} to {c['max']:.2f}), SE "
                      f"{c['se']:.2f}{'' if c['determined'] else ' (not within 0.1)'}"
                      for c in self.combinations]
        if self.regularised:
            lines.append("regularised (not determined by the markers alone): "
                         + ", ".join(self.regularised))
        return lines


def _f(v: float) -> str:
    return f"{v:10.3f}" if np.isfinite(v) else f"{'-':>10s}"


def _clean(x):
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    return x


def speeds(series: np.ndarray, rate: float) -> np.ndarray:
    """Speed (norm of the Savitzky-Golay velocity) of series (frames, points, 3), unit/s.

    Returns (frames, points), NaN where a series is too short for the derivative's window.
    """
    from ..kinematics.resample import derivative
    from ..markerset import MarkerSet

    series = np.asarray(series, float)
    ms = MarkerSet(series, tuple(f"p{i}" for i in range(series.shape[1])), rate)
    return np.linalg.norm(derivative(ms, 1), axis=2)


def _motion(disp: np.ndarray, speed: np.ndarray, scale: float) -> Motion:
    sp = speed[np.isfinite(speed)]
    return Motion(peak_displacement=float(np.max(disp)) * scale,
                  rms_displacement=float(np.sqrt(np.mean(disp ** 2))) * scale,
                  peak_speed=float(sp.max()) * scale if sp.size else float("nan"))


def marker_nodes(ds, *, source: str | None = None) -> dict[str, int]:
    """The landmark -> epidermal node map of a results dataset (attribute ``marker_nodes``)."""
    try:
        nodes = json.loads(ds.attrs.get("marker_nodes", "{}"))
    except (TypeError, ValueError):
        raise InputError("attribute marker_nodes is not JSON", source=source,
                         field="marker_nodes") from None
    n = ds.sizes["node"]
    return {str(k): int(v) for k, v in nodes.items() if 0 <= int(v) < n}


def lip_facing_nodes(ds, *, source: str | None = None) -> tuple[int, int, bool]:
    """The upper and lower lip's facing nodes on the midline, and whether they are twins.

    The mouth slit's twins share one rest position; the pair nearest the stomion landmark (or
    the midpoint of the lip centres) is taken, the upper one being the node whose triangle
    neighbours lie higher. Without twins: the lip-centre landmarks (``False``).
    """
    nodes = marker_nodes(ds, source=source)
    for need in ("upper_lip_center", "lower_lip_center"):
        if need not in nodes:
            raise InputError("the results name no lip-centre landmark", source=source,
                             field=f"marker_nodes.{need}")
    rest = ds["rest_positions"].transpose("node", "axis").values
    ul, ll = nodes["upper_lip_center"], nodes["lower_lip_center"]
    target = rest[nodes["stomion"]] if "stomion" in nodes else 0.5 * (rest[ul] + rest[ll])
    order = np.argsort(np.linalg.norm(rest - target, axis=1))[:24]
    scale = float(np.ptp(rest, axis=0).max()) or 1.0
    for i in order:
        twins = [int(j) for j in order
                 if j != i and np.linalg.norm(rest[j] - rest[i]) < 1e-9 * scale]
        if twins:
            a, b = int(i), twins[0]
            tri = ds["triangles"].values
            hy = [rest[np.unique(tri[np.any(tri == k, axis=1)])][:, 1].mean() for k in (a, b)]
            return (a, b, True) if hy[0] >= hy[1] else (b, a, True)
    return ul, ll, False


def describe(ds, *, audio_offset_s: float | None = None,
             source: str | None = None) -> Description:
    """Measure a results dataset's visible motion (see the module's definitions).

    Parameters
    ----------
    ds : results dataset (:func:`facemech.io.results.read_results`)
    audio_offset_s : audio against video, s, positive = audio later; default: the dataset's
        ``audio_offset_ms`` attribute (written by :mod:`facemech.speech.stimuli`), else 0
    source : name for messages

    Returns
    -------
    Description
    """
    nodes = marker_nodes(ds, source=source)
    pos = ds["positions"].transpose("time", "node", "axis").values
    rest = ds["rest_positions"].transpose("node", "axis").values
    rate = float(ds.attrs.get("frame_rate_hz", Parameters.frame_rate))
    t = ds["time"].values
    names = [n for part in PARTS.values() for n in part if n in nodes]
    idx = [nodes[n] for n in names]
    disp = np.linalg.norm(pos[:, idx] - rest[idx], axis=2)
    sp = speeds(pos[:, idx], rate)
    marks = {n: _motion(disp[:, k], sp[:, k], 1e3) for k, n in enumerate(names)}
    angle = (ds["jaw_angle"].values.astype(float) if "jaw_angle" in ds
             else np.zeros(len(t)))
    angle3 = np.zeros((len(angle), 1, 3))
    angle3[:, 0, 0] = angle
    jaw = _motion(np.abs(angle), speeds(angle3, rate)[:, 0], np.degrees(1.0))

    up, lo, _ = lip_facing_nodes(ds, source=source)
    aperture = (pos[:, up, 1] - pos[:, lo, 1]) * 1e3
    ap_rest = (rest[up, 1] - rest[lo, 1]) * 1e3
    if "mouth_corner_left" in nodes and "mouth_corner_right" in nodes:
        cl, cr = nodes["mouth_corner_left"], nodes["mouth_corner_right"]
        width = np.linalg.norm(pos[:, cl] - pos[:, cr], axis=1) * 1e3
        w_rest = float(np.linalg.norm(rest[cl] - rest[cr])) * 1e3
    else:
        width, w_rest = np.full(len(t), np.nan), float("nan")

    if audio_offset_s is None:
        offset_ms = float(ds.attrs.get("audio_offset_ms", 0.0))
    else:
        offset_ms = float(audio_offset_s) * 1e3
    settings = {k: _plain(ds.attrs[k]) for k in SETTING_ATTRS if k in ds.attrs}
    return Description(
        duration_s=len(t) / rate,
        frames=int(len(t)), frame_rate_hz=rate, landmarks=marks, jaw_angle=jaw,
        lip_aperture=_range(aperture, ap_rest), mouth_width=_range(width, w_rest),
        aperture_points=(int(up), int(lo)), audio_offset_ms=offset_ms, settings=settings,
        inputs=_json_attr(ds, "inputs", {}), stimulus=_json_attr(ds, "stimulus", []),
        series={"time": t.astype(float), "lip_aperture_mm": aperture,
                "mouth_width_mm": width}, **_inversion(ds))


def _inversion(ds) -> dict:
    """An inversion's fit per sensor and axis, combinations and regularised controls."""
    from ..inverse.sensor_fit import sensor_fit

    if "data_markers" not in ds or "markers" not in ds:
        return {}
    names = [str(n) for n in ds["marker"].values]
    fit = sensor_fit(ds["markers"].transpose("time", "marker", "axis").values,
                     ds["data_markers"].transpose("time", "marker", "axis").values, names)
    combos = []
    if "combination_activity" in ds:
        det = set(filter(None, str(ds.attrs.get("combinations_determined", "")).split(",")))
        act = ds["combination_activity"].values[:-1]
        for k, name in enumerate(str(n) for n in ds["combination"].values):
            v = act[:, k] if len(act) else ds["combination_activity"].values[:, k]
            combos.append({"name": name, "mean": float(np.mean(v)), "min": float(np.min(v)),
                           "max": float(np.max(v)),
                           "se": float(ds["combination_se"].values[k]),
                           "determined": name in det})
    reg = [n for n in str(ds.attrs.get("regularised", "")).split(",") if n]
    return {"sensor_fit": fit, "combinations": combos, "regularised": reg}


def _range(x: np.ndarray, rest: float) -> Range:
    if not np.isfinite(x).any():
        return Range(*(float("nan"),) * 3, rest)
    return Range(float(np.nanmin(x)), float(np.nanmax(x)), float(np.nanmean(x)), float(rest))


def _plain(v):
    return v.item() if isinstance(v, np.generic) else v


def _json_attr(ds, name: str, default):
    try:
        return json.loads(ds.attrs.get(name, json.dumps(default)))
    except (TypeError, ValueError):
        return default
