"""Reading raw EMG: a CSV with a ``time`` column (s) and one column per channel, or C3D analog."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..plausibility import check_time_column
from .tables import read_table, uniform_rate


def read_emg(path: str | Path) -> tuple[np.ndarray, float, tuple[str, ...]]:
    """Read raw EMG.

    Returns
    -------
    signal : (samples, channels)
    rate : Hz
    channels : names (muscle groups)
    """
    path = Path(path)
    if path.suffix.lower() == ".c3d":
        from .c3d import read_c3d_analog

        rate, names, data = read_c3d_analog(path)
        return data, rate, tuple(names)
    t, cols = read_table(path)
    cols.pop("__meta__")
    if not cols:
        raise InputError("no EMG channels", source=str(path), field="header")
    check_time_column(t, kind="emg", source=str(path))
    rate = uniform_rate(t, source=str(path))
    names = tuple(cols)
    for n in names:
        if not np.all(np.isfinite(cols[n])):
            r = int(np.nonzero(~np.isfinite(cols[n]))[0][0])
            raise InputError(f"row {r + 1} is empty or NaN", source=str(path), field=n)
    return np.column_stack([cols[n] for n in names]), rate, names
