"""The shape of the house (issue 17): a lazy, fast front door and a library that keeps its rules.

Each check reads the source tree or runs the installed command, so a change that breaks a rule
fails here, naming the module and the line.
"""

from __future__ import annotations

import ast
import inspect
import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "facemech"
CLI = SRC / "cli.py"
MAX_PARAMETERS = 12
#: the command line stays a thin layer: each command, its decorator and docstring included, at
#: most this many lines (parse, one call into workflows, print) ...
MAX_COMMAND_LINES = 12
#: ... and the lines of cli.py outside the commands (the decorator that makes options, the
#: sub-apps, the progress and error wiring) at most this many
MAX_CLI_FRAME_LINES = 170


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


def _commands(tree: ast.Module):
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and any(
                isinstance(d, ast.Call) and getattr(d.func, "id", None) == "command"
                for d in node.decorator_list):
            yield node.name, node.end_lineno - min(d.lineno for d in node.decorator_list) + 1


def test_the_cli_is_thin():
    """Every command is a few lines, and what frames them stays small, however many commands
    there are."""
    text = CLI.read_text()
    commands = dict(_commands(ast.parse(text)))
    assert len(commands) > 30  # the reading finds the commands
    long = {name: n for name, n in commands.items() if n > MAX_COMMAND_LINES}
    assert not long, f"commands over {MAX_COMMAND_LINES} lines: {long}"
    frame = len(text.splitlines()) - sum(commands.values())
    assert frame <= MAX_CLI_FRAME_LINES, f"cli.py has {frame} lines outside its commands"


def test_no_function_takes_more_than_twelve_parameters():
    """Every function of the library, the command line's commands included (issue 28: a
    command takes a group of options as one parameter, cli_options.GROUPS)."""
    offenders = []
    for path, tree in _modules():
        for node in ast.walk(tree):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            a = node.args
            count = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                     + (a.vararg is not None) + (a.kwarg is not None))
            if count > MAX_PARAMETERS:
                offenders.append(f"{path.relative_to(SRC)}:{node.lineno} {node.name} ({count})")
    assert not offenders, offenders


def test_the_commands_keep_their_options():
    """The groups give each command the options it had before them (names and defaults)."""
    from facemech import cli

    got = {}
    for group in (cli.app, cli.face_app, cli.emg_app, cli.markers_app, cli.experiment_app):
        for info in group.registered_commands:
            got[info.callback.__wrapped__.__name__] = set(
                inspect.signature(info.callback).parameters)
    assert got["simulate"] == {
        "output", "face", "activity", "emg", "units", "emg_baseline", "emg_calibration",
        "jaw_chin", "chin_marker", "jaw_second_marker", "jaw_incisor", "jaw_molar", "jaw_angle",
        "bite_block", "jaw_kinematics", "preset", "integrator", "substeps", "dt", "jaw_drive",
        "video", "audio", "view", "size", "background", "aa"}
    assert got["invert"] == {
        "markers", "output", "face", "method", "map_file", "preset", "figure", "positive",
        "controls", "chin_marker", "jaw_second_marker", "jaw_incisor", "jaw_molar", "jaw_fixed",
        "jaw_lead", "noise", "window", "tol", "bend", "smooth", "effort", "max_evaluations",
        "max_rate", "scale_pair", "jaw_kinematics", "dt", "units"}
    assert got["speak"] == {
        "text", "output", "audio", "textgrid", "voice", "rate_wpm", "word_tier", "phone_tier",
        "strength", "face", "preset", "video", "view", "size", "background", "aa", "blinks",
        "gaze", "head_motion", "seed", "scale", "plan", "plan_iterations", "phone_labels"}
    assert got["analyse"] == {
        "subject", "recording", "output", "units", "max_gap", "lowpass", "method", "controls",
        "noise", "window", "smooth", "preset", "video"}


