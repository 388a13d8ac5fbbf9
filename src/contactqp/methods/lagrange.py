"""Explicit Lagrange multipliers: the saddle-point system [[K, Cᵀ], [C, 0]] [D; λ] = [P; g].

Unilateral contact is an active-set loop on the same system: walls that pull (λ < 0) are
released and walls passed are added, until the set is stable. ``active_set`` chooses which
passed walls are added: "passed" every one (the textbook loop: its steps grow with the mesh,
as a contact patch is crossed a few nodes per step), "hull" (the default) the vertices of
convex hulls, with each step solved by statics in O(n) (:mod:`contactqp.methods.hull`), where
the contacts are walls alone on the full formulation; elsewhere "hull" is the textbook loop.
A textbook loop that comes back to a set it left (dependent rows: zero gaps closing a loop of
walls and bar contacts) hands over to Lemke's method (:mod:`contactqp.methods.lemke`) on the
same contact problem, up to LEMKE_LIMIT rows.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.methods import hull
from contactqp.methods._active_set import (
    DECISION_RTOL,
    ActiveSetCycle,
    active_set_loop,
    displacement_tolerance,
    pinning,
)
from contactqp.methods.base import Solution
from contactqp.methods.complementarity import solve_lemke
from contactqp.methods.schur import solve_schur
from contactqp.model import (
    Condensed,
    Model,
    element_forces,
    elongation_rows,
)
from contactqp.model.saddle import (  # noqa: F401 - banded_order, row_scale: their former place
    banded_order,
    row_scale,
    saddle_point_system,
    solve_saddle_point,
)


def solve_strain_saddle_point(model: Model, active: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                       np.ndarray]:
    """The strain formulation's saddle-point system with the walls ``active`` as equalities.

    Unknowns [u; e; N; λ]: displacements, element elongations, and the multipliers of the tie
    rows B u − e = 0 and of the walls. Stationarity in e gives N = k_e e, so the tie
    multipliers are the element forces (N). The matrix is ordered by reverse Cuthill–McKee,
    which makes it banded for a chain. Returns (u, N, λ of the active walls).
    """
    B = elongation_rows(model)
    k = model.layout.element_stiffness
    n, m = model.n_free, k.size
    C = model.C[active]
    hessian = sp.diags_array(np.concatenate((np.zeros(n), k)))
    rows = sp.vstack((sp.hstack((B, -sp.eye_array(m))), sp.hstack((C, sp.csr_array((C.shape[0], m))))))
    matrix = sp.csr_array(sp.block_array([[hessian, rows.T], [rows, None]], format="csr"))
    rhs = np.concatenate((model.P, np.zeros(2 * m), model.g[active]))
    from scipy.sparse.csgraph import reverse_cuthill_mckee  # imported when first needed

    order = reverse_cuthill_mckee(matrix, symmetric_mode=True).astype(int)
    x = linalg.solve(matrix, rhs, order=order)
    return x[:n], x[n + m:n + 2 * m], x[n + 2 * m:]


def independent_rows(C: sp.csr_array, kept: np.ndarray, adding: np.ndarray,
                     penetration: np.ndarray, force: np.ndarray) -> np.ndarray:
    """The active set ``kept`` plus the rows ``adding``, most penetrated first, kept
    independent: the saddle-point system of rows that tie a node twice to its position
    (walls on both sides of a clamped node, a wall and a bar contact to a held node, a loop of
    walls and bar contacts) is singular. A row that would close such a loop replaces the
    least loaded (``force``) row of the loop: with the others held, the new row is passed, so
    the loop cannot hold as it was."""
    active = kept.copy()
    if adding.size == 0:
        return active
    adding = adding[np.argsort(-penetration[adding], kind="stable")]
    entries = np.diff(C.indptr)
    if not (entries[active] == 2).any() and not (entries[adding] == 2).any():
        # walls alone: dependent exactly when two rows hold one node, which with the node
        # passing a wall takes gaps that leave it no position (refused) or round-off
        taken = np.zeros(C.shape[1], dtype=bool)
        taken[C.indices[C.indptr[:-1][active & (entries == 1)]]] = True
        nodes = C.indices[C.indptr[:-1][adding]]
        first = np.zeros(adding.size, dtype=bool)
        first[np.unique(nodes, return_index=True)[1]] = True
        active[adding[first & ~taken[nodes]]] = True
        return active
    ground = C.shape[1]

    def ends(row: int) -> tuple[int, int]:
        nodes = C.indices[C.indptr[row]:C.indptr[row + 1]]
        return int(nodes[0]), int(nodes[1]) if nodes.size == 2 else ground

    for row in adding:
        loop = _tie_loop([ends(r) + (r,) for r in np.flatnonzero(active)], *ends(int(row)))
        if loop:
            active[min(loop, key=lambda r: force[r])] = False
        active[row] = True
    return active


def _tie_loop(ties: list[tuple[int, int, int]], start: int, goal: int) -> list[int]:
    """The rows on the path of ``ties`` (node, node, row) from ``start`` to ``goal``, or []
    when none joins them (breadth first)."""
    neighbours: dict[int, list[tuple[int, int]]] = {}
    for a, b, row in ties:
        neighbours.setdefault(a, []).append((b, row))
        neighbours.setdefault(b, []).append((a, row))
    came: dict[int, tuple[int, int] | None] = {start: None}
    queue = [start]
    for node in queue:
        for following, row in neighbours.get(node, []):
            if following not in came:
                came[following] = (node, row)
                queue.append(following)
    if goal not in came:
        return []
    path, node = [], goal
    while came[node] is not None:
        node, row = came[node]
        path.append(row)
    return path


ACTIVE_SETS = ("hull", "passed")


def solve_lagrange(model: Model | Condensed, contact: str, *, max_iterations: int | None = None,
                   formulation: str = "full", active_set: str = "hull") -> Solution:
    """Lagrange multipliers; ``contact`` "equality" (every wall holds) or "inequality";
    ``formulation`` "full" (unknowns u) or "strain" (u and the element elongations e, tied by
    equality rows whose multipliers, the element forces, go to the Solution's info)."""
    if model.layout is None:  # no chain: the loop on the rows' Schur complement
        return solve_schur(model, contact, max_iterations=max_iterations)
    P, C, g = model.P, model.C, model.g  # K (sparse) only where the loop needs it
    element_force: list[np.ndarray] = []

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if formulation == "strain":
            u, forces, lam_active = solve_strain_saddle_point(model, active)
            element_force[:] = [forces]
        else:
            u, lam_active = solve_saddle_point(model.K, P, C[active], g[active])
        lam = np.zeros(model.n_contacts)
        lam[active] = lam_active
        return u, lam

    if contact == "equality":
        u, lam = step(np.ones(model.n_contacts, dtype=bool))
        return Solution(u, lam, solver="lagrange", info=_strain_info(element_force))

    def update(active: np.ndarray, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
        pen = C @ u - g
        disp_tol = displacement_tolerance(u, g, P, model.K)
        force_tol = DECISION_RTOL * max(np.abs(P).max(initial=0.0), np.abs(lam).max(initial=0.0))
        kept = active & (lam > -force_tol)
        return independent_rows(C, kept, np.flatnonzero(~active & (pen > disp_tol)), pen, lam)

    start, info, loop = None, _strain_info(element_force), "passed"
    found = (hull.solve_on_chain(model, contact, max_iterations)
             if active_set == "hull" and formulation == "full" else None)
    if found is not None:
        solution, start = found
        if solution is not None:
            return solution
        loop = "hull, then passed"
        info = {"active_set": f"{loop} (the hull's set came back)"}
    reason = None
    lemke_fits = (model.n_contacts <= LEMKE_LIMIT and not model.floating
                  and model.n_free * model.n_contacts <= LEMKE_ENTRIES)
    try:
        u, lam, iterations = active_set_loop(model.n_contacts, step, update, method="lagrange",
                                             max_iterations=max_iterations, start=start,
                                             pin=pinning(model))
        # a set can settle with a wall still passed: a dependent row (zero gaps closing a
        # loop of walls and bar contacts) is never added (independent_rows)
        if (C @ u - g > displacement_tolerance(u, g, P, model.K)).any():
            reason = "the loop settled with a wall still passed"
    except ActiveSetCycle as cycle:  # the same dependent rows can make the loop come back
        if not lemke_fits:
            raise
        reason = str(cycle)
    if reason is not None and lemke_fits:
        # Lemke's method on the same contact problem: finite, and it cannot cycle
        u, lam, iterations = _by_lemke(model)
        info = {"active_set": f"{loop}, then Lemke's method ({reason})"}
        if formulation == "strain":  # the element forces from u, as the tie rows give them
            element_force[:] = [element_forces(model.layout, model.full_displacements(u))]
    return Solution(u, lam, solver="lagrange", iterations=iterations,
                    info=info | _strain_info(element_force))


LEMKE_LIMIT = 500  # contact rows up to which a cycling loop hands over to Lemke's method
LEMKE_ENTRIES = 2**24  # ... and free nodes x rows, the dense K⁻¹Cᵀ it builds (128 MB)


def _by_lemke(model: Model | Condensed) -> tuple[np.ndarray, np.ndarray, int]:
    """(u, λ, pivots) by Lemke's method on the contact LCP
    (:func:`contactqp.methods.complementarity.solve_lemke`, any force carried round a loop of
    rows taken out)."""
    solution = solve_lemke(model, "inequality")
    return solution.u_free, solution.contact_force, solution.iterations


def _strain_info(element_force: list[np.ndarray]) -> dict:
    return {"element_force": element_force[0]} if element_force else {}
