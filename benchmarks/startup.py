"""Start-up benchmark of the command line (prints JSON).

For ``facemech --help``, ``facemech markers --help`` and ``facemech invert --help``, each run as
a program (``python -m facemech``): the CPU seconds (user + system) and the wall seconds it takes,
the best of ``--repeat`` runs after one that writes the bytecode, and the numerical libraries it
imported (none is expected: tests/docs/test_house.py checks that, since a test of seconds fails on a
slow machine). Before issue 32 a test held each help under one CPU second; this reports the
same number, to read against the machine it ran on (``cpu_model``).

Usage: python benchmarks/startup.py [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

from facemech.io.results import numerics_attrs

COMMANDS = (["--help"], ["markers", "--help"], ["invert", "--help"])
HEAVY = ("numpy", "scipy", "numba", "llvmlite", "xarray", "h5py", "h5netcdf", "matplotlib",
         "trimesh", "pandas", "PIL", "dask", "distributed")
_MODULES = ("import sys, runpy\n"
            "sys.argv = ['facemech', *{args!r}]\n"
            "try:\n"
            "    runpy.run_module('facemech', run_name='__main__', alter_sys=True)\n"
            "except SystemExit:\n"
            "    pass\n"
            "print('MODULES', sorted({{m.split('.')[0] for m in sys.modules}}))\n")


def _timed(args: list[str]) -> tuple[float, float]:
    """(CPU s, wall s) of one ``python -m facemech ARGS``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "facemech", *args], capture_output=True, check=True,
                   timeout=120)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def _heavy_imports(args: list[str]) -> list[str]:
    out = subprocess.run([sys.executable, "-c", _MODULES.format(args=args)], capture_output=True,
                         text=True, check=True, timeout=120).stdout
    loaded = set(eval(out.rsplit("MODULES ", 1)[1]))  # a list literal that we printed
    return sorted(loaded & set(HEAVY))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    opts = ap.parse_args()
    env = numerics_attrs()
    rows = {}
    for args in COMMANDS:
        _timed(args)  # bytecode written once
        runs = [_timed(args) for _ in range(opts.repeat)]
        rows[" ".join(args)] = {"cpu_s": round(min(c for c, _ in runs), 3),
                                "wall_s": round(min(w for _, w in runs), 3),
                                "heavy_imports": _heavy_imports(args)}
    print(json.dumps({"benchmark": "startup", "repeat": opts.repeat, "commands": rows,
                      "cpu_model": env["cpu_model"], "python_version": env["python_version"]},
                     indent=2))


if __name__ == "__main__":
    main()
