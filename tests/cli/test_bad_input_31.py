"""Bad input, the last mile (issue 31): checks before the long work, one line naming the file
and field (or option and value), nothing written, inputs byte-identical."""

from __future__ import annotations

import hashlib
import time

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError


def _snapshot(folder):
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.is_file() else "dir" for p in sorted(folder.rglob("*"))}


def refused(monkeypatch, capsys, tmp_path, *args, words=(), seconds=5.0) -> str:
    """Run ``facemech ARGS`` (``{t}`` in an argument: ``tmp_path``); it must exit 2 with one
    stderr line holding ``words``, within ``seconds``, leaving ``tmp_path`` as it was."""
    before = _snapshot(tmp_path)
    start = time.perf_counter()
    code, _, err = run_cli(monkeypatch, capsys, *(str(a).format(t=tmp_path) for a in args))
    took = time.perf_counter() - start
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("facemech: error: "), lines[0]
    for w in words:
        assert str(w).format(t=tmp_path) in lines[0], lines[0]
    assert "np.float64" not in lines[0] and "np.int64" not in lines[0], lines[0]
    assert _snapshot(tmp_path) == before, "the folder changed"
    assert took < seconds, f"refused after {took:.1f} s"
    return lines[0]


def _activity(path, frames=30):
    t = np.arange(frames) / 60.0
    path.write_text("time,OOS\n" + "".join(f"{x:.6f},0.1\n" for x in t))
    return path


# ---- audio checked before the long work ---------------------------------------------------------
@pytest.mark.parametrize("audio, why", [
    ("missing.wav", "no such audio file"),
    ("garbage.wav", "not a readable WAV file"),
    ("silent.wav", "silent"),
])
def test_render_checks_its_audio_first(monkeypatch, capsys, tmp_path, audio, why):
    from facemech.speech.wav import write_wav

    (tmp_path / "r.nc").write_bytes(b"not read: the audio is checked first")
    (tmp_path / "garbage.wav").write_bytes(b"RIFF\x10\x00\x00\x00garbage garbage")
    write_wav(tmp_path / "silent.wav", np.zeros(1000), 8000)
    refused(monkeypatch, capsys, tmp_path, "render", "{t}/r.nc", "-o", "{t}/m.mp4",
            "--audio", f"{{t}}/{audio}", words=(f"{{t}}/{audio}", "field 'audio'", why))


def test_simulate_checks_the_movies_audio_before_simulating(monkeypatch, capsys, tmp_path):
    _activity(tmp_path / "a.csv")
    (tmp_path / "garbage.wav").write_bytes(bytes(range(256)) * 4)
    refused(monkeypatch, capsys, tmp_path, "simulate", "-o", "{t}/out.nc", "--activity",
            "{t}/a.csv", "--video", "{t}/m.mp4", "--audio", "{t}/garbage.wav",
            words=("{t}/garbage.wav", "field 'audio'"))


def test_audio_for_png_frames_is_refused_first(monkeypatch, capsys, tmp_path):
    from facemech.speech.wav import write_wav

    (tmp_path / "r.nc").write_bytes(b"not read")
    write_wav(tmp_path / "v.wav", np.sin(np.arange(800) / 5.0), 8000)
    refused(monkeypatch, capsys, tmp_path, "render", "{t}/r.nc", "-o", "{t}/frames",
            "--audio", "{t}/v.wav", words=("not into PNG frames",))


def test_check_audio_gives_the_length(tmp_path):
    from facemech.speech.wav import check_audio, write_wav

    write_wav(tmp_path / "v.wav", np.sin(np.arange(8000) / 5.0), 8000)
    assert check_audio(tmp_path / "v.wav") == pytest.approx(1.0)
    with pytest.raises(InputError, match="a folder, not a WAV file"):
        check_audio(tmp_path)


