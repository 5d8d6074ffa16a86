"""Issue 14, one path from a recording to results: `facemech subject` and `facemech analyse` on
a twin lab recording (z-up lab frame in mm, 100 Hz C3D, head motion, gaps, 0.1 mm of noise)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import run_cli
from facemech import default_face, read_results
from facemech.geometry.surface_io import read_landmarks
from facemech.io.markers import read_markers, write_markers
from facemech.kinematics.alignment import fit_to_skin, similarity_fit
from facemech.markerset import MarkerSet
from facemech.solvers.forward import marker_nodes
from facemech.workflows.demo import run as run_demo
from twin_recording import lab_recordings

#: the lowest correlation of a seen muscle with the truth over tools/spread.py's environments
#: (subject-twin; RIS, the same in all four to 1e-11; 2026-11-29, the measured muscle laws)
SEEN_R_LOWEST = 0.9340


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    d = tmp_path_factory.mktemp("twin")
    run_demo(d / "demo", video=False)
    rec = lab_recordings(d / "demo" / "result.nc", d)
    return d, rec


def _truth_nodes(rec) -> dict[str, int]:
    names, nodes = marker_nodes(default_face())
    return {rec["names"][n]: int(k) for n, k in zip(names, nodes, strict=True)
            if n in rec["names"]}


@pytest.fixture(scope="module")
def subject(twin):
    from facemech.workflows.subject import make_subject

    d, rec = twin
    out = d / "S"
    done = make_subject("default", rec["rest"], out, head=",".join(rec["head"]),
                        frame=",".join(rec["frame"]), chin_marker=rec["chin"], units="mm")
    return out, done


def test_similarity_fit_recovers_a_known_transform():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(12, 3))
    a = np.deg2rad(37.0)
    r = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])
    fit = similarity_fit(p, 1.2 * p @ r.T + [1.0, -2.0, 0.5])
    assert fit.scale == pytest.approx(1.2, rel=1e-12)
    np.testing.assert_allclose(fit.rotation, r, atol=1e-12)
    np.testing.assert_allclose(fit.translation, [1.0, -2.0, 0.5], atol=1e-12)
    assert fit.rms < 1e-12
    mirrored = similarity_fit(p, p * [-1, 1, 1])  # a reflection is never returned
    assert np.linalg.det(mirrored.rotation) == pytest.approx(1.0)


@pytest.mark.parametrize("pitch_deg", [0.0, 25.0])
def test_markers_are_laid_on_the_skin_from_a_rough_frame(pitch_deg):
    face = default_face()
    skin = face.rest_positions[: face.n_surface]
    names, nodes = marker_nodes(face)
    pts = skin[np.unique(nodes)]
    a = np.deg2rad(30.0)  # the lab: turned 30 degrees about y, shifted 1.2 m
    r = np.array([[np.cos(a), 0, np.sin(a)], [0, 1.0, 0], [-np.sin(a), 0, np.cos(a)]])
    lab = pts @ r.T + [0.4, 1.2, -0.3]
    b = np.deg2rad(pitch_deg)  # the frame the user's markers give: off by a pitch
    off = np.array([[1.0, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    fit = fit_to_skin(lab, skin, off @ r.T)
    np.testing.assert_allclose(fit(lab), pts, atol=1e-6)


@pytest.mark.slow
def test_subject_maps_every_marker_to_its_node(subject, twin):
    out, done = subject
    _, rec = twin
    assert done.data.mapping == _truth_nodes(rec)  # 35 markers, none matched by name
    info = json.loads((out / "subject.json").read_text())
    assert info["warped"] and info["alignment"].startswith("by the skin")
    assert max(info["marker_to_skin_mm"].values()) < 0.5  # 0.1 mm of noise, averaged
    assert set(info["head"]) == set(rec["head"]) and info["chin_marker"] == rec["chin"]
    for name in ("face.npz", "mapping.csv", "rest.csv", "subject.png"):
        assert (out / name).stat().st_size > 0
    # the warped face's mapped nodes sit on the rest markers
    rest = read_landmarks(out / "rest.csv", required=())
    face = np.load(out / "face.npz", allow_pickle=False)
    nodes = [done.data.mapping[n] for n in rest]
    np.testing.assert_allclose(face["rest_positions"][nodes], np.array(list(rest.values())),
                               atol=2e-6)


@pytest.mark.slow
def test_analyse_recovers_the_twin(subject, twin, monkeypatch, capsys):
    out, _ = subject
    d, rec = twin
    res = d / "OUT"
    code, stdout, err = run_cli(monkeypatch, capsys, "analyse", out, rec["speech"], "-o", res,
                                "--units", "mm")
    assert code == 0, err
    assert "head motion removed with H1, H2, H3, H4" in stdout
    assert "gaps: 3 filled" in stdout and "resampled from 100 Hz to 60 Hz" in stdout
    truth, inv = read_results(d / "demo" / "result.nc"), read_results(res / "result.nc")
    n = min(truth.sizes["time"], inv.sizes["time"])
    r = {}
    for name, seen in zip(inv["control"].values, inv["identifiable"].values, strict=True):
        if name == "jaw":
            a, b = truth["jaw_angle"].values[:n], inv["jaw_angle"].values[:n]
        else:
            a = truth["activity"].sel(muscle=name).values[: n - 1]
            b = inv["activity"].sel(muscle=name).values[: n - 1]
        r[str(name)] = (float(np.corrcoef(a, b)[0, 1]), bool(seen))
    seen = {k: v for k, (v, ok) in r.items() if ok}
    assert len(seen) >= 7, r  # the jaw and most speech muscles are determined
    # RIS 0.806 in the default environment, 0.796 under other BLAS kernels (the lowest over
    # the environments of tools/spread.py, subject-twin; docs/reproducibility.md), less 0.05
    assert all(v >= SEEN_R_LOWEST - 0.05 for v in seen.values()), r
    assert r["jaw"][0] >= 0.95
    summary = json.loads((res / "summary.json").read_text())
    assert summary["error_mm"]["median"] < 0.3 and summary["frames"] == n
    cmp = json.loads((res / "comparison.json").read_text())
    assert cmp["error"]["median_mm"] == pytest.approx(summary["error_mm"]["median"], rel=1e-9)
    assert (res / "controls.png").stat().st_size > 0


def test_markers_named_as_landmarks_align_by_name(tmp_path):
    face = default_face()
    names, nodes = marker_nodes(face)
    keep = [k for k in range(len(names)) if names[k].startswith(("mouth", "nose", "chin", "R0"))
            and nodes[k] not in nodes[:k]]  # a landmark and a marker may share a node
    pts = face.rest_positions[nodes[keep]] * 1.1 @ np.array([[0, 0, 1.0], [1, 0, 0],
                                                              [0, 1, 0]]).T + [0.2, 0.1, 1.4]
    ms = MarkerSet(np.repeat(pts[None], 10, axis=0), tuple(names[k] for k in keep), 100.0)
    write_markers(tmp_path / "rest.trc", ms, units="mm")
    from facemech.workflows.subject import make_subject

    done = make_subject("default", tmp_path / "rest.trc", tmp_path / "S")
    info = done.data.info
    assert info["alignment"].startswith("by name")
    assert info["lab_to_model"]["scale"] == pytest.approx(1 / 1.1, rel=1e-9)
    assert done.data.mapping == {names[k]: int(nodes[k]) for k in keep}


def _refused(monkeypatch, capsys, *args) -> str:
    code, _, err = run_cli(monkeypatch, capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.slow
def test_subject_refuses_what_it_cannot_place(twin, tmp_path, monkeypatch, capsys):
    _, rec = twin
    base = ("subject", "default", "--markers", rec["rest"], "-o", tmp_path / "S")
    line = _refused(monkeypatch, capsys, *base, "--head", "H1,H2,H9")
    assert "field 'H9'" in line and "fewer than 3 head markers have data (H9 missing)" in line
    line = _refused(monkeypatch, capsys, *base)  # no frame, no landmark names; head on skin?
    assert "field 'frame'" in line
    # without --head the headband's markers are not on the skin: named, with the distance
    line = _refused(monkeypatch, capsys, *base, "--frame", ",".join(rec["frame"]))
    assert "from the skin after alignment" in line and "field 'H" in line
    line = _refused(monkeypatch, capsys, *base, "--head", ",".join(rec["head"]), "--frame",
                    ",".join(rec["frame"]), "--rest", "5,6")
    assert "field 'rest'" in line
    assert not (tmp_path / "S").exists()
    line = _refused(monkeypatch, capsys, "analyse", tmp_path, rec["speech"], "-o", tmp_path / "O")
    assert "not a subject folder" in line


@pytest.mark.slow
def test_a_recording_without_some_of_the_subjects_markers(subject, twin, tmp_path, monkeypatch,
                                                          capsys):
    out, done = subject
    _, rec = twin
    ms = read_markers(rec["speech"], units="mm")
    gone = [rec["chin"], "M03"]
    short = ms.select([n for n in ms.names if n not in gone])
    short = MarkerSet(short.positions[:40], short.names, short.rate, short.time[:40])
    write_markers(tmp_path / "short.trc", short, units="mm")
    code, stdout, err = run_cli(monkeypatch, capsys, "analyse", out, tmp_path / "short.trc",
                                "-o", tmp_path / "O", "--units", "mm")
    assert code == 0, err
    absent = next(x for x in stdout.splitlines() if "markers absent from the recording" in x)
    assert set(absent.split(": ")[1].split(", ")) == set(gone), absent
    assert "the jaw markers are missing or have gaps longer than 0.1 s" in stdout
    mapping = (tmp_path / "O" / "mapping.csv").read_text().splitlines()[1:]
    assert len(mapping) == len(done.data.mapping) - 2
    assert read_results(tmp_path / "O" / "result.nc").sizes["time"] == 24  # 0.4 s at 60 Hz


@pytest.mark.slow
def test_a_rest_recording_as_labs_have_them(twin, tmp_path, monkeypatch, capsys):
    """A reference marker on the table, a lip marker hidden all through the rest, a head
    marker lost: the subject is made from what is left, and the notes say so."""
    _, rec = twin
    ms = read_markers(rec["rest"], units="mm")
    pos = ms.positions.copy()
    pos[:, ms.index("M06")] = np.nan
    pos[:, ms.index("H4")] = np.nan
    table = ms.positions[:, :1] + [0.3, 0.0, -0.2]  # 300 mm away
    rest = MarkerSet(np.concatenate([pos, table], axis=1), (*ms.names, "REF"), ms.rate, ms.time)
    write_markers(tmp_path / "rest.c3d", rest, units="mm")
    out = tmp_path / "S[/x]"  # not rich markup
    code, stdout, err = run_cli(monkeypatch, capsys, "subject", "default", "--markers",
                                tmp_path / "rest.c3d", "-o", out, "--head", ",".join(rec["head"]),
                                "--frame", ",".join(rec["frame"]), "--units", "mm")
    assert code == 0, err
    assert "head markers without data, left out: H4" in stdout
    assert "markers without data in the rest interval, left out: M06" in stdout
    assert "markers not on the face, left out: REF" in stdout
    assert f"-> {out}/" in stdout
    mapping = (out / "mapping.csv").read_text()
    assert "M06" not in mapping and "REF" not in mapping and mapping.count("\n") == 1 + 34


@pytest.mark.slow
def test_analyse_estimates_the_jaw_when_the_chin_marker_has_a_long_gap(subject, twin, tmp_path,
                                                                        monkeypatch, capsys):
    out, _ = subject
    _, rec = twin
    ms = read_markers(rec["speech"], units="mm")
    pos = ms.positions[:40].copy()
    pos[10:40, ms.index(rec["chin"])] = np.nan  # 0.3 s, longer than --max-gap
    pos[:, ms.index("H2")] = np.nan  # a head marker lost: three remain
    write_markers(tmp_path / "r.c3d", MarkerSet(pos, ms.names, ms.rate, ms.time[:40]),
                  units="mm")
    code, stdout, err = run_cli(monkeypatch, capsys, "analyse", out, tmp_path / "r.c3d", "-o",
                                tmp_path / "O", "--units", "mm")
    assert code == 0, err
    assert "the jaw is estimated" in stdout and "head markers without data, left out: H2" in stdout
    assert "head motion removed with H1, H3, H4" in stdout
    assert "jaw" in json.loads((tmp_path / "O" / "summary.json").read_text())["determined"]
