"""The factorisations of a sparse model (:mod:`contactqp.model.sparse`): K's, and the
augmented matrices K + C_Aᵀ R C_A of the sets of rows held (:mod:`contactqp.model.augmented`).

Two engines, chosen with numbers (a study on 2D and 3D elasticity, 2·10⁴ to 10⁶ dofs, one
core): CHOLMOD's supernodal Cholesky through cvxopt, where it is installed (the optional
extra ``contactqp[cholmod]``; cvxopt is GPL-3, so it is never required), and scipy's SuperLU
otherwise. In 2D CHOLMOD factors 4–6 times faster than SuperLU (CPU 0.08 / 0.68 / 2.3 s at
2·10⁴ / 10⁵ / 3·10⁵ dofs against 0.32 / 2.7 / 9.9 s) and, unlike SuperLU, keeps its symbolic
analysis (the ordering and the supernodes) for a new matrix with the same pattern: a set of
rows held is one numeric factorisation of K + C_Aᵀ R C_A, whose pattern is fixed by giving it
once the pattern of K + Cᵀ C, every row's (:class:`Cholmod`). One analysis holds one factor at
a time; the factor says which matrix it holds and factors K again when K⁻¹ is asked after a
set's matrix (:class:`CholmodK`). A set's numeric factor can be taken over for rank updates
(:mod:`contactqp.model.updown`): the analysis then gets a copy of itself back (``spare``,
kept from the start) and factors again on it. The flexibility W = C K⁻¹ Cᵀ (the complementarity
methods) is then solved with K's factor, a block of rows at a time. cvxopt's CHOLMOD solves
those columns one by one; where cholespy (CHOLMOD again, the extra ``contactqp[cholmod]``) is
installed, a job of columns that pays for it goes to a second factor of K that it makes once
and solves a block at a time (:meth:`CholmodK.solve_many`).

The candidates measured on the Hertz models' K (benchmarks/factorisations.py; the table on
docs/benchmarks.md): SuperLU (COLAMD and minimum degree), qdldl, CHOLMOD through cvxopt,
kvxopt and cholespy, and PARDISO through pypardiso (MKL, 1.8 GB). CHOLMOD through cvxopt (or
kvxopt, the same library) factors and solves fastest on the four smaller meshes, PARDISO (both
cores) on the two largest, with 1.2 to 3.2 times the memory; cholespy's block solves are 2.0 to
2.7 times faster a column, its factorisation 2.4 to 6.9 times slower (its wheel ships the
reference BLAS). MUMPS (python-mumps 0.0.2) does not import with numpy 2, and scikit-sparse
has no wheel.

Memory. CHOLMOD's analysis plans L's entries before any is computed (:meth:`Cholmod.entries`);
a factor that needs more than the machine has available (:func:`available_memory`) is a
SolverError naming both, where the kernel would otherwise kill the process mid-factorisation
(the 3D sphere at 1.1·10⁶ dofs: 25.2 GB planned). SuperLU plans nothing ahead.

SuperLU (:func:`factorise`) runs with the minimum-degree ordering of Kᵀ + K and no pivoting off
the diagonal (K is symmetric positive definite): on a 2D grid of 8.4·10⁴ dofs it fills in less
than COLAMD and factors faster, and its pivots are LDLᵀ's, whose signs are K's inertia (the
sparse model reads them to refuse an indefinite K and to find the modes a singular K leaves
free). For the flexibility W = C K⁻¹ Cᵀ of a few rows, Z = L⁻¹ Pr Cᵀ is solved on the rows of
L each contact row reaches (its elimination-tree path, :func:`forward_columns`), kept once
computed (:class:`ColumnCache`), from SuperLU's Uᵀ.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # scipy.sparse.linalg loads at the first solve (start-up)
    import scipy.sparse.linalg as spla

ORDERING = "MMD_AT_PLUS_A"  # SuperLU's fill-reducing ordering for symmetric K
DENSE_REACH = 4000  # the forward solves go dense up to this many rows of L reached
SMALLEST_PIVOT = 1e-10  # a CHOLMOD pivot below this of K's largest diagonal entry: SuperLU
FILL = 4.0  # rows whose CᵀC has more than this times K's entries: no fixed pattern is kept
BLOCK_SAVING = 0.5  # of a CHOLMOD solve's column that cholespy's block solves save (measured
# 0.50-0.63 on the Hertz models, 3·10⁴ to 9·10⁵ dofs: benchmarks/factorisations.py) ...
BLOCK_FACTOR = 7.0  # ... against its factorisation, in CHOLMOD's (measured 2.4-6.9 times)


def factorise(K: sp.spmatrix, ordering: str = ORDERING) -> spla.SuperLU:
    """SuperLU of a symmetric positive (semi)definite K: ``ordering`` of the columns, the
    diagonal pivots kept (symmetric mode), so the factors have the symmetric fill."""
    import scipy.sparse.linalg as spla

    options = {"SymmetricMode": True} if ordering == ORDERING else {}
    return spla.splu(sp.csc_matrix(K), permc_spec=ordering,
                     diag_pivot_thresh=0.0 if ordering == ORDERING else 1.0, options=options)


def available_memory() -> int | None:
    """The memory this machine has available in bytes: Linux's MemAvailable, else all of its
    memory (the free pages elsewhere leave out what caches hold and would refuse factors that
    fit), or None where neither is known."""
    import os

    try:
        with open("/proc/meminfo") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return None


def cholespy_installed() -> bool:
    """Whether cholespy (CHOLMOD with solves of a block of columns; the extra
    ``contactqp[cholmod]``) can be imported."""
    try:
        import cholespy  # noqa: F401
    except ImportError:
        return False
    return True


def cholmod_installed() -> bool:
    """Whether CHOLMOD (cvxopt, the extra ``contactqp[cholmod]``) can be imported."""
    try:
        import cvxopt.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def lower_triangle(matrix: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, columns, values) of the entries on and below the diagonal of a square sparse
    matrix, in CSC order (column by column, rows increasing; duplicates summed), read off its
    CSC arrays (sp.tril goes through COO and back: 3 of the 8 ms of a 2D model's analysis at
    8.7·10³ dofs)."""
    csc = sp.csc_matrix(matrix)  # a copy where the format changes; never the caller's
    if not csc.has_canonical_format:
        csc = csc.copy()
        csc.sum_duplicates()  # sorts the indices too
    columns = np.repeat(np.arange(csc.shape[1]), np.diff(csc.indptr))
    keep = csc.indices >= columns
    return csc.indices[keep].astype(np.int64), columns[keep], csc.data[keep]


