"""The contact problem as a linear complementarity problem (LCP) in the contact forces, and the
solvers contact codes and physics engines use on it.

With u = K⁻¹(P − Cᵀλ), the gap each row leaves is w = W λ + q, with W = C K⁻¹ Cᵀ the
flexibility the contacts see (symmetric positive semidefinite; the Delassus operator of
physics engines) and q = g − C K⁻¹P the gaps the loads leave with no contact force.
Unilateral contact is the LCP w >= 0, λ >= 0, wᵀλ = 0 (:func:`contact_lcp`); equality contact
is W λ = −q. Every solver works on the LCP scaled to a unit diagonal (z = λ / D, M = D W D,
D = diag(W)^-½), where a stiff contact beside a soft one weighs the same, and stops on the
natural-map residual of that scaled problem, ‖min(z, M z + q̃)‖∞ / ‖q̃‖∞ (Siconos's measure):

- ``lemke``: Lemke's complementary pivoting (:mod:`contactqp.methods.lemke`), exact and finite;
- ``pgs``: projected Gauss–Seidel, z_i ← max(0, z_i − ω (M z + q̃)_i) row after row, with
  ``relaxation`` ω (1: PGS; 1 < ω < 2: PSOR), until the residual is under ``tolerance`` or
  ``max_iterations`` sweeps; it converges for any ω in (0, 2) on a positive definite M, as
  slowly as M is far from diagonally dominant (a condensed elastic bar is: each contact's
  neighbours see most of its flexibility);
- ``semismooth_newton``: Newton's method on Φ(z) = φ(z, M z + q̃) = 0 with a generalised
  Jacobian, ``ncp`` "min" (φ = min(a, b): full steps, the primal–dual active set, exact once
  its set is right; a set that comes back stops it) or "fischer-burmeister"
  (φ = a + b − √(a² + b²), smooth off the origin, with an Armijo line search on ½‖Φ‖²).

The answer is u = K⁻¹P − K⁻¹Cᵀ λ; any force carried round a loop of rows that hold a node both
ways is taken out (:func:`contactqp.model.without_circulation`). W is dense (rows × rows) and
K⁻¹Cᵀ free nodes × rows: up to LCP_ROWS rows (a SolverError beyond, which says so) and
LCP_ENTRIES entries of K⁻¹Cᵀ; a user's model with CHOLMOD's factor forms W a block of rows at
a time and keeps no K⁻¹Cᵀ (u is one solve at the end), so only LCP_ROWS holds there; but for
``semismooth_newton`` with "min" on a user's (sparse) model: past SET_ROUTE_ROWS rows it takes
its Newton steps as the model's set solves, without W (:func:`_newton_on_sets`; where those
sets come back, within the LCP's size, the steps on W go on from the start).
"""

from __future__ import annotations

import math

import numpy as np

from contactqp.errors import OptionError, SolverError
from contactqp.methods.base import Solution
from contactqp.methods.lemke import lemke, unit_diagonal
from contactqp.model import Condensed, ContactModel, Model, without_circulation
from contactqp.model.base import natural_map

LCP_ROWS = 2000  # contact rows up to which the LCP is formed (W dense, rows x rows)
LCP_ENTRIES = 2**24  # ... and free nodes x rows, the dense K⁻¹Cᵀ it builds (128 MB)
NCP_FUNCTIONS = ("min", "fischer-burmeister")
PGS_TOLERANCE = 1e-10  # natural-map residual (scaled LCP) at which PGS stops
PGS_MAX_ITERATIONS = 10_000  # sweeps, where PGS_WORK allows them
SET_ROUTE_ROWS = 64  # semismooth Newton ("min") on a user's model takes set solves past these
# rows: the LCP's W costs a solve per row, a set solve one factorisation (about five solves);
# measured on the Hertz cylinder, 261 rows and 47 608 dofs: 4.8 s by W, lagrange's sets 0.77 s
NEWTON_TOLERANCE = 1e-13
NEWTON_MAX_ITERATIONS = 100
# What one solve may cost, so that every run ends in about a minute at most on a laptop core
# (measured on the block of contactqp.fem with one row per bottom node, 2 cores shared):
LEMKE_ROWS = 1000  # rows Lemke takes: a pivot updates a rows x 2·rows tableau (12 ms at 1000
# rows), and its default limit of 50 + 4·rows pivots then ends within a minute
PGS_WORK = 10**10  # sweeps x rows² PGS may take: a sweep of 2000 rows takes 5-10 ms
NEWTON_FB_ROWS = 1000  # rows Fischer–Burmeister's Newton takes: each step a dense rows² solve
ARMIJO = 1e-4  # sufficient decrease of ½‖Φ‖² along the Newton step
HELD_OPEN = 1e-9  # a held row left open by more than this (of q's largest entry) is let go


