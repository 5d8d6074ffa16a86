"""Issue 15: an inversion you can trust. Twins of the demo utterance (jaw moving) through the
command line, with and without a jaw recording; one error definition shared by invert and
compare; standard errors that cover the truth; method objects that refuse foreign options."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

from conftest import run_cli
from facemech import InputError, MarkerSet, read_markers, read_results
from facemech.inverse import uncertainty as U
from facemech.inverse.methods import LeastSquares, Powell, method_from_options
from facemech.physics.model import model as face_model


def _facemech(*args):
    """Run the command line in a child process: (exit status, stdout, stderr)."""
    p = subprocess.run([sys.executable, "-m", "facemech", *map(str, args)], capture_output=True,
                       text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


@pytest.fixture(scope="module")
def demo_markers(tmp_path_factory):
    """The demo utterance simulated on the default face, and its 37 landmarks and markers."""
    d = tmp_path_factory.mktemp("demo")
    code, _, err = _facemech("demo", "-o", d, "--no-video")
    assert code == 0, err
    code, _, err = _facemech("export", d / "result.nc", "-o", d / "markers.trc")
    assert code == 0, err
    return d / "result.nc", d / "markers.trc"


#: the lowest correlation of a seen (identifiable) muscle with the truth over the environments
#: of tools/spread.py (demo-twin, either jaw): DAO, 0.8699 in all four to 1e-10 (2026-11-29,
#: the measured muscle laws; 0.8075 under the seeds')
SEEN_R_LOWEST = 0.8699


def _recovery(truth_path, inv_path):
    truth, inv = read_results(truth_path), read_results(inv_path)
    r = {}
    for name, seen in zip(inv["control"].values, inv["identifiable"].values, strict=True):
        if name == "jaw":
            r[name] = (np.corrcoef(truth["jaw_angle"], inv["jaw_angle"])[0, 1], bool(seen))
        else:
            a = truth["activity"].sel(muscle=name).values[:-1]
            b = inv["activity"].sel(muscle=name).values[:-1]
            r[str(name)] = (np.corrcoef(a, b)[0, 1], bool(seen))
    return r, inv


@pytest.mark.slow
@pytest.mark.parametrize("jaw", ["estimated", "chin marker"])
def test_demo_twin_through_the_cli(demo_markers, tmp_path, jaw, monkeypatch, capsys):
    truth, markers = demo_markers
    out = tmp_path / "inv.nc"
    extra = ["--chin-marker", "R01"] if jaw == "chin marker" else []
    code, stdout, err = run_cli(monkeypatch, capsys, "invert", "--markers", markers, "-o", out,
                                *extra)
    assert code == 0, err
    r, inv = _recovery(truth, out)
    # the jaw is never left at rest: estimated, and the note says where it came from
    assert "jaw: estimated with the muscle activity" in err
    assert ("chin marker R01" in err) == (jaw == "chin marker")
    assert r["jaw"][1] and r["jaw"][0] >= 0.95
    seen = {k: v for k, (v, ok) in r.items() if ok and k != "jaw"}
    assert len(seen) >= 6, r  # most speech muscles are seen by 37 markers
    # 0.87 (DAO) to 1.0, the same in every environment of tools/spread.py (demo-twin;
    # docs/reproducibility.md): SEEN_R_LOWEST, less a margin of 0.05
    assert all(v >= SEEN_R_LOWEST - 0.05 for v in seen.values()), r
    # LAO pulls the mouth corner as zygomaticus major does: the markers see their sum only. Its
    # flag sits at the edge of the criterion (its distance against the noise estimated from the
    # residuals, which moves with the last bit): not identifiable on this project's machines, an
    # AMD EPYC found it identifiable with r = 0.94 (issue 32). The notes say what the flag says
    assert r["LAO"][1] or "LAO" in inv.attrs["regularised"].split(",")
    # the largest per-frame error: 0.224 mm in every environment of tools/spread.py
    # (demo-twin; docs/reproducibility.md)
    assert inv["rms_error"].values.max() <= 0.3e-3
    # invert and compare give the same median and maximum per-frame error
    code, cmp_out, _ = run_cli(monkeypatch, capsys, "compare", out, markers, "--json")
    assert code == 0
    cmp = json.loads(cmp_out)
    assert cmp["error"]["median_mm"] == pytest.approx(inv.attrs["rms_error_mm_median"],
                                                      rel=1e-9)
    assert cmp["error"]["max_mm"] == pytest.approx(inv.attrs["rms_error_mm_max"], rel=1e-9)
    assert f"median {inv.attrs['rms_error_mm_median']:.3f} mm" in stdout
    # the results carry muscle outputs of the re-animation and the controls' uncertainty
    assert inv["muscle_force"].dims == ("time", "muscle_instance")
    assert np.isfinite(inv["control_se"].values[:-1]).all()


@pytest.mark.slow
def test_standard_errors_cover_the_truth_with_noisy_markers(demo_markers):
    """0.5 mm of marker noise: +-2 standard errors cover the true activity in at least 80 % of
    the frame-muscle pairs that the inversion marks identifiable."""
    from facemech import default_face
    from facemech.inverse.invert import invert
    from facemech.kinematics.mapping import closest_nodes

    truth_path, markers = demo_markers
    truth = read_results(truth_path)
    ms = read_markers(markers)
    rng = np.random.default_rng(7)
    noisy = MarkerSet(ms.positions + rng.normal(0.0, 0.5e-3, ms.positions.shape), ms.names,
                      ms.rate)
    face = default_face()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # ill-posed frames are expected here
        res = invert(face_model(face), noisy, closest_nodes(noisy, face))
    assert res.noise_mm == pytest.approx(0.5, rel=0.25)  # estimated from the residuals
    covered, pairs = 0, 0
    for j, name in enumerate(res.control_names):
        if not res.identifiable[j]:
            continue
        if name == "jaw":
            true = truth["jaw_angle"].values[1:] / 0.1
        else:
            true = truth["activity"].sel(muscle=name).values[:-1]
        est, se = res.controls[:-1, j], res.control_se[:-1, j]
        covered += int(np.sum(np.abs(est - true) <= 2 * se))
        pairs += len(est)
    assert pairs >= 3 * (len(res.time) - 1)  # at least three controls are identifiable
    assert covered / pairs >= 0.8


def test_uncertainty_kernels_analytic():
    j = np.diag([2.0, 4.0, 0.5])
    np.testing.assert_allclose(U.unit_standard_errors(j, np.zeros((0, 3)), 3),
                               [0.5, 0.25, 2.0])
    # a regularisation row shrinks the spread: sandwich form
    reg = np.array([[0.0, 0.0, 1.0]])
    se = U.unit_standard_errors(j, reg, 3)
    assert se[2] == pytest.approx(0.5 / (0.25 + 1.0))
    # identifiability: the part of a column the others cannot reproduce
    cols = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 3.0]])  # columns 0, 1 equal
    np.testing.assert_allclose(U.identifiability(cols), [0.0, 0.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(U.identifiability(np.array([[1.0, 0.0], [1.0, 0.0]])),
                               [np.sqrt(2.0), 0.0])  # a column that moves nothing
    tilted = np.array([[1.0, 0.0], [1.0, 1.0]]).T  # 45 degrees apart
    np.testing.assert_allclose(U.identifiability(tilted), [np.sqrt(0.5), 1.0])
    np.testing.assert_array_equal(U.identifiable(np.array([0.5, 2.0]), 0.05), [False, True])
    np.testing.assert_array_equal(U.identifiable(np.array([2.0, 6.0]), 0.5), [False, True])
    assert U.noise_from_residuals(np.array([8.0, 10.0]), np.array([4, 5])) == pytest.approx(
        np.sqrt(2.0))


def test_method_objects_validate_their_own_options():
    assert method_from_options("lsq", window=3, tol=None) == LeastSquares(window=3)
    assert method_from_options("powell", max_evaluations=50) == Powell(max_evaluations=50)
    with pytest.raises(InputError, match="window applies to the lsq method only|window "
                                         "applies to the lsq method, not to powell"):
        method_from_options("powell", window=3)
    with pytest.raises(InputError, match="xtol applies to the powell method, not to lsq"):
        method_from_options("lsq", xtol=1e-3)
    with pytest.raises(InputError, match="unknown method"):
        method_from_options("newton")
    for bad in (dict(window=0), dict(tol=-1.0), dict(smooth=float("nan")),
                dict(max_evaluations=0)):
        with pytest.raises(InputError) as info:
            LeastSquares(**bad)
        assert info.value.field == next(iter(bad))
    with pytest.raises(InputError) as info:
        Powell(xtol=0.0)
    assert info.value.field == "xtol"


@pytest.mark.slow
def test_invert_command_refuses_a_foreign_option(demo_markers, tmp_path, monkeypatch, capsys):
    _, markers = demo_markers
    code, _, err = run_cli(monkeypatch, capsys, "invert", "--markers", markers, "-o",
                           tmp_path / "x.nc", "--method", "powell", "--window", "3")
    assert code == 2 and "window applies to the lsq method, not to powell" in err
    assert "Traceback" not in err and not (tmp_path / "x.nc").exists()
    code, _, err = run_cli(monkeypatch, capsys, "invert", "--markers", markers, "-o",
                           tmp_path / "x.nc", "--jaw-fixed")
    assert code == 2 and "--chin-marker" in err
