"""QP backend: qpsolvers, one front end to many solvers (``qpsolvers.available_solvers``).

The rows go in as G x <= h (inequality, dual z >= 0) or A x = b (equality and the strain
formulation's tie rows, dual y); qpsolvers'
KKT condition is P x + q + Gᵀz + Aᵀy = 0. Its Solution says ``found``; that is the claim.
"""

from __future__ import annotations

import time
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from contactqp.methods.qp.outcome import QPOutcome, vector_or_nan

if TYPE_CHECKING:
    from contactqp.methods.qp.problem import QPProblem

DENSE_INPUT = {"quadprog"}  # refuses sparse matrices
# Settings each solver needs whatever the accuracy: ProxQP's sparse backend (never a dense K);
# OSQP's raise_error=False (a failure is a status, as for every backend, and no warning).
FIXED_SETTINGS = {"proxqp": {"backend": "sparse"}, "osqp": {"raise_error": False}}


def installed_solvers() -> tuple[str, ...]:
    return tuple(qpsolvers.available_solvers)


def canonical(solver: str) -> str:
    return solver.lower()


def _status(found: qpsolvers.Solution) -> str:
    """'found' or 'not found', with the solver's own status where qpsolvers keeps it."""
    text = "found" if found.found else "not found"
    extras = found.extras or {}
    for raw in (extras.get("status"), extras.get("infostring"),
                getattr(extras.get("info"), "status", None)):
        if raw is not None and np.ndim(raw) == 0:
            return f"{text} ({raw})"
    return text


def solve(qp: QPProblem, solver: str, settings: dict[str, Any],
          verbose: bool = False) -> QPOutcome:
    """Solve ``qp`` with qpsolvers' ``solver``; ``settings`` go to that solver as keywords."""
    start = time.perf_counter()
    inequality = qp.contact == "inequality"
    if inequality:  # walls in G x <= h, tie rows (if any) in A x = 0
        G, h = qp.C, qp.g
        A, b = (qp.ties, np.zeros(qp.n_ties)) if qp.ties is not None else (None, None)
    else:  # ties and walls together in A x = b
        G, h, A, b = None, None, qp.rows(), qp.rows_rhs()
    K, G, A = (None if M is None else sp.csc_matrix(M) for M in (qp.K, G, A))
    if solver in DENSE_INPUT:
        K, G, A = (None if M is None else M.toarray() for M in (K, G, A))
    problem = qpsolvers.Problem(K, qp.q, G=G, h=h, A=A, b=b)
    setup = time.perf_counter()
    options = {**FIXED_SETTINGS.get(solver, {}), **settings}
    with warnings.catch_warnings(record=not verbose) as said:
        # a solver's warning (ECOS: "inaccurate results") goes into the status, not to stderr:
        # the library prints nothing unless asked, and the check decides
        found = qpsolvers.solve_problem(problem, solver=solver, verbose=verbose, **options)
    solved = time.perf_counter()
    status = _status(found)
    if said:
        status += "; " + "; ".join(dict.fromkeys(str(w.message) for w in said))
    # qp.rows() order: ties (in A) then walls (in G for inequality, after the ties in A else)
    dual = np.concatenate((_part(found.y, qp.n_ties), _part(found.z, qp.g.size))) if inequality \
        else found.y
    iterations = _iterations(found.extras or {})
    return QPOutcome(
        vector_or_nan(found.x, qp.n), vector_or_nan(dual, qp.n_ties + qp.g.size), status,
        claimed_success=bool(found.found), iterations=iterations,
        info={"time_setup": setup - start, "time_solve": solved - setup},
    )


def _part(values: Any, size: int) -> np.ndarray:
    """A dual vector of ``size`` entries (empty when size is 0, NaNs when the solver gave none)."""
    if size == 0:
        return np.zeros(0)
    return vector_or_nan(values, size)


def _iterations(extras: dict[str, Any]) -> int:
    """The iteration count where qpsolvers keeps the solver's own info (0 when it does not)."""
    for key in ("iter", "iterations", "num_iters", "iter_count"):
        if np.ndim(extras.get(key)) == 0 and extras.get(key) is not None:
            return int(extras[key])
    info = extras.get("info")
    for key in ("iter", "iterations", "num_iters"):
        value = getattr(info, key, None) if not isinstance(info, dict) else info.get(key)
        if value is not None and np.ndim(value) == 0:
            return int(value)
    return 0