# ---- design tables: the whole table before the first row --------------------------------------
@pytest.mark.parametrize("cells, words", [
    ({"colour": "red"}, ("row 2, column 'colour'", "unknown column")),
    ({"amplitude": "-1"}, ("row 2, column 'amplitude'", "'-1'")),
    ({"id": "one"}, ("row 2, column 'id'", "'one' is used by an earlier row")),
    ({"av_offset_ms": "-100000"}, ("row 2, column 'av_offset_ms'", "-100000 ms")),
    ({"audio": "garbage.wav"}, ("row 2, column 'audio'", "garbage.wav")),
    ({"time_scale": "nan"}, ("row 2, column 'time_scale'", "'nan'")),
])
def test_a_design_table_that_cannot_run_is_refused_before_any_row(monkeypatch, capsys,
                                                                  tmp_path, cells, words):
    from facemech.speech.wav import write_wav

    (tmp_path / "r.nc").write_bytes(b"not read: the table is refused first")
    write_wav(tmp_path / "v.wav", np.sin(np.arange(4000) / 5.0), 8000)
    (tmp_path / "garbage.wav").write_bytes(b"RIFF....WAVEfmt nothing more")
    rows = [{"id": "one", "results": "r.nc", "audio": "v.wav"},
            {"id": "two", "results": "r.nc", "audio": "v.wav", **cells}]
    cols = list(dict.fromkeys(c for r in rows for c in r))
    (tmp_path / "d.csv").write_text("\n".join([",".join(cols)] + [
        ",".join(r.get(c, "") for c in cols) for r in rows]) + "\n")
    refused(monkeypatch, capsys, tmp_path, "stimuli", "{t}/d.csv", "-o", "{t}/out",
            words=("{t}/d.csv", *words))


@pytest.mark.parametrize("cells, words", [
    ("text = \"hello\"\ncolour = \"red\"", ("row 1, column 'colour'", "unknown column")),
    ("text = \"hello\"\nrate_wpm = \"fast\"", ("row 1, column 'rate_wpm'", "'fast'")),
    ("text = \"hello\"\nstrength = -2", ("row 1, column 'strength'", "-2")),
])
def test_text_rows_are_checked_before_any_is_spoken(monkeypatch, capsys, tmp_path, cells,
                                                    words):
    (tmp_path / "d.toml").write_text(f"[[stimulus]]\nid = \"a\"\n{cells}\n")
    refused(monkeypatch, capsys, tmp_path, "stimuli", "{t}/d.toml", "-o", "{t}/out",
            words=("{t}/d.toml", *words))


# ---- tracebacks and messages that named nothing ------------------------------------------------
def tiny_results(path, frames=6):
    """A small results file: three nodes, markers R01-R03 moving up 1 mm per frame."""
    import xarray as xr

    rest = np.array([[0.0, 0.0, 0.0], [0.03, 0.0, 0.0], [0.0, 0.03, 0.01]])
    pos = rest[None] + np.arange(frames)[:, None, None] * np.array([0.0, 1e-3, 0.0])
    ds = xr.Dataset({"positions": (("time", "node", "axis"), pos),
                     "markers": (("time", "marker", "axis"), pos.copy()),
                     "triangles": (("triangle", "corner"), np.array([[0, 1, 2]]))},
                    coords={"time": np.arange(frames) / 60.0, "axis": list("xyz"),
                            "marker": ["R01", "R02", "R03"]},
                    attrs={"frame_rate_hz": 60.0})
    ds.to_netcdf(path, engine="h5netcdf")
    return path


def marker_csv(path, rows, names=("R01", "R02")):
    head = "time," + ",".join(f"{n}_{a}" for n in names for a in "xyz")
    path.write_text("# units: mm\n" + head + "\n" + "".join(
        f"{k / 60:.6f}," + ",".join(r) + "\n" for k, r in enumerate(rows)))
    return path


