"""The command line: good runs end to end, bad input as one line, exit 2, nothing written."""

import json
import subprocess
import sys
import wave

import numpy as np
import pytest

from conftest import run_cli as cli
from conftest import without_progress
from facemech import default_face, read_results
from facemech.geometry.builder import default_surface


def assert_one_line_error(code, err, *needles):
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for n in needles:
        assert n in lines[0], (n, lines[0])


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    """The generic face exported as OBJ + landmark CSV (mm)."""
    d = tmp_path_factory.mktemp("template")
    code = subprocess.run([sys.executable, "-m", "facemech.cli", "face", "export-default", "-o",
                           str(d)], capture_output=True, text=True)
    assert code.returncode == 0, code.stderr
    return d / "generic_face.obj", d / "generic_face_landmarks.csv"


def test_face_build_from_exported_template_matches_the_builtin(template, tmp_path, monkeypatch,
                                                               capsys):
    obj, lm = template
    code, out, err = cli(monkeypatch, capsys, "face", "build", obj, lm, "-o", tmp_path / "f.npz")
    assert code == 0, err
    code, out, err = cli(monkeypatch, capsys, "face", "info", tmp_path / "f.npz", "--json")
    built = json.loads(out)
    code, out, err = cli(monkeypatch, capsys, "face", "info", "default", "--json")
    default = json.loads(out)
    for key in ("nodes_per_layer", "springs_by_kind", "prisms", "muscles", "free_fascia_nodes"):
        assert built[key] == default[key], key


def test_face_build_bad_input(template, tmp_path, monkeypatch, capsys):
    obj, lm = template
    out = tmp_path / "f.npz"
    lines = lm.read_text().splitlines()
    (tmp_path / "lm.csv").write_text("\n".join(ln for ln in lines if not ln.startswith("chin")))
    code, _, err = cli(monkeypatch, capsys, "face", "build", obj, tmp_path / "lm.csv", "-o", out)
    assert_one_line_error(code, err, "lm.csv", "chin")
    (tmp_path / "broken.obj").write_text("v 0 0 0\nf 1 2 3\nthis is not obj\n")
    code, _, err = cli(monkeypatch, capsys, "face", "build", tmp_path / "broken.obj", lm, "-o",
                       out)
    assert_one_line_error(code, err, "broken.obj")
    v, f, _ = default_surface()
    mid = len(f) // 2
    bad = np.concatenate([f, [[f[mid, 1], f[mid, 0], len(v) - 1]]])
    with open(tmp_path / "nm.obj", "w") as fh:
        fh.writelines(f"v {x * 1e3} {y * 1e3} {z * 1e3}\n" for x, y, z in v)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in bad)
    code, _, err = cli(monkeypatch, capsys, "face", "build", tmp_path / "nm.obj", lm, "-o", out)
    assert_one_line_error(code, err, "nm.obj", "non-manifold")
    assert not out.exists()


def write_activity_csv(path, frames=20, **levels):
    cols = sorted(levels)
    with open(path, "w") as fh:
        fh.write("time," + ",".join(cols) + "\n")
        for k in range(frames):
            fh.write(f"{k / 60:.6f}," + ",".join(str(levels[c]) for c in cols) + "\n")


def test_simulate_with_activity_and_chin_marker(tmp_path, monkeypatch, capsys, face):
    write_activity_csv(tmp_path / "act.csv", frames=24, OOS=0.3)  # DLI would pull the chin too
    chin = face.rest_positions[face.markers["R01"]] * 1e3
    with open(tmp_path / "chin.csv", "w") as fh:
        fh.write("# units: mm\ntime,R01_x,R01_y,R01_z\n")
        for k in range(24):
            drop = 6.0 * min(k / 12, 1.0)
            fh.write(f"{k / 60},{chin[0]},{chin[1] - drop},{chin[2]}\n")
    res = tmp_path / "r.nc"
    code, out, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "act.csv",
                         "--jaw-chin", tmp_path / "chin.csv", "--chin-marker", "R01",
                         "--integrator", "rosenbrock", "-o", res)
    assert code == 0, err
    ds = read_results(res)
    assert ds.sizes["time"] == 24
    jaw = ds["jaw_angle"].values
    # the jaw opens over 12 samples, applied 2 samples (33 ms) early
    assert jaw[0] > 0 and np.all(np.diff(jaw[:11]) > 0)
    assert np.argmax(jaw >= jaw.max() - 1e-12) == 10
    r01 = ds["markers"].sel(marker="R01").values
    assert (r01[-1, 1] - r01[0, 1]) * 1e3 == pytest.approx(-6.0, abs=1.5)
    assert ds.attrs["integrator"] == "rosenbrock"


