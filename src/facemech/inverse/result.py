"""The result of an inversion: controls with their uncertainty, the re-animation, diagnostics.

An :class:`Inversion` writes itself to the same NetCDF layout as a forward simulation
(:func:`facemech.io.results.to_dataset`), plus the inversion's own variables, so that every
command that reads results (render, still, compare, export) reads it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass(frozen=True, eq=False)
class Inversion:
    """Activity and jaw recovered from markers.

    Attributes
    ----------
    time : (frames,) s
    positions : (frames, n_surface, 3) m, the re-animated skin
    marker_names, marker_nodes : the data's markers that were used and their model nodes
    data_markers : (frames, markers, 3) m
    activity : (frames, groups) group activity of each frame's interval (the last row repeats the
        one before)
    jaw_angle : (frames,) rad; ``jaw_pose`` (frames, 3) when a pose series drove the jaw
    control_names, controls : the inverted controls (frames, c), the jaw last when estimated,
        in units of ``frame.JAW_UNIT`` rad
    control_se : (frames, c) standard errors of the controls (same units)
    identifiability : (c,) mm per unit (see :mod:`facemech.inverse.uncertainty`)
    identifiable : (c,) bool: the markers determine the control (at the noise level)
    combinations : the combinations of controls the markers measure
        (:mod:`facemech.inverse.combinations`), in pivot order
    noise_mm : marker noise used for the standard errors (mm); ``noise_how`` says where from
    rms_error : (frames,) m, the per-frame error: RMS over the markers used of the distance
        between model and data (frame 0: the model at rest against the first frame)
    markers_used, on_bound, condition, evaluations : per-frame diagnostics
    muscles : :class:`~facemech.physics.muscle_outputs.MuscleSeries` of the re-animation:
        tension (N), length (m), lengthening velocity (m/s), activation state (N) per muscle
        instance and frame
    """

    model: object
    params: object
    time: np.ndarray
    positions: np.ndarray
    marker_names: tuple
    marker_nodes: np.ndarray
    data_markers: np.ndarray
    activity: np.ndarray
    jaw_angle: np.ndarray
    jaw_pose: np.ndarray | None
    control_names: tuple
    controls: np.ndarray
    control_se: np.ndarray
    identifiability: np.ndarray
    identifiable: np.ndarray
    noise_mm: float
    noise_how: str
    rms_error: np.ndarray
    markers_used: np.ndarray
    on_bound: np.ndarray
    condition: np.ndarray
    evaluations: np.ndarray
    method: object
    positive: bool
    integrator: str
    dt: float
    wall_seconds: float
    notes: list = field(default_factory=list)
    source: str | None = None
    muscles: object = None  # MuscleSeries: force, length, velocity, activation per instance
    combinations: tuple = ()

    @property
    def sensor_fit(self) -> list:
        """The fit per sensor and axis (:func:`facemech.inverse.sensor_fit.sensor_fit`)."""
        from .sensor_fit import sensor_fit

        return sensor_fit(self.markers, self.data_markers, self.marker_names)

    @property
    def markers(self) -> np.ndarray:
        """(frames, markers, 3) m: the model's nodes of the data's markers."""
        return self.positions[:, self.marker_nodes]

    model_markers = markers

    @property
    def jaw_shift(self) -> np.ndarray:
        """(frames, 2) m, the condyles' shift (y, z): the pose series' where one drove the jaw,
        else the preset's jaw kinematics of the angle (:func:`~facemech.solvers.jaw.jaw_poses`,
        as the stepper moved it)."""
        if self.jaw_pose is not None:
            return self.jaw_pose[:, 1:]
        from ..solvers.jaw import jaw_poses

        return jaw_poses(self.jaw_angle, self.params)[:, 1:]

    def error_summary(self) -> dict:
        """Median and maximum per-frame error (mm), with warnings (see
        :func:`facemech.kinematics.stats.error_summary`)."""
        from ..kinematics.stats import error_summary

        return error_summary(self.rms_error, float(self.params.frame_rate), time_s=self.time)

    @property
    def attrs(self) -> dict:
        from .combinations import to_json
        from .determined import regularised
        from .sensor_fit import fit_to_json

        s = self.error_summary()
        m = self.method
        opts = {k: getattr(m, k) for k in m.__dataclass_fields__}
        return {
            "title": "facemech inversion",
            "inversion_method": m.name,
            "inversion_options": json.dumps(opts),
            "positive": int(self.positive),
            "controls": ",".join(self.control_names),
            "error_definition": "per frame: RMS over the markers used of the model-data "
                                "distance",
            "rms_error_mm_median": s["median_mm"],
            "rms_error_mm_max": s["max_mm"],
            "noise_mm": float(self.noise_mm),
            "noise_source": self.noise_how,
            "condition_median": float(np.nanmedian(self.condition))
            if np.isfinite(self.condition).any() else -1.0,
            "notes": " | ".join(self.notes + s["warnings"]),
            "sensor_fit": fit_to_json(self.sensor_fit),
            "combinations": to_json(self.combinations),
            "combinations_determined": ",".join(
                c.name for c in self.combinations if c.determined(self.noise_mm)),
            "regularised": ",".join(regularised(self.combinations, self.identifiable,
                                                self.control_names)),
        }

    def variables(self) -> dict:
        """The inversion's own variables: name -> (dims, values, attrs)."""
        out = {
            "rms_error": (("time",), self.rms_error, {"units": "m", "long_name":
                          "per-frame RMS over the markers used of the model-data distance"}),
            "markers_used": (("time",), self.markers_used, {"units": "1"}),
            "condition": (("time",), self.condition, {"units": "1"}),
            "data_markers": (("time", "marker", "axis"), self.data_markers,
                             {"units": "m", "long_name": "the inverted marker data"}),
            "controls": (("time", "control"), self.controls, {"units": "1 (jaw: 0.1 rad)"}),
            "control_se": (("time", "control"), self.control_se,
                           {"units": "1 (jaw: 0.1 rad)", "long_name": "standard error"}),
            "identifiability": (("control",), self.identifiability,
                                {"units": "mm per unit", "long_name": "marker motion of a "
                                 "sustained unit change that no other control reproduces"}),
            "identifiable": (("control",), self.identifiable.astype(np.int8), {"units": "1"}),
            "on_bound": (("time", "control"), self.on_bound.astype(np.int8), {"units": "1"}),
        }
        if self.combinations:
            sigma = max(float(self.noise_mm), 0.1) if np.isfinite(self.noise_mm) else 0.1
            out["combination_activity"] = (
                ("time", "combination"),
                np.column_stack([c.of(self.controls, self.control_names)
                                 for c in self.combinations]),
                {"units": "1 (jaw: 0.1 rad)", "long_name": "the combinations of controls the "
                 "markers measure (attribute combinations: their weights)"})
            out["combination_se"] = (("combination",), np.array([c.se(sigma) for c in
                                                                 self.combinations]),
                                     {"units": "1", "long_name": "standard error at the noise"})
        return out

    def to_dataset(self, inputs: dict | None = None):
        """An :class:`xarray.Dataset` in the results layout (see :mod:`facemech.io.results`)."""
        from ..io.results import to_dataset

        ds = to_dataset(self, inputs, self.variables())
        ds = ds.assign_coords(control=list(self.control_names))
        if self.combinations:
            ds = ds.assign_coords(combination=[c.name for c in self.combinations])
        return ds

    def write(self, path: str | Path, inputs: dict | None = None) -> Path:
        """Write the results file (NetCDF) atomically."""
        from ..io.results import write_dataset

        return write_dataset(path, self.to_dataset(inputs))
