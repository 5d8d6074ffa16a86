"""Readers that survive fuzzing (issue 31): random bytes, truncations and mutations of a valid
file end in facemech's own :class:`~facemech.errors.InputError` or a valid result: never
another exception, a hang or a child process left running.

Profiles (``FACEMECH_FUZZ=ci|deep``): ``ci`` (the default) runs a fixed, derandomised 200
examples per reader; ``deep`` runs 5000 random ones per reader (``FACEMECH_FUZZ=deep pytest
tests/io/test_fuzz_readers.py``). C3D is read in a child process (crash- and hang-proof), so its
header check runs 200 examples in-process and whole reads only 20.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from facemech.errors import InputError  # noqa: E402

_COMMON = dict(deadline=10_000, database=None, print_blob=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.function_scoped_fixture])
settings.register_profile("facemech-ci", max_examples=200, derandomize=True, **_COMMON)
settings.register_profile("facemech-deep", max_examples=5000, **_COMMON)
PROFILE = settings.get_profile("facemech-" + os.environ.get("FACEMECH_FUZZ", "ci"))

# tokens a hostile or broken file is made of: numbers out of range, separators, encodings
TOKENS = [b"nan", b"NaN", b"inf", b"-inf", b"-1", b"0", b"1e308", b"1e999", b"-0", b"", b",",
          b"\t", b"\n", b"\r\n", b"\x00", b"\xff\xfe", b"\xef\xbb\xbf", b'"', b"[", b"]", b"{",
          b"}", b"=", b":", b"#", b"9" * 40, b"0.000000001", b"-99999", b"x", b"\xe9"]


def fuzzed(seed: bytes):
    """Random bytes, a truncation of ``seed``, or ``seed`` with a few bytes or tokens set,
    inserted or deleted."""
    n = max(len(seed), 1)
    op = st.tuples(st.sampled_from(["set", "insert", "delete", "token"]), st.integers(0, n - 1),
                   st.binary(min_size=1, max_size=3), st.sampled_from(TOKENS),
                   st.integers(0, 6))

    def mutate(ops):
        b = bytearray(seed)
        for kind, i, chunk, token, k in ops:
            i = min(i, len(b))
            if kind == "set":
                b[i:i + len(chunk)] = chunk
            elif kind == "insert":
                b[i:i] = chunk
            elif kind == "delete":
                del b[i:i + k + 1]
            else:
                b[i:i + k] = token
        return bytes(b)

    return st.one_of(st.binary(max_size=2048),
                     st.integers(0, len(seed)).map(lambda k: seed[:k]),
                     st.lists(op, min_size=1, max_size=6).map(mutate))


def survives(read, path: Path, data: bytes):
    """Write ``data`` to ``path`` and read it: a result or an InputError, nothing else."""
    path.write_bytes(data)
    try:
        return read(path)
    except InputError:
        return None


# ---- the valid files ----------------------------------------------------------------------------
def _marker_csv() -> bytes:
    rows = "".join(f"{k / 60:.6f},{k},2,3,30,{2 + k},3\n" for k in range(5))
    return ("# units: mm\ntime,A_x,A_y,A_z,B_x,B_y,B_z\n" + rows).encode()


def _trc(folder: Path) -> bytes:
    from facemech.io.trc import write_trc
    from facemech.markerset import MarkerSet

    pos = np.linspace(0.0, 0.03, 4 * 2 * 3).reshape(4, 2, 3)
    write_trc(folder / "seed.trc", MarkerSet(pos, ("A", "B"), 60.0), units="mm")
    return (folder / "seed.trc").read_bytes()


def _tsv() -> bytes:
    rows = "".join(f"{k}\t{k / 100:.3f}\t{k}\t2\t3\t30\t{2 + k}\t3\n" for k in range(1, 5))
    return ("NO_OF_FRAMES\t4\nNO_OF_MARKERS\t2\nFREQUENCY\t100\nMARKER_NAMES\tA\tB\n"
            "Frame\tTime\tA X\tA Y\tA Z\tB X\tB Y\tB Z\n" + rows).encode()


def _activity() -> bytes:
    return ("time,OOS,DAO\n" + "".join(f"{k / 60:.6f},0.{k},0.1\n" for k in range(6))).encode()


def _emg() -> bytes:
    rows = "".join(f"{k / 1000:.4f},{np.sin(k):.4f},{np.cos(k):.4f}\n" for k in range(40))
    return ("time,OOS,DAO\n" + rows).encode()


def _landmarks() -> bytes:
    from facemech import default_face

    face = default_face()
    rest = face.rest_positions
    rows = "".join(f"{n},{rest[k, 0] * 1e3:.3f},{rest[k, 1] * 1e3:.3f},{rest[k, 2] * 1e3:.3f}\n"
                   for n, k in face.landmarks.items())
    return ("name,x,y,z\n" + rows).encode()


def _ibug_points() -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, 68, endpoint=False)
    return np.column_stack([60 * np.cos(t), 80 * np.sin(t), 10 * np.cos(2 * t)])


def _pts() -> bytes:
    rows = "".join(f"{x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in _ibug_points())
    return ("version: 1\nn_points: 68\n{\n" + rows + "}\n").encode()


def _ljson() -> bytes:
    return json.dumps({"version": 2, "landmarks": {"points": _ibug_points().tolist()}}).encode()


def _grid(n: int = 4, size_mm: float = 150.0):
    """A square sheet of 2 n^2 triangles, ``size_mm`` across (a face's size)."""
    g = np.linspace(0.0, size_mm, n + 1)
    v = np.array([[x, y, 0.1 * x * y / size_mm] for y in g for x in g])
    f = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            f += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return v, np.array(f)


def _obj() -> bytes:
    v, f = _grid()
    return ("".join(f"v {x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in v)
            + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)).encode()


def _ply() -> bytes:
    v, f = _grid()
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(v)}\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {len(f)}\n"
            "property list uchar int vertex_indices\nend_header\n")
    return (head + "".join(f"{x:.3f} {y:.3f} {z:.3f}\n" for x, y, z in v)
            + "".join(f"3 {a} {b} {c}\n" for a, b, c in f)).encode()