def contact_lcp(problem: Model | Condensed | ContactModel, max_rows: int | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """(W, q, K⁻¹P, K⁻¹Cᵀ) of a problem (module docstring); a SolverError past ``max_rows``
    rows (LCP_ROWS unless pgs is asked for more), or past LCP_ENTRIES of K⁻¹Cᵀ where the model
    cannot form W in blocks (``flexibility_in_blocks``); a model that can forms W a block of
    rows at a time and gives None for K⁻¹Cᵀ, and the answer's u is then one solve
    (:func:`_answer`)."""
    rows = problem.n_contacts
    max_rows = LCP_ROWS if max_rows is None else max_rows
    if _past_lcp(problem, max_rows):
        # a user's problem has dofs, a bar scene nodes: the refusal speaks the caller's words
        what, unknowns = (("problem", "free dofs") if problem.layout is None
                          else ("scene", "free nodes"))
        if problem.flexibility_in_blocks:
            raise SolverError(f"the complementarity methods form the dense flexibility "
                              f"W = C K⁻¹ Cᵀ (rows x rows, a solve per row): up to {max_rows} "
                              f"contact rows; this {what} has {rows} contact rows (use "
                              f"lagrange or semismooth_newton; pgs takes more with its option "
                              f"max_rows, at minutes to hours a run)")
        raise SolverError(f"the complementarity methods form the dense flexibility W = C K⁻¹ Cᵀ "
                          f"(rows x rows) and K⁻¹Cᵀ: up to {max_rows} contact rows and "
                          f"{LCP_ENTRIES} entries; this {what} has {rows} contact rows and "
                          f"{problem.n_free} {unknowns} (use lagrange; pgs takes more rows with "
                          f"its option max_rows)")
    u_free = problem.free_displacement
    if problem.flexibility_in_blocks:
        columns, W = None, problem.flexibility(np.arange(rows))
    else:
        columns, W = flexibility(problem)
    return W, problem.g - problem.C @ u_free, u_free, columns


def flexibility(problem: Model | Condensed) -> tuple[np.ndarray, np.ndarray]:
    """(K⁻¹Cᵀ, free nodes x rows; W = C K⁻¹ Cᵀ, rows x rows, symmetric): the contact
    operator, through the problem's own solve with K (statics where every bar is held by one
    support)."""
    columns = problem.solve_K(problem.C.T.toarray())
    W = problem.C @ columns
    return columns, 0.5 * (W + W.T)


def _answer(problem: Model | Condensed, contact: str, solver: str, z_solver,
            max_rows: int | None = None) -> Solution:
    """The Solution from the LCP's λ (``z_solver(M, q̃) -> (z, iterations, converged, status,
    info)`` on the scaled problem); equality contact by one linear solve."""
    W, q, u_free, columns = contact_lcp(problem, max_rows)
    if contact == "equality":
        # least squares: rows that repeat each other's constraint leave W singular, and the
        # least-norm forces are as good as any (an inconsistent set is named by the caller)
        lam = np.linalg.lstsq(W, -q, rcond=None)[0] if q.size else np.zeros(0)
        return Solution(_moved(problem, u_free, columns, lam), lam, solver=solver,
                        status="solved")
    M, q_scaled, D = unit_diagonal(W, q)
    z, iterations, converged, status, info = z_solver(M, q_scaled)
    residual = natural_map(z, M @ z + q_scaled, q_scaled)
    # a user's problem has no chain whose loops of rows could carry a force round
    lam = D * z if problem.layout is None else without_circulation(problem, D * z)
    return Solution(_moved(problem, u_free, columns, lam), lam, solver=solver,
                    iterations=iterations, status=status, claimed_success=converged,
                    info={**info, "natural_map": residual})


def _moved(problem: Model | Condensed | ContactModel, u_free: np.ndarray,
           columns: np.ndarray | None, lam: np.ndarray) -> np.ndarray:
    """u = K⁻¹P − K⁻¹Cᵀλ: from the columns K⁻¹Cᵀ where the LCP kept them, else one solve."""
    if columns is not None:
        return u_free - columns @ lam
    return u_free - problem.solve_K(problem.C_transpose_times(lam))


def _at_most(method: str, rows: int, limit: int, why: str) -> None:
    """A SolverError where ``rows`` contact rows are more than ``method`` takes."""
    if rows > limit:
        raise SolverError(f"{method} takes up to {limit} contact rows ({why}); this problem "
                          f"has {rows} (lagrange takes any number)")


def solve_lemke(problem: Model | Condensed, contact: str, *,
                max_iterations: int | None = None) -> Solution:
    """Lemke's method (:mod:`contactqp.methods.lemke`) on up to LEMKE_ROWS rows;
    ``max_iterations``: pivots (default 50 + 4 × rows)."""
    _at_most("lemke", problem.n_contacts, LEMKE_ROWS,
             "each pivot updates a dense tableau of rows x 2·rows entries")

    def pivots(M: np.ndarray, q: np.ndarray):
        limit = 50 + 4 * q.size if max_iterations is None else max_iterations
        z, count = lemke(M, q, limit)
        return z, count, True, "solved", {}

    return _answer(problem, contact, "lemke", pivots)


def pgs_sweeps(rows: int, max_iterations: int | None, lifted: bool = False) -> int:
    """The sweeps PGS may take on ``rows`` rows: ``max_iterations``, or by default
    PGS_MAX_ITERATIONS, within PGS_WORK (an OptionError where a given number is past it);
    ``lifted`` (pgs asked for more rows than LCP_ROWS): the work is the caller's choice."""
    if lifted:
        return PGS_MAX_ITERATIONS if max_iterations is None else max_iterations
    budget = max(1, PGS_WORK // max(rows, 1) ** 2)
    if max_iterations is None:
        return min(PGS_MAX_ITERATIONS, budget)
    if max_iterations > budget:
        raise OptionError(f"max_iterations = {max_iterations} sweeps of {rows} rows is more "
                          f"than pgs takes ({PGS_WORK:.0e} row updates x row length, about a "
                          f"minute): at most {budget} sweeps at this size")
    return max_iterations


def solve_pgs(problem: Model | Condensed, contact: str, *, relaxation: float = 1.0,
              tolerance: float = PGS_TOLERANCE, max_iterations: int | None = None,
              max_rows: int | None = None) -> Solution:
    """Projected Gauss–Seidel (``relaxation`` 1) or PSOR (module docstring); the iterate at
    the last sweep, with ``claimed_success`` False, when ``max_iterations`` sweeps (default
    PGS_MAX_ITERATIONS, within PGS_WORK: :func:`pgs_sweeps`) do not bring the residual under
    ``tolerance``. ``max_rows``: the rows up to which W is formed (default LCP_ROWS, so that a
    run ends in about a minute); asked past LCP_ROWS, PGS_WORK no longer bounds the sweeps
    (the caller chose a long run: 14 minutes at 10⁴ rows, docs/benchmarks.md), and W must fit
    in the memory available (:func:`w_fits`)."""
    max_rows = LCP_ROWS if max_rows is None else max_rows
    lifted = max_rows > LCP_ROWS
    max_iterations = pgs_sweeps(problem.n_contacts, max_iterations, lifted)
    if lifted and problem.n_contacts > LCP_ROWS:
        w_fits(problem.n_contacts)

    def sweeps(M: np.ndarray, q: np.ndarray):
        z = np.zeros(q.size)
        rows = [(i, M[i]) for i in range(q.size)]
        for sweep in range(1, max_iterations + 1):
            for i, row in rows:
                z[i] = max(0.0, z[i] - relaxation * (float(row @ z) + q[i]))
            if natural_map(z, M @ z + q, q) <= tolerance:
                return z, sweep, True, "converged", {"relaxation": relaxation}
        return (z, max_iterations, False, f"stopped after {max_iterations} sweeps",
                {"relaxation": relaxation})

    return _answer(problem, contact, "pgs", sweeps, max_rows)


W_COPIES = 3  # dense rows x rows arrays the LCP holds at once (W, its scaled M, a product)


def w_fits(rows: int) -> None:
    """A SolverError where W_COPIES dense rows x rows arrays need more memory than the machine
    has available (:func:`contactqp.model.factor.available_memory`)."""
    from contactqp.model.factor import available_memory

    needed, available = W_COPIES * 8 * rows**2, available_memory()
    if available is not None and needed > available:
        raise SolverError(f"pgs with {rows} rows forms W (rows x rows) and needs about "
                          f"{needed / 1e9:.1f} GB; this machine has {available / 1e9:.1f} GB "
                          "available (use lagrange or semismooth_newton)")


def solve_semismooth_newton(problem: Model | Condensed, contact: str, *, ncp: str = "min",
                            tolerance: float = NEWTON_TOLERANCE,
                            max_iterations: int = NEWTON_MAX_ITERATIONS) -> Solution:
    """Semismooth Newton on the NCP function ``ncp`` (module docstring), from λ = 0; "min"
    solves only the rows its step holds (the primal–dual active set), Fischer–Burmeister
    the whole rows x rows Jacobian (up to NEWTON_FB_ROWS rows)."""
    if ncp != "min":
        _at_most("semismooth_newton with ncp='fischer-burmeister'", problem.n_contacts,
                 NEWTON_FB_ROWS, "each step solves a dense rows x rows Jacobian")
    elif (contact == "inequality" and problem.layout is None and not problem.singular
          and (_past_lcp(problem) or problem.n_contacts > SET_ROUTE_ROWS)):
        found = _newton_on_sets(problem, max_iterations)
        if found.claimed_success or _past_lcp(problem):
            return found
        # its sets came back (rows that repeat each other): the LCP's held steps handle them

    def newton(M: np.ndarray, q: np.ndarray):
        z = np.zeros(q.size)
        merit = _merit(ncp, z, M, q)
        seen: set[bytes] = set()
        # Fischer–Burmeister, once under the tolerance, goes on while the residual keeps
        # falling: near a degenerate row (a node clamped by two zero-gap walls) it converges
        # only linearly, and stopping at 1e-13 left a force 3.2e-9 of F off where Lagrange is
        # exact (random scene, seed 100733; 28 steps reach 1e-16 and 9e-16 of F)
        best: tuple[float, np.ndarray, int] | None = None
        for iteration in range(1, max_iterations + 1):
            phi, jacobian = _ncp(ncp, z, M @ z + q, None if ncp == "min" else M)
            residual = natural_map(z, M @ z + q, q)
            if best is not None and not residual < 0.9 * best[0]:
                return best[1], best[2], True, "converged", {"ncp": ncp}  # round-off reached
            if residual <= tolerance:
                if ncp == "min" or residual == 0.0:
                    return z, iteration - 1, True, "converged", {"ncp": ncp}
                best = (residual, z, iteration - 1)
            if ncp == "min":
                # the full step: Newton on min is the primal-dual active set, exact once the
                # set is right; ½‖Φ‖² is not smooth, and a line search on it stalls (measured:
                # 21 of 150 random scenes); a set that comes back is a cycle
                key = (z <= M @ z + q).tobytes()
                if key in seen:
                    return z, iteration, False, "the active set cycles", {"ncp": ncp}
                seen.add(key)
                z = _held_step(M, q, ~np.frombuffer(key, dtype=bool))
                continue
            # least squares: rows that depend on each other (zero gaps closing a loop) leave
            # the generalised Jacobian singular, and any of its solutions will do
            step = np.linalg.lstsq(jacobian, -phi, rcond=None)[0]
            t = 1.0
            while True:  # Armijo on ½‖Φ‖²: the Newton step descends at rate −2·merit
                trial = z + t * step
                trial_merit = _merit(ncp, trial, M, q)
                if trial_merit <= (1.0 - 2.0 * ARMIJO * t) * merit or t < 1e-10:
                    break
                t *= 0.5
            if t < 1e-10:
                if best is not None:
                    return best[1], best[2], True, "converged", {"ncp": ncp}
                return z, iteration, False, "the line search stalled", {"ncp": ncp}
            z, merit = trial, trial_merit
        if best is not None:
            return best[1], best[2], True, "converged", {"ncp": ncp}
        converged = natural_map(z, M @ z + q, q) <= tolerance
        return (z, max_iterations, converged,
                "converged" if converged else f"stopped after {max_iterations} iterations",
                {"ncp": ncp})

    return _answer(problem, contact, "semismooth_newton", newton)


def _past_lcp(problem: ContactModel, max_rows: int | None = None) -> bool:
    """Whether the LCP is past what :func:`contact_lcp` forms (W dense, up to ``max_rows``
    rows, LCP_ROWS by default, and K⁻¹Cᵀ dense where the model does not form W in blocks)."""
    rows = problem.n_contacts
    return rows > (LCP_ROWS if max_rows is None else max_rows) or (not problem.flexibility_in_blocks
                               and problem.n_free * rows > LCP_ENTRIES)


def _newton_on_sets(model: ContactModel, max_iterations: int) -> Solution:
    """Semismooth Newton on min(λ, c (g − C u)) = 0 without W, for a sparse model past the
    LCP's size: each full step is the exact answer with the step's rows held (the model's set
    solve: one factorisation, whatever the rows), the set those rows whose λ_i exceeds
    c_i (g − C u)_i, c_i = s̄_i (the row stiffness bound, :attr:`ContactModel.row_stiffness`;
    any c > 0 has the same solution, and this one weighs a stiff row as a soft one). The
    primal–dual active set of Hintermüller, Ito and Kunisch; a set that comes back stops it."""
    c = np.where(np.asarray(model.row_stiffness) > 0.0, model.row_stiffness, 1.0)
    u = model.free_displacement
    lam = np.zeros(model.n_contacts)
    seen: set[bytes] = set()
    last = b""
    for iteration in range(1, max_iterations + 1):
        active = lam - c * (model.g - model.C_times(u)) > 0.0
        key = active.tobytes()
        if key in seen:
            done = key == last
            return Solution(u, lam, solver="semismooth_newton", iterations=iteration - 1,
                            status="converged" if done else "the active set cycles",
                            claimed_success=done, info={"ncp": "min", "route": "set solves"})
        seen.add(key)
        last = key
        u, lam = model.on_set(active)
    return Solution(u, lam, solver="semismooth_newton", iterations=max_iterations,
                    status=f"stopped after {max_iterations} iterations", claimed_success=False,
                    info={"ncp": "min", "route": "set solves"})


def _held_step(M: np.ndarray, q: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Newton's full step on Φ = min(z, M z + q) from a point whose rows ``held`` have
    z > M z + q: z = 0 off them, and M_HH z_H = −q_H on them (least squares: rows that depend
    on each other leave M_HH singular, and any of its solutions will do). The same z as the
    step through the whole Jacobian, solving only the held rows."""
    z = np.zeros(q.size)
    rows = np.flatnonzero(held)
    while rows.size:
        z[:] = 0.0
        z[rows] = np.linalg.lstsq(M[np.ix_(rows, rows)], -q[rows], rcond=None)[0]
        # held rows that ask for gaps no z meets at once (a looser parallel copy of a row):
        # least squares misses each; the rows it leaves open are let go, and the rest solved
        gaps = M[rows] @ z + q[rows]
        open_rows = gaps > HELD_OPEN * max(float(np.abs(q).max(initial=0.0)), 1.0)
        if not open_rows.any():
            break
        rows = rows[~open_rows]
    return z


def _ncp(ncp: str, a: np.ndarray, b: np.ndarray, M: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray | None]:
    """Φ = φ(a, b) and, given M, an element of its generalised Jacobian in z (a = z,
    b = M z + q)."""
    if ncp == "min":
        free = a <= b  # φ = a: the force's row; else φ = b: the gap's row
        phi = np.where(free, a, b)
        return phi, None if M is None else np.where(free[:, None], np.eye(a.size), M)
    r = np.hypot(a, b)
    if M is None:
        return a + b - r, None
    origin = r == 0.0  # φ is not differentiable there: the usual element, 1 − 1/√2 each
    safe = np.where(origin, 1.0, r)
    da = np.where(origin, 1.0 - 1.0 / math.sqrt(2.0), 1.0 - a / safe)
    db = np.where(origin, 1.0 - 1.0 / math.sqrt(2.0), 1.0 - b / safe)
    return a + b - r, np.diag(da) + db[:, None] * M


def _merit(ncp: str, z: np.ndarray, M: np.ndarray, q: np.ndarray) -> float:
    phi, _ = _ncp(ncp, z, M @ z + q)
    return 0.5 * float(phi @ phi)


__all__ = ["LCP_ENTRIES", "LCP_ROWS", "NCP_FUNCTIONS", "contact_lcp", "flexibility",
           "solve_lemke", "solve_pgs", "solve_semismooth_newton"]
