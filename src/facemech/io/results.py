"""Simulation results as NetCDF (xarray, h5netcdf engine), written atomically.

Variables: ``positions`` (time, node, axis; m, epidermal nodes), ``markers`` (time, marker,
axis; m, landmarks and virtual markers), ``activity`` (time, muscle; 1), the jaw's pose:
``jaw_angle`` (time; rad) and ``jaw_shift`` (time, shift_axis; m, the condyles' shift along y
and z; files written before it existed read as zeros) and the surface ``triangles`` (triangle,
corner) so that the file renders on its own. A
face built from a textured or coloured scan adds its look (``texture_uv`` (triangle, corner,
uv), ``texture_image`` (texel_y, texel_x, rgb), ``vertex_colour`` (node, rgb); read back with
:func:`facemech.geometry.appearance.appearance_from_dataset`).
The tongue tip's pose, ``tongue_tip`` (time, tongue_axis; m: ``protrusion`` forward and
``elevation`` up from its rest, in the mandible's frame; render geometry, not physics), is written
by ``facemech speak`` (:mod:`facemech.speech.tongue`); files without it read as the tongue at rest
(:func:`results_tongue`).
Muscle outputs, per muscle instance (coordinate ``muscle_instance``: ``"ZYG_R"``, ``"OOS_L"``,
...): ``muscle_force`` (time, muscle_instance; N, tension of eqs. 5-7), ``muscle_length`` (m),
``muscle_velocity`` (m/s, lengthening positive), ``muscle_activation`` (N, the activation
state M of eq. 4), ``muscle_group`` and ``muscle_max_force`` (N, k_f S) (see
:mod:`facemech.physics.muscle_outputs`; read back with :func:`results_muscles`). Files written
before these existed have none of them and still read.
Attributes carry provenance: facemech version, preset, integrator, dt, input hashes, and the
numerical environment that made the numbers (:func:`numerics_attrs`: the versions of numpy, scipy,
numba and llvmlite, the CPU that numba compiled for and the BLAS kernels' core type), since the
last bits of a result depend on them (docs/reproducibility.md).
"""

from __future__ import annotations

import gc
import hashlib
import json
import os
import platform
import sys
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError, missing_input

# the renderer reads the default depth here (re-exported)
from ..geometry.teeth import TEETH_DEPTH_DEFAULT, teeth_depth  # noqa: F401
from ..params import FRAME_RATE_HZ, MUSCLE_GROUPS


def file_hash(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex, first 16 characters)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


def array_hash(*arrays: np.ndarray) -> str:
    """SHA-256 of arrays' bytes (hex, first 16 characters)."""
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def render_attrs(model) -> dict:
    """Attributes that let a results file render without its face model: the jaw hinge (point,
    m, and axis) and the depth of the incisors behind the upper lip's surface (m,
    :func:`~facemech.geometry.teeth.teeth_depth`)."""
    depth = teeth_depth(model)
    return {"hinge_point_m": json.dumps([float(v) for v in model.hinge_point]),
            "hinge_axis": json.dumps([float(v) for v in model.hinge_axis]),
            "teeth_depth_m": depth}


