"""Carstens AG500/AG501 .pos and NDI Wave exports, on files written to their specifications
(the layouts in facemech.io.ema_formats): positions, units, axes, rates, missing samples and
roles read back; the CLI reads them by extension, with --rate and --sensors; bad files are one
line naming the file and the field."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.io.ema_formats import read_carstens_pos, read_ndi_wave
from facemech.io.markers import read_markers

#: a 3-D speaker in the model's axes, mm (x left, y up, z forward)
SPEAKER_MM = {"ul": (0.0, 9.0, 10.0), "ll": (0.0, -14.0, 11.0), "li": (0.0, -16.0, -1.0),
              "T1": (0.0, -10.0, -12.0), "T2": (0.5, -4.0, -30.0), "ref": (2.0, 30.0, 5.0)}
NAMES = list(SPEAKER_MM)
N = 50


def _model_mm(n=N, rate=250.0):
    """(frames, sensors, 3) mm: the speaker, the lower lip and incisor dropping 3 mm at 5 Hz."""
    pos = np.tile(np.array(list(SPEAKER_MM.values())), (n, 1, 1))
    drop = 3.0 * np.sin(2 * np.pi * 5.0 * np.arange(n) / rate)
    for s in ("ll", "li"):
        pos[:, NAMES.index(s), 1] -= drop
    return pos


def _pos_records(model_mm, *, extra_channels=0):
    """float32 records (frames, channels, 7) in Carstens axes: file x = model x, file y =
    -model z (front-back, backward), file z = model y (up); phi, theta, rms, extra after."""
    n, s, _ = model_mm.shape
    rec = np.zeros((n, s + extra_channels, 7), "<f4")
    rec[:, :s, 0] = model_mm[..., 0]
    rec[:, :s, 1] = -model_mm[..., 2]
    rec[:, :s, 2] = model_mm[..., 1]
    rec[:, :s, 3:5] = [12.0, -40.0]
    rec[:, :s, 5] = 1.5
    return rec


def write_ag501(path, model_mm, *, rate=250, version=3, extra_channels=0, size=None):
    rec = _pos_records(model_mm, extra_channels=extra_channels)
    text = (f"NumberOfChannels={rec.shape[1]}\nSamplingFrequencyHz={rate}\n"
            "Calf_Channel_0=none\n")
    head_len = size or 15 + 9 + len(text) + 30
    head = f"AG50xDATA_V00{version}\n{head_len:08d}\n{text}".encode()
    head = head + b"\x00" * (head_len - len(head))
    path.write_bytes(head + rec.tobytes())
    return path


def write_ag500(path, model_mm):
    rec = _pos_records(model_mm, extra_channels=12 - model_mm.shape[1])
    path.write_bytes(rec.tobytes())
    return path


def write_ndi(path, model_mm, *, rate=100.0, time_scale=1.0, lost=(), suffixes=False):
    """WaveFront's export: time, then per sensor ID, State, Q0 Qx Qy Qz, Tx Ty Tz (mm), with
    NDI axes, right-handed: Tx = model z (forward), Ty = model x (the subject's left), Tz =
    model y (up)."""
    n, s, _ = model_mm.shape
    head = ["Wav Time"]
    for k in range(s):
        sfx = f".{k}" if suffixes and k else ""
        head += [f"Sensor {k + 1} ID", f"Sensor {k + 1} State"] + [
            f"{c}{sfx}" for c in ("Q0", "Qx", "Qy", "Qz", "Tx", "Ty", "Tz")]
    rows = ["\t".join(head)]
    for f in range(n):
        cells = [f"{f / rate * time_scale:.6f}"]
        for k in range(s):
            x, y, z = model_mm[f, k]
            if (f, k) in lost:
                cells += [str(k + 1), "Missing", "", "", "", "", "", "", ""]
            else:
                cells += [str(k + 1), "OK", "1", "0", "0", "0", f"{z:.4f}", f"{x:.4f}",
                          f"{y:.4f}"]
        rows.append("\t".join(cells))
    path.write_text("\n".join(rows) + "\n")
    return path


def _check(ms, model_mm, names=NAMES, tol=1e-6):
    got = {n: ms.marker(n) for n in names}
    for k, n in enumerate(names):
        assert got[n] == pytest.approx(model_mm[:, k] * 1e-3, abs=tol), n
    assert ms.meta["roles"]["ul"] == "upper_lip" and ms.meta["roles"]["li"] == "lower_incisor"
    assert ms.meta["roles"]["T1"] == "tongue" and ms.meta["midsagittal"] is False


def test_ag501_pos_with_header(tmp_path):
    mm = _model_mm()
    ms = read_carstens_pos(write_ag501(tmp_path / "s.pos", mm, extra_channels=2),
                           sensors=NAMES + ["c7", "c8"])
    assert ms.rate == 250.0 and ms.n_frames == N and ms.meta["format"] == "carstens-ag501"
    _check(ms, mm, tol=1e-7)
    assert not ms.valid[:, ms.index("c7")].any()  # an unused channel: zeros, missing
    assert ms.meta["pos_extra"].shape == (N, 8, 4)
    assert ms.meta["pos_extra"][0, 0].tolist() == [12.0, -40.0, 1.5, 0.0]
    assert "[the lips lie" in ms.meta["axes"]  # the sign decided by the anatomy


def test_ag500_pos_without_header_at_200_hz_or_the_rate_given(tmp_path):
    mm = _model_mm(rate=200.0)
    path = write_ag500(tmp_path / "a.pos", mm)
    names = NAMES + [f"x{k}" for k in range(6)]
    ms = read_carstens_pos(path, sensors=names)
    assert ms.rate == 200.0 and ms.meta["format"] == "carstens-ag500" and ms.n_markers == 12
    _check(ms, mm, tol=1e-7)
    assert read_carstens_pos(path, rate=100.0).rate == 100.0
    assert read_carstens_pos(path).names[:2] == ("Ch1", "Ch2")


def test_ndi_wave_export(tmp_path):
    mm = _model_mm(rate=100.0)
    path = write_ndi(tmp_path / "w.tsv", mm, lost=[(5, 1)], suffixes=True)
    ms = read_markers(path, sensors=",".join(NAMES))
    assert ms.meta["format"] == "ndi-wave" and ms.rate == pytest.approx(100.0)
    assert not ms.valid[5, 1] and int((~ms.valid).sum()) == 1
    for k, n in enumerate(NAMES):
        v = ms.valid[:, k]
        assert ms.marker(n)[v] == pytest.approx(mm[v, k] * 1e-3, abs=1e-6), n
    assert read_ndi_wave(write_ndi(tmp_path / "ms.tsv", mm, time_scale=1e3)).meta[
        "time_units"] == "ms"


def test_ndi_wave_empty_ends_are_dropped(tmp_path):
    mm = _model_mm(rate=100.0)
    lost = [(f, k) for f in (0, 1, 2, N - 1) for k in range(len(NAMES))]
    ms = read_markers(write_ndi(tmp_path / "e.tsv", mm, lost=lost), sensors=NAMES)
    assert ms.n_frames == N - 4 and ms.meta["dropped_frames"] == [3, 1]


@pytest.mark.parametrize("kind", ["ag501", "ag500", "ndi"])
def test_the_cli_reads_them_by_extension(monkeypatch, capsys, tmp_path, kind):
    mm = _model_mm()
    if kind == "ag501":
        path = write_ag501(tmp_path / "s.pos", mm)
    elif kind == "ag500":
        path = write_ag500(tmp_path / "s.pos", mm)
    else:
        path = write_ndi(tmp_path / "s.tsv", mm)
    names = NAMES + [f"x{k}" for k in range(6)] if kind == "ag500" else NAMES
    args = ["--sensors", ",".join(names)] + (["--rate", "250"] if kind == "ag500" else [])
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info", path, *args)
    assert code == 0, err
    assert "250 Hz" in out or "100 Hz" in out
    code, out, err = run_cli(monkeypatch, capsys, "markers", "convert", path,
                             tmp_path / "o.csv", *args)
    assert code == 0, err
    back = read_markers(tmp_path / "o.csv")
    assert back.meta["roles"]["ll"] == "lower_lip"
    assert back.marker("ll")[:, 1] == pytest.approx(mm[:, 1, 1] * 1e-3, abs=1e-6)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "trim", path, "-o",
                             tmp_path / "t.csv", "--first", "10", "--last", "19", *args)
    assert code == 0, err
    cut = read_markers(tmp_path / "t.csv")
    rate = 100.0 if kind == "ndi" else 250.0
    assert cut.n_frames == 10 and cut.time[0] == pytest.approx(10 / rate, abs=1e-6)
    assert cut.meta["roles"]["ll"] == "lower_lip"
    assert cut.marker("ll")[:, 1] == pytest.approx(mm[10:20, 1, 1] * 1e-3, abs=1e-6)


def test_a_pos_files_angles_are_cut_with_its_frames(tmp_path):
    from facemech.kinematics.trim import trim

    mm = _model_mm()
    ms = read_carstens_pos(write_ag501(tmp_path / "s.pos", mm), sensors=NAMES)
    extra = ms.meta["pos_extra"].copy()
    extra[:, 0, 0] = np.arange(N)  # a marked angle per frame
    ms = type(ms)(ms.positions, ms.names, ms.rate, time=ms.time,
                  source_units=ms.source_units, meta={**ms.meta, "pos_extra": extra})
    cut = trim(ms, first=5, last=14)
    assert cut.meta["pos_extra"].shape == (10, len(NAMES), 4)
    assert cut.meta["pos_extra"][:, 0, 0].tolist() == list(range(5, 15))


def _bad(tmp_path):
    mm = _model_mm()
    good = write_ag501(tmp_path / "g.pos", mm).read_bytes()
    return {
        "pos truncated": ("t.pos", good[:-10], "data"),
        "pos header length not a number": ("h.pos", good.replace(b"\n000", b"\nxx0", 1),
                                           "header length"),
        "pos no channel count": ("c.pos", good.replace(b"NumberOfChannels", b"NumberOfKanals"),
                                 "NumberOfChannels"),
        "pos rate of 0": ("r.pos", good.replace(b"SamplingFrequencyHz=250",
                                                b"SamplingFrequencyHz=000"),
                          "SamplingFrequencyHz"),
        "pos unit ten times off": ("u.pos", None, "units"),
        "ndi time going back": ("b.tsv", None, "time"),
    }


@pytest.mark.parametrize("case", ["pos truncated", "pos header length not a number",
                                  "pos no channel count", "pos rate of 0",
                                  "pos unit ten times off", "ndi time going back"])
def test_bad_files_are_one_line(monkeypatch, capsys, tmp_path, case):
    name, content, field = _bad(tmp_path)[case]
    path = tmp_path / name
    mm = _model_mm()
    if case == "pos unit ten times off":
        write_ag501(path, mm * 10)
    elif case == "ndi time going back":
        lines = write_ndi(path, mm).read_text().splitlines()
        path.write_text("\n".join([lines[0], lines[2], lines[1]] + lines[3:]) + "\n")
    else:
        path.write_bytes(content)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info", path, "--sensors",
                             ",".join(NAMES))
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: {path}") and f"field '{field}'" in lines[0]


def test_options_a_format_does_not_take_are_refused(tmp_path):
    mm = _model_mm()
    path = write_ag501(tmp_path / "s.pos", mm)
    with pytest.raises(InputError) as err:
        read_markers(path, rate=100.0)
    assert err.value.field == "rate"
    with pytest.raises(InputError) as err:
        read_markers(path, sensors="a,b")
    assert err.value.field == "sensors"
    from test_articulography import write_txy

    with pytest.raises(InputError) as err:
        read_markers(write_txy(tmp_path / "x.txy"), sensors="a")
    assert err.value.field == "sensors"


def _file_xyz(path, kind, sensors):
    """(frames, sensors, 3) of the file's own position columns, read without facemech."""
    if kind == "ndi":
        lines = path.read_text().splitlines()
        head = lines[0].split("\t")
        cols = [[j for j, h in enumerate(head) if h.split(".")[0] == c] for c in ("Tx", "Ty", "Tz")]
        rows = [ln.split("\t") for ln in lines[1:]]
        return np.array([[[float(r[cols[a][k]]) for a in range(3)] for k in range(sensors)]
                         for r in rows])
    data = path.read_bytes()
    head_len = int(data.split(b"\n")[1])
    rec = np.frombuffer(data[head_len:], "<f4").reshape(-1, sensors, 7)
    return rec[..., :3].astype(float)


@pytest.mark.parametrize("kind", ["ag501", "ndi"])
def test_the_file_frame_is_turned_not_mirrored(tmp_path, kind):
    """A right-handed file frame becomes the right-handed model frame: the map from the file's
    own columns to the model's axes is a rotation (determinant +1), never a reflection."""
    mm = _model_mm() + np.random.default_rng(3).normal(0.0, 0.5, (N, len(NAMES), 3))
    path = (write_ndi(tmp_path / "w.tsv", mm) if kind == "ndi"
            else write_ag501(tmp_path / "w.pos", mm))
    ms = read_markers(path, sensors=",".join(NAMES))
    got = np.stack([ms.marker(n) for n in NAMES], axis=1).reshape(-1, 3)
    raw = _file_xyz(path, kind, len(NAMES)).reshape(-1, 3)
    a = np.linalg.lstsq(raw - raw.mean(0), got - got.mean(0), rcond=None)[0]
    turn = a * 1e3  # mm in the file, m in the model
    assert np.allclose(np.abs(turn), np.abs(turn).round(), atol=1e-6)  # axes onto axes
    assert np.linalg.det(a) > 0