def test_the_bump_is_the_ramp_mirrored_about_its_centre():
    import numpy as np

    from facemech.waveforms import cosine_bump, cosine_ramp

    t = np.linspace(-1.0, 2.0, 3001)
    np.testing.assert_allclose(cosine_bump(t, 0.4, 0.7),
                               cosine_ramp(1.0 - 2.0 * np.abs(t - 0.4) / 0.7), atol=1e-15)
    assert cosine_bump(0.4, 0.4, 0.7) == 1.0 and cosine_bump(0.05, 0.4, 0.7) == 0.0
    np.testing.assert_allclose(cosine_ramp([-1.0, 0.0, 0.5, 1.0, 3.0]), [0, 0, 0.5, 1, 1],
                               atol=1e-15)


# ---- the layers (issue 28): every import runs downward ------------------------------------------
ARCHITECTURE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
#: the cycle allowed: none (not even one of imports for type checking only)
TYPE_CHECKING_CYCLE = frozenset()


def _layers() -> dict[str, int]:
    """Folder or module name -> layer number, from docs/architecture.md's list."""
    text = ARCHITECTURE.read_text()
    block = text.split("<!-- layers -->", 1)[1].split("<!-- /layers -->", 1)[0]
    out = {}
    for line in block.strip().splitlines():
        number, rest = line.split(".", 1)
        names = rest.split("--", 1)[0].split("**")[2]
        for name in names.replace("`", " ").split():
            out[name.rstrip("/")] = int(number)
    return out


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_module(name: str) -> bool:
    rel = Path(*name.split("."))
    return (SRC.parent / rel).with_suffix(".py").is_file() or (SRC.parent / rel).is_dir()


def _imports_of(path: Path, tree: ast.Module) -> list[tuple[str, int, bool]]:
    """(module imported, line, for type checking only) of every facemech import in a module,
    at its top or inside a function."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    checking = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            checking.update(id(n) for n in ast.walk(node))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            # ``from . import params``: the submodule, else the module itself
            targets = [f"{base}.{a.name}" if _is_module(f"{base}.{a.name}") else base
                       for a in node.names]
        else:
            continue
        out += [(t, node.lineno, id(node) in checking) for t in set(targets)
                if t.split(".")[0] == "facemech"]
    return out


def _layer_of(module: str, layers: dict[str, int]) -> int | None:
    parts = module.split(".")
    if len(parts) == 1:
        return 1  # the package root: it imports only _version (ground)
    return layers.get(parts[1])


def _import_graph():
    graph = {}
    for path, tree in _modules():
        graph[_module_name(path)] = _imports_of(path, tree)
    return graph


def test_the_layer_list_names_every_folder_and_module():
    layers = _layers()
    names = {p.stem if p.is_file() else p.name for p in SRC.iterdir()
             if (p.suffix == ".py" and p.stem != "__init__") or (p / "__init__.py").is_file()}
    assert names == set(layers), (sorted(names - set(layers)), sorted(set(layers) - names))


def test_every_import_runs_downward():
    layers = _layers()
    upward = []
    for module, imports in _import_graph().items():
        here = _layer_of(module, layers)
        for target, line, _ in imports:
            there = _layer_of(target, layers)
            if there is not None and here is not None and there > here:
                upward.append(f"{module}:{line} -> {target} (layer {here} -> {there})")
    assert not upward, "\n".join(upward)


def test_no_import_cycle():
    graph = {m: {t for t, _, _ in imports if t != m} for m, imports in _import_graph().items()}
    # Tarjan's strongly connected components
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(comp)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    bad = [sorted(c) for c in cycles if c != TYPE_CHECKING_CYCLE]
    assert not bad, bad


def test_importing_facemech_changes_no_environment_variable_nor_thread_count():
    out = _run("import os, numba; before = (dict(os.environ), numba.get_num_threads()); "
               "import facemech, facemech.physics.threads, facemech.solvers.forward; "
               "from facemech import simulate, Parameters; "
               "print(before == (dict(os.environ), numba.get_num_threads()))",
               drop=("NUMBA_CACHE_DIR",))
    assert out.stdout.strip() == "True"
