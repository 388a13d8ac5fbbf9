"""Contact rows that no u meets all at once: the Problem refuses them in one line naming
them when it is made (and a solve holding every row on its gap, when that fails), and rows
that some u meets (however dependent) are never refused. Which rows leave no u is known from
how each problem is made (a loop of rows whose gaps sum below 0; rows built around a y >= 0
with Cᵀy = 0 and gᵀy < 0; gaps g = C u₀ + s, s >= 0, which u₀ meets), never from the code
under test."""

import re

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from closed_forms import imported_by
from contactqp.errors import ProblemError, SolverError
from contactqp.feasibility.rows import conflicting_rows


def stiffness(rng: np.random.Generator, n: int) -> sp.csr_array:
    """A random symmetric positive definite K (dense, as a user's small model)."""
    A = rng.normal(size=(n, n))
    return sp.csr_array(A @ A.T + n * np.eye(n))


def loop(rng: np.random.Generator, n: int, k: int, gap_sum: float
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows u_a(i) − u_a(i+1) <= g_i round a loop of k distinct dofs a, scaled by random
    factors, gaps summing (per unit row) to ``gap_sum``; returns (C, g, the loop's rows)."""
    dofs = rng.choice(n, size=k, replace=False)
    C = np.zeros((k, n))
    for i in range(k):
        C[i, dofs[i]], C[i, dofs[(i + 1) % k]] = 1.0, -1.0
    unit_gaps = rng.uniform(-1.0, 1.0, k)
    unit_gaps += (gap_sum - unit_gaps.sum()) / k
    factor = 10.0 ** rng.uniform(-2, 2, k)  # a row times a positive factor is the same row
    return C * factor[:, None], unit_gaps * factor, np.arange(k)


@pytest.mark.parametrize("seed", range(6))
def test_a_loop_of_rows_whose_gaps_sum_below_zero_is_named_when_the_problem_is_made(seed):
    rng = np.random.default_rng(seed)
    n, k = 8, 3 + seed % 4
    C, g, _ = loop(rng, n, k, gap_sum=-1e-3)
    # a row on a dof of its own, which some u always meets, is not named
    spare = np.setdiff1d(np.arange(n), np.flatnonzero(np.abs(C).sum(axis=0)))[0]
    extra = np.zeros((1, n))
    extra[0, spare] = 1.0
    arrays = (stiffness(rng, n), rng.normal(size=n), np.vstack((extra, C)),
              np.concatenate(([-0.5], g)))
    named = ", ".join(f"{i} (row[{i}])" for i in range(1, k + 1))
    # the loop's rows added each over its factor give 0·u <= the sum of the unit gaps
    weights = 1.0 / np.abs(C).max(axis=1)
    weights /= weights.max()
    y = ", ".join(f"{w:.3g}" for w in weights)
    with pytest.raises(ProblemError, match=rf"^C rows {re.escape(named)} leave no u") as error:
        contactqp.Problem(*arrays)
    assert f"weighted by y = [{y}]" in str(error.value)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("seed", range(6))
def test_a_loop_whose_gaps_sum_above_zero_is_solved_and_verified(seed):
    rng = np.random.default_rng(100 + seed)
    n, k = 8, 3 + seed % 4
    C, g, _ = loop(rng, n, k, gap_sum=1e-3)
    problem = contactqp.Problem(stiffness(rng, n), rng.normal(size=n), C, g)
    result = contactqp.solve(problem, "lagrange")
    assert result.verified
    assert np.all(C @ result.u <= g + 1e-9 * np.abs(g).max())


def dependent_rows(rng: np.random.Generator, m: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """m random rows and a y >= 0 with Cᵀy = 0 (each row less its part along y)."""
    y = rng.uniform(0.1, 1.0, m)
    C0 = rng.normal(size=(m, n))
    return C0 - np.outer(y, y @ C0) / (y @ y), y


@pytest.mark.parametrize("seed", range(8))
def test_rows_built_round_a_farkas_certificate_are_refused_and_gaps_some_u_meets_are_not(seed):
    rng = np.random.default_rng(200 + seed)
    m, n = 4 + seed % 3, 9
    C, y = dependent_rows(rng, m, n)
    # gaps a u₀ meets: never refused, whatever each method does with them
    u0 = rng.normal(size=n)
    g_met = C @ u0 + rng.uniform(0.0, 0.5, m) * np.abs(C @ u0)  # some below 0, met by u₀
    K, f = stiffness(rng, n), rng.normal(size=n)
    assert g_met.min() < 0.0
    result = contactqp.solve(contactqp.Problem(K, f, C, g_met), "lagrange")
    assert np.all(C @ result.u <= g_met + 1e-9 * np.abs(g_met).max())
    # gaps with gᵀy < 0: no u meets them (Farkas), and the message says so on one line
    g = rng.normal(size=m)
    g -= y * (g @ y + 0.5) / (y @ y)  # now gᵀy = −0.5
    with pytest.raises(ProblemError, match=r"^C rows .* leave no u that meets them all"):
        contactqp.Problem(K, f, C, g)
    assert conflicting_rows(sp.csr_array(C), g, np.zeros(m, dtype=bool),
                            tuple(f"row[{i}]" for i in range(m))) is not None


def test_equality_rows_whose_gaps_disagree_are_named():
    # r2 = r0 + r1 as rows, but g2 != g0 + g1: no u holds all three on their gaps
    C = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [1.0, 1.0, 0, 0]])
    rng = np.random.default_rng(5)
    with pytest.raises(ProblemError, match=r"^C rows 0 \(row\[0\]\), 1 \(row\[1\]\), 2 "):
        contactqp.Problem(stiffness(rng, 4), np.zeros(4), C, np.array([0.1, 0.2, 0.4]),
                          kinds=["equality"] * 3)
    # inequality rows that some u meets, held on their gaps by the solve: refused then
    consistent = contactqp.Problem(stiffness(rng, 4), np.zeros(4), C, np.array([0.1, 0.2, 0.3]))
    assert contactqp.solve(consistent, "lagrange", contact="equality").verified
    clash = contactqp.Problem(stiffness(rng, 4), np.zeros(4), -C, np.array([-0.1, -0.2, 0.4]))
    with pytest.raises(ProblemError, match="leave no u"):
        contactqp.solve(clash, "lagrange", contact="equality")


def test_rows_with_a_column_of_their_own_are_never_searched():
    # a row with a dof no other row touches can always be met: no linear programme (and no
    # 0.2 s import of scipy.optimize) for such rows, even with gaps below 0. Rows u_0 - u_i
    # (i = 1..20), each with dof i to itself, and a chain u_j - u_(j+1) (j = 21..30), whose
    # end rows have a dof to themselves once the rows beyond them are set aside
    code = ("import numpy as np, contactqp\n"
            "n = 32\n"
            "star = np.zeros((20, n)); star[:, 0] = 1.0; star[np.arange(20), "
            "np.arange(1, 21)] = -1.0\n"
            "chain = (np.eye(n) - np.eye(n, k=1))[21:31]\n"
            "C = np.vstack((star, chain))\n"
            "contactqp.Problem(np.eye(n), np.zeros(n), C, -np.ones(C.shape[0]))")
    assert imported_by(code, ("scipy.optimize",)) == []


def test_a_failure_on_rows_some_u_meets_is_left_as_it_was():
    # a solver that stops early fails on feasible rows: its own error, not a ProblemError
    rng = np.random.default_rng(7)
    C, g, _ = loop(rng, 8, 5, gap_sum=1e-3)
    problem = contactqp.Problem(stiffness(rng, 8), 1e3 * rng.normal(size=8), C, g)
    try:
        result = contactqp.solve(problem, "pgs", max_iterations=1)
    except SolverError as error:
        assert not isinstance(error, ProblemError)
    else:
        assert not result.verified