def _cpu_model() -> str:
    """The CPU's model name as the kernel reports it (Linux), else the platform's word."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def numerics_attrs() -> dict[str, str]:
    """The numerical environment, as results-file attributes (strings): the versions of numpy,
    scipy, numba and llvmlite (``numpy_version``, ...), ``numba_cpu`` (the CPU that numba's
    kernels are compiled for: ``NUMBA_CPU_NAME``, else LLVM's name of the host, e.g.
    ``skylake-avx512``), ``blas_core`` (the core type of each loaded OpenBLAS's kernels, e.g.
    ``SkylakeX``, which ``OPENBLAS_CORETYPE`` overrides), ``blas`` (JSON: every BLAS/LAPACK
    library that threadpoolctl sees, with version, core type and threading layer; not its
    thread count, which a run changes as it goes), ``cpu_model`` and ``machine``. Libraries not
    installed read ``"none"``."""
    from importlib import metadata

    def version(name: str) -> str:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "none"

    try:
        import numba

        cpu = numba.config.CPU_NAME or __import__("llvmlite.binding", fromlist=["binding"]
                                                   ).get_host_cpu_name()
    except ImportError:
        cpu = "none"
    try:
        import scipy.linalg  # noqa: F401  (loads scipy's own BLAS, so that it is listed too)
    except ImportError:
        pass
    try:
        from threadpoolctl import threadpool_info

        libs = [{k: lib.get(k) for k in ("internal_api", "version", "architecture",
                                         "threading_layer", "filepath")}
                for lib in threadpool_info() if lib.get("user_api") == "blas"]
    except Exception:  # a record, never a failure
        libs = []
    for lib in libs:
        lib["filepath"] = os.path.basename(lib["filepath"] or "")
    cores = sorted({str(lib["architecture"]) for lib in libs if lib.get("architecture")})
    return {"numpy_version": version("numpy"), "scipy_version": version("scipy"),
            "numba_version": version("numba"), "llvmlite_version": version("llvmlite"),
            "python_version": platform.python_version(), "numba_cpu": cpu,
            "blas_core": ",".join(cores) or "unknown", "blas": json.dumps(libs),
            "cpu_model": _cpu_model(), "machine": platform.machine()}


def to_dataset(sim, inputs: dict[str, str] | None = None, extra: dict | None = None):
    """An :class:`xarray.Dataset` of a :class:`~facemech.solvers.forward.Simulation` (or any run
    with the same fields: positions, markers, activity, jaw_angle, jaw_shift, ...)."""
    import xarray as xr

    from .._version import __version__
    from ..geometry.appearance import dataset_variables

    model = sim.model
    look, look_coords, look_attrs = dataset_variables(getattr(model, "appearance", None))
    shift = getattr(sim, "jaw_shift", None)
    if shift is None:  # a run that says nothing of the condyles: a hinge
        shift = np.zeros((len(sim.jaw_angle), 2))
    ds = xr.Dataset(
        {
            "positions": (("time", "node", "axis"), sim.positions,
                          {"units": "m", "long_name": "epidermal node positions"}),
            "markers": (("time", "marker", "axis"), sim.markers,
                        {"units": "m", "long_name": "landmarks and virtual markers"}),
            "activity": (("time", "muscle"), sim.activity,
                         {"units": "1", "long_name": "normalised muscle activity E"}),
            "jaw_angle": (("time",), sim.jaw_angle, {"units": "rad",
                                                     "long_name": "jaw hinge angle"}),
            "jaw_shift": (("time", "shift_axis"), np.asarray(shift, float),
                          {"units": "m", "long_name": "shift of the jaw hinge (condyles)"}),
            "triangles": (("triangle", "corner"), model.faces.astype(np.int32),
                          {"long_name": "epidermal surface triangles (node indices)"}),
            "rest_positions": (("node", "axis"), model.rest_positions[: model.n_surface],
                               {"units": "m"}),
            **look,
        },
        coords={
            "time": ("time", sim.time, {"units": "s"}),
            "axis": ["x", "y", "z"],
            "shift_axis": ["y", "z"],
            "marker": list(sim.marker_names),
            "muscle": list(MUSCLE_GROUPS),
            "node": np.arange(model.n_surface),
            **look_coords,
        },
        attrs={
            "title": "facemech simulation",
            "facemech_version": __version__,
            "face": model.name,
            "preset": sim.params.name,
            "integrator": sim.integrator,
            "dt_s": float(sim.dt),
            "frame_rate_hz": float(sim.params.frame_rate),
            "wall_seconds": float(sim.wall_seconds),
            "axes": "+x subject's left, +y up, +z forward",
            "marker_nodes": json.dumps({**model.landmarks, **model.markers}),
            **render_attrs(model),
            "inputs": json.dumps(inputs or {}),
            **numerics_attrs(),
            **look_attrs,
            **{k: (v if isinstance(v, (int, float, str)) else str(v))
               for k, v in sim.attrs.items()},
        },
    )
    muscles = getattr(sim, "muscles", None)
    if muscles is not None:
        from ..physics.muscle_outputs import series_variables

        for name, var in series_variables(muscles).items():
            ds[name] = var
    for name, var in (extra or {}).items():
        ds[name] = var
    return ds


def write_results(path: str | Path, sim, inputs: dict[str, str] | None = None,
                  extra: dict | None = None) -> Path:
    """Write a simulation to NetCDF atomically (nothing is left behind on failure).

    ``extra`` adds variables, name -> (dims, values, attrs) or a DataArray, e.g. an inversion's
    diagnostics, or the muscle outputs of its accepted states
    (:func:`facemech.physics.muscle_outputs.muscle_output_variables`). A simulation with
    ``muscles`` (:func:`~facemech.solvers.forward.simulate` fills them) writes them itself.
    """
    return write_dataset(path, to_dataset(sim, inputs, extra))


#: the variables of a results file stored compressed (zlib, level 4)
COMPRESSED_VARIABLES = ("positions", "markers", "activity", "texture_uv", "texture_image",
                        "muscle_force", "muscle_length", "muscle_velocity", "muscle_activation")


def write_dataset(path: str | Path, ds) -> Path:
    """Write a results dataset (as made by :func:`to_dataset`) to NetCDF atomically."""
    for name in ("positions", "markers"):
        if not np.all(np.isfinite(ds[name].values)):
            raise InputError("refusing to write non-finite values", source=str(path), field=name)
    enc = {v: {"zlib": True, "complevel": 4} for v in COMPRESSED_VARIABLES if v in ds}
    with atomic_path(path, suffix=".nc") as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf", encoding=enc)
    return Path(path)


#: the variables of a results file that must be finite everywhere (checked on reading)
FINITE_VARIABLES = ("positions", "markers", "rest_positions", "activity", "jaw_angle",
                    "jaw_shift", "tongue_tip")


def read_results(path: str | Path):
    """Open a results file as an :class:`xarray.Dataset` (loaded into memory)."""
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise missing_input(path)
    import h5py

    try:  # quick refusals first: not HDF5 at all, or HDF5 that h5py cannot open
        if not h5py.is_hdf5(path):
            raise OSError("no HDF5 signature")
        with h5py.File(path, "r"):
            pass
    except Exception as exc:
        raise InputError(f"not a readable NetCDF results file ({type(exc).__name__})",
                         source=str(path)) from None
    error, hook = None, sys.unraisablehook
    # a damaged file leaves h5netcdf a half-made File whose clean-up fails when it is
    # collected, outside any handler: that clean-up stays quiet, the error is reported
    sys.unraisablehook = lambda _: None
    try:
        try:
            with xr.open_dataset(path, engine="h5netcdf") as ds:
                ds = ds.load()
        except Exception as exc:
            error = f"not a readable NetCDF results file ({type(exc).__name__})"
        if error is not None:
            gc.collect()
    finally:
        sys.unraisablehook = hook
    if error is not None:
        raise InputError(error, source=str(path))
    for need in ("positions", "markers", "triangles"):
        if need not in ds:
            raise InputError("not a facemech results file", source=str(path), field=need)
    for name in FINITE_VARIABLES:
        if name in ds and not np.all(np.isfinite(ds[name].values)):
            bad = np.argwhere(~np.isfinite(ds[name].values))[0]
            where = ", ".join(f"{'frame' if d == 'time' else d} {int(i)}"
                              for d, i in zip(ds[name].dims, bad, strict=True))
            raise InputError(f"non-finite value at {where}: a results file holds finite numbers "
                             "only (was it edited by hand?)", source=str(path), field=name)
    return with_jaw_shift(ds)


def with_jaw_shift(ds):
    """``ds`` with a ``jaw_shift`` (time, shift_axis; m): zeros for files written before the
    jaw's glide (a hinge) or without a jaw."""
    if "jaw_shift" in ds:
        return ds
    ds["jaw_shift"] = (("time", "shift_axis"), np.zeros((ds.sizes["time"], 2)),
                       {"units": "m", "long_name": "shift of the jaw hinge (condyles)"})
    return ds.assign_coords(shift_axis=["y", "z"])