def test_plot_refuses_an_all_missing_measured_marker(monkeypatch, capsys, tmp_path):
    tiny_results(tmp_path / "r.nc")
    marker_csv(tmp_path / "m.csv", [[""] * 3 + ["1", "2", "3"]] * 6)
    refused(monkeypatch, capsys, tmp_path, "plot", "{t}/r.nc", "-o", "{t}/p.png", "--markers",
            "R01", "--measured", "{t}/m.csv", words=("{t}/m.csv", "field 'R01'", "no sample"))


@pytest.mark.parametrize("names, words", [(",", ("--markers", "','")),
                                          ("R01,X9", ("{t}/r.nc", "'X9'"))])
def test_plot_refuses_marker_names_it_cannot_draw(monkeypatch, capsys, tmp_path, names, words):
    tiny_results(tmp_path / "r.nc")
    refused(monkeypatch, capsys, tmp_path, "plot", "{t}/r.nc", "-o", "{t}/p.png", "--markers",
            names, words=words)


def test_plot_draws_measured_markers_without_gaps(monkeypatch, capsys, tmp_path):
    tiny_results(tmp_path / "r.nc")
    marker_csv(tmp_path / "m.csv", [[str(v) for v in (0, k, 0, 30, 0, 0)] for k in range(6)])
    code, _, err = run_cli(monkeypatch, capsys, "plot", tmp_path / "r.nc", "-o",
                           tmp_path / "p.png", "--markers", "R01,R02", "--measured",
                           tmp_path / "m.csv")
    assert code == 0, err
    assert (tmp_path / "p.png").stat().st_size > 1000


def test_regions_names_the_file_and_marker_of_a_gap(monkeypatch, capsys, tmp_path):
    full = [["0", "0", "0", "1", "2", "3"]] * 5
    marker_csv(tmp_path / "a.csv", full)
    marker_csv(tmp_path / "b.csv", full[:2] + [["0", "0", "0", "", "", ""]] + full[3:])
    refused(monkeypatch, capsys, tmp_path, "regions", "{t}/a.csv", "{t}/b.csv", "-o",
            "{t}/out", words=("{t}/b.csv", "field 'R02'", "frame 3"))


@pytest.mark.parametrize("pair, words", [("R01", ("--scale-pair", "'R01'")),
                                         ("R01,R01", ("--scale-pair",)),
                                         ("R01,Q7", ("--scale-pair", "'Q7'"))])
def test_invert_checks_its_scale_pair_first(monkeypatch, capsys, tmp_path, pair, words):
    marker_csv(tmp_path / "m.csv", [["0", "0", "0", "30", "2", "3"]] * 4)
    refused(monkeypatch, capsys, tmp_path, "invert", "--markers", "{t}/m.csv", "-o",
            "{t}/r.nc", "--scale-pair", pair, words=words)


def test_invert_refuses_a_frame_without_any_marker_first(monkeypatch, capsys, tmp_path):
    rows = [["0", "0", "0", "30", "2", "3"]] * 4
    marker_csv(tmp_path / "m.csv", rows[:2] + [[""] * 6] + rows[3:])
    refused(monkeypatch, capsys, tmp_path, "invert", "--markers", "{t}/m.csv", "-o",
            "{t}/r.nc", words=("{t}/m.csv", "frame 3", "no marker at all"))


def test_a_binary_landmark_file_is_refused(monkeypatch, capsys, tmp_path):
    (tmp_path / "face.obj").write_text("v 0 0 0\nv 150 0 0\nv 0 150 0\nf 1 2 3\n")
    (tmp_path / "lm.csv").write_bytes(bytes(range(256)) * 16)
    refused(monkeypatch, capsys, tmp_path, "face", "build", "{t}/face.obj", "{t}/lm.csv", "-o",
            "{t}/f.json", words=("{t}/lm.csv", "binary"))


def test_a_garbage_obj_names_the_file_not_a_module(tmp_path):
    from facemech.geometry.surface_io import read_surface

    (tmp_path / "g.obj").write_bytes(bytes(range(256)) * 16)
    with pytest.raises(InputError, match=r"g\.obj: field 'geometry': binary data"):
        read_surface(tmp_path / "g.obj")


