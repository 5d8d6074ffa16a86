"""The commands of README.md and docs/*.md, as written: each ``facemech`` line names a real
command and only options that command has (its ``--help`` works); the README's short commands
run, in order, on the files they name (the MOCHA recording where ../shared/data has it)."""

import re
import shlex
import time
from pathlib import Path

import pytest
import typer.main
from typer.testing import CliRunner

from conftest import run_cli
from facemech.cli import app

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"
CLICK = typer.main.get_command(app)
#: commands the README's examples run here for real, each in a few seconds
QUICK = {("markers", "info"), ("face", "export-default"), ("face", "build"), ("face", "info")}


def shell_lines(page: Path | str) -> list[str]:
    """The command lines of a Markdown file's (or text's) ``sh``/``bash``/``console`` code
    blocks: continuation lines joined, comments and prompts dropped."""
    lines, block, held = [], False, ""
    text = page.read_text() if isinstance(page, Path) else page
    for raw in text.splitlines():
        if raw.startswith("```"):
            block = not block and raw[3:].strip() in ("sh", "bash", "console", "shell")
            continue
        if not block:
            continue
        line = re.sub(r"(^|\s)#.*$", "", raw).strip().removeprefix("$ ")
        if held:
            line = held + " " + line
        held = line[:-1].rstrip() if line.endswith("\\") else ""
        if line and not held:
            lines.append(line)
    return lines


def resolve(line: str):
    """(the command's path of names, its click command, the rest of the line) of a
    ``facemech ...`` line; the path () is the root (a placeholder such as COMMAND)."""
    words = line.split()[1:]
    while words and words[0] in ("--threads", "--version"):
        words = words[2:] if words[0] == "--threads" else words[1:]
    cmd, path = CLICK, ()
    while words and hasattr(cmd, "commands") and words[0] in cmd.commands:
        cmd, path, words = cmd.commands[words[0]], (*path, words[0]), words[1:]
    return path, cmd, " ".join(words)


def options_of(cmd) -> set[str]:
    return {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)} | {"--help"}


def facemech_lines(page: Path | str) -> list[str]:
    return [ln for ln in shell_lines(page) if ln.startswith("facemech ")]


def section(page: Path, title: str) -> str:
    """The text of the section ``## title`` of a Markdown page."""
    text = page.read_text()
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_the_readme_starts_with_the_two_set_up_commands():
    """The project's rule: right after the title and the one-paragraph introduction, the
    README's first commands are `make demo` and `make test`."""
    text = (ROOT / "README.md").read_text()
    first = text.index("```")
    intro = [p for p in text[:first].split("\n\n") if p.strip()]
    assert len(intro) == 2 and intro[0].startswith("# facemech"), intro
    assert shell_lines(ROOT / "README.md")[:2] == ["make demo", "make test"]
    assert "pip install facemech" not in text  # not on PyPI: installed from the checkout


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_command_line_names_a_real_command_and_options(page):
    runner, helped, bad = CliRunner(), set(), []
    for line in facemech_lines(page):
        path, cmd, rest = resolve(line)
        if path not in helped:
            res = runner.invoke(app, [*path, "--help"])
            assert res.exit_code == 0, (line, res.output)
            helped.add(path)
        names = options_of(cmd) | options_of(CLICK)
        used = re.findall(r"(?:^|(?<=[\s\[(|]))(--?[A-Za-z][\w-]*)", rest)
        if path == () and rest.split()[:1] not in ([], ["COMMAND"]):
            bad.append(f"{line!r}: no such command")
        bad += [f"{line!r}: {' '.join(path)} has no option {o}" for o in used
                if o not in names]
    assert not bad, "\n".join(bad)


def test_the_readme_names_every_command():
    """Every command and subcommand of the command line is in the README's list."""
    listed = {resolve(ln)[0] for ln in facemech_lines(ROOT / "README.md")}
    for name, cmd in CLICK.commands.items():
        subs = getattr(cmd, "commands", None)
        for path in ([(name, s) for s in subs] if subs else [(name,)]):
            assert tuple(path) in listed, f"facemech {' '.join(path)} is not in README.md"


@pytest.mark.skipif(not (SHARED / "data" / "mocha" / "fsew0_001.ema").is_file(),
                    reason="the MOCHA recording is not beside the checkout")
def test_the_readmes_short_commands_run_as_written(monkeypatch, capsys, tmp_path):
    """The worked examples' quick commands, in their order (the scan example's files follow
    from one to the next), in a fresh folder; ../shared/ is the data beside the checkout."""
    monkeypatch.chdir(tmp_path)
    ran = []
    for line in facemech_lines(section(ROOT / "README.md", "Worked examples")):
        path, _, rest = resolve(line)
        if path not in QUICK:
            continue
        args = [a.replace("../shared/", f"{SHARED}/") for a in shlex.split(rest)]
        t0 = time.perf_counter()
        code, out, err = run_cli(monkeypatch, capsys, *path, *args)
        ran.append((line, time.perf_counter() - t0))
        assert code == 0, (line, err)
        if path == ("markers", "info"):  # what the README's comment says it prints
            assert "500 Hz" in out and "9 markers" in out, out
    assert [ln for ln, _ in ran][:1] == [
        "facemech markers info ../shared/data/mocha/fsew0_001.ema"]
    assert len(ran) == 4 and (tmp_path / "myface.npz").is_file(), ran
    assert max(t for _, t in ran) < 60, ran  # quick: seconds each on an idle core


def test_the_warm_up_module_the_readme_names_exists():
    import importlib

    for line in shell_lines(ROOT / "README.md"):
        if line.startswith("python -m facemech."):
            module = importlib.import_module(line.split()[2])
            assert callable(module.main), line


def test_invert_help_says_articulography_is_resampled_and_laid_on_the_face():
    """The help of ``invert --markers`` no longer asks every file to come in the model's frame
    and rate: articulography is resampled and its lips laid on the face."""
    from facemech.cli_options import help_for

    text = help_for("invert", "markers")
    assert "articulography" in text and "resampled" in text and ".ema" in text, text
