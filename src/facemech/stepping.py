"""The numerical method a preset steps with: :class:`StepOptions`, apart from the physics.

:class:`~facemech.params.Parameters` holds the constants of the face (the forces); this holds
how a solver integrates them: the integrator's name, its steps, the implicit methods' matrix
shares, predictor and Krylov correction, the drag taken into the matrix, and the contacts and
the prisms' volume floor stepped after a solve. A preset names both (:func:`preset_steps`);
:func:`facemech.solvers.step.solver_from_options` turns them into one solver object. Checked
when made: every field's kind and interval (:mod:`facemech.checks`) and the predictor's needs.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .checks import check_fields
from .errors import InputError

#: the least shares of the stiffness that the implicit matrix must hold for the predictor's
#: step to be stable at any stiffness: 3/4 of each spring's stiff branch (the scalar step's
#: spectral radius, docs/model.md), and 3 x each prism's volume Gram matrix (whose largest
#: eigenvalue is at least a third of the volume term's rank-one Hessian's)
PREDICTOR_LEAST_SHARES = {"implicit_stiffness_share": 0.75, "implicit_volume_scale": 3.0}


@dataclass(frozen=True)
class StepOptions:
    """How a preset's model is stepped (SI units).

    Attributes
    ----------
    integrator : {"euler", "implicit", "rosenbrock"} -- the integrator every command uses
    dt : s, the explicit Euler step (the paper's 0.33 ms)
    fast_dt : s, the explicit step of the fast paths (inversion, experiments)
    substeps : steps per frame of the implicit integrators
    predictor : the linearly implicit step about the explicit predictor x + h v
    krylov_iterations : GMRES iterations on the predictor's true linearisation (0: none)
    krylov_region : m, the radius about the mouth of the Krylov correction (0: the whole face)
    mass_drag : 1/s, a drag proportional to mass, exactly in the matrix (linear implicit only)
    implicit_stiffness_share : the share of each spring's stiff branch in the implicit matrix
    implicit_volume_scale : the factor on the prisms' volume Gram matrices in it
    implicit_contacts : the implicit methods step the bone and lip contacts after each solve
    volume_floor : a prism below this share of its rest volume is pushed back (0: none) ...
    volume_floor_modulus : Pa, ... by a one-sided penalty of this modulus
    """

    integrator: str = "euler"
    dt: float = 0.33e-3
    fast_dt: float = 1e-3
    substeps: int = 4
    predictor: bool = False
    krylov_iterations: int = 0
    krylov_region: float = 0.0
    mass_drag: float = 0.0
    implicit_stiffness_share: float = 0.3
    implicit_volume_scale: float = 1.0
    implicit_contacts: bool = False
    volume_floor: float = 0.0
    volume_floor_modulus: float = 0.0

    def __post_init__(self):
        check_fields(self)
        check_predictor(self)

    def with_(self, **changes) -> StepOptions:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def steps_per_frame(self, frame_rate: float) -> int:
        """Explicit Euler steps per frame at ``frame_rate`` Hz: 50 at the paper's 0.33 ms."""
        return max(1, int(1.0 / (frame_rate * self.dt) + 1e-9))


#: the names of :class:`StepOptions`'s fields
STEP_FIELDS = frozenset(f.name for f in fields(StepOptions))


def check_predictor(steps: StepOptions) -> None:
    """The predictor's step needs most of each stiffness in the matrix: InputError naming the
    field that holds too little (:data:`PREDICTOR_LEAST_SHARES`); the Krylov correction is a
    solve of the predictor's step and needs it; the mass drag needs the linear implicit step."""
    if steps.mass_drag and steps.integrator != "implicit":
        raise InputError(f"mass_drag is taken into the linearly implicit step's matrix: it needs "
                         f"integrator 'implicit' (got {steps.integrator!r})", field="mass_drag")
    region = steps.krylov_region
    if not (isinstance(region, (int, float)) and np.isfinite(region) and 0.0 <= region <= 0.5):
        raise InputError(f"krylov_region is a radius about the mouth in metres, 0 (the whole "
                         f"face) to 0.5 (got {region!r})", field="krylov_region")
    if region and not steps.krylov_iterations:
        raise InputError("krylov_region confines the Krylov correction: it needs "
                         "krylov_iterations > 0", field="krylov_region")
    if not steps.predictor:
        if steps.krylov_iterations:
            raise InputError("krylov_iterations solves the step about its predictor: it needs "
                             "predictor=True", field="krylov_iterations")
        return
    for name, least in PREDICTOR_LEAST_SHARES.items():
        if getattr(steps, name) < least:
            raise InputError(f"{name} must be at least {least} with predictor=True (got "
                             f"{getattr(steps, name)}): with less stiffness in the implicit "
                             f"matrix the predictor's step blows up", field=name)


#: the method of each built-in preset: the anatomical preset's linearly implicit Euler at 4
#: steps per frame with the contacts stepped after each solve; the seeds' explicit Euler, the
#: fast paths at 1 ms (``lucero1999``) or at the paper's step where 1 ms overshoots
PRESET_STEPS = {
    "anatomical": StepOptions(integrator="implicit", substeps=4, fast_dt=1.0 / 240.0,
                              dt=1.0 / 240.0, implicit_contacts=True),
    "lucero1999": StepOptions(),
    "pitermann2001": StepOptions(fast_dt=0.33e-3),
    "calibrated": StepOptions(fast_dt=0.33e-3),
}


def split_overrides(overrides: dict) -> tuple[dict, dict]:
    """(the :class:`StepOptions` fields of ``overrides``, the rest)."""
    steps = {k: v for k, v in overrides.items() if k in STEP_FIELDS}
    return steps, {k: v for k, v in overrides.items() if k not in STEP_FIELDS}


__all__ = ["PREDICTOR_LEAST_SHARES", "PRESET_STEPS", "STEP_FIELDS", "StepOptions",
           "check_predictor", "split_overrides"]
