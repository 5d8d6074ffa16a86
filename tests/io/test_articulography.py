"""Articulography in (issue 27 part 4): MOCHA-TIMIT and mngu0 EMA (EST binary and ascii, both
byte orders; MOCHA's plain layout) and X-ray microbeam .txy, read back with known positions,
units, axes, rates, missing samples and roles; bad files refused through the CLI with one line
naming the file and the field, exit 2, the folder untouched."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from conftest import run_cli
from facemech.errors import InputError
from facemech.io.articulography import (
    MOCHA_CHANNELS,
    ROLES,
    read_ema,
    read_est_track,
    read_xrmb_txy,
    sensor_role,
)
from facemech.io.markers import read_markers

# ---- writers of small files (layouts as in the module docstring) ----------------------------

#: a midsagittal speaker in the model's axes, mm (y up, z forward): lips in front, tongue behind
MODEL_MM = {"ui": (0.0, 0.0), "li": (-12.0, -1.0), "ul": (8.0, 8.0), "ll": (-15.0, 9.0),
            "tt": (-5.0, -10.0), "tb": (0.0, -25.0), "td": (5.0, -45.0), "v": (10.0, -60.0),
            "bn": (40.0, 10.0)}
N = 40
RATE = 500.0


def _lower_lip_y(n=N, rate=RATE):
    """mm, the lower lip's vertical path: 4 mm, 5 Hz."""
    return -15.0 + 4.0 * np.sin(2 * np.pi * 5.0 * np.arange(n) / rate)


def _mocha_values(forward_sign=-1.0, n=N):
    """(frames, 20) MOCHA channels in 0.01 mm; file x = forward_sign * model z (MOCHA: -1)."""
    vals = np.zeros((n, len(MOCHA_CHANNELS)))
    for coil, (y, z) in MODEL_MM.items():
        vals[:, MOCHA_CHANNELS.index(f"{coil}_x")] = forward_sign * z * 100
        vals[:, MOCHA_CHANNELS.index(f"{coil}_y")] = y * 100
    vals[:, MOCHA_CHANNELS.index("ll_y")] = _lower_lip_y(n) * 100
    vals[:, [13, 18]] = 0.0  # the unused **** channels
    return vals


def write_est(path, names, time, values, *, binary=True, order="01", present=None,
              breaks=True, extra="", cut=0):
    """An EST track as the Edinburgh Speech Tools write it (``cut``: bytes dropped at the end)."""
    n, c = values.shape
    head = (f"EST_File Track\nDataType {'binary' if binary else 'ascii'}\nNumFrames {n}\n"
            + (f"ByteOrder {order}\n" if binary else "")
            + f"NumChannels {c}\nEqualSpace 1\n" + ("BreaksPresent true\n" if breaks else "")
            + "CommentChar ;\n\n" + extra
            + "".join(f"Channel_{k} {nm}\n" for k, nm in enumerate(names)) + "EST_Header_End\n")
    flags = np.ones(n) if present is None else np.asarray(present, float)
    cols = [time, flags, values.T] if breaks else [time, values.T]
    table = np.vstack([np.atleast_2d(a) for a in cols]).T
    if binary:
        body = table.astype(("<" if order == "01" else ">") + "f4").tobytes()
    else:
        body = "".join("\t".join(f"{v:.9g}" for v in row) + "\n" for row in table).encode()
    path.write_bytes(head.encode() + body[:len(body) - cut])
    return path


def write_mocha(path, **kw):
    values = kw.pop("values", _mocha_values())
    t = np.arange(len(values)) / RATE
    names = [nm if nm != "v_x" and nm != "v_y" else nm + " " for nm in MOCHA_CHANNELS]
    return write_est(path, names, t, values, **kw)


