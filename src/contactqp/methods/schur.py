"""Lagrange multipliers on a sparse model: an active-set loop on the Schur complement.

With K factorised once (:class:`~contactqp.model.sparse.SparseModel`), the answer on a set A of
rows held on their gaps is

    W_AA λ_A = C_A u₀ − g_A,   W_AA = C_A K⁻¹ C_Aᵀ,   u = K⁻¹(P − C_Aᵀ λ_A),   u₀ = K⁻¹P,

(:func:`on_set`): W_AA comes from sparse forward solves, one per row that ever enters a set,
kept (:meth:`~contactqp.model.sparse.SparseModel.flexibility`); u is one solve with K per
set; the small dense W_AA is solved by Cholesky, scaled to a unit diagonal, or where rows
repeat each other's constraint (a redundant row) by its eigen-decomposition, for the
least-norm forces (:func:`small_solver`). Where K is singular and contact rows hold it, each
set is solved as the saddle-point system instead (:func:`saddle_solve`).

The loop (:func:`solve_schur`) is the primal–dual active set of the chain's Lagrange method:
from the rows that u₀ passes, a row enters where the answer passes its gap and leaves where its
force pulls, each by more than DECISION_RTOL of U or F (round-off is not contact); equality rows
are always in. At most max(ENTER_MIN, ENTER_FACTOR × the set's size) rows enter per step, the
deepest first, so that a load that passes many rows with no contact (a body pressed onto a
curved obstacle) does not solve for rows the answer leaves open. The answer ends with one
step of iterative refinement (:func:`refined`). On the benchmark grid (8.4·10⁴ dofs, 300
rows, 80 in contact): 5 sets, 88 rows solved for.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from contactqp.methods._active_set import DECISION_RTOL, ActiveSetCycle, active_set_loop
from contactqp.methods.base import Solution
from contactqp.methods.complementarity import LEMKE_ROWS, solve_lemke
from contactqp.model.schur import correction, on_set
from contactqp.model.sparse import SparseModel

ENTER_MIN = 64  # at least this many rows may enter in one step
ENTER_FACTOR = 1.0  # ... or this many times the set's size


def entering(model: SparseModel, active: np.ndarray, u: np.ndarray, lam: np.ndarray
             ) -> np.ndarray:
    """The next set (module docstring): rows that pull leave, rows that pass their gap enter,
    at most max(ENTER_MIN, ENTER_FACTOR × |set|) of the deepest per step."""
    F, U = model.force_scale, model.displacement_scale
    passed = model.C @ u - model.g
    # a held row the answer leaves open: the set's rows ask for gaps no u meets at once (a
    # looser parallel copy of a row, c·u <= 0.5 and 2c·u <= 1.5, both held), and W_AA's
    # least-norm solution misses both; the open one leaves
    keep = active & (((lam > -DECISION_RTOL * F) & (passed > -DECISION_RTOL * U))
                     | model.equality)
    candidates = np.flatnonzero(~active & (passed > DECISION_RTOL * U))
    limit = max(ENTER_MIN, int(ENTER_FACTOR * np.count_nonzero(keep)))
    if candidates.size > limit:  # the deepest first: a stiffness-weighted depth
        depth = passed[candidates] * model.row_stiffness[candidates]
        candidates = candidates[np.argsort(-depth, kind="stable")[:limit]]
    following = keep.copy()
    following[candidates] = True
    return following | model.equality


def solve_schur(model: SparseModel, contact: str = "inequality", *,
                max_iterations: int | None = None) -> Solution:
    """Lagrange multipliers by the active-set loop on the Schur complement (module
    docstring); ``contact="equality"`` holds every row on its gap."""
    equality = model.equality | (contact == "equality")
    if equality.all():
        u, lam = on_set(model, equality)
        return Solution(u, lam, solver="lagrange", info=_info(model))
    pin = None
    if model.factor is None:  # K singular: each set holds what K leaves free (pinning)
        pin = pinning(model)
        start = equality
    elif (start := equality | (model.C @ model.free_displacement - model.g > 0.0)
          ).sum() > ENTER_MIN:  # the deepest first, as every later step
        start = entering(model, equality, model.free_displacement, np.zeros(model.n_contacts))
    try:
        u, lam, iterations = active_set_loop(
            model.n_contacts, lambda active: on_set(model, active),
            lambda active, u, lam: entering(model, active, u, lam) | equality,
            method="lagrange", max_iterations=max_iterations, start=start, pin=pin)
    except ActiveSetCycle as cycle:  # dependent rows can make the loop come back
        if model.factor is None or model.n_contacts > LEMKE_ROWS or equality.any():
            raise
        solution = solve_lemke(model, contact)  # finite, and it cannot cycle
        return Solution(solution.u_free, solution.contact_force, solver="lagrange",
                        iterations=solution.iterations,
                        info={**_info(model), "active_set": f"passed, then Lemke's method "
                                                            f"({cycle})"})
    held = (lam != 0.0) | equality
    u, lam = refined(model, u, lam, np.flatnonzero(held if pin is None else pin(held)))
    return Solution(u, lam, solver="lagrange", iterations=iterations, info=_info(model))


HELD_RANK = 1e-10  # singular values of C_A X below this × the largest: a mode the set leaves free


def pinning(model: SparseModel) -> Callable[[np.ndarray], np.ndarray]:
    """For a K that leaves modes X free (:attr:`~contactqp.model.sparse.SparseModel.floating`,
    held by contact rows alone): a function that adds to a set the rows that stop each mode
    the set leaves free, in the direction the loads push it (both ways where they push it
    neither), the nearest first (the smallest gap per unit of motion), so that every set
    solved holds the body. A chain does the same bar by bar (:func:`contactqp.methods.
    _active_set.pinning`)."""
    modes = model.floating
    moves = model.C @ modes  # rows x modes: how each row closes as each mode moves
    push = modes.T @ model.P

    def pin(active: np.ndarray) -> np.ndarray:
        active = np.array(active, dtype=bool)
        for _ in range(2 * modes.shape[1] + 1):
            held = moves[active]
            _, sigma, vt = np.linalg.svd(held, full_matrices=True) if held.size else (
                None, np.zeros(0), np.eye(modes.shape[1]))
            rank = int(np.sum(sigma > HELD_RANK * max(float(np.abs(moves).max(initial=0.0)),
                                                       1e-300)))
            if rank == modes.shape[1]:
                return active
            free = vt[rank]
            ways = [np.sign(free @ push)] if free @ push != 0.0 else [1.0, -1.0]
            added = False
            for way in ways:
                closing = moves @ (way * free)
                candidates = np.flatnonzero(~active & (closing > HELD_RANK * np.abs(
                    closing).max(initial=0.0)))
                if candidates.size:
                    nearest = candidates[np.argmin(model.g[candidates] / closing[candidates])]
                    active[nearest] = added = True
            if not added:
                return active  # nothing stops it: the set solve says so
        return active
    return pin


def refined(model: SparseModel, u: np.ndarray, lam: np.ndarray, rows: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """One step of iterative refinement on the final set: the residuals K u − P + Cᵀλ (a
    product with K) and C_A u − g_A corrected (:func:`correction`, two solves). Where K mixes
    stiffnesses 1e6 apart, the set's first answer can leave a held row open by round-off
    of W_AA (2.3e-11 m past an element of 1e12 N/m: 46 N of 6.6e10 N); one step removes it."""
    residual = model.K @ u - model.P + model.C.T @ lam
    dlam, du = correction(model, rows, residual, model.C[rows] @ u - model.g[rows])
    lam = lam.copy()
    lam[rows] -= dlam
    return u - du, lam


def _info(model: SparseModel) -> dict[str, int]:
    return {"columns": model.cache.solves}


__all__ = ["refined", "solve_schur"]
