"""Independent kinematic regions of the face (Lucero & Munhall 2008).

QR factorisation with column pivoting of the stacked displacement matrix, ``A P = Q R``, orders
the markers by linear independence: the first k pivoted columns are the independent markers, the
rest are least-squares combinations of them, ``R11 X = R12`` (section II). The coefficients X
spread over the face are the "eigenregions".

Stacking: every utterance's displacements (frames, markers, 3) relative to its neutral frame
are flattened frame by frame with x, y, z interleaved, so row ``3 s + a`` holds axis ``a`` of
sample ``s``, utterances one after another: A is (3 M, N) for M samples and N markers.

R values are normalised by the square root of the number of rows, which turns |r_kk| into an
RMS displacement in the data's unit that does not grow with the amount of data. The epsilon-rank
is the smallest k whose residual block ``R22`` has a 2-norm no larger than the same block of a
displacement matrix made of pure measurement noise (standard deviation eps per coordinate, the
data's utterance structure and neutral frames), times ``sqrt(1 + ||X||_2^2)`` for the noise that
the fit carries over from the k noisy independent columns: the markers beyond it move no more,
independently, than noise would.

A is stacked in column-major order (LAPACK's geqp3 needs no transposed copy); only the (N, N)
triangle R is kept; the factorisation, the noise Gram matrix and the SVD run with BLAS capped at
one thread (:func:`one_blas_thread`; why: docs/design-log.md, "Marker regions").
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import InputError


def displacement_matrix(utterances: Sequence[np.ndarray], neutral: str | np.ndarray = "first",
                        *, source: str | None = None) -> np.ndarray:
    """Stack utterances (each (frames, markers, 3)) into A (3 M, N) of displacements.

    ``neutral="first"`` takes each utterance's first frame as its neutral; an array (markers, 3)
    is one neutral for all. Missing samples (NaN) are an error: fill or drop them first.
    """
    if len(utterances) == 0:
        raise InputError("no utterances", source=source, field="utterances")
    n = np.shape(utterances[0])[1]
    total = 0
    for u, x in enumerate(utterances):
        shape = np.shape(x)
        if len(shape) != 3 or shape[2] != 3:
            raise InputError(f"utterance {u} is not (frames, markers, 3)", source=source,
                             field=f"utterance {u}")
        if shape[1] != n:
            raise InputError(f"utterance {u} has {shape[1]} markers, the first has {n}",
                             source=source, field=f"utterance {u}")
        total += 3 * shape[0]
    a = np.empty((total, n), order="F")  # column-major: geqp3's layout, no copy to factorise
    xyz = np.dtype((np.void, 3 * a.itemsize))  # one (x, y, z) triple as a single item
    row = 0
    for u, x in enumerate(utterances):
        x = np.asarray(x, float)
        base = x[0] if isinstance(neutral, str) else np.asarray(neutral, float)
        d = np.ascontiguousarray(x - base)  # (frames, markers, 3)
        if not np.isfinite(d).all():
            f, m, _ = np.argwhere(~np.isfinite(d))[0]
            raise InputError(f"utterance {u} has a gap (marker {m}, frame {f}): fill or drop it",
                             source=source, field=f"utterance {u}")
        # column j of the block holds marker j's triples frame by frame: a transpose of
        # (frames, markers) triples, copied as whole triples
        block = a.T[:, row:row + 3 * len(x)]  # (markers, 3 frames), rows contiguous
        block.view(xyz).reshape(n, len(x))[...] = d.view(xyz).reshape(len(x), n).T
        row += 3 * len(x)
    if a.shape[0] < n:
        raise InputError(f"{a.shape[0]} rows for {n} markers: need at least as many samples x 3 "
                         "as markers", source=source, field="samples")
    return a


def noise_floor(utterances: Sequence[np.ndarray]) -> float:
    """Estimate the measurement noise (per coordinate, data unit) from second differences.

    For smooth motion sampled fast, the second difference of a trajectory is dominated by the
    noise; for white noise of standard deviation s its variance is 6 s^2. A median-based
    estimate keeps bursts of fast motion from inflating it.
    """
    total = sum(max(len(u) - 2, 0) * np.shape(u)[1] * 3 for u in utterances)
    step = max(1, int(total // 2_000_000))  # every step-th utterance keeps long data fast
    d2 = np.concatenate([np.diff(np.asarray(u, float), 2, axis=0).reshape(-1)
                         for u in utterances[::step] if len(u) > 2] or [np.zeros(0)])
    d2 = d2[np.isfinite(d2)]
    if len(d2) == 0:
        raise InputError("too few samples to estimate the noise", field="utterances")
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def one_blas_thread() -> AbstractContextManager:
    """A context in which BLAS and LAPACK use one thread (threadpoolctl).

    The region fit's tall factorisation is memory-bound; two OpenBLAS threads on a busy two-core
    machine made it several times slower than one (see ``benchmarks/regions.py``).
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def pivoted_qr(a: np.ndarray, *, pivoting: bool = True,
               overwrite_a: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The triangular factor and the column order of ``A P = Q R`` (LAPACK geqp3), on one thread.

    Parameters
    ----------
    a : (rows, N) finite matrix, rows >= N; column-major (Fortran) order avoids a copy
    pivoting : column pivoting (False: the columns in their given order, geqrf)
    overwrite_a : let LAPACK factorise ``a`` in place (its contents are then lost)

    Returns
    -------
    r : (N, N) upper triangular R (Q is never formed; only R's own rows are copied out)
    perm : (N,) column order P, int
    """
    with one_blas_thread():
        out = sla.qr(a, mode="raw", pivoting=pivoting, overwrite_a=overwrite_a,
                     check_finite=False)
    r = out[1]
    perm = out[2] if pivoting else np.arange(a.shape[1])
    return r, perm


def strong_rrqr(a: np.ndarray, k: int, f: float = 2.0, max_swaps: int = 500):
    """Strong rank-revealing QR (Gu & Eisenstat 1996) for a fixed k.

    Starts from QR with column pivoting and swaps a selected with an unselected column while
    some ``sqrt((R11^-1 R12)_ij^2 + (gamma_j(R22) / omega_i(R11))^2) > f``; each swap multiplies
    |det R11| by more than f, so it ends, and then every |X_ij| = |(R11^-1 R12)_ij| <= f.

    Returns (R, perm, swaps).
    """
    r, perm = pivoted_qr(a)
    n = a.shape[1]
    swaps = 0
    if k <= 0 or k >= n:
        return r, perm, swaps
    while swaps < max_swaps:
        r11 = r[:k, :k]
        r12 = r[:k, k:]
        r22 = r[k:, k:]
        x = sla.solve_triangular(r11, r12)
        inv = sla.solve_triangular(r11, np.eye(k))
        omega = 1.0 / np.linalg.norm(inv, axis=1)  # omega_i = 1 / ||row i of R11^-1||
        gamma = np.linalg.norm(r22, axis=0)
        crit = x**2 + (gamma[None, :] / omega[:, None]) ** 2
        i, j = np.unravel_index(np.argmax(crit), crit.shape)
        if np.sqrt(crit[i, j]) <= f:
            break
        perm = perm.copy()
        perm[i], perm[k + j] = perm[k + j], perm[i]
        r = pivoted_qr(a[:, perm], pivoting=False, overwrite_a=True)[0]
        swaps += 1
    return r, perm, swaps


def _noise_block_norms(utterances, neutral, eps: float, seed: int = 0) -> np.ndarray:
    """2-norms of the first j columns (j = 1..N) of a displacement matrix made of Gaussian
    position noise of standard deviation ``eps`` with the utterances' shapes and neutral."""
    rng = np.random.default_rng(seed)
    n = np.shape(utterances[0])[1]
    g = np.zeros((n, n))
    for u in utterances:
        e = rng.standard_normal(np.shape(u), dtype=np.float32)
        if isinstance(neutral, str):
            e -= e[0]
        e = e.transpose(0, 2, 1).reshape(-1, n)
        g += (e.T @ e).astype(float)
    g *= eps * eps
    return np.array([np.sqrt(max(np.linalg.eigvalsh(g[:j, :j])[-1], 0.0))
                     for j in range(1, g.shape[0] + 1)])


@dataclass(frozen=True)
class PCABaseline:
    """Best rank-k reconstruction (principal components) of the displacement matrix."""

    components: np.ndarray  # (k, N)

    def reconstruct(self, a: np.ndarray) -> np.ndarray:
        return a @ self.components.T @ self.components


class IndependentMarkers:
    """QR with column pivoting over marker displacements (scikit-learn style).

    Parameters
    ----------
    k : number of independent markers (default: the epsilon-rank)
    eps : data precision in the data's unit for the epsilon-rank (default: the noise floor
        estimated from the data, see :func:`noise_floor`)
    method : "qrcp" (LAPACK geqp3, the seed's) or "strong" (Gu-Eisenstat strong RRQR)
    bound : f of the strong RRQR, the bound on every |X_ij|
    neutral : "first" (each utterance's first frame) or a (markers, 3) array

    Attributes after :meth:`fit`
    ----------------------------
    selected_ : (k,) marker indices of the independent markers, in pivot order
    order_ : (N,) all markers in pivot order
    r_values_ : (N,) |r_jj| / sqrt(rows), data unit
    rank_ : epsilon-rank
    eps_ : the epsilon used
    coef_ : (k, N - k) X of R11 X = R12, columns in ``order_[k:]`` order
    residual_ : ||R22||_F (data unit; the least-squares residual of the fit)
    R_ : the triangular factor
    """

    def __init__(self, k: int | None = None, eps: float | None = None, *, method: str = "qrcp",
                 bound: float = 2.0, neutral: str | np.ndarray = "first"):
        if method not in ("qrcp", "strong"):
            raise InputError(f"unknown method {method!r} (qrcp or strong)", field="method")
        self.k = k
        self.eps = eps
        self.method = method
        self.bound = bound
        self.neutral = neutral

    def fit(self, utterances: Sequence[np.ndarray]) -> IndependentMarkers:
        a = displacement_matrix(utterances, self.neutral)
        n = a.shape[1]
        rows = a.shape[0]
        # LAPACK geqp3 on one thread; Q is never formed; A is factorised in place unless the
        # strong RRQR needs it again
        r, perm = pivoted_qr(a, overwrite_a=self.method != "strong")
        if self.method != "strong":
            del a
        norm = np.sqrt(rows)
        self.eps_ = float(self.eps if self.eps is not None else noise_floor(utterances))
        # epsilon-rank: smallest k whose residual block R22 is no larger (2-norm) than noise
        # would leave: the same block of a pure-noise displacement matrix of the data's
        # structure, grown by sqrt(1 + ||X||^2) for the noise the fit carries over from the k
        # (noisy) independent columns
        with one_blas_thread():
            self.noise_norms_ = _noise_block_norms(utterances, self.neutral, self.eps_) / norm
        rank = n
        for kk in range(1, n):
            x = sla.solve_triangular(r[:kk, :kk], r[:kk, kk:], check_finite=False)
            limit = self.noise_norms_[n - kk - 1] * np.sqrt(1.0 + np.linalg.norm(x, 2) ** 2)
            if np.linalg.norm(r[kk:, kk:], 2) / norm <= limit:
                rank = kk
                break
        self.rank_ = rank
        k = self.k if self.k is not None else rank
        if not 1 <= k <= n:
            raise InputError(f"k = {k} outside 1..{n}", field="k")
        if self.k is not None and self.k > rank:
            import warnings

            warnings.warn(f"k = {self.k} is larger than the epsilon-rank {rank}: the fit "
                          "coefficients of the extra markers rest on noise", stacklevel=2)
        self.swaps_ = 0
        if self.method == "strong":
            r, perm, self.swaps_ = strong_rrqr(a, k, self.bound)
        self.R_ = r
        self.order_ = np.asarray(perm)
        self.r_values_ = np.abs(np.diag(r)) / norm
        self.n_markers_ = n
        # principal directions of A = Q R P^T are those of R P^T (no SVD of the tall matrix)
        rp = np.empty_like(r)
        rp[:, self.order_] = r
        with one_blas_thread():
            self._vt = np.linalg.svd(rp, full_matrices=False)[2]
        self._set_k(k)
        return self

    def _set_k(self, k: int) -> None:
        """Selection, fit coefficients and residual for k, from the stored factorisation."""
        r, n = self.R_, self.n_markers_
        self.k_ = k
        self.selected_ = self.order_[:k]
        self.secondary_ = self.order_[k:]
        self.coef_ = (sla.solve_triangular(r[:k, :k], r[:k, k:]) if k < n
                      else np.zeros((k, 0)))
        self.residual_ = float(np.linalg.norm(r[k:, k:]))

    def with_k(self, k: int) -> IndependentMarkers:
        """The fitted QRCP model truncated at another k, without factorising again (the pivot
        order of column pivoting does not depend on k; strong RRQR's does, so refit that)."""
        import copy

        if self.method != "qrcp":
            raise InputError("with_k needs method='qrcp' (strong RRQR swaps depend on k)",
                             field="method")
        if not 1 <= k <= self.n_markers_:
            raise InputError(f"k = {k} outside 1..{self.n_markers_}", field="k")
        out = copy.copy(self)
        out.k = k
        out._set_k(k)
        return out

    def pca(self, k: int | None = None) -> PCABaseline:
        """The principal-component baseline with the same (or a given) k."""
        return PCABaseline(self._vt[: (k or self.k_)])

    def predict(self, independent: np.ndarray) -> np.ndarray:
        """All markers' displacements from the independent markers' displacements.

        Parameters
        ----------
        independent : (frames, k, 3) displacements of ``selected_`` (in that order)

        Returns
        -------
        (frames, N, 3) displacements, markers in their original order
        """
        p1 = np.asarray(independent, float)
        if p1.ndim != 3 or p1.shape[1] != self.k_:
            raise InputError(f"expected (frames, {self.k_}, 3) displacements of the independent "
                             "markers", field="independent")
        frames = p1.shape[0]
        out = np.empty((frames, self.n_markers_, 3))
        flat = p1.transpose(0, 2, 1).reshape(-1, self.k_)  # rows (frame, axis)
        p2 = flat @ self.coef_
        out[:, self.selected_] = p1
        out[:, self.secondary_] = p2.reshape(frames, 3, -1).transpose(0, 2, 1)
        return out

    def errors(self, utterances: Sequence[np.ndarray]) -> dict:
        """Held-out errors of the secondary markers (data unit): mean absolute 3-D error, the
        relative error (mean error over mean displacement), and the same for PCA with k."""
        err, mag, pca_err = [], [], []
        pca = self.pca()
        for x in utterances:
            x = np.asarray(x, float)
            base = x[0] if isinstance(self.neutral, str) else self.neutral
            d = x - base
            pred = self.predict(d[:, self.selected_])
            sec = self.secondary_
            err.append(np.linalg.norm(pred[:, sec] - d[:, sec], axis=2).reshape(-1))
            mag.append(np.linalg.norm(d[:, sec], axis=2).reshape(-1))
            a = d.transpose(0, 2, 1).reshape(-1, d.shape[1])
            rec = pca.reconstruct(a).reshape(d.shape[0], 3, -1).transpose(0, 2, 1)
            pca_err.append(np.linalg.norm(rec[:, sec] - d[:, sec], axis=2).reshape(-1))
        e, m, pe = (np.concatenate(v) for v in (err, mag, pca_err))
        return {"mean_abs_error": float(e.mean()), "relative_error": float(e.mean() / m.mean()),
                "pca_mean_abs_error": float(pe.mean()), "max_error": float(e.max())}

    def score(self, utterances: Sequence[np.ndarray]) -> float:
        """Negative mean absolute error of the secondary markers (higher is better)."""
        return -self.errors(utterances)["mean_abs_error"]
