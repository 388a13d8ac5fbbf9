"""Banded and sparse solves (contactqp.linalg) against numpy's dense solve of the same matrix."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from contactqp.errors import SolverError
from contactqp.linalg import solve, solve_spd_band


def chain(n: int, seed: int = 0) -> sp.csr_array:
    """A random SPD tridiagonal matrix (springs of stiffness 1 to 1e3 in a chain, one end held)."""
    k = 10.0 ** np.random.default_rng(seed).uniform(0.0, 3.0, n)
    diagonal = k + np.r_[k[1:], 0.0]
    return sp.csr_array(sp.diags_array([-k[1:], diagonal, -k[1:]], offsets=[-1, 0, 1]))


@pytest.mark.parametrize("spd", [True, False])
def test_a_narrow_matrix_is_solved_like_a_dense_one(spd):
    A = chain(50)
    rhs = np.random.default_rng(1).normal(size=(50, 3))
    # cond(A) < 1e6 here: 1e-9 covers any backward-stable solve
    np.testing.assert_allclose(solve(A, rhs, spd=spd), np.linalg.solve(A.toarray(), rhs),
                               rtol=1e-9, atol=1e-12)


def test_a_wide_matrix_goes_to_superlu_with_the_same_answer():
    A = chain(30).toarray()
    A[0, -1] = A[-1, 0] = -0.5  # a corner entry: bandwidth 29, too wide for the band solvers
    rhs = np.arange(30.0)
    np.testing.assert_allclose(solve(sp.csr_array(A), rhs), np.linalg.solve(A, rhs), rtol=1e-9)


def test_an_ordering_that_makes_the_matrix_narrow_gives_the_same_answer():
    A = chain(20).toarray()
    order = np.random.default_rng(2).permutation(20)
    shuffled = A[np.ix_(order, order)]
    rhs = np.ones(20)
    back = np.empty(20, dtype=int)
    back[order] = np.arange(20)
    x = solve(sp.csr_array(shuffled), rhs[order], order=back)
    np.testing.assert_allclose(x, np.linalg.solve(shuffled, rhs[order]), rtol=1e-9)


def test_a_singular_or_indefinite_matrix_is_a_solver_error():
    A = chain(10).toarray()
    A[:, 3] = 0.0
    A[3, :] = 0.0
    with pytest.raises(SolverError, match="singular"):
        solve(sp.csr_array(A), np.ones(10))
    with pytest.raises(SolverError, match="not positive definite"):
        solve(sp.csr_array(-chain(10).toarray()), np.ones(10), spd=True)
    with pytest.raises(np.linalg.LinAlgError):
        solve_spd_band(np.array([[-1.0]]), np.ones(1))


def test_a_one_by_one_system_is_solved_or_called_singular():
    """A 1 x 1 system (a scene with one unknown): x = b / a for any a ≠ 0, indefinite too
    (scipy's solve_banded before 1.15 indexed past such a band), and a = 0 is singular."""
    np.testing.assert_allclose(solve(sp.csr_array([[-4.0]]), np.array([2.0])), [-0.5])
    np.testing.assert_allclose(solve(sp.csr_array([[4.0]]), np.array([2.0]), spd=True), [0.5])
    with pytest.raises(SolverError, match="singular"):
        solve(sp.csr_array([[0.0]]), np.array([1.0]))
