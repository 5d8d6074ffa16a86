"""The implicit step's constant matrix, factorised once: a sparse Cholesky factor.

The implicit integrators (:mod:`.implicit`) solve ``M + h C + h^2 K`` (symmetric positive
definite: masses, the springs' dashpot Laplacian, a share of the rest stiffness) three to a dozen
times a step, for the three axes at once. CHOLMOD's simplicial factor (through ``cholespy``, which
ships it) solves it in a third of the time SuperLU takes with its symmetric settings (0.38-0.41
against 1.05-1.15 ms for the built-in face's 4333 unknowns and three right-hand sides, one core;
``benchmarks/solve.py``), with the same solution to 1e-15 of its size. A matrix CHOLMOD finds
not positive definite (none of facemech's presets makes one) falls back to SuperLU.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu


class CholeskyFactor:
    """A sparse symmetric positive definite matrix's Cholesky factor (CHOLMOD, ``cholespy``).

    Parameters
    ----------
    matrix : (n, n) sparse, symmetric positive definite (both triangles stored)

    Raises
    ------
    ValueError
        The matrix is not positive definite.
    """

    def __init__(self, matrix: sp.spmatrix):
        from cholespy import CholeskySolverD, MatrixType

        a = sp.coo_matrix(matrix)
        self.shape = a.shape
        self._factor = CholeskySolverD(a.shape[0], a.row.astype(np.int32),
                                       a.col.astype(np.int32),
                                       np.ascontiguousarray(a.data, dtype=np.float64),
                                       MatrixType.COO)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """The solution of ``A x = rhs`` for rhs (n,) or (n, k); a new array."""
        b = np.ascontiguousarray(rhs, dtype=np.float64)
        x = np.empty_like(b)
        self._factor.solve(b, x)
        return x


def factorise(matrix: sp.spmatrix):
    """The factor of the implicit step's matrix (symmetric positive definite), with a
    ``solve(rhs)`` for rhs (n,) or (n, k): CHOLMOD's Cholesky factor, or SuperLU's
    (symmetric mode, no pivoting: the same fill-reducing ordering of A + A^T) where CHOLMOD
    finds the matrix not positive definite."""
    try:
        return CholeskyFactor(matrix)
    except ValueError:
        return splu(sp.csc_matrix(matrix), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options={"SymmetricMode": True})
