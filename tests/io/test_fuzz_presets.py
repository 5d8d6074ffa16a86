"""Preset files (``--preset file.json``, :func:`facemech.params.read_preset`) that survive
property-based testing (issue 58): any JSON document, a valid preset with one value replaced
by any JSON value, and the valid file's bytes mutated, end in a valid
:class:`~facemech.params.Parameters` or in an :class:`~facemech.errors.InputError` naming the
file (and, for a JSON document, the field): never another exception. Profiles as in
``test_fuzz_readers`` (``FACEMECH_FUZZ=ci|deep``)."""

from __future__ import annotations

import json
import math

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from facemech.errors import InputError  # noqa: E402
from facemech.params import Parameters, read_preset, read_preset_steps, write_preset  # noqa: E402
from test_fuzz_readers import PROFILE, fuzzed  # noqa: E402

#: JSON scalars a hostile or broken preset holds: huge integers (beyond a float), NaN and the
#: infinities (Python's json reads and writes them), booleans where numbers go, odd text
SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(-10**400, 10**400),
    st.sampled_from([10**400, -10**400, 2**63, 0, -1, 1]),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
    st.sampled_from(["glide", "hinge", "anatomical", "facemech-preset", "1.5", "nan", ""]))
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=10), inner, max_size=4)),
    max_leaves=12)
KEYS = {
    "": ["format", "version", "name", "base", "scales", "jaw", "muscle", "step", "extra"],
    "scales": ["force", "stiffness", "lips", "sphincter", "nose"],
    "jaw": ["kinematics", "glide_rate_mm_per_rad", "glide_slope_deg", "hinge"],
    "muscle": ["fv_vmax_fibre_lengths_per_s", "fv_curvature", "activation_tau_ms",
               "activation_damping", "tau"],
    "step": ["substeps", "predictor", "krylov_iterations", "krylov_region_mm",
             "mass_drag_per_s", "implicit_stiffness_share", "viscous_time_ms", "stiffening",
             "volume_floor", "volume_floor_modulus_pa", "dt"],
}


def _valid() -> dict:
    return {"format": "facemech-preset", "version": 1, "name": "s01", "base": "anatomical",
            "scales": {"force": 1.1, "stiffness": 0.9, "lips": 1.2, "sphincter": 1.0},
            "jaw": {"kinematics": "glide", "glide_rate_mm_per_rad": 8.0,
                    "glide_slope_deg": 30.0},
            "muscle": {"fv_vmax_fibre_lengths_per_s": 11.0, "activation_tau_ms": 16.5},
            "step": {"substeps": 4, "viscous_time_ms": 3.0}}


@st.composite
def mutated(draw) -> dict:
    """The valid preset with one to three entries replaced by any JSON value, removed, or
    added (known or unknown keys), at the top or inside a block."""
    doc = _valid()
    for _ in range(draw(st.integers(1, 3))):
        block = draw(st.sampled_from(sorted(KEYS)))
        where = doc if block == "" else doc.get(block)
        if not isinstance(where, dict):
            continue
        key = draw(st.sampled_from(KEYS[block]))
        if draw(st.booleans()) and key in where:
            del where[key]
        else:
            where[key] = draw(VALUES)
    return doc


def _read(path, text: str):
    """Write ``text`` to ``path`` and read it as a preset: Parameters or an InputError naming
    the file, nothing else (the test fails on any other exception)."""
    path.write_text(text, encoding="utf-8")
    try:
        p = read_preset(path)
    except InputError as exc:
        assert exc.source == str(path), exc.one_line()
        return exc
    assert isinstance(p, Parameters)
    return p


def _field_of_json(result) -> None:
    """A JSON document's refusal names its field; a read preset holds only finite numbers."""
    if isinstance(result, InputError):
        assert result.field, result.one_line()
        assert "\n" not in result.one_line()
    else:
        for name in ("k_force", "shear_superficial", "glide_rate", "glide_slope", "fv_vmax",
                     "tau_activation", "viscous_time"):
            assert math.isfinite(getattr(result, name)), name


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("presets")


def test_the_valid_preset_is_read(folder):
    p = _read(folder / "valid.json", json.dumps(_valid()))
    assert isinstance(p, Parameters) and p.name == "s01"
    assert read_preset_steps(folder / "valid.json").substeps == 4
    assert p.viscous_time == pytest.approx(3e-3) and p.glide_rate == pytest.approx(8e-3)


@PROFILE
@given(doc=VALUES)
def test_any_json_document_is_a_preset_or_a_clean_error(folder, doc):
    _field_of_json(_read(folder / "any.json", json.dumps(doc)))


@PROFILE
@given(doc=mutated())
def test_a_mutated_preset_is_a_preset_or_a_clean_error(folder, doc):
    _field_of_json(_read(folder / "mutated.json", json.dumps(doc)))


@PROFILE
@given(data=fuzzed(json.dumps(_valid(), indent=1).encode()))
def test_a_preset_files_bytes_fuzzed_are_a_preset_or_a_clean_error(folder, data):
    path = folder / "bytes.json"
    path.write_bytes(data)
    try:
        assert isinstance(read_preset(path), Parameters)
    except InputError as exc:
        assert exc.source == str(path) and "\n" not in exc.one_line()


@pytest.mark.parametrize("text, field", [
    ('{"format": "facemech-preset", "base": "anatomical", "scales": {}, '
     '"step": {"substeps": 1e999}}', "step.substeps"),
    ('{"format": "facemech-preset", "base": "anatomical", "scales": {}, '
     '"step": {"substeps": NaN}}', "step.substeps"),
    ('{"format": "facemech-preset", "base": "anatomical", "scales": {}, '
     '"muscle": {"fv_curvature": 1' + "0" * 400 + '}}', "muscle.fv_curvature"),
    ('{"format": "facemech-preset", "base": "anatomical", "scales": {"force": true}}',
     "force"),
    ('{"format": "facemech-preset", "base": "anatomical", "scales": {}, '
     '"jaw": {"kinematics": ["glide"]}}', "jaw.kinematics"),
    ("[" * 100_000, None),
], ids=["inf-steps", "nan-steps", "huge-number", "bool-scale", "list-name", "deep"])
def test_found_by_the_properties(folder, text, field):
    """Cases the properties found: a count of steps that is infinite or NaN, a number beyond
    a float, a boolean scale, a list where a name goes, a nesting deeper than Python's stack."""
    err = _read(folder / "found.json", text)
    assert isinstance(err, InputError) and err.field == field, err
    write_preset(folder / "written.json", "s", {"force": 1.2})  # what calibrate writes is read
    assert read_preset(folder / "written.json").name == "s"
