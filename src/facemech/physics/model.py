"""The face model as one value: a face, its parameters, its compiled physics and the preset's
numerical method, made once.

A command makes its :class:`Model` where it starts (:func:`model`: the preset read, the tissue
geometry of the preset applied to the face, :class:`~facemech.physics.assembly.Physics`
built); every library function below takes it as it is, and none rebuilds it or falls back to
default parameters (MuJoCo's ``mjModel`` with its ``opt``, constant, beside the state).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..geometry.builder import FaceModel, for_tissue, load_face
from ..params import DEFAULT_PRESET, Parameters, Preset, preset_steps
from ..params import preset as named_preset
from ..stepping import PRESET_STEPS, StepOptions, split_overrides
from .assembly import Physics


@dataclass(frozen=True, eq=False)
class Model:
    """A face with its parameters and compiled physics (read-only).

    Attributes
    ----------
    physics : Physics -- the force kernels' constants of ``face`` under ``params``
    steps : StepOptions -- the preset's numerical method (the solvers' defaults)
    face : FaceModel -- the face simulated, in the preset's tissue geometry
    params : Parameters -- the constants of the model (SI)
    """

    physics: Physics
    steps: StepOptions

    @property
    def face(self) -> FaceModel:
        return self.physics.model

    @property
    def params(self) -> Parameters:
        return self.physics.params

    def with_steps(self, **changes) -> Model:
        """The same model stepped otherwise (its physics kept, not rebuilt)."""
        return Model(self.physics, self.steps.with_(**changes))


def model(face: FaceModel | str | Path | None = None,
          preset: str | Path | Parameters | Preset | None = None, *,
          steps: StepOptions | None = None, **overrides) -> Model:
    """The :class:`Model` of a face under a preset: the one place where a preset meets a face.

    Parameters
    ----------
    face : FaceModel, a built-in face name or a face file (None: the built-in ``default``);
        rebuilt for the preset's tissue geometry here, once
        (:func:`~facemech.geometry.builder.for_tissue`)
    preset : a preset's name, a preset file, :class:`Parameters` or a
        :class:`~facemech.params.Preset` (None: the default preset)
    steps : the numerical method (default: the preset's, :func:`facemech.params.preset_steps`;
        for :class:`Parameters` that of the built-in preset of their name, else the anatomical
        preset's for a continuum tissue and the seeds' otherwise)
    **overrides : fields of :class:`Parameters` or of :class:`StepOptions` changed from the
        preset's (SI)
    """
    if isinstance(preset, Preset):
        params, steps = preset.params, preset.steps if steps is None else steps
    elif isinstance(preset, Parameters):
        params = preset
        if steps is None:
            steps = PRESET_STEPS.get(params.name) or PRESET_STEPS[
                "anatomical" if params.is_continuum else "lucero1999"]
    else:
        name = DEFAULT_PRESET if preset is None else str(preset)
        params = named_preset(name)
        steps = preset_steps(name) if steps is None else steps
    method, physical = split_overrides(overrides)
    if physical:
        params = params.with_(**physical)
    if method:
        steps = steps.with_(**method)
    face = (for_tissue(face, params.tissue) if isinstance(face, FaceModel)
            else load_face(face, tissue=params.tissue))
    return Model(Physics.build(face, params), steps)


__all__ = ["Model", "model"]
