"""Tresca's problem as a QP (2D) or a second-order cone program (3D), for any backend.

The primal (on the free dofs, slip v = T u − c measured from the increment's start):

    min ½uᵀKu − fᵀu + Σ sᵢ tᵢ   subject to   C u ≤ g,   tᵢ ≥ ‖Tᵢu − cᵢ‖,

one auxiliary tᵢ per frictional contact (sᵢ > 0; a contact with sᵢ = 0 carries no friction and
needs none). In 2D tᵢ ≥ |Tᵢu − cᵢ| is two linear rows, Tᵢu − tᵢ ≤ cᵢ with dual αᵢ and
−Tᵢu − tᵢ ≤ −cᵢ with dual βᵢ, so every QP solver takes it. Its KKT conditions read

    K u − f + Cᵀλ_N + Tᵀ(α − β) = 0,     sᵢ − αᵢ − βᵢ = 0,    α, β ≥ 0:

**the duals of the tangential rows are the friction forces**, λ_T = α − β, and their bound
|λ_T,i| ≤ αᵢ + βᵢ = sᵢ comes out of the stationarity in t (the box of the dual), as the
duals λ_N ≥ 0 of the normal rows are the contact forces. In 3D tᵢ ≥ ‖Tᵢu − cᵢ‖ is a
second-order cone whose dual (sᵢ, −λ_T,i) lies in the same cone: ‖λ_T,i‖ ≤ sᵢ (Clarabel,
cvxpy).

The Hessian blkdiag(K, 0) is only semidefinite: there is no curvature in t. Backends that need a
positive definite one (quadprog; ECOS through qpsolvers, which factors it) take the dual
instead, a QP in the forces alone over a box,

    min ½λᵀWλ − bᵀλ   subject to   λ_N ≥ 0,   −s ≤ λ_T ≤ s     (W = G K⁻¹ Gᵀ, b = G u₀ − h),

whose answer is λ itself and u = K⁻¹(f − Gᵀλ) (``formulation="dual"``; any backend takes it).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contactqp.errors import OptionError, SolverError
from contactqp.friction.law import Law
from contactqp.friction.model import FrictionModel
from contactqp.friction.reduced import join
from contactqp.progress import silenced

# backends that need a positive definite Hessian: the primal has none in t
POSITIVE_DEFINITE_ONLY = ("quadprog", "ecos")
DENSE_LIMIT = 5000  # unknowns past which a dense backend (a dense n x n matrix) is refused
# tolerances that take each backend near double precision (the check judges what it gives)
TIGHT = {
    # raise_error=False: a failure is a status, as for every backend, and no warning (the
    # frictionless path's qpsolvers_.FIXED_SETTINGS)
    "osqp": {"eps_abs": 1e-10, "eps_rel": 1e-10, "polishing": True, "max_iter": 200_000,
             "raise_error": False},
    "scs": {"eps_abs": 1e-10, "eps_rel": 1e-10, "max_iters": 200_000},
    "qpalm": {"eps_abs": 1e-10, "eps_rel": 1e-10, "max_iter": 100_000},
    "proxqp": {"eps_abs": 1e-10, "eps_rel": 0.0},
    "piqp": {"eps_abs": 1e-10, "eps_rel": 1e-12},
    "cvxopt": {"abstol": 1e-12, "reltol": 1e-12, "feastol": 1e-12},
    "clarabel": {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10},
    "ecos": {"abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10},
    "highs": {"output_flag": False},
}


@dataclass(frozen=True)
class PrimalQP:
    """min ½xᵀPx + qᵀx s.t. G x ≤ h, x = (u on the free dofs, t per frictional contact).

    Attributes
    ----------
    P, G : scipy.sparse.csc_array
    q, h : arrays
    frictional : int array
        The contacts that carry a t (sᵢ > 0), in the order of t.
    """

    P: sp.csc_array
    q: np.ndarray
    G: sp.csc_array
    h: np.ndarray
    frictional: np.ndarray

    def forces(self, model: FrictionModel, duals: np.ndarray) -> np.ndarray:
        """λ = (λ_N, λ_T) from the duals of G's rows: λ_T = α − β (module docstring)."""
        mN, J = model.normal_rows, self.frictional.size
        lam_T = np.zeros((model.contacts, 1))
        lam_T[self.frictional, 0] = duals[mN:mN + J] - duals[mN + J:mN + 2 * J]
        return join(duals[:mN] if mN else None, lam_T)