def _check_mocha(ms, tol=1e-9):
    """The MOCHA speaker comes back in metres, model axes, x = 0, with its roles."""
    assert ms.names == ("ui", "li", "ul", "ll", "tt", "tb", "td", "v", "bn")
    assert ms.rate == pytest.approx(RATE, rel=1e-6)
    assert ms.source_units == "mm"
    assert np.all(ms.positions[..., 0] == 0.0)
    for coil, (y, z) in MODEL_MM.items():
        p = ms.marker(coil)
        assert p[:, 2] == pytest.approx(np.full(N, z * 1e-3), abs=tol), coil
        if coil != "ll":
            assert p[:, 1] == pytest.approx(np.full(N, y * 1e-3), abs=tol), coil
    assert ms.marker("ll")[:, 1] == pytest.approx(_lower_lip_y() * 1e-3, abs=tol)
    assert ms.meta["midsagittal"] is True
    assert ms.meta["roles"] == {"ui": "upper_incisor", "li": "lower_incisor", "ul": "upper_lip",
                                "ll": "lower_lip", "tt": "tongue", "tb": "tongue",
                                "td": "tongue", "v": "velum", "bn": "reference"}
    assert set(ms.meta["roles"].values()) <= set(ROLES)
    assert "model z (forward) = -file x" in ms.meta["axes"]
    assert "model y (up) = +file y" in ms.meta["axes"]


# ---- MOCHA-TIMIT ----------------------------------------------------------------------------
@pytest.mark.parametrize("order", ["01", "10"])
def test_mocha_binary_est_in_both_byte_orders(tmp_path, order):
    ms = read_markers(write_mocha(tmp_path / "fsew0_001.ema", order=order))
    _check_mocha(ms, tol=1e-9)  # 0.01-mm integers and float32 sines: exact to 1e-6 mm
    assert ms.meta["format"] == "est-mocha" and ms.meta["byte_order"] == order
    assert ms.meta["ignored_channels"] == ["****", "****"]
    assert "break" in ms.meta["missing_value"]
    assert any("ll -> the lower lip" in s for s in ms.meta["notes"])


def test_byte_order_matters(tmp_path):
    """The same bytes read with the other byte order are not the same numbers."""
    path = write_mocha(tmp_path / "a.ema", order="01")
    raw = path.read_bytes().replace(b"ByteOrder 01", b"ByteOrder 10")
    (tmp_path / "b.ema").write_bytes(raw)
    try:
        swapped = read_markers(tmp_path / "b.ema")
    except InputError:  # times that are not increasing, or a span no face has
        return
    assert not np.allclose(swapped.positions, read_markers(path).positions, equal_nan=True)


def test_mocha_ascii_est_and_est_suffix(tmp_path):
    ms = read_markers(write_mocha(tmp_path / "u.est", binary=False))
    _check_mocha(ms, tol=1e-9)
    assert ms.meta["data_type"] == "ascii"


def test_est_content_is_recognised_whatever_the_suffix(tmp_path):
    ms = read_markers(write_mocha(tmp_path / "u.dat"))
    assert ms.meta["format"] == "est-mocha"


def test_breaks_and_nan_are_missing_samples(tmp_path):
    values = _mocha_values()
    values[5, MOCHA_CHANNELS.index("ul_y")] = np.nan
    present = np.ones(N)
    present[[10, 11]] = 0.0
    ms = read_markers(write_mocha(tmp_path / "g.ema", values=values, present=present))
    assert not ms.valid[[10, 11]].any()  # a break frame: every sensor missing
    assert not ms.valid[5, ms.index("ul")] and ms.valid[5, ms.index("ll")]
    assert int((~ms.valid).sum()) == 2 * 9 + 1


def test_mocha_file_with_front_back_reversed_is_turned_by_anatomy(tmp_path):
    """A file whose x points forward (not MOCHA's convention): the lips still come out in
    front, and the notes say the axis was decided by the sensors."""
    ms = read_markers(write_mocha(tmp_path / "r.ema", values=_mocha_values(forward_sign=+1.0)))
    assert ms.marker("ul")[0, 2] == pytest.approx(8e-3)
    assert ms.marker("td")[0, 2] == pytest.approx(-45e-3)
    assert "model z (forward) = +file x" in ms.meta["axes"]
    assert any("opposite" in s for s in ms.meta["notes"])


@pytest.mark.parametrize("with_time", [True, False])
def test_mocha_plain_text_layout(tmp_path, with_time):
    vals = _mocha_values()
    table = np.column_stack([np.arange(N) / RATE, np.ones(N), vals]) if with_time else vals
    path = tmp_path / "fsew0_001.ema"
    path.write_text("".join(" ".join(f"{v:.6f}" for v in row) + "\n" for row in table))
    ms = read_markers(path)
    _check_mocha(ms, tol=1e-8)
    assert ms.meta["format"] == "mocha-text"


