"""The shape of the house (issue 17): a lazy, fast front door and a library that keeps its rules.

Each check reads the source tree or runs the installed command, so a change that breaks a rule
fails here, naming the module and the line.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "facemech"
CLI = SRC / "cli.py"
MAX_PARAMETERS = 12
MAX_CLI_LINES = 350


def _modules():
    for path in sorted(SRC.rglob("*.py")):
        yield path, ast.parse(path.read_text(), filename=str(path))


def _imported(tree: ast.AST) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _run(code: str, drop: tuple[str, ...] = ()) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["PYTHONDONTWRITEBYTECODE"] = "0"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=120, check=True)


def test_importing_the_cli_loads_neither_numba_nor_scipy_signal():
    out = _run("import sys, facemech.cli; "
               "print(sorted(m for m in sys.modules if m.split('.')[0] == 'numba' "
               "or m.startswith('scipy.signal')))").stdout
    assert out.strip() == "[]"


def test_the_package_namespace_is_what_all_names():
    out = _run("import facemech; "
               "print(sorted(n for n in vars(facemech) if not n.startswith('_')))").stdout
    assert out.strip() == "[]", "names leak from the package root: " + out
    out = _run("import facemech; print(all(hasattr(facemech, n) for n in facemech.__all__))")
    assert out.stdout.strip() == "True"


#: the numerical and file libraries that the command line's help must not import: each costs
#: tenths of a second to load (numba and scipy the most), so a help that imports none stays fast
#: on any machine. What it takes in seconds is measured by benchmarks/startup.py, not here: a
#: test of seconds fails on a slow or busy machine (issue 32)
HEAVY = ("numpy", "scipy", "numba", "llvmlite", "xarray", "h5py", "h5netcdf", "matplotlib",
         "trimesh", "pandas", "PIL", "dask", "distributed")


@pytest.mark.parametrize("args", [["--help"], ["markers", "--help"], ["invert", "--help"]])
def test_help_imports_no_numerical_library(args):
    code = ("import sys, runpy\n"
            f"sys.argv = ['facemech', *{args!r}]\n"
            "try:\n"
            "    runpy.run_module('facemech', run_name='__main__', alter_sys=True)\n"
            "except SystemExit as exc:\n"
            "    assert exc.code in (0, None), exc.code\n"
            "print('MODULES', sorted({m.split('.')[0] for m in sys.modules}))\n")
    # a user's environment: without conftest's FACEMECH_THREADS, which makes the root command
    # set numba's threads (and so import numba) before a subcommand's help
    out = _run(code, drop=("FACEMECH_THREADS",)).stdout
    assert "Usage" in out
    loaded = set(ast.literal_eval(out.rsplit("MODULES ", 1)[1].strip()))
    assert not loaded & set(HEAVY), sorted(loaded & set(HEAVY))


def test_only_the_cli_imports_typer_or_rich_progress():
    offenders = []
    for path, tree in _modules():
        if path == CLI:
            continue
        bad = {n for n in _imported(tree) if n.split(".")[0] == "typer"
               or n.startswith("rich.progress")}
        if bad:
            offenders.append(f"{path.relative_to(SRC)}: {sorted(bad)}")
    assert not offenders, offenders


def test_no_library_module_switches_the_matplotlib_backend():
    offenders = []
    for path, tree in _modules():
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "use" and isinstance(node.func.value, ast.Name)
                    and node.func.value.id in ("matplotlib", "mpl")):
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not offenders, offenders


def test_the_cli_is_short():
    lines = len(CLI.read_text().splitlines())
    assert lines < MAX_CLI_LINES, f"cli.py has {lines} lines"


def _public_entry_point(node: ast.FunctionDef, exported: set[str]) -> bool:
    """A command of the command line, or a name in ``__all__`` with a numpydoc Parameters list."""
    doc = ast.get_docstring(node) or ""
    command = any(isinstance(d, ast.Call) and "command" in (getattr(d.func, "attr", None),
                  getattr(d.func, "id", None)) for d in node.decorator_list)
    if command:
        return bool(doc)
    return node.name in exported and "Parameters\n----------" in doc


def _exported(tree: ast.Module) -> set[str]:
    for node in tree.body:
        if (isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__"
                                                 for t in node.targets)):
            try:
                return set(ast.literal_eval(node.value))
            except ValueError:
                return set()
    return set()


def test_no_function_takes_more_than_twelve_parameters():
    root_all = set(_run("import facemech; print(' '.join(facemech.__all__))").stdout.split())
    offenders = []
    for path, tree in _modules():
        exported = _exported(tree) | root_all
        for node in ast.walk(tree):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            a = node.args
            count = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                     + (a.vararg is not None) + (a.kwarg is not None))
            if count > MAX_PARAMETERS and not _public_entry_point(node, exported):
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno} {node.name} ({count})")
    assert not offenders, offenders


def test_the_bump_is_the_ramp_mirrored_about_its_centre():
    import numpy as np

    from facemech.waveforms import cosine_bump, cosine_ramp

    t = np.linspace(-1.0, 2.0, 3001)
    np.testing.assert_allclose(cosine_bump(t, 0.4, 0.7),
                               cosine_ramp(1.0 - 2.0 * np.abs(t - 0.4) / 0.7), atol=1e-15)
    assert cosine_bump(0.4, 0.4, 0.7) == 1.0 and cosine_bump(0.05, 0.4, 0.7) == 0.0
    np.testing.assert_allclose(cosine_ramp([-1.0, 0.0, 0.5, 1.0, 3.0]), [0, 0, 0.5, 1, 1],
                               atol=1e-15)