def _results(folder: Path) -> bytes:
    import xarray as xr

    pos = np.linspace(0.0, 0.03, 4 * 3 * 3).reshape(4, 3, 3)
    ds = xr.Dataset({"positions": (("time", "node", "axis"), pos),
                     "markers": (("time", "marker", "axis"), pos[:, :2]),
                     "triangles": (("triangle", "corner"), np.array([[0, 1, 2]]))},
                    coords={"time": np.arange(4) / 60.0, "marker": ["A", "B"],
                            "axis": list("xyz")}, attrs={"frame_rate_hz": 60.0})
    ds.to_netcdf(folder / "seed.nc", engine="h5netcdf")
    return (folder / "seed.nc").read_bytes()


def _wav(folder: Path) -> bytes:
    from facemech.speech.wav import write_wav

    write_wav(folder / "seed.wav", np.sin(np.arange(400) / 3.0), 8000)
    return (folder / "seed.wav").read_bytes()


def _textgrid() -> bytes:
    return b"""File type = "ooTextFile"
Object class = "TextGrid"

0
0.6
<exists>
2
"IntervalTier"
"words"
0
0.6
2
0
0.3
"ba"
0.3
0.6
"da"
"IntervalTier"
"phones"
0
0.6
4
0
0.1
"b"
0.1
0.3
"a"
0.3
0.4
"d"
0.4
0.6
"a"
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder with the files the design tables and manifests name."""
    d = tmp_path_factory.mktemp("fuzz")
    _results(d)
    _wav(d)
    (d / "a.csv").write_bytes(_activity())
    return d


def _read_markers(path):
    from facemech.io.markers import read_markers

    return read_markers(path)


# ---- the readers --------------------------------------------------------------------------------
def _case(name, suffix, seed, read):
    return pytest.param(suffix, seed, read, id=name)


def _activity_read(path):
    from facemech.io.activity import read_activity

    return read_activity(path)


def _emg_read(path):
    from facemech.io.emg import read_emg

    return read_emg(path)


def _landmark_read(path):
    from facemech.geometry.surface_io import read_landmarks

    return read_landmarks(path)


def _ibug_read(path):
    from facemech.geometry.ibug import read_ibug68

    return read_ibug68(path)


def _surface_read(path):
    from facemech.geometry.surface_io import read_surface

    return read_surface(path)


def _results_read(path):
    from facemech.io.results import read_results, results_markers

    ds = read_results(path)
    return results_markers(ds, source=path)


def _design_read(path):
    from facemech.speech.design import check_design

    return check_design(path)


def _manifest_read(path):
    from facemech.workflows.batch_jobs import read_manifest

    return read_manifest(path)


def _textgrid_read(path):
    from facemech.speech.alignment_io import read_textgrid

    return read_textgrid(path)


def _wav_read(path):
    from facemech.speech.wav import read_wav

    return read_wav(path)


