"""Explicit Lagrange multipliers: the saddle-point system [[K, Cᵀ], [C, 0]] [D; λ] = [P; g].

Unilateral contact is an active-set loop on the same system: walls whose node is past them are
added, walls that pull (λ < 0) are released, until the set is stable.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.methods._active_set import active_set_loop
from contactqp.model import Model
from contactqp.result import Solution

# An active-set decision ignores penetrations and pulls below this fraction of the
# displacement and force scales: round-off, not contact.
DECISION_RTOL = 1e-12


def saddle_point_system(K: sp.sparray, C: sp.sparray) -> sp.csr_array:
    """The sparse saddle-point matrix [[K, Cᵀ], [C, 0]]."""
    return sp.csr_array(sp.block_array([[K, C.T], [C, None]], format="csr"))


def banded_order(C: sp.csr_array, n: int) -> np.ndarray:
    """An ordering of [D; λ] that puts each multiplier right after the last unknown of its
    row, so that the saddle-point matrix of a chain is banded."""
    last = np.maximum.reduceat(C.indices, C.indptr[:-1]) if C.shape[0] else np.zeros(0, int)
    keys = np.concatenate((2 * np.arange(n), 2 * last + 1))
    return np.argsort(keys, kind="stable")


def solve_saddle_point(K: sp.sparray, P: np.ndarray, C: sp.csr_array,
                       g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve [[K, Cᵀ], [C, 0]] [D; λ] = [P; g] in one sparse solve; returns (D, λ)."""
    n = K.shape[0]
    x = linalg.solve(saddle_point_system(K, C), np.concatenate((P, g)), order=banded_order(C, n))
    return x[:n], x[n:]


def solve_lagrange(model: Model, contact: str, *, max_iterations: int | None = None) -> Solution:
    """Lagrange multipliers; ``contact`` "equality" (every wall holds) or "inequality"."""
    K, P, C, g = model.K, model.P, model.C, model.g

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u, lam_active = solve_saddle_point(K, P, C[active], g[active])
        lam = np.zeros(model.n_walls)
        lam[active] = lam_active
        return u, lam

    if contact == "equality":
        u, lam = step(np.ones(model.n_walls, dtype=bool))
        return Solution(u, lam, solver="lagrange")

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        pen = C @ u - g
        # |P| / max diag K keeps the scale physical when the exact u is 0 (closed zero gaps)
        disp_tol = DECISION_RTOL * max(np.abs(u).max(initial=0.0), np.abs(g).max(initial=0.0),
                                       np.abs(P).max(initial=0.0) / K.diagonal().max())
        force_tol = DECISION_RTOL * max(np.abs(P).max(initial=0.0), np.abs(lam).max(initial=0.0))
        return np.where(active, lam > -force_tol, pen > disp_tol)

    u, lam, iterations = active_set_loop(model.n_walls, step, update, method="lagrange",
                                         max_iterations=max_iterations)
    return Solution(u, lam, solver="lagrange", iterations=iterations)
