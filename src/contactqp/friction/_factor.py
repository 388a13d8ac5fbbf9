"""One sparse factorisation of K that also gives the flexibility of the contact rows.

Every friction method and the check work on the contact rows G = [C; T] through
W = G K⁻¹ Gᵀ, the rows' flexibility (the Delassus operator of the field): the answer is
decided by a small dense problem in the contact forces, and u follows by one solve. W needs
only (K⁻¹)_cc, the block of K⁻¹ on the dofs c that the rows touch, and (K⁻¹)_cc = S⁻¹ for
S = K_cc − K_ci K_ii⁻¹ K_ic, the Schur complement of the rest. When c is eliminated last,
S is the trailing block of the factors, L_cc U_cc: one factorisation gives it, where a solve
per contact dof (2 to 4 per contact, each a full forward and back substitution) would cost
tens of factorisations at 10⁵ dofs.

SuperLU (scipy) is run in its symmetric mode without pivoting (an LDLᵀ in LU clothes, stable
for a positive definite K) on a minimum-degree ordering of K + Kᵀ. The touched dofs are made a
clique of explicit zeros in the pattern it orders, so minimum degree eliminates them last;
where it does not, a second factorisation with that ordering and the touched dofs moved to
the end does.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from contactqp.errors import ProblemError

# the dense Schur complement (nc², 8 bytes each) stays below 300 MB, the clique below 36·10⁶
# explicit zeros; past it W is made by a solve per touched dof
MAX_TOUCHED = 6000
# a pivot below this fraction of its dof's diagonal: K is singular on the free dofs (a rigid
# motion not held; positive definite pivots of an SPD K are at least λ_min ≥ this · K_ii)
SINGULAR = 1e-13
SYMMETRIC = {"SymmetricMode": True}


def _lu(matrix: sp.csc_array, ordering: str) -> sla.SuperLU:
    """SuperLU without pivoting, a refusal in one line when a pivot vanishes."""
    try:
        return sla.splu(matrix, permc_spec=ordering, diag_pivot_thresh=0.0, options=SYMMETRIC)
    except RuntimeError as error:  # "Factor is exactly singular"
        raise ProblemError(f"K: singular on the free dofs ({error}); hold every rigid motion "
                           "with prescribed dofs") from None


class Factor:
    """K = LU with the touched dofs last, its solves, and (K⁻¹) on the touched dofs.

    Parameters
    ----------
    K : scipy.sparse array, n x n
        Symmetric positive definite (the free dofs' stiffness).
    touched : int array
        The dofs the contact rows read, sorted.
    """

    def __init__(self, K: sp.csc_array, touched: np.ndarray):
        n, nc = K.shape[0], touched.size
        self.touched = touched
        self._order = None  # a permutation applied before SuperLU, when its own does not do
        schur_ready = 0 < nc <= MAX_TOUCHED
        lu = _lu(_with_clique(K, touched) if schur_ready else sp.csc_matrix(K), "MMD_AT_PLUS_A")
        if schur_ready and not _touched_last(lu, touched, n):
            elimination = np.argsort(lu.perm_c)
            rest = elimination[~np.isin(elimination, touched)]
            self._order = np.concatenate([rest, touched])
            lu = _lu(sp.csc_matrix(K[self._order][:, self._order]), "NATURAL")
            schur_ready = _touched_last(lu, np.arange(n - nc, n), n)
        self._lu = lu
        _refuse_indefinite(lu, K, self._order)
        self._schur = _schur_cholesky(lu, self._positions(), n) if schur_ready else None

    def _positions(self) -> np.ndarray:
        """Where each touched dof sits in the factors."""
        n = self._lu.shape[0]
        own = (np.arange(n - self.touched.size, n) if self._order is not None
               else self.touched)
        return self._lu.perm_c[own]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (one column or several)."""
        if self._order is None:
            return self._lu.solve(rhs)
        out = np.empty_like(rhs)
        out[self._order] = self._lu.solve(rhs[self._order])
        return out

    def flexibility(self, rows: sp.csr_array) -> np.ndarray:
        """W = G K⁻¹ Gᵀ for rows G that read only the touched dofs (dense, k x k)."""
        G = rows.tocsc()[:, self.touched].toarray()
        if self._schur is None:
            full = rows.T.toarray() if rows.shape[0] else np.zeros((rows.shape[1], 0))
            return _symmetric(rows @ self.solve(full))
        return _symmetric(G @ la.cho_solve(self._schur, G.T))


def _with_clique(K: sp.sparray, touched: np.ndarray) -> sp.csc_matrix:
    """K with explicit zeros joining every pair of touched dofs (same values, wider pattern)."""
    coo = sp.coo_matrix(K)
    ii, jj = np.meshgrid(touched, touched, indexing="ij")
    rows = np.concatenate([coo.row, ii.ravel()])
    cols = np.concatenate([coo.col, jj.ravel()])
    values = np.concatenate([coo.data, np.zeros(ii.size)])
    matrix = sp.csc_matrix((values, (rows, cols)), shape=K.shape)  # duplicates summed
    return matrix


def _touched_last(lu: sla.SuperLU, touched: np.ndarray, n: int) -> bool:
    """Whether SuperLU kept its row order equal to its column order and eliminated the
    touched dofs last."""
    tail = np.sort(lu.perm_c[touched])
    return (np.array_equal(lu.perm_r, lu.perm_c)
            and np.array_equal(tail, np.arange(n - touched.size, n)))


def _refuse_indefinite(lu: sla.SuperLU, K: sp.sparray, order: np.ndarray | None) -> None:
    """A pivot that is not positive, or negligible against its dof's diagonal: K is not
    positive definite on the free dofs (symmetric, unpivoted: the pivots are LDLᵀ's D)."""
    diagonal = np.asarray(K.diagonal(), dtype=float)
    if order is not None:
        diagonal = diagonal[order]
    own = np.argsort(lu.perm_c)  # position p holds the matrix's column own[p]
    pivots = lu.U.diagonal()
    ratio = pivots / np.where(diagonal[own] > 0.0, diagonal[own], 1.0)
    worst = int(np.argmin(ratio))
    if not ratio[worst] > SINGULAR:
        raise ProblemError(f"K: not positive definite on the free dofs (pivot {pivots[worst]:.3g}"
                           f" against a diagonal of {diagonal[own][worst]:.3g}); hold every "
                           "rigid motion with prescribed dofs")


def _schur_cholesky(lu: sla.SuperLU, positions: np.ndarray, n: int):
    """The Cholesky factor of S = L_cc U_cc, in the touched dofs' own order."""
    tail = n - positions.size
    L = sp.csc_matrix(lu.L)[:, tail:].tocsr()[tail:]
    U = sp.csc_matrix(lu.U)[:, tail:].tocsr()[tail:]
    S = (L @ U).toarray()
    local = positions - tail
    S = _symmetric(S[np.ix_(local, local)])
    try:
        return la.cho_factor(S, lower=True, check_finite=False)
    except la.LinAlgError:
        raise ProblemError("K: its Schur complement onto the contact dofs is not positive "
                           "definite (K is not positive definite on the free dofs)") from None


def _symmetric(matrix: np.ndarray) -> np.ndarray:
    """The symmetric part (a product of exact symmetric factors, up to round-off)."""
    return 0.5 * (matrix + matrix.T)