#: the results variable of the tongue tip's pose and its axis' labels
TONGUE_TIP = "tongue_tip"
TONGUE_AXES = ("protrusion", "elevation")


def tongue_variable(series: np.ndarray) -> dict:
    """The results variables of a tongue tip series (frames, 2) m (protrusion, elevation),
    ``{"tongue_tip": (dims, values, attrs)}``, for ``extra`` of :func:`to_dataset` (its
    coordinate ``tongue_axis`` is added with :func:`with_tongue_axis`)."""
    a = np.asarray(series, float)
    if a.ndim != 2 or a.shape[1] != 2 or not np.all(np.isfinite(a)):
        raise InputError(f"a tongue tip series is a finite (frames, 2) array, not {a.shape}",
                         field=TONGUE_TIP)
    return {TONGUE_TIP: (("time", "tongue_axis"), a,
                         {"units": "m", "long_name": "tongue tip pose from rest (protrusion "
                          "forward, elevation up; the mandible's frame; render geometry)"})}


def with_tongue(ds, series: np.ndarray):
    """``ds`` with its ``tongue_tip`` set to ``series`` (frames, 2) m (:func:`tongue_variable`)
    and the coordinate ``tongue_axis``."""
    if len(series) != ds.sizes["time"]:
        raise InputError(f"the tongue tip series has {len(series)} frames, the results "
                         f"{ds.sizes['time']}", field=TONGUE_TIP)
    ds = ds.assign_coords(tongue_axis=list(TONGUE_AXES))
    for name, var in tongue_variable(series).items():
        ds[name] = var
    return ds


