"""The set solve of a model with a few rows, or of a chain: the saddle-point system
[[K, C_Aᵀ], [C_A, 0]] [u; λ_A] = [force; gap] by one sparse LU, ordered so that a chain's is
banded (:func:`banded_order`). It is the set solve the protocol offers where a model has no
faster one (:meth:`contactqp.model.base.ContactModel.set_solve`), and Lagrange's step on a
chain (:mod:`contactqp.methods.lagrange`).

Rows that repeat each other's constraint (a node held by walls on both sides with zero gaps, a
loop of bar contacts) leave the system singular: their forces are not unique, only Cᵀλ is.
Then the rows' block is regularised by −ε·I (ε = REDUNDANT_SHIFT of the rows' scale) and the
answer refined on the system itself, which gives λ near the least-norm forces, and the set is
said to be redundant (the check then compares Cᵀλ).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import SolverError

REDUNDANT_SHIFT = 1e-10  # −ε·I of the rows' block where they repeat a constraint
REFINE_STEPS = 3  # iterative refinement of a regularised solve


def saddle_point_system(K: sp.sparray, C: sp.sparray) -> sp.csr_array:
    """The sparse saddle-point matrix [[K, Cᵀ], [C, 0]], assembled from the entries (scipy's
    block_array took ~0.6 ms per active-set step on the 4-element default scene)."""
    n, m = K.shape[0], C.shape[0]
    Kc, Cc = sp.coo_array(K), sp.coo_array(C)
    row = np.concatenate((Kc.row, Cc.col, n + Cc.row))
    col = np.concatenate((Kc.col, n + Cc.row, Cc.col))
    data = np.concatenate((Kc.data, Cc.data, Cc.data))
    return sp.csr_array(sp.coo_array((data, (row, col)), shape=(n + m, n + m)))


def banded_order(C: sp.csr_array, n: int) -> np.ndarray:
    """An ordering of [D; λ] that puts each multiplier right after the last unknown of its
    row, so that the saddle-point matrix of a chain is banded."""
    last = np.maximum.reduceat(C.indices, C.indptr[:-1]) if C.shape[0] else np.zeros(0, int)
    keys = np.concatenate((2 * np.arange(n), 2 * last + 1))
    return np.argsort(keys, kind="stable")


def solve_saddle_point(K: sp.sparray, P: np.ndarray, C: sp.csr_array,
                       g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve [[K, Cᵀ], [C, 0]] [D; λ] = [P; g] in one sparse solve; returns (D, λ).

    The rows of C (and g) are solved scaled by the power of 2 nearest above K's largest
    diagonal entry, and λ scaled back: the same system exactly, but its LU pivots weigh the
    contact rows as K's own (measured: a random scene of two bars with elements of 1.7e5 to
    2.8e12 N/m, a wall and a bar contact active, unscaled: a wall's force 44 N off of 35 kN and
    its node 1.2e-9 m off its gap; scaled: 3e-5 N and at the gap)."""
    n = K.shape[0]
    scale = row_scale(K)
    x = linalg.solve(saddle_point_system(K, C * scale), np.concatenate((P, g * scale)),
                     order=banded_order(C, n))
    return x[:n], x[n:] * scale


def row_scale(K: sp.sparray) -> float:
    """The power of 2 nearest above K's largest diagonal entry (1 for an empty or zero K): the
    contact rows' scale in a saddle-point solve (scaling by it is exact)."""
    top = float(np.abs(K.diagonal()).max(initial=0.0))
    return float(np.ldexp(1.0, np.frexp(top)[1])) if 0.0 < top < np.inf else 1.0


DEPENDENT = 1e-10  # a pivot of the rows' unit-diagonal Gram matrix below this: rows repeat


def rows_dependent(C_A: sp.csr_array) -> bool:
    """Whether some rows of C_A are a combination of others (they repeat a constraint, and
    their forces are not unique): a pivot of C_A C_Aᵀ, scaled to a unit diagonal, below
    DEPENDENT (sparse LU; on a chain C_A C_Aᵀ is banded). A banded LU of the saddle-point
    system need not say so: round-off leaves its pivot 1e-16 instead of 0, and the answer
    carries forces of 1e5 that cancel (measured: walls on both sides of a node)."""
    return gram_factor(C_A) is None