DESIGN_CSV = b"id,results,audio,amplitude,av_offset_ms\none,seed.nc,seed.wav,0.5,20\n"
DESIGN_TOML = (b'[defaults]\nresults = "seed.nc"\n[[stimulus]]\nid = "one"\naudio = "seed.wav"\n'
               b'time_scale = 1.5\nfreeze_region = "lips"\n')
MANIFEST_CSV = b"id,job,activity,dt\ns0,simulate,a.csv,0.001\n"
MANIFEST_TOML = b'[[item]]\nid = "s0"\njob = "simulate"\nactivity = "a.csv"\n'

TEXT_READERS = [
    ("marker-csv", ".csv", _marker_csv, _read_markers),
    ("marker-tsv", ".tsv", _tsv, _read_markers),
    ("activity-csv", ".csv", _activity, _activity_read),
    ("emg-csv", ".csv", _emg, _emg_read),
    ("landmark-csv", ".csv", _landmarks, _landmark_read),
    ("ibug-pts", ".pts", _pts, _ibug_read),
    ("ibug-ljson", ".ljson", _ljson, _ibug_read),
    ("obj", ".obj", _obj, _surface_read),
    ("ply", ".ply", _ply, _surface_read),
    ("design-csv", ".csv", lambda: DESIGN_CSV, _design_read),
    ("design-toml", ".toml", lambda: DESIGN_TOML, _design_read),
    ("manifest-csv", ".csv", lambda: MANIFEST_CSV, _manifest_read),
    ("manifest-toml", ".toml", lambda: MANIFEST_TOML, _manifest_read),
    ("textgrid", ".TextGrid", _textgrid, _textgrid_read),
]
FILE_READERS = [
    ("marker-trc", ".trc", _trc, _read_markers),
    ("results-nc", ".nc", _results, _results_read),
    ("wav", ".wav", _wav, _wav_read),
]


def _check(name, suffix, make, read, folder):
    seed = make(folder) if make in (_trc, _results, _wav) else make()
    target = folder / f"fuzzed-{name}{suffix}"
    assert survives(read, target, seed) is not None, f"the valid {name} file is refused"

    @PROFILE
    @given(data=fuzzed(seed))
    def run(data):
        survives(read, target, data)

    run()


#: readers whose fuzzing takes tens of seconds (a NetCDF file written per example): marked slow
SLOW_READERS = {"results-nc"}


@pytest.mark.parametrize("name, suffix, make, read", [
    pytest.param(*r, id=r[0], marks=pytest.mark.slow if r[0] in SLOW_READERS else ())
    for r in TEXT_READERS + FILE_READERS])
def test_a_reader_survives_fuzzing(folder, name, suffix, make, read):
    _check(name, suffix, make, read, folder)


def test_the_c3d_header_check_survives_fuzzing(folder):
    pytest.importorskip("ezc3d")
    from facemech.io.c3d import check_header, write_c3d_points
    from facemech.markerset import MarkerSet

    pos = np.linspace(0.0, 0.03, 4 * 2 * 3).reshape(4, 2, 3)
    write_c3d_points(folder / "seed.c3d", MarkerSet(pos, ("A", "B"), 60.0), units="mm")
    seed = (folder / "seed.c3d").read_bytes()
    target = folder / "fuzzed.c3d"

    @PROFILE
    @given(data=fuzzed(seed))
    def run(data):
        survives(lambda p: check_header(p) or True, target, data)

    run()


def test_whole_c3d_reads_survive_fuzzing(folder):
    """Through the child process: each read is a new interpreter, so fewer examples."""
    pytest.importorskip("ezc3d")
    import psutil  # noqa: F401  (only to skip where absent)

    from facemech.io.c3d import write_c3d_points
    from facemech.markerset import MarkerSet

    pos = np.linspace(0.0, 0.03, 4 * 2 * 3).reshape(4, 2, 3)
    write_c3d_points(folder / "seed2.c3d", MarkerSet(pos, ("A", "B"), 60.0), units="mm")
    seed = (folder / "seed2.c3d").read_bytes()
    target = folder / "fuzzed2.c3d"
    assert survives(_read_markers, target, seed) is not None
    children = {p.pid for p in psutil.Process().children(recursive=True)}

    @settings(PROFILE, max_examples=20 if PROFILE.max_examples <= 200 else 200)
    @given(data=fuzzed(seed))
    def run(data):
        survives(_read_markers, target, data)

    run()
    left = {p.pid for p in psutil.Process().children(recursive=True)} - children
    assert not left, f"child processes left running: {left}"