def test_numpy_scalars_print_as_values():
    err = InputError(f"rate {np.float64(np.nan)!r} Hz, {np.int64(3)!r} frames", field="rate")
    assert str(err) == "field 'rate': rate nan Hz, 3 frames"


# ---- no file facemech cannot read back ---------------------------------------------------------
def test_an_infinite_coordinate_is_an_error_naming_the_cell(monkeypatch, capsys, tmp_path):
    marker_csv(tmp_path / "m.csv", [["0", "0", "0", "1", "2", "3"], ["0", "0", "0", "1", "inf",
                                                                     "3"]] * 2)
    refused(monkeypatch, capsys, tmp_path, "markers", "info", "{t}/m.csv",
            words=("{t}/m.csv", "field 'R02_y'", "row 2", "'inf'"))


def test_an_infinite_trc_coordinate_is_an_error_naming_marker_and_frame(tmp_path):
    from facemech.io.markers import read_markers
    from facemech.io.trc import write_trc
    from facemech.markerset import MarkerSet

    write_trc(tmp_path / "a.trc", MarkerSet(np.ones((3, 1, 3)) * 0.01, ("A",), 60.0),
              units="mm")
    text = (tmp_path / "a.trc").read_text().splitlines()
    cells = text[-1].split("\t")
    cells[3] = "-inf"
    (tmp_path / "b.trc").write_text("\n".join([*text[:-1], "\t".join(cells)]) + "\n")
    with pytest.raises(InputError, match=r"b\.trc: field 'A_y': infinite coordinate at frame 3"):
        read_markers(tmp_path / "b.trc")


def test_a_byte_order_mark_is_read(tmp_path):
    from facemech.io.markers import read_markers

    marker_csv(tmp_path / "m.csv", [["0", "0", "0", "30", "2", "3"]] * 3)
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + (tmp_path / "m.csv").read_bytes())
    ms = read_markers(tmp_path / "bom.csv")
    assert ms.names == ("R01", "R02") and ms.n_frames == 3
    assert ms.marker("R02")[0] == pytest.approx([0.03, 0.002, 0.003])


@pytest.mark.parametrize("suffix", [".trc", ".tsv"])
def test_a_byte_order_mark_is_read_in_trc_and_tsv(tmp_path, suffix):
    from facemech.io.markers import read_markers

    if suffix == ".trc":
        from facemech.io.trc import write_trc
        from facemech.markerset import MarkerSet

        write_trc(tmp_path / "a.trc", MarkerSet(np.full((3, 2, 3), 0.01), ("A", "B"), 60.0),
                  units="mm")
        text = (tmp_path / "a.trc").read_bytes()
    else:
        text = (b"NO_OF_FRAMES\t2\nFREQUENCY\t100\nMARKER_NAMES\tA\tB\n"
                b"1\t0.00\t10\t2\t3\t30\t2\t3\n2\t0.01\t10\t2\t3\t30\t2\t3\n")
    (tmp_path / f"bom{suffix}").write_bytes(b"\xef\xbb\xbf" + text)
    assert read_markers(tmp_path / f"bom{suffix}").names == ("A", "B")


def test_resampling_to_fewer_than_two_frames_is_refused(monkeypatch, capsys, tmp_path):
    marker_csv(tmp_path / "m.csv", [["0", "0", "0", "30", "2", "3"]] * 6)
    refused(monkeypatch, capsys, tmp_path, "markers", "resample", "{t}/m.csv", "-o",
            "{t}/r.csv", "--rate", "0.001", words=("field 'rate'", "at least two"))


