"""Lemke's complementary pivoting method for the linear complementarity problem (LCP).

Find z with w = M z + q, w >= 0, z >= 0, wᵀz = 0. For contact, z is the contact forces λ, M
the flexibility the contacts see, W = C K⁻¹ Cᵀ (symmetric positive semidefinite), q the gaps
left with no contact force, g − C K⁻¹P, and w the gaps left at the answer.

The method (Lemke 1965; Cottle, Pang and Stone, *The Linear Complementarity Problem*, §4.4)
adds an artificial variable z0 with covering vector d = 1, w = M z + q + d z0, starts from the
almost complementary basis that makes z0 just large enough for w >= 0, and pivots: the variable
that enters is always the complement of the one that left, until z0 leaves. With the
lexicographic ratio test no basis repeats, so it ends in finitely many pivots; for a positive
semidefinite M it ends with a solution whenever the LCP has one (copositive-plus matrices),
and in a secondary ray otherwise. No well-kept Python package offers it, so it is written here
plainly (a dense tableau: it is for tens or hundreds of contacts, not 10⁵).
"""

from __future__ import annotations

import numpy as np

from contactqp.errors import SolverError

PIVOT_TOLERANCE = 1e-12  # entries below this (M and q scaled to 1) do not bound a ratio


def lemke(M: np.ndarray, q: np.ndarray, max_pivots: int | None = None) -> tuple[np.ndarray, int]:
    """(z, pivots) solving the LCP (module docstring); SolverError on a secondary ray (no
    solution found) or past ``max_pivots`` (default 50 + 10 n)."""
    M = np.asarray(M, dtype=float)
    q = np.asarray(q, dtype=float)
    n = q.size
    if n == 0 or q.min() >= 0.0:
        return np.zeros(n), 0
    # scaled to 1 so that one tolerance serves: w = M z + q with z = z_s · (|q| / |M|)
    m_scale = float(np.abs(M).max()) or 1.0
    q_scale = float(np.abs(q).max())
    # the tableau of [I, −M, −d] x = q over x = (w, z, z0), as B⁻¹ [I, −M, −d | q]
    tableau = np.hstack((np.eye(n), -M / m_scale, -np.ones((n, 1)), (q / q_scale)[:, None]))
    basis = np.arange(n)  # the basic variable of each row: w first
    artificial = 2 * n
    row = int(np.argmin(tableau[:, -1]))  # z0 enters where w is most negative
    entering = artificial
    limit = 50 + 10 * n if max_pivots is None else max_pivots
    for pivots in range(1, limit + 1):
        _pivot(tableau, row, entering)
        leaving, basis[row] = int(basis[row]), entering
        if leaving == artificial:
            z = np.zeros(n)
            held = (basis >= n) & (basis < 2 * n)
            z[basis[held] - n] = np.maximum(tableau[held, -1], 0.0)
            return z * (q_scale / m_scale), pivots
        entering = leaving + n if leaving < n else leaving - n  # its complement
        row = _lexicographic_ratio(tableau, entering, n)
        if row < 0:
            raise SolverError("lemke: a secondary ray (the complementarity problem has no "
                              "solution Lemke's method can reach)")
    raise SolverError(f"lemke: no solution in {limit} pivots")


def _pivot(tableau: np.ndarray, row: int, column: int) -> None:
    tableau[row] /= tableau[row, column]
    others = np.flatnonzero(np.arange(tableau.shape[0]) != row)
    tableau[others] -= np.outer(tableau[others, column], tableau[row])


def _lexicographic_ratio(tableau: np.ndarray, column: int, n: int) -> int:
    """The row that leaves when ``column`` enters: the least ratio of the basic value to the
    column's entry over rows where it is positive, ties broken by the rows of B⁻¹ (the first n
    columns) divided the same way; −1 when no row bounds it."""
    entries = tableau[:, column]
    rows = np.flatnonzero(entries > PIVOT_TOLERANCE)
    if rows.size == 0:
        return -1
    for key in (-1, *range(n)):  # the basic values first, then B⁻¹ column by column
        ratios = tableau[rows, key] / entries[rows]
        rows = rows[ratios <= ratios.min() + PIVOT_TOLERANCE * max(1.0, abs(ratios.min()))]
        if rows.size == 1:
            break
    return int(rows[0])


__all__ = ["lemke"]
