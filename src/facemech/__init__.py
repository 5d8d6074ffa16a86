"""facemech: physics and kinematics of the speaking face.

A three-layer mass-spring-damper face moved by Hill-type muscles and a jaw hinge, driven by
processed EMG or by muscle activity (Lucero & Munhall 1999). SI units inside; +x the subject's
left, +y up, +z forward.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("facemech")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0+unknown"

from .emg import EMGActivity, process_emg
from .errors import FacemechError, InputError, SimulationBlowUp
from .geometry.builder import BuildOptions, FaceModel, build_face, default_face, load_face
from .geometry.surface_io import read_landmarks, read_surface
from .io.activity import read_activity, seven_channel_control, write_activity
from .io.emg import read_emg
from .io.markers import read_marker_csv, read_markers, write_marker_csv, write_markers
from .io.results import read_results, write_results
from .kinematics.frames import align_to_model, to_anatomical_frame
from .kinematics.gaps import fill_gaps, find_gaps
from .kinematics.mapping import closest_nodes, read_mapping, scale_adapt, warp_face
from .kinematics.resample import derivative, resample
from .kinematics.rigid import head_correct, rigid_fit
from .markerset import MarkerSet
from .params import (
    EMG_CHANNELS,
    MUSCLE_GROUPS,
    PRESETS,
    Parameters,
    default_parameters,
    preset,
    read_preset,
    write_preset,
)
from .physics.assembly import Physics
from .solvers.forward import Simulation, simulate
from .solvers.jaw import angles_from_chin, jaw_angles_from_marker
from .solvers.state import State
from .solvers.step import INTEGRATORS, Stepper

#: pictures and exports, imported on first use (they load the renderer's kernels)
_LAZY = {
    "RenderOptions": "facemech.viz.video", "render_results": "facemech.viz.video",
    "still": "facemech.viz.video", "write_viewer": "facemech.viz.viewer",
    "export_results": "facemech.io.export",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'facemech' has no attribute {name!r}")


__all__ = [
    "__version__", "RenderOptions", "render_results", "still", "write_viewer", "export_results",
    "BuildOptions", "EMGActivity", "EMG_CHANNELS", "FaceModel", "FacemechError",
    "INTEGRATORS", "InputError", "MUSCLE_GROUPS", "MarkerSet", "PRESETS", "Parameters", "Physics",
    "Simulation", "SimulationBlowUp", "State", "Stepper", "align_to_model", "angles_from_chin",
    "build_face", "closest_nodes", "default_face", "default_parameters", "derivative", "fill_gaps",
    "find_gaps", "head_correct", "jaw_angles_from_marker", "load_face", "preset", "process_emg",
    "read_activity", "read_emg", "read_landmarks", "read_mapping", "read_marker_csv",
    "read_markers", "read_preset", "read_results", "read_surface", "resample", "rigid_fit",
    "scale_adapt", "seven_channel_control", "simulate", "to_anatomical_frame", "warp_face",
    "write_activity", "write_marker_csv", "write_markers", "write_preset", "write_results",
]
