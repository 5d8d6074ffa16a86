"""The inversion's options as input groups (:mod:`facemech.inputs`): how it fits
(:class:`InversionOptions`: the method, the sign of activity, the controls, the marker noise)
and the method's own options (:class:`FitOptions`, each None when not given: the method's
default then; :func:`facemech.inverse.methods.method_from_options` checks them against it)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from ..inputs import option

__all__ = ["FitOptions", "InversionOptions", "as_options", "inversion_options"]


@dataclass(frozen=True)
class InversionOptions:
    """How an inversion fits: the method (``lsq`` or ``powell``), activity kept >= 0, the
    controls (``speech``, ``emg7``, ``all`` or comma-separated groups; None: ``speech``, or the
    part of it the markers determine) and the marker noise for the standard errors (mm; None:
    from the residuals)."""

    method: str = option("lsq", "lsq (fast) or powell (the seeds')")
    positive: bool = option(True, "keep activity >= 0")
    controls: str | None = option(None, "speech, emg7, all, or listed groups (default: "
                                  "speech, or what the markers determine)")
    noise: float | None = option(None, "marker noise for the SEs, mm (or fit)", unit="mm")


def inversion_options(inversion: InversionOptions | None, given: dict) -> InversionOptions:
    """``inversion`` (None: the defaults) with the options given one by one as keywords
    (``method=``, ``positive=``, ``controls=``, ``noise=``)."""
    return replace(inversion or InversionOptions(), **given)


@dataclass(frozen=True)
class FitOptions:
    """The fit's options (None: not given): see :class:`facemech.inverse.methods.LeastSquares`;
    ``max_evaluations`` is Powell's too."""

    window: int | None = option(None, "lsq: frames fitted per frame (2)", unit="frames")
    tol: float | None = option(None, "lsq: stop at RMS gains below this, mm (0: stop when no "
                               "step gains)", unit="mm")
    bend: float | None = option(None, "lsq weight, mm/unit: --bend, --smooth (0.3), --effort",
                                unit="mm")
    smooth: float | None = option(None, "see --bend", unit="mm")
    effort: float | None = option(None, "see --bend (0; 0.1 when the control pick adds for "
                                  "sign)", unit="mm")
    max_evaluations: int | None = option(None, "model steps per frame (400)")
    max_rate: float | None = option(None, "lsq: largest change of a muscle per second, 1/s (0: "
                                    "none)", unit="1/s")

    def as_dict(self) -> dict:
        """Option name -> value, None where not given."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


def as_options(options) -> dict:
    """The method's options as a dict: from :class:`FitOptions`, a dict or None (none)."""
    if isinstance(options, FitOptions):
        return options.as_dict()
    return dict(options or {})
