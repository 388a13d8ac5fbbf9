"""The penalty method: K + ε CᵀC, P + ε Cᵀg; contact force = ε × penetration.

With unilateral contact the penalty acts only on the walls that are passed (iterated until the
set is stable). The answer always leaves a penetration of about λ/ε.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import SolverError
from contactqp.methods import hull
from contactqp.methods._active_set import (
    DECISION_RTOL,
    active_set_loop,
    displacement_tolerance,
    pinning,
)
from contactqp.methods.base import Solution
from contactqp.methods.schur import pinning as sparse_pinning
from contactqp.model import Condensed, ContactModel, Model, wall_stiffness
from contactqp.model.augmented import penalised
from contactqp.model.base import PENALTY_PER_STIFFNESS
from contactqp.model.factor import factorise

TEXTBOOK_PENALTY = 1e14  # N/m, the textbook example's ε (in SI units: penalty=1e14)


def default_penalty(model: Model | Condensed) -> float:
    """ε = 1e6 × the stiffness the walls see (:func:`contactqp.model.wall_stiffness`), in the
    scene's units, so that it means the same in every unit system. The penalty's force error
    is about s/ε of the force (s the stiffness a wall sees): 3e-7 of F on the default scene
    (ε = 1.3e14 N/m, the textbook's order), and round-off in K + ε CᵀC grows with ε. Measured
    (force error / F; verified on 300 random scenes): 1e6 × s: 3.1e-7 on the default scene,
    9.7e-9 with a wall at each of 1e3 nodes, 228 of 300 verified; 1e8 × s: 2.9e-9, 0.27 (the
    round-off), 181 of 300. With a wall at each of 1e4 nodes or more no ε tried is right."""
    seen = wall_stiffness(model)
    return PENALTY_PER_STIFFNESS * (1.0 if seen is None else seen)


def solve_penalty(model: Model | Condensed, contact: str, *, penalty: float | None = None,
                  max_iterations: int | None = None) -> Solution:
    """Penalty ``penalty`` (ε, force per length in the scene's units; default
    :func:`default_penalty`); ``contact`` "equality" or "inequality"."""
    if model.layout is None:  # no chain: a penalty per row, one factorisation per set
        return _general(model, contact, penalty=penalty, max_iterations=max_iterations)
    eps = default_penalty(model) if penalty is None else penalty
    K, P, C, g = model.K, model.P, model.C, model.g

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Ca = C[active]
        u = linalg.solve(K + eps * (Ca.T @ Ca), P + eps * (Ca.T @ g[active]), spd=True)
        lam = np.where(active, eps * (C @ u - g), 0.0)
        return u, lam

    if contact == "equality":
        u, lam = step(np.ones(model.n_contacts, dtype=bool))
        return Solution(u, lam, solver="penalty", info={"penalty": eps})

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        # a wall is added past +tol and released below −tol: without the band, a load that
        # just brings the node to the wall cycled (penetrated by round-off when open, pulled
        # by round-off when closed; found by benchmarks/run.py, case "touching")
        pen = C @ u - g
        tol = displacement_tolerance(u, g, P, K)
        return np.where(active, pen > -tol, pen > tol)

    start, info = hull_start(model), {"penalty": eps}
    if start is not None:
        info["start"] = "the walls that push in the hull's answer"
    u, lam, iterations = active_set_loop(model.n_contacts, step, update, method="penalty",
                                         max_iterations=max_iterations, start=start,
                                         pin=pinning(model))
    return Solution(u, lam, solver="penalty", iterations=iterations, info=info)


def hull_start(model: Model | Condensed) -> np.ndarray | None:
    """The walls that push in the exact unilateral answer, as the hull loop finds it in O(n)
    (:mod:`contactqp.methods.hull`; walls only, every bar supported), or None where it does not
    apply. The penalty's loop from every wall open adds every passed wall at once and then
    releases a couple per step from the edges of a contact patch: 502 steps on an obstacle of
    10³ walls, 5000 on 10⁴ (measured); from the hull's set it settles in a few, at the same
    answer (the penalised energy is strictly convex: its minimum is the loop's one fixed
    point)."""
    found = hull.solve_on_chain(model, "inequality")
    if found is None:
        return None
    solution, reached = found
    return solution.contact_force > 0.0 if solution is not None else reached


def penalised_solve(model: ContactModel, eps: np.ndarray, cache: dict[bytes, Any]):
    """u(active, shift) = (K + C_AᵀE C_A)⁻¹ (P + C_Aᵀ shift_A): one factorisation per set
    (a numeric one on K's analysis where K's factor is CHOLMOD's)."""
    def solve(active: np.ndarray, shift: np.ndarray) -> np.ndarray:
        key = active.tobytes()
        if key not in cache:
            C_A = model.C[active]
            try:
                cache[key] = penalised(model, np.where(active, eps, 0.0)) or factorise(
                    sp.csc_matrix(model.K + C_A.T @ sp.diags_array(eps[active]) @ C_A))
            except RuntimeError:  # a zero pivot: K is singular along a mode no row in A holds
                raise SolverError(
                    f"K + εC_AᵀC_A is singular with {int(active.sum())} rows in contact: K "
                    "leaves a mode free that they do not hold (lagrange and qp solve a K held "
                    "by contact alone)") from None
        try:
            return cache[key].solve(model.P + model.C[active].T @ shift[active])
        except ArithmeticError:  # CHOLMOD: the penalised matrix is not positive definite
            raise SolverError(f"K + εC_AᵀC_A is not positive definite with {int(active.sum())} "
                              "rows in contact") from None
    return solve


def equalities(model: ContactModel, contact: str) -> np.ndarray:
    return model.equality | (contact == "equality")


def _general(model: ContactModel, contact: str, *, penalty: float | None = None,
             max_iterations: int | None = None) -> Solution:
    """The penalty on a model with no chain: K + C_AᵀE C_A on the rows passed (E = diag ε_i,
    ε_i = PENALTY_PER_STIFFNESS × s_i, s_i the stiffness row i sees,
    :attr:`~contactqp.model.base.ContactModel.row_stiffness`; a given ``penalty`` is one ε for
    every row), until the set of passed rows settles: one factorisation per set."""
    eps = (PENALTY_PER_STIFFNESS * model.row_stiffness if penalty is None
           else np.full(model.n_contacts, float(penalty)))
    solve, equality = penalised_solve(model, eps, {}), equalities(model, contact)
    g, U = model.g, model.displacement_scale

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = solve(active, eps * g)
        return u, np.where(active, eps * (model.C @ u - g), 0.0)

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        pen, tol = model.C @ u - g, DECISION_RTOL * U
        return np.where(active, pen > -tol, pen > tol) | equality

    # K singular (a body held by contact alone): each set holds what K leaves free, as
    # Lagrange's does (methods.schur.pinning), from the rows that hold it
    pin = sparse_pinning(model) if model.factor is None else None
    start = equality if pin is not None else equality | (model.C @ model.free_displacement > g)
    u, lam, iterations = active_set_loop(model.n_contacts, step, update, method="penalty",
                                         max_iterations=max_iterations, start=start, pin=pin)
    return Solution(u, lam, solver="penalty", iterations=iterations,
                    info={"penalty": float(eps.max(initial=0.0))})