def test_a_one_frame_trc_is_refused_and_never_written(monkeypatch, capsys, tmp_path):
    from facemech.io.markers import write_markers
    from facemech.markerset import MarkerSet

    one = MarkerSet(np.full((1, 2, 3), 0.01), ("A", "B"), 60.0)
    with pytest.raises(InputError, match="field 'frames'"):
        write_markers(tmp_path / "one.trc", one)
    assert not (tmp_path / "one.trc").exists()
    (tmp_path / "one.trc").write_text(
        "PathFileType\t4\t(X/Y/Z)\tone.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n"
        "60\t60\t1\t1\tmm\nFrame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n\n1\t0.0\t1\t2\t3\n")
    refused(monkeypatch, capsys, tmp_path, "markers", "info", "{t}/one.trc",
            words=("{t}/one.trc", "field 'frames'", "at least two"))


# ---- sizes as typed ----------------------------------------------------------------------------
def test_the_design_manifest_writes_the_size_as_typed():
    from facemech.workflows.pictures import render_options
    from facemech.workflows.stimuli import _render_settings

    assert _render_settings(render_options(size="640x480"), True)["size"] == "640x480"
    assert _render_settings(render_options(size="640x480"), False) == {"video": False}


# ---- plausibility ------------------------------------------------------------------------------
def test_a_rest_interval_must_lie_inside_the_recording(monkeypatch, capsys, tmp_path):
    marker_csv(tmp_path / "m.csv", [["0", "0", "0", "30", "2", "3"]] * 31)  # 0.5 s
    refused(monkeypatch, capsys, tmp_path, "subject", "default", "--markers", "{t}/m.csv",
            "-o", "{t}/S", "--rest", "0.4,1.0",
            words=("{t}/m.csv", "field 'rest'", "0.4,1 s", "0 to 0.5 s"))


def test_unlabelled_trajectories_are_left_out_unless_named():
    from facemech.markerset import MarkerSet
    from facemech.workflows.subject import labelled

    ms = MarkerSet(np.zeros((2, 4, 3)), ("LLIP", "*12", "Unlabeled 3", "*7"), 60.0)
    kept, note = labelled(ms)
    assert kept.names == ("LLIP",)
    assert note == ["unlabelled trajectories left out: *12, Unlabeled 3, *7 (name one with "
                    "--head, --frame or --chin-marker to use it)"]
    kept, note = labelled(ms, named=("*7",))
    assert kept.names == ("LLIP", "*7") and "*7," not in note[0]
    assert labelled(ms.select(["LLIP"]))[1] == []
    with pytest.raises(InputError, match="every trajectory is unlabelled"):
        labelled(ms.select(["*12"]))


def test_a_fifo_is_named_as_such_not_as_missing(monkeypatch, capsys, tmp_path):
    os = pytest.importorskip("os")
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    os.mkfifo(tmp_path / "m.csv")
    refused(monkeypatch, capsys, tmp_path, "markers", "info", "{t}/m.csv",
            words=("{t}/m.csv", "a FIFO (named pipe), not a file"))
    from facemech.speech.wav import check_audio

    with pytest.raises(InputError, match="FIFO"):
        check_audio(tmp_path / "m.csv")


def test_speak_checks_a_recorded_voice_first(monkeypatch, capsys, tmp_path):
    (tmp_path / "v.wav").write_bytes(b"RIFF\x00\x00\x00\x00WAVE")
    (tmp_path / "v.TextGrid").write_text("not read")
    refused(monkeypatch, capsys, tmp_path, "speak", "--audio", "{t}/v.wav", "--textgrid",
            "{t}/v.TextGrid", "-o", "{t}/out", words=("{t}/v.wav", "field 'audio'"))


def test_a_ply_face_naming_a_missing_vertex_is_refused(tmp_path):
    """Found by the fuzz tests: a face index past the vertex list reached trimesh's merge as an
    IndexError; it is now facemech's own error naming the file and the field."""
    from facemech.geometry.surface_io import read_surface

    path = tmp_path / "bad.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\n"
                    "property list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n3 0 1 6\n")
    with pytest.raises(InputError) as info:
        read_surface(path)
    assert info.value.field == "faces" and "vertex 6" in str(info.value)
    assert str(path) in str(info.value)
