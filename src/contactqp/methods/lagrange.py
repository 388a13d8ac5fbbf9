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

import itertools

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import SolverError
from contactqp.methods import hull
from contactqp.methods._active_set import (
    DECISION_RTOL,
    ActiveSetCycle,
    active_set_loop,
    default_max_iterations,
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
from contactqp.model.augmented import STEPS
from contactqp.model.chain.to_problem import problem_from_scene
from contactqp.model.factor import CholmodK
from contactqp.model.iterative import CORRECTION_RTOL, UNMET, AmgK, redundant, solve_set, unmet_rows
from contactqp.model.saddle import (  # noqa: F401 - banded_order, row_scale: their former place
    banded_order,
    row_scale,
    saddle_point_system,
    solve_saddle_point,
)
from contactqp.model.sparse import problem_model


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
    if model.layout is None:  # no chain: the primal-dual active set on the sparse model
        if isinstance(model.factor, AmgK):
            return solve_projected(model, contact, max_iterations=max_iterations)
        if isinstance(model.factor, CholmodK):
            return solve_augmented(model, contact, max_iterations=max_iterations)
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
    except SolverError:  # a singular set: bars held by contact alone through rows that
        # repeat a constraint, where Lemke's handover needs K⁻¹
        if not (model.floating and formulation == "full"):
            raise
        u, lam, iterations = _as_its_problem(model, contact, max_iterations)
        return Solution(u, lam, solver="lagrange", iterations=iterations,
                        info={"active_set": f"{loop}, then the scene as its problem (the "
                                            "chain's loop met a singular set)"})
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


def _as_its_problem(model: Model, contact: str, max_iterations: int | None
                    ) -> tuple[np.ndarray, np.ndarray, int]:
    """(u, λ, steps) of a chain whose bars contact alone holds through rows that repeat a
    constraint (zero gaps closing a loop: random_scene seed 404007, floating 0.5): the scene
    as its problem, whose set solves take a K that contact holds, u read back at the chain's
    free nodes (the problem's dofs are the scene's nodes, its rows the chain's)."""
    general = problem_model(problem_from_scene(model.layout.scene))
    found = solve_lagrange(general, contact, max_iterations=max_iterations)
    return (model.free_part(general.full_displacements(found.u_free)), found.contact_force,
            found.iterations)


def _strain_info(element_force: list[np.ndarray]) -> dict:
    return {"element_force": element_force[0]} if element_force else {}


def next_set(model, active: np.ndarray, u: np.ndarray, lam: np.ndarray,
             equality: np.ndarray) -> np.ndarray:
    """The primal-dual active set's next set: the held rows that pull, or that the answer
    leaves open (a looser parallel copy of a row held with it), leave; every row the answer
    passes enters; each by more than DECISION_RTOL of F or U (round-off is not contact)."""
    F, U = model.force_scale, model.displacement_scale
    passed = model.C @ u - model.g
    keep = active & (lam > -DECISION_RTOL * F) & (passed > -DECISION_RTOL * U)
    return keep | (~active & (passed > DECISION_RTOL * U)) | equality


def first_guess(model) -> np.ndarray:
    """The rows passed after one steepest-descent step from u₀ = K⁻¹P towards closing its
    penetrations p, each row weighted by its stiffness s̄ (the forces λ₀ = μ S p of the force
    scale, :func:`contactqp.model.base.first_step_forces`; one solve with K), and the rows
    passed after a second step of the same kind on the forces (projected onto λ >= 0; one
    solve, two where the projection cuts): the union of both. Where the first step opens
    every row, the rows u₀ passes.

    After one step what is left of the penetration is nearly flat over the contact, so the
    rows it leaves passed turn on a knife edge of the step: on the 2D Hertz cylinder it holds
    the answer's set to a few rows (u₀ passes 59 rows at 8 754 dofs, the step 27, the
    answer's 27), on the 3D sphere a third too few (138 of 203 at 32 550 dofs), and the
    second step, which passes fewer in 2D and more in 3D, finds the rest (207 of them, 4 too
    many): lagrange's set factorisations there fell from 4 to 1 (2.55 to 1.52 s), and on
    every 2D mesh of the scaling benchmark the set is the one step's (docs/benchmarks.md,
    "A first set from a second step")."""
    model.force_scale  # noqa: B018 - its first step's solve is kept: the one taken here
    C, g, stiffness = model.C, model.g, model.row_stiffness
    u0 = model.free_displacement
    passed = C @ u0 - g
    weighted = np.where(passed > 0.0, stiffness * passed, 0.0)
    if not np.any(weighted):
        return passed > 0.0
    push = C.T @ weighted
    moved = model.pseudo_solve(push)  # the force scale's solve, kept
    step = float(passed @ weighted) / float(push @ moved)
    u1 = u0 - step * moved
    left = C @ u1 - g
    after = left > 0.0
    if not after.any():
        return passed > 0.0
    forces = step * weighted  # the second step: steepest descent on the forces, projected
    direction = np.where((forces > 0.0) | after, stiffness * left, 0.0)
    moved = model.pseudo_solve(C.T @ direction)
    curvature = float(direction @ (C @ moved))
    if not curvature > 0.0:
        return after
    length = float(left @ direction) / curvature  # the exact line search's
    trial = forces + length * direction
    if np.all(trial >= 0.0):
        u2 = u1 - length * moved
    else:
        u2 = u0 - model.pseudo_solve(C.T @ np.maximum(trial, 0.0))
    return after | (C @ u2 - g > 0.0)


def released_ahead(following: np.ndarray, count: int, lam: np.ndarray,
                   equality: np.ndarray) -> np.ndarray:
    """``following`` with ``count`` more rows released (as many as the step released): the
    held rows of least force (:func:`solve_augmented` asks where the steps' releases halve)."""
    held = np.flatnonzero(following & ~equality)
    if held.size <= count:
        return following
    ahead = following.copy()
    ahead[held[np.argpartition(lam[held], count)[:count]]] = False
    return ahead


def halving(released: list[int]) -> bool:
    """Whether the rows released by the last steps, each of which only released (none
    entered), halve: HALVING_STEPS of them, AHEAD_LEAST rows or more in the last, each
    within HALVING of half the one before. Past a contact's edge the held set acts as a
    punch whose edge rows pull, and on a 2D edge each step releases about half of the rows
    held beyond the answer's (measured on the Hertz cylinder at 3.3·10⁵ dofs: 191, 103, 53,
    27, 14, 7, 4, 2, 1 rows, a factorisation each): releasing twice as many then takes the
    geometric tail at once. On the 3D sphere the releases fall faster (71, 41, 16; 23, 15,
    2), and releasing ahead there overshoots."""
    if len(released) < HALVING_STEPS or released[-1] < AHEAD_LEAST:
        return False
    last = released[-HALVING_STEPS:]
    return all(a > 0 and abs(b / a - 0.5) <= HALVING for a, b in itertools.pairwise(last))


HALVING_STEPS = 3  # releases in a row that show the halving
HALVING = 0.1  # ... each this close to half the one before
AHEAD_LEAST = 4  # rows released in the last, at least (fewer: the set is solved from the one
# before's factor, contactqp.model.augmented.UPDATE_ROWS)


ON_THE_WAY = 1  # Uzawa steps for a set on the way (the penalised answer, off by
# 1/(1 + STIFFER) of the forces or less); the set they settle on is solved to round-off


def solve_augmented(model, contact: str, *, max_iterations: int | None = None) -> Solution:
    """Lagrange on a sparse model whose K CHOLMOD factors: the primal-dual active set
    (semismooth Newton on min(λ, g − C u) = 0) from a first guess (:func:`first_guess`),
    each set solved by
    one numeric factorisation of K + C_AᵀRC_A (:mod:`contactqp.model.augmented`), so that a
    step costs the same whatever the rows in contact, and every row the answer passes enters
    at once. The sets on the way are solved by ON_THE_WAY steps; the set they settle on to
    round-off, and decided again. A set that comes back (rows that repeat a constraint) hands
    over to the Schur complement's loop (:func:`contactqp.methods.schur.solve_schur`).
    Measured on the Hertz cylinder (contactqp.fem, 1.9·10⁴ to 1.7·10⁵ dofs): 2, 4 and 6 steps
    (the last the settled set again, to round-off) at 27, 214 and 754 rows in contact, where
    the same loop from the rows u₀ passes took 9 and 11 (27, 214); a set that differs from the
    one before by a few rows is solved from that one's factor (Woodbury,
    :class:`contactqp.model.augmented.Update`), by more through rank updates of a factor
    (:mod:`contactqp.model.updown`) where they cost less than a factorisation.
    Where the steps only release rows and the releases halve (:func:`halving`), twice as many
    are released (:func:`released_ahead`): on the 3.3·10⁵-dof cylinder of the scaling
    benchmark, 88 to 4 239 rows in contact, 5–8 set factorisations became 4 (a row released
    ahead that comes back undoes it: the set the step decided is taken, and no more)."""
    from contactqp.model.augmented import augmented_set

    equality = model.equality | (contact == "equality")
    start = equality | first_guess(model)
    limit = default_max_iterations(model.n_contacts) if max_iterations is None else int(
        max_iterations)
    active, seen, steps = start, {start.tobytes()}, ON_THE_WAY
    start, ahead = None, np.zeros(model.n_contacts, dtype=bool)  # the rows released ahead
    decided, released = active, []  # the step's own set; the rows of the releases in a row
    for iteration in range(1, limit + 1):
        rows = np.flatnonzero(active)
        solver = augmented_set(model, rows)
        if solver is None and rows.size:  # rows that repeat a constraint
            return solve_schur(model, contact, max_iterations=max_iterations)
        lam = np.zeros(model.n_contacts)
        if rows.size:
            u, lam[rows] = (solver.answer_on_set(model, start) if steps == STEPS else
                            solver.solve(model, model.P, model.g[rows], steps=steps))
            start = (u, lam[rows])  # where the same set's exact solve starts
        else:
            u = model.free_displacement.copy()
        following = next_set(model, active, u, lam, equality)
        if ahead is not None and steps != STEPS:  # releasing ahead where releases halve
            entered = (following & ~active).any()
            if (following & ahead).any():  # a row released ahead came back: the set that
                following, ahead = decided, None  # the step before decided, and no more
            else:
                count = int(np.count_nonzero(active & ~following))
                released = [*released, count] if count and not entered else []
                decided = following
                if halving(released):
                    following = released_ahead(decided, count, lam, equality)
                    released = []
                ahead = following ^ decided
        if np.array_equal(following, active):
            if steps == STEPS or not rows.size:
                # no refinement step after: Uzawa's steps are one, on the system's residuals
                return Solution(u, lam, solver="lagrange", iterations=iteration,
                                info={"active_set": "primal-dual", "set_factorisations":
                                      model.cache.set_factorisations,
                                      "set_updates": model.cache.set_updates})
            steps = STEPS  # the same set again, to round-off, and decided again
            continue
        start = None
        if following.tobytes() in seen:  # dependent rows can make the loop come back
            if steps == STEPS:
                return solve_schur(model, contact, max_iterations=max_iterations)
            steps = STEPS  # or a set on the way decided by a loose solve: exact from here
        seen.add(following.tobytes())
        active = following
    raise SolverError(f"lagrange: the active-set loop did not settle in {limit} steps")


def solve_projected(model, contact: str, *, max_iterations: int | None = None) -> Solution:
    """Lagrange on a sparse model whose K is solved by conjugate gradients (``engine="amg"``,
    :mod:`contactqp.model.iterative`): the primal-dual active set from :func:`first_guess`,
    each set solved by projected conjugate gradients started from the last set's answer (no
    W_AA: a set costs the same whatever the rows in contact); the set it settles on is
    refined once with the system's own residuals (a product with K). ``info["cg_iterations"]``:
    the conjugate-gradient iterations of each solve. A set it settles on whose dependent rows
    leave some rows' gaps unmet is solved again with those rows held first (the greedy
    independent subset of :func:`contactqp.model.iterative.solve_set`), and decided again;
    where that too leaves a gap unmet (rows that repeat a constraint with gaps that
    conflict), or a set comes back, a SolverError: this engine has no Schur complement to hand
    over to."""
    solves = len(model.factor.iterations)  # the engine's solves before this one's
    equality = model.equality | (contact == "equality")
    active = equality | first_guess(model)
    limit = default_max_iterations(model.n_contacts) if max_iterations is None else int(
        max_iterations)
    seen, u = {active.tobytes()}, model.free_displacement.copy()
    prefer = None  # rows of a dependent set to hold first: those the last solve left unmet
    for iteration in range(1, limit + 1):
        rows = np.flatnonzero(active)
        lam = np.zeros(model.n_contacts)
        u, lam[rows] = solve_set(model, rows, model.P, model.g[rows], start=u, prefer=prefer)
        following = next_set(model, active, u, lam, equality)
        if np.array_equal(following, active):
            unmet = unmet_rows(model, rows, u)
            if unmet.size and prefer is None:  # settled on dependent rows, some left unmet:
                prefer = unmet  # the same set again, those held first
                continue
            if unmet.size:
                why = ("repeat each other's constraint with gaps that no u meets at once: "
                       "engine='amg' holds an independent subset and does not choose which "
                       "rows to let go" if redundant(model, rows) else
                       "are independent, yet nearly repeat each other's constraint: their "
                       "projection leaves gaps unmet")
                raise SolverError(f"lagrange: the {rows.size} rows held {why} ({unmet.size} "
                                  f"missed by more than {UNMET:g} of their terms; "
                                  "engine='direct' takes them)")
            residual = model.K @ u - model.P + model.C.T @ lam
            du, dlam = solve_set(model, rows, residual, model.C[rows] @ u - model.g[rows],
                                 rtol=CORRECTION_RTOL, prefer=prefer)  # the subset it settled on
            u, lam[rows] = u - du, lam[rows] - dlam
            return Solution(u, lam, solver="lagrange", iterations=iteration,
                            info={"active_set": "primal-dual", "engine": "amg",
                                  "cg_iterations": model.factor.iterations[solves:]})
        prefer = None
        if following.tobytes() in seen:
            raise SolverError("lagrange: the active set came back to a set it left (rows "
                              "that repeat a constraint?); engine='direct' hands such sets "
                              "over to the Schur complement")
        seen.add(following.tobytes())
        active = following
    raise SolverError(f"lagrange: the active-set loop did not settle in {limit} steps")
