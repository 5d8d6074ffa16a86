"""3-D statistics of trajectories (Pitermann & Munhall 2001, eqs. 5-7) and per-axis
cross-correlations of displacement and acceleration (Lucero & Munhall 1999, Tables III-IV).

All functions take trajectories as (frames, 3) or (frames, markers, 3) arrays in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..params import Parameters
from .resample import savgol_derivative

__all__ = ["Comparison", "MarkerStatistics", "acceleration", "axis_correlations", "centroid",
           "compare", "corr3d", "cross_correlation", "error_summary", "frame_errors", "json_safe",
           "movement", "runs", "std3d", "summary5"]

#: Hz, the frame rate assumed where none is given: the parameters' (the model's output rate)
FRAME_RATE = Parameters.frame_rate


def centroid(v: np.ndarray) -> np.ndarray:
    """mu_v = (1/n) sum_i v_i (eq. 5)."""
    return np.mean(v, axis=0)


def std3d(v: np.ndarray) -> np.ndarray:
    """sigma_v = sqrt(sum_i |v_i - mu_v|^2 / (n - 1)) (eq. 6)."""
    d = v - centroid(v)
    return np.sqrt(np.sum(d * d, axis=(0, -1)) / (len(v) - 1))


#: a trajectory whose 3-D spread is below this share of its coordinates has no motion
_STILL = 64 * np.finfo(float).eps


def corr3d(v: np.ndarray, w: np.ndarray, *, published: bool = True) -> np.ndarray:
    """3-D correlation of two trajectories (Pitermann & Munhall 2001, eq. 7), in [-1, 1].

    ``r = sum_i (v_i - mu_v) . (w_i - mu_w) / sqrt(sum_i |v_i - mu_v|^2 sum_i |w_i - mu_w|^2)``:
    the covariance of eq. 7 over the product of the sigmas of eq. 6, with one normalisation
    throughout. ``published=True`` takes 1/n in the numerator and population sigmas (1/n),
    ``published=False`` takes 1/(n - 1) in both; the normalisations cancel, so both forms give
    the same number and a trajectory correlates with itself at exactly 1.

    Eq. 7 as printed divides a 1/n numerator by the (n - 1) sigmas of eq. 6; that mixture caps a
    self-correlation at (n - 1) / n (0.983 at 60 frames, 0.9936 at 156) and lowers every
    correlation by the same factor. It is not reproduced here.

    The sums are taken about the centroids (eq. 5), not as ``mean(v . w) - mu_v . mu_w``: that
    difference of raw moments loses all its digits for a marker that moves little next to its
    distance from the origin (a marker still to 0.1 um at 10 cm, or lab coordinates) and gave
    self-correlations such as 1.0025.

    Parameters
    ----------
    v, w : (frames, 3) or (frames, markers, 3) arrays, same units
        Frames where either is not finite are left out (per marker).
    published : bool
        The form (1/n or 1/(n - 1) throughout); both give the same number.

    Returns
    -------
    float array, one per marker: NaN for a trajectory with no motion (all frames equal to within
    rounding) or fewer than 2 usable frames.
    """
    v = np.asarray(v, float)
    w = np.asarray(w, float)
    ok = np.all(np.isfinite(v) & np.isfinite(w), axis=-1)  # (frames[, markers])
    okx = ok[..., None]
    count = ok.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu_v = np.where(okx, v, 0.0).sum(axis=0) / count[..., None]
        mu_w = np.where(okx, w, 0.0).sum(axis=0) / count[..., None]
        dv = np.where(okx, v - mu_v, 0.0)
        dw = np.where(okx, w - mu_w, 0.0)
        sv = np.sum(dv * dv, axis=(0, -1))
        sw = np.sum(dw * dw, axis=(0, -1))
        # the covariance over the sigmas, each with the form's normalisation (1/n published,
        # 1/(n - 1) unbiased), which cancels: both forms are this one number
        r = np.sum(dv * dw, axis=(0, -1)) / np.sqrt(sv * sw)
    # no motion: spread within the rounding of the positions themselves
    scale_v = np.max(np.where(okx, np.abs(v), 0.0), axis=(0, -1))
    scale_w = np.max(np.where(okx, np.abs(w), 0.0), axis=(0, -1))
    still = ((np.sqrt(sv / np.maximum(count, 1)) <= _STILL * scale_v)
             | (np.sqrt(sw / np.maximum(count, 1)) <= _STILL * scale_w) | (count < 2))
    return np.where(still, np.nan, np.clip(r, -1.0, 1.0))


#: window of the acceleration statistics, s: 7 samples at 60 Hz, smoother than the default
#: derivative because a second derivative of recorded markers amplifies noise most
ACCELERATION_WINDOW_S = 0.1


def acceleration(x: np.ndarray, rate: float) -> np.ndarray:
    """Second derivative along axis 0 (unit per s^2), by :func:`savgol_derivative`."""
    return savgol_derivative(x, rate, 2, window_s=ACCELERATION_WINDOW_S)


def cross_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Zero-lag normalised cross-correlation (Pearson) of two series (NaN if one is flat)."""
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt(np.sum(a * a) * np.sum(b * b))
    return float(np.clip(np.sum(a * b) / den, -1.0, 1.0)) if den > 0 else float("nan")


