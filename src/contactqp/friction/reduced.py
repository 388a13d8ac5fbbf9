"""The answer in the contact forces alone: the sets, the equations on a set, the active set.

With u = K⁻¹(f − Gᵀλ) every condition of a friction problem is a condition on the forces
λ = (λ_N, λ_T) and on what the rows read, w = G u − h = b − Wλ (b = G u₀ − h, W the rows'
flexibility, :mod:`.model`): w_N = C u − g is minus the gap, w_T = T(u − u_prev) the slip.

A **set** says of each contact whether its normal row is closed (w_N = 0) or open
(λ_N = 0), and whether it sticks (w_T = 0) or slips (λ_T = sᵢ ŵ, its friction force at the
bound and along the slip; ŵ = w_T/‖w_T‖, in 2D the sign σᵢ the set carries). On a set the
conditions are equations, linear in 2D (Tresca and Coulomb alike: λ_T = σ μ λ_N), smooth in
3D; :func:`solve_on_set` solves them by Newton's method. The answer is the solution of its own
set's equations that meets every inequality: λ_N ≥ 0 where closed, w_N ≤ 0 where open,
‖λ_T‖ ≤ sᵢ where sticking, w_T along the slip direction where slipping.

:func:`active_set` finds that set by the primal–dual active-set rule (Hintermüller, Ito and
Kunisch's semismooth Newton for the box; Alart and Curnier's for friction): closed where
λ_N + k w_N > 0, slipping where ‖λ_T + k w_T‖ > sᵢ in the direction of that vector, k each
row's stiffness. For Tresca in 2D it solves a box-constrained QP in λ and stops on a set that
repeats and meets every inequality: the exact answer, up to the dense solves' round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la

from contactqp.friction.law import COULOMB, Law
from contactqp.friction.model import FrictionModel

NEWTON = 30  # Newton steps on one set (2D: one step and one to confirm)
SETTLED = 1e-13  # a set's equations below this of the force and length scales are solved
MAX_SETS = 100  # the active set's changes before it gives up
# the rule moves a slip zone's edge by about one row per step on a long zone (a bar on a
# bed: 81 steps for 160 nodes); past this many steps from zero it restarts from the dual
# solved by an interior point method, after which it needs a few
QUICK_SETS = 25
NIL_SLIP = 1e-12  # a 3D slip this small against its bound (as a force) has no direction
SINGULAR = 1e-14  # a reciprocal condition number below this: the set's equations are singular


@dataclass(frozen=True, eq=False)
class Sets:
    """Which contacts are closed, which slip, and in which direction.

    Attributes
    ----------
    closed : bool array, m
        The normal row holds (w_N = 0); all True with no normal rows.
    slip : bool array, m
        The friction force is at its bound, along the slip.
    direction : array, m x d
        The slip direction of each slipping contact (a unit vector; ±1 in 2D), zero elsewhere.
    """

    closed: np.ndarray
    slip: np.ndarray
    direction: np.ndarray

    def key(self) -> bytes:
        """The set as bytes (directions by sign in 2D, ignored in 3D, where they are
        solved for)."""
        sign = np.sign(self.direction[:, 0]) if self.direction.shape[1] == 1 else 0 * self.slip
        return self.closed.tobytes() + self.slip.tobytes() + sign.astype(np.int8).tobytes()


def split(model: FrictionModel, vector: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
    """(normal part, tangential part m x d) of a vector over the rows G = [C; T]."""
    mN = model.normal_rows
    normal = vector[:mN] if mN else None
    return normal, vector[mN:].reshape(model.contacts, model.d)


def join(normal: np.ndarray | None, tangential: np.ndarray) -> np.ndarray:
    """The vector over the rows G = [C; T] of a normal and a tangential (m x d) part."""
    tangential = np.asarray(tangential, dtype=float).ravel()
    return tangential if normal is None else np.concatenate([normal, tangential])


def zero_friction(model: FrictionModel, law: Law, closed: np.ndarray) -> np.ndarray:
    """Contacts whose friction force is zero by the law: no friction at all, or (Coulomb)
    an open contact."""
    zero = ~law.frictional
    return zero | ~closed if law.kind == COULOMB else zero


def equations(model: FrictionModel, law: Law, sets: Sets, forces: np.ndarray,
              reads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The residual R(λ) of a set's equations and its Jacobian dR/dλ, where w = b − Wλ.

    Parameters
    ----------
    forces : array, k
        λ = (λ_N, λ_T).
    reads : array, k
        w = (C u − g, T(u − u_prev)) at those forces.
    """
    W, mN, d, m = model.flexibility, model.normal_rows, model.d, model.contacts
    k = forces.size
    residual, jacobian = np.empty(k), np.zeros((k, k))
    inert = model.inert
    if mN:
        closed = np.flatnonzero(sets.closed & ~inert[:mN])
        open_ = np.flatnonzero(~sets.closed | inert[:mN])
        residual[closed], jacobian[closed] = reads[closed], -W[closed]
        residual[open_], jacobian[open_, open_] = forces[open_], 1.0
    lam_N, lam_T = split(model, forces)
    _, w_T = split(model, reads)
    bound = law.bound(lam_N)
    zero = zero_friction(model, law, sets.closed)
    stick = ~zero & ~sets.slip
    slip = ~zero & sets.slip
    rows = mN + d * np.arange(m)[:, None] + np.arange(d)  # the tangential rows of each contact
    for contacts, kind in ((zero, "zero"), (stick, "stick"), (slip, "slip")):
        own = rows[contacts]
        if own.size == 0:
            continue
        flat = own.ravel()
        if kind == "stick":
            residual[flat[inert[flat]]] = forces[flat[inert[flat]]]
            jacobian[flat[inert[flat]], flat[inert[flat]]] = 1.0
            flat = flat[~inert[flat]]
        if kind == "zero":
            residual[flat], jacobian[flat, flat] = forces[flat], 1.0
        elif kind == "stick":
            residual[flat], jacobian[flat] = reads[flat], -W[flat]
        else:
            _slip_equations(law, sets, contacts, own, lam_T, w_T, bound, W, residual,
                            jacobian, model.tangential_stiffness)
    return residual, jacobian