def primal_qp(model: FrictionModel, law: Law, origin: np.ndarray) -> PrimalQP:
    """The 2D Tresca QP (module docstring) with the slip measured from ``origin`` = c."""
    J = np.flatnonzero(law.frictional)
    j = J.size
    T_J = model.T[J]
    identity = sp.identity(j, format="csr")
    blocks = [[sp.hstack([T_J, -identity])], [sp.hstack([-T_J, -identity])]]
    h = [origin[J], -origin[J]]
    if model.C is not None:
        blocks.insert(0, [sp.hstack([model.C, sp.csr_array((model.contacts, j))])])
        h.insert(0, model.gap)
    P = sp.block_diag([model.K, sp.csc_array((j, j))], format="csc")
    q = np.concatenate([-model.load, law.values[J]])
    G = sp.vstack([row[0] for row in blocks], format="csc")
    return PrimalQP(sp.csc_array(P), q, sp.csc_array(G), np.concatenate(h), J)


def solve_clarabel(model: FrictionModel, law: Law, origin: np.ndarray,
                   settings: dict) -> tuple[np.ndarray, np.ndarray, int, str, float]:
    """Tresca by Clarabel on the primal (QP in 2D, SOCP in 3D): (u, λ, iterations, status,
    seconds)."""
    import clarabel

    J = np.flatnonzero(law.frictional)
    n, j, d = model.K.shape[0], J.size, model.d
    P = sp.block_diag([sp.triu(model.K), sp.csc_array((j, j))], format="csc")
    q = np.concatenate([-model.load, law.values[J]])
    if d == 1:
        qp = primal_qp(model, law, origin)
        A, b, cones = qp.G, qp.h, [clarabel.NonnegativeConeT(qp.h.size)]
    else:
        A, b, cones = _cone_rows(model, J, origin)
    options = clarabel.DefaultSettings()
    options.verbose = False
    for key, value in {**TIGHT["clarabel"], **settings}.items():
        setattr(options, key, value)
    start = time.perf_counter()
    found = clarabel.DefaultSolver(sp.csc_matrix(P), q, sp.csc_matrix(A), b, cones,
                                   options).solve()
    seconds = time.perf_counter() - start
    x, z = np.asarray(found.x), np.asarray(found.z)
    if d == 1:
        forces = qp.forces(model, z)
    else:
        mN = model.normal_rows
        lam_T = np.zeros((model.contacts, d))
        # rows (tᵢ, Tᵢu − cᵢ) = b − A x: A = [0, −1; −Tᵢ, 0]; stationarity in u gives
        # −Tᵢᵀ z_T,i where the friction force acts as −Tᵢᵀλ_T,i: λ_T,i = −z_T,i
        lam_T[J] = -z[mN:].reshape(j, d + 1)[:, 1:]
        forces = join(z[:mN] if mN else None, lam_T)
    return x[:n], forces, int(found.iterations), str(found.status), seconds


def _cone_rows(model: FrictionModel, J: np.ndarray, origin: np.ndarray):
    """Clarabel's rows for 3D: C u ≤ g (nonnegative cone), then per frictional contact
    (tᵢ, Tᵢu − cᵢ) in a second-order cone of dimension 3."""
    import clarabel

    j, d = J.size, model.d
    n = model.K.shape[0]
    cone_rows = []
    b = []
    for local, contact in enumerate(J):
        t_row = sp.csr_array(([-1.0], ([0], [n + local])), shape=(1, n + j))
        T_rows = sp.hstack([-model.T[d * contact:d * contact + d], sp.csr_array((d, j))])
        cone_rows += [t_row, T_rows]
        b += [np.zeros(1), -origin[d * contact:d * contact + d]]
    cones = [clarabel.SecondOrderConeT(d + 1)] * j
    if model.C is not None:
        cone_rows.insert(0, sp.hstack([model.C, sp.csr_array((model.contacts, j))]))
        b.insert(0, model.gap)
        cones.insert(0, clarabel.NonnegativeConeT(model.contacts))
    return sp.vstack(cone_rows, format="csc"), np.concatenate(b), cones


