"""Contact rows that no displacement meets all at once, found with a certificate.

A :class:`~contactqp.Problem` refuses, when it is made, a row that is zero, a constraint given
twice and two parallel rows that leave no u (:func:`contactqp.problem.validated`). Three or
more rows can leave no u as well, e.g. a loop u₀ − u₁ <= g₀, u₁ − u₂ <= g₁, u₂ − u₀ <= g₂ with
g₀ + g₁ + g₂ < 0. Every method then fails in its own way (an active set that cycles, a
secondary ray, an answer the check does not verify), so when a solve fails the rows are tested
here and, if they leave no u, the solve ends with one line that names them.

By Farkas' lemma the rows C u <= g (inequality rows; equality rows C u = g) leave no u exactly
when some y, >= 0 on the inequality rows, has Cᵀy = 0 and gᵀy < 0: adding the rows with the
weights y gives 0 <= gᵀy. Rows whose gaps are all >= 0 (equality rows' = 0) are met by u = 0.
Otherwise such a y is looked for by a linear programme (scipy's HiGHS, only when a solve has
failed: importing scipy.optimize takes 0.2 s) over the rows, each scaled to unit length, and
the columns they touch; it is then checked in floating point rather than taken from the
solver's status: it is reported only if any u meeting the rows would have to move more than
:data:`ABSURD_MOVE` times the largest gap, |gᵀy| / ‖Cᵀy‖₁ (from (Cᵀy)ᵀu = yᵀC u <= gᵀy).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

ABSURD_MOVE = 1e9  # a u this many times the largest gap counts as no u at all
NAMED_ROWS = 6  # rows named in the message at most (the rest counted)


def conflicting_rows(C: sp.csr_array, g: np.ndarray, equality: np.ndarray,
                     names: tuple[str, ...]) -> str | None:
    """One line naming rows of C u (<= or =) g that no u meets all at once (module
    docstring), or None when no certificate of that is found. ``equality``: per row, held
    on its gap."""
    weights = _certificate(C, g, equality)
    if weights is None:
        return None
    rows = np.flatnonzero(weights)
    listed = ", ".join(f"{i} ({names[i]})" for i in rows[:NAMED_ROWS])
    more = f" and {rows.size - NAMED_ROWS} more" if rows.size > NAMED_ROWS else ""
    y = ", ".join(f"{weights[i]:.3g}" for i in rows[:NAMED_ROWS])
    return (f"C rows {listed}{more} leave no u that meets them all: weighted by y = [{y}"
            f"{', ...' if more else ''}] they add up to 0·u <= {float(g @ weights):.6g} "
            "(their gaps so weighted), which no u can meet; check these rows' gaps and signs")


def _certificate(C: sp.csr_array, g: np.ndarray, equality: np.ndarray) -> np.ndarray | None:
    """y (module docstring) for the rows as given, checked in floating point, or None."""
    if not (np.any(g[~equality] < 0.0) or np.any(g[equality] != 0.0)):
        return None  # u = 0 meets every row
    # each row scaled to unit length, so that u is measured against the gaps
    length = np.sqrt(np.asarray(C.multiply(C).sum(axis=1)).reshape(-1))
    unit = sp.csr_array(sp.diags_array(1.0 / length) @ C)
    gaps = g / length
    size = float(np.abs(gaps).max())
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
    from scipy.optimize import linprog  # 0.2 s to import: only once a solve has failed

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


__all__ = ["ABSURD_MOVE", "conflicting_rows"]
