"""The commands' input groups are declared once: ``simulate``'s, ``invert``'s, ``speak``'s,
``analyse``'s and the ``markers`` commands' options, their
batch jobs' keys and the workflows' objects are the groups' fields (facemech.inputs)."""

from __future__ import annotations

import inspect
from pathlib import Path

from facemech import cli, cli_options
from facemech.inputs import REQUIRED, inputs_of
from facemech.workflows.batch_jobs import JOBS

GROUPED = {"simulate": ("controls", "jaw_source", "stepping"),
           "invert": ("marker_file", "model", "jaw_markers", "inversion", "fit"),
           "speak": ("speaking", "recording", "alive"),
           "analyse": ("analysis", "preparation"), "markers_info": ("reader",),
           "markers_convert": ("reader",), "markers_trim": ("bounds", "reader")}


def _command(name):
    return next(i.callback for i in (*cli.app.registered_commands,
                                     *cli.markers_app.registered_commands)
                if i.callback.__wrapped__.__name__ == name)


def test_each_option_of_a_group_is_its_declared_field():
    for command, groups in GROUPED.items():
        params = inspect.signature(_command(command)).parameters
        for group in groups:
            for i in inputs_of(cli_options.GROUPS[group]):
                opt = params[i.key].default
                assert opt.default == (... if i.default is REQUIRED else i.default), i.key
                assert opt.help == cli_options.help_for(command, i.key, i) and opt.help, i.key
                assert params[i.key].annotation == i.type, i.key


def test_the_batch_jobs_take_the_same_groups_by_the_options_names():
    for command, groups in GROUPED.items():
        if command not in JOBS:
            continue
        job = JOBS[command]
        for group in groups:
            cls = cli_options.GROUPS[group]
            assert cls in job.groups
            for i in inputs_of(cls):
                assert job.options[i.manifest_key] == i.kind, (command, i.key)
    # what the manifest had drifted from: invert's --max-rate, --map read as "map"
    assert JOBS["invert"].options["max_rate"] == "float"
    assert JOBS["invert"].options["map"] == "path" and "map_file" not in JOBS["invert"].options
    # the simulate job's keys, as before the groups
    assert set(JOBS["simulate"].options) == {
        "activity", "emg", "emg_baseline", "emg_calibration", "jaw_chin", "chin_marker",
        "jaw_second_marker", "jaw_angle", "jaw_incisor", "jaw_molar", "bite_block", "units",
        "face", "preset", "jaw_kinematics", "integrator", "substeps", "dt", "jaw_drive"}
    # the speak job's keys: those before the groups, and the command's four it lacked
    assert set(JOBS["speak"].options) == {
        "text", "audio", "textgrid", "voice", "rate", "word_tier", "phone_tier", "strength",
        "face", "preset", "video", "blinks", "gaze", "head_motion", "seed", "view", "size",
        "background", "aa", "scale", "plan", "plan_iterations", "phone_labels"}


def test_a_group_is_made_from_the_command_line_and_checks_itself(monkeypatch):
    from facemech.jaw.inputs import JawSource
    from facemech.workflows.inputs import Stepping

    seen = {}
    monkeypatch.setattr("facemech.workflows.simulate.simulate_files",
                        lambda **kw: seen.update(kw), raising=True)
    monkeypatch.setattr(cli, "_staged", lambda run, **kw: run(**kw))
    from typer.testing import CliRunner

    res = CliRunner().invoke(cli.app, ["simulate", "-o", "r.nc", "--activity", "a.csv",
                                       "--jaw-chin", "m.csv", "--jaw-second-marker", "M2",
                                       "--substeps", "3"])
    assert res.exit_code == 0, res.output
    assert seen["jaw"] == JawSource(markers=Path("m.csv"), second_marker="M2")
    assert seen["stepping"] == Stepping(substeps=3)
    res = CliRunner().invoke(cli.app, ["simulate", "-o", "r.nc", "--activity", "a.csv",
                                       "--jaw-incisor", "LI"])
    assert res.exit_code != 0 and "--jaw-chin" in str(res.exception)


def test_speak_takes_its_groups_from_the_command_line(monkeypatch):
    from typer.testing import CliRunner

    from facemech.workflows.inputs import Alive, Recording, Speaking

    seen = {}
    monkeypatch.setattr("facemech.workflows.speech.speak", lambda *a, **kw: seen.update(kw))
    monkeypatch.setattr("facemech.workflows.speech.speak_report", lambda res, out: [])
    monkeypatch.setattr(cli, "_staged", lambda run, **kw: run(**kw))
    res = CliRunner().invoke(cli.app, ["speak", "hello", "-o", "s", "--rate", "200", "--no-plan",
                                       "--scale", "word:hello=1.5", "--scale", "class:open=0.8",
                                       "--no-video", "--no-gaze", "--seed", "7"])
    assert res.exit_code == 0, res.output
    assert seen["speaking"] == Speaking(rate_wpm=200, plan=False, video=False,
                                        scale=["word:hello=1.5", "class:open=0.8"])
    assert seen["recording"] == Recording() and seen["alive"] == Alive(gaze=False, seed=7)
    assert seen["text"] == "hello" and seen["face"] == "default"


