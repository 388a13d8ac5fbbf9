"""The penalty, the augmented Lagrangian and the QP backends on a sparse model (a user's own
K, f, C, g; :mod:`contactqp.model.sparse`). Lagrange is :mod:`contactqp.methods.schur`; the
complementarity methods take a sparse model as they take a chain (:mod:`~contactqp.methods.
complementarity`, W = C K⁻¹ Cᵀ dense up to its stated size).

The penalty's ε is per row: PENALTY_PER_STIFFNESS times the stiffness the row sees (s_i =
c_iᵀK c_i / (c_iᵀc_i)², :attr:`~contactqp.model.sparse.SparseModel.row_stiffness`), so it
means the same in every unit system and on every mesh; the augmented Lagrangian's is
AUGMENTED_PER_STIFFNESS times it. The QP is the model's, scaled by F and U as a scene's is.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import OptionError, SolverError
from contactqp.methods._active_set import DECISION_RTOL, active_set_loop
from contactqp.methods.augmented import DEFAULT_MAX_ITERATIONS, DEFAULT_TOLERANCE
from contactqp.methods.qp import DEFAULT_BACKEND, attempted, resolve_solver
from contactqp.methods.qp.problem import QPProblem
from contactqp.methods.qp.settings import accuracy_settings
from contactqp.model.sparse import SparseModel, factorise
from contactqp.result import Solution

PENALTY_PER_STIFFNESS = 1e6  # the penalty's ε_i: this many times the stiffness row i sees
AUGMENTED_PER_STIFFNESS = 100.0  # the augmented Lagrangian's


def _penalised_solve(model: SparseModel, eps: np.ndarray, cache: dict[bytes, Any]):
    """u(active, shift) = (K + C_AᵀE C_A)⁻¹ (P + C_Aᵀ shift_A): one factorisation per set."""
    def solve(active: np.ndarray, shift: np.ndarray) -> np.ndarray:
        key = active.tobytes()
        if key not in cache:
            C_A = model.C[active]
            try:
                cache[key] = factorise(sp.csc_matrix(
                    model.K + C_A.T @ sp.diags_array(eps[active]) @ C_A))
            except RuntimeError:  # a zero pivot: K is singular along a mode no row in A holds
                raise SolverError(
                    f"K + εC_AᵀC_A is singular with {int(active.sum())} rows in contact: K "
                    "leaves a mode free that they do not hold (lagrange and qp solve a K held "
                    "by contact alone)") from None
        return cache[key].solve(model.P + model.C[active].T @ shift[active])
    return solve


def _equalities(model: SparseModel, contact: str) -> np.ndarray:
    return model.equality | (contact == "equality")


def solve_penalty(model: SparseModel, contact: str, *, penalty: float | None = None,
                  max_iterations: int | None = None) -> Solution:
    """The penalty: K + C_AᵀE C_A on the rows passed (E = diag ε_i, module docstring; a given
    ``penalty`` is one ε for every row), until the set of passed rows settles."""
    eps = (PENALTY_PER_STIFFNESS * model.row_stiffness if penalty is None
           else np.full(model.n_contacts, float(penalty)))
    solve, equality = _penalised_solve(model, eps, {}), _equalities(model, contact)
    g, U = model.g, model.displacement_scale

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = solve(active, eps * g)
        return u, np.where(active, eps * (model.C @ u - g), 0.0)

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        pen, tol = model.C @ u - g, DECISION_RTOL * U
        return np.where(active, pen > -tol, pen > tol) | equality

    u, lam, iterations = active_set_loop(model.n_contacts, step, update, method="penalty",
                                         max_iterations=max_iterations,
                                         start=equality | (model.C @ model.free_displacement > g))
    return Solution(u, lam, solver="penalty", iterations=iterations,
                    info={"penalty": float(eps.max(initial=0.0))})


def solve_augmented(model: SparseModel, contact: str, *, penalty: float | None = None,
                    tolerance: float = DEFAULT_TOLERANCE,
                    max_iterations: int = DEFAULT_MAX_ITERATIONS) -> Solution:
    """The augmented Lagrangian (Uzawa) with ε_i (module docstring): for fixed λ the set of
    rows with λ_i + ε_i(C_i u − g_i) > 0 is settled, then λ ← max(0, that) (equality rows: no
    max), until an update changes λ by at most ``tolerance`` × max(‖λ‖, F)."""
    eps = (AUGMENTED_PER_STIFFNESS * model.row_stiffness if penalty is None
           else np.full(model.n_contacts, float(penalty)))
    solve, equality = _penalised_solve(model, eps, {}), _equalities(model, contact)
    lam, F = np.zeros(model.n_contacts), model.force_scale

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = solve(active, eps * model.g - lam)
        return u, lam + eps * (model.C @ u - model.g)

    def update(active: np.ndarray, u: np.ndarray, trial: np.ndarray) -> np.ndarray:
        band = DECISION_RTOL * max(float(np.abs(trial).max(initial=0.0)), F)
        return np.where(active, trial > -band, trial > band) | equality

    previous = np.inf
    for iteration in range(1, max_iterations + 1):
        u, trial, _ = active_set_loop(model.n_contacts, step, update, method="augmented",
                                      start=equality | (lam > 0.0))
        new_lam = np.where(equality, trial, np.maximum(trial, 0.0))
        change = float(np.abs(new_lam - lam).max(initial=0.0))
        lam = new_lam
        converged = change <= tolerance * max(float(np.abs(lam).max(initial=0.0)), F)
        if converged or (change >= previous and iteration > 2):
            status = "solved" if converged else "stalled at round-off"
            return Solution(u, lam, solver="augmented", iterations=iteration, status=status,
                            info={"penalty": float(eps.max(initial=0.0))})
        previous = change
    return Solution(u, lam, solver="augmented", iterations=max_iterations,
                    status=f"not converged in {max_iterations} updates", claimed_success=False)


def qp_from_sparse(model: SparseModel, contact: str, scale: bool = True) -> QPProblem:
    """The QP of a sparse model, scaled by its F and U (x = u / U, multipliers λ / F) as a
    scene's QP is; mixed inequality and equality rows are refused (the backends take one
    kind of row)."""
    equality = model.equality
    if equality.any() and not equality.all() and contact != "equality":
        raise OptionError("qp: the QP backends take rows of one kind, and this problem mixes "
                          "inequality and equality rows (use lagrange, penalty or augmented)")
    kind = "equality" if contact == "equality" or equality.all() else "inequality"
    U, F = (model.displacement_scale, model.force_scale) if scale else (1.0, 1.0)
    return QPProblem(K=sp.csc_array(model.K / (F / U)), q=-model.P / F,
                     C=sp.csc_array(model.C), g=model.g / U, contact=kind,
                     displacement_scale=U, force_scale=F)


def solve_qp(model: SparseModel, contact: str, *, backend: str = DEFAULT_BACKEND,
             solver: str | None = None, accuracy: str = "default", scale: bool = True,
             verbose: bool = False) -> Solution:
    """A QP backend on the model's QP (:func:`qp_from_sparse`); its duals are the contact
    forces (:func:`contactqp.methods.qp.solve_qp` for the options)."""
    module, name = resolve_solver(backend, solver)
    settings = accuracy_settings(name, accuracy, scaled=scale, backend=backend)
    start = time.perf_counter()
    qp = qp_from_sparse(model, contact, scale)
    built = time.perf_counter()
    outcome = attempted(module, backend, name, qp, settings, verbose)
    u_free, contact_force = qp.to_si(outcome.x, np.asarray(outcome.dual, dtype=float))
    label = backend if name == backend else f"{backend}/{name}"
    info = {"backend": backend, "solver": name, "accuracy": accuracy, "scale": bool(scale),
            "time_qp_data": built - start, **outcome.info}
    return Solution(u_free, contact_force, solver=label, iterations=int(outcome.iterations),
                    status=outcome.status, claimed_success=bool(outcome.claimed_success),
                    info=info)


__all__ = ["AUGMENTED_PER_STIFFNESS", "PENALTY_PER_STIFFNESS", "qp_from_sparse",
           "solve_augmented", "solve_penalty", "solve_qp"]