def test_simulate_bad_input(tmp_path, monkeypatch, capsys):
    res = tmp_path / "r.nc"
    write_activity_csv(tmp_path / "hi.csv", DAO=1.5)
    code, _, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "hi.csv", "-o",
                       res)
    assert_one_line_error(code, err, "hi.csv", "DAO", "outside [0, 1]")
    write_activity_csv(tmp_path / "unk.csv", BICEPS=0.5)
    code, _, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "unk.csv", "-o",
                       res)
    assert_one_line_error(code, err, "unk.csv", "BICEPS")
    with open(tmp_path / "emg.csv", "w") as fh:
        fh.write("time,DLI,OOS\n")
        for k in range(500):
            fh.write(f"{k / 2500},{np.sin(k)},{'' if k == 77 else np.cos(k)}\n")
    code, _, err = cli(monkeypatch, capsys, "simulate", "--emg", tmp_path / "emg.csv", "-o", res)
    assert_one_line_error(code, err, "emg.csv", "OOS")
    write_activity_csv(tmp_path / "ok.csv", OOS=1.0)
    code, _, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "ok.csv",
                       "--preset", "lucero1999", "--dt", "0.004", "-o", res)
    assert_one_line_error(code, err, "blow-up at frame", "time step")
    code, _, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "ok.csv",
                       "--integrator", "euler", "-o", res)
    assert_one_line_error(code, err, "integrator", "implicit")
    code, _, err = cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "ok.csv",
                       "--preset", "nope", "-o", res)
    assert_one_line_error(code, err, "preset")
    assert not res.exists() and not list(tmp_path.glob(".r.nc*"))


def test_emg_process_command(tmp_path, monkeypatch, capsys):
    rng = np.random.default_rng(0)
    with open(tmp_path / "emg.csv", "w") as fh:
        fh.write("time,LAO,MEN\n")
        for k in range(5000):
            burst = 1.0 if 2500 <= k < 3500 else 0.05
            men = 0.05 * rng.standard_normal() + (0.5 if k > 4000 else 0.0)
            fh.write(f"{k / 2500},{burst * rng.standard_normal()},{men}\n")
    code, out, err = cli(monkeypatch, capsys, "emg", "process", tmp_path / "emg.csv", "-o",
                         tmp_path / "act.csv")
    assert code == 0, err
    from facemech import read_activity

    t, act = read_activity(tmp_path / "act.csv")
    assert len(t) == 120
    lao = act[:, 2]
    assert lao[(t > 1.1) & (t < 1.3)].mean() > 0.5 and lao[t < 0.8].mean() < 0.05


