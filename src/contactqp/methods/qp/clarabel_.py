"""QP backend: Clarabel's own Python interface (an interior-point conic solver).

The rows go in as A x + s = b with s in the nonnegative cone (inequality) or the zero cone
(equality, and the strain formulation's tie rows); z is the dual of those rows, and Clarabel's KKT condition is P x + q + Aᵀz = 0.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import clarabel

from contactqp.methods.qp.outcome import QPOutcome, vector_or_nan

if TYPE_CHECKING:
    from contactqp.methods.qp.problem import QPProblem



def installed_solvers() -> tuple[str, ...]:
    return ("clarabel",)


def canonical(solver: str) -> str:
    return solver.lower()


def solve(qp: QPProblem, solver: str, settings: dict[str, Any],
          verbose: bool = False) -> QPOutcome:
    """Solve ``qp`` with Clarabel; ``settings`` are DefaultSettings attributes."""
    start = time.perf_counter()
    options = clarabel.DefaultSettings()
    options.verbose = verbose
    for key, value in settings.items():
        setattr(options, key, value)
    m, ties = qp.g.size, qp.n_ties
    cones = [clarabel.ZeroConeT(ties)] if ties else []
    if m:
        cones.append(clarabel.NonnegativeConeT(m) if qp.contact == "inequality"
                     else clarabel.ZeroConeT(m))
    engine = clarabel.DefaultSolver(qp.K_upper, qp.q, qp.rows(), qp.rows_rhs(), cones, options)
    setup = time.perf_counter()
    found = engine.solve()
    solved = time.perf_counter()
    status = str(found.status)
    return QPOutcome(
        vector_or_nan(found.x, qp.n), vector_or_nan(found.z, m + ties), status,
        claimed_success=status == "Solved", iterations=int(found.iterations),
        info={"time_setup": setup - start, "time_solve": solved - setup},
    )