def test_plain_text_rate_must_be_positive(tmp_path):
    path = tmp_path / "p.ema"
    path.write_text("".join(" ".join("1" for _ in range(20)) + "\n" for _ in range(3)))
    assert read_ema(path, rate=250.0).rate == 250.0
    with pytest.raises(InputError) as err:
        read_ema(path, rate=0.0)
    assert err.value.field == "rate" and str(path) in str(err.value)


# ---- mngu0 (3-D) ----------------------------------------------------------------------------
MNGU0_MM = {"T1": (-6.0, -12.0, 0.5), "T2": (2.0, -30.0, 0.0), "T3": (6.0, -45.0, -0.4),
            "jaw": (-14.0, -2.0, 0.3), "upperlip": (9.0, 9.0, 0.0),
            "lowerlip": (-14.0, 10.0, -0.2), "ref": (35.0, 12.0, 1.0)}


@pytest.mark.parametrize("py_forward", [False, True])
def test_mngu0_est_three_coordinates_in_mm(tmp_path, py_forward):
    """Coils T1..ref with px py pz (and an angle channel that is left out); py backward
    (or forward: the lips decide) and pz up; the lateral axis keeps the frame right-handed."""
    names, cols = [], []
    n = 30
    for coil, (y, z, x) in MNGU0_MM.items():
        # a right-handed file frame: py = s z, pz = y, px = py x pz direction -> px = -s x
        s = 1.0 if py_forward else -1.0
        for axis, v in (("px", -s * x), ("py", s * z), ("pz", y)):
            names.append(f"{coil}_{axis}")
            cols.append(np.full(n, v))
        names.append(f"{coil}_phi")
        cols.append(np.full(n, 90.0))
    values = np.column_stack(cols)
    values[7, names.index("T2_py")] = np.nan  # mngu0 marks a lost coil sample with NaN
    path = write_est(tmp_path / "mngu0_s1_0001.ema", names, np.arange(n) * 0.005, values,
                     order="10")
    ms = read_markers(path)
    assert ms.meta["format"] == "est-mngu0" and ms.meta["midsagittal"] is False
    assert ms.rate == pytest.approx(200.0, rel=1e-6) and ms.source_units == "mm"
    assert ms.meta["roles"] == {"T1": "tongue", "T2": "tongue", "T3": "tongue",
                                "jaw": "lower_incisor", "upperlip": "upper_lip",
                                "lowerlip": "lower_lip", "ref": "reference"}
    for coil, (y, z, x) in MNGU0_MM.items():
        good = np.arange(n) != 7 if coil == "T2" else slice(None)
        assert ms.marker(coil)[good] == pytest.approx(
            np.tile(np.array([x, y, z]) * 1e-3, (n, 1))[good], abs=1e-9), coil
    assert not ms.valid[7, ms.index("T2")]
    assert len(ms.meta["ignored_channels"]) == len(MNGU0_MM)


# ---- X-ray microbeam --------------------------------------------------------------------------
#: pellets in the XRMB frame, micrometres: x forward, y up, origin at the upper incisors
XRMB_UM = {"UL": (8000, 10000), "LL": (9000, -16000), "T1": (-12000, -8000),
           "T2": (-25000, -2000), "T3": (-38000, 2000), "T4": (-50000, 3000),
           "MNI": (-1000, -13000), "MNM": (-40000, -20000)}
XRMB_STEP_S = 1.0 / 145.6


def write_txy(path, *, n=20, time_scale=1e3, header=False, lost=(), rows=None):
    """A .txy file: time then x y of the eight pellets; ``lost``: (frame, pellet) as 1000000."""
    lines = ["time " + " ".join(f"{p}_x {p}_y" for p in XRMB_UM)] if header else []
    for k in range(n):
        cells = [f"{k * XRMB_STEP_S * time_scale:.10g}"]
        for p, (x, y) in XRMB_UM.items():
            yy = y + (500 * k if p == "LL" else 0)
            cells += ["1000000", "1000000"] if (k, p) in lost else [str(x), str(yy)]
        lines.append("\t".join(cells))
    path.write_text("\n".join(rows if rows is not None else lines) + "\n")
    return path


