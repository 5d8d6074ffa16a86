"""Time stepping: the paper's explicit Euler and two fast implicit integrators.

Each solver advances an immutable :class:`~facemech.solvers.state.State` through one control
frame with the activity held (Lucero & Munhall 1999): a frozen description, ``init(physics)``
returning a :class:`~facemech.solvers.solver_state.SolverState`, and ``step(solver_state, state,
controls)`` returning the next state. ``ExplicitEuler(dt)`` (``"euler"``, the paper's 0.33 ms,
:mod:`.explicit`); ``LinearImplicitEuler(substeps)`` (``"implicit"``) and ``Rosenbrock2``
(``"rosenbrock"``) on a constant factorised matrix (:mod:`.implicit`).

:class:`Stepper` turns a model's method (:class:`~facemech.stepping.StepOptions`) into one solver
object once, and a frame's activity and jaw target into
:class:`~facemech.solvers.state.Controls`. The jaw drive ``"ramp"`` (default) moves the pose
linearly over the frame, ``"hold"`` sets it at the frame's start as the paper does.
"""

from __future__ import annotations

import numpy as np

from ..checks import check_value
from ..errors import InputError
from ..physics.model import Model
from ..stepping import StepOptions
from .explicit import ExplicitEuler
from .implicit import IMPLICIT_STIFFNESS_SHARE, ROS2_GAMMA, LinearImplicitEuler, Rosenbrock2
from .jaw import jaw_poses
from .solver_state import Solver, SolverState
from .state import Controls, State

#: the integrators' names, as presets and the command line give them, and their solvers
SOLVERS = {"euler": ExplicitEuler, "implicit": LinearImplicitEuler, "rosenbrock": Rosenbrock2}
INTEGRATORS = tuple(SOLVERS)
JAW_DRIVES = ("ramp", "hold")


def solver_from_options(integrator: str | None, steps: StepOptions, frame_rate: float, *,
                        substeps: int | None = None, dt: float | None = None) -> Solver:
    """The solver object an integrator's name and its options stand for.

    Parameters
    ----------
    integrator : {"euler", "implicit", "rosenbrock"} or None (the preset's)
    steps : StepOptions -- the preset's method, for the defaults (``dt``, ``substeps``) and
        the implicit methods' options
    frame_rate : Hz, the model's frame rate
    substeps : int, optional
        Steps per frame of the implicit integrators (default: the preset's). An error with
        ``euler``, which takes ``dt``.
    dt : float, optional, s
        Step of explicit Euler (default: the preset's). With an implicit integrator it may only
        repeat the step that ``substeps`` gives (an error otherwise, naming ``substeps``).

    Raises
    ------
    InputError
        An unknown name, or an option the method does not take (``field`` names it).
    """
    name = steps.integrator if integrator is None else integrator
    for option, value in (("substeps", substeps), ("dt", dt)):
        if value is not None:  # the command line's intervals (facemech.checks)
            check_value(option, value)
    if name not in SOLVERS:
        raise InputError(f"unknown integrator {name!r} (expected one of "
                         f"{', '.join(INTEGRATORS)})", field="integrator")
    if name == "euler":
        if substeps is not None:
            raise InputError("substeps sets the steps per frame of the implicit integrators; "
                             "explicit Euler takes its step from dt", field="substeps")
        return ExplicitEuler(steps.dt if dt is None else dt)
    solver = SOLVERS[name](steps.substeps if substeps is None else substeps, steps)
    if dt is not None:
        h = 1.0 / frame_rate / solver.substeps
        if not abs(float(dt) - h) <= 1e-9 * h:
            raise InputError(f"dt ({float(dt) * 1e3:.3g} ms) is the explicit Euler step; the "
                             f"{name} integrator takes {solver.substeps} steps per frame "
                             f"({h * 1e3:.3g} ms): set substeps instead", field="dt")
    return solver


