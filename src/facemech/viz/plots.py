"""Kinematic plots like Figs. 4-6 of Lucero & Munhall (1999): vertical (y) and protrusion (z)
displacement and acceleration of a marker against time, simulated and (optionally) measured,
with their cross-correlation."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..kinematics.stats import acceleration, cross_correlation
from ..params import FRAME_RATE_HZ


def subplots(nrows: int = 1, ncols: int = 1, *, figsize, **kw):
    """A figure and its axes, made without pyplot: no backend is chosen or switched (a
    notebook's stays as it is) and nothing is kept alive after the figure is dropped."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kw)


def save_figure(fig, path: str | Path, title: str = "") -> Path:
    """Title, lay out and write a figure as PNG (atomically)."""
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=110)
    return Path(path)


def kinematics_figure(path: str | Path, time: np.ndarray, trajectories: dict[str, np.ndarray],
                      *, rate: float = FRAME_RATE_HZ, measured: dict[str, np.ndarray] | None = None,
                      title: str = "") -> Path:
    """Write a PNG with, per marker, displacement and acceleration in y and z.

    Parameters
    ----------
    time : (frames,) s
    trajectories : name -> (frames, 3) positions in metres (simulated)
    measured : name -> (frames, 3) measured positions in metres (dashed), optional
    """
    names = list(trajectories)
    fig, axes = subplots(4, len(names), figsize=(3.2 * len(names), 8.5), sharex=True,
                             squeeze=False)
    rows = [("y displacement (mm)", 1, False), ("z displacement (mm)", 2, False),
            ("y acceleration (m/s²)", 1, True), ("z acceleration (m/s²)", 2, True)]
    for c, name in enumerate(names):
        sim = trajectories[name] - trajectories[name][0]
        meas = None
        if measured is not None and name in measured:
            meas = measured[name] - measured[name][0]
        for r, (label, axis, acc) in enumerate(rows):
            ax = axes[r, c]
            s = acceleration(sim[:, axis], rate) if acc else sim[:, axis] * 1e3
            ax.plot(time, s, "k-", lw=1.2, label="model")
            if meas is not None:
                m = acceleration(meas[:, axis], rate) if acc else meas[:, axis] * 1e3
                ax.plot(time, m, "k--", lw=1.0, label="measured")
                ax.set_title(f"r = {cross_correlation(s, m):.2f}", fontsize=8)
            if c == 0:
                ax.set_ylabel(label, fontsize=8)
            if r == 0:
                ax.set_title(name if meas is None else f"{name}  {ax.get_title()}", fontsize=9)
                if meas is not None:
                    ax.legend(fontsize=7, loc="best", frameon=False)
            ax.tick_params(labelsize=7)
        axes[-1, c].set_xlabel("time (s)", fontsize=8)
    return save_figure(fig, path, title)


def activity_figure(path: str | Path, time: np.ndarray, activity: np.ndarray,
                    groups: tuple[str, ...], jaw_angle: np.ndarray | None = None) -> Path:
    """Write a PNG of the muscle activity (and jaw angle) driving a simulation."""
    used = [g for g in range(activity.shape[1]) if np.any(activity[:, g] > 0)]
    n = len(used) + (jaw_angle is not None)
    fig, axes = subplots(max(n, 1), 1, figsize=(7, 0.9 * max(n, 1) + 0.8), sharex=True,
                             squeeze=False)
    for r, g in enumerate(used):
        axes[r, 0].fill_between(time, activity[:, g], color="0.35", lw=0)
        axes[r, 0].set_ylim(0, 1.05)
        axes[r, 0].set_ylabel(groups[g], rotation=0, ha="right", fontsize=8)
        axes[r, 0].tick_params(labelsize=7)
    if jaw_angle is not None:
        axes[-1, 0].plot(time, np.degrees(jaw_angle), "k-")
        axes[-1, 0].set_ylabel("jaw (°)", rotation=0, ha="right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    return save_figure(fig, path)


def inversion_figure(path: str | Path, time: np.ndarray, controls: np.ndarray,
                     names: tuple[str, ...], *, truth: np.ndarray | None = None,
                     rms_error: np.ndarray | None = None, se: np.ndarray | None = None,
                     identifiable: np.ndarray | None = None, title: str = "",
                     fit: tuple | None = None, combinations=(), noise_mm: float = 0.1) -> Path:
    """Write a PNG of inverted controls, one panel per control, and the fit.

    Parameters
    ----------
    time : (frames,) s
    controls : (frames, c) recovered controls (the last frame repeats the one before); a
        control named ``jaw`` is drawn in degrees (its values are in units of 0.1 rad)
    names : the c control names
    truth : (frames, c) known controls (dashed), for synthetic data
    rms_error : (frames,) per-frame RMS marker error in metres (bottom panel)
    se : (frames, c) standard errors: a band of +-2 SE (about 95 %)
    identifiable : (c,) bool: controls the markers do not determine are drawn grey and
        labelled "regularised"
    fit : (sensor names, model (frames, sensors, 3) m, measured (frames, sensors, 3) m): a
        panel per sensor and axis the data vary along, model against measured
    combinations : :class:`~facemech.inverse.combinations.Combination` the markers measure, a
        panel each with +-2 SE at ``noise_mm`` (drawn when some control is not determined)
    """
    from .plots_fit import combination_panel, control_panel, sensor_panels

    seen_all = identifiable is None or bool(np.all(identifiable))
    combos = [] if seen_all else list(combinations)
    fits = sensor_panels(None, time, *fit) if fit is not None else 0
    n = len(names) + len(combos) + fits + (rms_error is not None)
    fig, axes = subplots(n, 1, figsize=(7, 0.85 * n + 1.0), sharex=True, squeeze=False)
    lo = min(0.0, float(np.min(controls)))
    for r, name in enumerate(names):
        control_panel(axes[r, 0], time, controls[:, r], name, lo=lo,
                      se=None if se is None else se[:, r],
                      truth=None if truth is None else truth[:, r],
                      seen=identifiable is None or bool(identifiable[r]))
    if truth is not None or se is not None:
        axes[0, 0].legend(fontsize=7, loc="upper right", frameon=False, ncol=3)
    r = len(names)
    for k, c in enumerate(combos):
        combination_panel(axes[r + k, 0], time, c, controls, names, noise_mm)
    r += len(combos)
    if fit is not None:
        sensor_panels(axes[r:r + fits, 0], time, *fit)
    if rms_error is not None:
        ax = axes[-1, 0]
        ax.plot(time, rms_error * 1e3, "k.-", lw=0.8, ms=3)
        ax.set_ylabel("error\n(mm)", rotation=0, ha="right", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("time (s)")
    return save_figure(fig, path, title)
