"""The penalty method: K + ε CᵀC, P + ε Cᵀg; contact force = ε × penetration.

With unilateral contact the penalty acts only on the walls that are passed (iterated until the
set is stable). The answer always leaves a penetration of about λ/ε.
"""

from __future__ import annotations

import math

import numpy as np

from contactqp import linalg
from contactqp.errors import OptionError
from contactqp.methods._active_set import active_set_loop, displacement_tolerance
from contactqp.model import Model
from contactqp.result import Solution

DEFAULT_PENALTY = 1e14  # N/m, as in the textbook example


def penalty_value(penalty: float) -> float:
    """``penalty`` as a positive finite float, else an OptionError naming it."""
    try:
        value = float(penalty)
    except (TypeError, ValueError):
        raise OptionError(f"penalty must be a number (N/m), got {penalty!r}") from None
    if not (math.isfinite(value) and value > 0.0):
        raise OptionError(f"penalty must be a positive finite number (N/m), got {penalty!r}")
    return value


def solve_penalty(model: Model, contact: str, *, penalty: float = DEFAULT_PENALTY,
                  max_iterations: int | None = None) -> Solution:
    """Penalty ``penalty`` (ε, N/m); ``contact`` "equality" or "inequality"."""
    eps = penalty_value(penalty)
    K, P, C, g = model.K, model.P, model.C, model.g

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Ca = C[active]
        u = linalg.solve(K + eps * (Ca.T @ Ca), P + eps * (Ca.T @ g[active]), spd=True)
        lam = np.where(active, eps * (C @ u - g), 0.0)
        return u, lam

    if contact == "equality":
        u, lam = step(np.ones(model.n_contacts, dtype=bool))
        return Solution(u, lam, solver="penalty")

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        # a wall is added past +tol and released below −tol: without the band, a load that
        # just brings the node to the wall cycled (penetrated by round-off when open, pulled
        # by round-off when closed; found by benchmarks/run.py, case "touching")
        pen = C @ u - g
        tol = displacement_tolerance(u, g, P, K)
        return np.where(active, pen > -tol, pen > tol)

    u, lam, iterations = active_set_loop(model.n_contacts, step, update, method="penalty",
                                         max_iterations=max_iterations)
    return Solution(u, lam, solver="penalty", iterations=iterations)
