"""facemech: physics and kinematics of the speaking face.

A three-layer mass-spring-damper face moved by Hill-type muscles and a jaw hinge, driven by
processed EMG or by muscle activity (Lucero & Munhall 1999). SI units inside; +x the subject's
left, +y up, +z forward.
"""

import importlib as _importlib
import os as _os

from ._version import __version__


def _numba_cache_dir(package_dir: str, environ, writable) -> str | None:
    """Where numba should cache compiled kernels, or None to leave numba's own choice.

    numba caches beside the sources (``__pycache__``), else under the user's cache folder, and
    fails with a traceback when it can write neither. When the installed package cannot be
    written and no ``NUMBA_CACHE_DIR`` is set, a per-user folder in the temporary directory is
    used instead. Importing facemech changes no environment variable: the command line
    (:func:`facemech.cli.main`) sets ``NUMBA_CACHE_DIR`` from this before numba starts; a
    program that imports the library from a read-only installation sets it itself.
    """
    if environ.get("NUMBA_CACHE_DIR") or writable(package_dir):
        return None
    import tempfile

    return _os.path.join(tempfile.gettempdir(), f"facemech-numba-cache-{_os.getuid()}")


#: every public name and the module that defines it; each module is imported on first use, so
#: ``import facemech`` (and the command line's start) loads neither numba nor scipy
_PUBLIC = {
    "BuildOptions": "facemech.geometry.builder",
    "EMGActivity": "facemech.emg",
    "EMG_CHANNELS": "facemech.params",
    "FaceModel": "facemech.geometry.builder",
    "FacemechError": "facemech.errors",
    "INTEGRATORS": "facemech.solvers.step",
    "InputError": "facemech.errors",
    "MUSCLE_GROUPS": "facemech.params",
    "MarkerSet": "facemech.markerset",
    "Model": "facemech.physics.model",
    "PRESETS": "facemech.params",
    "Parameters": "facemech.params",
    "Physics": "facemech.physics.assembly",
    "RenderOptions": "facemech.viz.video",
    "Simulation": "facemech.solvers.forward",
    "SimulationBlowUp": "facemech.errors",
    "State": "facemech.solvers.state",
    "Stepper": "facemech.solvers.step",
    "align_to_model": "facemech.kinematics.frames",
    "angles_from_chin": "facemech.solvers.jaw",
    "build_face": "facemech.geometry.builder",
    "closest_nodes": "facemech.kinematics.mapping",
    "default_face": "facemech.geometry.builder",
    "default_parameters": "facemech.params",
    "derivative": "facemech.kinematics.resample",
    "drop_empty_ends": "facemech.kinematics.trim",
    "export_results": "facemech.io.export",
    "fill_gaps": "facemech.kinematics.gaps",
    "find_gaps": "facemech.kinematics.gaps",
    "head_correct": "facemech.kinematics.rigid",
    "jaw_angles_from_marker": "facemech.solvers.jaw_drive",
    "load_face": "facemech.geometry.builder",
    "model": "facemech.physics.model",
    "preset": "facemech.params",
    "process_emg": "facemech.emg",
    "read_activity": "facemech.io.activity",
    "read_emg": "facemech.io.emg",
    "read_landmarks": "facemech.geometry.surface_io",
    "read_mapping": "facemech.kinematics.mapping",
    "read_marker_csv": "facemech.io.markers",
    "read_markers": "facemech.io.markers",
    "read_preset": "facemech.params",
    "read_results": "facemech.io.results",
    "read_surface": "facemech.geometry.surface_io",
    "render_results": "facemech.viz.video",
    "resample": "facemech.kinematics.resample",
    "rigid_fit": "facemech.kinematics.rigid",
    "scale_adapt": "facemech.kinematics.mapping",
    "seven_channel_control": "facemech.io.activity",
    "simulate": "facemech.solvers.forward",
    "still": "facemech.viz.video",
    "to_anatomical_frame": "facemech.kinematics.frames",
    "trim": "facemech.kinematics.trim",
    "warp_face": "facemech.kinematics.mapping",
    "write_activity": "facemech.io.activity",
    "write_marker_csv": "facemech.io.markers",
    "write_markers": "facemech.io.markers",
    "write_preset": "facemech.params",
    "write_results": "facemech.io.results",
    "write_viewer": "facemech.viz.viewer",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    try:
        module = _PUBLIC[name]
    except KeyError:
        raise AttributeError(f"module 'facemech' has no attribute {name!r}") from None
    value = getattr(_importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
