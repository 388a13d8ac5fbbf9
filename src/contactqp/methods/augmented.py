"""The augmented Lagrangian method (Uzawa): a moderate penalty plus multiplier updates.

For fixed multipliers λ the displacements minimise
    Π(D) + Σᵢ [max(0, λᵢ + ε(CᵢD − gᵢ))² − λᵢ²] / (2ε)
(unilateral contact; for equality contact drop the max), which is the penalty system with the
right-hand side shifted by the multipliers:
    (K + ε C_AᵀC_A) D = P − C_Aᵀ(λ_A − ε g_A),   A = walls with λᵢ + ε(CᵢD − gᵢ) > 0.
Then λ ← max(0, λ + ε(C D − g)). Each update shrinks the force error by about 1/(1 + ε f)
(f the compliance at the wall), so a penalty that alone would leave a visible penetration
converges to the exact contact force in a few updates, without the ill-conditioning of a
penalty large enough to be accurate on its own.
"""

from __future__ import annotations

import numpy as np

from contactqp import linalg
from contactqp.methods._active_set import DECISION_RTOL, active_set_loop, pinning
from contactqp.methods.base import Solution
from contactqp.methods.penalty import equalities, penalised_solve
from contactqp.methods.schur import pinning as sparse_pinning
from contactqp.model import Condensed, ContactModel, Model, wall_stiffness, without_circulation
from contactqp.model.base import AUGMENTED_PER_STIFFNESS

DEFAULT_TOLERANCE = 1e-10  # stop when an update changes λ by less than this, relative
DEFAULT_MAX_ITERATIONS = 100


def default_penalty(model: Model | Condensed) -> float:
    """ε = 100 × the stiffness the walls see (N/m), :func:`contactqp.model.wall_stiffness`:
    the largest eigenvalue σ of S⁻¹, S the flexibility between the walled nodes. An update
    shrinks the force error of each mode by σᵢ/(σᵢ + ε) <= 1/101, and ε stays far from the
    round-off of a penalty that is accurate on its own (it does not grow with the mesh).
    Measured: 100 × the stiffness the walls see together (a smaller σ) took 100 updates
    on two zero-gap walls joined by an element 300 times stiffer than the bar before them."""
    seen = wall_stiffness(model)
    return AUGMENTED_PER_STIFFNESS * (1.0 if seen is None else seen)


def solve_augmented(model: Model | Condensed, contact: str, *, penalty: float | None = None,
                    tolerance: float = DEFAULT_TOLERANCE,
                    max_iterations: int = DEFAULT_MAX_ITERATIONS) -> Solution:
    """Augmented Lagrangian with penalty ε (N/m; default :func:`default_penalty`), multiplier
    updates until one changes λ by at most ``tolerance`` × max(‖λ‖, ‖P‖), or until an update
    no longer shrinks the change (round-off: status says so). If that takes more than
    ``max_iterations`` updates the last iterate is returned with ``claimed_success`` False."""
    if model.layout is None:  # no chain: a penalty per row, one factorisation per set
        return _general(model, contact, penalty=penalty, tolerance=tolerance,
                        max_iterations=max_iterations)
    eps = default_penalty(model) if penalty is None else penalty
    K, P, C, g = model.K, model.P, model.C, model.g
    unilateral = contact == "inequality"
    lam = np.zeros(model.n_contacts)
    inner_solves = 0

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        nonlocal inner_solves
        inner_solves += 1
        Ca = C[active]
        rhs = P - Ca.T @ (lam[active] - eps * g[active])
        u = linalg.solve(K + eps * (Ca.T @ Ca), rhs, spd=True)
        return u, lam + eps * (C @ u - g)

    def update(active: np.ndarray, u: np.ndarray, trial: np.ndarray) -> np.ndarray:
        # a round-off band, as in the penalty's and Lagrange's loops: a node clamped between
        # two walls (gaps summing to 0) sits on both, and its two trial forces are ± round-off
        # (without the band the set cycled on 21 of 6000 random scenes)
        band = DECISION_RTOL * max(float(np.abs(trial).max(initial=0.0)),
                                   float(np.abs(P).max(initial=0.0)))
        return np.where(active, trial > -band, trial > band)

    pin = pinning(model)
    previous = np.inf
    for iteration in range(1, max_iterations + 1):
        if unilateral:
            u, trial, _ = active_set_loop(model.n_contacts, step, update, method="augmented",
                                          start=lam > 0.0, pin=pin)
            new_lam = np.maximum(trial, 0.0)
        else:
            u, new_lam = step(np.ones(model.n_contacts, dtype=bool))
        change = float(np.abs(new_lam - lam).max(initial=0.0))
        scale = max(float(np.abs(new_lam).max(initial=0.0)), float(np.abs(P).max(initial=0.0)))
        lam = new_lam
        converged = change <= tolerance * scale
        if converged or (change >= previous and iteration > 2):
            status = "solved" if converged else "stalled at round-off"
            lam = without_circulation(model, lam) if unilateral else lam
            return Solution(u, lam, solver="augmented", iterations=iteration, status=status,
                            info={"penalty": eps, "inner_solves": inner_solves})
        previous = change
    return Solution(u, lam, solver="augmented", iterations=max_iterations,
                    status=f"not converged in {max_iterations} updates", claimed_success=False,
                    info={"penalty": eps, "inner_solves": inner_solves})


def _general(model: ContactModel, contact: str, *, penalty: float | None = None,
             tolerance: float = DEFAULT_TOLERANCE,
             max_iterations: int = DEFAULT_MAX_ITERATIONS) -> Solution:
    """The augmented Lagrangian (Uzawa) with ε_i (module docstring): for fixed λ the set of
    rows with λ_i + ε_i(C_i u − g_i) > 0 is settled, then λ ← max(0, that) (equality rows: no
    max), until an update changes λ by at most ``tolerance`` × max(‖λ‖, F)."""
    eps = (AUGMENTED_PER_STIFFNESS * model.row_stiffness if penalty is None
           else np.full(model.n_contacts, float(penalty)))
    solve, equality = penalised_solve(model, eps, {}), equalities(model, contact)
    lam, F = np.zeros(model.n_contacts), model.force_scale

    def step(active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = solve(active, eps * model.g - lam)
        return u, lam + eps * (model.C @ u - model.g)

    def update(active: np.ndarray, u: np.ndarray, trial: np.ndarray) -> np.ndarray:
        band = DECISION_RTOL * max(float(np.abs(trial).max(initial=0.0)), F)
        return np.where(active, trial > -band, trial > band) | equality

    previous = np.inf
    # K singular (a body held by contact alone): each set holds what K leaves free
    general_pin = sparse_pinning(model) if model.factor is None else None
    for iteration in range(1, max_iterations + 1):
        u, trial, _ = active_set_loop(model.n_contacts, step, update, method="augmented",
                                      start=equality | (lam > 0.0), pin=general_pin)
        new_lam = np.where(equality, trial, np.maximum(trial, 0.0))
        change = float(np.abs(new_lam - lam).max(initial=0.0))
        lam = new_lam
        converged = change <= tolerance * max(float(np.abs(lam).max(initial=0.0)), F)
        if converged or (change >= previous and iteration > 2):
            status = "solved" if converged else "stalled at round-off"
            return Solution(u, lam, solver="augmented", iterations=iteration, status=status,
                            info={"penalty": float(eps.max(initial=0.0))})
        previous = change
    return Solution(u, lam, solver="augmented", iterations=max_iterations,
                    status=f"not converged in {max_iterations} updates", claimed_success=False)
