"""The sparse factorisations a user can install from wheels, as candidates for the floor
(benchmarks/scale.py) and for their comparison (benchmarks/factorisations.py): each a
factor() and a solve(factor, b) on K, whatever was needed to hand K over made beforehand (its
triangle, its format), so that only the factorisation and the solve are timed.

    superlu_colamd  scipy's SuperLU, COLAMD (scipy's default)
    superlu_mmd     scipy's SuperLU, minimum degree of Kᵀ + K, symmetric mode (contactqp's
                    fallback, contactqp.model.factor.factorise)
    qdldl           qdldl's LDLᵀ with AMD (OSQP's; a solve per right-hand side)
    cvxopt          CHOLMOD's supernodal Cholesky through cvxopt (contactqp's, the extra
                    ``cholmod``)
    kvxopt          the same CHOLMOD through kvxopt (a fork of cvxopt)
    cholespy        CHOLMOD through cholespy (its solve takes a block of right-hand sides)
    pardiso         PARDISO (MKL) through pypardiso, symmetric positive definite (mtype 2)
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

CANDIDATES = ("superlu_colamd", "superlu_mmd", "qdldl", "cvxopt", "kvxopt", "cholespy",
              "pardiso")


def factor_and_solve(name: str, K: sp.csc_matrix) -> tuple[Any, Any]:
    """(factor(), solve(factor, b)) of candidate ``name`` on K (b: a vector or n x k)."""
    n = K.shape[0]
    if name.startswith("superlu"):
        options = ({} if name == "superlu_colamd" else
                   {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.0,
                    "options": {"SymmetricMode": True}})
        return (lambda: spla.splu(K, **options)), (lambda factor, b: factor.solve(b))
    if name == "qdldl":
        import qdldl

        upper = sp.triu(K, format="csc")

        def solve_each(factor: Any, b: np.ndarray) -> np.ndarray:
            return (factor.solve(b) if b.ndim == 1
                    else np.column_stack([factor.solve(column) for column in b.T]))

        return (lambda: qdldl.Solver(upper, upper=True)), solve_each
    if name in ("cvxopt", "kvxopt"):
        base, cholmod = importlib.import_module(name), importlib.import_module(f"{name}.cholmod")
        lower = sp.tril(K, format="coo")
        held = base.spmatrix(lower.data, lower.row.tolist(), lower.col.tolist(), K.shape)

        def factor() -> Any:
            symbolic = cholmod.symbolic(held)
            cholmod.numeric(held, symbolic)
            return symbolic

        def solve(factor: Any, b: np.ndarray) -> np.ndarray:
            x = base.matrix(b)
            cholmod.solve(factor, x)
            return np.array(x).reshape(b.shape)

        return factor, solve
    if name == "cholespy":
        import cholespy

        lower = sp.csc_matrix(sp.tril(K))
        lower.sort_indices()

        def solve_block(factor: Any, b: np.ndarray) -> np.ndarray:
            b = np.ascontiguousarray(b)
            x = np.zeros_like(b)
            factor.solve(b, x)
            return x

        return (lambda: cholespy.CholeskySolverD(
            n, lower.indptr.astype(np.int32), lower.indices.astype(np.int32), lower.data,
            cholespy.MatrixType.CSC)), solve_block
    if name == "pardiso":
        import pypardiso

        upper = sp.triu(K, format="csr")
        upper.sort_indices()

        def factor_pardiso() -> Any:
            solver = pypardiso.PyPardisoSolver(mtype=2)
            solver.factorize(upper)
            return solver

        return factor_pardiso, (lambda factor, b: factor.solve(upper, b))
    raise ValueError(f"no candidate {name!r}")
