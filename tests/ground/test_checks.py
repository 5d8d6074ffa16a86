"""Parameters that check themselves (issue 28): one table of names, kinds and intervals
(facemech.checks) serves the Python API and the command line."""

from __future__ import annotations

import math
from dataclasses import fields

import pytest

from facemech import cli_options
from facemech.checks import CHOICES, KINDS, RANGES
from facemech.errors import InputError
from facemech.inverse.methods import LeastSquares, Powell
from facemech.params import PRESETS, Parameters, preset, preset_steps
from facemech.stepping import STEP_FIELDS, StepOptions


def test_an_unknown_material_is_an_error_naming_the_field():
    with pytest.raises(InputError, match="material") as exc:
        Parameters(material="contnuum")
    assert exc.value.field == "material"


@pytest.mark.parametrize("field, value", [("integrator", "eulr"), ("tissue", "anatomic"),
                                         ("material", 1), ("fixed_skull_contact", "yes"),
                                         ("predictor", "yes")])
def test_a_word_not_among_its_choices_is_an_error_naming_the_field(field, value):
    made = StepOptions if field in STEP_FIELDS else Parameters
    with pytest.raises(InputError) as exc:
        made(**{field: value})
    assert exc.value.field == field


def _outside(interval: str) -> list[float]:
    lo, hi = (float(v) for v in interval[1:-1].split(","))
    out = [math.nan, math.inf]
    out.append(lo if interval[0] == "(" else lo - 1.0)
    if math.isfinite(hi):
        out.append(hi if interval[-1] == ")" else hi * 2 + 1)
    return out


def _field_rows():
    names = {f.name for f in fields(Parameters)} | STEP_FIELDS
    return [(n, v) for n, r in RANGES.items() if n in names for v in _outside(r)]


@pytest.mark.parametrize("field, value", _field_rows())
def test_every_field_out_of_its_interval_is_refused_when_made(field, value):
    """Of the constants (:class:`Parameters`) and of the method (:class:`StepOptions`)."""
    if KINDS[field] == "int" and math.isfinite(value):
        value = int(value)
    made = StepOptions if field in STEP_FIELDS else Parameters
    with pytest.raises(InputError) as exc:
        made(**{field: value})
    assert exc.value.field == field


def test_the_constants_and_the_method_share_no_field():
    assert not {f.name for f in fields(Parameters)} & STEP_FIELDS


def test_the_presets_pass_their_own_checks_and_the_table_names_every_choice():
    for name in PRESETS:
        preset(name)
        preset_steps(name)
    from facemech.solvers.step import INTEGRATORS

    assert CHOICES["integrator"] == INTEGRATORS


def test_the_command_lines_intervals_are_the_tables():
    assert all(RANGES[name] == interval for name, interval in cli_options.RANGES.items())


#: the command line's numbers and the Python objects that take them
_API = {"window": LeastSquares, "tol": LeastSquares, "bend": LeastSquares, "smooth": LeastSquares,
        "effort": LeastSquares, "max_evaluations": LeastSquares, "dt": StepOptions,
        "substeps": StepOptions}


@pytest.mark.parametrize("name, value", [(n, v) for n in _API for v in
                                         _outside(cli_options.RANGES[n])])
def test_what_the_command_line_refuses_the_python_api_refuses(name, value):
    if KINDS[name] == "int" and math.isfinite(value):
        value = int(value)
    with pytest.raises(InputError) as exc:
        _API[name](**{name: value})
    assert exc.value.field == name
    with pytest.raises(InputError):
        cli_options.check_number("--" + name, value, cli_options.RANGES[name])
    if name == "max_evaluations":
        with pytest.raises(InputError):
            Powell(max_evaluations=value)


def test_tol_0_is_one_rule_for_the_command_line_and_python():
    """``tol`` 0 (iterate until no step gains) is taken by both, and a negative tol or one
    past 100 mm refused by both: the table's one interval [0, 100]."""
    assert cli_options.RANGES["tol"] == RANGES["tol"] == "[0, 100]"
    cli_options.check_number("--tol", 0.0, cli_options.RANGES["tol"])
    assert LeastSquares(tol=0.0).tol == 0.0
    for value in (-1e-9, 100.5):
        with pytest.raises(InputError):
            cli_options.check_number("--tol", value, cli_options.RANGES["tol"])
        with pytest.raises(InputError) as exc:
            LeastSquares(tol=value)
        assert exc.value.field == "tol"


