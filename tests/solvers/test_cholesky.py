"""The implicit step's factor (:mod:`facemech.solvers.cholesky`): CHOLMOD's Cholesky factor of a
symmetric positive definite matrix, SuperLU's of one that is not."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve


def _laplacian_plus_mass(n: int, shift: float) -> sp.csc_matrix:
    """A path graph's Laplacian plus ``shift`` on the diagonal (positive definite for a
    positive shift, indefinite for a shift between -4 and 0)."""
    main = np.full(n, 2.0 + shift)
    off = -np.ones(n - 1)
    return sp.diags([off, main, off], [-1, 0, 1]).tocsc()


def test_a_positive_definite_matrix_gets_cholmods_factor_and_solves_three_axes():
    from facemech.solvers.cholesky import CholeskyFactor, factorise

    a = _laplacian_plus_mass(300, 0.05)
    f = factorise(a)
    assert isinstance(f, CholeskyFactor)
    rhs = np.random.default_rng(1).standard_normal((300, 3))
    x = f.solve(rhs)
    np.testing.assert_allclose(a @ x, rhs, atol=1e-10)
    np.testing.assert_allclose(x, spsolve(a, rhs), rtol=1e-10, atol=1e-12)
    # a vector, and a view that is not C-contiguous, solve as well; the input is kept
    np.testing.assert_allclose(f.solve(rhs[:, 1]), x[:, 1], rtol=1e-12)
    col = np.asfortranarray(rhs)
    np.testing.assert_allclose(f.solve(col), x, rtol=1e-12)
    np.testing.assert_array_equal(col, rhs)


def test_a_matrix_that_is_not_positive_definite_falls_back_to_superlu():
    from facemech.solvers.cholesky import CholeskyFactor, factorise

    a = _laplacian_plus_mass(50, -0.5)  # symmetric, indefinite, not singular
    assert np.linalg.eigvalsh(a.toarray()).min() < 0
    f = factorise(a)
    assert not isinstance(f, CholeskyFactor)
    rhs = np.random.default_rng(2).standard_normal((50, 3))
    np.testing.assert_allclose(a @ f.solve(rhs), rhs, atol=1e-9)
