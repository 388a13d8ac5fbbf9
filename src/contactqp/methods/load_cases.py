"""Lagrange multipliers and the penalty over many load cases at once: one factorisation of K,
every case's free displacement from it, and each case's active set decided on the contact
rows alone.

With u = K⁻¹(P − Cᵀλ), every case is a problem in its contact forces only: the flexibility
W = C K⁻¹ Cᵀ (rows x rows, the same for every case) and q = C K⁻¹P − g (per case, the
penetration the loads would cause with no contact). A set A of held rows gives
(W_AA + I/ε) λ_A = q_A (1/ε = 0 for Lagrange multipliers, whose held rows close exactly; the
penalty's rows penetrate by λ/ε), and the cases that hold the same rows share that small
system. The active set moves as the single-case loops move it
(:mod:`contactqp.methods.lagrange`'s textbook loop, :mod:`contactqp.methods.penalty`): rows that
pull are released and rows passed are added, with the same tolerances. The answer is the same
equations' answer as the single-case methods give, found another way; it is checked as every
answer is. A case whose rows come out dependent (a singular W_AA) or whose set does not settle
is marked unsettled, for the caller to solve on its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.methods._active_set import DECISION_RTOL, default_max_iterations
from contactqp.methods.complementarity import flexibility
from contactqp.model import Model

CASES_ROWS = 64  # contact rows up to which the cases are solved together (W is rows x rows;
# a case's set of held rows is one 64-bit key)
CASES_ENTRIES = 2**22  # ... and free nodes x rows, the dense K⁻¹Cᵀ it builds (32 MB)
FEW_COLUMNS = 32  # up to this many columns, numpy reduces a row faster down a transposed copy
# (measured: 10⁴ x 4, 0.03 ms against 0.4 ms along the short rows; even at 32 columns)


def row_reduce(reduce: np.ufunc, values: np.ndarray, **initial: float) -> np.ndarray:
    """``reduce.reduce(values, axis=1, **initial)`` (np.maximum or np.minimum: the same
    numbers in any order): for a few columns, down the columns of a transposed copy, since
    numpy reduces along short rows one row at a time."""
    if values.shape[1] <= FEW_COLUMNS:
        return reduce.reduce(np.ascontiguousarray(values.T), axis=0, **initial)
    return reduce.reduce(values, axis=1, **initial)


def fits(model: Model) -> bool:
    """Whether :func:`solve_cases` takes the model: few contact rows (W is dense), and K⁻¹
    (no bar held by contact alone, :attr:`Model.floating`)."""
    return (0 < model.n_contacts <= CASES_ROWS and model.n_free * model.n_contacts <= CASES_ENTRIES
            and not model.floating)


@dataclass(frozen=True)
class CasesSolution:
    """The free nodes' displacements (cases x free nodes), the contact forces (cases x rows),
    the active-set steps of each case and whether its set settled; and K⁻¹P of each case."""

    u_free: np.ndarray
    contact_force: np.ndarray
    iterations: np.ndarray
    settled: np.ndarray
    free_displacement: np.ndarray


def solve_cases(model: Model, contact: str, loads: np.ndarray, gaps: np.ndarray, *,
                penalty: float | None = None, max_iterations: int | None = None,
                shared: tuple[np.ndarray, np.ndarray] | None = None) -> CasesSolution:
    """Every case of ``loads`` (cases x free nodes, the nodal loads P) and ``gaps`` (cases x
    rows): by Lagrange multipliers (``penalty`` None) or the penalty ε (module docstring).
    ``shared``: :func:`contactqp.methods.complementarity.flexibility` of the model, when the
    caller keeps it."""
    C = model.C
    flexibility_columns, W = flexibility(model) if shared is None else shared
    u_free = model.solve_K(loads.T).T  # K⁻¹P of every case
    q = (C @ u_free.T).T - gaps
    cases, rows = q.shape
    soft = 0.0 if penalty is None else 1.0 / penalty
    if contact == "equality":
        active = np.ones((cases, rows), dtype=bool)
        lam, singular = _held_forces(W, soft, q, active)
        return CasesSolution(u_free - lam @ flexibility_columns.T, lam, np.ones(cases, int),
                             ~singular, u_free)
    # the single-case loops' tolerances (contactqp.methods._active_set), per case
    load_size = row_reduce(np.maximum, np.abs(loads), initial=0.0)
    floor = np.maximum(row_reduce(np.maximum, np.abs(gaps), initial=0.0),
                       load_size / model.band[0].max(initial=1.0))
    limit = default_max_iterations(rows) if max_iterations is None else int(max_iterations)
    active = np.zeros((cases, rows), dtype=bool)
    lam = np.zeros((cases, rows))
    steps = np.zeros(cases, dtype=int)
    open_cases = np.arange(cases)  # cases still moving
    settled = np.zeros(cases, dtype=bool)
    for _ in range(limit):
        if open_cases.size == 0:
            break
        # every case still open (as a batch often starts): views, not copies of every array
        pick = slice(None) if open_cases.size == cases else open_cases
        now = active[pick]
        steps[pick] += 1
        if now.any():
            forces, singular = _held_forces(W, soft, q[pick], now)
            lam[pick] = forces
            u = u_free[pick] - forces @ flexibility_columns.T
            penetration = q[pick] - forces @ W  # C u − g
        else:  # no row held (the first step): no force, and u is K⁻¹P
            forces, singular = lam[pick], np.zeros(now.shape[0], dtype=bool)
            u, penetration = u_free[pick], q[pick]
        disp_tol = DECISION_RTOL * np.maximum(row_reduce(np.maximum, np.abs(u), initial=0.0),
                                              floor[pick])[:, None]
        if penalty is None:
            force_tol = DECISION_RTOL * np.maximum(
                load_size[pick], row_reduce(np.maximum, np.abs(forces), initial=0.0))[:, None]
            following = (now & (forces > -force_tol)) | (~now & (penetration > disp_tol))
        else:
            following = np.where(now, penetration > -disp_tol, penetration > disp_tol)
        still = (following != now).any(axis=1) & ~singular
        settled[open_cases[~still & ~singular]] = True
        active[pick] = following
        open_cases = open_cases[still]
    u = u_free - lam @ flexibility_columns.T
    return CasesSolution(u, lam, steps, settled, u_free)


def _held_forces(W: np.ndarray, soft: float, q: np.ndarray,
                 active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """λ with (W_AA + soft·I) λ_A = q_A on each case's held rows A, one small solve per set
    of held rows; and whether each case's system was singular (its λ left 0)."""
    lam = np.zeros(q.shape)
    singular = np.zeros(q.shape[0], dtype=bool)
    if q.shape[0] == 1:
        first, which = np.zeros(1, dtype=np.intp), np.zeros(1, dtype=np.intp)
    elif q.shape[1] == 1:  # one row: the cases that hold it
        _one_row(lam, W, soft, q, np.flatnonzero(active[:, 0]), 0)
        return lam, singular
    else:  # each case's set as one integer (rows <= 64), so that finding the sets sorts numbers
        keys = active @ np.left_shift(np.uint64(1), np.arange(q.shape[1], dtype=np.uint64))
        _, first, which = np.unique(keys, return_index=True, return_inverse=True)
    for index, held in enumerate(active[first]):
        if not held.any():
            continue
        members = np.flatnonzero(which == index)
        rows = np.flatnonzero(held)
        if rows.size == 1:
            _one_row(lam, W, soft, q, members, int(rows[0]))
            continue
        system = W[np.ix_(rows, rows)] + soft * np.eye(rows.size)
        try:
            forces = np.linalg.solve(system, q[np.ix_(members, rows)].T).T
        except np.linalg.LinAlgError:
            singular[members] = True
            continue
        if np.linalg.cond(system) > 1.0 / (64.0 * np.finfo(float).eps):  # dependent rows
            singular[members] = True
            continue
        lam[np.ix_(members, rows)] = forces
    return lam, singular


def _one_row(lam: np.ndarray, W: np.ndarray, soft: float, q: np.ndarray, members: np.ndarray,
             row: int) -> None:
    """λ of the ``members`` cases that hold row ``row`` alone: its penetration over its
    compliance (W_ii + soft > 0: the compliance at the row, never singular), by a division
    rather than a solve (a 1 x 1 solve of 5 000 cases: 0.27 ms)."""
    lam[members, row] = q[members, row] / (W[row, row] + soft)


__all__ = ["CASES_ENTRIES", "CASES_ROWS", "CasesSolution", "fits", "row_reduce", "solve_cases"]
