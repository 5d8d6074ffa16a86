"""An input group declared once (facemech.inputs): its fields give the command line's options,
the manifest's keys and kinds, and the Python object, by the same names and defaults."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from facemech.errors import InputError
from facemech.inputs import REQUIRED, from_keys, from_manifest, inputs_of, manifest_kinds, option


@dataclass(frozen=True)
class Drive:
    """A test group: a file under another key, a renamed flag, a pair read as text."""

    path: Path = option(REQUIRED, "the file", key="drive_file")
    gain: float | None = option(None, "gain, 1/s", unit="1/s", flags=("--k",))
    frames: int = option(3, "frames")
    held: bool = option(False, "hold it")
    span: str | tuple[float, float] | None = option(None, "START,STOP (s)", cli=str | None)
    preset: str = option("anatomical", "a name or a file", kind="file_or_name")

    def __post_init__(self):
        if self.frames < 1:
            raise InputError("frames must be >= 1", field="frames")


def test_each_field_is_one_input_with_its_key_flags_and_kind():
    got = {i.name: i for i in inputs_of(Drive)}
    assert list(got) == ["path", "gain", "frames", "held", "span", "preset"]
    assert (got["path"].key, got["path"].flags, got["path"].manifest_key) == (
        "drive_file", ("--drive-file",), "drive_file")
    assert got["path"].default is REQUIRED and got["path"].help == "the file"
    assert (got["gain"].key, got["gain"].manifest_key, got["gain"].unit) == ("gain", "k", "1/s")
    assert got["span"].type == str | None  # the command line's type, not the field's
    assert manifest_kinds(Drive) == {"drive_file": "path", "k": "float", "frames": "int",
                                     "held": "bool", "span": "str", "preset": "file_or_name"}


def test_a_group_is_made_from_keys_and_from_a_manifest_and_checks_itself():
    made = from_keys(Drive, {"drive_file": Path("a.csv"), "gain": 2.0, "other": 1})
    assert made == Drive(Path("a.csv"), gain=2.0)  # not given: the defaults; others ignored
    assert from_manifest(Drive, {"drive_file": "a.csv", "k": 0.5}).gain == 0.5
    with pytest.raises(InputError) as e:
        from_keys(Drive, {"drive_file": Path("a.csv"), "frames": 0})
    assert e.value.field == "frames"


def test_a_type_without_a_kind_must_name_one():
    @dataclass(frozen=True)
    class Odd:
        shape: list[int] | None = option(None, "a list")

    with pytest.raises(TypeError, match="kind"):
        inputs_of(Odd)
