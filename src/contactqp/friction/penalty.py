"""The penalty method and the augmented Lagrangian with friction, as the field uses them (2D).

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
with a moderate ε. 3D (d = 2) is refused: there the slip direction makes the regularised law
nonlinear within a state (a Newton with its consistent tangent), which is not implemented.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from contactqp.errors import OptionError, SolverError
from contactqp.friction.answer import FrictionAnswer, force_scale, make_answer
from contactqp.friction.law import COULOMB, Law
from contactqp.friction.model import FrictionModel
from contactqp.friction.reduced import join, split
from contactqp.model.base import AUGMENTED_PER_STIFFNESS, PENALTY_PER_STIFFNESS, row_stiffness

MAX_STATES = 100  # state updates per solve before the loop is stopped ("not settled")
MAX_ITERATIONS = 100  # the augmented Lagrangian's updates of λ̄ (default)
TOLERANCE = 1e-10  # of F: the change of λ that ends the augmented Lagrangian (default)


def solve_penalised(model: FrictionModel, law: Law, previous_u: np.ndarray | None,
                    augmented: bool, options: dict) -> FrictionAnswer:
    """One increment by the penalty (``augmented=False``) or the augmented Lagrangian
    (module docstring). ``options``: ``penalty`` (one ε for every row, force/length; default
    PENALTY_PER_STIFFNESS, or AUGMENTED_PER_STIFFNESS, times each row's stiffness
    c_iᵀK c_i/(c_iᵀc_i)²), ``max_iterations`` and ``tolerance`` (the augmented Lagrangian's)."""
    if model.d != 1:
        raise OptionError(f"{'augmented' if augmented else 'penalty'} takes friction in 2D "
                          "only (one tangential row per contact): in 3D the slip direction "
                          "makes the regularised law nonlinear within a state, which needs a "
                          "Newton with its consistent tangent; use lagrange, qp or cone")
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
    for _ in range(updates):
        u, lam, settled, states = _settle(model, law, eps, lam_bar, targets, u)
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
    return (AUGMENTED_PER_STIFFNESS if augmented else PENALTY_PER_STIFFNESS) * stiffness


def _law_forces(model: FrictionModel, law: Law, eps: np.ndarray, lam_bar: np.ndarray,
                reads: np.ndarray) -> tuple[np.ndarray, tuple]:
    """(λ by the regularised law at ``reads`` = G u − h, the states: closed, stick, sign)."""
    mN = model.normal_rows
    eps_N, eps_T = split(model, eps)
    bar_N, bar_T = split(model, lam_bar)
    read_N, slip = split(model, reads)
    if mN:
        trial_N = bar_N + eps_N * read_N
        closed = trial_N > 0.0
        lam_N = np.where(closed, trial_N, 0.0)
    else:
        closed, lam_N = np.ones(model.contacts, dtype=bool), None
    bound = law.bound(lam_N)
    trial_T = bar_T[:, 0] + eps_T[:, 0] * slip[:, 0]
    stick = np.abs(trial_T) <= bound
    sign = np.sign(trial_T)
    lam_T = np.where(stick, trial_T, bound * sign)
    return join(lam_N, lam_T[:, None]), (closed, stick, sign)


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


__all__ = ["MAX_STATES", "solve_penalised"]
