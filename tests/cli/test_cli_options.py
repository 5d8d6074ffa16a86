"""Numeric options are checked before a command runs (issue 18): finite, in range, the option
named in one stderr line, exit 2, nothing written; and the option catalogue is complete."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from conftest import run_cli
from facemech import cli, cli_options
from facemech.errors import InputError
from facemech.io.markers import write_markers
from facemech.markerset import MarkerSet


def _refused(monkeypatch, capsys, tmp_path, *args) -> str:
    before = sorted(tmp_path.iterdir())
    code, out, err = run_cli(monkeypatch, capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert sorted(tmp_path.iterdir()) == before, "a file was written"
    return lines[0]


@pytest.mark.parametrize("args, option", [
    (("simulate", "-o", "{t}/r.nc", "--activity", "{t}/a.csv", "--dt", "nan"), "--dt"),
    (("simulate", "-o", "{t}/r.nc", "--activity", "{t}/a.csv", "--dt", "inf"), "--dt"),
    (("simulate", "-o", "{t}/r.nc", "--activity", "{t}/a.csv", "--dt", "-1e-5"), "--dt"),
    (("simulate", "-o", "{t}/r.nc", "--activity", "{t}/a.csv", "--substeps", "0"), "--substeps"),
    (("markers", "resample", "{t}/m.csv", "-o", "{t}/r.csv", "--rate", "0"), "--rate"),
    (("markers", "resample", "{t}/m.csv", "-o", "{t}/r.csv", "--rate", "1e9"), "--rate"),
    (("markers", "fill-gaps", "{t}/m.csv", "-o", "{t}/g.csv", "--max-gap", "-inf"), "--max-gap"),
    (("emg", "process", "{t}/e.csv", "-o", "{t}/a.csv", "--rate", "nan"), "--rate"),
    (("render", "{t}/r.nc", "-o", "{t}/v.mp4", "--aa", "9"), "--aa"),
    (("still", "{t}/r.nc", "-o", "{t}/s.png", "--time", "nan"), "--time"),
    (("speak", "hello", "-o", "{t}/sp", "--rate", "20"), "--rate"),
    (("speak", "hello", "-o", "{t}/sp", "--strength", "nan"), "--strength"),
    (("regions", "{t}/m.csv", "-o", "{t}/rg", "-k", "0"), "-k"),
    (("invert", "--markers", "{t}/m.csv", "-o", "{t}/i.nc", "--window", "0"), "--window"),
    (("invert", "--markers", "{t}/m.csv", "-o", "{t}/i.nc", "--noise", "-1"), "--noise"),
    (("invert", "--markers", "{t}/m.csv", "-o", "{t}/i.nc", "--tol", "-1"), "--tol"),
    (("experiment", "pitermann2001-synthetic", "--noise", "nan"), "--noise"),
    (("experiment", "lucero2008", "-o", "{t}/l", "--frames", "1"), "--frames"),
])
def test_numeric_options_are_checked_before_anything_runs(monkeypatch, capsys, tmp_path, args,
                                                          option):
    line = _refused(monkeypatch, capsys, tmp_path, *(a.format(t=tmp_path) for a in args))
    assert line.startswith(f"facemech: error: option {option}: must be a finite number"), line


@pytest.mark.parametrize("value, interval, ok", [
    (0.0, "(0, 1]", False), (1e-12, "(0, 1]", True), (1.0, "(0, 1]", True),
    (1.0, "[0, 1)", False), (0.0, "[0, 1)", True), (1e300, "[0, inf)", True),
    (math.inf, "[0, inf)", False), (math.nan, None, False), (-5.0, None, True),
    (math.nan, "[0, inf)", False), (-math.inf, "(-inf, 0]", False), (4, "[1, 4]", True),
])
def test_intervals_are_open_or_closed_as_written(value, interval, ok):
    if ok:
        cli_options.check_number("--x", value, interval)
    else:
        with pytest.raises(InputError, match="option --x"):
            cli_options.check_number("--x", value, interval)


def _commands():
    for group in (cli.app, cli.face_app, cli.emg_app, cli.markers_app, cli.experiment_app):
        for info in group.registered_commands:
            yield info.callback


def test_every_option_has_help_and_every_range_a_number_option():
    numeric = set()
    for fn in _commands():
        for p in inspect.signature(fn).parameters.values():
            assert p.default.help, f"{fn.__name__}: --{p.name} has no help"
            if p.annotation in (int, float, int | None, float | None):
                numeric.add(p.name)
    assert set(cli_options.RANGES) <= numeric, set(cli_options.RANGES) - numeric
    # every help override names a real command and parameter
    params = {f"{fn.__wrapped__.__name__}.{p}" for fn in _commands()
              for p in inspect.signature(fn).parameters}
    overrides = {k for k in cli_options.HELP if "." in k}
    assert overrides <= params, overrides - params


def _markers(tmp_path):
    t = np.arange(12) / 60.0
    pos = np.zeros((12, 3, 3))
    pos[:, 0] = [-0.03, 0, 0]
    pos[:, 1] = [0.03, 0, 0]
    pos[:, 2] = [0, 0.001, 0.02]
    pos[:, 2, 1] += 0.002 * np.sin(2 * np.pi * t)
    path = tmp_path / "m.csv"
    write_markers(path, MarkerSet(pos, ("R", "L", "F"), 60.0, t), units="mm")
    return path


@pytest.mark.parametrize("eps", ["-1mm", "nanmm", "0", "2m", "inf"])
def test_region_epsilon_must_be_a_small_positive_length(monkeypatch, capsys, tmp_path, eps):
    m = _markers(tmp_path)
    line = _refused(monkeypatch, capsys, tmp_path, "regions", m, m, "-o", tmp_path / "rg",
                    f"--eps={eps}")
    assert "field 'eps'" in line and "between 0 and 100 mm" in line, line


def test_anatomical_frame_reference_outside_the_recording(monkeypatch, capsys, tmp_path):
    m = _markers(tmp_path)
    line = _refused(monkeypatch, capsys, tmp_path, "markers", "frame", m, "-o", tmp_path / "f.csv",
                    "--right", "R", "--left", "L", "--front", "F", "--reference", "12")
    assert line.startswith(f"facemech: error: {m}: field 'reference'") and "0..11" in line, line


@pytest.mark.parametrize("text", ["nan,1", "1,inf", "-1,2", "2,1", "1"])
def test_rest_intervals_are_finite_ordered_seconds(text):
    from facemech.workflows.emg import as_interval

    with pytest.raises(InputError, match="field 'baseline'"):
        as_interval(text, "baseline")
    assert as_interval("0,1.5", "baseline") == (0.0, 1.5)


@pytest.mark.parametrize("threads", ["0", "-1", "100000"])
def test_thread_count_is_checked(monkeypatch, capsys, threads):
    code, _, err = run_cli(monkeypatch, capsys, "--threads", threads, "face", "info")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "field 'threads'" in lines[0], err


def test_thread_count_is_set(monkeypatch, capsys):
    from facemech.physics import threads

    before = threads.get_threads()
    try:
        code, _, err = run_cli(monkeypatch, capsys, "--threads", "1", "face", "info")
        assert code == 0, err
        assert threads.get_threads() == 1
    finally:
        threads.set_threads(before)
