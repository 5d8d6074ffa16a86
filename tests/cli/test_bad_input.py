"""Bad input (issue 18): one stderr line naming the file and the field, exit 2, no traceback,
and the folder left exactly as it was (input bytes identical, nothing new, no temporary file).
"""

from __future__ import annotations

import hashlib
import json
import math
import re

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.markerset import MarkerSet

TRC_HEADER = ("PathFileType\t4\t(X/Y/Z)\tx.trc\n"
              "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\t"
              "OrigDataStartFrame\tOrigNumFrames\n"
              "{rate}\t{rate}\t3\t{n}\tmm\t{rate}\t1\t3\n"
              "Frame#\tTime\t{labels}\n"
              "\t\t{axes}\n\n")


def _trc(rate="60", times=("0.0", "0.0166667", "0.0333333"), labels=("A",)) -> str:
    head = TRC_HEADER.format(rate=rate, n=len(labels), labels="\t\t\t".join(labels) + "\t\t",
                             axes="\t".join(f"{a}{k + 1}" for k in range(len(labels))
                                            for a in "XYZ"))
    rows = "".join(f"{k + 1}\t{t}\t" + "\t".join(["1.0", "2.0", "3.0"] * len(labels)) + "\n"
                   for k, t in enumerate(times))
    return head + rows


