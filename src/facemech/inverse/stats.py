"""3-D statistics of trajectories (Pitermann & Munhall 2001, eqs. 5-7) and per-axis
cross-correlations of displacement and acceleration (Lucero & Munhall 1999, Tables III-IV).

All functions take trajectories as (frames, 3) or (frames, markers, 3) arrays in metres.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter


def centroid(v: np.ndarray) -> np.ndarray:
    """mu_v = (1/n) sum_i v_i (eq. 5)."""
    return np.mean(v, axis=0)


def std3d(v: np.ndarray) -> np.ndarray:
    """sigma_v = sqrt(sum_i |v_i - mu_v|^2 / (n - 1)) (eq. 6)."""
    d = v - centroid(v)
    return np.sqrt(np.sum(d * d, axis=(0, -1)) / (len(v) - 1))


def corr3d(v: np.ndarray, w: np.ndarray, *, published: bool = True) -> np.ndarray:
    """3-D correlation of two trajectories.

    ``published=True`` is eq. 7 as printed: ``(1/n sum v_i . w_i - mu_v . mu_w) / (sigma_v
    sigma_w)`` with the (n - 1) sigmas of eq. 6, so a trajectory correlates with itself at
    (n - 1) / n; ``published=False`` uses 1/(n - 1) in the numerator too (exactly 1 for v = w).
    """
    n = len(v)
    num = np.sum(v * w, axis=(0, -1)) / n - np.sum(centroid(v) * centroid(w), axis=-1)
    if not published:
        num = num * n / (n - 1)
    return num / (std3d(v) * std3d(w))


def acceleration(x: np.ndarray, rate: float, window_s: float = 0.1, order: int = 3) -> np.ndarray:
    """Second derivative along axis 0 by a Savitzky-Golay filter (unit per s^2).

    The window (``window_s``, odd, at least ``order + 2`` samples) shrinks to the series'
    length; a series too short for it gives zeros.
    """
    n = len(x)
    win = max(order + 2, int(round(window_s * rate)) | 1)
    if win > n:
        win = n if n % 2 else n - 1
    if win <= order:
        return np.zeros_like(x)
    return savgol_filter(x, win, order, deriv=2, delta=1.0 / rate, axis=0)


def cross_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Zero-lag normalised cross-correlation (Pearson) of two series (NaN if one is flat)."""
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt(np.sum(a * a) * np.sum(b * b))
    return float(np.sum(a * b) / den) if den > 0 else float("nan")


def axis_correlations(a: np.ndarray, b: np.ndarray, rate: float = 60.0) -> dict:
    """Per-axis Pearson correlations of displacement and of acceleration (Savitzky-Golay,
    0.1-s cubic; left out for fewer than 5 frames)."""
    out = {}
    for kind in ("displacement", "acceleration"):
        x, y = a - a[0], b - b[0]
        if kind == "acceleration":
            if len(a) < 5:
                continue
            x, y = acceleration(x, rate), acceleration(y, rate)
        out[kind] = {ax: cross_correlation(x[:, i], y[:, i]) for i, ax in enumerate("xyz")}
    return out


def frame_errors(model: np.ndarray, data: np.ndarray) -> np.ndarray:
    """Per-frame error sqrt(E / N), E = sum_i |m_i - n_i|^2 over the N markers (frames,)."""
    d = model - data
    ok = np.all(np.isfinite(d), axis=-1)
    e = np.where(ok, np.sum(np.where(ok[..., None], d, 0.0) ** 2, axis=-1), 0.0)
    return np.sqrt(e.sum(axis=1) / np.maximum(ok.sum(axis=1), 1))


def summary5(x: np.ndarray) -> dict:
    """min, first quartile, median, third quartile, max."""
    q = np.nanpercentile(x, [0, 25, 50, 75, 100])
    return dict(zip(("min", "q1", "median", "q3", "max"), map(float, q), strict=True))


def movement(data: np.ndarray) -> float:
    """Movement amplitude: 2 x RMS over markers of each marker's 3-D standard deviation."""
    s = np.array([std3d(data[:, m]) for m in range(data.shape[1])])
    return float(2.0 * np.sqrt(np.mean(s * s)))


def compare(a: np.ndarray, b: np.ndarray, names, rate: float = 60.0) -> dict:
    """All statistics of model ``a`` against data ``b`` (frames, markers, 3), metres -> mm."""
    per_marker = {}
    for m, name in enumerate(names):
        per_marker[name] = {
            "corr3d_published": float(corr3d(a[:, m], b[:, m])),
            "corr3d_unbiased": float(corr3d(a[:, m], b[:, m], published=False)),
            **axis_correlations(a[:, m], b[:, m], rate),
        }
    err = frame_errors(a, b) * 1e3
    return {"markers": per_marker, "frame_error_mm": summary5(err),
            "movement_mm": movement(b) * 1e3, "frames": int(len(a))}


def error_summary(per_frame_m, rate: float = 60.0) -> dict:  # TEMPORARY until merge
    e = np.asarray(per_frame_m, float) * 1e3
    med, mx = float(np.nanmedian(e)), float(np.nanmax(e))
    w = []
    if mx > 1.0 or mx > 5 * med:
        w.append(f"maximum per-frame error {mx:.2f} mm at {np.nanargmax(e) / rate:.2f} s")
    return {"median_mm": med, "max_mm": mx, "warnings": w}
