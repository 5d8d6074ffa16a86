"""How well a re-animation follows each sensor, axis by axis.

For a sensor's coordinate along one axis, model ``m(t)`` and measured ``d(t)`` over the frames
where the sensor was recorded (metres in, mm out):

    rms = sqrt(mean((m - d)^2)),  largest = max |m - d|,
    corr = Pearson's r of m and d,  range share = (max m - min m) / (max d - min d),

the range share saying how much of the recorded excursion the model makes (1: all of it;
above 1: more). An axis along which the data do not vary (midsagittal articulography, whose x
is set to the model point's) is left out.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from ..kinematics.stats import cross_correlation

__all__ = ["AxisFit", "fit_from_json", "fit_lines", "fit_to_json", "sensor_fit"]

#: m: an axis whose recorded range is below this is constant (not fitted; left out)
CONSTANT_RANGE_M = 1e-9


@dataclass(frozen=True)
class AxisFit:
    """The fit of one sensor along one axis.

    Attributes
    ----------
    sensor, axis : the sensor's name and "x", "y" or "z"
    rms_mm, largest_mm : RMS and largest model-data difference, mm
    corr : Pearson's correlation of model and data over time (nan where the model is still)
    range_share : the model's range over the recorded range
    samples : frames the sensor was recorded in
    """

    sensor: str
    axis: str
    rms_mm: float
    largest_mm: float
    corr: float
    range_share: float
    samples: int


def sensor_fit(model: np.ndarray, measured: np.ndarray, names) -> list[AxisFit]:
    """The fit of every sensor along every axis the data vary along.

    Parameters
    ----------
    model, measured : (frames, sensors, 3) m; NaN where a sensor was not recorded
    names : (sensors,) names

    Returns
    -------
    list of AxisFit, sensor by sensor, x y z
    """
    model, measured = np.asarray(model, float), np.asarray(measured, float)
    out = []
    for j, name in enumerate(names):
        ok = np.all(np.isfinite(measured[:, j]), axis=1) & np.all(np.isfinite(model[:, j]), axis=1)
        for a, axis in enumerate("xyz"):
            d, m = measured[ok, j, a], model[ok, j, a]
            if len(d) == 0 or np.ptp(d) < CONSTANT_RANGE_M:
                continue
            diff = (m - d) * 1e3
            out.append(AxisFit(str(name), axis, float(np.sqrt(np.mean(diff ** 2))),
                               float(np.max(np.abs(diff))), cross_correlation(m, d),
                               float(np.ptp(m) / np.ptp(d)), int(ok.sum())))
    return out


def fit_lines(fits: list[AxisFit]) -> list[str]:
    """One line per sensor: each axis's RMS, largest error, correlation and range share."""
    by: dict[str, list[AxisFit]] = {}
    for f in fits:
        by.setdefault(f.sensor, []).append(f)
    return [f"{s}: " + "; ".join(f"{f.axis} RMS {f.rms_mm:.2f} mm, largest {f.largest_mm:.2f} "
                                 f"mm, r {f.corr:.2f}, range {100 * f.range_share:.0f} %"
                                 for f in fs) for s, fs in by.items()]


def fit_to_json(fits: list[AxisFit]) -> str:
    """The fits as a JSON list of objects (the results' ``sensor_fit`` attribute)."""
    return json.dumps([{k: (None if isinstance(v, float) and not np.isfinite(v) else v)
                        for k, v in asdict(f).items()} for f in fits])


def fit_from_json(text: str) -> list[AxisFit]:
    """The fits from :func:`fit_to_json`'s text."""
    return [AxisFit(**{k: (float("nan") if v is None else v) for k, v in row.items()})
            for row in json.loads(text)]