def runs(ok: np.ndarray) -> list[slice]:
    """The runs of consecutive True samples of a boolean series, as slices."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], np.asarray(ok, int), [0]))))
    return [slice(int(i), int(j)) for i, j in zip(edges[::2], edges[1::2], strict=True)]


#: frames of a run of consecutive data that gives an acceleration (a cubic fit needs 5)
ACCELERATION_MIN_FRAMES = 5


def axis_correlations(a: np.ndarray, b: np.ndarray, rate: float = FRAME_RATE) -> dict:
    """Per-axis Pearson correlations of displacement and of acceleration (Savitzky-Golay,
    0.1-s cubic), over the frames where both have data.

    The displacements are taken from the first frame with data in both. The acceleration is
    computed within each run of consecutive frames with data in both (a gap is not bridged)
    and left out when no run has 5 frames.

    Parameters
    ----------
    a, b : (frames, 3) arrays, same units; NaN where missing
    rate : frame rate, Hz

    Returns
    -------
    dict: ``displacement`` (and ``acceleration``) -> {"x", "y", "z"} -> Pearson r (NaN with
    fewer than 2 frames in both or a flat series)
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    ok = np.all(np.isfinite(a) & np.isfinite(b), axis=-1)
    if not ok.any():
        nan = dict.fromkeys("xyz", float("nan"))
        return {"displacement": nan}
    first = int(np.argmax(ok))
    x, y = a[ok] - a[first], b[ok] - b[first]
    out = {"displacement": {ax: cross_correlation(x[:, i], y[:, i])
                            for i, ax in enumerate("xyz")}}
    long = [r for r in runs(ok) if r.stop - r.start >= ACCELERATION_MIN_FRAMES]
    if long:
        x = np.concatenate([acceleration(a[r] - a[first], rate) for r in long])
        y = np.concatenate([acceleration(b[r] - b[first], rate) for r in long])
        out["acceleration"] = {ax: cross_correlation(x[:, i], y[:, i])
                               for i, ax in enumerate("xyz")}
    return out


def frame_errors(model: np.ndarray, data: np.ndarray) -> np.ndarray:
    """Per-frame error: the RMS over the markers used, sqrt(E / N) (frames,), metres.

    E = sum_i |m_i - n_i|^2 over the N markers present in both (finite in both) at that frame.
    This is the one per-frame error of facemech: ``compare``, ``invert`` and the results files
    report it (:func:`error_summary` for the median and maximum). A frame with no marker in
    both gives NaN.

    Parameters
    ----------
    model, data : (frames, markers, 3) arrays, metres, the same markers in the same order
    """
    d = np.asarray(model, float) - np.asarray(data, float)
    ok = np.all(np.isfinite(d), axis=-1)
    e = np.where(ok, np.sum(np.where(ok[..., None], d, 0.0) ** 2, axis=-1), 0.0)
    used = ok.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(used > 0, np.sqrt(e.sum(axis=1) / used), np.nan)


#: the summary warns when the largest per-frame error exceeds this (mm) ...
ERROR_WARN_MM = 1.0
#: ... or this many times the median
ERROR_WARN_RATIO = 5.0


