"""Compile the physics and rendering kernels once, ahead of a first run.

numba compiles each kernel on its first call and caches the machine code (beside the sources,
or in ``NUMBA_CACHE_DIR``); later processes load it in a fraction of a second.
:func:`warm_up` calls every kernel that ``facemech demo``, ``simulate``, ``render`` and
``invert`` use: the built-in face built, a few frames simulated, written, drawn and
inverted (its explicit steps). It then writes a stamp (:func:`stamp_path`) that
names numba's version and the kernels' source files (size, modification time).
:func:`needed` is true while the stamp is missing or stale; the command line then runs the
warm-up first, with a line saying so and how long it took (``FACEMECH_WARMUP=0``: not).

``python -m facemech.warmup`` (the Makefile's install step) and ``facemech warmup`` run it.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from .progress import StagedProgress

#: the warm-up's time on an unloaded core with nothing cached, s (the first-use line says it)
TYPICAL_S = 90

_PACKAGE = Path(__file__).resolve().parent
_IMPORTS_NUMBA = re.compile(rb"^\s*(from numba|import numba)", re.MULTILINE)


def cache_dir(environ=os.environ) -> Path:
    """The folder of the stamp: ``NUMBA_CACHE_DIR`` if set, else the package's
    ``__pycache__`` (where numba caches), else a per-user folder in the temporary directory
    (:func:`facemech._numba_cache_dir`'s choice for a read-only installation)."""
    from . import _numba_cache_dir

    chosen = environ.get("NUMBA_CACHE_DIR") or _numba_cache_dir(
        str(_PACKAGE), environ, lambda d: os.access(d, os.W_OK))
    return Path(chosen) if chosen else _PACKAGE / "__pycache__"


def stamp_path(environ=os.environ) -> Path:
    """The stamp file that :func:`warm_up` writes."""
    return cache_dir(environ) / "facemech-kernels.json"


def fingerprint(package: Path = _PACKAGE) -> str:
    """numba's version and the size and modification time (ns) of every source file of
    ``package`` that imports numba (the files numba's cache keys its kernels on)."""
    import numba

    rows = [f"numba {numba.__version__}"]
    for path in sorted(package.rglob("*.py")):
        if _IMPORTS_NUMBA.search(path.read_bytes()) and path.name != "warmup.py":
            st = path.stat()
            rows.append(f"{path.relative_to(package)} {st.st_size} {st.st_mtime_ns}")
    return hashlib.sha256("\n".join(rows).encode()).hexdigest()


def needed(environ=os.environ, package: Path = _PACKAGE) -> bool:
    """Whether the kernels may have to be compiled: the stamp missing, unreadable or made for
    other sources or another numba (``FACEMECH_WARMUP=0`` in ``environ``: never)."""
    if environ.get("FACEMECH_WARMUP", "1") == "0":
        return False
    try:
        stamp = json.loads(stamp_path(environ).read_text())
    except (OSError, ValueError):
        return True
    return not isinstance(stamp, dict) or stamp.get("fingerprint") != fingerprint(package)


def _write_stamp(seconds: float, environ=os.environ) -> None:
    path = stamp_path(environ)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"fingerprint": fingerprint(), "seconds": round(seconds, 1)}))
    os.replace(tmp, path)


#: the warm-up's stage, as progress reports it: parts 0 to 4 of 4
STAGE = "compile the kernels"


def warm_up(progress: StagedProgress | None = None) -> float:
    """Call every kernel of the demo, simulate, render and invert once (numba compiles or loads
    each), then write the stamp. ``progress`` (staged) gets :data:`STAGE`, parts done of 4.
    Returns the wall time, s."""
    from .demo import utterance
    from .inverse.workflow import invert_marker_set
    from .io.markers import read_markers
    from .io.results import write_results
    from .physics.model import model as face_model
    from .solvers.forward import simulate
    from .viz.movie import write_snapshot
    from .viz.render import RenderOptions
    from .viz.scene import build_scene, look_from_model

    def say(done: int) -> None:
        if progress is not None:
            progress(STAGE, done, 4)

    t0 = time.perf_counter()
    say(0)
    model = face_model("default")
    face = model.face
    say(1)
    _, act, jaw = utterance()
    frames = slice(40, 44)  # a closure: muscles, lips in contact, the jaw moving
    sim = simulate(model, act[frames], jaw[frames])
    say(2)
    with tempfile.TemporaryDirectory(prefix="facemech-warmup-") as tmp:
        write_results(Path(tmp) / "r.nc", sim)
        scene = build_scene(look_from_model(face))
        write_snapshot(Path(tmp) / "s.png", scene, sim.positions[-1], sim.jaw_pose[-1],
                       options=RenderOptions(size=(96, 96)))
        say(3)
        invert_marker_set(read_markers(Path(tmp) / "r.nc"), model)
        say(4)
    seconds = time.perf_counter() - t0
    _write_stamp(seconds)
    return seconds


def _note(line: str) -> None:
    print(f"facemech: {line}", file=sys.stderr, flush=True)


def warm_up_if_needed(progress: StagedProgress | None = None, *, skip: bool = False,
                      say: Callable[[str], None] = _note) -> float | None:
    """:func:`warm_up` when :func:`needed` (and not ``skip``), with a line to ``say`` (default:
    stderr) before it (what, about how long) and after it (how long it took). Returns its wall
    time (s), None when not run."""
    if skip or not needed():
        return None
    say(f"compiling the physics kernels once (about {TYPICAL_S} s)...")
    seconds = warm_up(progress)
    say(f"physics kernels compiled in {seconds:.0f} s; later runs load them")
    return seconds


def main() -> None:
    """``python -m facemech.warmup``: the warm-up with a line per part and the total."""
    from . import _numba_cache_dir

    chosen = _numba_cache_dir(str(_PACKAGE), os.environ, lambda d: os.access(d, os.W_OK))
    os.environ.update({} if chosen is None else {"NUMBA_CACHE_DIR": chosen})
    from .progress import LogProgress

    print(f"facemech: compiling the physics kernels once (about {TYPICAL_S} s; cached in "
          f"{cache_dir()})", flush=True)
    with LogProgress("warmup", every=0.0) as log:
        seconds = warm_up(log.report)
    print(f"facemech: physics kernels compiled in {seconds:.0f} s", flush=True)


if __name__ == "__main__":
    main()