@pytest.mark.parametrize("time_scale, unit", [(1.0, "s"), (1e3, "ms"), (1e6, "us")])
def test_xrmb_txy_units_axes_rate_and_missing(tmp_path, time_scale, unit):
    path = write_txy(tmp_path / "tp011.txy", time_scale=time_scale, lost=[(3, "T2"), (4, "MNM")])
    ms = read_markers(path)
    assert ms.names == tuple(XRMB_UM)
    assert ms.rate == pytest.approx(145.6, rel=1e-6)
    assert ms.meta["time_units"] == unit and ms.source_units == "um"
    assert ms.meta["format"] == "xrmb-txy" and ms.meta["missing_value"] == "1000000"
    assert ms.meta["midsagittal"] is True
    assert ms.meta["roles"]["MNI"] == "lower_incisor" and ms.meta["roles"]["MNM"] == "molar"
    assert ms.meta["roles"]["UL"] == "upper_lip" and ms.meta["roles"]["T4"] == "tongue"
    for p, (x, y) in XRMB_UM.items():
        got = ms.marker(p)
        ok = ms.valid[:, ms.index(p)]
        assert np.all(got[ok, 0] == 0.0)
        assert got[ok, 2] == pytest.approx(np.full(ok.sum(), x * 1e-6))  # +x forward = +z
        if p != "LL":
            assert got[ok, 1] == pytest.approx(np.full(ok.sum(), y * 1e-6))
    assert ms.marker("LL")[:, 1] == pytest.approx((-16000 + 500 * np.arange(20)) * 1e-6)
    assert not ms.valid[3, ms.index("T2")] and not ms.valid[4, ms.index("MNM")]
    assert int((~ms.valid).sum()) == 2
    assert "model z (forward) = +file x" in ms.meta["axes"]


def test_xrmb_header_line_names_the_pellets(tmp_path):
    ms = read_xrmb_txy(write_txy(tmp_path / "h.txy", header=True))
    assert ms.names == tuple(XRMB_UM)


def test_units_override(tmp_path):
    """A caller's unit replaces the layout's (a .txy exported in mm, say); micrometres read as
    mm span 50 m and are refused, naming the unit."""
    um = write_txy(tmp_path / "um.txy").read_text().splitlines()
    rows = [" ".join([r.split()[0]] + [f"{float(v) / 1000:g}" for v in r.split()[1:]])
            for r in um]
    ms = read_markers(write_txy(tmp_path / "mm.txy", rows=rows), units="mm")
    assert ms.source_units == "mm"
    assert ms.marker("T4")[0, 2] == pytest.approx(-50e-3)
    with pytest.raises(InputError) as err:
        read_markers(tmp_path / "um.txy", units="mm")
    assert err.value.field == "units" and "um" in str(err.value)


def test_sensor_roles():
    assert sensor_role("UL") == "upper_lip" and sensor_role("upperlip") == "upper_lip"
    assert sensor_role("ll") == "lower_lip" and sensor_role("lowerlip") == "lower_lip"
    for n in ("li", "jaw", "MNI", "MI", "LJ"):
        assert sensor_role(n) == "lower_incisor", n
    for n in ("MNM", "MM", "molar"):
        assert sensor_role(n) == "molar", n
    for n in ("T1", "t4", "tt", "TB", "td", "tongue_tip"):
        assert sensor_role(n) == "tongue", n
    assert sensor_role("ui") == "upper_incisor" and sensor_role("v") == "velum"
    assert sensor_role("bn") == "reference" and sensor_role("ref") == "reference"
    assert sensor_role("mystery") == "other"


def test_est_track_as_stored(tmp_path):
    t = np.arange(4) * 0.01
    path = write_est(tmp_path / "t.est", ["a_x", "a_y"], t, np.arange(8.0).reshape(4, 2),
                     order="10", present=[1, 1, 0, 1])
    track = read_est_track(path)
    assert track.names == ("a_x", "a_y") and track.binary
    assert track.time == pytest.approx(t)
    assert track.present.tolist() == [True, True, False, True]
    assert track.values[:, 1].tolist() == [1.0, 3.0, 5.0, 7.0]


