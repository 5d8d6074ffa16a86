"""Muscle activity files: a ``time`` column (s), one column per muscle group, values in [0, 1]."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from ..params import EMG_CHANNELS, FRAME_RATE_HZ, MUSCLE_GROUPS
from ..plausibility import check_time_column
from .tables import read_table


def resample_to_frames(t: np.ndarray, values: np.ndarray, rate: float) -> tuple[np.ndarray,
                                                                               np.ndarray]:
    """Linear interpolation of (n, k) samples at times t onto a grid at ``rate`` Hz from t[0]."""
    n = int(np.floor((t[-1] - t[0]) * rate + 1e-3)) + 1  # tolerate rounded time stamps
    grid = t[0] + np.arange(n) / rate
    out = np.column_stack([np.interp(grid, t, values[:, j]) for j in range(values.shape[1])])
    return grid, out


def read_activity(path: str | Path, *,
                  frame_rate: float = FRAME_RATE_HZ) -> tuple[np.ndarray, np.ndarray]:
    """Read an activity CSV and return it at the frame rate.

    Columns are muscle groups (:data:`~facemech.params.MUSCLE_GROUPS`, case-insensitive);
    groups without a column are inactive. Samples not at the frame rate are interpolated
    linearly onto a ``frame_rate`` grid.

    Returns
    -------
    time : (frames,) s
    activity : (frames, groups) in [0, 1]
    """
    t, cols = read_table(path)
    cols.pop("__meta__")
    check_time_column(t, kind="control", source=str(path))
    act = np.zeros((len(t), len(MUSCLE_GROUPS)))
    if not cols:
        raise InputError("no muscle columns", source=str(path), field="header")
    for name, v in cols.items():
        key = name.strip().upper()
        if key not in MUSCLE_GROUPS:
            raise InputError(f"unknown muscle group (expected some of {', '.join(MUSCLE_GROUPS)})",
                             source=str(path), field=name)
        bad = ~np.isfinite(v) | (v < 0) | (v > 1)
        if bad.any():
            r = int(np.nonzero(bad)[0][0])
            what = ("is empty or NaN" if np.isnan(v[r])
                    else f"value {float(v[r]):g} is outside [0, 1]")
            raise InputError(f"row {r + 1}: {what}", source=str(path), field=name)
        act[:, MUSCLE_GROUPS.index(key)] = v
    d = np.diff(t) * frame_rate
    if np.max(np.abs(d - 1.0)) > 1e-3:  # not already at the frame rate
        t, act = resample_to_frames(t, act, frame_rate)
    return t, act


def write_activity(path: str | Path, time: np.ndarray, activity: np.ndarray,
                   groups: tuple[str, ...] = MUSCLE_GROUPS) -> None:
    """Write an activity table (frames, groups) as CSV, atomically."""
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write("time," + ",".join(groups) + "\n")
        for k in range(len(time)):
            fh.write(f"{time[k]:.6f}," + ",".join(f"{a:.6f}" for a in activity[k]) + "\n")


def seven_channel_control(channels: dict[str, np.ndarray]) -> np.ndarray:
    """Group activity (frames, groups) from the seeds' EMG channels.

    The channels are those of :data:`~facemech.params.EMG_CHANNELS` (LLS, LAO, DAO, DLI, MEN,
    OOS, OOI); zygomatic major follows levator anguli oris (they share one signal in Lucero &
    Munhall 1999, II.C). Left and right sides are driven alike. Other groups stay at zero.
    """
    n = len(next(iter(channels.values())))
    act = np.zeros((n, len(MUSCLE_GROUPS)))
    for name, v in channels.items():
        act[:, MUSCLE_GROUPS.index(name)] = v
    if "LAO" in channels and "ZYG" not in channels:
        act[:, MUSCLE_GROUPS.index("ZYG")] = channels["LAO"]
    return act


__all__ = ["read_activity", "write_activity", "seven_channel_control", "EMG_CHANNELS"]