class Stepper:
    """Advances states of one face model with one integrator.

    Parameters
    ----------
    model : Model -- the face, its physics and the preset's method
        (:func:`facemech.physics.model.model`)
    integrator : {"euler", "implicit", "rosenbrock"} or a :class:`Solver`, optional
        Default: the preset's (``model.steps.integrator``): ``euler`` for the seeds' presets,
        ``implicit`` for the anatomical one, whose physiological forces and tissue viscosity
        make explicit steps unstable. A solver object (``ExplicitEuler(dt)``,
        ``LinearImplicitEuler(substeps)``, ``Rosenbrock2(substeps)``, or any object with
        the protocol's ``name``, ``init`` and ``step``) carries its own options.
    substeps : int, optional
        Steps per frame of the implicit integrators (default: the preset's, 4: h = 4.2 ms); an
        error with ``euler``.
    dt : float, optional
        Step of the explicit integrator (default: the preset's 0.33 ms). With an implicit
        integrator it may only repeat the step that ``substeps`` gives (an error otherwise).
    jaw_drive : {"ramp", "hold"}

    Attributes
    ----------
    solver : Solver
    solver_state : SolverState -- ``solver.init(physics)``
    integrator : str -- the solver's name
    n_steps : int -- steps per frame
    dt : float, s -- the step taken
    """

    def __init__(self, model: Model, *, integrator=None, substeps: int | None = None,
                 dt: float | None = None, jaw_drive: str = "ramp"):
        if jaw_drive not in JAW_DRIVES:
            raise InputError(f"unknown jaw drive {jaw_drive!r} (expected ramp or hold)",
                             field="jaw_drive")
        if isinstance(integrator, Solver):
            for name, value in (("substeps", substeps), ("dt", dt)):
                if value is not None:
                    raise InputError(f"give {name} to the solver object, not beside it",
                                     field=name)
            solver = integrator
        else:
            solver = solver_from_options(integrator, model.steps, model.params.frame_rate,
                                         substeps=substeps, dt=dt)
        physics = model.physics
        self.physics = physics
        self.solver = solver
        self.solver_state: SolverState = solver.init(physics)
        self.integrator = solver.name
        self.jaw_drive = jaw_drive
        self.frame_duration = self.solver_state.frame_duration
        self.n_steps = self.solver_state.n_steps
        self.dt = self.solver_state.step

    def jaw_pose(self, jaw) -> np.ndarray:
        """The jaw pose (3,) (angle rad, shift_y m, shift_z m) of a frame's jaw target: a (3,)
        pose as given, or an angle completed by the preset's ``jaw_kinematics`` (the coupled
        condyle glide, or no shift for the hinge; :func:`~facemech.solvers.jaw.jaw_poses`)."""
        pose = np.asarray(jaw, float)
        if pose.ndim == 0:
            return jaw_poses(float(pose), self.physics.params)
        if pose.shape != (3,):
            raise InputError(f"a jaw target is an angle or a (3,) pose, got shape {pose.shape}",
                             field="jaw")
        return pose.copy()

    def controls(self, state: State, activity: np.ndarray, jaw) -> Controls:
        """The :class:`Controls` of a frame from ``state`` with ``activity`` (groups,) towards the
        jaw target ``jaw`` (an angle or a (3,) pose), as ``jaw_drive`` says."""
        target = self.jaw_pose(jaw)
        start = target if self.jaw_drive == "hold" else state.jaw_pose
        return Controls(np.asarray(activity, float), start, target)

    def advance(self, state: State, activity: np.ndarray, jaw) -> State:
        """Advance ``state`` by one frame with ``activity`` (one per group, [0, 1]).

        The jaw goes from the state's pose (``jaw_angle``, ``jaw_shift``) to ``jaw``, as
        ``jaw_drive`` says: ``ramp`` moves the pose linearly over the frame, ``hold`` sets it
        at the frame's start. ``jaw`` is an angle (rad; the condyles' shift then follows the
        preset's ``jaw_kinematics``: the coupled glide, or none for the hinge) or a (3,) pose
        (angle rad, shift_y m, shift_z m). Returns a new :class:`State`; ``state`` is not
        modified.
        """
        return self.solver.step(self.solver_state, state, self.controls(state, activity, jaw))


__all__ = ["Stepper", "INTEGRATORS", "JAW_DRIVES", "SOLVERS", "Solver", "solver_from_options",
           "ExplicitEuler", "LinearImplicitEuler", "Rosenbrock2", "ROS2_GAMMA",
           "IMPLICIT_STIFFNESS_SHARE"]
