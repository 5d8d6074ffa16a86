"""Shared fixtures. Caches of matplotlib and Mesa go to a temporary folder, never ~/.cache;
the force kernels run on one thread. Under pytest-xdist (``make test``: two workers, ``--dist
loadgroup``) the tests of a module that share a module-scoped fixture run on one worker, so
that the fixture is built once."""

from __future__ import annotations

import atexit
import os
import re
import shutil
import sys
import tempfile

_CACHE = tempfile.mkdtemp(prefix="facemech-test-cache-")
atexit.register(shutil.rmtree, _CACHE, ignore_errors=True)  # not left in /tmp after the run
os.environ.setdefault("MPLCONFIGDIR", _CACHE)
os.environ.setdefault("XDG_CACHE_HOME", _CACHE)
os.environ.setdefault("MPLBACKEND", "Agg")
# one thread for the force kernels, whatever the machine's load: results pinned to the bit
# (the seeds' Experiment 1 table is rounding-sensitive, docs/performance.md); the tests of
# threads set their counts themselves
os.environ.setdefault("FACEMECH_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from facemech import MUSCLE_GROUPS, default_face  # noqa: E402
from facemech.cli import main  # noqa: E402
from facemech.physics.threads import set_threads  # noqa: E402

# importing facemech sets no thread count (issue 28): this process's kernels on the count above
set_threads()


def pytest_configure(config):
    # pytest-xdist registers it too; here so that a run without xdist (-p no:xdist) knows it
    config.addinivalue_line("markers", "xdist_group(name): run on one worker under "
                            "pytest-xdist's --dist loadgroup")
    _check_loadgroup(config)


def _check_loadgroup(config):
    """pytest 9.2 derives a test's id from elsewhere than pytest-xdist 3.8 writes its group to,
    so under ``--dist loadgroup`` the groups are silently lost and every worker builds each
    module fixture again (two minutes more on ``make test``): such a run stops here."""
    if config.getoption("dist", "no") != "loadgroup" or not config.getoption("numprocesses"):
        return
    import xdist

    def version(text):
        return tuple(int(p) for p in re.findall(r"\d+", text)[:2])

    if version(pytest.__version__) >= (9, 2) and version(xdist.__version__) <= (3, 8):
        raise pytest.UsageError(
            f"pytest {pytest.__version__} loses pytest-xdist {xdist.__version__}'s --dist "
            "loadgroup groups: install the pinned versions (pip install -c constraints.txt)")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """A test that uses a module-, class- or package-scoped fixture joins its module's group
    (``xdist_group``): under ``--dist loadgroup`` a group runs on one worker, so that the fixture
    (a built head, a simulation) is built once, not once per worker. Other tests are handed out
    one by one; session fixtures are built once per worker. Without xdist the groups change
    nothing. Runs before xdist's own hook (in each worker), which reads the groups."""
    for item in items:
        info = getattr(item, "_fixtureinfo", None)
        if info is None or item.get_closest_marker("xdist_group") is not None:
            continue
        # the last definition of each name is the one the test gets (a module may override)
        shared = any(defs and defs[-1].scope in ("module", "class", "package")
                     for defs in info.name2fixturedefs.values())
        if shared and getattr(item, "module", None) is not None:
            item.add_marker(pytest.mark.xdist_group(item.module.__name__))


@pytest.fixture(scope="session")
def face():
    """The built-in generic face, with the default (anatomical) tissue."""
    return default_face()


@pytest.fixture(scope="session")
def seeds_face():
    """The built-in generic face with the seeds' uniform 4-mm tissue (Lucero & Munhall 1999)."""
    return default_face(tissue="uniform")


def activity(frames: int, **levels: float) -> np.ndarray:
    """Constant activity (frames, 16) with the named groups at the given levels."""
    a = np.zeros((frames, len(MUSCLE_GROUPS)))
    for g, v in levels.items():
        a[:, MUSCLE_GROUPS.index(g)] = v
    return a


#: a progress line of :class:`facemech.progress.LogProgress` (a stage's count or the heartbeat):
#: how many of them come depends on the clock (a slow machine prints "still working" where a fast
#: one prints nothing), so checks of stderr's other lines leave them out (issue 32)
PROGRESS_LINE = re.compile(r"^facemech: ([^:]+: (still working \(\d+ s\)|(frame )?\d+(/\d+)?, "
                           r"[\d.]+ s elapsed(, about .+ left)?)|compiling the physics kernels "
                           r"once .*|physics kernels compiled .*)$")


def without_progress(err: str) -> str:
    """``err`` less its progress lines (:data:`PROGRESS_LINE`): what a command said, whatever
    the clock."""
    kept = [ln for ln in err.splitlines() if not PROGRESS_LINE.match(ln)]
    return "\n".join(kept) + ("\n" if kept else "")


def seen_triangles(scene, verts, cam):
    """The renderer's depth pass over a scene's frame: per pixel the camera depth (m, -inf where
    nothing) and the index of the triangle seen (-1: none), for tests that ask what shows."""
    from facemech.viz.raster import rasterise

    h, w = cam.size
    p = cam.project(verts, 1)
    z = np.full((h, w), -np.inf, np.float32)
    tid = np.full((h, w), -1, np.int32)
    bary = np.empty((h, w, 2), np.float32)
    rasterise(p[:, 0], p[:, 1], p[:, 2], scene.tris, scene.uv, scene.tex, scene.alpha_test,
              scene.two_sided, scene.atlas, z, tid, bary)
    return z, tid


def run_cli(monkeypatch, capsys, *args) -> tuple[int, str, str]:
    """Run ``facemech ARGS`` in this process: (exit status, stdout, stderr less its progress
    lines, :func:`without_progress`)."""
    monkeypatch.setattr(sys, "argv", ["facemech", *map(str, args)])
    code = 0
    try:
        main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, without_progress(err)