def _snapshot(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def _refused(monkeypatch, capsys, tmp_path, name: str, content, field: str | None,
             command=("markers", "convert")):
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    before = _snapshot(tmp_path)
    code, out, err = run_cli(monkeypatch, capsys, *command, path, tmp_path / "out.csv")
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: {path}"), lines[0]
    if field is not None:
        assert f"field '{field}'" in lines[0], lines[0]
    assert _snapshot(tmp_path) == before, "the folder changed"
    return lines[0]


JUNK = bytes(range(256)) * 8


@pytest.mark.parametrize("name", ["junk.trc", "junk.csv", "junk.tsv"])
def test_binary_junk_in_a_text_format(monkeypatch, capsys, tmp_path, name):
    line = _refused(monkeypatch, capsys, tmp_path, name, JUNK, None)
    assert "text" in line or "binary" in line


@pytest.mark.parametrize("times, why", [
    (("0.0", "nan", "0.0333333"), "a NaN time"),
    (("0.0", "0.05", "0.0333333"), "time going back"),
    (("0.0", "0.0", "0.0333333"), "a repeated time"),
])
def test_trc_time_must_be_finite_and_increasing(monkeypatch, capsys, tmp_path, times, why):
    line = _refused(monkeypatch, capsys, tmp_path, "t.trc", _trc(times=times), "Time")
    assert "strictly increasing" in line, why


@pytest.mark.parametrize("rate", ["inf", "0", "-60", "nan"])
def test_trc_rate_must_be_positive_and_finite(monkeypatch, capsys, tmp_path, rate):
    _refused(monkeypatch, capsys, tmp_path, "r.trc", _trc(rate=rate), "DataRate")


def test_duplicate_marker_labels_name_the_file_and_the_label(monkeypatch, capsys, tmp_path):
    line = _refused(monkeypatch, capsys, tmp_path, "d.trc", _trc(labels=("UL", "UL")), "UL")
    assert "duplicate" in line


def test_csv_time_in_the_wrong_order(monkeypatch, capsys, tmp_path):
    text = "# units: mm\ntime,A_x,A_y,A_z\n0.0,1,2,3\n0.02,1,2,3\n0.01,1,2,3\n"
    _refused(monkeypatch, capsys, tmp_path, "m.csv", text, "time")


@pytest.mark.parametrize("rate", [0.0, -1.0, math.inf, math.nan, 1e9])
def test_the_marker_set_refuses_impossible_rates(rate):
    with pytest.raises(InputError, match="rate"):
        MarkerSet(np.zeros((3, 1, 3)), ("A",), rate)


def test_the_marker_set_refuses_unordered_time():
    with pytest.raises(InputError, match="frame 3"):
        MarkerSet(np.zeros((3, 1, 3)), ("A",), 60.0, time=np.array([0.0, 0.2, 0.1]))
    with pytest.raises(InputError, match="2 times for 3 frames"):
        MarkerSet(np.zeros((3, 1, 3)), ("A",), 60.0, time=np.array([0.0, 0.2]))


# ---- results files -----------------------------------------------------------------------------
def _tiny_results(path, positions):
    import xarray as xr

    ds = xr.Dataset({"positions": (("time", "node", "axis"), positions),
                     "markers": (("time", "marker", "axis"), np.zeros((2, 1, 3))),
                     "triangles": (("triangle", "corner"), np.array([[0, 1, 2]]))},
                    attrs={"frame_rate_hz": 60.0})
    ds.to_netcdf(path, engine="h5netcdf")


def test_a_results_file_holding_nan_is_refused_on_reading(tmp_path):
    from facemech.io.results import read_results

    pos = np.zeros((2, 3, 3))
    _tiny_results(tmp_path / "ok.nc", pos)
    assert read_results(tmp_path / "ok.nc")["positions"].shape == (2, 3, 3)
    pos[1, 2, 0] = np.nan
    _tiny_results(tmp_path / "nan.nc", pos)
    with pytest.raises(InputError, match=r"nan\.nc: field 'positions': non-finite value at "
                                         r"frame 1, node 2, axis 0"):
        read_results(tmp_path / "nan.nc")


# ---- outputs -----------------------------------------------------------------------------------
def test_an_output_equal_to_an_input_is_refused(tmp_path):
    from facemech.atomic import check_output

    src = tmp_path / "in.csv"
    src.write_text("x")
    with pytest.raises(InputError, match="refusing to overwrite an input"):
        check_output(src, [None, src], field="-o")
    link = tmp_path / "link.csv"
    link.symlink_to(src)
    with pytest.raises(InputError, match="field '-o'"):
        check_output(link, [src], field="-o")
    with pytest.raises(InputError, match="refusing"):
        check_output(tmp_path / "sub" / ".." / "in.csv", [src])
    assert check_output(tmp_path / "out.csv", [src]) == tmp_path / "out.csv"
    assert src.read_text() == "x" and sorted(p.name for p in tmp_path.iterdir()) == [
        "in.csv", "link.csv"]


def test_an_output_where_it_cannot_be_written_is_refused(tmp_path):
    from facemech.atomic import check_output

    (tmp_path / "file").write_text("x")
    (tmp_path / "folder").mkdir()
    with pytest.raises(InputError, match="goes through the file"):
        check_output(tmp_path / "file" / "out.nc")
    with pytest.raises(InputError, match="a folder is in the way"):
        check_output(tmp_path / "folder")
    with pytest.raises(InputError, match="a file is in the way"):
        check_output(tmp_path / "file", folder=True)
    assert check_output(tmp_path / "new" / "deeper", folder=True).name == "deeper"
    assert not (tmp_path / "new").exists(), "checking created the folder"


def test_pending_temporary_files_are_removed(tmp_path):
    from facemech.atomic import atomic_path, remove_pending

    with pytest.raises(RuntimeError), atomic_path(tmp_path / "out.csv") as tmp:
        tmp.write_text("half")
        assert remove_pending() == 1 and not tmp.exists()
        raise RuntimeError
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("sig, status", [("SIGINT", 130), ("SIGTERM", 143)])
def test_a_signal_removes_temporary_files_and_exits_with_the_shell_status(tmp_path, sig,
                                                                          status):
    import subprocess
    import sys

    code = f"""
import os, signal
from facemech.interrupts import install
from facemech.atomic import atomic_path
install()
with atomic_path({str(tmp_path / 'out.nc')!r}) as tmp:
    tmp.write_text("half written")
    os.kill(os.getpid(), signal.{sig})
    import time; time.sleep(5)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == status
    assert done.stderr.strip() == "facemech: interrupted"
    assert list(tmp_path.iterdir()) == []


def test_an_unwritable_package_sends_the_numba_cache_to_a_temporary_folder():
    import facemech

    assert facemech._numba_cache_dir("/pkg", {}, lambda d: True) is None
    assert facemech._numba_cache_dir("/pkg", {"NUMBA_CACHE_DIR": "/c"}, lambda d: False) is None
    where = facemech._numba_cache_dir("/pkg", {}, lambda d: False)
    assert "facemech-numba-cache" in where


# ---- C3D in every byte order -------------------------------------------------------------------
def _c3d_bytes(processor: int, frames: int, data_bytes: int) -> bytes:
    """A C3D header + parameter header announcing 2 float points over ``frames`` frames."""
    order = ">" if processor == 86 else "<"
    words = np.zeros(256, dtype=f"{order}u2")
    words[1], words[2], words[3], words[4], words[8] = 2, 0, 1, frames, 3
    head = bytearray(words.tobytes())
    head[0], head[1] = 2, 0x50
    sign = {84: 15, 85: 13, 86: 12}[processor]
    head[sign] |= 0x80  # a negative scale: float samples
    params = bytearray(512)
    params[:4] = bytes([1, 0x50, 1, processor])
    return bytes(head) + bytes(params) + bytes(data_bytes)


@pytest.mark.parametrize("processor", [84, 85, 86])
def test_a_truncated_c3d_is_refused_in_every_byte_order(tmp_path, processor):
    from facemech.io.c3d import check_header

    whole = 10 * 2 * 4 * 4  # 10 frames x 2 points x (x, y, z, residual) x 4 bytes
    (tmp_path / "whole.c3d").write_bytes(_c3d_bytes(processor, 10, whole))
    check_header(tmp_path / "whole.c3d")
    (tmp_path / "cut.c3d").write_bytes(_c3d_bytes(processor, 10, whole - 16))
    with pytest.raises(InputError, match=r"cut\.c3d: field .header.: truncated"):
        check_header(tmp_path / "cut.c3d")


def test_a_c3d_with_an_unknown_processor_is_refused(tmp_path):
    from facemech.io.c3d import check_header

    (tmp_path / "odd.c3d").write_bytes(_c3d_bytes(84, 10, 320)[:515] + b"\x57"
                                       + _c3d_bytes(84, 10, 320)[516:])
    with pytest.raises(InputError, match="field 'processor'"):
        check_header(tmp_path / "odd.c3d")


# ---- plausibility: the declared unit -----------------------------------------------------------
def _marker_csv(scale: float, unit: str) -> str:
    rows = [f"{k / 60:.6f}," + ",".join(f"{v * scale:.9g}" for v in (0.03, 0.0, 0.1, -0.03, 0.0,
                                                                       0.1, 0.0, -0.04, 0.11))
            for k in range(4)]
    return f"# units: {unit}\ntime,L_x,L_y,L_z,R_x,R_y,R_z,C_x,C_y,C_z\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize("scale, unit, looks", [(1.0, "mm", "m"), (1e6, "mm", "um"),
                                                (1e3, "m", "mm")])
def test_values_in_another_unit_than_declared_are_refused(monkeypatch, capsys, tmp_path, scale,
                                                          unit, looks):
    line = _refused(monkeypatch, capsys, tmp_path, "m.csv", _marker_csv(scale, unit), "units")
    assert f"the values look like {looks}" in line


def test_a_face_in_its_declared_unit_is_read(monkeypatch, capsys, tmp_path):
    from facemech.io.markers import read_markers

    (tmp_path / "m.csv").write_text(_marker_csv(1e3, "mm"))
    ms = read_markers(tmp_path / "m.csv")
    np.testing.assert_allclose(ms.positions[0, 2], [0.0, -0.04, 0.11])


# ---- plausibility: times, jaw angles, face size ------------------------------------------------
def test_an_activity_time_column_in_milliseconds_is_refused(monkeypatch, capsys, tmp_path):
    from facemech.io.activity import read_activity

    (tmp_path / "a.csv").write_text("time,OOS\n0,0\n500,1\n1000,0\n")
    with pytest.raises(InputError, match=r"a\.csv: field 'time': rows 500 s apart; the times "
                                         r"look like milliseconds"):
        read_activity(tmp_path / "a.csv")
    (tmp_path / "b.csv").write_text("time,OOS\n0,0\n0.5,1\n1.0,0\n")
    t, act = read_activity(tmp_path / "b.csv")
    assert t[-1] == pytest.approx(1.0) and act.max() == pytest.approx(1.0)


def test_an_emg_time_column_in_milliseconds_is_refused(tmp_path):
    from facemech.io.emg import read_emg

    t = np.arange(2000) / 1000.0
    rows = "\n".join(f"{x * 1e3:g},{np.sin(x):.4f}" for x in t)
    (tmp_path / "e.csv").write_text("time,OOS\n" + rows + "\n")
    with pytest.raises(InputError, match=r"e\.csv: field 'time': EMG sampled at 1 Hz.*look like "
                                         r"milliseconds"):
        read_emg(tmp_path / "e.csv")
    rows = "\n".join(f"{x:.4f},{np.sin(x):.4f}" for x in t)
    (tmp_path / "s.csv").write_text("time,OOS\n" + rows + "\n")
    assert read_emg(tmp_path / "s.csv")[1] == pytest.approx(1000.0)


def test_jaw_angles_outside_the_anatomy_are_refused():
    from facemech.plausibility import check_jaw_angles

    ok = np.radians([0.0, 12.0, 34.0, -4.0])
    assert check_jaw_angles(ok) is not None
    with pytest.raises(InputError, match="sample 2: a jaw angle of -34.0 degrees"):
        check_jaw_angles(np.radians([0.0, -34.0]), source="j.csv")
    with pytest.raises(InputError, match="20 looks like degrees given as radians"):
        check_jaw_angles([0.0, 20.0], source="j.csv", field="angle")
    assert check_jaw_angles(np.radians([50.0]), limits_deg=(-5, 60))[0] == pytest.approx(
        np.radians(50.0))


@pytest.mark.parametrize("width_m, unit, looks", [(0.15e-3, "mm", "m"), (150.0, "mm", "um"),
                                                  (1.5, "cm", "mm")])
def test_a_face_not_face_sized_in_its_unit_is_refused(width_m, unit, looks):
    from facemech.plausibility import check_face_size

    with pytest.raises(InputError, match=f"the values look like {looks}$"):
        check_face_size(width_m, unit=unit, source="scan.obj")
    assert check_face_size(0.16, unit=unit) == 0.16


def test_collinear_head_markers_are_refused_before_anything_is_written():
    from facemech.kinematics.rigid import head_correct

    pos = np.zeros((5, 4, 3))
    pos[:, 0] = [0.0, 0.0, 0.1]
    pos[:, 1] = [0.02, 0.0, 0.1]
    pos[:, 2] = [0.04, 0.0, 0.1]  # on the line through the first two
    pos[:, 3] = [0.0, -0.05, 0.1]
    ms = MarkerSet(pos.copy(), ("H1", "H2", "H3", "UL"), 60.0, meta={"source": "rec.trc"})
    with pytest.raises(InputError, match=r"rec\.trc: field 'head': the head markers H1, H2, H3 "
                                         r"lie on one line"):
        head_correct(ms, ["H1", "H2", "H3"])
    pos[:, 2] = [0.02, 0.03, 0.09]
    fixed = head_correct(MarkerSet(pos, ("H1", "H2", "H3", "UL"), 60.0), ["H1", "H2", "H3"])
    np.testing.assert_allclose(fixed.markers.positions[:, 3], pos[:, 3], atol=1e-12)


@pytest.mark.parametrize("command", [
    ("markers", "convert", "{in}", "-o", "{in}"),
    ("markers", "resample", "{in}", "-o", "{in}"),
    ("markers", "fill-gaps", "{in}", "-o", "{in}"),
    ("emg", "process", "{emg}", "-o", "{emg}"),
    ("simulate", "--activity", "{act}", "-o", "{act}"),
])
def test_a_command_never_overwrites_its_input(monkeypatch, capsys, tmp_path, command):
    (tmp_path / "m.trc").write_text(_trc(labels=("A", "B")).replace("1.0\t2.0\t3.0\n",
                                                                     "1.0\t2.0\t3.0\n", 1))
    t = np.arange(600) / 1000.0
    (tmp_path / "e.csv").write_text("time,OOS\n" + "\n".join(f"{x:.4f},{np.sin(50 * x):.4f}"
                                                             for x in t) + "\n")
    (tmp_path / "a.csv").write_text("time,OOS\n0,0\n0.5,1\n")
    files = {"{in}": tmp_path / "m.trc", "{emg}": tmp_path / "e.csv", "{act}": tmp_path / "a.csv"}
    before = _snapshot(tmp_path)
    code, _, err = run_cli(monkeypatch, capsys, *[files.get(a, a) for a in command])
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "refusing to overwrite an input" in err and "field '-o'" in err
    assert _snapshot(tmp_path) == before


# ---- compare: statistics with gaps -------------------------------------------------------------
#: mm, three markers at rest: left and right mouth corners and the chin (spans a face's size)
_REST = np.array([[30.0, 0.0, 100.0], [-30.0, 0.0, 100.0], [0.0, -40.0, 110.0]])


def _model_mm(frames: int = 10) -> np.ndarray:
    """(frames, 3, 3) mm: the markers moving down and up by up to 4 mm."""
    k = np.arange(frames)[:, None, None]
    return _REST[None] + np.array([0.0, -4.0, 0.0]) * np.sin(np.pi * k / (frames - 1))


def _csv(path, pos_mm, unit: str = "mm", names=("L", "R", "C")):
    head = "time," + ",".join(f"{n}_{a}" for n in names for a in "xyz")
    rows = [f"{k / 60:.6f}," + ",".join("" if not np.isfinite(v) else f"{v:.9g}"
                                        for v in p.reshape(-1)) for k, p in enumerate(pos_mm)]
    path.write_text(f"# units: {unit}\n{head}\n" + "\n".join(rows) + "\n")
    return path


def _tree(folder):
    """Every file (its bytes' hash) and folder under ``folder``."""
    return {str(p.relative_to(folder)): (hashlib.sha256(p.read_bytes()).hexdigest()
                                         if p.is_file() else "folder")
            for p in sorted(folder.rglob("*"))}


def _one_line_error(monkeypatch, capsys, folder, args, source, field) -> str:
    """Run ``facemech ARGS``: exit 2, one stderr line naming ``source`` and ``field``, no
    traceback, and nothing under ``folder`` changed."""
    before = _tree(folder)
    code, _, err = run_cli(monkeypatch, capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: {source}: field '{field}': "), lines[0]
    assert _tree(folder) == before, "the folder changed"
    return lines[0]


def test_compare_skips_frames_without_data(monkeypatch, capsys, tmp_path):
    model = _model_mm()
    data = model + (np.arange(10) + 1.0)[:, None, None] * np.array([1.0, 0.0, 0.0])  # k + 1 mm
    data[[2, 5]] = np.nan  # two frames without any marker
    data[7, 2] = np.nan  # the chin missing at frame 7: that frame's error from L and R
    a, b = _csv(tmp_path / "a.csv", model), _csv(tmp_path / "b.csv", data)
    code, out, err = run_cli(monkeypatch, capsys, "compare", a, b, "--json")
    assert code == 0, err
    res = json.loads(out)
    hand = np.median([k + 1.0 for k in range(10) if k not in (2, 5)])  # (5 + 7) / 2 = 6 mm
    assert hand == 6.0
    assert res["error"]["median_mm"] == pytest.approx(hand, rel=1e-6)
    assert res["frame_error_mm"]["min"] == pytest.approx(1.0, rel=1e-6)  # never a 0 mm frame
    assert res["error"]["max_mm"] == pytest.approx(10.0, rel=1e-6)
    assert (res["frames"], res["frames_skipped"], res["samples_skipped"]) == (10, 2, 1)
    assert res["missing_markers"] == []
    for name, m in res["markers"].items():  # an offset along x only: y and z follow exactly
        assert m["displacement"]["y"] == pytest.approx(1.0, abs=1e-9), name
        assert m["corr3d_published"] is not None and 0.0 < m["corr3d_published"] < 1.0, name
    code, out, err = run_cli(monkeypatch, capsys, "compare", a, b)
    assert code == 0 and "median 6.000, max 10.000" in out
    assert "2 of 10 frames without data were skipped" in out
    assert "1 of 24 marker-frames without data were skipped" in out
    assert "no marker" not in err  # the gaps are in the summary, not a warning


def test_compare_leaves_out_a_marker_without_data(monkeypatch, capsys, tmp_path):
    model = _model_mm()
    data = model.copy()
    data[:, 0] += [0.0, 0.0, 3.0]  # L 3 mm forward, R exact: RMS sqrt(9 / 2) mm
    data[:, 2] = np.nan  # the chin never recorded
    a, b = _csv(tmp_path / "a.csv", model), _csv(tmp_path / "b.csv", data)
    code, out, err = run_cli(monkeypatch, capsys, "compare", a, b, "--json")
    assert code == 0, err
    res = json.loads(out)
    assert res["missing_markers"] == ["C"] and sorted(res["markers"]) == ["L", "R"]
    assert res["error"]["median_mm"] == pytest.approx(np.sqrt(4.5), rel=1e-6)
    assert (res["frames_skipped"], res["samples_skipped"]) == (0, 0)
    assert res["markers"]["R"]["corr3d_published"] == pytest.approx(1.0, abs=1e-9)
    code, out, _ = run_cli(monkeypatch, capsys, "compare", a, b)
    assert "1 of 3 markers without data in both were left out: C" in out
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", a, b, "--markers", "C"),
                           b, "C")
    assert "no frame has data in both inputs for the marker C (B has no data)" in line


def test_compare_refuses_data_without_any_sample(monkeypatch, capsys, tmp_path):
    a = _csv(tmp_path / "a.csv", _model_mm())
    b = _csv(tmp_path / "b.csv", np.full((10, 3, 3), np.nan))
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", a, b), b, "markers")
    assert "no frame has data in both inputs for any marker (B has no data)" in line
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", b, a), b, "markers")
    assert line.endswith("(A has no data)")
    half = _model_mm()  # data in A's first half only, in B's second half only
    half[5:] = np.nan
    other = _model_mm()
    other[:5] = np.nan
    a, b = _csv(tmp_path / "h.csv", half), _csv(tmp_path / "o.csv", other)
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", a, b), b, "markers")
    assert line.endswith("(A and B have data at different frames)")


@pytest.mark.parametrize("scale, label, guess", [(1.0, "m", "mm"), (1e-3, "mm", "m")])
def test_compare_refuses_a_metre_millimetre_mix_up(monkeypatch, capsys, tmp_path, scale, label,
                                                   guess):
    model = _model_mm()[:, 2:]  # one marker: the span check of a marker file does not apply
    a = _csv(tmp_path / "a.csv", model, names=("C",))
    b = _csv(tmp_path / "b.csv", model * scale, unit=label, names=("C",))
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", a, b), b, "units")
    assert re.search(r"median error [0-9.]+ m(m)? \(more than 50 mm\): are the data in "
                     f"{guess} labelled as {label}\\?", line), line
    lab = _csv(tmp_path / "lab.csv", model + 500.0, names=("C",))  # right unit, other origin
    line = _one_line_error(monkeypatch, capsys, tmp_path, ("compare", a, lab), lab, "units")
    assert "median error 866 mm" in line and "model's frame" in line
    near = _csv(tmp_path / "near.csv", model + 20.0, names=("C",))  # 34.6 mm: accepted
    code, out, _ = run_cli(monkeypatch, capsys, "compare", a, near, "--json")
    assert code == 0 and json.loads(out)["error"]["median_mm"] == pytest.approx(
        20.0 * np.sqrt(3), rel=1e-6)


# ---- every writing command checks its output before any work -----------------------------------
_WRITERS = {  # command (the output last, after -o), what the output is: "file" or "folder"
    "render": (("render", "{r}"), "file"),
    "still": (("still", "{r}"), "file"),
    "plot": (("plot", "{r}"), "file"),
    "view": (("view", "{r}"), "file"),
    "export": (("export", "{r}"), "file"),
    "export-obj": (("export", "{r}", "--format", "obj"), "folder"),
    "invert": (("invert", "--markers", "{m}"), "file"),
    "regions": (("regions", "{m}"), "folder"),
    "speak": (("speak", "hello", "--audio", "{w}"), "folder"),
    "stimuli": (("stimuli", "{d}"), "folder"),
    "calibrate": (("calibrate", "{m}:OOS"), "file"),
    "crosstalker": (("experiment", "pitermann2001-crosstalker"), "file"),
    "synthetic": (("experiment", "pitermann2001-synthetic"), "folder"),
    "lucero2008": (("experiment", "lucero2008"), "folder"),
}


@pytest.fixture
def inputs(tmp_path):
    """Input files (not even valid: the output is checked before any is read), an existing
    folder and an unrelated file."""
    files = {"{r}": "r.nc", "{m}": "m.csv", "{w}": "voice.wav", "{d}": "design.csv",
             "{file}": "notes.txt"}
    for name in files.values():
        (tmp_path / name).write_text(f"{name}: left exactly as it was\n")
    (tmp_path / "taken.json").mkdir()
    return {k: tmp_path / v for k, v in files.items()} | {"{dir}": tmp_path / "taken.json"}


def _args(command, inputs, output, *extra):
    return [*(inputs.get(a, a) for a in command), *extra, "-o", output]


@pytest.mark.parametrize("which", [w for w in _WRITERS if w not in (
    "crosstalker", "synthetic", "lucero2008", "calibrate")])
def test_a_writing_command_refuses_its_input_as_output(monkeypatch, capsys, tmp_path, inputs,
                                                       which):
    command, _ = _WRITERS[which]
    given = next(inputs[a] for a in command if a in inputs)
    line = _one_line_error(monkeypatch, capsys, tmp_path, _args(command, inputs, given), given,
                           "-o")
    assert f"the output is the input {given}: refusing to overwrite an input" in line


# export takes an existing folder as the folder of a mesh sequence: never in the way
@pytest.mark.parametrize("which", [w for w in _WRITERS if w != "export"])
def test_a_writing_command_refuses_a_folder_or_file_in_the_way(monkeypatch, capsys, tmp_path,
                                                               inputs, which):
    command, kind = _WRITERS[which]
    output = inputs["{dir}" if kind == "file" else "{file}"]
    line = _one_line_error(monkeypatch, capsys, tmp_path, _args(command, inputs, output),
                           output, "-o")
    assert (f"a {'folder' if kind == 'file' else 'file'} is in the way of the output "
            f"{kind}") in line


@pytest.mark.parametrize("which", list(_WRITERS))
def test_a_writing_command_refuses_a_path_through_a_file(monkeypatch, capsys, tmp_path, inputs,
                                                         which):
    command, kind = _WRITERS[which]
    output = inputs["{file}"] / "sub" / ("out" if kind == "folder" else "out.json")
    line = _one_line_error(monkeypatch, capsys, tmp_path, _args(command, inputs, output),
                           output, "-o")
    assert f"the path goes through the file {inputs['{file}']}" in line


def test_invert_checks_its_figure_before_the_inversion(monkeypatch, capsys, tmp_path, inputs):
    m = inputs["{m}"]
    args = ("invert", "--markers", m, "-o", tmp_path / "r2.nc", "--figure")
    line = _one_line_error(monkeypatch, capsys, tmp_path, (*args, m), m, "--figure")
    assert "refusing to overwrite an input" in line
    line = _one_line_error(monkeypatch, capsys, tmp_path, (*args, tmp_path / "r2.nc"),
                           tmp_path / "r2.nc", "--figure")
    assert "the figure and the results file are the same path" in line
    line = _one_line_error(monkeypatch, capsys, tmp_path, (*args, inputs["{dir}"]),
                           inputs["{dir}"], "--figure")
    assert "a folder is in the way" in line


# ---- landmarks and numeric options, through the command line ---------------------------------
def _face_files(folder, change):
    """The generic face as OBJ (mm) and a landmark CSV changed by ``change(landmarks_m)``."""
    from facemech.geometry.builder import default_surface

    v, f, lm = default_surface()
    with open(folder / "face.obj", "w") as fh:
        fh.writelines(f"v {x * 1e3:.6f} {y * 1e3:.6f} {z * 1e3:.6f}\n" for x, y, z in v)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    lm = change(dict(lm))
    with open(folder / "lm.csv", "w") as fh:
        fh.write("name,x,y,z\n")
        fh.writelines(f"{n},{p[0] * 1e3:.6f},{p[1] * 1e3:.6f},{p[2] * 1e3:.6f}\n"
                      for n, p in lm.items())
    return folder / "face.obj", folder / "lm.csv"


def _off_skin(lm):
    lm["nose_tip"] = lm["nose_tip"] + [0.0, 0.0, 0.1]
    return lm


def _twice(lm):
    lm["chin"] = lm["menton"] + [0.0, 0.0005, 0.0]
    return lm


def _swapped(lm):
    lm["mouth_corner_left"], lm["mouth_corner_right"] = (lm["mouth_corner_right"],
                                                         lm["mouth_corner_left"])
    return lm


@pytest.mark.parametrize("change, field, words", [
    (_off_skin, "nose_tip", "from the surface"),
    (_twice, "menton", "'chin' and 'menton'"),
    (_swapped, "mouth_corner_left", "mouth_corner_right"),
])
def test_implausible_landmarks_are_refused(monkeypatch, capsys, tmp_path, change, field, words):
    surface, landmarks = _face_files(tmp_path, change)
    line = _one_line_error(monkeypatch, capsys, tmp_path,
                           ("face", "build", surface, landmarks, "-o", tmp_path / "f.npz"),
                           landmarks, field)
    assert words in line, line


@pytest.mark.parametrize("args, option", [
    (("markers", "resample", "m.csv", "-o", "r.csv", "--rate", "nan"), "--rate"),
    (("simulate", "-o", "r.nc", "--activity", "a.csv", "--dt", "inf"), "--dt"),
    (("invert", "--markers", "m.csv", "-o", "i.nc", "--noise", "-0.5"), "--noise"),
    (("render", "r.nc", "-o", "v.mp4", "--aa", "0"), "--aa"),
])
def test_numeric_options_are_refused_by_name(monkeypatch, capsys, tmp_path, args, option):
    (tmp_path / "m.csv").write_text("time,A_x,A_y,A_z\n0,1,2,3\n")
    before = _tree(tmp_path)
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(monkeypatch, capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: option {option}: must be a finite number")
    assert _tree(tmp_path) == before
