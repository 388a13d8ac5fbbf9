"""QP backend: OSQP's own Python interface (1.x API; ADMM, first order).

The rows go in as l <= A x <= u with l = −∞ (inequality) or l = u (equality, and the strain
formulation's tie rows); y is their dual,
and OSQP's KKT condition is P x + q + Aᵀy = 0 (y > 0 where the upper bound holds).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np
import osqp
import scipy.sparse as sp

from contactqp.methods.qp.outcome import QPOutcome, vector_or_nan

if TYPE_CHECKING:
    from contactqp.methods.qp.problem import QPProblem

SOLVED = "solved"  # OSQP's status text for success; "solved inaccurate" is not a claim


def installed_solvers() -> tuple[str, ...]:
    return ("osqp",)


def canonical(solver: str) -> str:
    return solver.lower()


def solve(qp: QPProblem, solver: str, settings: dict[str, Any],
          verbose: bool = False) -> QPOutcome:
    """Solve ``qp`` with OSQP; ``settings`` are OSQP settings (eps_abs, polishing, ...)."""
    start = time.perf_counter()
    upper = qp.rows_rhs()
    lower = upper.copy()
    if qp.contact == "inequality":
        lower[qp.n_ties:] = -np.inf
    engine = osqp.OSQP()
    engine.setup(sp.csc_matrix(qp.K_upper), qp.q, sp.csc_matrix(qp.rows()), lower,
                 upper, verbose=verbose, **settings)
    setup = time.perf_counter()
    found = engine.solve(raise_error=False)
    solved = time.perf_counter()
    status = str(found.info.status)
    return QPOutcome(
        vector_or_nan(found.x, qp.n), vector_or_nan(found.y, upper.size), status,
        claimed_success=status == SOLVED, iterations=int(found.info.iter),
        info={"time_setup": setup - start, "time_solve": solved - setup,
              "polish_status": int(found.info.status_polish)},
    )
