"""The set solve of a sparse model by the augmented matrix: the exact answer with a set A of
rows held on their gaps at the cost of one numeric factorisation, whatever the number of rows.

The answer on A solves the saddle-point system K u + C_Aᵀλ = f, C_A u = g_A. Adding
C_Aᵀ R (C_A u − g_A) = 0 to the first equation (R = diag ρ_i > 0) changes nothing of the answer:

    (K + C_Aᵀ R C_A) u + C_Aᵀλ = f + C_Aᵀ R g_A,   C_A u = g_A.

M_A = K + C_Aᵀ R C_A is symmetric positive definite, and its pattern is one pattern for every
set (that of K + CᵀC, every row's: :func:`contactqp.model.factor.cholmod_of`), so a set costs
one numeric factorisation on a symbolic analysis made once. λ follows by Uzawa's iteration on
the augmented system, written as iterative refinement with the residuals of the saddle-point
system itself (r = f − K u − C_Aᵀλ by a product with K, s = g_A − C_A u):

    u ← u + M_A⁻¹(r + C_Aᵀ R s),   λ ← λ + R (C_A u − g_A),

whose error in λ shrinks per step by 1/(1 + μ), μ the eigenvalues of R^½ W_AA R^½ (W_AA =
C_A K⁻¹ C_Aᵀ). With ρ_i = STIFFER × s̄_i (s̄_i = c_iᵀK c_i/(c_iᵀc_i)², at least the stiffness
the row sees: :attr:`~contactqp.model.base.ContactModel.row_stiffness`) each row's own entry
of R^½ W_AA R^½ is at least STIFFER, so a few steps reach round-off (3–4 on the Hertz
cylinder; the steps stop where they no longer shrink by SLOWER below NOISE, round-off noise,
and the steps that show the noise are taken: they are measured against F, and a row whose
entries are far from 1 needs them, as a row of 1e30 beside one of 1e-30 on a K of 1e20 did,
whose answer stopped at the steps' geometric tail was 8.6e41 of F out of balance); the
residuals are the system's own, so the fixed point is the exact answer, not the penalised one
(no dense W_AA is formed; each step is one solve with M_A's factor). A correction for the
refinement of an answer (:func:`contactqp.model.schur.correction`) is one step: its error is
what the refinement measures next (:mod:`contactqp.check.on_set`). Rows that repeat each
other's constraint (C_A of lower rank: the answer fixes only Cᵀλ) keep the Schur complement's
least-norm solve (:mod:`contactqp.model.schur`).

A set that differs from a factored one by a few rows costs less than a numeric
factorisation: up to UPDATE_ROWS rows by Woodbury from the held factor (:class:`Update`, a
solve per row), more by rank updates of the factor taken over (:func:`_by_updates`,
:mod:`contactqp.model.updown`: CHOLMOD's update of a row costs 1/630 to 1/100 of a numeric
factorisation on the Hertz models), where they cost less than a factorisation by the times
measured so far. An updated factor is checked before a set's exact solve (:func:`_resolves`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import SolverError
from contactqp.linalg import magnitude
from contactqp.model.factor import Cholmod, CholmodK

SparseModel = Any  # the model these functions read (contactqp.model.sparse.SparseModel)

STIFFER = 1e4  # ρ_i = this × s̄_i: each row's augmented stiffness, against its own
STEPS = 40  # Uzawa steps at most per solve
EXACT = 1e-15  # of F and U: a step below this is round-off, the solve stops
SLOWER = 0.5  # a step that shrinks by less than this after the first few: round-off noise
NOISE = 1e-8  # ... where it is already below this of F and U: above, a step that grows
# is the iteration's first steps, not noise (random scene 91043 as a problem: 3.0, 3.7,
# then 1.3e-7, 5.8e-8, 1.8e-16; stopped at 3.7, the answer was 6.6e-8 of F off)
KEPT = 2  # augmented factors kept per model (the last sets solved)
UPDATE_ROWS = 4  # a set that differs from the held one by this many rows or fewer is solved
# from its factor (Woodbury): a solve costs about a fifth of a numeric factorisation (CHOLMOD,
# 2D, 9·10⁴ dofs)


@dataclass(frozen=True, eq=False)
class RowProducts:
    """Every row's entries of CᵀC in the lower triangle, as positions in the pattern's
    values: row i adds ρ_i × ``products`` at ``positions`` where ``row`` is i."""

    row: np.ndarray
    positions: np.ndarray
    products: np.ndarray

    @classmethod
    def of(cls, C: sp.csr_array, engine: Cholmod) -> RowProducts:
        C = sp.csr_array(C)
        C.sort_indices()
        counts = np.diff(C.indptr)
        row = np.repeat(np.arange(counts.size), counts**2)
        start = np.repeat(np.cumsum(counts**2) - counts**2, counts**2)  # each row's first
        within = np.arange(row.size) - start
        first = C.indptr[row] + within // counts[row]
        second = C.indptr[row] + within % counts[row]
        lower = C.indices[first] >= C.indices[second]
        first, second, row = first[lower], second[lower], row[lower]
        return cls(row, engine.position(C.indices[first], C.indices[second]),
                   C.data[first] * C.data[second])


@dataclass(eq=False)
class Update:
    """M_A⁻¹ from the held factor of a set B's M_B and the few rows V where A and B differ
    (Woodbury): M_A = M_B + Vᵀ D V, D = diag(ρ) on the rows A adds and −ρ on those it drops,
    M_A⁻¹ = M_B⁻¹ − Z (D⁻¹ + V Z)⁻¹ Zᵀ with Z = M_B⁻¹Vᵀ (one solve per row; where rows are
    dropped the capacitance loses about log₁₀ STIFFER digits to cancellation, which the Uzawa
    steps, on the system's own residuals, do not keep)."""

    key: bytes = field(repr=False)  # the held factor's
    V: sp.csr_array = field(repr=False)
    signed: np.ndarray = field(repr=False)  # D's diagonal
    Z: np.ndarray | None = field(default=None, repr=False)
    capacitance: np.ndarray | None = field(default=None, repr=False)

    def solve(self, engine: Cholmod, rhs: np.ndarray) -> np.ndarray:
        if self.Z is None:
            self.Z = engine.solve(self.V.T.toarray())
            self.capacitance = np.diag(1.0 / self.signed) + self.V @ self.Z
        y = engine.solve(rhs)
        return y - self.Z @ np.linalg.solve(self.capacitance, self.V @ y)


@dataclass(eq=False)
class AugmentedSet:
    """One set of rows and its augmented matrix M_A's values (factored when asked, or served
    by ``update`` from the factor of the set before while that is held)."""

    rows: np.ndarray
    rho: np.ndarray
    values: np.ndarray
    key: bytes = field(repr=False)
    steps: int = 0  # Uzawa steps taken, over every solve with this set
    answer: tuple | None = field(default=None, repr=False)  # (P, g_A, u, λ_A) on P, g
    update: Update | None = None
    gram: Any = field(default=None, repr=False)  # C_A C_Aᵀ's factor and scale, as
    # contactqp.model.saddle.gram_factor made it to find the rows independent (:meth:`held_share`)
    held_rows: Any = field(default=None, repr=False)  # (C, C_A, C_Aᵀ): the rows of the C given

    def rows_of(self, C: sp.csr_array) -> tuple[sp.csr_array, Any]:
        """(C_A, C_Aᵀ) of ``C`` (every model that shares this set shares its C), made once."""
        if self.held_rows is None or self.held_rows[0] is not C:
            C_A = C[self.rows]
            self.held_rows = (C, C_A, C_A.T)
        return self.held_rows[1], self.held_rows[2]

    def operator(self, model: SparseModel):
        """(M_A⁻¹ as a function, whether the factor it reads still holds M_A, whether that
        is a factor moved by rank updates): the held factor of M_A, the factor of the set
        before with ``update`` (Woodbury), a factor moved to M_A by rank updates
        (:func:`_by_updates`), or M_A factored now."""
        engine = model.factor.engine
        if engine.holds == self.key:
            return engine.solve, lambda: engine.holds == self.key, False
        if self.update is not None and engine.holds == self.update.key:
            update = self.update
            return ((lambda rhs: update.solve(engine, rhs)),
                    lambda: engine.holds == update.key, False)
        modified = _by_updates(model, self)
        if modified is not None:
            return modified.solve, lambda: modified.holds == self.key, True
        try:
            engine.factor(self.key, self.values)
        except ArithmeticError:
            raise SolverError("K + C_AᵀRC_A is not positive definite") from None
        model.cache.set_factorisations += 1
        return engine.solve, lambda: engine.holds == self.key, False

    def answer_on_set(self, model: SparseModel, start: tuple[np.ndarray, np.ndarray] | None
                      = None) -> tuple[np.ndarray, np.ndarray]:
        """(u, λ_A) with the rows held on their gaps under the model's loads, to round-off,
        from ``start`` (an earlier step's (u, λ_A)) if given; kept (Lagrange's last set is
        the check's)."""
        gap = model.g[self.rows]  # a model with other loads or gaps shares the sets
        if self.answer is None or self.answer[0] is not model.P or not np.array_equal(
                self.answer[1], gap):
            self.answer = (model.P, gap, *self.solve(model, model.P, gap, start=start))
        return self.answer[2].copy(), self.answer[3].copy()

    def solve(self, model: SparseModel, force: np.ndarray, gap: np.ndarray,
              within: float = EXACT, steps: int = STEPS,
              start: tuple[np.ndarray, np.ndarray] | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
        """(u, λ_A) with K u + C_Aᵀλ_A = force and C_A u = gap (module docstring), to
        round-off, or until a step is below ``within`` (of F and U), or ``steps`` steps;
        from ``start`` (u, λ_A) where given, else from 0."""
        F, U = model.force_scale, model.displacement_scale  # K's solves first
        inverse, holding, updated = self.operator(model)
        if updated and steps > 1 and not _resolves(model, self, inverse):
            model.cache.modified, model.cache.updates_refused = None, True
            return self.solve(model, force, gap, within, steps, start)
        C_A, C_A_T = self.rows_of(model.C)
        u, lam = ((np.zeros(model.n_free), np.zeros(self.rows.size)) if start is None
                  else (start[0].copy(), start[1].copy()))
        last = np.inf
        for step in range(steps):
            if step == 0 and start is None:  # from u = 0, λ = 0: the residuals are the data
                r, s = force, gap
            else:
                r = force - model.K @ u - C_A_T @ lam
                s = gap - C_A @ u
            if not holding():  # nothing between the steps solves with K
                raise SolverError("the augmented factor was replaced during its solve")
            du = inverse(r + C_A_T @ (self.rho * s))
            u = u + du
            dlam = self.rho * (C_A @ u - gap)
            lam = lam + dlam
            self.steps += 1
            size = max(float(np.abs(du).max(initial=0.0)) / U,
                       float(np.abs(dlam).max(initial=0.0)) / F)
            if size <= within or (step >= 1 and SLOWER * last < size <= NOISE):
                break
            last = size
        if updated and steps > 1 and size > NOISE:  # the updated factor is too far off to
            # resolve the set (a downdate's cancellation): factored from here on
            model.cache.modified, model.cache.updates_refused = None, True
            return self.solve(model, force, gap, within, steps, start)
        if steps > 1:  # an exact solve: the force left where the rows hold goes to their λ
            lam = lam + self.held_share(C_A, force - model.K @ u - C_A_T @ lam)
        return u, lam

    def held_share(self, C_A: sp.csr_array, residual: np.ndarray) -> np.ndarray:
        """The forces on the rows that take up the part of ``residual`` that C_Aᵀ reaches:
        (C_A C_Aᵀ)⁻¹ C_A r. Where a held row is far stiffer than the dofs it holds (ρ_i of
        1e14 beside entries of K of 1e5), M_A⁻¹r moves u by less than its round-off, and a
        force left on that dof stays in r whatever the steps: random scene 91043 as a
        problem stopped with 6.3e-9 of F there, its gap closed to 1e-25. Moved into λ, the
        residual is left only where u must change."""
        factor, scale = self.gram
        return scale * factor.solve(scale * (C_A @ residual))


def augmented_values(model: SparseModel, weight: np.ndarray) -> np.ndarray:
    """The values of K + Cᵀ diag(weight) C on the analysed pattern (weight: per row, 0 for
    the rows left out)."""
    products = model.cache.products
    if products is None:
        products = model.cache.products = RowProducts.of(model.C, model.factor.engine)
    return model.factor.values + np.bincount(
        products.positions, weights=weight[products.row] * products.products,
        minlength=model.factor.values.size)


@dataclass(eq=False)
class Penalised:
    """K + C_Aᵀ E C_A on the shared analysis, factored when a solve asks for it: the penalty's
    and the augmented Lagrangian's matrix of a set (:mod:`contactqp.methods.penalty`)."""

    model: SparseModel
    values: np.ndarray = field(repr=False)
    key: tuple = field(repr=False)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        engine = self.model.factor.engine
        if engine.holds != self.key:
            self.model.force_scale  # noqa: B018 - K's solves for the scales first
            engine.factor(self.key, self.values)  # ArithmeticError where not definite
            self.model.cache.set_factorisations += 1
        return engine.solve(rhs)


def penalised(model: SparseModel, weight: np.ndarray) -> Penalised | None:
    """K + Cᵀ diag(weight) C by CHOLMOD on K's analysis, or None where K's factor is not
    CHOLMOD's."""
    if not isinstance(model.factor, CholmodK):
        return None
    return Penalised(model, augmented_values(model, weight), ("penalty", weight.tobytes()))


def augmented_set(model: SparseModel, rows: np.ndarray) -> AugmentedSet | None:
    """The augmented set solve of ``rows`` (kept: the last KEPT sets), or None where K's
    factor is not CHOLMOD's (SuperLU keeps no analysis to reuse) or the rows repeat each
    other's constraint."""
    if not isinstance(model.factor, CholmodK) or not rows.size:
        return None
    key = rows.tobytes()
    sets = model.cache.sets
    found = sets.get(key)
    if found is not None:
        return found
    from contactqp.model.saddle import gram_factor

    C_A = model.C[rows]
    gram = gram_factor(C_A)
    if gram is None:  # rows that repeat a constraint
        return None
    rho = STIFFER * model.row_stiffness[rows]
    weight = np.zeros(model.n_contacts)
    weight[rows] = rho
    found = AugmentedSet(rows.copy(), rho, augmented_values(model, weight), key,
                         update=_update(model, rows), gram=gram,
                         held_rows=(model.C, C_A, C_A.T))
    while len(sets) >= KEPT:
        sets.pop(next(iter(sets)))
    sets[key] = found
    return found


def _update(model: SparseModel, rows: np.ndarray) -> Update | None:
    """The Woodbury update from the set whose factor is held, where ``rows`` differ from it
    by 1 to UPDATE_ROWS rows; else None."""
    held = model.cache.sets.get(model.factor.engine.holds)
    if held is None:
        return None
    added, dropped = np.setdiff1d(rows, held.rows), np.setdiff1d(held.rows, rows)
    if not 0 < added.size + dropped.size <= UPDATE_ROWS:
        return None
    changed = np.concatenate((added, dropped))
    rho = STIFFER * model.row_stiffness[changed]
    return Update(held.key, sp.csr_array(model.C[changed]),
                  np.concatenate((rho[:added.size], -rho[added.size:])))


TAKEOVER_SHARE = 0.5  # taking a factor over for rank updates (its change to a simplicial LDLᵀ),
# in numeric factorisations, before one is measured (measured 0.2-0.3 on 2D Hertz models)
ROW_SHARE = 1 / 300  # an update's cost a row, in numeric factorisations, before one is
# measured (measured 1/630 to 1/100: 2D and 3D Hertz models, 1.6·10⁴ to 8.8·10⁵ dofs)
SLOWER_SOLVES = 1.5  # a solve with the simplicial factor, in supernodal ones, before one is
# measured (measured 1.4 in 2D, 2 in 3D)
SOLVES_AFTER = 8  # solves a set's factor still serves: the steps left and the check's
AMORTISED = 2.0  # numeric factorisations that taking a factor over saves: this set's and at
# least one after (a 2D contact's edge is crossed in several sets: 6 on the scaling
# benchmark's cylinder)


def _by_updates(model: SparseModel, target: AugmentedSet):
    """The factor of ``target``'s M_A by rank updates (:mod:`contactqp.model.updown`) where
    they cost less than a numeric factorisation: of the updated factor kept with the model,
    or of the engine's factor of a set, taken over; each row that enters an update and each
    that leaves a downdate. None otherwise (or where the library is not there)."""
    from contactqp.model import updown

    if updown.library() is None or model.cache.updates_refused:
        return None
    cache, engine = model.cache, model.factor.engine
    numeric = engine.numeric_seconds or model.factor.factor_seconds or 1.0
    copy = cache.modified
    if copy is not None and copy.holds == target.key:
        return copy
    # the solves left run on the simplicial factor: its extra time counts against it
    column = model.factor.column_seconds or 0.0
    slower = SOLVES_AFTER * max(0.0, (copy.column_seconds if copy is not None and
                                      copy.column_seconds else SLOWER_SOLVES * column) - column)
    row = copy.row_seconds if copy is not None and copy.row_seconds else ROW_SHARE * numeric
    options = []  # (the rows' updates, what the route costs in all, its base)
    if copy is not None and copy.holds is not None:
        rows = _changed(copy.rows, target.rows) * row
        options.append((rows, slower + rows, None))
    held = cache.sets.get(engine.holds)  # a set's factor (K's is kept for K's solves, and a
    # first set of many rows by updates of it cost twice a numeric factorisation on the 3D
    # sphere, 207 rows at 32 550 dofs)
    base = None if held is None else (held.rows, held.rho)
    if base is not None:
        made = (cache.takeover_seconds if cache.takeover_seconds is not None
                else TAKEOVER_SHARE * numeric)
        rows = _changed(base[0], target.rows) * row
        options.append((rows, made + slower + rows, base))
    # the updates must beat this set's numeric factorisation; taking the factor over and the
    # slower solves, AMORTISED of them
    options = [option for option in options if option[0] < numeric
               and option[1] < AMORTISED * numeric]
    if not options:
        return None
    _, _, base = min(options, key=lambda option: option[1])
    if base is not None:
        copy = _take_over(model, base)
        if copy is None:
            return None
    return copy if _move(model, copy, target) else None


def _resolves(model: SparseModel, target: AugmentedSet, inverse) -> bool:
    """Whether an updated factor of ``target``'s M_A solves it: M_A x = b for a random b, to
    PROBE of the terms of M_A x (a downdate's cancellation leaves digits, not all; a factor
    off by more would let the refinement stop on small steps that are not small residuals).
    One solve, before the exact solve of a set."""
    b = np.random.default_rng(0).standard_normal(model.n_free)
    x = inverse(b)
    C_A, C_A_T = target.rows_of(model.C)
    product = model.K @ x + C_A_T @ (target.rho * (C_A @ x))
    terms = (magnitude(model.K) @ np.abs(x)
             + magnitude(C_A_T) @ (target.rho * (magnitude(C_A) @ np.abs(x))) + np.abs(b))
    return bool(np.all(np.abs(product - b) <= PROBE * terms.max(initial=0.0)))


PROBE = 1e-8  # of the terms of M_A x: an updated factor that solves M_A worse is not used


def _changed(rows: np.ndarray, other: np.ndarray) -> int:
    """How many rows one set has that the other has not, both ways."""
    return int(np.setxor1d(rows, other, assume_unique=True).size)


def _take_over(model: SparseModel, base: tuple[np.ndarray, np.ndarray]):
    """The engine's numeric factor (of K + Cᵀ diag(ρ) C on the ``base`` rows and weights)
    taken over for rank updates (:meth:`contactqp.model.updown.Modified.taken_from`; the
    engine keeps its analysis and factors again when asked), kept as the model's modified
    factor; None where the machine has not the memory for the change (twice the factor's
    entries) or the library refuses."""
    from contactqp.model import updown
    from contactqp.model.factor import available_memory

    cache, engine = model.cache, model.factor.engine
    entries, available = engine.entries(), available_memory()
    if engine.spare is None or (entries is not None and available is not None
                                and 16 * entries[1] > available):
        return None
    cache.modified = None  # its memory back first
    start = time.perf_counter()
    held, engine.holds = engine.holds, None  # whatever happens, its numeric factor goes
    copy = updown.Modified.taken_from(engine.symbolic, engine.n, engine.spare)
    cache.takeover_seconds = time.perf_counter() - start
    if copy is None:
        return None
    copy.holds, copy.rows, copy.rho = held, base[0].copy(), base[1].copy()
    cache.modified = copy
    return copy


def _move(model: SparseModel, copy, target: AugmentedSet) -> bool:
    """Update ``copy`` from the set it holds to ``target``: the rows that enter first (the
    matrix stays positive definite on the way), then those that leave; False (and the copy
    dropped) where CHOLMOD refuses."""
    entering = np.setdiff1d(target.rows, copy.rows, assume_unique=True)
    leaving = np.setdiff1d(copy.rows, target.rows, assume_unique=True)
    copy.holds = None
    done = (copy.update(model.C[entering], _weights(target.rows, target.rho, entering),
                        add=True) and
            copy.update(model.C[leaving], _weights(copy.rows, copy.rho, leaving), add=False))
    if not done:
        model.cache.modified = None
        return False
    copy.holds, copy.rows, copy.rho = target.key, target.rows.copy(), target.rho.copy()
    model.cache.set_updates += 1
    return True


def _weights(rows: np.ndarray, rho: np.ndarray, which: np.ndarray) -> np.ndarray:
    """ρ of the rows ``which`` (some of ``rows``, whose weights are ``rho``)."""
    order = np.argsort(rows, kind="stable")
    return rho[order[np.searchsorted(rows, which, sorter=order)]]


__all__ = ["EXACT", "STIFFER", "AugmentedSet", "Penalised", "RowProducts", "augmented_set",
           "augmented_values", "penalised"]