def _slip_equations(law: Law, sets: Sets, contacts: np.ndarray, own: np.ndarray,
                    lam_T: np.ndarray, w_T: np.ndarray, bound: np.ndarray, W: np.ndarray,
                    residual: np.ndarray, jacobian: np.ndarray,
                    stiffness: np.ndarray) -> None:
    """λ_T − s ŵ = 0 on slipping contacts (in 2D ŵ is the set's sign; in 3D the slip's own
    direction, whose derivative is (I − ŵŵᵀ)/‖w‖ dw/dλ, dw/dλ = −W). A 3D contact whose slip
    is nil (k‖w‖ within NIL_SLIP of its bound: a set corrected from sticking starts there)
    takes the set's direction, the active-set rule's trial ‖λ_T + k w_T‖, held fixed for
    that step: the slip's own direction is round-off there."""
    index = np.flatnonzero(contacts)
    s = bound[index]
    d = own.shape[1]
    if d == 1:
        direction = sets.direction[index]
        moving = np.zeros(index.size, bool)
    else:
        length = np.linalg.norm(w_T[index], axis=1)
        moving = length * stiffness[index] > NIL_SLIP * s
        direction = np.where(moving[:, None],
                             w_T[index] / np.where(moving, length, 1.0)[:, None],
                             sets.direction[index])
    residual[own] = lam_T[index] - s[:, None] * direction
    for local, rows in enumerate(own):
        jacobian[rows, rows] = 1.0
        if moving[local]:
            hat = direction[local]
            projector = (np.eye(d) - np.outer(hat, hat)) / length[local]
            jacobian[rows] += s[local] * projector @ W[rows]
        if law.kind == COULOMB:  # s = μ λ_N: the bound moves with the normal force
            jacobian[rows, index[local]] -= law.values[index[local]] * direction[local]


def solve_on_set(model: FrictionModel, law: Law, sets: Sets, b: np.ndarray,
                 start: np.ndarray) -> tuple[np.ndarray, bool]:
    """The forces that meet a set's equations (Newton's method from ``start``).

    Returns
    -------
    forces : array, k
    solved : bool
        False where the equations are singular or Newton's method does not settle.
    """
    W = model.flexibility
    forces = start.copy()
    scale = _scale(forces, b, model)
    for _ in range(NEWTON):
        residual, jacobian = equations(model, law, sets, forces, b - W @ forces)
        if np.abs(residual).max(initial=0.0) <= SETTLED * scale:
            return forces, True
        step = newton_step(jacobian, residual)
        if step is None:
            return forces, False
        forces = forces - step
        if not np.all(np.isfinite(forces)):
            return start, False
    residual, _ = equations(model, law, sets, forces, b - W @ forces)
    return forces, bool(np.abs(residual).max(initial=0.0) <= 1e3 * SETTLED * scale)


def newton_step(jacobian: np.ndarray, residual: np.ndarray) -> np.ndarray | None:
    """J⁻¹R, or None where J is singular. The rows that fix one force each (an open row, a
    frictionless or a Tresca slipping contact: a row of the identity) are taken out first, so
    the dense solve is only as large as the rows held (closed, sticking, Coulomb slipping)."""
    unit = (np.count_nonzero(jacobian, axis=1) == 1) & (np.diag(jacobian) == 1.0)
    step = np.empty_like(residual)
    step[unit] = residual[unit]
    rest = np.flatnonzero(~unit)
    if rest.size == 0:
        return step
    block = jacobian[np.ix_(rest, rest)]
    right = residual[rest] - jacobian[np.ix_(rest, np.flatnonzero(unit))] @ step[unit]
    try:
        lu = la.lu_factor(block, check_finite=False)
    except (la.LinAlgError, ValueError):
        return None
    diagonal = np.abs(np.diag(lu[0]))
    if diagonal.min(initial=1.0) <= SINGULAR * diagonal.max(initial=1.0):
        return None
    step[rest] = la.lu_solve(lu, right, check_finite=False)
    return step


