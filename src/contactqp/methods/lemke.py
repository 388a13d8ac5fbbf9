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

# Entries below this (of M scaled to a unit diagonal, q to 1) do not bound a ratio; a second
# try loosens it. W = C K⁻¹ Cᵀ carries round-off of ~1e-12 of its diagonal from the solves with
# K and is singular where rows depend on each other (where Lemke is called): 1e-12 took noise
# as pivots (a false ray on a guarantee-benchmark scene, seed 2026 scene 198), 1e-10 did not.
# A third try tightens it: press fits that need forces 10⁵ times q's scale pivot on entries
# below 1e-9 (random_scene seed 3361: walls on both sides of nodes, rows of W equal to 1e-3; a
# false ray at 1e-9 and 1e-7, the exact answer in 6 pivots at 1e-11). The check judges each.
PIVOT_TOLERANCES = (1e-9, 1e-7, 1e-11)
# An answer that leaves a gap passed by more than this (of q's largest entry) is tried again
# with the next tolerance, and the best kept (the check judges any): round-off, not 1e-8 (seed
# 877 of random single bars: at 1e-9 Lemke skipped a pivot below it, left a gap passed by
# 2.3e-10 of q and a force of 0.35 N beside one of 6.3e6 N at 0; at 1e-11, exact)
SOLUTION_TOLERANCE = 1e-12


def lemke(M: np.ndarray, q: np.ndarray, max_pivots: int | None = None) -> tuple[np.ndarray, int]:
    """(z, pivots) solving the LCP (module docstring); SolverError on a secondary ray (no
    solution found, with any pivot tolerance) or past ``max_pivots`` (default 50 + 10 n).
    In floating point the answer may leave a gap passed by round-off: the caller's check
    judges it.
    M is scaled symmetrically to a unit diagonal first (D M D, D = diag(M)^-½), so that a
    contact of small flexibility beside a large one is pivoted like any other."""
    M = np.asarray(M, dtype=float)
    q = np.asarray(q, dtype=float)
    n = q.size
    if n == 0 or q.min() >= 0.0:
        return np.zeros(n), 0
    scaled_M, scaled_q, D = unit_diagonal(M, q)
    q_scale = float(np.abs(scaled_q).max())
    scaled_q = scaled_q / q_scale
    best, failure = None, None
    for tolerance in PIVOT_TOLERANCES:  # the next only where the one before falls short
        try:
            z, pivots = _lemke(scaled_M, scaled_q, tolerance, max_pivots)
        except SolverError as error:
            failure = error
            continue
        z = D * z * q_scale
        passed = max(-float((M @ z + q).min()), 0.0)  # how far the answer leaves a gap passed
        if best is None or passed < best[2]:
            best = (z, pivots, passed)
        if passed <= SOLUTION_TOLERANCE * float(np.abs(q).max()):
            break
    if best is None:
        raise failure
    return best[0], best[1]


def unit_diagonal(M: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(D M D with a unit diagonal, D q, D = diag(M)^-½): the LCP in z = λ / D, where a
    contact of small flexibility beside a large one weighs the same (a zero diagonal entry
    takes 1/√ of M's largest entry)."""
    diagonal = np.diag(M)
    fallback = 1.0 / np.sqrt(float(np.abs(M).max(initial=0.0)) or 1.0)
    with np.errstate(divide="ignore"):
        D = np.where(diagonal > 0.0, 1.0 / np.sqrt(diagonal), fallback)
    return D[:, None] * M * D[None, :], D * q, D


def _lemke(M: np.ndarray, q: np.ndarray, tolerance: float,
           max_pivots: int | None) -> tuple[np.ndarray, int]:
    """Lemke's pivots on M and q as given (scaled by the caller)."""
    n = q.size
    # the tableau of [I, −M, −d] x = q over x = (w, z, z0), as B⁻¹ [I, −M, −d | q]
    tableau = np.asfortranarray(np.hstack((np.eye(n), -M, -np.ones((n, 1)), q[:, None])))
    basis = np.arange(n)  # the basic variable of each row: w first
    artificial = 2 * n
    # z0 enters where w is most negative; among ties the last row, the lexicographic choice
    # (its row of B⁻¹ = I is the least), so that every tableau stays lexicographically positive
    row = int(np.flatnonzero(q <= q.min() + tolerance * abs(q.min()))[-1])
    entering = artificial
    limit = 50 + 10 * n if max_pivots is None else max_pivots
    for pivots in range(1, limit + 1):
        _pivot(tableau, row, entering)
        leaving, basis[row] = int(basis[row]), entering
        if leaving == artificial:
            z = np.zeros(n)
            held = (basis >= n) & (basis < 2 * n)
            z[basis[held] - n] = np.maximum(tableau[held, -1], 0.0)
            return z, pivots
        entering = leaving + n if leaving < n else leaving - n  # its complement
        row = _lexicographic_ratio(tableau, entering, n, tolerance)
        if row < 0:
            raise SolverError("lemke: a secondary ray (the complementarity problem has no "
                              "solution Lemke's method can reach)")
    raise SolverError(f"lemke: no solution in {limit} pivots")


def _rank_one(*args, **kwargs):
    """BLAS's dger (scipy.linalg.blas is imported at the first pivot, not at start-up)."""
    from scipy.linalg.blas import dger

    return dger(*args, **kwargs)


def _pivot(tableau: np.ndarray, row: int, column: int) -> None:
    """Gauss–Jordan on ``column`` at ``row``, in place: a rank-1 update by BLAS's dger on the
    Fortran-ordered tableau (2.5 times faster than numpy's outer product at 1000 rows)."""
    tableau[row] /= tableau[row, column]
    entries = tableau[:, column].copy()
    entries[row] = 0.0
    _rank_one(-1.0, entries, tableau[row].copy(), a=tableau, overwrite_a=True)


def _lexicographic_ratio(tableau: np.ndarray, column: int, n: int, tolerance: float) -> int:
    """The row that leaves when ``column`` enters: the least ratio of the basic value to the
    column's entry over rows where it is positive, ties broken by the rows of B⁻¹ (the first n
    columns) divided the same way; −1 when no row bounds it."""
    entries = tableau[:, column]
    rows = np.flatnonzero(entries > tolerance)
    if rows.size == 0:
        return -1
    for key in (-1, *range(n)):  # the basic values first, then B⁻¹ column by column
        ratios = tableau[rows, key] / entries[rows]
        rows = rows[ratios <= ratios.min() + tolerance * max(1.0, abs(ratios.min()))]
        if rows.size == 1:
            break
    return int(rows[0])


__all__ = ["lemke", "unit_diagonal"]