def gram_factor(C_A: sp.csr_array) -> tuple[Any, np.ndarray] | None:
    """(the sparse LU of C_A C_Aᵀ scaled to a unit diagonal, that scale s): (C_A C_Aᵀ)⁻¹b =
    s · LU⁻¹(s · b); None where the rows are dependent (:func:`rows_dependent`)."""
    diagonal = _disjoint_rows(C_A)
    if diagonal is not None:  # rows that share no dof: C_A C_Aᵀ is its diagonal
        scale = 1.0 / np.sqrt(diagonal)
        return DiagonalFactor(diagonal * scale * scale), scale
    gram = sp.csc_matrix(C_A @ C_A.T)
    if not np.all(gram.diagonal() > 0.0):  # a row with no entry: dependent on any other
        return None
    scale = 1.0 / np.sqrt(gram.diagonal())
    gram = sp.csc_matrix(sp.diags_array(scale) @ gram @ sp.diags_array(scale))
    import scipy.sparse.linalg as spla  # at the first solve, not at start-up

    try:
        factor = spla.splu(gram, diag_pivot_thresh=1.0)
    except RuntimeError:  # "Factor is exactly singular"
        return None
    if np.abs(factor.U.diagonal()).min(initial=1.0) < DEPENDENT:
        return None
    return factor, scale


def _disjoint_rows(C_A: sp.csr_array) -> np.ndarray | None:
    """C_A C_Aᵀ's diagonal where the rows share no dof (C_A C_Aᵀ is then diagonal: a contact
    row per node and direction, as the Hertz models write them), each entry above 0 and finite;
    else None. Measured: splu of that diagonal took 0.8 ms a set on the 5 106-dof sphere (54
    rows held; this, 0.06 ms), twice in lagrange's 60 ms with its check."""
    C_A = sp.csr_array(C_A)
    if not C_A.has_canonical_format:
        return None
    if np.unique(C_A.indices).size != C_A.indices.size:
        return None
    if not C_A.shape[0] or np.diff(C_A.indptr).min() == 0:  # an empty row
        return None
    diagonal = np.add.reduceat(C_A.data**2, C_A.indptr[:-1])
    return diagonal if np.all(diagonal > 0.0) and np.all(np.isfinite(diagonal)) else None


@dataclass(frozen=True, eq=False)
class DiagonalFactor:
    """The factor of a diagonal matrix: what :func:`gram_factor` gives for rows that share no
    dof, whose ``solve`` divides by the diagonal as the LU of that matrix would."""

    diagonal: np.ndarray

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        return b / (self.diagonal if b.ndim == 1 else self.diagonal[:, None])


def set_solve(K: sp.sparray, C_A: sp.csr_array, force: np.ndarray, gap: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, bool]:
    """(u, λ_A, redundant) with K u + C_Aᵀλ_A = force and C_A u = gap (module docstring); a
    SolverError where K and the rows leave a mode free."""
    n = K.shape[0]
    if C_A.shape[0] == 0:
        return linalg.solve(K, force, spd=True), np.zeros(0), False
    if not rows_dependent(C_A):
        try:
            u, lam = solve_saddle_point(K, force, C_A, gap)
            return u, lam, False
        except SolverError:  # K singular along a mode the rows leave free
            pass
    scale = row_scale(K)
    matrix = saddle_point_system(K, C_A * scale)
    shift = REDUNDANT_SHIFT * scale
    regular = (matrix - sp.diags_array(np.concatenate((np.zeros(n), np.full(C_A.shape[0],
                                                                             shift))))).tocsr()
    rhs = np.concatenate((force, gap * scale))
    order = banded_order(C_A, n)
    x = linalg.solve(regular, rhs, order=order)
    for _ in range(REFINE_STEPS):  # on the system itself: the regularisation's error out
        x = x + linalg.solve(regular, rhs - matrix @ x, order=order)
    return x[:n], x[n:] * scale, True


__all__ = ["DEPENDENT", "REDUNDANT_SHIFT", "DiagonalFactor", "banded_order", "gram_factor",
           "row_scale", "rows_dependent", "saddle_point_system", "set_solve",
           "solve_saddle_point"]
