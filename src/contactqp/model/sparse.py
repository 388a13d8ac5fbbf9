"""A user's problem → the sparse model: the prescribed dofs condensed out, K factorised once.

The methods and the check call the same few operations the chain model offers: solve with K
(:meth:`SparseModel.solve_K`), the flexibility W = C_A K⁻¹ C_Aᵀ of the rows that need it
(:meth:`SparseModel.flexibility`, from sparse forward solves kept once computed, or CHOLMOD's
solves), the set solve (:meth:`SparseModel.set_solve`), K, P, C, g, and the scales F and U.

Condensing (scikit-fem's ``condense``): with I the free dofs and D the prescribed ones, the
unknowns are u_I, K_II u_I = f_I − K_ID u_D − C_Iᵀλ, and the rows C_I u_I <= g − C_D u_D (a
row may touch a prescribed dof: a contact against a moving punch, a bar contact that ends at
a support); the support of a prescribed dof then carries the row's force too, R_D = K_D u −
f_D + C_Dᵀλ.

K is factorised once (:mod:`contactqp.model.factor`): by CHOLMOD where the optional extra
``contactqp[cholmod]`` is installed, on the pattern of K + CᵀC so that each set of rows held is
one numeric factorisation of K + C_AᵀRC_A (:mod:`contactqp.model.augmented`), else by
SuperLU (minimum degree, symmetric mode), whose sets are solved by the rows' Schur complement
(:mod:`contactqp.model.schur`). The pivots are LDLᵀ's, so their signs are K's inertia
(Sylvester): a pivot below −:data:`NEGATIVE_PIVOT` of its own diagonal entry shows K
indefinite, refused in one line (CHOLMOD stops at a pivot that is not positive: SuperLU then
names it). A pivot within :data:`SINGULAR_PIVOT` of its own diagonal entry (never of the
largest: a stiffness contrast of 10¹⁴ leaves every pivot near its own entry) may be a free
mode: the modes are sought by inverse iteration, and kept where their forces are round-off of
what their entries make (:data:`FREE_MODE`); a mode that no contact row holds is an error
naming it ("nothing holds the model along ..."), one that rows hold is solved through the
saddle-point system.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # scipy.linalg and scipy.sparse.linalg load at the first solve (start-up)
    import scipy.sparse.linalg as spla

from contactqp.errors import OptionError, SolverError
from contactqp.model import iterative, schur
from contactqp.model.base import (
    ContactModel,
    ScaleTerms,
    balanced_by_contact,
    first_step_forces,
    normalised_modes,
)
from contactqp.model.factor import (
    ORDERING,
    CholmodK,
    ColumnCache,
    cholmod_of,
    diagonal_pivots,
    elimination_tree,
    factorise,
    forward_columns,
    reach,
)
from contactqp.model.iterative import AmgK
from contactqp.model.singular import (
    HELD,
    factor_or_none,
    free_modes,
    held_by_contact,
    loads_held,
    plain_factor,
)
from contactqp.problem import SPARSE_MODEL, Problem, detached

EINSUM_WORK = 10**8  # multiply-adds up to which W is formed by einsum rather than BLAS
SOLVE_BLOCK = 2**25  # entries of a block of solved columns K⁻¹C_rowsᵀ (256 MB)


@dataclass(frozen=True, eq=False)
class SparseModel(ContactModel):
    """The condensed problem and its factorisation (module docstring).

    Attributes
    ----------
    source : the problem's arrays: its detached copy (:func:`contactqp.problem.detached`), so
        that a Problem that keeps its model and the model do not hold each other.
    free : the free dofs (indices into the problem's u).
    K, P, C, g : K_II, f_I − K_ID u_D, C_I and g: the problem in the free dofs.
    factor : K's factorisation, CHOLMOD's (:class:`~contactqp.model.factor.CholmodK`) or
        SuperLU's (None where K is singular: :attr:`floating`), or with ``engine="amg"`` its
        multigrid hierarchy (:class:`~contactqp.model.iterative.AmgK`).
    floating : the modes K leaves free, which contact rows hold (free dofs x modes, or None).
    """

    source: Problem
    free: np.ndarray
    K: sp.csc_matrix
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray
    factor: spla.SuperLU | CholmodK | AmgK | None
    floating: np.ndarray | None = None
    cache: ColumnCache = field(default_factory=ColumnCache)
    origin: weakref.ref | None = None  # the user's Problem, held weakly

    @classmethod
    def of(cls, problem: Problem, *parts: Any) -> SparseModel:
        """The model of ``problem`` from its parts (the fields after ``source``)."""
        return cls(detached(problem), *parts, origin=weakref.ref(problem))

    @property
    def problem(self) -> Problem:
        """The user's Problem solved: the object itself while anything holds it, else its
        detached copy (the same arrays)."""
        problem = None if self.origin is None else self.origin()
        return self.source if problem is None else problem

    @property
    def n_free(self) -> int:
        return int(self.P.size)

    @property
    def engine(self) -> str:
        """How it solves with K: "amg" (conjugate gradients, :mod:`~contactqp.model.iterative`)
        or "direct" (a factorisation)."""
        return "amg" if isinstance(self.factor, AmgK) else "direct"

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
        if rhs.ndim == 1 or isinstance(self.factor, (CholmodK, AmgK)):
            return self.factor.solve(rhs)
        # one column at a time: SuperLU's multi-column solve costs more than the columns
        # alone (measured at 8.4·10⁴ dofs: 10 columns 150 ms at once, 12 ms each alone)
        return np.column_stack([self.factor.solve(rhs[:, k]) for k in range(rhs.shape[1])]
                               ) if rhs.shape[1] else np.zeros(rhs.shape)

    def _solved_columns(self, C_rows: sp.csr_array):
        """(the rows' slice, their C, K⁻¹ of their columns) a block of rows at a time, each
        block at most SOLVE_BLOCK entries of K⁻¹C_blockᵀ (CHOLMOD's factor; cholespy's where
        the columns left pay for it: :meth:`CholmodK.blocks_pay`)."""
        block = max(1, SOLVE_BLOCK // max(self.n_free, 1))
        for start in range(0, C_rows.shape[0], block):
            where = slice(start, start + block)
            C_block = C_rows[where]
            solve = (self.factor.solve_many if self.factor.blocks_pay(C_rows.shape[0] - start)
                     else self.factor.solve)
            yield where, C_block, solve(C_block.T.toarray())

    @property
    def flexibility_in_blocks(self) -> bool:
        """Whether :meth:`flexibility` solves a block of columns at a time (CHOLMOD's
        factor, or conjugate gradients'); SuperLU's forward columns are kept dense on the dofs
        they reach."""
        return isinstance(self.factor, (CholmodK, AmgK))

    def flexibility(self, rows: np.ndarray) -> np.ndarray:
        """W = C_rows K⁻¹ C_rowsᵀ (rows x rows, dense): with CHOLMOD's factor by solves with
        the rows' columns (each W_ii kept), else SuperLU gives Pr K Prᵀ = L U with the
        diagonal pivots kept, and K symmetric makes U = D Lᵀ (D = diag U), so K⁻¹ =
        Prᵀ U⁻¹ D U⁻ᵀ Pr and W = Zᵀ D Z with Z = U⁻ᵀ Pr Cᵀ: one sparse forward solve per row
        (:func:`forward_columns`), computed once."""
        cache, rows = self.cache, np.asarray(rows, dtype=np.intp)
        if self.flexibility_in_blocks:  # K⁻¹C_rowsᵀ by CHOLMOD, a block of rows at a time
            if not rows.size:
                return np.zeros((0, 0))
            C_rows = self.C[rows]
            W = np.empty((rows.size, rows.size))
            for where, _, moved in self._solved_columns(C_rows):
                W[:, where] = C_rows @ moved
            cache.solves += rows.size
            W = 0.5 * (W + W.T)
            self._kept_compliance()[rows] = np.diagonal(W)
            return W
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
        model = SparseModel.of(problem, self.free, self.K, P, self.C, g, self.factor,
                               self.floating, self.cache)
        loads_held(model)
        # what K and C alone decide, where this model has worked it out already; never P or g
        for name in ("row_stiffness", "row_roots", "_entries", "_one_entry_per_row",
                     "_free_run", "_prescribed_rows", "_prescribed_free"):
            if name in self.__dict__:
                model.__dict__[name] = self.__dict__[name]
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
        if isinstance(self.factor, AmgK):  # projected conjugate gradients
            return iterative.set_solve(self, rows, np.asarray(force, dtype=float),
                                       np.asarray(gap, dtype=float))
        dlam, du = schur.correction(self, rows, np.asarray(force, dtype=float),
                                    np.asarray(gap, dtype=float))
        return du, dlam

    def redundant(self, rows: np.ndarray) -> bool:
        if self.factor is None:
            return super().redundant(rows)
        if isinstance(self.factor, AmgK):
            return iterative.redundant(self, np.asarray(rows, dtype=np.intp))
        return schur.redundant(self, np.asarray(rows, dtype=np.intp))

    def on_set(self, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.factor is None:
            return super().on_set(active)
        if isinstance(self.factor, AmgK):
            return iterative.on_set(self, active)
        return schur.on_set(self, active)

    def seen_stiffness(self, rows: np.ndarray) -> np.ndarray:
        """1 / W_ii of each of ``rows`` (W_ii from the rows' forward solves, kept,
        :meth:`flexibility`; where K leaves modes free, 0 for a row that moves one and
        c K⁺ cᵀ from :meth:`pseudo_solve` for the others)."""
        rows = np.asarray(rows, dtype=np.intp)
        if not rows.size:
            return np.zeros(0)
        if self.flexibility_in_blocks:  # one solve per row: only the rows asked for
            # and not solved before (W's diagonal, kept), a block of columns at a time
            # (K⁻¹C_rowsᵀ of 10⁴ rows on 3.3·10⁵ dofs: 25 GiB)
            kept = self._kept_compliance()
            compliance = kept[rows]
            new = np.unique(rows[np.isnan(compliance)])
            for where, C_block, moved in self._solved_columns(self.C[new]):
                kept[new[where]] = np.asarray(C_block.multiply(moved.T).sum(axis=1)).reshape(-1)
            compliance = kept[rows]
        elif self.factor is not None:
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

    def _kept_compliance(self) -> np.ndarray:
        """W_ii of every row solved so far (NaN for the others), kept with the factor."""
        if self.cache.compliance is None:
            self.cache.compliance = np.full(self.n_contacts, np.nan)
        return self.cache.compliance

    def support_change(self, du: np.ndarray) -> np.ndarray:
        """K_DI du: the prescribed dofs' forces of a move of the free ones."""
        if not self.problem.prescribed.size:
            return np.zeros(0)
        return self._prescribed_free @ du

    @cached_property
    def _prescribed_rows(self) -> sp.csr_array:
        """K_D: K's rows at the prescribed dofs (each check reads them several times)."""
        return self.problem.K[self.problem.prescribed]

    @cached_property
    def _prescribed_free(self) -> sp.csr_array:
        """K_DI: K's rows at the prescribed dofs, columns at the free ones."""
        return self._prescribed_rows[:, self.free]

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
        if self.factor is not None:  # the last one kept: the force scale's is asked again
            kept = self.__dict__.get("_last_pseudo")
            if kept is None or not np.array_equal(kept[0], rhs):
                kept = self.__dict__["_last_pseudo"] = (np.array(rhs), self.solve_K(rhs))
            return kept[1].copy()
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
        u0_free = (self.free_displacement if self.floating is None else
                   self.pseudo_solve(balanced_by_contact(self.P, self.modes, self.C)))
        u0 = self.full_displacements(u0_free)
        C = self.C
        size = np.abs(C).max(axis=1).toarray().reshape(-1) if C.shape[0] else np.zeros(0)
        pen = C @ u0_free - self.g
        passed = np.where(self.equality, np.abs(pen), np.maximum(pen, 0.0))
        contact = first_step_forces(passed, self.row_stiffness, self.C_transpose_times,
                                    self.energy_of)
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
        return self._prescribed_rows @ u - problem.f[problem.prescribed]


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


def problem_model(problem: Problem, engine: str = "direct") -> SparseModel:
    """The model of ``problem``, built once per engine and kept with it: a Problem owns
    read-only arrays and does not change, so every later solve, check or study of the same
    problem object reuses the model and what it has worked out (K's factorisation, K⁻¹P, the
    scales, the columns of W), as :func:`contactqp.model.chain.model.scene_model` does for a
    scene. ``engine``: "direct" (K factorised) or "amg" (conjugate gradients with pyamg's
    multigrid: :mod:`contactqp.model.iterative`)."""
    check_engine(engine)
    key = _KEPT_MODEL if engine == "direct" else f"{_KEPT_MODEL}_{engine}"
    model = problem.__dict__.get(key)
    if model is None:
        model = problem.__dict__[key] = build_sparse_model(problem, engine=engine)
    return model


_KEPT_MODEL = SPARSE_MODEL  # where problem_model keeps a problem's model
ENGINES = ("direct", "amg")  # how a user's model solves with K (problem_model)


def check_engine(engine: Any) -> None:
    """An OptionError in one line where ``engine`` is not one of ENGINES (any type)."""
    if not (isinstance(engine, str) and engine in ENGINES):
        shown = repr(engine) if isinstance(engine, str) else type(engine).__name__
        raise OptionError(f"engine must be one of {', '.join(ENGINES)}; got {shown[:60]}")


def as_sparse_model(value: Any, engine: str = "direct") -> SparseModel:
    """``value`` if it is a SparseModel of that engine, the kept model of a Problem (by
    ``engine``); an OptionError for anything else, a model of another engine included."""
    check_engine(engine)
    if isinstance(value, SparseModel):
        if value.engine != engine:
            raise OptionError(f"this model solves with engine={value.engine!r}, not "
                              f"engine={engine!r}: pass engine={value.engine!r}, or its "
                              f"problem (model.problem) to have it solved with {engine!r}")
        return value
    if isinstance(value, Problem):
        return problem_model(value, engine)
    raise OptionError(f"the model must be a contactqp.Scene, a contactqp.Problem or a model "
                      f"of one, got {type(value).__name__}")


def build_sparse_model(problem: Problem, ordering: str = ORDERING, engine: str = "direct"
                       ) -> SparseModel:
    """Condense the prescribed dofs out and factorise K_II once (module docstring); a
    ProblemError where K is not positive semidefinite (the factorisation's evidence named) or
    where nothing holds the model along a mode K leaves free. ``engine="amg"``: K_II's
    multigrid hierarchy instead of its factorisation (:mod:`contactqp.model.iterative`; K
    positive definite)."""
    check_engine(engine)
    n = problem.n
    held = np.zeros(n, dtype=bool)
    held[problem.prescribed] = True
    free = np.flatnonzero(~held)
    K = problem.K
    K_II = sp.csc_matrix(K[free][:, free])
    P, g = _loads_and_gaps(problem, free)
    C = sp.csr_array(problem.C[:, free])
    if engine == "amg" and free.size:
        modes = iterative.rigid_body_modes(problem.coordinates, problem.K)
        factor = AmgK.of(K_II, None if modes is None else modes[free])
        return SparseModel.of(problem, free, K_II, P, C, g, factor, None, ColumnCache())
    factor = cholmod_of(K_II, C) if ordering == ORDERING else None
    if factor is not None:  # K positive definite, its pivots far from 0
        return SparseModel.of(problem, free, K_II, P, C, g, factor, None, ColumnCache())
    factor, cache, candidates = factor_or_none(K_II, ordering)
    floating = None
    if factor is None:
        floating = free_modes(K_II, candidates, free)
        if floating is None:  # the tiny pivots were a stiffness contrast, not a free mode
            factor, cache = plain_factor(K_II, ordering)
        else:
            held_by_contact(problem, free, C, floating)
    model = SparseModel.of(problem, free, K_II, P, C, g, factor, floating, cache)
    loads_held(model)
    return model


def _loads_and_gaps(problem: Problem, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P, g) in the free dofs: f_I − K_ID u_D, and g − C_D u_D (a row on a prescribed dof)."""
    P = problem.f[free] - (problem.K[free][:, problem.prescribed] @ problem.prescribed_values
                           if problem.prescribed.size else 0.0)
    g = problem.g
    if problem.prescribed.size and problem.C[:, problem.prescribed].nnz:  # rows on a support
        g = g - problem.C[:, problem.prescribed] @ problem.prescribed_values
    return P, g


__all__ = [
    "ENGINES",
    "ORDERING",
    "SparseModel",
    "build_sparse_model",
    "check_engine",
    "diagonal_pivots",
    "elimination_tree",
    "factorise",
    "forward_columns",
    "free_modes",
    "reach",
]
