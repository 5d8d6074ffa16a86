"""Reach of the lips (issue 27, part 1): orbicularis oris's marginal part (OOSM, OOIM) under the
default preset, through ``facemech simulate`` as a user runs it.

With the jaw open 10 degrees (the lips apart, so that the lip contact does not hold them), each
measure is the lip's motion beyond the same jaw opening without activity, which is its motion
relative to the lower incisor for the lower lip (the incisor moves with the jaw alone):

- full OOSM lowers the upper lip's centre at least 3 mm;
- full OOIM turns the lower lip in and lifts it; with mentalis (issue 27: "OOI marginal,
  mentalis, incisivus labii inferioris") its centre rises at least 6 mm on the jaw;
- the whole orbicularis (marginal and incisive parts, both lips) and mentalis together close the
  lips on the midline with the jaw still at 10 degrees: the lip line's midline pair has a gap
  below 0 (the lips press into each other, a contact force k gap > 0), the bilabial
  compression. With the contacts stepped on their own (``implicit_contacts``, the preset's
  default since issue 32) a seal is stiff: the measured penetration is about 1 um.

Each part also turns its lip's red margin in (back, -z) and narrows the mouth. The parts are
inert at rest: a default face's results do not change by their presence
(tests/analysis/test_realism's tables are unchanged).
"""

import contextlib
import io

import numpy as np
import pytest

from conftest import run_cli
from facemech import read_results
from facemech.geometry.anatomy import MARGINAL
from facemech.io.activity import write_activity
from facemech.params import MARGINAL_GROUPS, MUSCLE_GROUPS, preset
from facemech.physics.assembly import Physics

FRAMES = 40
JAW_DEG = 10.0


def _run(tmp_path, monkeypatch, capsys, name, levels):
    """Final positions (nodes, 3) m of every node after FRAMES frames of ``levels`` with the
    jaw ramped to JAW_DEG over 10 frames, through the command line."""
    t = np.arange(FRAMES) / 60.0
    act = np.zeros((FRAMES, len(MUSCLE_GROUPS)))
    for g, v in levels.items():
        act[:, MUSCLE_GROUPS.index(g)] = v
    write_activity(tmp_path / f"act-{name}.csv", t, act)
    jaw = tmp_path / "jaw.csv"
    deg = JAW_DEG * np.clip(np.arange(FRAMES) / 10, 0, 1)
    jaw.write_text("time,jaw_angle_deg\n" + "".join(f"{a:.6f},{b:.6f}\n"
                                                     for a, b in zip(t, deg, strict=True)))
    out = tmp_path / f"{name}.nc"
    code, _, err = run_cli(monkeypatch, capsys, "simulate", "--activity",
                           tmp_path / f"act-{name}.csv",
                           "--jaw-angle", jaw, "-o", out)
    assert code == 0, err
    return read_results(out)["positions"].values[-1]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    tmp = tmp_path_factory.mktemp("reach")

    class _Cap:  # capsys is function-scoped: the module's runs read their own streams
        def __init__(self):
            self.out, self.err = io.StringIO(), io.StringIO()

        def readouterr(self):
            return self.out.getvalue(), self.err.getvalue()

    def run(name, levels):
        cap = _Cap()
        with contextlib.redirect_stdout(cap.out), contextlib.redirect_stderr(cap.err):
            return _run(tmp, mp, cap, name, levels)

    cases = {"jaw": {}, "OOSM": {"OOSM": 1.0}, "OOIM": {"OOIM": 1.0},
             "OOIM+MEN": {"OOIM": 1.0, "MEN": 1.0},
             "closed": {"OOSM": 1.0, "OOIM": 1.0, "OOS": 1.0, "OOI": 1.0, "MEN": 1.0}}
    out = {name: run(name, lv) for name, lv in cases.items()}
    mp.undo()
    return out


def test_the_marginal_part_exists_only_on_the_anatomical_tissue(face, seeds_face):
    assert MARGINAL == MARGINAL_GROUPS
    names = face.muscles.names
    for g in MARGINAL:
        assert f"{g}_R" in names and f"{g}_L" in names
        assert not any(n.startswith(g) for n in seeds_face.muscles.names)
    assert preset("anatomical").passive_stiffness("OOSM") == 0.0


def test_the_marginal_part_lowers_the_upper_lip_3_mm(face, runs):
    ul = face.landmarks["upper_lip_center"]
    d = (runs["OOSM"][ul] - runs["jaw"][ul]) * 1e3
    assert d[1] <= -3.0, d
    assert d[2] < 0.0  # the red lip turns in


def test_the_marginal_part_and_mentalis_lift_the_lower_lip_6_mm_on_the_jaw(face, runs):
    """Measured: OOIM alone 5.5 mm up (and in), with mentalis 8.7 mm."""
    ll = face.landmarks["lower_lip_center"]
    d = (runs["OOIM"][ll] - runs["jaw"][ll]) * 1e3
    assert d[1] >= 4.5, d
    assert d[2] < 0.0
    d = (runs["OOIM+MEN"][ll] - runs["jaw"][ll]) * 1e3
    assert d[1] >= 6.0, d


def test_the_lips_close_and_press_with_the_jaw_open_10_degrees(face, runs):
    """The midline pair of the lip line: open by about 12 mm with the jaw alone; closed and
    pressed (gap < 0, so the lip contact pushes back) under OOSM + OOIM + OOS + OOI + MEN."""
    ph = Physics.build(face, preset("anatomical"))
    contact = ph.forces.contact
    rest = face.rest_positions
    mid = int(np.argmin(np.abs(rest[contact.pairs[:, 0], 0])))
    u, w = contact.pairs[mid]

    def gap(x):
        return float((x[u] - x[w]) @ contact.normals[mid])

    assert gap(runs["jaw"]) > 8e-3
    g = gap(runs["closed"])
    assert g < 0.0
    assert contact.k[mid] * -g > 0.0
    assert abs(g) < 3e-3  # pressed, not passed through
