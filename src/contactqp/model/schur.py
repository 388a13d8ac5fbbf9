"""The set solve of a sparse model (:class:`~contactqp.model.sparse.SparseModel`): the exact
answer with a set A of rows held on their gaps, from K's factorisation and the Schur
complement of the rows,

    W_AA λ_A = C_A u₀ − g_A,   W_AA = C_A K⁻¹ C_Aᵀ,   u = K⁻¹(P − C_Aᵀ λ_A),   u₀ = K⁻¹P,

(:func:`on_set`): W_AA comes from sparse forward solves, one per row that ever enters a set,
kept (:meth:`~contactqp.model.sparse.SparseModel.flexibility`); u is one solve with K per
set; the small dense W_AA is solved by Cholesky, scaled to a unit diagonal, or where rows
repeat each other's constraint (a redundant row) by its eigen-decomposition, for the
least-norm forces (:func:`small_solver`). Where K is singular and contact rows hold it, each
set is solved as the saddle-point system instead (:func:`saddle_solve`). Where K's factor is
CHOLMOD's, a set of independent rows is solved by its augmented matrix instead, one numeric
factorisation and no W_AA (:mod:`contactqp.model.augmented`). Lagrange's loop
(:mod:`contactqp.methods.schur`) and the check (:mod:`contactqp.check.on_set`) both solve
their sets here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from contactqp.errors import SolverError
from contactqp.model import saddle
from contactqp.model.augmented import augmented_set

SparseModel = Any  # the model these functions read (contactqp.model.sparse.SparseModel)

PSEUDO_INVERSE_RTOL = 1e-12  # eigenvalues of the scaled W_AA below this × the largest: redundant


def small_solver(W: np.ndarray) -> tuple[Callable[[np.ndarray], np.ndarray], bool]:
    """(a function rhs -> λ solving W λ = rhs, whether W is singular): W symmetric positive
    semidefinite (rows x rows), scaled to a unit diagonal, by Cholesky, or where a pivot
    falls below PSEUDO_INVERSE_RTOL (rows that repeat each other's constraint: redundant
    rows, whose forces the answer does not fix) the least-norm solution from the
    eigen-decomposition. (Not the eigen-decomposition always: on the benchmark's W
    it ran 100 times slower than on a random matrix of its size, 0.25 s at 80 rows, where
    Cholesky takes 0.2 ms.)"""
    diagonal = np.diagonal(W)
    if not np.all(diagonal > 0.0):
        raise SolverError("a contact row sees no flexibility (C_i K⁻¹ C_iᵀ <= 0)")
    import scipy.linalg  # at the first solve, not at start-up

    d = 1.0 / np.sqrt(diagonal)
    scaled = d[:, None] * W * d[None, :]
    try:
        factor = scipy.linalg.cho_factor(scaled, lower=True, check_finite=False)
        if np.diagonal(factor[0]).min() ** 2 > PSEUDO_INVERSE_RTOL:
            return (lambda rhs: d * scipy.linalg.cho_solve(factor, d * rhs, check_finite=False),
                    False)
    except np.linalg.LinAlgError:
        pass
    values, vectors = np.linalg.eigh(scaled)
    keep = values > PSEUDO_INVERSE_RTOL * values.max()
    vectors, values = vectors[:, keep], values[keep]
    return lambda rhs: d * (vectors @ ((vectors.T @ (d * rhs)) / values)), True


def small_solve(model: SparseModel, rows: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """W_AA⁻¹ rhs for the rows ``rows``: the solver of the last set asked for is kept (the
    loop's last set, the check's and each refinement step solve with the same W)."""
    if not rows.size:
        return np.zeros(0)
    key = rows.tobytes()
    cache = model.cache
    if cache.solver is None or cache.solver[0] != key:
        cache.solver = (key, *small_solver(model.flexibility(rows)))
    return cache.solver[1](rhs)


def redundant(model: SparseModel, rows: np.ndarray) -> bool:
    """Whether the rows' W_AA is singular: rows that repeat each other's constraint, so that
    the answer fixes their forces on the dofs, Cᵀλ, but not each row's."""
    if not rows.size or model.factor is None or augmented_set(model, rows) is not None:
        return False
    small_solve(model, rows, np.zeros(rows.size))
    return bool(model.cache.solver[2])


def on_set(model: SparseModel, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u on the free dofs, λ per row) with the rows in ``active`` held on their gaps and the
    others carrying nothing: the equality-constrained problem, exactly (module docstring)."""
    lam = np.zeros(model.n_contacts)
    rows = np.flatnonzero(active)
    if model.factor is None:  # K singular, held by contact rows: the saddle-point system
        u, lam[rows] = saddle_solve(model, rows, model.P, model.g[rows])
        return u, lam
    u0 = model.free_displacement
    if not rows.size:
        return u0.copy(), lam
    augmented = augmented_set(model, rows)
    if augmented is not None:  # one numeric factorisation, no W_AA
        u, lam[rows] = augmented.answer_on_set(model)
        return u, lam
    lam[rows] = small_solve(model, rows, model.C[rows] @ u0 - model.g[rows])
    return model.solve_K(model.P - model.C.T @ lam), lam


def saddle_solve(model: SparseModel, rows: np.ndarray, force: np.ndarray, gap: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(u, λ_rows) with K u + C_Aᵀλ = force and C_A u = gap, by the sparse saddle-point system
    (:func:`contactqp.model.saddle.set_solve`; rows that repeat a constraint regularised): for
    a K that only contact rows hold (no factorisation of K alone exists). A SolverError where
    the rows do not hold what it leaves free."""
    try:
        u, lam, _ = saddle.set_solve(model.K, model.C[rows], force, gap)
    except SolverError:
        raise SolverError(f"K is singular and the {rows.size} rows held do not hold what it "
                          "leaves free") from None
    return u, lam


def correction(model: SparseModel, rows: np.ndarray, residual: np.ndarray,
                       gap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(δλ, δu) with K δu + C_Aᵀδλ = r (a residual force on the free dofs) and C_A δu = s
    (``gap``, the rows' residual C_A u − g_A; default 0): δλ = W_AA⁻¹ (C_A K⁻¹ r − s),
    δu = K⁻¹(r − C_Aᵀ δλ) (two solves; the saddle-point system where K is singular)."""
    if model.factor is None:
        du, dlam = saddle_solve(model, rows, residual,
                                np.zeros(rows.size) if gap is None else gap)
        return dlam, du
    augmented = augmented_set(model, rows)
    if augmented is not None:
        # one Uzawa step: a correction's own error is 1/(1 + STIFFER) of it or less, and the
        # refinement that asks for it measures what is left (contactqp.check.on_set)
        du, dlam = augmented.solve(model, residual, np.zeros(rows.size) if gap is None else gap,
                                   steps=1)
        return dlam, du
    y = model.solve_K(residual)
    if not rows.size:
        return np.zeros(0), y
    rhs = model.C[rows] @ y - (0.0 if gap is None else gap)
    dlam = small_solve(model, rows, rhs)
    return dlam, model.solve_K(residual - model.C[rows].T @ dlam)


__all__ = ["correction", "on_set", "redundant", "saddle_solve", "small_solve", "small_solver"]
