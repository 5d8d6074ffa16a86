"""The tests show the house: one folder per floor of docs/architecture.md, every test path that
the Makefile, CI and the docs name exists, and the ``slow`` marker is registered and used."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TESTS = ROOT / "tests"
#: folders of tests that are not a floor of the house: the tests that keep the docs true
EXTRA = {"docs"}
#: a floor's name in docs/architecture.md's list -> its tests' folder where the two differ
FOLDER = {"domain": ("analysis", "inverse", "speech")}


def _floors() -> set[str]:
    text = (ROOT / "docs" / "architecture.md").read_text()
    block = text.split("<!-- layers -->")[1].split("<!-- /layers -->")[0]
    names = re.findall(r"^\d+\. \*\*([a-z]+)\*\*", block, flags=re.M)
    assert len(names) >= 10, names
    return {f for n in names for f in FOLDER.get(n, (n,))}


def test_every_test_file_sits_in_a_floor_folder():
    folders = {p.parent.name for p in TESTS.rglob("test_*.py")
               if "__pycache__" not in p.parts}
    assert not list(TESTS.glob("test_*.py")), "a test file in tests/ itself: give it its floor"
    assert folders <= _floors() | EXTRA, folders - _floors() - EXTRA
    assert len(folders) >= 12


def test_test_paths_named_elsewhere_exist():
    named = set()
    for page in [ROOT / "Makefile", ROOT / ".ci" / "run", ROOT / "CONTRIBUTING.md",
                 ROOT / "README.md", *ROOT.glob("docs/*.md"), *ROOT.glob("tools/*.py"),
                 *ROOT.glob("benchmarks/*.py"), *ROOT.rglob("src/facemech/**/*.py")]:
        named |= set(re.findall(r"\btests/[\w/]+\.py\b", page.read_text()))
    # the Makefile's lists written with $(addprefix ...)
    make = (ROOT / "Makefile").read_text().replace("\\\n", " ")
    for folder, files in re.findall(r"\$\(addprefix (tests/\w+/test_),([^)]*)\)", make):
        named |= {folder + f for f in files.split()}
    missing = sorted(p for p in named if not (ROOT / p).is_file())
    assert named and not missing, missing


def test_the_slow_marker_is_registered_and_used():
    ini = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert any(m.startswith("slow:") for m in ini["markers"])
    assert "--strict-markers" in ini["addopts"]
    used = [p for p in TESTS.rglob("test_*.py")
            if "mark.slow" in p.read_text() and p.name != "test_layout.py"]
    assert len(used) >= 5, used
    assert '-m "not slow"' in (ROOT / "Makefile").read_text()