@dataclass(eq=False)
class Cholmod:
    """One symbolic analysis of a fixed pattern (lower triangle, CSC order: ``rows``,
    ``columns``) and the numeric factor it holds (``holds``: a key of the matrix, None at
    first)."""

    n: int
    rows: np.ndarray
    columns: np.ndarray
    symbolic: Any
    matrix: Any  # cvxopt's copy of the pattern, whose values each factorisation sets
    holds: Any = None
    numeric_seconds: float | None = None  # the last numeric factorisation's time
    spare: int | None = None  # a copy of the analysis, for rank updates to take the numeric
    # factor over (contactqp.model.updown), where CHOLMOD's library is found

    @classmethod
    def of_pattern(cls, pattern: sp.csc_matrix) -> Cholmod:
        """The analysis of a symmetric ``pattern`` (its lower triangle, explicit zeros
        kept), CHOLMOD's own ordering (AMD)."""
        rows, columns, _ = lower_triangle(pattern)
        return cls.of_triangle(pattern.shape[0], rows, columns)

    @classmethod
    def of_triangle(cls, n: int, rows: np.ndarray, columns: np.ndarray) -> Cholmod:
        """The analysis of the pattern whose lower triangle has entries at (``rows``,
        ``columns``), in CSC order (:func:`lower_triangle`)."""
        from cvxopt import cholmod, spmatrix

        from contactqp.model import updown

        # the pattern's values a scalar: no array of ones to convert (3.3·10⁵ dofs, 2.4·10⁶
        # entries: 116 ms against 163 ms)
        matrix = spmatrix(1.0, rows, columns, (n, n))
        made = cls(n, rows, columns, cholmod.symbolic(matrix), matrix)
        made.spare = updown.spare_analysis(made.symbolic)
        if made.spare is not None:
            weakref.finalize(made, updown.release, made.spare)
        return made

    def entries(self) -> tuple[int, int] | None:
        """(the entries of L, those its numeric factor stores) as the analysis plans them: the
        column counts' sum, and the supernodes' size where it is supernodal (their blocks
        store zeros too); None where they cannot be read. cvxopt does not expose them: they are
        read from CHOLMOD's cholmod_factor (its layout, the same since CHOLMOD 2: n, minor,
        Perm, ColCount, IPerm, nzmax, p, i, x, z, nz, next, prev, nsuper, ssize, xsize,
        maxcsize, maxesize, super, pi, px, s, then ordering, is_ll, is_super, is_monotonic,
        itype as ints), and kept only where they are consistent: n the pattern's, itype int or
        long, the count between the pattern's entries and n(n+1)/2, the size up to n²."""
        import ctypes

        from contactqp.model.updown import factor_address

        address = factor_address(self.symbolic)
        word = ctypes.sizeof(ctypes.c_size_t)
        if not address or word != 8 or ctypes.sizeof(ctypes.c_void_p) != 8:
            return None
        size, void = ctypes.c_size_t, ctypes.c_void_p
        n = size.from_address(address).value
        counts = void.from_address(address + 3 * word).value
        xsize = size.from_address(address + 15 * word).value
        flags = (ctypes.c_int * 5).from_address(address + 22 * word)
        is_super, itype = flags[2], flags[4]
        if n != self.n or itype not in (0, 2) or is_super not in (0, 1) or not counts:
            return None
        kind = ctypes.c_int64 if itype == 2 else ctypes.c_int32
        column = np.ctypeslib.as_array(ctypes.cast(counts, ctypes.POINTER(kind)), shape=(n,))
        count = int(column.sum(dtype=np.int64))
        stored = int(xsize) if is_super else count
        if not (self.rows.size <= count <= n * (n + 1) // 2 and count <= stored <= n * n):
            return None
        return count, stored

    def position(self, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
        """Where (row, column) entries of the lower triangle sit in the pattern's values."""
        n = np.int64(self.n)  # n² passes 2³¹ from 46 341 dofs
        keys = self.columns.astype(np.int64) * n + self.rows  # increasing: CSC order
        return np.searchsorted(keys, np.asarray(columns, dtype=np.int64) * n + rows)

    def factor(self, key: Any, values: np.ndarray) -> None:
        """Factor the matrix with ``values`` on the pattern (numeric only), kept as ``key``;
        ArithmeticError where it is not positive definite."""
        from cvxopt import cholmod, matrix

        self.holds = None
        start = time.perf_counter()
        self.matrix.V = matrix(values)  # in place: a new spmatrix sorts its entries (10x)
        cholmod.numeric(self.matrix, self.symbolic)
        self.numeric_seconds = time.perf_counter() - start
        self.holds = key

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """The held matrix's inverse times ``rhs`` (one column or several)."""
        from cvxopt import cholmod, matrix

        rhs = np.asarray(rhs, dtype=float)
        b = matrix(np.array(rhs.reshape(self.n, -1), order="F"))
        cholmod.solve(self.symbolic, b)
        return np.array(b).reshape(rhs.shape)

    def pivots(self) -> np.ndarray:
        """The pivots of the held factor, LDLᵀ's D = diag(L)², in an order CHOLMOD keeps to
        itself (its post-ordering)."""
        from cvxopt import cholmod

        return np.array(cholmod.diag(self.symbolic)).reshape(-1) ** 2


@dataclass(eq=False)
class CholmodK:
    """K's factorisation by CHOLMOD, on the analysis the sets' matrices share: ``solve``
    factors K again where a set's matrix took its place. ``values``: K on the pattern.
    ``solve_many``: a job of many columns, by a second factor of K that cholespy makes where
    it is installed and pays for itself (``blocks``); ``factor_seconds`` and
    ``column_seconds`` (K's analysis and factorisation, a column of a solve: timed) say when.
    """

    engine: Cholmod
    values: np.ndarray
    factorisations: int = 1
    factor_seconds: float = 0.0
    column_seconds: float | None = None  # a column of CHOLMOD's last solve with K
    blocks: Any = None  # cholespy's factor of K, once made (False where it refused K)

    def held(self) -> Cholmod:
        if self.engine.holds != "K":
            self.engine.factor("K", self.values)
            self.factorisations += 1
        return self.engine

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        engine = self.held()
        start = time.perf_counter()
        x = engine.solve(rhs)
        self.column_seconds = (time.perf_counter() - start) / max(1, x.size // self.engine.n)
        return x

    def blocks_pay(self, columns: int) -> bool:
        """Whether a job of ``columns`` solves pays for cholespy's factor of K: each column
        BLOCK_SAVING of a CHOLMOD solve saved against BLOCK_FACTOR CHOLMOD factorisations
        (made already, or cholespy not installed: whether it is made)."""
        if self.blocks is not None:
            return self.blocks is not False
        if self.column_seconds is None or not cholespy_installed():
            return False
        return columns * BLOCK_SAVING * self.column_seconds > BLOCK_FACTOR * self.factor_seconds

    def solve_many(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs for n x k ``rhs``, one block of a job that :meth:`blocks_pay` for:
        cvxopt's CHOLMOD solves column by column, cholespy's a block at once, 2.0 to 2.7 times
        faster a column on the Hertz models (benchmarks/factorisations.py), for a second
        factorisation of K, 2.4 to 6.9 times cvxopt's (its wheel ships the reference BLAS);
        :meth:`solve` where cholespy is not installed (the extra ``cholmod``)."""
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim != 2 or not cholespy_installed() or self.blocks is False:
            return self.solve(rhs)
        if self.blocks is None:
            import cholespy

            from contactqp.progress import silenced

            rows, columns = self.engine.rows, self.engine.columns  # K's lower triangle, CSC
            pointers = np.searchsorted(columns, np.arange(self.engine.n + 1))
            try:
                with silenced():  # CHOLMOD's own warning where it refuses K, from C
                    self.blocks = cholespy.CholeskySolverD(
                        self.engine.n, pointers.astype(np.int32), rows.astype(np.int32),
                        np.ascontiguousarray(self.values, dtype=float),
                        cholespy.MatrixType.CSC)
            except (ValueError, RuntimeError):  # not positive definite to its pivots
                self.blocks = False
                return self.solve(rhs)
        b = np.ascontiguousarray(rhs)
        x = np.zeros_like(b)
        self.blocks.solve(b, x)
        return x


def cholmod_of(K: sp.csc_matrix, C: sp.csr_array) -> CholmodK | None:
    """K's CHOLMOD factor on the pattern of K + CᵀC, or None where CHOLMOD is not installed,
    where the rows' CᵀC would more than FILL-fold K's entries, or where a pivot is not above
    SMALLEST_PIVOT of K's largest diagonal entry (K indefinite, singular, nearly singular, or
    of a stiffness contrast that hides which: SuperLU's pivots, each over its own dof's
    entry, then say which; CHOLMOD's post-ordering keeps its pivots' dofs to itself)."""
    if not cholmod_installed() or K.shape[0] == 0:
        return None
    start = time.perf_counter()
    rows, columns, data = lower_triangle(K)
    if (np.diff(C.indptr).max(initial=0) <= 1
            and np.count_nonzero(rows == columns) == K.shape[0]):
        # each row reads one dof at most and K keeps every diagonal entry: CᵀC, diagonal,
        # adds no entry to K's pattern (the Hertz models), so no sum of patterns is formed
        engine = Cholmod.of_triangle(K.shape[0], rows, columns)
        values = data.astype(float)  # K's values in place
    else:
        gram = abs(C.T) @ abs(C)
        if gram.nnz > FILL * max(K.nnz, 1):
            return None
        engine = Cholmod.of_pattern(sp.csc_matrix(abs(K) + gram))
        if np.array_equal(rows, engine.rows) and np.array_equal(columns, engine.columns):
            values = data.astype(float)  # the rows add no entry to K's: in place
        else:
            values = np.bincount(engine.position(rows, columns), weights=data,
                                 minlength=engine.rows.size).astype(float, copy=False)
    needed, available = 8 * (engine.entries() or (0, 0))[1], available_memory()
    if available is not None and needed > available:
        from contactqp.errors import SolverError

        raise SolverError(
            f"K's Cholesky factor ({K.shape[0]} dofs) needs {needed / 1e9:.1f} GB (CHOLMOD's "
            f"analysis: {needed // 8:.3g} entries of L) and this machine has "
            f"{available / 1e9:.1f} GB available: engine='amg' solves K without a factor "
            "(pip install contactqp[amg])")
    try:
        engine.factor("K", values)
    except ArithmeticError:
        return None
    if not engine.pivots().min(initial=np.inf) > SMALLEST_PIVOT * K.diagonal().max():
        return None
    return CholmodK(engine, values, factor_seconds=time.perf_counter() - start)


@dataclass(eq=False)
class ColumnCache:
    """Z_i = U⁻ᵀ Pr c_i for the rows asked for so far, dense on the rows they reach
    (``support``, increasing; ``values``: support x rows, in the order computed):
    W = C K⁻¹ Cᵀ = Zᵀ D Z (:meth:`SparseModel.flexibility`)."""

    pivots: np.ndarray | None = None  # D: SuperLU's diag(U) (U = D Lᵀ)
    where: dict[int, int] = field(default_factory=dict)
    support: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    values: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    parent: np.ndarray | None = None  # the elimination tree of L
    lower: sp.csr_matrix | None = None  # Uᵀ (SuperLU builds a new copy at each .U)
    solves: int = 0  # columns computed
    solver: tuple[bytes, Any, bool] | None = None  # (rows, W_AA's solver, singular) of the
    # last set solved
    sets: dict[bytes, Any] = field(default_factory=dict)  # augmented set solves, by rows
    products: Any = None  # every row's CᵀC on the augmented pattern (model.augmented)
    set_factorisations: int = 0  # numeric factorisations of augmented matrices
    modified: Any = None  # a set's factor that rank updates move to other sets
    # (contactqp.model.updown.Modified), once made
    set_updates: int = 0  # sets reached by rank updates of ``modified``
    takeover_seconds: float | None = None  # the last factor taken over for ``modified``, timed
    updates_refused: bool = False  # an updated factor that did not resolve its set: none since
    compliance: np.ndarray | None = None  # W_ii per row where solved so far (NaN elsewhere;
    # CHOLMOD's factor: each is a solve, asked by the LCP's W and the check's own s)

    def add(self, rows: list[int], nodes: np.ndarray, y: np.ndarray) -> None:
        """Keep the columns y (on ``nodes``) of ``rows``."""
        support = np.union1d(self.support, nodes)
        values = np.zeros((support.size, self.values.shape[1] + len(rows)))
        values[np.searchsorted(support, self.support), : self.values.shape[1]] = self.values
        values[np.searchsorted(support, nodes), self.values.shape[1]:] = y
        start = len(self.where)
        self.where.update({row: start + k for k, row in enumerate(rows)})
        self.support, self.values, self.solves = support, values, self.solves + len(rows)


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
    """(the rows reached, Z there): Z = lower⁻¹ Pr Cᵀ for some rows of C, solved on the rows
    it reaches alone. A contact row's column is zero off its elimination-tree path: 80 rows of
    the benchmark grid reach 2·10³ of its 8.4·10⁴ dofs together, so this costs a fraction of
    one solve with K (dense up to DENSE_REACH rows)."""
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


__all__ = ["ORDERING", "Cholmod", "CholmodK", "ColumnCache", "cholmod_installed",
           "cholmod_of", "diagonal_pivots", "elimination_tree", "factorise",
           "forward_columns", "lower_triangle", "reach"]
