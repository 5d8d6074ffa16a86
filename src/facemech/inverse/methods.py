"""The inversion's methods as small immutable option objects, each validating its own options.

``LeastSquares`` is the default (a receding horizon solved by bounded Gauss-Newton, see
:mod:`facemech.inverse.frame`); ``Powell`` is the seeds' direction-set minimisation of one
frame's marker cost (Pitermann & Munhall 2001, II.C). An option that belongs to the other method
is an error (:func:`method_from_options`), never silently ignored.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..checks import check_value
from ..errors import InputError


def _non_negative(obj, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, (int, float)) and value >= 0):
            raise InputError(f"{name} must be a number >= 0 (got {value!r})", field=name)


@dataclass(frozen=True)
class LeastSquares:
    """Receding-horizon bounded Gauss-Newton (the default method).

    Parameters
    ----------
    window : frames fitted per frame (>= 1); only the first frame's controls are kept
    tol : mm; a frame's iterations stop when an accepted step lowers the RMS marker residual by
        less than this (default 0.01 mm, a tenth of a good motion-capture system's precision);
        0: they stop only when no step gains (the step is below 1e-6, the linearisation
        predicts no gain or a step fails with fresh responses), after 12 iterations or at
        ``max_evaluations`` (tol is only compared with, never divided by)
    bend : mm per unit activity, weight of second differences of activity across the window
        (acts for windows of 3 frames or more)
    smooth : mm per unit, weight of first differences (from the previous frame's controls);
        it damps the frame-to-frame alternation that the activation filter hides from the
        markers (default 0.3: a change of 0.1 in one frame costs as much as 0.03 mm of error)
    effort : mm per unit, weight of the activity itself
    prior_weight : mm per unit, weight of ``activity - prior`` (a prior such as processed EMG)
    jaw_prior_weight : mm per 0.1 rad, weight of ``jaw - recorded jaw`` when a jaw recording
        is the starting point of an estimated jaw
    max_evaluations : frame steps of the model per frame, at most
    max_rate : 1/s, the largest change of a muscle control per second, as a bound on each
        frame's change from the frame before (0: none)
    """

    window: int = 2
    tol: float = 0.01
    bend: float = 0.03
    smooth: float = 0.3
    effort: float = 0.0
    prior_weight: float = 0.0
    jaw_prior_weight: float = 0.05
    max_evaluations: int = 400
    max_rate: float = 0.0

    name = "lsq"

    def __post_init__(self):
        if not (isinstance(self.window, int) and self.window >= 1):
            raise InputError(f"window must be a whole number of frames >= 1 (got "
                             f"{self.window!r})", field="window")
        _non_negative(self, "tol", "bend", "smooth", "effort", "prior_weight",
                      "jaw_prior_weight", "max_rate")
        if not (isinstance(self.max_evaluations, int) and self.max_evaluations >= 1):
            raise InputError(f"max_evaluations must be >= 1 (got {self.max_evaluations!r})",
                             field="max_evaluations")
        # the command line's intervals (facemech.checks)
        for name in ("window", "tol", "bend", "smooth", "effort", "max_evaluations", "max_rate"):
            check_value(name, getattr(self, name))


@dataclass(frozen=True)
class Powell:
    """Powell's direction-set method on one frame's marker cost E (mm^2), the seeds' method.

    Parameters
    ----------
    max_evaluations : cost evaluations (frame steps of the model) per frame, at most
    xtol : activity tolerance of the line searches
    ftol : relative tolerance of the cost
    """

    max_evaluations: int = 400
    xtol: float = 1e-3
    ftol: float = 1e-9

    name = "powell"

    def __post_init__(self):
        if not (isinstance(self.max_evaluations, int) and self.max_evaluations >= 1):
            raise InputError(f"max_evaluations must be >= 1 (got {self.max_evaluations!r})",
                             field="max_evaluations")
        check_value("max_evaluations", self.max_evaluations)
        for name in ("xtol", "ftol"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0):
                raise InputError(f"{name} must be a number > 0 (got {value!r})", field=name)


METHODS = {"lsq": LeastSquares, "powell": Powell}


def method_from_options(name: str, **options):
    """The method object for ``name`` from the options given (None: not given).

    An option of the other method is an error naming it.
    """
    if name not in METHODS:
        raise InputError(f"unknown method {name!r} (lsq or powell)", field="method")
    cls = METHODS[name]
    own = {f.name for f in fields(cls)}
    given = {k: v for k, v in options.items() if v is not None}
    for key in given:
        if key not in own:
            other = [n for n, c in METHODS.items() if key in {f.name for f in fields(c)}]
            where = f"the {other[0]} method" if other else "no method"
            raise InputError(f"{key} applies to {where}, not to {name}", field=key)
    return cls(**given)
