"""Marker data: formats and round trips, head motion, frames, gaps, resampling, mapping."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

from conftest import without_progress
from facemech import (
    InputError,
    MarkerSet,
    closest_nodes,
    derivative,
    fill_gaps,
    find_gaps,
    head_correct,
    read_mapping,
    read_markers,
    resample,
    rigid_fit,
    scale_adapt,
    to_anatomical_frame,
    write_markers,
)
from facemech.solvers.jaw import rotation_matrix

HEAD = ("head_top", "head_left", "head_right", "nasion_m")


def face_markers(face, frames=120, rate=60.0, seed=0):
    """Face markers (the 19 virtual markers) moving like speech, plus 4 head markers, in m."""
    rng = np.random.default_rng(seed)
    names = list(face.markers)
    rest = np.array([face.rest_positions[face.markers[n]] for n in names])
    head = np.array([[0.0, 0.09, -0.02], [0.07, 0.02, -0.05], [-0.07, 0.02, -0.05],
                     [0.0, 0.0, 0.01]])
    t = np.arange(frames) / rate
    lips = 0.004 * np.sin(2 * np.pi * 3 * t)[:, None, None] * rng.normal(size=(1, len(names), 3))
    pos = np.concatenate([rest[None] + lips, np.broadcast_to(head, (frames, 4, 3))], axis=1)
    return MarkerSet(pos, (*names, *HEAD), rate, source_units="mm")


def move_head(ms, max_deg=20.0, max_mm=50.0, seed=1):
    """Apply a smooth rigid motion per frame: rotations up to max_deg, translations up to max_mm."""
    rng = np.random.default_rng(seed)
    n = ms.n_frames
    ph = rng.uniform(0, 2 * np.pi, 6)
    s = np.linspace(0, 1, n)
    out = np.empty_like(ms.positions)
    for k in range(n):
        ang = np.radians(max_deg) * np.sin(2 * np.pi * s[k] + ph[:3])
        r = (rotation_matrix([1, 0, 0], ang[0]) @ rotation_matrix([0, 1, 0], ang[1])
             @ rotation_matrix([0, 0, 1], ang[2]))
        t = max_mm * 1e-3 * np.sin(2 * np.pi * s[k] + ph[3:])
        out[k] = ms.positions[k] @ r.T + t
    return ms.with_positions(out)


def test_rigid_fit_is_exact_and_never_reflects():
    rng = np.random.default_rng(3)
    p = rng.normal(size=(5, 3))
    r = rotation_matrix([1, 2, 3], 0.7)
    t = np.array([0.1, -0.2, 0.3])
    r2, t2 = rigid_fit(p, p @ r.T + t)
    np.testing.assert_allclose(r2, r, atol=1e-12)
    np.testing.assert_allclose(t2, t, atol=1e-12)
    mirrored = p * np.array([-1, 1, 1])
    r3, _ = rigid_fit(p, mirrored)
    assert np.linalg.det(r3) == pytest.approx(1.0)


def test_head_motion_is_undone(face):
    truth = face_markers(face)
    moved = move_head(truth)
    res = head_correct(moved, HEAD, reference=0)
    # the reference frame is unmoved in `truth` only up to frame 0's motion: compare through it
    r0, t0 = rigid_fit(truth.positions[0, -4:], res.markers.positions[0, -4:])
    expect = truth.positions @ r0.T + t0
    err = np.linalg.norm(res.markers.positions - expect, axis=2)
    assert err.max() < 1e-6  # 0.001 mm
    assert np.nanmax(res.residual) < 1e-9
    assert len(res.unfixed_frames) == 0


def test_head_motion_with_noise_is_close_to_the_noise(face):
    truth = face_markers(face, frames=200)
    rng = np.random.default_rng(5)
    moved = move_head(truth)
    noisy = moved.with_positions(moved.positions + rng.normal(0, 0.5e-3, moved.positions.shape))
    clean_ref = head_correct(moved, HEAD, reference=0).markers.positions
    res = head_correct(noisy, HEAD, reference=0)
    err = res.markers.positions[:, :-4] - clean_ref[:, :-4]
    per_axis_rms = np.sqrt(np.mean(err**2))
    # own noise (0.5 mm) plus the fit error that 4 noisy head markers carry to the face
    assert per_axis_rms < 2.0 * 0.5e-3
    assert 0.2e-3 < np.median(res.residual) < 1.0e-3  # the residual reports the noise


def test_missing_head_markers(face):
    moved = move_head(face_markers(face, frames=30))
    pos = moved.positions.copy()
    h = [moved.index(n) for n in HEAD]
    pos[5, h[0]] = np.nan  # three remain: fixed
    pos[9, h[0]] = np.nan
    pos[9, h[1]] = np.nan  # two remain: not fixed
    res = head_correct(moved.with_positions(pos), HEAD, reference=0)
    assert res.unfixed_frames.tolist() == [9]
    assert np.isnan(res.markers.positions[9]).all()
    assert res.head_markers_used[5] == 3 and np.isfinite(res.markers.positions[5, 0]).all()
    with pytest.raises(InputError, match="at least 3 head markers"):
        head_correct(moved, HEAD[:2])


def synthetic_set(n_markers=4, frames=50, rate=100.0, seed=2):
    rng = np.random.default_rng(seed)
    pos = rng.normal(size=(frames, n_markers, 3)) * 0.05
    pos[10:13, 1] = np.nan
    pos[0, 2] = np.nan
    return MarkerSet(pos, tuple(f"M{k:03d}" for k in range(n_markers)), rate, source_units="mm")


@pytest.mark.parametrize("chain", [("csv", "trc", "c3d", "csv"), ("c3d", "trc", "csv")])
def test_round_trips_keep_names_units_gaps_and_values(tmp_path, chain):
    pytest.importorskip("ezc3d")
    ms = synthetic_set()
    cur = ms
    for k, ext in enumerate(chain):
        path = tmp_path / f"step{k}.{ext}"
        write_markers(path, cur)
        cur = read_markers(path)
        assert cur.names == ms.names and cur.source_units == "mm"
        assert cur.rate == pytest.approx(ms.rate)
        np.testing.assert_array_equal(np.isnan(cur.positions), np.isnan(ms.positions))
        tol = 1e-6 * 0.05 if "c3d" in chain[: k + 1] else 1e-12  # float32 in C3D
        np.testing.assert_allclose(cur.positions, ms.positions, atol=tol, rtol=0)


def test_c3d_with_more_than_255_labels_and_metres(tmp_path):
    pytest.importorskip("ezc3d")
    ms = synthetic_set(n_markers=300, frames=5)
    write_markers(tmp_path / "big.c3d", ms, units="m")
    back = read_markers(tmp_path / "big.c3d")
    assert back.names == ms.names and back.source_units == "m"
    np.testing.assert_allclose(back.positions, ms.positions, atol=1e-7)


def test_c3d_written_by_the_c3d_package_reads_like_ezc3d(tmp_path):
    c3d = pytest.importorskip("c3d")
    pytest.importorskip("ezc3d")
    ms = synthetic_set(frames=20)
    ms = ms.with_positions(np.nan_to_num(ms.positions, nan=0.0))  # c3d writes no NaN points
    w = c3d.Writer(point_rate=ms.rate, analog_rate=ms.rate, point_scale=-1.0, point_units="mm  ")
    w.set_point_labels(list(ms.names))
    frames = []
    for k in range(ms.n_frames):
        pts = np.zeros((ms.n_markers, 5), np.float32)
        pts[:, :3] = ms.positions[k] * 1e3
        frames.append((pts, np.zeros((0, 1), np.float32)))
    w.add_frames(frames)
    with open(tmp_path / "pkg.c3d", "wb") as fh, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "No analog data found in file."
        w.write(fh)
    write_markers(tmp_path / "ez.c3d", ms)
    a = read_markers(tmp_path / "pkg.c3d")
    b = read_markers(tmp_path / "ez.c3d")
    assert a.names == b.names and a.rate == b.rate and a.source_units.strip() == "mm"
    np.testing.assert_allclose(a.positions, b.positions, atol=1e-7)


def test_corrupt_c3d_is_a_clean_error(tmp_path):
    pytest.importorskip("ezc3d")
    write_markers(tmp_path / "ok.c3d", synthetic_set())
    data = (tmp_path / "ok.c3d").read_bytes()
    (tmp_path / "trunc.c3d").write_bytes(data[:700])
    (tmp_path / "junk.c3d").write_bytes(b"\x02\x50" + bytes(range(256)) * 8)
    for name in ("trunc.c3d", "junk.c3d"):
        with pytest.raises(InputError) as info:
            read_markers(tmp_path / name)
        assert name in str(info.value)


def test_qualisys_tsv(tmp_path):
    lines = ["NO_OF_FRAMES\t3", "NO_OF_CAMERAS\t8", "NO_OF_MARKERS\t2", "FREQUENCY\t200",
             "DATA_INCLUDED\t3D", "MARKER_NAMES\tchin\tnose",
             "Frame\tTime\tchin X\tchin Y\tchin Z\tnose X\tnose Y\tnose Z",
             "1\t0.000\t1.0\t2.0\t3.0\t4.0\t5.0\t6.0",
             "2\t0.005\t1.5\t2.5\t3.5\t0.000\t0.000\t0.000",
             "3\t0.010\t2.0\t3.0\t4.0\t4.2\t5.2\t6.2"]
    (tmp_path / "q.tsv").write_text("\n".join(lines) + "\n")
    ms = read_markers(tmp_path / "q.tsv")
    assert ms.names == ("chin", "nose") and ms.rate == 200 and ms.source_units == "mm"
    assert ms.positions[1, 0, 2] == pytest.approx(3.5e-3)
    assert np.isnan(ms.positions[1, 1]).all()


def test_trc_rate_must_match_its_time_column(tmp_path):
    ms = synthetic_set(frames=5)
    write_markers(tmp_path / "a.trc", ms)
    text = (tmp_path / "a.trc").read_text().splitlines()
    text[2] = text[2].replace("100\t100", "60\t60", 1)
    (tmp_path / "b.trc").write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match="field 'DataRate'"):
        read_markers(tmp_path / "b.trc")


def test_units_are_never_guessed(tmp_path):
    (tmp_path / "a.csv").write_text("time,m_x,m_y,m_z\n0,1,2,3\n0.01,1,2,3\n")
    with pytest.raises(InputError, match="no length unit"):
        read_markers(tmp_path / "a.csv")
    (tmp_path / "b.csv").write_text("# units: furlong\ntime,m_x,m_y,m_z\n0,1,2,3\n0.01,1,2,3\n")
    with pytest.raises(InputError, match="unknown length unit"):
        read_markers(tmp_path / "b.csv")
    assert read_markers(tmp_path / "a.csv", units="mm").positions[0, 0, 0] == 1e-3


def test_anatomical_frame_from_three_points():
    rng = np.random.default_rng(4)
    local = {"right": [-0.02, 0, 0], "left": [0.02, 0, 0], "incisor": [0, 0, 0.03],
             "other": [0.01, 0.02, -0.01]}
    names = tuple(local)
    p = np.array([local[n] for n in names])
    r = rotation_matrix(rng.normal(size=3), 0.8)
    t = np.array([0.3, -0.1, 0.5])
    world = (p @ r.T + t)[None].repeat(3, axis=0)
    ms = MarkerSet(world, names, 60.0)
    back = to_anatomical_frame(ms, right="right", left="left", front="incisor", origin="incisor")
    want = p - np.array(local["incisor"])
    np.testing.assert_allclose(back.positions[1], want, atol=1e-12)


def test_gaps_are_found_filled_and_flagged():
    t = np.arange(100) / 100
    pos = np.stack([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t), t], axis=1)[:, None] * 0.01
    pos = np.repeat(pos, 2, axis=1)
    truth = pos.copy()
    pos[20:25, 0] = np.nan  # short, interior
    pos[50:80, 0] = np.nan  # long
    pos[:3, 1] = np.nan  # at the start
    ms = MarkerSet(pos, ("a", "b"), 100.0)
    gaps = find_gaps(ms)
    assert [(g.marker, g.start, g.length, g.interior) for g in gaps] == [
        ("a", 20, 5, True), ("a", 50, 30, True), ("b", 0, 3, False)]
    out, done, left = fill_gaps(ms, max_length=10)
    assert [g.start for g in done] == [20] and len(left) == 2
    np.testing.assert_allclose(out.positions[20:25, 0], truth[20:25, 0], atol=2e-6)
    assert out.filled[20:25, 0].all() and out.filled.sum() == 5
    assert np.isnan(out.positions[50:80, 0]).all() and np.isnan(out.positions[:3, 1]).all()
    assert not out.measured[20:25, 0].any()


def test_resampling_keeps_the_band_and_removes_aliases():
    rate = 240.0
    t = np.arange(480) / rate
    slow = 0.005 * np.sin(2 * np.pi * 3 * t)
    fast = 0.002 * np.sin(2 * np.pi * 50 * t)  # would alias to 10 Hz at 60 Hz
    pos = np.zeros((len(t), 1, 3))
    pos[:, 0, 0] = slow + fast
    ms = MarkerSet(pos, ("m",), rate)
    out = resample(ms, 60.0)
    assert out.rate == 60 and out.n_frames == 120
    want = 0.005 * np.sin(2 * np.pi * 3 * out.time)
    inner = slice(10, -10)
    np.testing.assert_allclose(out.positions[inner, 0, 0], want[inner], atol=0.2e-3)


def test_savitzky_golay_derivatives():
    rate = 100.0
    t = np.arange(300) / rate
    pos = np.zeros((len(t), 1, 3))
    pos[:, 0, 1] = 0.01 * np.sin(2 * np.pi * 2 * t)
    ms = MarkerSet(pos, ("m",), rate)
    v = derivative(ms, 1)
    a = derivative(ms, 2)
    w = 2 * np.pi * 2
    inner = slice(10, -10)
    np.testing.assert_allclose(v[inner, 0, 1], 0.01 * w * np.cos(w * t[inner]), atol=0.003)
    np.testing.assert_allclose(a[inner, 0, 1], -0.01 * w**2 * np.sin(w * t[inner]), atol=0.05)


def test_markers_to_nodes_and_scaling_adaptation(face, tmp_path):
    names = list(face.markers)
    rest = np.array([face.rest_positions[face.markers[n]] for n in names])
    ms = MarkerSet(rest[None].repeat(4, axis=0), tuple(names), 60.0)
    assert closest_nodes(ms, face) == {n: face.markers[n] for n in names}
    # another talker: per-axis scaled, moved
    factors = np.array([1.1, 0.9, 1.05])
    other = ms.with_positions(ms.positions / factors + np.array([0.002, -0.001, 0.0]))
    ad = scale_adapt(other, face, {n: face.markers[n] for n in names}, ("R02", "L07"))
    np.testing.assert_allclose(ad.factors, factors, rtol=1e-9)
    np.testing.assert_allclose(ad.markers.positions[0], rest, atol=1e-12)
    (tmp_path / "map.csv").write_text("marker,node\nR01,R01\nR03,17\n")
    assert read_mapping(tmp_path / "map.csv", ms, face) == {"R01": face.markers["R01"],
                                                            "R03": 17}
    (tmp_path / "bad.csv").write_text("marker,node\nXX9,R01\n")
    with pytest.raises(InputError, match="field 'XX9'"):
        read_mapping(tmp_path / "bad.csv", ms, face)
    far = ms.with_positions(ms.positions + np.array([0.0, 0.0, 0.05]))
    with pytest.raises(InputError, match="from the nearest node"):
        closest_nodes(far, face)


def run_cli(*args):
    """``facemech ARGS`` as a program; its stderr less the progress lines, which depend on the
    clock (conftest.without_progress)."""
    run = subprocess.run([sys.executable, "-m", "facemech.cli", *map(str, args)],
                         capture_output=True, text=True)
    run.stderr = without_progress(run.stderr)
    return run


@pytest.mark.slow
def test_markers_cli(face, tmp_path):
    pytest.importorskip("ezc3d")
    moved = move_head(face_markers(face, frames=60))
    pos = moved.positions.copy()
    pos[20:23, 0] = np.nan
    write_markers(tmp_path / "in.c3d", moved.with_positions(pos))
    r = run_cli("markers", "info", tmp_path / "in.c3d", "--json")
    assert r.returncode == 0, r.stderr
    assert '"rate_hz": 60.0' in r.stdout and '"frames": 3' in r.stdout
    r = run_cli("markers", "head-correct", tmp_path / "in.c3d", "--head", ",".join(HEAD), "-o",
                tmp_path / "hc.trc", "--report", tmp_path / "hc.json")
    assert r.returncode == 0, r.stderr
    r = run_cli("markers", "fill-gaps", tmp_path / "hc.trc", "-o", tmp_path / "f.csv",
                "--max-gap", "0.1")
    assert r.returncode == 0 and "filled 1 gaps" in r.stdout, r.stdout + r.stderr
    r = run_cli("markers", "resample", tmp_path / "f.csv", "--rate", "30", "-o",
                tmp_path / "r.csv")
    assert r.returncode == 0, r.stderr
    assert read_markers(tmp_path / "r.csv").n_frames == 30
    r = run_cli("markers", "convert", tmp_path / "r.csv", tmp_path / "r.c3d")
    assert r.returncode == 0, r.stderr
    # bad input: one line, exit 2, nothing written
    r = run_cli("markers", "head-correct", tmp_path / "in.c3d", "--head", "head_top,nasion_m",
                "-o", tmp_path / "x.csv")
    assert r.returncode == 2 and "at least 3 head markers" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "x.csv").exists()
    (tmp_path / "bad.c3d").write_bytes(b"not a c3d file at all" * 20)
    r = run_cli("markers", "convert", tmp_path / "bad.c3d", tmp_path / "x.csv")
    assert r.returncode == 2 and "bad.c3d" in r.stderr and "Traceback" not in r.stderr
    (tmp_path / "nounit.csv").write_text("time,m_x,m_y,m_z\n0,1,2,3\n0.1,1,2,3\n")
    r = run_cli("markers", "info", tmp_path / "nounit.csv")
    assert r.returncode == 2 and "units" in r.stderr
    assert run_cli("markers", "info", tmp_path / "nounit.csv", "--units", "mm").returncode == 0


def test_markers_frame_command(tmp_path):
    local = {"right": [-0.02, 0, 0], "left": [0.02, 0, 0], "incisor": [0, 0, 0.03]}
    p = np.array(list(local.values()))
    r = rotation_matrix([0.3, 1.0, 0.2], 0.5)
    world = (p @ r.T + np.array([0.1, 0.2, 0.3]))[None].repeat(4, axis=0)
    write_markers(tmp_path / "w.csv", MarkerSet(world, tuple(local), 60.0, source_units="mm"))
    run = run_cli("markers", "frame", tmp_path / "w.csv", "--right", "right", "--left", "left",
                  "--front", "incisor", "--origin", "incisor", "-o", tmp_path / "f.csv")
    assert run.returncode == 0, run.stderr
    back = read_markers(tmp_path / "f.csv")
    np.testing.assert_allclose(back.positions[2], p - p[2], atol=1e-9)
