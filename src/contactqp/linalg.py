"""Sparse solves that use LAPACK's banded routines when the matrix is narrow.

A bar is a chain, so K is tridiagonal, and the saddle-point matrix [[K, Cᵀ], [C, 0]] becomes
banded too once each multiplier is ordered next to the node it acts on. LAPACK solves a banded
system in O(n) (``pbsv``, Cholesky, for SPD matrices; ``gbsv``, LU with partial pivoting, for
indefinite ones). Anything wider goes to SuperLU.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import SolverError

MAX_BANDWIDTH = 8  # beyond this, SuperLU with a fill-reducing ordering is the better tool


def _lapack() -> ModuleType:
    """scipy.linalg, imported at the first solve rather than with contactqp (0.15 s of the
    start-up of every command line call otherwise)."""
    import scipy.linalg

    return scipy.linalg


def _sparse_lu() -> ModuleType:
    """scipy.sparse.linalg (SuperLU), imported when first used: it imports scipy.linalg."""
    import scipy.sparse.linalg

    return scipy.sparse.linalg


def _bandwidths(matrix: sp.coo_array) -> tuple[int, int]:
    """(lower, upper) bandwidth of a sparse matrix."""
    if matrix.nnz == 0:
        return 0, 0
    offsets = matrix.row - matrix.col
    return max(int(offsets.max()), 0), max(int(-offsets.min()), 0)


def _band_storage(matrix: sp.coo_array, lower: int, upper: int) -> np.ndarray:
    """LAPACK band storage: ab[upper + i - j, j] = a[i, j]; with upper = 0 this is also the
    symmetric lower storage that ``solveh_banded`` reads."""
    ab = np.zeros((lower + upper + 1, matrix.shape[1]))
    ab[upper + matrix.row - matrix.col, matrix.col] = matrix.data  # entries are unique (summed)
    return ab


def solve_spd_band(band: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve with an SPD matrix in LAPACK symmetric lower band storage (one Cholesky
    factorisation for every column of ``rhs``). Raises numpy's LinAlgError when the matrix
    is not positive definite."""
    if band.shape[1] == 1:  # scipy's tridiagonal path (ptsv) rejects a 1 x 1 system
        if not band[0, 0] > 0.0:
            raise np.linalg.LinAlgError("1 x 1 matrix is not positive")
        return _solve_one_by_one(band[0, 0], rhs)
    return _lapack().solveh_banded(band, rhs, lower=True, check_finite=False)


def _solve_one_by_one(pivot: float, rhs: np.ndarray) -> np.ndarray:
    """x = rhs / pivot, or numpy's LinAlgError where the 1 x 1 matrix is 0."""
    if pivot == 0.0:
        raise np.linalg.LinAlgError("1 x 1 matrix is 0")
    return np.asarray(rhs, dtype=float) / pivot


def magnitude(matrix: Any) -> Any:
    """|matrix| for a product, sharing the matrix's index arrays where it is compressed (abs()
    copies them: 0.1 s of the check on a 3.3·10⁵-dof model's K)."""
    if getattr(matrix, "format", None) in ("csr", "csc"):
        return type(matrix)((np.abs(matrix.data), matrix.indices, matrix.indptr),
                            shape=matrix.shape)
    return abs(matrix)


def symmetric_eigenvalues(matrix: np.ndarray) -> np.ndarray:
    """The eigenvalues of a dense symmetric matrix, ascending (LAPACK syevr)."""
    return _lapack().eigvalsh(matrix, check_finite=False)


def solve(matrix: sp.sparray, rhs: np.ndarray, *, spd: bool = False,
          order: np.ndarray | None = None) -> np.ndarray:
    """Solve ``matrix @ x = rhs`` (rhs may have several columns).

    ``spd``: the matrix is symmetric positive definite (banded Cholesky is used when narrow).
    ``order``: a permutation of the unknowns that makes the matrix narrow, if one is known.
    Raises SolverError when the matrix is singular (or, with ``spd``, not positive definite).
    """
    csr = sp.csr_array(matrix)
    csr.sum_duplicates()  # free when already canonical; a permutation adds no duplicates
    coo = csr.tocoo()
    rhs = np.asarray(rhs, dtype=float)
    if order is not None:
        position = np.empty_like(order)
        position[order] = np.arange(order.size)
        coo = sp.coo_array((coo.data, (position[coo.row], position[coo.col])), shape=coo.shape)
        rhs = rhs[order]
    lower, upper = _bandwidths(coo)
    try:
        if max(lower, upper) <= MAX_BANDWIDTH and spd:
            x = solve_spd_band(_band_storage(sp.coo_array(sp.tril(coo)), lower, 0), rhs)
        elif coo.shape[0] == 1:  # scipy before 1.15 misreads a 1 x 1 band in solve_banded
            x = _solve_one_by_one(coo.toarray()[0, 0], rhs)
        elif max(lower, upper) <= MAX_BANDWIDTH:
            x = _lapack().solve_banded((lower, upper), _band_storage(coo, lower, upper), rhs,
                                       check_finite=False)
        else:
            x = _sparse_lu().splu(sp.csc_array(coo)).solve(rhs)
    except (np.linalg.LinAlgError, RuntimeError) as error:
        kind = "not positive definite" if spd else "singular"
        raise SolverError(f"the linear system is {kind} ({error})") from None
    if not np.all(np.isfinite(x)):
        raise SolverError("the linear system is singular to working precision (non-finite solution)")
    if order is not None:
        unordered = np.empty_like(x)
        unordered[order] = x
        x = unordered
    return x
