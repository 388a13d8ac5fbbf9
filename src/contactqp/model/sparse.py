"""A user's problem → the sparse model: the prescribed dofs condensed out, K factorised once.

The methods and the check call the same few operations the chain model offers: solve with K
(:meth:`SparseModel.solve_K`), the flexibility W = C_A K⁻¹ C_Aᵀ of the rows that need it
(:meth:`SparseModel.flexibility`, from sparse forward solves kept once computed), K, P, C, g,
and the scales F and U.

Condensing (scikit-fem's ``condense``): with I the free dofs and D the prescribed ones, the
unknowns are u_I, K_II u_I = f_I − K_ID u_D − C_Iᵀλ, and the rows C_I u_I <= g − C_D u_D (a
row may touch a prescribed dof: a contact against a moving punch, a bar contact that ends at
a support); the support of a prescribed dof then carries the row's force too, R_D = K_D u −
f_D + C_Dᵀλ.

The factorisation is SuperLU's (``scipy.sparse.linalg.splu``) with the minimum-degree ordering
of Kᵀ + K and no pivoting off the diagonal (K is symmetric positive definite): measured on a
2D grid of 8.4·10⁴ dofs (benchmarks/problem.py) it fills in less than COLAMD and factors
faster. The pivots are LDLᵀ's, so their signs are K's inertia (Sylvester): a pivot below
−:data:`NEGATIVE_PIVOT` of its own diagonal entry shows K indefinite, refused in one line. A
pivot within :data:`SINGULAR_PIVOT` of its own diagonal entry (never of the largest: a
stiffness contrast of 10¹⁴ leaves every pivot near its own entry) may be a free mode: the
modes are sought by inverse iteration, and kept where their forces are round-off of what
their entries make (:data:`FREE_MODE`); a mode that no contact row holds is an error naming it
("nothing holds the model along ..."), one that rows hold is solved through the saddle-point
system.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # scipy.linalg and scipy.sparse.linalg load at the first solve (start-up)
    import scipy.sparse.linalg as spla

from contactqp.errors import OptionError, ProblemError, SolverError
from contactqp.model import schur
from contactqp.model.base import (
    ContactModel,
    ScaleTerms,
    balanced_by_contact,
    first_step_forces,
    normalised_modes,
)
from contactqp.problem import Problem

ORDERING = "MMD_AT_PLUS_A"  # SuperLU's fill-reducing ordering for symmetric K
EINSUM_WORK = 10**8  # multiply-adds up to which W is formed by einsum rather than BLAS
DENSE_REACH = 4000  # the forward solves go dense up to this many rows of L reached
SINGULAR_PIVOT = 1e-10  # a pivot below this times its own diagonal entry: a mode may be free
NEGATIVE_PIVOT = 1e-8  # a pivot below −this times its own diagonal entry: K is indefinite
SHIFT = 1e-10  # the shift (of each dof's own diagonal) under which free modes are sought
FREE_MODE = 1e-13  # a mode whose forces are this much of what its entries make is free
MAX_MODES = 64  # free modes sought at most (six per floating body in 3D: ten bodies)
HELD = 1e-8  # a mode x with ‖C x‖ below this × ‖C‖‖x‖ is held by no contact row


def factorise(K: sp.spmatrix, ordering: str = ORDERING) -> spla.SuperLU:
    """SuperLU of a symmetric positive (semi)definite K: ``ordering`` of the columns, the
    diagonal pivots kept (symmetric mode), so the factors have the symmetric fill."""
    import scipy.sparse.linalg as spla

    options = {"SymmetricMode": True} if ordering == ORDERING else {}
    return spla.splu(sp.csc_matrix(K), permc_spec=ordering,
                     diag_pivot_thresh=0.0 if ordering == ORDERING else 1.0, options=options)


@dataclass(eq=False)
class ColumnCache:
    """Z_i = U⁻ᵀ Pr c_i for the rows asked for so far, dense on the rows they reach
    (``support``, increasing; ``values``: support x rows, in the order computed):
    W = C K⁻¹ Cᵀ = Zᵀ D Z (:meth:`SparseModel.flexibility`)."""

    pivots: np.ndarray | None = None  # D, the diagonal of U (U = D Lᵀ, K symmetric)
    where: dict[int, int] = field(default_factory=dict)
    support: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    values: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    parent: np.ndarray | None = None  # the elimination tree of L
    lower: sp.csr_matrix | None = None  # Uᵀ (SuperLU builds a new copy at each .U)
    solves: int = 0  # columns computed
    solver: tuple[bytes, Any, bool] | None = None  # (rows, W_AA's solver, singular) of the
    # last set solved

    def add(self, rows: list[int], nodes: np.ndarray, y: np.ndarray) -> None:
        """Keep the columns y (on ``nodes``) of ``rows``."""
        support = np.union1d(self.support, nodes)
        values = np.zeros((support.size, self.values.shape[1] + len(rows)))
        values[np.searchsorted(support, self.support), : self.values.shape[1]] = self.values
        values[np.searchsorted(support, nodes), self.values.shape[1]:] = y
        start = len(self.where)
        self.where.update({row: start + k for k, row in enumerate(rows)})
        self.support, self.values, self.solves = support, values, self.solves + len(rows)


@dataclass(frozen=True, eq=False)
class SparseModel(ContactModel):
    """The condensed problem and its factorisation (module docstring).

    Attributes
    ----------
    problem : the user's Problem.
    free : the free dofs (indices into the problem's u).
    K, P, C, g : K_II, f_I − K_ID u_D, C_I and g: the problem in the free dofs.
    factor : SuperLU of K (None where K is singular: :attr:`floating`).
    floating : the modes K leaves free, which contact rows hold (free dofs x modes, or None).
    """

    problem: Problem
    free: np.ndarray
    K: sp.csc_matrix
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray
    factor: spla.SuperLU | None
    floating: np.ndarray | None = None
    cache: ColumnCache = field(default_factory=ColumnCache)

    @property
    def n_free(self) -> int:
        return int(self.P.size)

    @property
    def n_contacts(self) -> int:
        return int(self.g.size)

    @property
    def equality(self) -> np.ndarray:
        return self.problem.equality

    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (one column or several) with the factorisation."""
        if self.factor is None:
            raise SolverError("K is singular (a mode only contact rows hold): this method "
                              "needs K⁻¹; use lagrange or qp")
        rhs = np.asarray(rhs, dtype=float)
        if self.n_free == 0:  # every dof prescribed: nothing to solve
            return rhs.copy()
        if rhs.ndim == 1:
            return self.factor.solve(rhs)
        # one column at a time: SuperLU's multi-column solve costs more than the columns
        # alone (measured at 8.4·10⁴ dofs: 10 columns 150 ms at once, 12 ms each alone)
        return np.column_stack([self.factor.solve(rhs[:, k]) for k in range(rhs.shape[1])]
                               ) if rhs.shape[1] else np.zeros(rhs.shape)

    def flexibility(self, rows: np.ndarray) -> np.ndarray:
        """W = C_rows K⁻¹ C_rowsᵀ (rows x rows, dense). SuperLU gives Pr K Prᵀ = L U with the
        diagonal pivots kept, and K symmetric makes U = D Lᵀ (D = diag U), so K⁻¹ =
        Prᵀ U⁻¹ D U⁻ᵀ Pr and W = Zᵀ D Z with Z = U⁻ᵀ Pr Cᵀ: one sparse forward solve per row
        (:func:`forward_columns`), computed once."""
        cache, rows = self.cache, np.asarray(rows, dtype=np.intp)
        new = [int(i) for i in dict.fromkeys(rows.tolist()) if int(i) not in cache.where]
        if new:
            if self.factor is None:
                self.solve_K(np.zeros(self.n_free))  # the SolverError that says why
            if cache.parent is None:
                cache.parent = elimination_tree(cache.lower)
            cache.add(new, *forward_columns(self.factor.perm_r, cache.lower, cache.parent,
                                            self.C[new]))
        if not rows.size:
            return np.zeros((0, 0))
        Y = cache.values[:, [cache.where[int(i)] for i in rows]]
        W = _gram(Y, Y * cache.pivots[cache.support, None])
        return 0.5 * (W + W.T)

    def with_values(self, problem: Problem) -> SparseModel:
        """The model of ``problem``, this one's with other loads, gaps or prescribed values
        (:meth:`contactqp.Problem.with_values`): K's factorisation, its free modes and the
        columns of W shared; P and g anew."""
        P, g = _loads_and_gaps(problem, self.free)
        model = SparseModel(problem, self.free, self.K, P, self.C, g, self.factor, self.floating,
                            self.cache)
        _loads_held(model)
        return model

    # --- the protocol (contactqp.model.base)
    layout = None  # no chain: no bar quantities

    @property
    def row_names(self) -> tuple[str, ...]:
        return self.problem.names

    @property
    def units(self) -> tuple[str, str]:
        """(force, length) from the problem's label "force, length" ("" where not given)."""
        return self.problem.unit_names

    def set_solve(self, rows: np.ndarray, force: np.ndarray, gap: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """The set solve by K's factorisation and the rows' Schur complement (or the
        saddle-point system where K is singular): :mod:`contactqp.model.schur`."""
        rows = np.asarray(rows, dtype=np.intp)
        if self.factor is None:  # no K⁻¹: the saddle-point system (rows that repeat a
            return super().set_solve(rows, force, gap)  # constraint regularised)
        dlam, du = schur.correction(self, rows, np.asarray(force, dtype=float),
                                    np.asarray(gap, dtype=float))
        return du, dlam

    def redundant(self, rows: np.ndarray) -> bool:
        if self.factor is None:
            return super().redundant(rows)
        return schur.redundant(self, np.asarray(rows, dtype=np.intp))

    def on_set(self, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.factor is None:
            return super().on_set(active)
        return schur.on_set(self, active)

    def seen_stiffness(self, rows: np.ndarray) -> np.ndarray:
        """1 / W_ii of each of ``rows`` (W_ii from the rows' forward solves, kept,
        :meth:`flexibility`; where K leaves modes free, 0 for a row that moves one and
        c K⁺ cᵀ from :meth:`pseudo_solve` for the others)."""
        rows = np.asarray(rows, dtype=np.intp)
        if not rows.size:
            return np.zeros(0)
        if self.factor is not None:
            compliance = np.diagonal(self.flexibility(rows)).copy()
        else:
            moves = np.abs(self.C[rows] @ self.floating).max(axis=1) > HELD * np.abs(
                self.C[rows]).max(axis=1).toarray().reshape(-1)
            compliance = np.full(rows.size, np.inf)
            for k in np.flatnonzero(~moves):
                c = self.C[[rows[k]]].toarray().reshape(-1)
                compliance[k] = float(c @ self.pseudo_solve(c))
        with np.errstate(divide="ignore"):
            return np.where(np.isfinite(compliance) & (compliance > 0.0), 1.0 / compliance,
                            np.where(compliance == 0.0, np.inf, 0.0))

    def support_change(self, du: np.ndarray) -> np.ndarray:
        """K_DI du: the prescribed dofs' forces of a move of the free ones."""
        problem = self.problem
        if not problem.prescribed.size:
            return np.zeros(0)
        return problem.K[problem.prescribed][:, self.free] @ du

    @property
    def singular(self) -> bool:
        """Whether K leaves modes free (held by contact rows alone)."""
        return self.factor is None

    def reactions_of(self, u: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
        """Each prescribed dof's force, (K u − f + Cᵀλ) there: what it takes to hold the dof
        against the elements, the loads and the rows that push on it."""
        problem = self.problem
        reactions = self.reactions(u)
        if reactions.size and self.pushes_supports:
            reactions = reactions + problem.C[:, problem.prescribed].T @ contact_force
        return reactions

    @cached_property
    def pushes_supports(self) -> bool:
        """Whether a contact row touches a prescribed dof."""
        problem = self.problem
        return bool(problem.prescribed.size and problem.C[:, problem.prescribed].nnz)

    @cached_property
    def modes(self) -> np.ndarray:
        """The free modes (:attr:`floating`) in reduced row-echelon form, each scaled to a
        largest entry of 1 (:func:`contactqp.model.base.normalised_modes`); none where K is
        definite."""
        if self.floating is None:
            return np.zeros((self.n_free, 0))
        return normalised_modes(self.floating)

    def pseudo_solve(self, rhs: np.ndarray) -> np.ndarray:
        """K⁺ rhs: K⁻¹ rhs, or where K leaves modes X free (orthonormal) the least-norm
        solution of K u = rhs − X Xᵀ rhs (the part only contact can carry taken out), from
        the saddle-point system [[K, X], [Xᵀ, 0]] (X's few dense columns)."""
        if self.factor is not None:
            return self.solve_K(rhs)
        X = self.floating
        if "_pseudo" not in self.__dict__:
            import scipy.sparse.linalg as spla

            saddle = sp.bmat([[self.K, sp.csc_matrix(X)], [sp.csc_matrix(X.T), None]],
                             format="csc")
            self.__dict__["_pseudo"] = spla.splu(saddle)
        rhs = np.asarray(rhs, dtype=float)
        return self.__dict__["_pseudo"].solve(np.concatenate((rhs, np.zeros(X.shape[1]))))[
            : self.n_free]

    def scale_terms(self) -> ScaleTerms:
        """The scales' terms (:mod:`contactqp.model.base`)."""
        problem = self.problem
        u0_free = self.pseudo_solve(balanced_by_contact(self.P, self.modes, self.C))
        u0 = self.full_displacements(u0_free)
        C = self.C
        size = np.abs(C).max(axis=1).toarray().reshape(-1) if C.shape[0] else np.zeros(0)
        pen = C @ u0_free - self.g
        passed = np.where(self.equality, np.abs(pen), np.maximum(pen, 0.0))
        contact = first_step_forces(passed, self.row_stiffness, C, self.pseudo_solve)
        coordinates = problem.coordinates
        extent = (float(np.max(np.ptp(coordinates, axis=0), initial=0.0))
                  if coordinates is not None and coordinates.size else 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            lengths, gaps = passed / size, np.maximum(self.g, 0.0) / size
        return ScaleTerms(
            loads=_largest(problem.f), reactions=_largest(self.reactions(u0)),
            contact=_largest(contact), unbalanced=_largest(self.modes.T @ self.P),
            free=_largest(u0), passed=_largest(lengths), widest=_largest(gaps),
            size=extent or 1.0,
            softest=float(self.K.diagonal().min(initial=np.inf)) if self.n_free else 0.0)

    def full_displacements(self, u_free: np.ndarray) -> np.ndarray:
        """Every dof's displacement: u_free on the free dofs, the prescribed values on the
        others."""
        problem = self.problem
        u = np.empty(problem.n)
        u[self.free] = u_free
        u[problem.prescribed] = problem.prescribed_values
        return u

    def reactions(self, u: np.ndarray) -> np.ndarray:
        """What the elements and loads ask of each prescribed dof's support: (K u − f) there
        (with no contact force; :meth:`reactions_of` adds the rows')."""
        problem = self.problem
        if not problem.prescribed.size:
            return np.zeros(0)
        K_D = problem.K[problem.prescribed]
        return K_D @ u - problem.f[problem.prescribed]


def _largest(values: np.ndarray) -> float:
    return float(np.abs(values).max(initial=0.0))


def _gram(Y: np.ndarray, Z: np.ndarray) -> np.ndarray:
    """Yᵀ Z for the flexibility: sparse where Y is (rows that reach few dofs, e.g. a row on
    every dof of a diagonal K), by einsum's own loops while small (OpenBLAS threads on a busy
    machine took 0.11 s for 80 rows x 2·10³ dofs, einsum 3 ms), else by BLAS."""
    if np.count_nonzero(Y) < 0.1 * Y.size:
        return (sp.csc_array(Y).T @ sp.csc_array(Z)).toarray()
    if Y.shape[1] ** 2 * Y.shape[0] <= EINSUM_WORK:
        return np.einsum("ik,il->kl", Y, Z, optimize=False)
    return Y.T @ Z


def elimination_tree(L: sp.spmatrix) -> np.ndarray:
    """parent[j]: the first row below the diagonal in column j of L (−1 for a root)."""
    L = sp.csc_matrix(L)
    L.sort_indices()
    counts = np.diff(L.indptr)
    parent = np.full(L.shape[0], -1)
    has = counts > 1
    parent[has] = L.indices[L.indptr[:-1][has] + 1]
    return parent


def reach(parent: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Every node on the elimination-tree paths from ``starts`` to the roots, increasing: where
    L⁻¹b is not zero for b nonzero at ``starts``."""
    seen = np.zeros(parent.size, dtype=bool)
    for node in starts.tolist():
        while node >= 0 and not seen[node]:
            seen[node] = True
            node = parent[node]
    return np.flatnonzero(seen)


def forward_columns(perm_r: np.ndarray, lower: sp.csr_matrix, parent: np.ndarray,
                    rows: sp.csr_array) -> tuple[np.ndarray, np.ndarray]:
    """(the rows reached, Z there): Z = lower⁻¹ Pr Cᵀ for some rows of C (``lower`` = Uᵀ),
    solved on the rows it reaches alone. A contact row's column is zero off its
    elimination-tree path: 80 rows of the benchmark grid reach 2·10³ of its 8.4·10⁴ dofs
    together, so this costs a fraction of one solve with K (dense up to DENSE_REACH rows)."""
    b = sp.csc_array(rows.T)
    permuted = perm_r[b.indices]  # Pr: row i of b goes to perm_r[i]
    nodes = reach(parent, np.unique(permuted))
    local = np.full(parent.size, -1)
    local[nodes] = np.arange(nodes.size)
    rhs = np.zeros((nodes.size, b.shape[1]))
    columns = np.repeat(np.arange(b.shape[1]), np.diff(b.indptr))
    rhs[local[permuted], columns] = b.data
    sub = sp.csr_matrix(lower[nodes][:, nodes])
    import scipy.linalg
    import scipy.sparse.linalg as spla

    if nodes.size <= DENSE_REACH:
        z = scipy.linalg.solve_triangular(sub.toarray(), rhs, lower=True, check_finite=False)
    else:
        z = spla.spsolve_triangular(sub, rhs, lower=True)
    z = np.asarray(z).reshape(nodes.size, b.shape[1])
    # the columns decay along the path into subnormal numbers, on which every later product
    # runs many times slower; they are below any force
    z[np.abs(z) < np.finfo(float).tiny] = 0.0
    return nodes, z


def diagonal_pivots(U: sp.csc_matrix) -> np.ndarray:
    """The diagonal of SuperLU's U, read from its index arrays (scipy's .diagonal() of the
    2.3·10⁶ entries of the benchmark's U took 0.46 s)."""
    columns = np.repeat(np.arange(U.shape[1]), np.diff(U.indptr))
    on = U.indices == columns
    pivots = np.zeros(U.shape[0])
    pivots[columns[on]] = U.data[on]  # one diagonal entry per column
    return pivots


def problem_model(problem: Problem) -> SparseModel:
    """The model of ``problem``, built once and kept with it: a Problem owns read-only
    arrays and does not change, so every later solve, check or study of the same problem
    object reuses the model and what it has worked out (K's factorisation, K⁻¹P, the scales,
    the columns of W), as :func:`contactqp.model.chain.model.scene_model` does for a scene."""
    model = problem.__dict__.get(_KEPT_MODEL)
    if model is None:
        model = problem.__dict__[_KEPT_MODEL] = build_sparse_model(problem)
    return model


_KEPT_MODEL = "_sparse_model"  # where problem_model keeps a problem's model


def as_sparse_model(value: Any) -> SparseModel:
    """``value`` if it is a SparseModel, the kept model of a Problem; an OptionError for
    anything else."""
    if isinstance(value, SparseModel):
        return value
    if isinstance(value, Problem):
        return problem_model(value)
    raise OptionError(f"the model must be a contactqp.Scene, a contactqp.Problem or a model "
                      f"of one, got {type(value).__name__}")


def build_sparse_model(problem: Problem, ordering: str = ORDERING) -> SparseModel:
    """Condense the prescribed dofs out and factorise K_II once (module docstring); a
    ProblemError where K is not positive semidefinite (the factorisation's evidence named) or
    where nothing holds the model along a mode K leaves free."""
    n = problem.n
    held = np.zeros(n, dtype=bool)
    held[problem.prescribed] = True
    free = np.flatnonzero(~held)
    K = problem.K
    K_II = sp.csc_matrix(K[free][:, free])
    P, g = _loads_and_gaps(problem, free)
    C = sp.csr_array(problem.C[:, free])
    factor, cache, candidates = _factor_or_none(K_II, ordering)
    floating = None
    if factor is None:
        floating = free_modes(K_II, candidates, free)
        if floating is None:  # the tiny pivots were a stiffness contrast, not a free mode
            factor, cache = _plain_factor(K_II, ordering)
        else:
            _held_by_contact(problem, free, C, floating)
    model = SparseModel(problem, free, K_II, P, C, g, factor, floating, cache)
    _loads_held(model)
    return model


def _loads_and_gaps(problem: Problem, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P, g) in the free dofs: f_I − K_ID u_D, and g − C_D u_D (a row on a prescribed dof)."""
    P = problem.f[free] - (problem.K[free][:, problem.prescribed] @ problem.prescribed_values
                           if problem.prescribed.size else 0.0)
    g = problem.g
    if problem.prescribed.size and problem.C[:, problem.prescribed].nnz:  # rows on a support
        g = g - problem.C[:, problem.prescribed] @ problem.prescribed_values
    return P, g


def _plain_factor(K: sp.csc_matrix, ordering: str) -> tuple[spla.SuperLU, ColumnCache]:
    factor = factorise(K, ordering)
    return factor, ColumnCache(pivots=diagonal_pivots(factor.U), lower=sp.csr_matrix(factor.U.T))


def _relative_pivots(factor: spla.SuperLU, diagonal: np.ndarray) -> np.ndarray | None:
    """Each pivot over the diagonal entry of K it was taken from (the elimination order), or
    None where SuperLU did not keep the pivots on the diagonal (then they say nothing of K's
    inertia)."""
    if not np.array_equal(factor.perm_r, factor.perm_c):
        return None
    own = diagonal[elimination_order(factor)]
    pivots = diagonal_pivots(factor.U)
    relative = np.sign(pivots) * np.inf  # a pivot where K's diagonal is 0: only its sign
    relative[pivots == 0.0] = 0.0
    positive = own > 0.0
    relative[positive] = pivots[positive] / own[positive]
    return relative


def elimination_order(factor: spla.SuperLU) -> np.ndarray:
    """The dof eliminated at each step: Pr K Pc = L U puts dof j at position perm_c[j]."""
    return np.argsort(factor.perm_c)


def _indefinite(K: sp.csc_matrix, relative: np.ndarray, order: np.ndarray,
                pivots: np.ndarray) -> None:
    """A ProblemError naming the pivot that shows K has a negative eigenvalue: a pivot of
    LDLᵀ (a symmetric elimination) below −NEGATIVE_PIVOT of its own diagonal entry, which
    round-off of a positive semidefinite K cannot make (Sylvester: the pivots' signs are
    K's inertia)."""
    negative = np.flatnonzero(relative < -NEGATIVE_PIVOT)
    if not negative.size:
        return
    k = int(negative[np.argmin(relative[negative])])
    dof = int(order[k])
    raise ProblemError(
        f"K must be positive semidefinite, but it has {negative.size} negative "
        f"eigenvalue{'s' if negative.size > 1 else ''}: its symmetric factorisation meets the "
        f"pivot {float(pivots[k]):.6g} at free dof {dof} (K there {float(K[dof, dof]):.6g}); "
        "the energy ½uᵀKu is unbounded below")


def _factor_or_none(K: sp.csc_matrix, ordering: str
                    ) -> tuple[spla.SuperLU | None, ColumnCache, int]:
    """(the factorisation, a cache holding its pivots and Uᵀ, 0), or (None, an empty cache,
    the number of pivots that are zero to working precision) where K is singular or nearly:
    a pivot within SINGULAR_PIVOT of its own diagonal entry (a stiffness contrast alone never
    makes one: the rule is relative to each dof's own stiffness, not to the stiffest). A
    ProblemError where a pivot shows K indefinite. U is read once (scipy copies it out at each
    .U)."""
    if K.shape[0] == 0:
        K = sp.eye(1, format="csc")
    diagonal = K.diagonal()
    try:
        factor = factorise(K, ordering)
    except RuntimeError:  # "Factor is exactly singular": a zero pivot; the shifted K says more
        return None, ColumnCache(), _shifted_inertia(K, ordering)
    relative = _relative_pivots(factor, diagonal)
    if relative is None:
        return None, ColumnCache(), _shifted_inertia(K, ordering)
    U = factor.U
    pivots = diagonal_pivots(U)
    _indefinite(K, relative, elimination_order(factor), pivots)
    tiny = int(np.count_nonzero(relative <= SINGULAR_PIVOT))
    if tiny:
        return None, ColumnCache(), tiny
    # Uᵀ: lower triangular with L's structure (K symmetric), for the forward solves
    return factor, ColumnCache(pivots=pivots, lower=sp.csr_matrix(U.T)), 0


def _shift(K: sp.csc_matrix) -> sp.csc_matrix:
    """SHIFT times each dof's own diagonal entry (the largest where it is 0), a diagonal."""
    diagonal = K.diagonal()
    floor = float(diagonal.max(initial=0.0)) or 1.0
    return sp.diags_array(SHIFT * np.where(diagonal > 0.0, diagonal, floor), format="csc")


def _shifted_inertia(K: sp.csc_matrix, ordering: str) -> int:
    """After a zero pivot: K shifted by SHIFT of its own diagonal is factorised instead (a
    positive semidefinite K becomes definite); a negative pivot of that is K's negative
    eigenvalue (a ProblemError), else every dof counts as a candidate free mode."""
    shifted = sp.csc_matrix(K + _shift(K))
    try:
        factor = factorise(shifted, ordering)
    except RuntimeError:
        raise ProblemError("K must be positive semidefinite, but K shifted by "
                           f"{SHIFT:.0e} of its diagonal is still singular (a zero pivot): K "
                           "has a negative eigenvalue") from None
    relative = _relative_pivots(factor, shifted.diagonal())
    if relative is not None:
        _indefinite(shifted, relative, elimination_order(factor), diagonal_pivots(factor.U))
        return int(np.count_nonzero(relative <= 1e3 * SHIFT))
    return min(K.shape[0], 64)  # no inertia to read: a generous number of trial modes


def free_modes(K: sp.csc_matrix, count: int = 8, free: np.ndarray | None = None
               ) -> np.ndarray | None:
    """An orthonormal basis of the modes K leaves free (columns), or None where no mode is
    (a stiffness contrast made the pivots tiny, not a free mode). With D K's diagonal (its
    largest where 0) and K̃ = D^-½ K D^-½ (a unit diagonal, so that no dof's stiffness
    matters more than another's), subspace inverse iteration on K̃ + SHIFT·I from ``count``
    (the tiny pivots) plus a margin of trial vectors, then Rayleigh–Ritz on K̃: the Ritz
    vectors are K̃'s own, and a mode is free where its forces ‖K x‖∞ are within FREE_MODE of
    what its entries make, ‖|K| |x|‖∞ (round-off). A ProblemError where a mode's energy is
    negative beyond round-off (K indefinite; ``free`` names the dofs)."""
    n = K.shape[0]
    diagonal = K.diagonal()
    D = np.where(diagonal > 0.0, diagonal, float(diagonal.max(initial=0.0)) or 1.0)
    root = np.sqrt(D)
    factor = factorise(sp.csc_matrix(K + sp.diags_array(SHIFT * D, format="csc")))
    import scipy.linalg

    y = np.random.default_rng(0).standard_normal((n, min(n, count + 4, MAX_MODES)))
    for _ in range(4):  # (K̃ + SHIFT·I)⁻¹ y = D^½ (K + SHIFT·D)⁻¹ D^½ y
        y = scipy.linalg.qr(root[:, None] * factor.solve(root[:, None] * y), mode="economic")[0]
    x = y / root[:, None]
    values, rotation = np.linalg.eigh(x.T @ (K @ x))  # Rayleigh–Ritz on K̃ (yᵀK̃y = xᵀKx)
    x = x @ rotation
    forces = K @ x
    made = (abs(K) @ np.abs(x)).max(axis=0)
    size = np.abs(forces).max(axis=0)
    negative = values < -FREE_MODE * np.einsum("ij,ij->j", np.abs(x), abs(K) @ np.abs(x))
    if negative.any():
        mode = x[:, int(np.flatnonzero(negative)[0])]
        dofs = np.argsort(-np.abs(mode), kind="stable")[:4]
        names = free[dofs] if free is not None else dofs
        raise ProblemError(f"K must be positive semidefinite, but a mode moving dofs "
                           f"{', '.join(map(str, names.tolist()))} has negative energy: K has a "
                           "negative eigenvalue")
    keep = size <= FREE_MODE * np.where(made > 0.0, made, 1.0)
    if not keep.any():
        return None
    return scipy.linalg.orth(x[:, keep])


def _held_by_contact(problem: Problem, free: np.ndarray, C: sp.csr_array,
                     modes: np.ndarray) -> None:
    """A ProblemError naming a mode no contact row touches (K x = 0 and C x = 0)."""
    if modes.shape[1] == 0:
        return
    touched = C @ modes
    _, sigma, vt = np.linalg.svd(touched, full_matrices=True) if touched.size else (
        None, np.zeros(0), np.eye(modes.shape[1]))
    scale = float(abs(C).max()) if C.nnz else 1.0
    count = int(np.sum(sigma > HELD * scale))
    if count == modes.shape[1]:
        return
    raise ProblemError(f"nothing holds the model along a mode K leaves free and no contact row "
                       f"touches, moving {_moving(modes @ vt[count:][0], free)}: prescribe a "
                       "dof or add a contact row there")


def _moving(mode: np.ndarray, free: np.ndarray) -> str:
    """The four dofs a mode moves most, with how much (its largest entry 1)."""
    mode = mode / np.abs(mode).max()
    moving = free[np.argsort(-np.abs(mode), kind="stable")[:4]]
    return ", ".join(f"dof {d} ({mode[np.searchsorted(free, d)]:+.2f})" for d in moving)


BALANCED = 1e-9  # of the load on the free modes: what the rows may leave unbalanced


def _loads_held(model: SparseModel) -> None:
    """A ProblemError where the loads on the modes K leaves free X cannot be carried by the
    rows that touch them: no λ (>= 0 on the inequality rows) with (C X)ᵀλ = XᵀP (the body is
    pushed away from every row that could stop it: the energy has no minimum), or where
    nothing loads a mode and only open rows touch it (nothing presses the body against a row:
    its position is not determined)."""
    modes = model.floating
    if modes is None or modes.shape[1] == 0:
        return
    import scipy.optimize  # only for a K held by contact alone

    touched = (model.C @ modes).T  # modes x rows
    load = modes.T @ model.P
    equality = model.equality
    columns = np.hstack((touched, -touched[:, equality]))  # an equality row pulls too
    _, left = scipy.optimize.nnls(columns, load)
    size = float(np.abs(load).max(initial=0.0))
    if left > BALANCED * max(size, 1e-300) and size > 0.0:
        raise ProblemError(
            f"the loads push the model along a mode K leaves free, moving "
            f"{_moving(modes @ load, model.free)}, away from every contact row that could stop "
            "it: the energy has no minimum (add a row on that side, or prescribe a dof)")
    if size == 0.0 and not np.any((np.abs(touched).max(axis=0) > 0.0) & (model.g <= 0.0)):
        raise ProblemError(
            f"nothing loads the model along a mode K leaves free, moving "
            f"{_moving(modes[:, 0], model.free)}, and only open rows touch it: its position "
            "there is not determined (load it against a row, or prescribe a dof)")


__all__ = ["ORDERING", "SparseModel", "build_sparse_model", "diagonal_pivots",
           "elimination_tree", "factorise", "forward_columns", "free_modes", "reach"]
