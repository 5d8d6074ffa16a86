"""The articulography readers under fuzzing, and the two bad inputs of issue 58 they met.

Arbitrary bytes, truncations and mutations of valid EST (binary both byte orders, ascii,
mngu0's 3-D layout), MOCHA plain-text, X-ray microbeam ``.txy``, Carstens ``.pos`` (AG501 with
its header, AG500 without) and NDI Wave files give a valid
MarkerSet or facemech's InputError: never another exception, and never a warning (numpy's
RuntimeWarning is turned into an error here). Profiles as in ``test_fuzz_readers.py``.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import given  # noqa: E402

from conftest import run_cli  # noqa: E402
from facemech.errors import InputError  # noqa: E402
from facemech.io.markers import read_markers  # noqa: E402
from test_articulography import (  # noqa: E402
    MOCHA_CHANNELS,
    _mocha_values,
    write_est,
    write_mocha,
    write_txy,
)
from test_fuzz_readers import PROFILE, fuzzed  # noqa: E402

N = 8


def _read_silently(path):
    """read_markers with every warning an error: a result, or an InputError."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return read_markers(path)
        except InputError:
            return None


def _mocha_binary(folder, order):
    return write_mocha(folder / f"seed{order}.ema", values=_mocha_values(n=N), order=order)


def _mocha_ascii(folder):
    return write_mocha(folder / "seeda.ema", values=_mocha_values(n=N), binary=False)


def _mngu0(folder):
    names = [f"{c}_{a}" for c in ("upperlip", "lowerlip", "jaw", "T1") for a in ("px", "py", "pz")]
    vals = np.tile([0, 9, 9, 0, -14, -10, 0, -12, -2, 0, -6, -12], (N, 1)).astype(float)
    return write_est(folder / "seedm.est", names, np.arange(N) * 0.005, vals)


def _mocha_text(folder):
    vals = _mocha_values(n=N)
    rows = [" ".join([f"{k / 500:.6f}", "1"] + [f"{v:.3f}" for v in row])
            for k, row in enumerate(vals)]
    path = folder / "seedt.ema"
    path.write_text("\n".join(rows) + "\n")
    return path


def _txy(folder):
    return write_txy(folder / "seed.txy", n=N, lost=[(2, "T2")])


def _ag501(folder):
    from test_ema_formats import _model_mm, write_ag501

    return write_ag501(folder / "seed.pos", _model_mm(n=N))


def _ag500(folder):
    from test_ema_formats import _model_mm, write_ag500

    return write_ag500(folder / "seed5.pos", _model_mm(n=N))


def _ndi(folder):
    from test_ema_formats import _model_mm, write_ndi

    return write_ndi(folder / "seed.tsv", _model_mm(n=N), lost=[(3, 1)])


SEEDS = {"est-binary-01": lambda f: _mocha_binary(f, "01"),
         "est-binary-10": lambda f: _mocha_binary(f, "10"),
         "est-ascii": _mocha_ascii, "est-mngu0": _mngu0, "mocha-text": _mocha_text,
         "xrmb-txy": _txy, "carstens-ag501": _ag501, "carstens-ag500": _ag500,
         "ndi-wave": _ndi}


@pytest.mark.parametrize("name", list(SEEDS))
def test_an_articulography_reader_survives_fuzzing(tmp_path, name):
    seed_path = SEEDS[name](tmp_path)
    seed = seed_path.read_bytes()
    assert _read_silently(seed_path) is not None, f"the valid {name} file is refused"
    target = tmp_path / f"fuzzed{seed_path.suffix}"

    @PROFILE
    @given(data=fuzzed(seed))
    def run(data):
        target.write_bytes(data)
        _read_silently(target)

    run()


# ---- issue 58's rows ------------------------------------------------------------------------
def _real_like(folder, order="01"):
    """A MOCHA EST binary file of 200 frames of speech-like motion (0.01 mm)."""
    vals = _mocha_values(n=200)
    vals[:, MOCHA_CHANNELS.index("li_y")] += 300 * np.sin(np.arange(200) / 15.0)
    return write_mocha(folder / "s.ema", values=vals, order=order)


@pytest.mark.parametrize("said, data", [("10", "01"), ("01", "10")])
def test_a_byte_order_that_lies_is_refused_without_a_warning(monkeypatch, capsys, tmp_path,
                                                             said, data):
    path = _real_like(tmp_path, order=data)
    raw = path.read_bytes().replace(f"ByteOrder {data}".encode(), f"ByteOrder {said}".encode())
    path.write_bytes(raw)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError) as err:
            read_markers(path)
    assert err.value.field == "ByteOrder"
    code, out, errtext = run_cli(monkeypatch, capsys, "markers", "info", path)
    assert code == 2 and errtext.strip().count("\n") == 0, errtext
    assert "RuntimeWarning" not in errtext and "field 'ByteOrder'" in errtext
    assert path.read_bytes() == raw


@pytest.mark.parametrize("factor, word", [(10.0, "large"), (0.1, "small")])
def test_a_unit_ten_times_off_is_refused(monkeypatch, capsys, tmp_path, factor, word):
    """Inside the readers' 1 mm - 5 m window but not a mouth: the lips 233 mm or 2.3 mm apart."""
    vals = _mocha_values(n=40) * factor
    path = write_mocha(tmp_path / "u.ema", values=vals)
    code, out, err = run_cli(monkeypatch, capsys, "markers", "info", path)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"facemech: error: {path}: field 'units'")
    assert f"10 times too {word}" in lines[0]
    ok = read_markers(write_mocha(tmp_path / "ok.ema", values=_mocha_values(n=40)))
    assert ok.n_frames == 40


def test_a_jaw_that_moves_a_decimetre_is_refused(tmp_path):
    vals = _mocha_values(n=40)
    vals[:, MOCHA_CHANNELS.index("li_y")] += 10000 * np.sin(np.arange(40) / 6.0)  # +-100 mm
    vals[:, MOCHA_CHANNELS.index("ll_y")] += 10000 * np.sin(np.arange(40) / 6.0)
    with pytest.raises(InputError) as err:
        read_markers(write_mocha(tmp_path / "j.ema", values=vals))
    assert err.value.field == "units" and "lower incisor" in str(err.value)