def error_summary(per_frame_m: np.ndarray, rate_hz: float = FRAME_RATE, *,
                  time_s: np.ndarray | None = None, warn_mm: float = ERROR_WARN_MM,
                  warn_ratio: float = ERROR_WARN_RATIO, gaps: bool = True) -> dict:
    """Median and maximum of a per-frame error, with the warnings a summary must show.

    Parameters
    ----------
    per_frame_m : (frames,) array, metres
        The per-frame error of :func:`frame_errors` (RMS over the markers used); NaN frames
        (no marker) are left out of the statistics. Pass every frame that the result claims
        to fit (frame 0 included), so that every report of one result gives the same numbers.
    rate_hz : frame rate (Hz): frame k is at k / rate_hz seconds
    time_s : (frames,) array, s, optional: the frames' times, in place of k / rate_hz
    warn_mm : warn when the maximum exceeds this (mm)
    warn_ratio : warn when the maximum exceeds this many times the median
    gaps : warn about the frames without an error (False where the caller reports them)

    Returns
    -------
    dict
        ``median_mm``, ``max_mm`` (float, NaN without any frame), ``max_frame`` (int, -1
        without any frame), ``max_time_s``, ``frames`` (frames with an error),
        ``summary_mm`` (:func:`summary5`: min, q1, median, q3, max) and ``warnings`` (list of
        str, e.g. "maximum per-frame error 8.6 mm at 1.23 s is more than 1 mm").
    """
    e = np.asarray(per_frame_m, float).reshape(-1) * 1e3
    t = (np.arange(len(e)) / float(rate_hz) if time_s is None
         else np.asarray(time_s, float).reshape(-1))
    ok = np.isfinite(e)
    warnings: list[str] = []
    if not ok.any():
        return {"median_mm": float("nan"), "max_mm": float("nan"), "max_frame": -1,
                "max_time_s": float("nan"), "frames": 0,
                "summary_mm": dict.fromkeys(("min", "q1", "median", "q3", "max"), float("nan")),
                "warnings": ["no frame has a marker in both the model and the data"]}
    k = int(np.nanargmax(e))
    med, big = float(np.median(e[ok])), float(e[k])
    where = f"maximum per-frame error {big:.3g} mm at {t[k]:.2f} s"
    if big > warn_mm:
        warnings.append(f"{where} is more than {warn_mm:g} mm")
    if big > warn_ratio * med:
        warnings.append(f"{where} is more than {warn_ratio:g} x the median ({med:.3g} mm)")
    if gaps and not ok.all():
        warnings.append(f"{int((~ok).sum())} frames have no marker in both and are left out")
    return {"median_mm": med, "max_mm": big, "max_frame": k, "max_time_s": float(t[k]),
            "frames": int(ok.sum()), "summary_mm": summary5(e[ok]), "warnings": warnings}


def summary5(x: np.ndarray) -> dict:
    """min, first quartile, median, third quartile, max."""
    q = np.nanpercentile(x, [0, 25, 50, 75, 100])
    return dict(zip(("min", "q1", "median", "q3", "max"), map(float, q), strict=True))


def movement(data: np.ndarray, ok: np.ndarray | None = None) -> float:
    """Movement amplitude: 2 x RMS over markers of each marker's 3-D standard deviation.

    Parameters
    ----------
    data : (frames, markers, 3) array, any length unit; NaN where missing
    ok : (frames, markers) bool array, optional: the samples to use (default: the finite ones)

    Returns
    -------
    float, the unit of ``data``: each marker's deviation over its own frames with data (a marker
    with fewer than 2 is left out); NaN when no marker has 2.
    """
    data = np.asarray(data, float)
    use = np.all(np.isfinite(data), axis=-1)
    if ok is not None:
        use &= ok
    s = np.array([std3d(data[use[:, m], m]) if use[:, m].sum() >= 2 else np.nan
                  for m in range(data.shape[1])])
    s = s[np.isfinite(s)]
    return float(2.0 * np.sqrt(np.mean(s * s))) if len(s) else float("nan")


@dataclass(frozen=True)
class MarkerStatistics:
    """One marker's statistics of model against data.

    Attributes
    ----------
    corr3d_published, corr3d_unbiased : 3-D correlation (:func:`corr3d`; NaN: no motion)
    displacement : {"x", "y", "z"} -> Pearson r of the displacements from the first frame
    acceleration : the same of the accelerations; None for fewer than 5 frames
    """

    corr3d_published: float
    corr3d_unbiased: float
    displacement: dict
    acceleration: dict | None = None

    def as_dict(self) -> dict:
        out = {"corr3d_published": self.corr3d_published,
               "corr3d_unbiased": self.corr3d_unbiased, "displacement": self.displacement}
        if self.acceleration is not None:
            out["acceleration"] = self.acceleration
        return out