def test_the_solver_options_of_a_run_are_checked_too():
    from facemech.solvers.step import solver_from_options

    for option, value in (("dt", 1.0), ("dt", -1e-5), ("substeps", 0)):
        with pytest.raises(InputError) as exc:
            solver_from_options("implicit", preset_steps("anatomical"), 60.0, **{option: value})
        assert exc.value.field == option


def test_the_inversions_and_analyses_objects_refuse_what_the_command_line_refuses():
    from facemech.inverse.workflow import JawMarkers
    from facemech.workflows.subject import Preparation

    for make, name, value in ((JawMarkers, "jaw_lead", 601), (JawMarkers, "jaw_lead", -1),
                              (Preparation, "max_gap", 0.0), (Preparation, "max_gap", 1e4),
                              (Preparation, "lowpass", -1.0), (Preparation, "lowpass", 2e3)):
        with pytest.raises(InputError):
            make(**{name: value})
        with pytest.raises(InputError):
            cli_options.check_number("--" + name, value, cli_options.RANGES[name])


def _entries(tmp):
    """The command line's numbers and the Python functions that take them, each called so that
    an in-range value fails later (a missing or unwritable file) and never runs the work."""
    from facemech.speech.alive import Liveliness
    from facemech.speech.tts import synthesize
    from facemech.viz.render import RenderOptions
    from facemech.viz.video import still
    from facemech.workflows import batch, experiments, markers, photo, regions, speak

    taken = tmp / "taken"
    taken.write_text("a file where a folder is wanted")
    missing = tmp / "missing"
    return {
        "rate_wpm": lambda v: synthesize("hello", voice="", rate_wpm=v),
        "strength": lambda v: speak.speak(taken, "hello", strength=v),
        "seed": lambda v: speak.speak(taken, "hello", alive=Liveliness(seed=v)),
        "aa": lambda v: RenderOptions(supersample=v),
        "time": lambda v: still(missing.with_suffix(".nc"), tmp / "x.png", time=v),
        "frames": lambda v: experiments.crosstalker(tmp / "x.json", frames=v,
                                                    preset=str(missing.with_suffix(".json"))),
        "utterances": lambda v: experiments.lucero2008(taken, utterances=v),
        "k": lambda v: regions.regions([], taken, k=v),
        "workers": lambda v: batch.run_batch(missing.with_suffix(".csv"), tmp / "b", workers=v),
        "ipd": lambda v: photo.face_from_photo_file(missing.with_suffix(".jpg"),
                                                    tmp / "t.npz", ipd=v),
        "distance": lambda v: photo.face_from_photo_file(missing.with_suffix(".jpg"),
                                                         tmp / "t.npz", distance=v),
        "reference": lambda v: markers.frame_file(missing.with_suffix(".csv"), tmp / "o.csv",
                                                  right="a", left="b", front="c", reference=v),
    }


_INSIDE = {"rate_wpm": 160, "strength": 1.0, "seed": 0, "aa": 2, "time": 0.5, "frames": 60,
           "utterances": 40, "k": 10, "workers": 2, "ipd": 63.4, "distance": 1.0,
           "reference": 0}


@pytest.mark.parametrize("name, value", [(n, v) for n in _INSIDE for v in
                                         _outside(cli_options.RANGES[n])])
def test_every_number_the_command_line_refuses_raises_through_its_python_entry(
        name, value, tmp_path):
    if KINDS[name] == "int" and math.isfinite(value):
        value = int(value)
    with pytest.raises(InputError) as exc:
        _entries(tmp_path)[name](value)
    assert exc.value.field == name
    with pytest.raises(InputError):
        cli_options.check_number("--" + name, value, cli_options.RANGES[name])


@pytest.mark.parametrize("name", sorted(_INSIDE))
def test_an_in_range_number_passes_its_python_entrys_check(name, tmp_path):
    """The entry goes past the check (and then fails on the missing or unwritable file)."""
    try:
        _entries(tmp_path)[name](_INSIDE[name])
    except Exception as e:  # noqa: BLE001 - anything but the check's refusal
        assert getattr(e, "field", None) != name, e


def test_physics_refuses_a_face_of_another_tissue_naming_both(seeds_face):
    """No silent swap (issue 28): the caller rebuilds the face for the preset, explicitly."""
    from facemech.geometry.builder import for_tissue
    from facemech.physics.assembly import Physics

    anatomical = preset("anatomical")
    assert seeds_face.tissue == "uniform" != anatomical.tissue
    with pytest.raises(InputError, match="uniform.*anatomical") as exc:
        Physics.build(seeds_face, anatomical)
    assert exc.value.field == "face"
    rebuilt = for_tissue(seeds_face, anatomical.tissue)
    assert Physics.build(rebuilt, anatomical).model is rebuilt
