"""A results file written block by block, for runs too long to hold in memory.

:class:`ResultsStream` is a sink for :func:`facemech.solvers.forward.simulate_blocks`: the
first block of frames is written by xarray exactly as :func:`~facemech.io.results.write_results`
writes a whole run (the same :func:`~facemech.io.results.to_dataset`, variables, attributes and
compression), but with ``time`` an unlimited (extendable) dimension; every later block is
appended along ``time`` with h5netcdf, and the ``wall_seconds`` attribute is brought up to date.
:func:`~facemech.io.results.read_results` reads the file exactly as the one written in memory
(same variables, dimensions, attributes and values, bit for bit). The file is written to a
temporary path and renamed on success (:func:`~facemech.atomic.atomic_path`): an error or an
interruption leaves nothing behind.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..errors import InputError
from .results import COMPRESSED_VARIABLES, to_dataset

#: target size (bytes) of one HDF5 chunk of a variable along ``time``
CHUNK_BYTES = 1 << 20


def time_chunks(ds, most: int) -> dict:
    """Chunk shapes of the ``time`` variables of a results dataset: about :data:`CHUNK_BYTES`
    each, whole along every other dimension, at most ``most`` frames.

    Returns
    -------
    dict
        variable name -> chunk shape (tuple of int).
    """
    out = {}
    for name, var in ds.variables.items():
        if "time" not in var.dims or var.dims[0] != "time":
            continue
        frame_bytes = max(var.dtype.itemsize * int(np.prod(var.shape[1:], dtype=np.int64)), 1)
        frames = int(min(max(CHUNK_BYTES // frame_bytes, 1), max(most, 1)))
        out[name] = (frames, *var.shape[1:])
    return out


class ResultsStream:
    """Appends blocks of a simulation (:class:`~facemech.solvers.forward.Simulation` of
    consecutive frames) to a results file at ``path`` (a temporary file: see
    :func:`stream_results`, which also renames it).

    Parameters
    ----------
    path : the file being written (created on the first block)
    inputs : input name -> file hash, the results' provenance (as ``write_results``)
    source : the final file's name, for messages
    """

    def __init__(self, path: str | Path, inputs: dict[str, str] | None = None,
                 source: str | Path | None = None):
        self.path = Path(path)
        self.inputs = inputs
        self.source = str(source if source is not None else path)
        self.frames = 0
        self._file = None

    def __call__(self, block) -> None:
        """Write one block: its frames must follow those already written."""
        ds = to_dataset(block, self.inputs)
        for name in ("positions", "markers"):
            if not np.all(np.isfinite(ds[name].values)):
                raise InputError("refusing to write non-finite values", source=self.source,
                                 field=name)
        first = round(float(block.time[0]) * float(block.params.frame_rate))
        if first != self.frames:
            raise ValueError(f"block starts at frame {first}, {self.frames} frames written")
        if self._file is None:
            self._create(ds)
        else:
            self._append(ds)
        self.frames += ds.sizes["time"]

    def _create(self, ds) -> None:
        import h5netcdf

        chunks = time_chunks(ds, ds.sizes["time"])
        enc = {name: {"chunksizes": shape} for name, shape in chunks.items()}
        for name in COMPRESSED_VARIABLES:
            if name in ds:
                enc.setdefault(name, {}).update(zlib=True, complevel=4)
        ds.to_netcdf(self.path, engine="h5netcdf", encoding=enc, unlimited_dims=["time"])
        self._file = h5netcdf.File(self.path, "a")

    def _append(self, ds) -> None:
        f = self._file
        start, stop = self.frames, self.frames + ds.sizes["time"]
        f.resize_dimension("time", stop)
        for name, var in ds.variables.items():
            if "time" in var.dims:
                if var.dims[0] != "time":
                    raise ValueError(f"{name}: time must be the first dimension to append")
                f.variables[name][start:stop] = var.values
        f.attrs["wall_seconds"] = float(ds.attrs["wall_seconds"])

    def close(self) -> None:
        """Close the file (it stays where it is)."""
        if self._file is not None:
            self._file.close()
            self._file = None


@contextlib.contextmanager
def stream_results(path: str | Path,
                   inputs: dict[str, str] | None = None) -> Iterator[ResultsStream]:
    """A :class:`ResultsStream` writing ``path`` atomically.

    The blocks go to a temporary file beside ``path``, renamed to ``path`` when the block
    exits normally; on an error (a blow-up, a progress callback raising, an interruption) the
    temporary file is removed and ``path`` is left as it was.

    Examples
    --------
    >>> with stream_results("long.nc", inputs) as sink:
    ...     simulate_blocks(face, activity, jaw, sink=sink)
    """
    with atomic_path(path, suffix=".nc") as tmp:
        stream = ResultsStream(tmp, inputs, source=path)
        try:
            yield stream
        finally:
            stream.close()
        if stream.frames == 0:
            raise ValueError("no frames were written")