@pytest.mark.slow
def test_render_and_plot(tmp_path, monkeypatch, capsys, face):
    pytest.importorskip("imageio_ffmpeg")
    import imageio_ffmpeg

    write_activity_csv(tmp_path / "act.csv", frames=6, DAO=0.8)
    res = tmp_path / "r.nc"
    assert cli(monkeypatch, capsys, "simulate", "--activity", tmp_path / "act.csv", "-o",
               res)[0] == 0
    rate = 16000
    with wave.open(str(tmp_path / "a.wav"), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        tone = (0.3 * 32767 * np.sin(2 * np.pi * 220 * np.arange(rate) / rate)).astype("<i2")
        w.writeframes(tone.tobytes())
    movie = tmp_path / "m.mp4"
    code, out, err = cli(monkeypatch, capsys, "render", res, "-o", movie, "--audio",
                         tmp_path / "a.wav", "--size", "640x360")
    assert code == 0, err
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(movie))
    assert frames == 6
    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-i", str(movie)],
                           capture_output=True, text=True)
    assert "Audio: aac" in probe.stderr and "h264" in probe.stderr
    assert "640x360" in probe.stderr and "60 fps" in probe.stderr
    code, out, err = cli(monkeypatch, capsys, "plot", res, "-o", tmp_path / "k.png")
    assert code == 0 and (tmp_path / "k.png").stat().st_size > 10000
    code, _, err = cli(monkeypatch, capsys, "plot", res, "-o", tmp_path / "k2.png", "--markers",
                       "R03,NOPE")
    assert_one_line_error(code, err, "NOPE")


def test_cli_entry_point_runs_as_a_program():
    run = subprocess.run([sys.executable, "-m", "facemech.cli", "face", "info", "nope.npz"],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert without_progress(run.stderr).strip().startswith("facemech: error: nope.npz")
    assert "Traceback" not in run.stderr


@pytest.mark.slow
def test_demo_runs_without_data(tmp_path, monkeypatch, capsys):
    code, out, err = cli(monkeypatch, capsys, "demo", "-o", tmp_path / "d", "--no-video")
    assert code == 0, err
    summary = json.loads((tmp_path / "d" / "summary.json").read_text())
    assert summary["frames"] == 156
    assert 5.0 < summary["largest_lip_displacement_mm"] < 30.0
    assert "real-time factor" in out
    ds = read_results(tmp_path / "d" / "result.nc")
    assert np.all(np.isfinite(ds["positions"].values))
    for name in ("kinematics.png", "activity.png", "snapshot.png", "activity.csv"):
        assert (tmp_path / "d" / name).stat().st_size > 1000
    assert summary["preset"] == "anatomical"
    # the anatomical default's muscles move the mouth corner further than the seeds' published
    # constants do under the same activity and jaw
    code, out, err = cli(monkeypatch, capsys, "demo", "-o", tmp_path / "c", "--no-video",
                         "--preset", "lucero1999")
    assert code == 0, err
    seeds = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert seeds["preset"] == "lucero1999"
    corner = default_face().landmarks["mouth_corner_left"]
    reach = []
    for d in ("d", "c"):
        p = read_results(tmp_path / d / "result.nc")["positions"].values[:, corner]
        reach.append(np.linalg.norm(p - p[0], axis=1).max())
    assert reach[0] > 1.2 * reach[1]  # the jaw moves the corner alike in both


def test_experiment_and_invert_options_are_checked(tmp_path, monkeypatch, capsys):
    code, _, err = cli(monkeypatch, capsys, "experiment", "pitermann2001-synthetic",
                       "--preset", "stiff")
    assert_one_line_error(code, err, "preset", "calibrated")
    code, _, err = cli(monkeypatch, capsys, "experiment", "pitermann2001-crosstalker",
                       "--preset", "stiff")
    assert_one_line_error(code, err, "preset")
    face = default_face()
    mk = tmp_path / "m.csv"
    rows = ["# units: mm", "time," + ",".join(f"{n}_{a}" for n in ("R03", "R05", "R07")
                                               for a in "xyz")]
    for k in range(3):
        pts = [face.rest_positions[face.markers[n]] * 1e3 for n in ("R03", "R05", "R07")]
        rows.append(f"{k / 60}," + ",".join(f"{v:.4f}" for p in pts for v in p))
    mk.write_text("\n".join(rows) + "\n")
    res = tmp_path / "r.nc"
    code, _, err = cli(monkeypatch, capsys, "invert", "--markers", mk, "--tol", "-1", "-o", res)
    assert_one_line_error(code, err, "tol")
    code, _, err = cli(monkeypatch, capsys, "invert", "--markers", mk, "--window", "0", "-o", res)
    assert_one_line_error(code, err, "window")
    assert not res.exists()