def test_speaks_older_keywords_make_the_same_groups():
    from facemech.speech.alive import Liveliness
    from facemech.speech.planning import PLAN_ITERATIONS
    from facemech.workflows.inputs import Alive, Recording, Speaking
    from facemech.workflows.speech import _older_forms

    assert Speaking().plan_iterations == PLAN_ITERATIONS  # plan=True: the planner's default
    assert Speaking.from_keywords(plan=3, voice="en-gb").iterations() == 3
    assert Speaking.from_keywords(plan=True).iterations() == PLAN_ITERATIONS
    assert Speaking.from_keywords(plan=0).iterations() == 0
    assert Speaking.from_keywords(plan=False).iterations() is False
    assert Speaking.from_keywords(Speaking(voice="en-gb"), rate_wpm=120) == Speaking(
        voice="en-gb", rate_wpm=120)
    art = Speaking(strength=1.2, scale="word:balloon=1.5;class:open=0.8").articulation()
    assert art.strength == 1.2 and [str(r) for r in art.rules] == [
        "word:balloon=1.5", "class:open=0.8"]
    assert Alive(head_motion=False, seed=3).liveliness() == Liveliness(head=False, seed=3)
    rec, alive, rest = _older_forms({"audio": "a.wav", "textgrid": None}, {"blinks": False}, {
        "textgrid": "a.TextGrid", "tiers": ("words", "phones"), "face": "f.npz",
        "articulation": {"strength": 0.5, "plan": False}})
    assert rec == Recording("a.wav", "a.TextGrid", "words", "phones")
    assert alive == Alive(blinks=False)
    assert rest == {"face": "f.npz", "strength": 0.5, "plan": False}


def test_analyse_takes_its_groups_and_its_older_keywords(monkeypatch):
    from typer.testing import CliRunner

    from facemech.workflows import subject
    from facemech.workflows.inputs import Analysis, Preparation

    seen = {}
    monkeypatch.setattr(subject, "analyse", lambda *a, **kw: seen.update(kw))
    monkeypatch.setattr(cli, "_staged", lambda run, **kw: run(**kw))
    res = CliRunner().invoke(cli.app, ["analyse", "s", "r.c3d", "-o", "o", "--method", "powell",
                                       "--window", "5", "--lowpass", "0", "--video"])
    assert res.exit_code == 0, res.output
    assert seen["analysis"] == Analysis("powell", window=5, video=True)
    assert seen["preparation"] == Preparation(lowpass=0.0)
    assert seen["analysis"].fit_options() == {}  # powell: no lsq options
    assert subject.ANALYSE_LSQ == {"window": 3, "smooth": 1.0} == Analysis().fit_options()
    inv = Analysis(controls="all", noise=0.2).inversion()
    assert (inv.method, inv.controls, inv.noise, inv.positive) == ("lsq", "all", 0.2, True)


def test_markers_trim_takes_its_bounds_as_a_group_or_as_keywords(tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from facemech.io.markers import read_markers
    from facemech.workflows.inputs import Bounds, MarkerReading
    from facemech.workflows.markers import trim_file

    src = tmp_path / "m.csv"
    src.write_text("time,A_x,A_y,A_z\n" + "".join(f"{i / 100},{i},0,0\n" for i in range(10)))
    a = trim_file(src, tmp_path / "a.csv", bounds=Bounds(first=2, last=5), units="mm").data
    b = trim_file(src, tmp_path / "b.csv", first=2, last=5, units="mm").data
    assert a.n_frames == b.n_frames == 4 and (a.positions == b.positions).all()
    assert read_markers(tmp_path / "a.csv").n_frames == 4
    seen = {}
    monkeypatch.setattr("facemech.workflows.markers.trim_file", lambda *a, **kw: seen.update(kw))
    res = CliRunner().invoke(cli.app, ["markers", "trim", str(src), "-o", "t.csv", "--start",
                                       "0.02", "--rate", "100"])
    assert res.exit_code == 0, res.output
    assert seen["bounds"] == Bounds(start=0.02) and seen["reader"] == MarkerReading(rate=100.0)
