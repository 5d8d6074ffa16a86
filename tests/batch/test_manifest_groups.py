"""A manifest's row makes its job's input groups when it is read: a conflict of options (two
jaw drives) or a number out of its interval is an error naming the row, before anything runs;
the groups reach the workflow as the command line hands them."""

from __future__ import annotations

import pytest

from facemech.errors import InputError
from facemech.inputs import from_manifest
from facemech.jaw.inputs import JawMarkers, JawSource
from facemech.workflows.batch_jobs import read_manifest


def _manifest(tmp_path, header, row):
    (tmp_path / "a.csv").write_text("time,OOS\n0,0\n1,0\n")
    (tmp_path / "m.csv").write_text("x\n")
    path = tmp_path / "batch.csv"
    path.write_text(f"id,job,{header}\nitem1,simulate,{row}\n")
    return path


def test_two_jaw_drives_in_a_row_are_refused_when_read(tmp_path):
    path = _manifest(tmp_path, "activity,jaw_chin,jaw_incisor,chin_marker", "a.csv,m.csv,LI,R01")
    with pytest.raises(InputError) as e:
        read_manifest(path)
    assert e.value.message.startswith("row 1: give one jaw drive") and e.value.source == str(path)


def test_a_jaw_lead_out_of_its_interval_is_refused_when_read(tmp_path):
    (tmp_path / "m.csv").write_text("x\n")
    path = tmp_path / "batch.toml"
    path.write_text('[[item]]\nid = "i"\njob = "invert"\nmarkers = "m.csv"\njaw_lead = 601\n')
    with pytest.raises(InputError) as e:
        read_manifest(path)
    assert "row 1" in e.value.message and e.value.field == "jaw_lead"


def test_a_row_gives_the_groups_the_command_line_would(tmp_path):
    path = _manifest(tmp_path, "activity,jaw-chin,jaw_second_marker,bite_block",
                     "a.csv,m.csv,M2,yes")
    item = read_manifest(path)[0]
    assert from_manifest(JawSource, item.options) == JawSource(
        markers=str((tmp_path / "m.csv").resolve()), second_marker="M2", bite_block=True)
    assert from_manifest(JawMarkers, {"chin_marker": "R01", "jaw_lead": 0}) == JawMarkers(
        "R01", jaw_lead=0)