def solve_qpsolvers(model: FrictionModel, law: Law, origin: np.ndarray, solver: str,
                    formulation: str, settings: dict
                    ) -> tuple[np.ndarray, np.ndarray, int, str, float]:
    """Tresca (2D) by a qpsolvers backend on the primal or the dual: (u, λ, iterations,
    status, seconds)."""
    import qpsolvers

    if solver not in qpsolvers.available_solvers:
        raise OptionError(f"method: the QP backend {solver!r} is not installed (installed: "
                          f"{', '.join(qpsolvers.available_solvers)}); pip install "
                          "'contactqp[solvers]' adds the optional ones")
    if model.d != 1:
        raise OptionError(f"method: {solver!r} takes QPs; 3D Tresca is a second-order cone "
                          "program: use 'clarabel', 'cvxpy' or 'active_set'")
    options = {**TIGHT.get(solver, {}), **settings}
    dense = solver in qpsolvers.dense_solvers and solver not in qpsolvers.sparse_solvers
    if formulation == "dual":
        return _qpsolvers_dual(model, law, origin, solver, dense, options)
    if solver in POSITIVE_DEFINITE_ONLY:
        raise OptionError(f"method: {solver} needs a positive definite Hessian and the primal "
                          "Tresca QP has no curvature in t; use formulation='dual'")
    qp = primal_qp(model, law, origin)
    if dense and qp.q.size > DENSE_LIMIT:
        raise OptionError(f"method: {solver} is a dense solver and the QP has {qp.q.size} "
                          f"unknowns (past {DENSE_LIMIT}); use a sparse backend")
    P, G = ((qp.P.toarray(), qp.G.toarray()) if dense
            else (sp.csc_matrix(qp.P), sp.csc_matrix(qp.G)))
    problem = qpsolvers.Problem(P, qp.q, G, qp.h)
    start = time.perf_counter()
    found = _qpsolvers_solve(qpsolvers, problem, solver, options)
    seconds = time.perf_counter() - start
    if not found.found or found.x is None or found.z is None:
        raise SolverError(f"{solver}: found no solution of the Tresca QP")
    n = model.K.shape[0]
    return (np.asarray(found.x)[:n], qp.forces(model, np.asarray(found.z)),
            _iterations(found), "solved", seconds)


def _qpsolvers_dual(model: FrictionModel, law: Law, origin: np.ndarray, solver: str,
                    dense: bool, options: dict):
    """The box QP in the forces (module docstring), by a qpsolvers backend."""
    import qpsolvers

    b = _reduced_rhs(model, origin)
    lower, upper = box(model, law)
    # rows whose force the law fixes at zero stay out, and rows that read no free dof
    # (model.inert: their force is left at zero, and W would be singular with them)
    keep = (upper > lower) & ~model.inert
    W = model.flexibility[np.ix_(keep, keep)]
    # the box as rows −λ ≤ −lower, λ ≤ upper where finite (λ_N has no upper bound, and
    # quadprog and ECOS take no infinite bound)
    identity = np.eye(W.shape[0])
    finite = np.isfinite(upper[keep])
    G = np.vstack([-identity, identity[finite]])
    h = np.concatenate([-lower[keep], upper[keep][finite]])
    problem = (qpsolvers.Problem(W, -b[keep], G, h) if dense else
               qpsolvers.Problem(sp.csc_matrix(W), -b[keep], sp.csc_matrix(G), h))
    start = time.perf_counter()
    found = _qpsolvers_solve(qpsolvers, problem, solver, options)
    seconds = time.perf_counter() - start
    if not found.found or found.x is None:
        raise SolverError(f"{solver}: found no solution of the dual Tresca QP")
    forces = np.zeros(b.size)
    forces[keep] = found.x
    return model.displacement(forces), forces, _iterations(found), "solved", seconds


def _qpsolvers_solve(qpsolvers, problem, solver: str, options: dict):
    """qpsolvers.solve_problem, silenced; a backend's refusal or failure (its own
    exception) as one SolverError line."""
    try:
        with silenced():
            return qpsolvers.solve_problem(problem, solver=solver, **options)
    except (qpsolvers.ProblemError, qpsolvers.SolverError, ValueError, ArithmeticError) as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise SolverError(f"{solver}: {first}") from None


def box(model: FrictionModel, law: Law) -> tuple[np.ndarray, np.ndarray]:
    """The bounds of the forces in 2D Tresca: λ_N ≥ 0, −s ≤ λ_T ≤ s."""
    s = law.values
    lower = join(None if model.C is None else np.zeros(model.contacts), -s)
    upper = join(None if model.C is None else np.full(model.contacts, np.inf), s)
    return lower, upper


def _reduced_rhs(model: FrictionModel, origin: np.ndarray) -> np.ndarray:
    """b = G u₀ − h for the slip origin c."""
    h = origin if model.C is None else np.concatenate([model.gap, origin])
    return model.rows @ model.unloaded - h


def _iterations(found) -> int:
    """The iteration count a qpsolvers Solution's extras carry, where the backend gives one."""
    extras = found.extras or {}
    for key in ("iter", "iterations", "iter_count", "num_iter"):
        value = np.asarray(extras.get(key, []))
        if value.size:  # quadprog reports [iterations, inactive constraints]
            return int(value.ravel()[0])
    info = extras.get("info")
    value = getattr(info, "iter", None) if info is not None else None
    return int(value) if value is not None else -1


