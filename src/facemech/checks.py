"""One table of the names facemech accepts: each number's kind and interval, each word's choices.

The same table serves the Python API and the command line: :class:`facemech.params.Parameters`
checks its fields when made (:func:`check_fields`), the inversion's methods their options, and
:mod:`facemech.cli` every number a command is given (:data:`facemech.cli_options.RANGES`, the
rows that are options of a command). A value out of its interval, of the wrong kind or not one of
its choices is an :class:`~facemech.errors.InputError` naming the field. Pure Python: importing
it costs nothing.

Rows: ``name: kind interval-or-choices``. Kinds: ``float`` (a finite real number), ``int`` (a
whole number), ``bool``, ``str``; an interval ``(lo, hi]`` is open or closed as written (bounds
may be ``inf``), choices are words separated by ``|``. Units as in the help: rates Hz, times and
steps s, noise and the inversion's weights mm; the preset's fields SI (:mod:`facemech.params`).
"""

from __future__ import annotations

import math

from .errors import InputError

__all__ = ["CHOICES", "KINDS", "RANGES", "check_fields", "check_number", "check_value"]

_TABLE = """
rate: float (0, 1e5]
dt: float (0, 0.01]
max_gap: float (0, 3600]
time: float [0, inf)
noise: float [0, 100]
noise_mm: float [0, 100]
tol: float [0, 100]
bend: float [0, 1e6]
smooth: float [0, 1e6]
effort: float [0, 1e6]
max_rate: float [0, 1e6]
window: int [1, 1000]
substeps: int [1, 1e5]
reference: int [0, inf)
frames: int [2, 1e6]
utterances: int [1, 1e4]
k: int [1, 1000]
aa: int [1, 4]
rate_wpm: int [80, 450]
strength: float [0, 2]
seed: int [0, 4294967295]
blink_rate_per_min: float (0, 60]
jaw_lead: int [0, 600]
max_evaluations: int [1, 1e7]
lowpass: float [0, 1000]
workers: int [1, 1024]
ipd: float [50, 80]
distance: float [0.3, 20]
name: str
node_mass: float [0, inf)
damping: float [0, inf)
k_epidermis: float [0, inf)
k_fascia: float [0, inf)
k_muscle_layer: float [0, inf)
k_dermal_low: float [0, inf)
k_dermal_high: float [0, inf)
biphasic_knee: float [0, inf)
sigma: float [0, 1]
spring_ref_length: float (0, inf)
depth_fascia: float (0, inf)
depth_skull: float (0, inf)
k_force: float [0, inf)
f1: float [0, inf)
f2: float [0, inf)
f3: float [0, inf)
f4: float [0, inf)
k_passive_per_cm2: float [0, inf)
k_volume: float [0, inf)
k_shape: float [0, inf)
k_restore: float [0, inf)
k_lip_contact: float [0, inf)
fast_dt: float (0, 0.01]
frame_rate: float (0, 1e5]
material: str per_spring|continuum
tissue: str uniform|anatomical
integrator: str euler|implicit|rosenbrock
density: float (0, inf)
shear_superficial: float [0, inf)
shear_deep: float [0, inf)
lip_stiffness_factor: float [0, inf)
poisson: float [0, 0.5)
skin_modulus_thickness: float [0, inf)
viscous_time: float [0, inf)
dashpot_isotropy: float [0, 1]
predictor: bool
krylov_iterations: int [0, 8]
mass_drag: float [0, 1000]
implicit_stiffness_share: float [0, 10]
implicit_volume_scale: float [0, 10]
stiffening: float [0, inf)
fixed_skull_contact: bool
sphincter_scale: float [0, inf)
tether: float [0, inf)
incisive_area_cm2: float [0, inf)
k_bone_contact: float [0, inf)
implicit_contacts: bool
volume_floor: float [0, 1)
volume_floor_modulus: float [0, inf)
"""


def _rows(text: str):
    for line in text.strip().splitlines():
        name, rest = line.split(": ", 1)
        kind, _, spec = rest.partition(" ")
        yield name, kind, spec


#: name -> kind: float, int, bool or str
KINDS: dict[str, str] = {name: kind for name, kind, _ in _rows(_TABLE)}
#: name -> the interval its number must lie in; NaN and infinities never pass
RANGES: dict[str, str] = {name: spec for name, kind, spec in _rows(_TABLE)
                          if kind in ("float", "int") and spec}
#: name -> the words it may be
CHOICES: dict[str, tuple[str, ...]] = {name: tuple(spec.split("|"))
                                       for name, kind, spec in _rows(_TABLE)
                                       if kind == "str" and spec}


def check_number(option: str, value: float, interval: str | None = None) -> None:
    """Refuse ``value`` unless it is finite and lies in ``interval`` (the command line's check).

    Parameters
    ----------
    option : the option's name, for the message (e.g. ``--dt``)
    value : the number given
    interval : ``"(lo, hi]"`` style, bounds may be ``inf``; None: any finite number

    Raises
    ------
    InputError : naming ``option``, the interval and the value
    """
    if not _within(value, interval):
        within = f" in {interval}" if interval else ""
        raise InputError(f"must be a finite number{within}, got {value}", source=f"option {option}")


def _within(value, interval: str | None) -> bool:
    lo, hi = (float(v) for v in interval[1:-1].split(",")) if interval else (-math.inf, math.inf)
    above = interval is None or (lo < value if interval[0] == "(" else lo <= value)
    below = interval is None or (value < hi if interval[-1] == ")" else value <= hi)
    return math.isfinite(value) and above and below


def _is_real(value) -> bool:
    try:
        return not isinstance(value, (bool, str)) and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def check_value(name: str, value, *, source: str | None = None) -> None:
    """Refuse ``value`` for the table's row ``name`` (a name not in the table passes).

    Raises
    ------
    InputError : ``field=name``: a number of the wrong kind or out of its interval, a word not
        among the choices
    """
    kind = KINDS.get(name)
    if kind is None:
        return
    if kind == "bool":
        ok, want = isinstance(value, bool) or type(value).__name__ == "bool_", "true or false"
    elif kind == "str":
        choices = CHOICES.get(name)
        ok = isinstance(value, str) and (choices is None or value in choices)
        want = "text" if choices is None else "one of " + ", ".join(choices)
    else:
        interval = RANGES.get(name)
        whole = kind != "int" or (_is_real(value) and float(value) == int(float(value)))
        ok = _is_real(value) and whole and _within(float(value), interval)
        want = ("a whole number" if kind == "int" else "a finite number") + (
            f" in {interval}" if interval else "")
    if not ok:
        raise InputError(f"{name} must be {want} (got {value!r})", source=source, field=name)


def check_fields(obj, *, source: str | None = None) -> None:
    """Check every field of a dataclass ``obj`` that the table names (:func:`check_value`)."""
    for name in getattr(obj, "__dataclass_fields__", {}):
        check_value(name, getattr(obj, name), source=source)
