"""The marker-set type: labelled marker trajectories with rate, units and validity.

A :class:`MarkerSet` holds positions (frames, markers, 3) in metres, NaN where a sample is
missing, the sampling rate, the unit of the file it came from (``source_units``, kept for writing
back), and per sample flags: ``filled`` marks samples that a gap filler made up, so that no
filled sample passes for a measured one. ``to_xarray`` gives the ecosystem's labelled array.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .errors import InputError

#: Hz, the highest sampling rate accepted: above any motion-capture system (they reach a few kHz)
MAX_RATE_HZ = 100_000.0
#: the roles an articulography reader may give a sensor in ``meta["roles"]`` (readers:
#: :mod:`facemech.io.articulography`; use: :mod:`facemech.kinematics.roles`)
SENSOR_ROLES = ("upper_lip", "lower_lip", "lower_incisor", "upper_incisor", "molar", "tongue",
                "velum", "reference", "other")


def match_name(name: str, names, *, source: str | None = None) -> str:
    """The marker of ``names`` that the user means by ``name``.

    The exact name if there is one; else the one name equal to it ignoring case (``ul`` finds
    ``UL``). Two names that differ only in case and neither exact (``Ul`` among ``UL`` and
    ``ul``) are a clash, refused.

    Raises
    ------
    InputError
        Naming ``name``: no such marker, or a clash of names that differ only in case.
    """
    names = tuple(names)
    if name in names:
        return name
    same = [n for n in names if n.casefold() == str(name).casefold()]
    if len(same) == 1:
        return same[0]
    if same:
        raise InputError(f"{' and '.join(same)} differ only in case: give the exact name",
                         source=source, field=str(name))
    raise InputError(f"no such marker (have {', '.join(names[:12])}"
                     f"{', ...' if len(names) > 12 else ''})", source=source, field=str(name))


def shared_names(a, b, *, source: str | None = None) -> list[tuple[str, str]]:
    """(name in ``a``, name in ``b``) of the markers both have, in ``a``'s order, matched as
    :func:`match_name` does: exactly, else ignoring case where that is unambiguous.

    Raises
    ------
    InputError
        Naming the marker when its name matches two of the other side's ignoring case.
    """
    out = []
    for n in a:
        if n in b:
            out.append((n, n))
            continue
        same = [m for m in b if m.casefold() == n.casefold()]
        mine = [m for m in a if m.casefold() == n.casefold()]
        if len(same) > 1 or (same and len(mine) > 1):
            raise InputError(f"{', '.join(dict.fromkeys(mine + same))} differ only in case: "
                             "rename them (facemech markers convert) or give --markers",
                             source=source, field=n)
        if same:
            out.append((n, same[0]))
    return out


@dataclass(frozen=True, eq=False)
class MarkerSet:
    """Marker trajectories.

    Attributes
    ----------
    positions : (frames, markers, 3) float array, metres; NaN = missing
    names : marker labels
    rate : sampling rate, Hz
    time : (frames,) s (defaults to frame / rate)
    source_units : length unit of the file the data came from (``mm``, ``m``, ...)
    filled : (frames, markers) bool, samples made up by a gap filler
    meta : free-form provenance (file, reader, processing steps)
    """

    positions: np.ndarray
    names: tuple[str, ...]
    rate: float
    time: np.ndarray | None = None
    source_units: str = "m"
    filled: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        pos = np.asarray(self.positions, float)
        if pos.ndim != 3 or pos.shape[2] != 3:
            raise InputError(f"marker positions must be (frames, markers, 3), got {pos.shape}",
                             field="positions")
        names = tuple(str(n) for n in self.names)
        if len(names) != pos.shape[1]:
            raise InputError(f"{len(names)} names for {pos.shape[1]} markers", field="names")
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise InputError("duplicate marker label", field=dup)
        if not (np.isfinite(self.rate) and 0 < self.rate <= MAX_RATE_HZ):
            raise InputError(f"sampling rate {float(self.rate)!r} Hz is not a finite rate in "
                             f"(0, {MAX_RATE_HZ:g}] Hz", field="rate")
        if np.isinf(pos).any():  # a broken sample, not a missing one (NaN)
            k, m, a = (int(i[0]) for i in np.nonzero(np.isinf(pos)))
            raise InputError(f"infinite coordinate at frame {k + 1} (leave a missing sample "
                             "empty or NaN)", field=f"{names[m]}_{'xyz'[a]}")
        t = (np.arange(pos.shape[0]) / self.rate if self.time is None
             else np.asarray(self.time, float))
        if t.shape != pos.shape[:1]:
            raise InputError(f"{t.size} times for {pos.shape[0]} frames", field="time")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            bad = int(np.argmax(~np.isfinite(t))) if not np.all(np.isfinite(t)) else \
                int(np.argmax(np.diff(t) <= 0)) + 1
            raise InputError(f"time must be finite and strictly increasing (frame {bad + 1}: "
                             f"{float(t[bad])!r} s)", field="time")
        filled = (np.zeros(pos.shape[:2], bool) if self.filled is None
                  else np.asarray(self.filled, bool))
        for name, a in (("positions", pos), ("time", t), ("filled", filled)):
            # read-only, also the caller's array if it was passed without a copy: an edit of
            # the data after the set is made fails loudly instead of changing the set silently
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "rate", float(self.rate))

    # ---- views ------------------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return self.positions.shape[0]

    @property
    def n_markers(self) -> int:
        return self.positions.shape[1]

    @property
    def valid(self) -> np.ndarray:
        """(frames, markers) True where a sample is present (measured or filled)."""
        return np.all(np.isfinite(self.positions), axis=2)

    @property
    def measured(self) -> np.ndarray:
        """(frames, markers) True where a sample was measured (present and not filled)."""
        return self.valid & ~self.filled

    def index(self, name: str) -> int:
        """The column of the marker ``name`` means (:func:`match_name`)."""
        return self.names.index(match_name(name, self.names, source=self.meta.get("source")))

    def marker(self, name: str) -> np.ndarray:
        """(frames, 3) trajectory of one marker, metres."""
        return self.positions[:, self.index(name)]

    def select(self, names) -> MarkerSet:
        """A marker set with only the named markers, in that order."""
        idx = [self.index(n) for n in names]
        return replace(self, positions=self.positions[:, idx],
                       names=tuple(self.names[i] for i in idx), filled=self.filled[:, idx])

    def renamed(self, names) -> MarkerSet:
        """The set with its markers called ``names`` (same order), the roles following them."""
        names = tuple(str(n) for n in names)
        roles = self.meta.get("roles")
        meta = dict(self.meta)
        if isinstance(roles, dict):
            new = dict(zip(self.names, names, strict=True))
            meta["roles"] = {new.get(k, k): v for k, v in roles.items()}
        return replace(self, names=names, meta=meta)

    def with_positions(self, positions: np.ndarray, **changes) -> MarkerSet:
        """A copy with new positions (and any other field changed)."""
        return replace(self, positions=positions, **changes)

    # ---- xarray -----------------------------------------------------------------------------
    def to_xarray(self):
        """An :class:`xarray.DataArray` (time, marker, axis) in metres with the metadata."""
        import xarray as xr

        return xr.DataArray(
            self.positions, dims=("time", "marker", "axis"),
            coords={"time": ("time", self.time, {"units": "s"}), "marker": list(self.names),
                    "axis": ["x", "y", "z"],
                    "filled": (("time", "marker"), self.filled)},
            attrs={"units": "m", "rate_hz": self.rate, "source_units": self.source_units},
            name="markers",
        )

    @classmethod
    def from_xarray(cls, da) -> MarkerSet:
        """Inverse of :meth:`to_xarray`."""
        if da.attrs.get("units", "m") != "m":
            raise InputError("marker array must be in metres", field="units")
        filled = da.coords["filled"].values if "filled" in da.coords else None
        return cls(da.transpose("time", "marker", "axis").values,
                   tuple(str(m) for m in da["marker"].values), float(da.attrs["rate_hz"]),
                   time=da["time"].values, source_units=da.attrs.get("source_units", "m"),
                   filled=filled)
