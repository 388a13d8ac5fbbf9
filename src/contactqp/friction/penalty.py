"""The penalty method and the augmented Lagrangian with friction, as the field uses them.

Glossary as :mod:`.model`; ε_N, ε_T the penalties of the normal and the tangential rows
(force/length), λ̄ the multipliers the augmented Lagrangian carries (zero for the penalty).
The regularised law (Wriggers, *Computational Contact Mechanics*, ch. 5: a stiff spring in
each direction and the return mapping of plasticity on the tangential one):

    λ_N,i = ⟨λ̄_N,i + ε_N,i (C_i u − g_i)⟩₊          a penetration pushes back
    t_i   = λ̄_T,i + ε_T,i v_i,  v_i = T_i(u − u_prev)  the trial friction force
    λ_T,i = t_i where |t_i| ≤ b_i (stick), b_i sign(t_i) where not (slip),
    b_i   = s_i (Tresca) or μ_i λ_N,i (Coulomb).

For fixed states (each contact closed or open, stuck or slipping one way) the law is linear
in u: one sparse LU of K + C_Aᵀ ε_N C_A + T_Sᵀ ε_T T_S (plus, for Coulomb, the coupling
T_Pᵀ μ σ ε_N C_P of the slipping contacts, not symmetric). The states are updated from the
answer until they repeat (an active-set, semismooth Newton loop; ``"cycled"`` if they
come back to an earlier one). The augmented Lagrangian (Uzawa's update; Simo and Laursen
1992) then sets λ̄ ← λ and solves again, until λ changes by less than ``tolerance`` of F.

What each leaves: the penalty a penetration λ_N/ε_N and, where a contact sticks, a creep
λ_T/ε_T, so its answer is not the law's and the check says so (flagged unless ε is large
enough for them to fall within the tolerances); the augmented Lagrangian drives both to zero
with a moderate ε.

In 3D (d = 2 rows per contact) a slipping contact's force b t/‖t‖ turns with its trial force,
so the law is nonlinear within a state: the states and u are found together by Newton's
method with the consistent tangent of the return mapping (Simo and Taylor 1985; Wriggers
§10.5): a slipping contact adds T_iᵀ b ε_T (I − t̂t̂ᵀ)/‖t‖ T_i (and, for Coulomb, T_iᵀ μ t̂
ε_N C_i), a sticking one T_iᵀ ε_T T_i, a closed one C_iᵀ ε_N C_i. It stops when the states
repeat and the step is below NEWTON_STEP of the largest displacement.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from contactqp.errors import ProblemError, SolverError
from contactqp.friction.answer import FrictionAnswer, force_scale, make_answer
from contactqp.friction.law import COULOMB, Law
from contactqp.friction.model import FrictionModel
from contactqp.friction.reduced import join, split
from contactqp.model.base import AUGMENTED_PER_STIFFNESS, PENALTY_PER_STIFFNESS, row_stiffness

MAX_STATES = 100  # state updates per solve before the loop is stopped ("not settled")
NEWTON_STEP = 1e-13  # 3D: a Newton step this small of the largest displacement has settled
HALVINGS = 30  # 3D: a Newton step halved at most this often (then taken as it is)
MAX_ITERATIONS = 100  # the augmented Lagrangian's updates of λ̄ (default)
TOLERANCE = 1e-10  # of F: the change of λ that ends the augmented Lagrangian (default)


def solve_penalised(model: FrictionModel, law: Law, previous_u: np.ndarray | None,
                    augmented: bool, options: dict) -> FrictionAnswer:
    """One increment by the penalty (``augmented=False``) or the augmented Lagrangian
    (module docstring). ``options``: ``penalty`` (one ε for every row, force/length; default
    PENALTY_PER_STIFFNESS, or AUGMENTED_PER_STIFFNESS, times each row's stiffness
    c_iᵀK c_i/(c_iᵀc_i)²), ``max_iterations`` and ``tolerance`` (the augmented Lagrangian's)."""
    start = time.perf_counter()
    previous_u = model.previous(previous_u)
    eps = _penalties(model, options.get("penalty"), augmented)
    targets = model.targets(previous_u)
    lam_bar = np.zeros(model.rows.shape[0])
    updates = options.get("max_iterations", MAX_ITERATIONS) if augmented else 1
    tolerance = options.get("tolerance", TOLERANCE)
    history: list[float] = []
    u = model.unloaded
    status, states_total = "solved", 0
    settle = _settle if model.d == 1 else _newton
    for _ in range(updates):
        u, lam, settled, states = settle(model, law, eps, lam_bar, targets, u)
        states_total += states
        if settled is not True:
            status = settled
            break
        if not augmented:
            break
        change = float(np.abs(lam - lam_bar).max(initial=0.0)) / force_scale(model, law, lam)
        history.append(change)
        lam_bar = lam
        if change <= tolerance:
            status = "converged"
            break
    else:
        status = "not converged" if augmented else status
    run = {"method": "augmented" if augmented else "penalty", "status": status,
           "iterations": len(history) if augmented else states_total,
           "seconds": time.perf_counter() - start, "history": history,
           "info": {"states": states_total, "penalty_normal": _largest(eps[:model.normal_rows]),
                    "penalty_tangential": _largest(eps[model.normal_rows:])}}
    return make_answer(model, law, u, lam, previous_u, run)


def _largest(values: np.ndarray) -> float:
    return float(values.max(initial=0.0))


def _penalties(model: FrictionModel, penalty, augmented: bool) -> np.ndarray:
    """ε per row of G = [C; T]: the option's one value, or the default per row stiffness."""
    if penalty is not None:
        return np.full(model.rows.shape[0], float(penalty))
    stiffness = row_stiffness(model.K, model.rows)  # NaN on a row that reads no free dof
    stiffness = np.where(np.isfinite(stiffness), stiffness, 0.0)
    if model.d > 1:  # one ε_T per contact, its rows' largest, so that t keeps v's direction
        mN = model.normal_rows
        tangential = stiffness[mN:].reshape(model.contacts, model.d).max(axis=1)
        stiffness[mN:] = np.repeat(tangential, model.d)
    return (AUGMENTED_PER_STIFFNESS if augmented else PENALTY_PER_STIFFNESS) * stiffness


def _law_forces(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
                reads: np.ndarray) -> tuple[np.ndarray, tuple]:
    """(λ by the regularised law at ``reads`` = G u − h, the states: closed, stick, sign)."""
    _, eps_T = split(model, eps)
    _, bar_T = split(model, lam_bar)
    _, slip = split(model, reads)
    closed, lam_N = _normal_law(model, eps, lam_bar, reads)
    bound = law.bound(lam_N)
    trial_T = bar_T[:, 0] + eps_T[:, 0] * slip[:, 0]
    stick = np.abs(trial_T) <= bound
    sign = np.sign(trial_T)
    lam_T = np.where(stick, trial_T, bound * sign)
    return join(lam_N, lam_T[:, None]), (closed, stick, sign)


def _normal_law(model: FrictionModel, eps: np.ndarray, lam_bar: np.ndarray,
                reads: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(closed, λ_N): λ_N = ⟨λ̄_N + ε_N (C u − g)⟩₊ per contact; all closed and None with no
    normal rows."""
    if not model.normal_rows:
        return np.ones(model.contacts, dtype=bool), None
    eps_N, _ = split(model, eps)
    bar_N, _ = split(model, lam_bar)
    read_N, _ = split(model, reads)
    trial_N = bar_N + eps_N * read_N
    closed = trial_N > 0.0
    return closed, np.where(closed, trial_N, 0.0)


def _settle(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
            targets: np.ndarray, u: np.ndarray):
    """(u, λ, True or what stopped it, state updates) of the regularised law with λ̄ fixed:
    the states from the answer, the answer from the states, until they repeat."""
    G = model.rows
    seen: list[bytes] = []  # the states solved for, in turn
    solved = None
    for count in range(1, MAX_STATES + 1):
        lam, states = _law_forces(model, law, eps, lam_bar, G @ u - targets)
        if seen and _key(states) == seen[-1]:  # the law at u is the states u solves
            return u, lam, True, count - 1
        if solved is not None:  # a slip that turns round sticks first (the return
            closed, stick, sign = states  # mapping's elastic predictor): no flip in one step
            turned = ~stick & ~solved[1] & (sign == -solved[2])
            states = (closed, stick | turned, np.where(turned, solved[2], sign))
        if _key(states) in seen:
            return u, lam, "cycled", count - 1
        seen.append(_key(states))
        solved = states
        u = _solve_states(model, law, eps, lam_bar, targets, states)
    lam, _ = _law_forces(model, law, eps, lam_bar, G @ u - targets)
    return u, lam, "not settled", MAX_STATES


def _key(states: tuple) -> bytes:
    """The states as bytes (a sticking contact's sign left out: it changes nothing)."""
    closed, stick, sign = states
    return b"".join(np.asarray(s, dtype=np.int8).tobytes()
                    for s in (closed, stick, np.where(stick, 0.0, sign)))


def _solve_states(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
                  targets: np.ndarray, states: tuple) -> np.ndarray:
    """u with the states fixed: K u + Cᵀλ_N(u) + Tᵀλ_T(u) = f, each force linear in u."""
    closed, stick, sign = states
    mN = model.normal_rows
    eps_N, eps_T = split(model, eps)
    bar_N, bar_T = split(model, lam_bar)
    h_N, h_T = split(model, targets)
    T = model.T
    matrix = model.K.tocsr()
    rhs = model.load.copy()
    slip = ~stick
    # stick: λ_T = λ̄_T + ε_T (T u − c)
    k_T = np.where(stick, eps_T[:, 0], 0.0)
    matrix = matrix + T.T @ sp.diags_array(k_T) @ T
    rhs -= T.T @ np.where(stick, bar_T[:, 0] - eps_T[:, 0] * h_T[:, 0], 0.0)
    if mN:
        C = model.C
        k_N = np.where(closed, eps_N, 0.0)
        matrix = matrix + C.T @ sp.diags_array(k_N) @ C
        rhs -= C.T @ np.where(closed, bar_N - eps_N * h_N, 0.0)
    if law.kind == COULOMB:  # slipping and closed: λ_T = μ σ (λ̄_N + ε_N (C u − g))
        coupled = slip & closed
        weight = np.where(coupled, law.values * sign, 0.0)
        matrix = matrix + T.T @ sp.diags_array(weight * eps_N) @ model.C
        rhs -= T.T @ (weight * (bar_N - eps_N * h_N))
    else:  # Tresca: λ_T = s σ
        rhs -= T.T @ np.where(slip, law.values * sign, 0.0)
    try:
        return spla.splu(sp.csc_array(matrix)).solve(rhs)
    except RuntimeError as error:  # an exactly singular matrix
        raise SolverError(f"the penalised system is singular ({error})") from None


def _newton(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
            targets: np.ndarray, u: np.ndarray):
    """3D: (u, λ, True or what stopped it, Newton steps) of the regularised law with λ̄
    fixed, by Newton's method on r(u) = K u − f + Gᵀλ(u) = 0 with the consistent tangent
    K + Gᵀ M G, each step halved until ‖r‖ falls (the stiff penalty makes a slip's direction
    swing by a full step; module docstring). Where no halving lowers ‖r‖ it creeps: on the
    Cattaneo spheres at the default ε (1e6 × the rows' stiffness) it does not settle within
    MAX_STATES steps, and says so ("not settled")."""
    G = model.rows

    def residual(u):
        lam, M, key = _law_3d(model, law, eps, lam_bar, G @ u - targets)
        return model.K @ u - model.load + G.T @ lam, lam, M, key

    r, lam, M, key = residual(u)
    last = None
    for count in range(1, MAX_STATES + 1):
        step = _tangent_solve(model, M, r)
        settled = (np.abs(step).max(initial=0.0)
                   <= NEWTON_STEP * max(float(np.abs(u).max(initial=0.0)), 1e-300))
        if key == last and settled:
            return u, lam, True, count - 1
        last = key
        size = np.linalg.norm(r)
        for halving in range(HALVINGS + 1):
            trial = u - 0.5**halving * step
            found = residual(trial)
            if np.linalg.norm(found[0]) < (1.0 - 1e-4 * 0.5**halving) * size:
                break
        u, (r, lam, M, key) = trial, found
    return u, lam, "not settled", MAX_STATES


def _tangent_solve(model: FrictionModel, M: sp.csr_array, r: np.ndarray) -> np.ndarray:
    """(K + Gᵀ M G)⁻¹ r by K's factorisation, shared with the exact route and the check, and
    the rows' flexibility W = G K⁻¹ Gᵀ (Woodbury): y = K⁻¹ r, then
    y − K⁻¹Gᵀ (I + M W)⁻¹ M G y; one small dense solve per step, no new factorisation.
    Where K cannot be factorised (a body held by its contacts alone) or I + M W is singular,
    the tangent is factorised whole (SuperLU)."""
    G = model.rows
    try:
        W = model.flexibility
        y = model.factor.solve(r)
        z = np.linalg.solve(np.eye(W.shape[0]) + M @ W, M @ (G @ y))
        if np.all(np.isfinite(z)):
            return y - model.factor.solve(G.T @ z)
    except (ProblemError, np.linalg.LinAlgError):
        pass
    tangent = sp.csc_array(model.K + G.T @ M @ G)
    try:
        return spla.splu(tangent).solve(r)
    except RuntimeError as error:  # an exactly singular tangent
        raise SolverError(f"the penalised tangent is singular ({error})") from None


def _law_3d(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
            reads: np.ndarray):
    """(λ by the regularised law at ``reads``, M = dλ/d(G u) so that the tangent is
    K + Gᵀ M G, the states as bytes) in 3D (module docstring)."""
    m, d, mN = model.contacts, model.d, model.normal_rows
    eps_N, eps_T = split(model, eps)
    _, bar_T = split(model, lam_bar)
    _, slip = split(model, reads)
    closed, lam_N = _normal_law(model, eps, lam_bar, reads)
    normal = [sp.diags_array(np.where(closed, eps_N, 0.0))] if mN else []
    bound = law.bound(lam_N)
    trial = bar_T + eps_T * slip
    size = np.linalg.norm(trial, axis=1)
    stick = size <= bound
    along = trial / np.where(size > 0.0, size, 1.0)[:, None]
    lam_T = np.where(stick[:, None], trial, bound[:, None] * along)
    # the d x d block of dλ_T/d(T u) per contact: ε_T I sticking, b ε_T (I − t̂t̂ᵀ)/‖t‖ slipping
    weight = np.where(stick, 1.0, bound / np.where(size > 0.0, size, 1.0)) * eps_T[:, 0]
    blocks = weight[:, None, None] * (np.eye(d) - np.where(stick, 0.0, 1.0)[:, None, None]
                                      * along[:, :, None] * along[:, None, :])
    tangential = sp.block_diag(list(blocks), format="csr")
    if mN:
        # Coulomb, slipping and closed: b = μ λ_N(u) moves with C u (dλ_T/d(C u) = μ t̂ ε_N)
        coupled = (~stick & closed) if law.kind == COULOMB else np.zeros(m, dtype=bool)
        column = np.where(coupled, law.values * eps_N, 0.0)[:, None] * along  # m x d
        coupling = sp.csr_array((column.ravel(), (np.arange(m * d), np.repeat(np.arange(m), d))),
                                shape=(m * d, m))
        M = sp.block_array([[normal[0], None], [coupling, tangential]], format="csr")
    else:
        M = tangential
    key = b"".join(np.asarray(s, dtype=np.int8).tobytes() for s in (closed, stick))
    return join(lam_N, lam_T), sp.csr_array(M), key


__all__ = ["MAX_STATES", "solve_penalised"]
