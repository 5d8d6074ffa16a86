"""The face model as one value: a face, its parameters and its compiled physics, made once.

A command makes its :class:`Model` where it starts (:func:`model`: the preset read, the tissue
geometry of the preset applied to the face, :class:`~facemech.physics.assembly.Physics`
built); every library function below takes it as it is, and none rebuilds it or falls back to
default parameters (MuJoCo's ``mjModel``, constant, beside the state).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..geometry.builder import FaceModel, for_tissue, load_face
from ..params import DEFAULT_PRESET, Parameters
from ..params import preset as named_preset
from .assembly import Physics


@dataclass(frozen=True, eq=False)
class Model:
    """A face with its parameters and compiled physics (read-only).

    Attributes
    ----------
    physics : Physics -- the force kernels' constants of ``face`` under ``params``
    face : FaceModel -- the face simulated, in the preset's tissue geometry
    params : Parameters -- the constants of the model (SI)
    """

    physics: Physics

    @property
    def face(self) -> FaceModel:
        return self.physics.model

    @property
    def params(self) -> Parameters:
        return self.physics.params

    def with_params(self, **changes) -> Model:
        """A new model of the same face with some parameters changed (rebuilt once)."""
        return model(self.face, self.params.with_(**changes))


def model(face: FaceModel | str | Path | None = None,
          preset: str | Path | Parameters | None = None, **overrides) -> Model:
    """The :class:`Model` of a face under a preset: the one place where a preset meets a face.

    Parameters
    ----------
    face : FaceModel, a built-in face name or a face file (None: the built-in ``default``);
        rebuilt for the preset's tissue geometry here, once
        (:func:`~facemech.geometry.builder.for_tissue`)
    preset : a preset's name, a preset file, or :class:`Parameters` (None: the default preset)
    **overrides : Parameters fields changed from the preset's (SI)
    """
    if isinstance(preset, Parameters):
        params = preset
    else:
        params = named_preset(DEFAULT_PRESET if preset is None else str(preset))
    if overrides:
        params = params.with_(**overrides)
    face = (for_tissue(face, params.tissue) if isinstance(face, FaceModel)
            else load_face(face, tissue=params.tissue))
    return Model(Physics.build(face, params))


__all__ = ["Model", "model"]
