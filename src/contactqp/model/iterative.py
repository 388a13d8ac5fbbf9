"""K solved by conjugate gradients with an algebraic multigrid preconditioner: the engine of a
sparse model whose factorisation does not fit in memory (``engine="amg"``; pyamg, the optional
extra ``contactqp[amg]``).

Why. A direct factorisation of K grows faster than K in 3D: on the Hertz sphere at 1.1·10⁶
dofs CHOLMOD's numeric factorisation did not fit in 24 GB beside the model. With this engine
lagrange solved it and the check verified it in 451 s (the hierarchy 28 s, 12 solves of 24–62
iterations; a and p₀ within 0.05 % of Hertz: docs/benchmarks.md, "3D at 10⁶ dofs, solved").
Below about 10⁵ dofs the direct engine is faster (a factorisation once, then milliseconds a
solve), so ``engine="direct"`` stays the default.

The engine (:class:`AmgK`): pyamg's smoothed aggregation of K on the free dofs, with the
rigid-body modes of the nodes as its near null space where the problem's coordinates give them
(:func:`rigid_body_modes`), and scipy's conjugate gradients with one V-cycle as the
preconditioner.

A set of rows held on their gaps (:func:`solve_set`) is solved by projected conjugate
gradients on the null space of the rows: with Π = I − C_Aᵀ(C_A C_Aᵀ)⁻¹C_A (C_A C_Aᵀ is sparse
and small, factored once per set by SuperLU: :func:`contactqp.model.saddle.gram_factor`),

    u = u_p + z,   u_p = C_Aᵀ(C_A C_Aᵀ)⁻¹ g_A,   Π K Π z = Π(f − K u_p),
    λ_A = (C_A C_Aᵀ)⁻¹C_A(f − K u),

the V-cycle projected the same way (Π M Π) as the preconditioner, started from the last set's
answer. No W_AA is formed, so a set costs the same whatever the rows in contact. Where rows
repeat each other's constraint (C_A C_Aᵀ singular), an independent subset of them is held and
the others carry nothing: the answer fixes only Cᵀλ there (:func:`redundant`). Where the rows
left out then miss their gaps (dependent rows whose gaps conflict), lagrange holds those rows
first and decides again (:func:`contactqp.methods.lagrange.solve_projected`); where that too
leaves a gap unmet, a SolverError says so, and the direct engine hands such sets to the Schur
complement's least-norm solve (on random spring networks of 5–9 dofs, 990 problems of
tests/test_problem_solve.py's kinds with fresh seeds, a third of them built to hold dependent
or touching rows: 17 refused so, none answered wrong).

Errors. Each solve stops where its residual is within RTOL (1e-10) of its own right-hand side,
a correction of a refinement (:func:`set_solve`) within CORRECTION_RTOL (1e-6) of its own:
never at an absolute floor, under which what a correction leaves would be hidden from the next.
The solves are inexact, and the check measures how much: its reference is refined with
residuals computed by products with K (each correction shrinks what is left by about
CORRECTION_RTOL), and the refinement's tail of corrections is its bound
(:mod:`contactqp.check.on_set`). A solve that does not reach its tolerance in MAX_ITERATIONS is
a SolverError.

Definiteness. A factorisation's pivots prove K positive definite or not (Sylvester); this
engine's evidence is weaker, of two kinds: the coarsest level's Galerkin matrix Pᵀ K P, which
is positive definite where K is, must factor by Cholesky, and conjugate gradients preconditioned
by the hierarchy must solve K x = b for a random b to RTOL with every curvature positive
(:func:`_curvature`: an indefinite K fails it but for a chance of about RTOL·√n). An indefinite
K is refused where either fails; the direct engine proves it and names the pivot.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError, SolverError, SolverNotAvailable

SparseModel = Any  # the model these functions read (contactqp.model.sparse.SparseModel)

RTOL = 1e-10  # a solve stops where its residual is this much of its right-hand side's ...
CORRECTION_RTOL = 1e-6  # ... a correction of a refinement where it is this much (set_solve)
MAX_ITERATIONS = 2000  # conjugate-gradient iterations at most per solve
MAX_COARSE = 500  # unknowns of the coarsest level, at most where the aggregation gets there
# (solved by a dense Cholesky factor: pyamg's default, a pseudo-inverse by the SVD, took 6.4 s
# on the 1 908 unknowns of the sphere's coarsest level at 32 550 dofs, Cholesky 0.1 s)
MODE_RTOL = 1e-8  # a rigid-body mode is kept where |K b| is at most this of |K||b|
UNMET = 1e-8  # a held row that misses its gap by more than this of its terms: a dependent
# set whose gaps conflict (:func:`unmet_rows`)
PROJECTED = 1e-13  # a projected right-hand side's component below this of its terms: round-off
KEPT_SETS = 2  # the sets' factors of C_A C_Aᵀ kept (the loop's last and the check's)


def rigid_body_modes(coordinates: np.ndarray | None, K: sp.csr_array) -> np.ndarray | None:
    """The rigid-body modes of the nodes (n x 3 in 2D, n x 6 in 3D), or the translations
    alone, or None: the dofs that sit at one point (a row of ``coordinates``, n x d) are one
    node's, in the order x, y(, z) of their numbers; each mode is kept only where the whole
    K moves none of it (|K b| within MODE_RTOL of |K||b|: the order was right and nothing ties
    the model to the ground), the translations alone where the rotations are not."""
    if coordinates is None or coordinates.ndim != 2 or coordinates.shape[1] not in (2, 3):
        return None
    d = coordinates.shape[1]
    _, node, counts = np.unique(coordinates, axis=0, return_inverse=True, return_counts=True)
    node = node.reshape(-1)
    if not np.all(counts == d):
        return None
    order = np.lexsort((np.arange(node.size), node))  # by node, then by dof number
    component = np.empty(node.size, dtype=np.intp)
    component[order] = np.tile(np.arange(d), counts.size)
    x = coordinates - coordinates.mean(axis=0)
    translations = np.zeros((node.size, d))
    translations[np.arange(node.size), component] = 1.0
    rotations = []
    for a, b in ((0, 1),) if d == 2 else ((0, 1), (1, 2), (2, 0)):
        mode = np.zeros(node.size)  # the rotation in the plane of axes a and b
        mode[component == a] = -x[component == a, b]
        mode[component == b] = x[component == b, a]
        rotations.append(mode)
    size = abs(sp.csr_array(K))

    def rigid(modes: np.ndarray) -> bool:
        return bool(np.all(np.abs(K @ modes).max(axis=0)
                           <= MODE_RTOL * (size @ np.abs(modes)).max(axis=0)))

    modes = np.column_stack((translations, *rotations))
    if rigid(modes):
        return modes
    return translations if rigid(translations) else None


@dataclass(eq=False)
class AmgK:
    """K's multigrid hierarchy and the conjugate-gradient solves by it (module docstring).

    Attributes
    ----------
    K : K on the free dofs (CSR).
    hierarchy : pyamg's smoothed-aggregation hierarchy of K.
    iterations : the conjugate-gradient iterations of each solve so far.
    setup_seconds : the hierarchy's set-up time with its test of definiteness.
    """

    K: sp.csr_matrix
    hierarchy: Any
    iterations: list[int] = field(default_factory=list)
    setup_seconds: float = 0.0
    _magnitude: sp.csr_matrix | None = field(default=None, repr=False)

    @classmethod
    def of(cls, K: sp.spmatrix, modes: np.ndarray | None) -> AmgK:
        """The hierarchy of K (``modes``: its near null space, None for pyamg's constant); a
        ProblemError where the coarsest level shows K not positive definite."""
        try:
            import pyamg
        except ImportError:
            raise SolverNotAvailable("engine='amg' needs pyamg: pip install contactqp[amg] "
                                     "(or pip install pyamg)") from None
        K = sp.csr_matrix(K)
        K.sort_indices()
        start = time.perf_counter()
        # quiet: what a zero or negative pivot does to the set-up shows in the test below
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            hierarchy = pyamg.smoothed_aggregation_solver(K, B=modes, max_coarse=MAX_COARSE,
                                                          coarse_solver="cholesky")
        coarsest = hierarchy.levels[-1].A
        try:
            if not np.isfinite(coarsest.data).all():
                raise np.linalg.LinAlgError
            np.linalg.cholesky(coarsest.toarray())
        except np.linalg.LinAlgError:
            raise ProblemError(
                f"K must be positive definite for engine='amg': the coarsest level of its "
                f"multigrid hierarchy, Pᵀ K P ({coarsest.shape[0]} x {coarsest.shape[0]}), has "
                f"no Cholesky factor (engine='direct' names an indefinite K's pivot, and "
                f"solves a singular K whose free modes contact rows hold)") from None
        met = _curvature(K, hierarchy)
        if met == "negative":
            raise ProblemError(
                f"K must be positive definite for engine='amg': conjugate gradients on K x = b "
                f"(b random, {K.shape[0]} free dofs) met a direction of negative curvature "
                f"(engine='direct' names an indefinite K's pivot, and solves a singular K whose "
                f"free modes contact rows hold)")
        if met:
            raise SolverError(
                f"conjugate gradients (engine='amg') on K x = b (b random, {K.shape[0]} free "
                f"dofs) did not converge in {MAX_ITERATIONS} iterations: K singular, or too "
                f"ill-conditioned for its multigrid (engine='direct' says which)")
        return cls(K, hierarchy, setup_seconds=time.perf_counter() - start)

    @property
    def magnitude(self) -> sp.csr_matrix:
        """|K| (kept; its index arrays K's own): the terms of a product with K."""
        if self._magnitude is None:
            self._magnitude = sp.csr_matrix((np.abs(self.K.data), self.K.indices,
                                             self.K.indptr), shape=self.K.shape)
        return self._magnitude

    def blocks_pay(self, columns: int) -> bool:
        """Never (CholmodK's question): conjugate gradients solve a column at a time."""
        return False

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (one column or several, each by conjugate gradients)."""
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 2:
            return (np.column_stack([self.solve(rhs[:, k]) for k in range(rhs.shape[1])])
                    if rhs.shape[1] else np.zeros(rhs.shape))
        return self.cg(_Operator(self.K.shape[0], self.K.dot), rhs,
                       self.hierarchy.aspreconditioner(cycle="V"), None)

    solve_many = solve

    def cg(self, operator: Any, rhs: np.ndarray, preconditioner: Any,
           start: np.ndarray | None, rtol: float | None = None) -> np.ndarray:
        """scipy's conjugate gradients to ``rtol`` (default RTOL) of ``rhs``; a SolverError
        where they do not get there."""
        import scipy.sparse.linalg as spla

        size = float(np.linalg.norm(rhs))
        if size == 0.0:
            return np.zeros_like(rhs)
        steps = [0]

        def count(_: np.ndarray) -> None:
            steps[0] += 1

        with np.errstate(all="ignore"):  # a breakdown is reported below, never printed
            try:
                x, info = spla.cg(operator, rhs, x0=start, rtol=RTOL if rtol is None else rtol,
                                  atol=0.0,
                                  maxiter=MAX_ITERATIONS, M=preconditioner, callback=count)
            except ValueError:  # NaN reached the coarsest level's solve
                x, info = np.full_like(rhs, np.nan), -1
        self.iterations.append(steps[0])
        if info != 0 or not np.isfinite(x).all():
            residual = float(np.linalg.norm(rhs - operator.matvec(x))) / size
            raise SolverError(f"conjugate gradients (engine='amg') did not converge: "
                              f"{steps[0]} iterations left a relative residual {residual:.1e} "
                              f"(K singular, or rows held that nearly repeat each other's "
                              f"constraint? engine='direct' says which)")
        return x


def _curvature(K: sp.csr_matrix, hierarchy: Any) -> str:
    """"negative" where K shows a direction of negative curvature, "unsolved" where the solve
    does not converge, else "": pyamg's conjugate gradients, preconditioned
    by the hierarchy's V-cycle, on K x = b for b random (the seed fixed), to RTOL, stop where a
    curvature pᵀKp or rᵀMr is negative (pyamg reports -1). Why this is evidence: with M positive
    definite (the V-cycle of a positive definite K with symmetric smoothing is), the iteration is
    Lanczos on M^-½KM^-½; while every curvature is positive its residual polynomial has only
    positive roots and p(0) = 1, so along an eigenvector of a negative eigenvalue |p| > 1 and the
    residual keeps b's component there: the solve converges to RTOL only where that component is
    under about RTOL of |b|, a chance of about RTOL·√n for a random b (10⁻⁷ at 10⁶ dofs)."""
    from pyamg.krylov import cg

    b = np.random.default_rng(0).standard_normal(K.shape[0])
    # recorded, so never printed: pyamg's cg sets its own filter to "always"
    with np.errstate(all="ignore"), warnings.catch_warnings(record=True):
        x, info = cg(K, b, tol=RTOL, maxiter=MAX_ITERATIONS,
                     M=hierarchy.aspreconditioner(cycle="V"))
    if info < 0:
        return "negative"
    return "unsolved" if info > 0 or not np.isfinite(x).all() else ""


def _Operator(n: int, matvec: Any) -> Any:
    import scipy.sparse.linalg as spla

    return spla.LinearOperator((n, n), matvec=matvec, dtype=float)


def _gram(model: SparseModel, rows: np.ndarray, prefer: np.ndarray | None = None
          ) -> tuple[np.ndarray, Any, np.ndarray]:
    """(the positions in ``rows`` of the rows kept, the factor of their C_A C_Aᵀ and its scale:
    :func:`contactqp.model.saddle.gram_factor`), kept for the last KEPT_SETS sets. Where the
    rows repeat each other's constraint, an independent subset of them (:func:`_independent`,
    the rows ``prefer`` first): the others hold nothing the kept ones do not."""
    key = rows.tobytes() + (b"" if prefer is None else b"|" + prefer.tobytes())
    sets = model.cache.sets
    found = sets.get(key)
    if found is None:
        from contactqp.model.saddle import gram_factor

        kept, gram = np.arange(rows.size), gram_factor(model.C[rows])
        if gram is None:
            kept = _independent(model, rows, prefer)
            gram = gram_factor(model.C[rows[kept]])
            if gram is None:
                raise SolverError(f"the {rows.size} rows held repeat each other's constraint "
                                  "and no independent subset was found (engine='direct' "
                                  "takes them)")
        while len(sets) >= KEPT_SETS:
            sets.pop(next(iter(sets)))
        found = sets[key] = (kept, *gram)
    return found


DEPENDENT_ROWS = 4000  # rows up to which a dependent set is reduced by a dense QR (128 MB)
INDEPENDENT_RTOL = 1e-10  # R's diagonal below this of its column: a dependent row


def _independent(model: SparseModel, rows: np.ndarray, prefer: np.ndarray | None = None
                 ) -> np.ndarray:
    """The positions in ``rows`` of an independent subset of them: QR of their scaled
    C_A C_Aᵀ, its columns in the order ``prefer`` (rows), then the others, each kept where it
    is not within INDEPENDENT_RTOL of the span of those before it (a greedy choice, in that
    order); up to DEPENDENT_ROWS rows, beyond a SolverError."""
    if rows.size > DEPENDENT_ROWS:
        raise SolverError(f"the {rows.size} rows held repeat each other's constraint: "
                          f"engine='amg' reduces such sets up to {DEPENDENT_ROWS} rows "
                          "(engine='direct' takes them)")
    import scipy.linalg

    C_A = model.C[rows]
    gram = (C_A @ C_A.T).toarray()
    scale = 1.0 / np.sqrt(np.diagonal(gram))
    first = np.zeros(rows.size, dtype=bool)
    if prefer is not None:
        first[np.isin(rows, prefer)] = True
    order = np.concatenate((np.flatnonzero(first), np.flatnonzero(~first)))
    scaled = (scale[:, None] * gram * scale[None, :])[:, order]
    R = scipy.linalg.qr(scaled, mode="r")[0]
    own = np.linalg.norm(scaled, axis=0)
    return np.sort(order[np.abs(np.diagonal(R)) > INDEPENDENT_RTOL * own])


def redundant(model: SparseModel, rows: np.ndarray) -> bool:
    """Whether the rows repeat each other's constraint (C_A C_Aᵀ singular; so too where its
    independent subset is not found, :func:`_gram`'s SolverError)."""
    try:
        return bool(rows.size) and _gram(model, rows)[0].size < rows.size
    except SolverError:
        return True


def solve_set(model: SparseModel, rows: np.ndarray, force: np.ndarray, gap: np.ndarray,
              start: np.ndarray | None = None, rtol: float = RTOL,
              prefer: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(u, λ_A) with K u + C_Aᵀλ_A = force and C_A u = gap, by projected conjugate gradients
    (module docstring) to ``rtol``, started from ``start`` (projected onto the rows' gaps);
    where the rows are dependent, the rows ``prefer`` held first (:func:`_independent`)."""
    engine: AmgK = model.factor
    if not rows.size:
        return engine.cg(_Operator(model.n_free, engine.K.dot), force,
                         engine.hierarchy.aspreconditioner(cycle="V"), start, rtol), np.zeros(0)
    kept, factor, scale = _gram(model, rows, prefer)
    C_A = model.C[rows[kept]]
    C_At = C_A.T
    gap = gap[kept]  # the others' gaps: met where the kept rows' are

    def gram_solve(b: np.ndarray) -> np.ndarray:
        return scale * factor.solve(scale * b)

    def project(x: np.ndarray) -> np.ndarray:
        return x - C_At @ gram_solve(C_A @ x)

    cycle = engine.hierarchy.aspreconditioner(cycle="V")
    lifted = gram_solve(gap)
    particular = C_At @ lifted
    operator = _Operator(model.n_free, lambda z: project(engine.K @ project(z)))
    preconditioner = _Operator(model.n_free, lambda r: project(cycle.matvec(project(r))))
    unheld = force - engine.K @ particular
    held = gram_solve(C_A @ unheld)
    rhs = unheld - C_At @ held
    # a component within the round-off of the terms it is made of is nothing (per dof: a load
    # the rows do not hold can be 10⁻³⁰ of one they do where K's stiffnesses differ so)
    reach = np.abs(particular) + abs(C_At) @ np.abs(lifted)  # u_p's components and their terms
    terms = np.abs(force) + engine.magnitude @ reach + abs(C_At) @ np.abs(held)
    rhs[np.abs(rhs) <= PROJECTED * terms] = 0.0
    if kept.size >= model.n_free or not rhs.any():
        u = particular  # the rows hold every dof, or the load they do not hold is round-off
    else:
        rhs = project(rhs)  # in the null space again (the round-off removed is of its size)
        z = engine.cg(operator, rhs, preconditioner,
                      None if start is None else project(start - particular), rtol)
        u = particular + project(z)
    lam = np.zeros(rows.size)
    lam[kept] = gram_solve(C_A @ (force - engine.K @ u))
    return u, lam


def unmet_rows(model: SparseModel, rows: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The held rows whose gap u misses by more than UNMET of the row's terms |C_A||u| +
    |g_A|: a dependent set is solved on an independent subset of its rows
    (:func:`solve_set`), and the rows left out miss their gaps where the set's gaps
    conflict."""
    C_A, g_A = model.C[rows], model.g[rows]
    return rows[np.abs(C_A @ u - g_A) > UNMET * (abs(C_A) @ np.abs(u) + np.abs(g_A))]


def set_solve(model: SparseModel, rows: np.ndarray, force: np.ndarray, gap: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """(δu, δλ_A) with K δu + C_Aᵀδλ_A = force and C_A δu = gap (the protocol's set solve: a
    correction of a refinement, to CORRECTION_RTOL; what it leaves is the next correction,
    which the refinement measures)."""
    return solve_set(model, rows, force, gap, rtol=CORRECTION_RTOL)


def on_set(model: SparseModel, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u, λ per row) with the rows ``active`` held on their gaps, the others carrying
    nothing, started from u₀ = K⁻¹P."""
    lam = np.zeros(model.n_contacts)
    rows = np.flatnonzero(active)
    u, lam[rows] = solve_set(model, rows, model.P, model.g[rows],
                             start=model.free_displacement)
    return u, lam


__all__ = ["CORRECTION_RTOL", "RTOL", "UNMET", "AmgK", "on_set",
           "redundant", "rigid_body_modes", "set_solve", "solve_set", "unmet_rows"]
