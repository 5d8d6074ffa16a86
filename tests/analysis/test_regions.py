"""Independent markers and eigenregions (Lucero & Munhall 2008)."""

import json
import sys
import warnings

import numpy as np
import pytest
import scipy.linalg as sla

from facemech import InputError
from facemech.analysis import regions
from facemech.analysis.corpus import COPY_SOURCE, COPY_TARGET, embedded_corpus
from facemech.analysis.lucero2008 import insertion_distances
from facemech.analysis.regions import (
    IndependentMarkers,
    displacement_matrix,
    noise_floor,
    pivoted_qr,
    strong_rrqr,
)


def latent_utterances(n_utt=12, frames=80, n_markers=15, n_sources=4, noise=1e-4, seed=0):
    """Markers driven linearly by a few smooth sources, plus white noise (metres)."""
    rng = np.random.default_rng(seed)
    mix = rng.normal(size=(n_sources, n_markers))  # each marker a mix of the source points
    rest = rng.normal(size=(n_markers, 3)) * 0.03
    out = []
    for _ in range(n_utt):
        t = np.linspace(0, 1, frames)[:, None]
        src = np.stack([2e-3 * np.sin(2 * np.pi * rng.uniform(1, 4, 3) * t + rng.uniform(0, 6, 3))
                        for _ in range(n_sources)], axis=1)  # (frames, sources, 3)
        src -= src[0]
        x = rest + np.einsum("fsc,sm->fmc", src, mix)
        out.append(x + rng.normal(0, noise, x.shape))
    return out


def test_selection_is_scipys_pivot_order_and_residual_is_R22():
    utts = latent_utterances()
    a = displacement_matrix(utts)
    q, r, piv = sla.qr(a, mode="economic", pivoting=True)
    for k in range(1, a.shape[1]):
        m = IndependentMarkers(k=k, eps=1e-9).fit(utts)
        np.testing.assert_array_equal(m.selected_, piv[:k])
        # ||R22||_F is the residual of the least-squares fit of the other columns
        x, *_ = np.linalg.lstsq(a[:, piv[:k]], a[:, piv[k:]], rcond=None)
        resid = np.linalg.norm(a[:, piv[k:]] - a[:, piv[:k]] @ x)
        assert m.residual_ == pytest.approx(resid, rel=1e-9)
        np.testing.assert_allclose(m.coef_, x, atol=1e-8)
        k_view = IndependentMarkers(k=1, eps=1e-9).fit(utts).with_k(k)
        np.testing.assert_array_equal(k_view.selected_, m.selected_)
        np.testing.assert_allclose(k_view.coef_, m.coef_, atol=1e-12)


def test_stacking_rows_are_sample_then_axis():
    u = np.zeros((2, 2, 3))
    u[1] = [[1, 2, 3], [4, 5, 6]]
    a = displacement_matrix([u])
    np.testing.assert_array_equal(a, [[0, 0], [0, 0], [0, 0], [1, 4], [2, 5], [3, 6]])


def test_rank_and_held_out_error():
    utts = latent_utterances(noise=1e-4)
    m = IndependentMarkers().fit(utts[:9])
    assert m.rank_ == 4  # four sources
    assert m.eps_ == pytest.approx(1e-4, rel=0.3)  # the noise floor is found
    errs = [IndependentMarkers(k=k, eps=m.eps_).fit(utts[:9]).errors(utts[9:])["mean_abs_error"]
            for k in (1, 2, 3, 4)]
    assert all(b < a for a, b in zip(errs, errs[1:], strict=False)), errs
    assert errs[-1] < 4e-4  # at the noise level (sqrt(2) 0.1 mm per axis) once k reaches the rank
    pred = IndependentMarkers(k=4, eps=m.eps_).fit(utts[:9])
    d = utts[9] - utts[9][0]
    full = pred.predict(d[:, pred.selected_])
    np.testing.assert_array_equal(full[:, pred.selected_], d[:, pred.selected_])


def test_noise_floor_of_smooth_motion():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 2, 240)[:, None, None]
    clean = 0.01 * np.sin(2 * np.pi * 1.5 * t) * np.ones((1, 5, 3))
    assert noise_floor([clean + rng.normal(0, 0.5e-3, clean.shape)]) == pytest.approx(0.5e-3,
                                                                                     rel=0.1)


