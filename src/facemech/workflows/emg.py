"""EMG workflows: raw EMG recordings (and their calibration) to normalised muscle activity."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from ..errors import InputError


def frame_rate(rate: float | None = None) -> float:
    """``rate`` (Hz), or the default parameters' frame rate (:attr:`Parameters.frame_rate`)."""
    if rate is not None:
        return float(rate)
    from ..params import default_parameters

    return float(default_parameters().frame_rate)


def as_interval(value: str | Sequence[float] | None, field: str) -> tuple[float, float] | None:
    """A time interval (start, stop) in s from a pair, or from text ``"START,STOP"``.

    Raises :class:`~facemech.errors.InputError` naming ``field`` for text that is not two
    finite numbers from 0 s, or an interval whose stop is not after its start.
    """
    if value is None:
        return None
    try:
        a, b = (float(v) for v in (value.split(",") if isinstance(value, str) else value))
    except (TypeError, ValueError):
        raise InputError("expected START,STOP in seconds", field=field) from None
    if not (math.isfinite(a) and math.isfinite(b) and a >= 0):
        raise InputError(f"START,STOP must be finite seconds from 0, got {value}", field=field)
    if not b > a:
        raise InputError("STOP must be after START", field=field)
    return a, b


def emg_activity(emg: str | Path, *, rate: float | None = None,
                 baseline: str | Sequence[float] | None = None,
                 calibration: str | Path | None = None,
                 calibration_baseline: str | Sequence[float] | None = None,
                 baseline_field: str = "baseline"):
    """Read a raw EMG recording (and a calibration recording) and process it to activity.

    Rectify, integrate (17-ms trapezoid), downsample and normalise
    (:func:`facemech.emg.process_emg`).

    Parameters
    ----------
    emg : raw EMG, CSV (time + one column per channel) or C3D analog
    rate : output rate, Hz (default: the parameters' frame rate)
    baseline : rest interval (start, stop) s in the recording, or ``"START,STOP"``
    calibration : a recording of maximal gestures with the same channels, in the same order
    calibration_baseline : rest interval of the calibration recording, s
    baseline_field : the option named in an error about ``baseline``

    Returns
    -------
    facemech.emg.EMGActivity : time (frames,) s, activity (frames, channels) in [0, 1]

    Raises
    ------
    InputError
        When the calibration's channels differ from the recording's (field ``header``).
    """
    from ..emg import process_emg
    from ..io.emg import read_emg

    sig, fs, names = read_emg(emg)
    cal = cal_fs = None
    if calibration is not None:
        cal, cal_fs, cal_names = read_emg(calibration)
        if tuple(n.upper() for n in cal_names) != tuple(n.upper() for n in names):
            raise InputError("calibration channels differ from the recording's",
                             source=str(calibration), field="header")
    return process_emg(sig, fs, names, out_rate=frame_rate(rate),
                       baseline=as_interval(baseline, baseline_field), calibration=cal,
                       calibration_rate=cal_fs,
                       calibration_baseline=as_interval(calibration_baseline,
                                                         "calibration-baseline"),
                       source=str(emg))


def process_emg_file(emg: str | Path, output: str | Path, *, rate: float | None = None,
                     baseline: str | Sequence[float] | None = None,
                     calibration: str | Path | None = None,
                     calibration_baseline: str | Sequence[float] | None = None):
    """:func:`emg_activity` written to an activity CSV ``output`` (time + channels).

    Returns
    -------
    Written : ``data`` the :class:`facemech.emg.EMGActivity`
    """
    from ..io.activity import write_activity
    from .outcome import Written

    rate = frame_rate(rate)
    from ..atomic import check_output

    check_output(output, [emg, calibration], field="-o")
    res = emg_activity(emg, rate=rate, baseline=baseline, calibration=calibration,
                       calibration_baseline=calibration_baseline)
    write_activity(output, res.time, res.activity, res.channels)
    return Written(Path(output), res, f"{len(res.time)} frames at {rate:g} Hz, channels "
                   f"{', '.join(res.channels)} -> {output}",
                   "".join(f"facemech: note: {n}\n" for n in res.notes))