def solve_cvxpy(model: FrictionModel, law: Law, origin: np.ndarray, settings: dict
                ) -> tuple[np.ndarray, np.ndarray, int, str, float]:
    """Tresca by cvxpy (QP in 2D, SOCP in 3D), the friction forces read from the duals of
    the constraints on t: (u, λ, iterations, status, seconds)."""
    import cvxpy as cp

    J = np.flatnonzero(law.frictional)
    d = model.d
    u = cp.Variable(model.K.shape[0])
    energy = 0.5 * cp.quad_form(u, cp.psd_wrap(sp.csc_matrix(model.K))) - model.load @ u
    constraints = []
    if model.C is not None:
        constraints.append(sp.csr_matrix(model.C) @ u <= model.gap)
    if J.size:  # no frictional row: no t (cvxpy 1.7 refuses a variable of size 0)
        t = cp.Variable(J.size)
        rows = d * J[:, None] + np.arange(d)
        slips = [sp.csr_matrix(model.T[rows[:, a]]) @ u - origin[rows[:, a]] for a in range(d)]
        if d == 1:
            constraints += [slips[0] <= t, -slips[0] <= t]
        else:
            constraints.append(cp.SOC(t, cp.vstack(slips), axis=0))
        energy = energy + law.values[J] @ t
    problem = cp.Problem(cp.Minimize(energy), constraints)
    start = time.perf_counter()
    try:
        with silenced():
            problem.solve(**settings)
    except cp.error.SolverError as error:
        raise SolverError(f"cvxpy: {str(error).splitlines()[0]}") from None
    seconds = time.perf_counter() - start
    if u.value is None:
        raise SolverError(f"cvxpy: found no solution of the Tresca problem ({problem.status})")
    offset = 1 if model.C is not None else 0
    lam_T = np.zeros((model.contacts, d))
    if J.size and d == 1:
        lam_T[J, 0] = constraints[offset].dual_value - constraints[offset + 1].dual_value
    elif J.size:
        # cvxpy's SOC dual (z₀, z) with ‖z‖ ≤ z₀: the friction force is −z
        lam_T[J] = -np.asarray(constraints[offset].dual_value[1]).reshape(d, J.size).T
    normal = None if model.C is None else np.asarray(constraints[0].dual_value)
    stats = problem.solver_stats
    iterations = int(stats.num_iters) if stats and stats.num_iters is not None else -1
    return np.asarray(u.value), join(normal, lam_T), iterations, problem.status, seconds


def reduced_socp(model: FrictionModel, law: Law, b: np.ndarray) -> np.ndarray:
    """The dual in the forces alone, min ½λᵀWλ − bᵀλ over λ_N ≥ 0 and ‖λ_T,i‖ ≤ sᵢ, by
    Clarabel (small and dense: k = m + d·m unknowns): a start for the active set where its
    own rule does not settle, and its route in 3D."""
    import clarabel

    W, k, d, mN = model.flexibility, b.size, model.d, model.normal_rows
    fixed = np.flatnonzero(np.repeat(~law.frictional, d)) + mN
    rows, rhs, cones = [], [], []
    if fixed.size:
        rows.append(sp.csr_array((np.ones(fixed.size), (np.arange(fixed.size), fixed)),
                                 shape=(fixed.size, k)))
        rhs.append(np.zeros(fixed.size))
        cones.append(clarabel.ZeroConeT(fixed.size))
    if mN:
        rows.append(sp.hstack([-sp.identity(mN), sp.csr_array((mN, k - mN))]))
        rhs.append(np.zeros(mN))
        cones.append(clarabel.NonnegativeConeT(mN))
    for i in np.flatnonzero(law.frictional):
        own = mN + d * i + np.arange(d)
        block = sp.csr_array((-np.ones(d), (np.arange(1, d + 1), own)), shape=(d + 1, k))
        rows.append(block)
        rhs.append(np.concatenate([[law.values[i]], np.zeros(d)]))
        cones.append(clarabel.SecondOrderConeT(d + 1))
    options = clarabel.DefaultSettings()
    options.verbose = False
    for key, value in TIGHT["clarabel"].items():
        setattr(options, key, value)
    found = clarabel.DefaultSolver(sp.csc_matrix(np.triu(W)), -b,
                                   sp.csc_matrix(sp.vstack(rows)), np.concatenate(rhs),
                                   cones, options).solve()
    forces = np.asarray(found.x)
    if forces.size != k or not np.all(np.isfinite(forces)):
        raise SolverError(f"clarabel: no answer to the reduced Tresca problem ({found.status})")
    return forces