def test_strong_rrqr_bounds_the_coefficients():
    # Kahan's matrix: column pivoting keeps the natural order and the coefficients grow
    n, c = 30, 0.285
    s = np.sqrt(1 - c**2)
    kahan = np.diag(s ** np.arange(n)) @ (np.eye(n) - c * np.triu(np.ones((n, n)), 1))
    kahan = kahan @ np.diag(1 - 1e-7 * np.arange(n))  # keep the pivoting order natural
    _, r, piv = sla.qr(kahan, pivoting=True)
    k = n - 1
    x_qrcp = sla.solve_triangular(r[:k, :k], r[:k, k:])
    assert np.abs(x_qrcp).max() > 5
    r2, piv2, swaps = strong_rrqr(kahan, k, f=1.5)
    x = sla.solve_triangular(r2[:k, :k], r2[:k, k:])
    assert swaps >= 1 and np.abs(x).max() <= 1.5 + 1e-9
    assert abs(np.prod(np.diag(r2[:k, :k]))) > abs(np.prod(np.diag(r[:k, :k])))


def test_bad_input():
    utts = latent_utterances(n_utt=3)
    with pytest.raises(InputError, match="utterance 1 has 14 markers"):
        IndependentMarkers().fit([utts[0], utts[1][:, :14]])
    gap = utts[0].copy()
    gap[5, 2, 1] = np.nan
    with pytest.raises(InputError, match=r"gap \(marker 2, frame 5\)"):
        IndependentMarkers().fit([gap])
    with pytest.raises(InputError, match="need at least as many"):
        IndependentMarkers().fit([utts[0][:3]])
    with pytest.warns(UserWarning, match="larger than the epsilon-rank"):
        IndependentMarkers(k=8).fit(utts)
    with pytest.raises(InputError, match="outside"):
        IndependentMarkers(k=99).fit(utts)


@pytest.fixture(scope="module")
def corpus():
    return embedded_corpus(10, 30)


def test_embedded_corpus_and_the_copied_marker_artifact(corpus):
    assert len(corpus.utterances) == 10 and corpus.utterances[0].shape == (30, 57, 3)
    m = IndependentMarkers().fit(corpus.utterances)
    names = corpus.names
    r = m.r_values_
    assert names[m.order_[-1]] in (COPY_SOURCE, COPY_TARGET)
    assert r[-1] <= 0.01 * r[-2]
    assert m.rank_ < 57
    assert m.eps_ == pytest.approx(0.5e-3, rel=0.25)
    assert names[m.order_[0]] in ("lower_lip_C", "lower_lip_R1", "lower_lip_L1", "chin_C")
    clean = IndependentMarkers().fit(embedded_corpus(10, 30, copied_eyelid=False).utterances)
    assert clean.r_values_[-1] > 0.3e-3  # without the copy no column is redundant


def _old_pivoted_qr(a, *, pivoting=True, overwrite_a=False):
    """The factorisation before the one-thread economical path: scipy's qr(mode="r") of the
    row-major matrix, the full (rows, N) triangle, then its first N rows."""
    out = sla.qr(np.ascontiguousarray(a), mode="r", pivoting=pivoting)
    n = a.shape[1]
    return out[0][:n], (out[1] if pivoting else np.arange(n))


