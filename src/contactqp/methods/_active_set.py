"""One active-set loop for every method that enforces unilateral contact by equalities."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from contactqp.errors import SolverError

Step = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
Update = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


# An active-set decision ignores penetrations and pulls below this fraction of the
# displacement and force scales: round-off, not contact.
DECISION_RTOL = 1e-12


def displacement_tolerance(u: np.ndarray, g: np.ndarray, P: np.ndarray, K) -> float:
    """DECISION_RTOL of the displacement scale max(‖u‖, ‖g‖, ‖P‖ / max diag K): the last term
    keeps it physical when the exact u is 0 (closed zero gaps)."""
    return DECISION_RTOL * max(np.abs(u).max(initial=0.0), np.abs(g).max(initial=0.0),
                               np.abs(P).max(initial=0.0) / K.diagonal().max())


class ActiveSetCycle(SolverError):
    """The active-set loop came back to a set it had left."""


def default_max_iterations(n_rows: int) -> int:
    return 50 + 2 * n_rows




def active_set_loop(n_rows: int, step: Step, update: Update, *, method: str,
                    max_iterations: int | None = None,
                    start: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Iterate ``active -> step(active) = (u, λ) -> update(active, u, λ)`` to a fixed point.

    Starts from ``start`` (default: every wall open). Returns (u, λ, iterations). It
    terminates: a set that comes back (a cycle) or more than ``max_iterations`` steps is a
    SolverError that says so.
    """
    limit = default_max_iterations(n_rows) if max_iterations is None else int(max_iterations)
    active = np.zeros(n_rows, dtype=bool) if start is None else np.asarray(start, dtype=bool)
    seen = {active.tobytes()}
    for iteration in range(1, limit + 1):
        u, lam = step(active)
        following = update(active, u, lam)
        if np.array_equal(following, active):
            return u, lam, iteration
        key = following.tobytes()
        if key in seen:
            raise ActiveSetCycle(
                f"{method}: the active-set loop cycles (walls in contact "
                f"{np.flatnonzero(following).tolist()} came back after {iteration} steps)"
            )
        seen.add(key)
        active = following
    raise SolverError(f"{method}: the active-set loop did not settle in {limit} steps")