def _scale(forces: np.ndarray, b: np.ndarray, model: FrictionModel) -> float:
    """A size for the equations' residuals, which mix forces and lengths (force units: a
    length times its row's stiffness)."""
    lengths = np.abs(b) * model.row_stiffness
    return max(float(np.abs(forces).max(initial=0.0)), float(lengths.max(initial=0.0)), 1e-300)


def next_sets(model: FrictionModel, law: Law, forces: np.ndarray, reads: np.ndarray) -> Sets:
    """The active-set rule: closed where λ_N + k w_N > 0, slipping where ‖λ_T + k w_T‖
    exceeds the bound, in that vector's direction (k each row's stiffness)."""
    k = model.row_stiffness
    lam_N, lam_T = split(model, forces)
    kN, _ = split(model, k)
    kT = model.tangential_stiffness[:, None]
    w_N, w_T = split(model, reads)
    closed = (np.ones(model.contacts, bool) if lam_N is None else lam_N + kN * w_N > 0.0)
    trial = lam_T + kT * w_T
    length = np.linalg.norm(trial, axis=1)
    bound = law.bound(None if lam_N is None else np.where(closed, lam_N + kN * w_N, 0.0))
    slip = (length > bound) & ~zero_friction(model, law, closed)
    direction = np.where(slip[:, None], trial / np.where(length > 0.0, length, 1.0)[:, None], 0.0)
    return Sets(closed, slip, direction)


def violations(model: FrictionModel, law: Law, sets: Sets, forces: np.ndarray,
               reads: np.ndarray) -> np.ndarray:
    """How far each inequality of a set is missed, as a force (k·length for the reads):
    normal forces that pull, open rows that pass, sticking friction past its bound,
    slips against their direction. Zero where the set's answer is the answer."""
    kN, _ = split(model, model.row_stiffness)
    kT = model.tangential_stiffness
    lam_N, lam_T = split(model, forces)
    w_N, w_T = split(model, reads)
    misses = []
    if lam_N is not None:
        misses.append(np.where(sets.closed, -lam_N, kN * w_N))
    zero = zero_friction(model, law, sets.closed)
    bound = law.bound(lam_N)
    size = np.linalg.norm(lam_T, axis=1)
    excess = size - bound
    # in 3D the set's equations turn λ_T along the slip itself: the slip must not vanish
    direction = (sets.direction if model.d == 1
                 else lam_T / np.where(size > 0.0, size, 1.0)[:, None])
    against = -np.sum(w_T * direction, axis=1) * kT
    misses.append(np.where(zero, 0.0, np.where(sets.slip, against, excess)))
    return np.maximum(np.concatenate(misses), 0.0)


def active_set(model: FrictionModel, law: Law, b: np.ndarray, start: np.ndarray | None = None,
               accept: float = 1e-12, max_sets: int = MAX_SETS
               ) -> tuple[np.ndarray, Sets, int, str]:
    """The exact answer by the active-set rule (module docstring).

    Parameters
    ----------
    b : array, k
        G u₀ − h: what the rows read with no contact force.
    start : array, k, optional
        Forces to start from (a previous increment's); default zero.
    accept : float
        The inequalities may be missed by this fraction of the force scale (round-off).
    max_sets : int
        The set changes allowed.

    Returns
    -------
    forces, sets, iterations, status
        ``status`` is ``"solved"``, or ``"cycled"`` / ``"not converged"`` / ``"singular"``
        with the last forces.
    """
    W = model.flexibility
    forces = np.zeros(b.size) if start is None else start.copy()
    sets = next_sets(model, law, forces, b - W @ forces)
    seen = {sets.key()}
    for iteration in range(1, max_sets + 1):
        forces, solved = solve_on_set(model, law, sets, b, forces)
        if not solved:
            return forces, sets, iteration, "singular"
        reads = b - W @ forces
        scale = _scale(forces, b, model)
        if violations(model, law, sets, forces, reads).max(initial=0.0) <= accept * scale:
            return forces, sets, iteration, "solved"
        sets = next_sets(model, law, forces, reads)
        if sets.key() in seen and model.d == 1:
            return forces, sets, iteration, "cycled"
        seen.add(sets.key())
    return forces, sets, max_sets, "not converged"