def results_tongue(ds) -> np.ndarray | None:
    """(frames, 2) m, the tongue tip's pose (protrusion, elevation) of a results dataset, or
    None for a file without it (the tongue at rest)."""
    if TONGUE_TIP not in ds:
        return None
    var = ds[TONGUE_TIP]
    if set(var.dims) != {"time", "tongue_axis"}:
        raise InputError(f"tongue_tip has dimensions {var.dims}, not (time, tongue_axis)",
                         source=ds.encoding.get("source"), field=TONGUE_TIP)
    a = np.asarray(var.transpose("time", "tongue_axis").values, float)
    if a.shape != (ds.sizes["time"], 2) or not np.all(np.isfinite(a)):
        raise InputError(f"a tongue tip series is a finite (frames, 2) array, not {a.shape}",
                         source=ds.encoding.get("source"), field=TONGUE_TIP)
    return a


def results_muscles(ds):
    """The muscle outputs of a results dataset, or None for a file without them.

    Parameters
    ----------
    ds : xarray.Dataset, as returned by :func:`read_results`

    Returns
    -------
    MuscleSeries or None
        (frames, muscle instances) arrays in SI units (N, m, m/s, N), the instance names and
        groups.
    """
    from ..physics.muscle_outputs import OUTPUT_VARIABLES, MuscleSeries

    if not all(var in ds for _, var, _, _ in OUTPUT_VARIABLES):
        return None
    arrays = {attr: ds[var].transpose("time", "muscle_instance").values
              for attr, var, _, _ in OUTPUT_VARIABLES}
    n = arrays["force"].shape[1]
    return MuscleSeries(
        names=tuple(str(v) for v in ds["muscle_instance"].values),
        groups=tuple(str(v) for v in ds["muscle_group"].values) if "muscle_group" in ds
        else ("",) * n,
        max_force=(ds["muscle_max_force"].values if "muscle_max_force" in ds
                   else np.full(n, np.nan)),
        **arrays)


def results_markers(ds, *, source: str | Path | None = None):
    """The model's markers of a results dataset as a :class:`~facemech.markerset.MarkerSet`.

    Parameters
    ----------
    ds : xarray.Dataset
        As returned by :func:`read_results`: ``markers`` (time, marker, axis; m) with the names
        in the ``marker`` coordinate, the rate in the ``frame_rate_hz`` attribute (60 Hz if
        absent).
    source : the file it came from, for messages and provenance

    Returns
    -------
    MarkerSet
        Positions (frames, markers, 3) in metres, the results' ``time`` (s), ``source_units``
        ``"m"`` (what the results hold; writers convert on request).
    """
    from ..markerset import MarkerSet

    src = None if source is None else str(source)
    var = ds["markers"]
    unit = var.attrs.get("units", "m")
    if unit != "m":
        raise InputError(f"markers must be in metres, not {unit!r}", source=src,
                         field="markers")
    rate = float(ds.attrs.get("frame_rate_hz", FRAME_RATE_HZ))
    return MarkerSet(var.transpose("time", "marker", "axis").values,
                     tuple(str(n) for n in ds["marker"].values), rate,
                     time=ds["time"].values, source_units="m",
                     meta={"source": src, "format": "results"})