# ---- through the CLI ------------------------------------------------------------------------
def _snapshot(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("name", ["fsew0_001.ema", "mngu.est", "tp011.txy"])
def test_markers_info_and_convert(monkeypatch, capsys, tmp_path, name):
    path = tmp_path / name
    if name.endswith(".txy"):
        write_txy(path)
    elif name.startswith("mngu"):
        names = [f"{c}_{a}" for c in ("upperlip", "lowerlip", "T1") for a in ("px", "py", "pz")]
        write_est(path, names, np.arange(5) * 0.005,
                  np.tile([0, -9, 9, 0, -10, -14, 0, 12, -6], (5, 1)).astype(float))
    else:
        write_mocha(path)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info", path)
    assert code == 0, err
    assert str(path) in out and " Hz" in out
    code, out, err = run_cli(monkeypatch, capsys, "markers", "convert", path, tmp_path / "o.csv")
    assert code == 0, err
    src, back = read_markers(path), read_markers(tmp_path / "o.csv")
    assert back.names == src.names
    assert np.allclose(back.positions, src.positions, atol=1e-9, equal_nan=True)


def _mocha_bytes(tmp_path, **kw):
    return write_mocha(tmp_path / "tmp.bin", **kw).read_bytes()


def _bad_cases(tmp_path):
    """name -> (file name, content, field)."""
    mocha = _mocha_bytes(tmp_path)
    good_txy = write_txy(tmp_path / "tmp.txt").read_text().splitlines()
    t_back = _mocha_values()
    cases = {
        "txy wrong column count": ("a.txy", "\n".join(good_txy[:3] + [good_txy[3] + "\t7"]),
                                   "columns"),
        "txy only missing codes": ("b.txy", "\n".join(
            f"{k * 6.868:.3f} " + " ".join(["1000000"] * 16) for k in range(5)), "data"),
        "txy time going back": ("c.txy", "\n".join([good_txy[0], good_txy[2], good_txy[1]]
                                                   + good_txy[3:]), "time"),
        "txy rate of 0": ("d.txy", "\n".join("0.0 " + ln.split("\t", 1)[1]
                                             for ln in good_txy), "time"),
        "est truncated binary body": ("e.ema", mocha[:-7], "NumFrames"),
        "est body too long": ("f.ema", mocha + b"\0\0\0\0", "NumFrames"),
        "est NumChannels not a number": ("g.ema", mocha.replace(b"NumChannels 20",
                                                                b"NumChannels 2O"),
                                         "NumChannels"),
        "est no header end": ("h.ema", mocha.replace(b"EST_Header_End", b"EST_Header_Edn"),
                              "EST_Header_End"),
        "est bad byte order": ("i.ema", mocha.replace(b"ByteOrder 01", b"ByteOrder 42"),
                               "ByteOrder"),
        "est bad data type": ("j.ema", mocha.replace(b"DataType binary", b"DataType floaty"),
                              "DataType"),
        "est not a track": ("k.ema", mocha.replace(b"EST_File Track", b"EST_File Label"),
                            "EST_File"),
        "est only breaks": ("l.ema", _mocha_bytes(tmp_path, present=np.zeros(N)), "data"),
        "est time not increasing": ("m.ema", write_est(
            tmp_path / "tmp2.bin", MOCHA_CHANNELS, np.r_[0.0, 0.004, 0.002,
                                                         0.006 + np.arange(N - 3) * 0.002],
            t_back).read_bytes(), "time"),
        "est rate of 0": ("n.ema", write_est(tmp_path / "tmp3.bin", MOCHA_CHANNELS,
                                             np.zeros(N), t_back).read_bytes(), "time"),
        "est ascii row short": ("o.ema", _ascii_short(tmp_path), "columns"),
        "mocha plain wrong column count": ("p.ema", "1 2 3 4 5\n1 2 3 4 5\n", "columns"),
        "est coil without its y": ("q.ema", mocha.replace(b"Channel_7 ul_y", b"Channel_7 ul_q"),
                                   "ul_x"),
        "est NumFrames 0": ("r.ema", mocha.replace(b"NumFrames 40", b"NumFrames 0"),
                            "NumFrames"),
    }
    for p in tmp_path.glob("tmp*"):
        p.unlink()
    return cases


def _ascii_short(tmp_path):
    text = write_mocha(tmp_path / "tmp4.bin", binary=False).read_text().splitlines()
    text[-2] = text[-2].rsplit("\t", 1)[0]
    return "\n".join(text) + "\n"


BAD = ["txy wrong column count", "txy only missing codes", "txy time going back",
       "txy rate of 0", "est truncated binary body", "est body too long",
       "est NumChannels not a number", "est no header end", "est bad byte order",
       "est bad data type", "est not a track", "est only breaks", "est time not increasing",
       "est rate of 0", "est ascii row short", "mocha plain wrong column count",
       "est coil without its y", "est NumFrames 0"]


@pytest.mark.parametrize("case", BAD)
@pytest.mark.parametrize("command", ["info", "convert"])
def test_bad_files_are_refused_in_one_line(monkeypatch, capsys, tmp_path, case, command):
    name, content, field = _bad_cases(tmp_path)[case]
    path = tmp_path / name
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    before = _snapshot(tmp_path)
    args = ("markers", "info", path) if command == "info" else \
        ("markers", "convert", path, tmp_path / "out.csv")
    code, out, err = run_cli(monkeypatch, capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2, (case, err)
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: {path}"), lines[0]
    assert f"field '{field}'" in lines[0], (case, lines[0])
    assert _snapshot(tmp_path) == before, "the folder changed"


def test_rate_of_zero_is_named(monkeypatch, capsys, tmp_path):
    name, content, _ = _bad_cases(tmp_path)["txy rate of 0"]
    (tmp_path / name).write_text(content)
    code, _, err = run_cli(monkeypatch, capsys, "markers", "info", tmp_path / name)
    assert code == 2 and "0 Hz" in err


def test_invert_refuses_a_bad_txy_before_any_work(monkeypatch, capsys, tmp_path):
    name, content, _ = _bad_cases(tmp_path)["txy only missing codes"]
    (tmp_path / name).write_text(content)
    before = _snapshot(tmp_path)
    code, _, err = run_cli(monkeypatch, capsys, "invert", "--markers", tmp_path / name,
                           "-o", tmp_path / "r.nc")
    errors = [ln for ln in err.splitlines() if ln.startswith("facemech: error:")]
    assert code == 2 and len(errors) == 1 and "Traceback" not in err, err
    assert "field 'data'" in errors[0] and str(tmp_path / name) in errors[0]
    assert _snapshot(tmp_path) == before


@pytest.mark.parametrize("name", ["junk.ema", "junk.txy"])
def test_binary_junk_is_refused(monkeypatch, capsys, tmp_path, name):
    (tmp_path / name).write_bytes(bytes(range(256)) * 8)
    code, _, err = run_cli(monkeypatch, capsys, "markers", "info", tmp_path / name)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "binary data where a text" in err and str(tmp_path / name) in err


def test_invert_leaves_out_a_molar_pellet_lost_throughout(monkeypatch, capsys, tmp_path):
    """X-ray microbeam often loses the molar pellet for a whole recording: the inversion then
    drives the jaw from the lower incisor alone, says so in a note, and the lower lip riding a
    3-mm jaw drop is fitted within 0.3 mm."""
    n = 80
    drop = 3000 * (1 - np.cos(np.pi * np.arange(n) / (n - 1))) / 2  # micrometres, smooth
    rows = []
    for k in range(n):
        cells = [f"{k * XRMB_STEP_S * 1e3:.10g}"]
        for p, (x, y) in XRMB_UM.items():
            moves = p in ("LL", "MNI")
            cells += (["1000000", "1000000"] if p == "MNM"
                      else [str(x), f"{y - (drop[k] if moves else 0):.0f}"])
        rows.append("\t".join(cells))
    path = write_txy(tmp_path / "tp.txy", rows=rows)
    out = tmp_path / "inv.nc"
    code, outp, err = run_cli(monkeypatch, capsys, "invert", "--markers", path,
                              "--face", "default-coarse", "-o", out)
    assert code == 0, err
    text = " ".join((outp + err).split())
    assert f"molar pellet MNM left out ({n} of {n} samples missing)" in text, text
    assert "driven by the bone point MNI" in text
    from facemech import read_results

    res = read_results(out)
    assert float(np.nanmax(res["rms_error"].values)) < 0.3e-3
