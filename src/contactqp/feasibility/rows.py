"""A Problem's contact rows, checked when it is made: no zero row, no constraint given twice,
and rows that some u meets all at once (:func:`row_conflict`).

Two parallel or opposite rows are compared directly. Three or more rows can leave no u as
well, e.g. a loop u₀ − u₁ <= g₀, u₁ − u₂ <= g₁, u₂ − u₀ <= g₂ with g₀ + g₁ + g₂ < 0, where
every method would fail in its own way (an active set that cycles, a secondary ray, an answer
the check does not verify). By Farkas' lemma the rows C u <= g (inequality rows; equality
rows C u = g) leave no u exactly when some y, >= 0 on the inequality rows, has Cᵀy = 0 and
gᵀy < 0: adding the rows with the weights y gives 0 <= gᵀy (:func:`conflicting_rows`).

Most problems need no search for y: rows whose gaps are all >= 0 (an equality row's = 0) are
met by u = 0, and a row with a column that no other row touches has y = 0 in any such sum, so
such rows are set aside, round after round, and what is left (the core) must hold three rows
or more. Otherwise y is looked for by a linear programme over the core (scipy's HiGHS;
importing scipy.optimize takes 0.2 s, once per process), and checked in floating point
rather than taken from the solver's status: the rows are named only if any u meeting them
would have to move more than :data:`ABSURD_MOVE` times the largest gap, |gᵀy| / ‖Cᵀy‖₁ (from
(Cᵀy)ᵀu = yᵀC u <= gᵀy), each row scaled to unit length.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

ABSURD_MOVE = 1e9  # a u this many times the largest gap counts as no u at all
NAMED_ROWS = 6  # rows named in the message at most (the rest counted)
PEELING_ROUNDS = 16  # rounds that set aside rows with a column of their own (then the LP)


def row_conflict(C: sp.csr_array, g: np.ndarray, equality: np.ndarray,
                 names: tuple[str, ...]) -> str | None:
    """One line naming the first thing wrong with the rows (a zero row, a constraint twice,
    rows that no u meets all at once), or None. ``equality``: per row, held on its gap."""
    empty = np.flatnonzero(np.diff(C.indptr) == 0)
    if empty.size:
        return f"C row {empty[0]} ({names[empty[0]]}) is zero: it constrains nothing (drop it)"
    scale = np.sqrt(np.asarray((C.multiply(C)).sum(axis=1)).reshape(-1))
    unit = sp.csr_array(sp.diags_array(1.0 / scale) @ C)
    gram = sp.triu(unit @ unit.T, k=1).tocoo()
    parallel = np.abs(gram.data) >= 1.0 - 1e-12
    for i, j, value in zip(gram.row[parallel], gram.col[parallel], gram.data[parallel]):
        clash = _parallel_pair(int(i), int(j), float(np.sign(value)), g / scale, equality,
                               names)
        if clash:
            return clash
    return conflicting_rows(C, g, equality, names)


def _parallel_pair(i: int, j: int, sign: float, gaps: np.ndarray, equality: np.ndarray,
                   names: tuple[str, ...]) -> str | None:
    """Rows i and j are parallel (sign +1) or opposite (−1); ``gaps`` per unit row. The same
    constraint twice, or two that no u meets at once, is an error; a parallel row whose gap
    never binds is allowed (a redundant row)."""
    pair = f"C rows {i} ({names[i]}) and {j} ({names[j]})"
    a, b = gaps[i], sign * gaps[j]  # row j as a bound on c·u: <= b (sign +1) or >= b (−1)
    tight = abs(a - b) <= 1e-12 * max(abs(a), abs(b))
    if tight and (sign > 0 or equality[i] or equality[j]):
        return (f"{pair} are the same constraint (the same row and gap, up to a positive "
                "factor): drop one")
    if sign > 0:  # c·u <= a and c·u <= b: only equalities can conflict
        clash = (equality[i] and equality[j]) or (equality[i] and a > b) or (
            equality[j] and b > a)
    else:  # c·u <= a and c·u >= b
        clash = b > a and not tight or (equality[i] and equality[j] and not tight)
    if clash:
        return (f"{pair} are {'parallel' if sign > 0 else 'opposite'} and their gaps "
                f"({gaps[i]:.6g} and {gaps[j]:.6g} per unit row) leave no u that satisfies both")
    return None


def conflicting_rows(C: sp.csr_array, g: np.ndarray, equality: np.ndarray,
                     names: tuple[str, ...]) -> str | None:
    """One line naming rows of C u (<= or =) g that no u meets all at once (module
    docstring), or None when no certificate of that is found."""
    if not (np.any(g[~equality] < 0.0) or np.any(g[equality] != 0.0)):
        return None  # u = 0 meets every row
    core = _core(C)
    if core.size < 3:  # two rows: compared as a pair (row_conflict)
        return None
    weights = _certificate(C[core], g[core], equality[core])
    if weights is None:
        return None
    rows = core[np.flatnonzero(weights)]
    y = weights[weights != 0.0]
    listed = ", ".join(f"{i} ({names[i]})" for i in rows[:NAMED_ROWS])
    more = f" and {rows.size - NAMED_ROWS} more" if rows.size > NAMED_ROWS else ""
    shown = ", ".join(f"{w:.3g}" for w in y[:NAMED_ROWS]) + (", ..." if more else "")
    return (f"C rows {listed}{more} leave no u that meets them all: weighted by y = [{shown}]"
            f" they add up to 0·u <= {float(g[rows] @ y):.6g} (their gaps so weighted), "
            "which no u can meet; check these rows' gaps and signs")


def _core(C: sp.csr_array) -> np.ndarray:
    """The rows left once every row with a column no other (left) row touches is set aside,
    round after round (module docstring): only they can carry a certificate."""
    rows = np.repeat(np.arange(C.shape[0]), np.diff(C.indptr))
    columns = C.indices
    keep = np.ones(C.shape[0], dtype=bool)
    for _ in range(PEELING_ROUNDS):
        kept = keep[rows]
        touching = np.bincount(columns[kept], minlength=C.shape[1])
        alone = rows[kept & (touching[columns] == 1)]
        if alone.size == 0:
            break
        keep[alone] = False
    return np.flatnonzero(keep)


def _certificate(C: sp.csr_array, g: np.ndarray, equality: np.ndarray) -> np.ndarray | None:
    """y (module docstring) for the rows as given, largest |y| 1, checked in floating point;
    or None."""
    # each row scaled to unit length, so that u is measured against the gaps
    length = np.sqrt(np.asarray(C.multiply(C).sum(axis=1)).reshape(-1))
    unit = sp.csr_array(sp.diags_array(1.0 / length) @ C)
    gaps = g / length
    size = float(np.abs(gaps).max())
    if size == 0.0:  # every gap 0: u = 0 meets every row, so no certificate exists
        return None
    y = _farkas(unit, gaps / size, equality)
    if y is None:
        return None
    total = float(gaps @ y)
    residual = float(np.abs(unit.T @ y).sum())
    if total >= 0.0 or residual * ABSURD_MOVE * size > -total:
        return None
    weights = y / length
    return weights / np.abs(weights).max()


def _farkas(C: sp.csr_array, g: np.ndarray, equality: np.ndarray) -> np.ndarray | None:
    """The y of least Σ|y| with Cᵀy = 0, gᵀy = −1, y >= 0 on the inequality rows, by HiGHS
    over the columns the rows touch; None where it finds none."""
    from scipy.optimize import linprog  # 0.2 s to import: only for a core of three rows or more

    m = g.size
    rows = sp.csc_array(C[:, np.unique(C.indices)].T)  # Cᵀ over the touched columns
    # y = y⁺ − y⁻, y⁻ = 0 on the inequality rows
    A = sp.vstack((sp.hstack((rows, -rows)), sp.csr_array(np.concatenate((g, -g))[None, :])))
    b = np.zeros(A.shape[0])
    b[-1] = -1.0
    bounds = [(0.0, None)] * m + [(0.0, None if e else 0.0) for e in equality]
    found = linprog(np.ones(2 * m), A_eq=A, b_eq=b, bounds=bounds, method="highs")
    if found.status != 0:
        return None
    y = found.x[:m] - found.x[m:]
    y[np.abs(y) <= 1e-12 * np.abs(y).max(initial=0.0)] = 0.0  # the LP's round-off
    y[~equality] = np.maximum(y[~equality], 0.0)
    return y


__all__ = ["ABSURD_MOVE", "conflicting_rows", "row_conflict"]
