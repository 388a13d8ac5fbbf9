"""K's inertia and the modes it leaves free, for a sparse model (:mod:`contactqp.model.sparse`)
where CHOLMOD is not installed or its pivots come near 0: SuperLU's LDLᵀ pivots, each over its
own dof's diagonal entry (module docstring of :mod:`contactqp.model.sparse`), refuse an
indefinite K in one line and point to the modes a singular K leaves free, found by subspace
inverse iteration (:func:`free_modes`) and kept where the contact rows hold them and the loads
on them can be carried (:func:`loads_held`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # scipy.sparse.linalg loads at the first solve (start-up)
    import scipy.sparse.linalg as spla

from contactqp.errors import ProblemError
from contactqp.model.factor import ColumnCache, diagonal_pivots, factorise
from contactqp.problem import Problem

# a pivot below this times its own diagonal entry: a mode may be free (free_modes decides;
# 1e-10 missed a floating bar whose stiffnesses differ 1e7-fold, pivot 2.9e-10: seed 704183
# of tests/test_front_ends.py, where the scene and its problem then had other scales)
SINGULAR_PIVOT = 1e-8
NEGATIVE_PIVOT = 1e-8  # a pivot below −this times its own diagonal entry: K is indefinite
SHIFT = 1e-10  # the shift (of each dof's own diagonal) under which free modes are sought
FREE_MODE = 1e-13  # a mode whose forces are this much of what its entries make is free
MAX_MODES = 64  # free modes sought at most (six per floating body in 3D: ten bodies)
# inverse iterations: each takes a free mode's trial vector SHIFT / λ closer to it, λ the
# nearest eigenvalue that is not free, down to SINGULAR_PIVOT: (1e-10 / 1e-8)^8 = 1e-16, round-
# off. Four left 1.3e-13 of a free mode's forces beside an eigenvalue of 2.3e-8 (random scene
# 1382, floating 0.5, as a problem: over FREE_MODE, so the mode was missed and SuperLU then met
# its zero pivot, a RuntimeError); eight leave 1e-19
ITERATIONS = 8
HELD = 1e-8  # a mode x with ‖C x‖ below this × ‖C‖‖x‖ is held by no contact row


def plain_factor(K: sp.csc_matrix, ordering: str) -> tuple[spla.SuperLU, ColumnCache]:
    """K's factorisation where its tiny pivots were no free mode (:func:`free_modes`); a
    ProblemError in one line where SuperLU still meets a zero pivot."""
    try:
        factor = factorise(K, ordering)
    except RuntimeError:  # "Factor is exactly singular"
        raise ProblemError("K is singular (a zero pivot in its factorisation), but no mode it "
                           "leaves free was found to within round-off: scale K's rows to "
                           "similar stiffness, or prescribe a dof on each free body") from None
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


def factor_or_none(K: sp.csc_matrix, ordering: str
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
    for _ in range(ITERATIONS):  # (K̃ + SHIFT·I)⁻¹ y = D^½ (K + SHIFT·D)⁻¹ D^½ y
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


def held_by_contact(problem: Problem, free: np.ndarray, C: sp.csr_array,
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


def loads_held(model: Any) -> None:
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


__all__ = ["FREE_MODE", "HELD", "NEGATIVE_PIVOT", "SINGULAR_PIVOT", "elimination_order",
           "factor_or_none", "free_modes", "held_by_contact", "loads_held", "plain_factor"]