@pytest.mark.parametrize("method", ["qrcp", "strong"])
def test_one_thread_economical_fit_matches_the_old_path(corpus, monkeypatch, method):
    utts = corpus.utterances
    a = displacement_matrix(utts)
    assert a.flags.f_contiguous and a.shape == (3 * 10 * 30, 57)
    np.testing.assert_array_equal(a, np.concatenate(
        [(u - u[0]).reshape(-1, 57, 3).transpose(0, 2, 1).reshape(-1, 57) for u in utts]))
    r_old, piv_old = _old_pivoted_qr(a)
    r, piv = pivoted_qr(a)
    assert r.shape == (57, 57) and np.array_equal(r, np.triu(r))
    np.testing.assert_array_equal(piv, piv_old)
    np.testing.assert_allclose(r, r_old, rtol=0, atol=1e-12 * np.abs(r_old).max())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        new = IndependentMarkers(k=12, method=method).fit(utts)
        with monkeypatch.context() as mp:  # the fit as it was, computed directly
            mp.setattr(regions, "pivoted_qr", _old_pivoted_qr)
            old = IndependentMarkers(k=12, method=method).fit(utts)
    assert new.rank_ == old.rank_ and new.swaps_ == old.swaps_
    for name in ("order_", "selected_", "secondary_"):
        np.testing.assert_array_equal(getattr(new, name), getattr(old, name))
    scale = np.abs(old.R_).max()
    np.testing.assert_allclose(new.R_, old.R_, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(new.coef_, old.coef_, rtol=0, atol=1e-9)  # the eigenregions
    np.testing.assert_allclose(new.r_values_, old.r_values_, rtol=1e-9, atol=0)
    assert new.residual_ == pytest.approx(old.residual_, rel=1e-9)
    np.testing.assert_allclose(np.abs(new.pca(3).components), np.abs(old.pca(3).components),
                               atol=1e-9)


def test_factorisation_runs_on_one_blas_thread(monkeypatch):
    from threadpoolctl import threadpool_info

    def blas_threads():
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    seen = []
    real_qr = sla.qr

    def spy(*args, **kw):
        seen.append((blas_threads(), kw.get("mode")))
        return real_qr(*args, **kw)

    before = blas_threads()
    monkeypatch.setattr(regions.sla, "qr", spy)
    utts = latent_utterances(n_utt=3)
    IndependentMarkers(k=3, eps=1e-9, method="strong").fit(utts)
    assert seen and all(t == {1} and mode == "raw" for t, mode in seen)
    assert blas_threads() == before  # restored afterwards


def test_first_selected_markers_sit_near_muscle_insertions(corpus, face):
    m = IndependentMarkers().fit(corpus.utterances)
    sel = [corpus.names[i] for i in m.order_[:10]]
    d = insertion_distances(face, corpus.nodes, sel, draws=500)
    assert d.selected_mean_mm < d.random_mean_mm


def test_regions_cli(tmp_path, monkeypatch, capsys):
    from facemech import MarkerSet, write_markers
    from facemech.cli import main

    utts = latent_utterances(n_utt=8, n_markers=10)
    files = []
    for k, u in enumerate(utts):
        f = tmp_path / f"u{k}.csv"
        write_markers(f, MarkerSet(u, tuple(f"m{j}" for j in range(10)), 60.0,
                                   source_units="mm"))
        files.append(f)
    monkeypatch.setattr(sys, "argv", ["facemech", "regions", *map(str, files), "-k", "4",
                                      "--train", "1-6", "--test", "7-8", "--eps", "0.1mm",
                                      "-o", str(tmp_path / "out")])
    with pytest.raises(SystemExit) as info:
        main()
    assert info.value.code in (0, None)
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["k"] == 4 and s["rank"] == 4 and s["eps_mm"] == pytest.approx(0.1)
    assert [r["k"] for r in s["held_out_error"]] == list(range(1, 10))
    for f in ("r_values.png", "eigenregions.png", "orthogonal_regions.png", "errors.png",
              "trajectory.png"):
        assert (tmp_path / "out" / f).stat().st_size > 5000
    # a file with other markers
    write_markers(tmp_path / "odd.csv", MarkerSet(utts[0][:, :9], tuple(f"m{j}" for j in
                                                                        range(9)), 60.0,
                                                  source_units="mm"))
    monkeypatch.setattr(sys, "argv", ["facemech", "regions", str(files[0]),
                                      str(tmp_path / "odd.csv"), "-o", str(tmp_path / "x")])
    with pytest.raises(SystemExit) as info:
        main()
    assert info.value.code == 2
    assert "odd.csv" in capsys.readouterr().err


def test_experiment_lucero2008_small(tmp_path, monkeypatch, capsys):
    from facemech.cli import main

    monkeypatch.setattr(sys, "argv", ["facemech", "experiment", "lucero2008", "--utterances",
                                      "10", "--frames", "30", "--no-video", "-o",
                                      str(tmp_path / "e")])
    with warnings.catch_warnings():
        with pytest.raises(SystemExit) as info:
            main()
    assert info.value.code in (0, None)
    out = capsys.readouterr().out
    assert "epsilon-rank:" in out and "| 56 of 57" in out
    s = json.loads((tmp_path / "e" / "summary.json").read_text())
    assert s["all_utterances"]["last_selected"] in (COPY_SOURCE, COPY_TARGET)
    assert s["strong_rrqr"]["max_abs_coefficient"] <= 2.0 + 1e-9