@dataclass(frozen=True)
class Comparison:
    """All statistics of a model's markers against data (:func:`compare`).

    Attributes
    ----------
    markers : name -> :class:`MarkerStatistics`
    frame_error_mm : five-number summary (min, q1, median, q3, max) of the per-frame error
        (:func:`frame_errors`), mm
    error : :func:`error_summary` of the per-frame error (median, maximum, warnings)
    movement_mm : movement amplitude of the data (:func:`movement`), mm
    frames : number of frames
    frames_skipped : frames without a marker in both (left out of every statistic)
    samples_skipped : marker-frames without data in both, among the other frames and the
        markers compared (left out of their frame's error and their marker's statistics)
    missing_markers : markers without a single frame in both (left out of everything)
    notes : how the inputs were brought together (resampled, laid on the model), one each
    """

    markers: dict
    frame_error_mm: dict
    error: dict
    movement_mm: float
    frames: int
    frames_skipped: int = 0
    samples_skipped: int = 0
    missing_markers: tuple = ()
    notes: tuple = ()

    @property
    def warnings(self) -> list:
        """The error summary's warnings (str)."""
        return self.error["warnings"]

    @property
    def gaps(self) -> list:
        """What was skipped for want of data, one sentence each (empty without gaps)."""
        n = len(self.markers) + len(self.missing_markers)
        used = (self.frames - self.frames_skipped) * len(self.markers)
        out = []
        if self.frames_skipped:
            out.append(f"{self.frames_skipped} of {self.frames} frames without data were "
                       "skipped")
        if self.samples_skipped:
            out.append(f"{self.samples_skipped} of {used} marker-frames without data were "
                       "skipped")
        if self.missing_markers:
            out.append(f"{len(self.missing_markers)} of {n} markers without data in both were "
                       f"left out: {', '.join(self.missing_markers)}")
        return out

    def as_dict(self) -> dict:
        """The statistics as JSON-ready nested dicts (NaN kept: see :func:`json_safe`)."""
        return {"markers": {n: m.as_dict() for n, m in self.markers.items()},
                "frame_error_mm": self.frame_error_mm, "error": self.error,
                "movement_mm": self.movement_mm, "frames": self.frames,
                "frames_skipped": self.frames_skipped, "samples_skipped": self.samples_skipped,
                "missing_markers": list(self.missing_markers), "notes": list(self.notes)}


def json_safe(obj):
    """A copy of nested dicts and lists with NaN and infinities as None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


def compare(a: np.ndarray, b: np.ndarray, names, rate: float = FRAME_RATE) -> Comparison:
    """All statistics of model ``a`` against data ``b``, over the samples with data in both.

    A frame without any marker in both is skipped, a marker-frame without data in both is left
    out of its frame's error and its marker's statistics, and a marker without a single frame
    in both is left out; the :class:`Comparison` counts each.

    Parameters
    ----------
    a, b : (frames, markers, 3) arrays, metres, the markers ``names`` in that order; NaN where
        missing
    names : marker names
    rate : frame rate, Hz (the times of the warnings, the acceleration's window)

    Returns
    -------
    Comparison
        Per-marker 3-D correlations (:func:`corr3d`) and per-axis correlations, the per-frame
        error's five-number summary and :func:`error_summary`, the movement (mm), the frames
        and what was skipped.

    Raises
    ------
    InputError
        When no marker has a frame with data in both (field: the marker, or ``markers``).
    """
    names = list(names)
    a, b = np.asarray(a, float), np.asarray(b, float)
    both = np.all(np.isfinite(a) & np.isfinite(b), axis=-1)  # (frames, markers)
    kept = both.any(axis=0)
    if not kept.any():
        raise InputError("no frame has data in both inputs" + (
            f" for the marker {names[0]}" if len(names) == 1 else " for any marker"),
            field=names[0] if len(names) == 1 else "markers")
    missing = tuple(n for n, k in zip(names, kept, strict=True) if not k)
    a, b, both = a[:, kept], b[:, kept], both[:, kept]
    per_marker = {}
    for m, name in enumerate(n for n, k in zip(names, kept, strict=True) if k):
        ax = axis_correlations(a[:, m], b[:, m], rate)
        per_marker[name] = MarkerStatistics(
            float(corr3d(a[:, m], b[:, m])), float(corr3d(a[:, m], b[:, m], published=False)),
            ax["displacement"], ax.get("acceleration"))
    summary = error_summary(frame_errors(a, b), rate, gaps=False)
    frames_with = both.any(axis=1)
    return Comparison(markers=per_marker, frame_error_mm=summary["summary_mm"], error=summary,
                      movement_mm=movement(b, both) * 1e3, frames=int(len(a)),
                      frames_skipped=int((~frames_with).sum()),
                      samples_skipped=int((~both[frames_with]).sum()), missing_markers=missing)
