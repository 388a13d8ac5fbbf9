"""The check of an answer with friction: the residuals of the law, and an error bound.

**Residuals** (:func:`friction_residuals`), each the worst miss over the contacts as a fraction
of the force scale F (:func:`~.answer.force_scale`: the loads, the reactions of the
prescribed dofs with no contact force, the normal and friction forces, Coulomb's μλ_N); a
length counts as the force its row's stiffness k = 1/W_ii gives it:

- ``equilibrium``: K u − f + Cᵀλ_N + Tᵀλ_T on the free dofs;
- ``contact``: min(λ_N, k·gap), the normal law's natural map (a pulling force, a penetration,
  a force on an open row);
- ``cone``: ‖λ_T‖ past its bound (s, or μλ_N);
- ``stick``: min(k‖v‖, s − ‖λ_T‖): a contact that moves while its friction force is inside
  its bound (it must stick);
- ``opposing``: min(k‖v‖, ‖λ_T − s v/‖v‖‖): a contact that moves without its friction force at
  the bound along the slip v (on the body it must oppose the slip with all of s). Both are
  complementarity measures, so that a slip at round-off level, whose direction means
  nothing, counts only as much as it moves;
- ``friction_law``: ‖λ_T − P(λ_T + k v)‖, P the projection on the disc (box in 2D) of radius
  s: the friction law's natural map, zero exactly where the three above are.

**Error bound** (:func:`check_tresca`). Tresca's problem is convex and its u unique: the check
reads the answer's sets (open, stick, slip and direction), solves their equations exactly
(:func:`~.reduced.solve_on_set`, then iterative refinement with products by K, not the
factorisation) and tests the reference against every inequality. Where it meets them (to
ACCEPT of F) it satisfies all the KKT conditions: it is the answer, and the distance to it is
the bound. Where it does not, the sets are corrected by the active-set rule up to REFINE
times; past that there is no bound, and no verdict of verified.

**Coulomb** (:func:`check_coulomb`) has no minimum principle and its answers need not be unique
(:func:`~.examples.nonunique_coulomb`). The same reference, with sᵢ = μᵢλ_N,i in the set's
equations, says: *an exact Coulomb solution with these sets lies within the bound*. It does
not say that it is the only one, nor which of several a loading process would reach.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.errors import ProblemError
from contactqp.friction.answer import FrictionAnswer, force_scale, read_sets
from contactqp.friction.law import COULOMB, Law, coulomb, tresca
from contactqp.friction.model import FrictionModel
from contactqp.friction.reduced import (
    Sets,
    equations,
    newton_step,
    next_sets,
    solve_on_set,
    split,
    violations,
)

ACCEPT = 1e-9  # the reference may miss an inequality by this much of F (round-off)
REFINE = 4  # set corrections the check tries before it gives up
REFINE_STEPS = 3  # iterative refinement steps of the reference
VERIFIED = 1e-6  # an answer within this of F and U of the exact one, every residual below it


@dataclass(frozen=True)
class FrictionResiduals:
    """Each condition's worst miss as a fraction of ``force_scale`` (module docstring)."""

    equilibrium: float
    contact: float
    cone: float
    stick: float
    opposing: float
    friction_law: float
    force_scale: float

    @property
    def worst(self) -> float:
        """The largest of the residuals."""
        return max(self.equilibrium, self.contact, self.cone, self.stick, self.opposing,
                   self.friction_law)


@dataclass(frozen=True, eq=False)
class FrictionCheck:
    """The verdict on one answer.

    Attributes
    ----------
    law : str
        ``"tresca"`` or ``"coulomb"``.
    residuals : FrictionResiduals
    force_error_bound, displacement_error_bound : float
        How far the answer's forces (force: the normal and friction forces and the reactions
        of the prescribed dofs) and displacements (length) are from the exact answer's on the
        reference's sets; infinite where no reference was found.
    displacement_scale : float
        U, the largest displacement of the reference (or the answer) on the free dofs.
    verified : bool
        A reference was found, both bounds are within VERIFIED of F and U, and every residual
        is below VERIFIED.
    set_changes : int
        How many corrections the reference's sets needed from the answer's own.
    verdict : str
        One line: what the check says and, for Coulomb, what it does not.
    reference_u : array or None
        The reference's displacement of all dofs.
    reference_forces : array or None
        The reference's forces (λ_N, λ_T flat).
    """

    law: str
    residuals: FrictionResiduals
    force_error_bound: float
    displacement_error_bound: float
    displacement_scale: float
    verified: bool
    set_changes: int
    verdict: str
    reference_u: np.ndarray | None = None
    reference_forces: np.ndarray | None = None


def friction_residuals(model: FrictionModel, answer: FrictionAnswer, *, slip_bound=None,
                       mu=None, previous_u=None) -> FrictionResiduals:
    """The residuals of the friction law of one answer, as fractions of F (module docstring).

    Parameters
    ----------
    model : FrictionModel
    answer : FrictionAnswer
        Any method's answer (its u, normal and friction forces are read; nothing else).
    slip_bound, mu : float or array
        Exactly one: Tresca's bounds (force) or Coulomb's coefficients.
    previous_u : array, n, optional
        The state the increment started from (default zero).
    """
    return _residuals(model, _law(model, slip_bound, mu), answer, model.previous(previous_u))


def _law(model: FrictionModel, slip_bound, mu) -> Law:
    """The law from exactly one of its two parameters."""
    if (slip_bound is None) == (mu is None):
        raise ProblemError("give exactly one of slip_bound (Tresca) and mu (Coulomb)")
    return tresca(model, slip_bound) if mu is None else coulomb(model, mu)


def _residuals(model: FrictionModel, law: Law, answer: FrictionAnswer,
               previous_u: np.ndarray) -> FrictionResiduals:
    forces = answer.forces
    u_free = answer.u[model.free]
    F = force_scale(model, law, forces)
    reads = model.rows @ u_free - model.targets(previous_u)
    kN, _ = split(model, model.row_stiffness)
    kT = model.tangential_stiffness
    lam_N, lam_T = split(model, forces)
    w_N, v = split(model, reads)
    imbalance = model.K @ u_free - model.load + model.rows.T @ forces
    contact = 0.0 if lam_N is None else float(np.abs(np.minimum(lam_N, -kN * w_N)).max())
    bound = law.bound(lam_N)
    size, length = np.linalg.norm(lam_T, axis=1), np.linalg.norm(v, axis=1)
    moves = length * kT
    along = v / np.where(length > 0.0, length, 1.0)[:, None]
    misdirected = np.linalg.norm(lam_T - bound[:, None] * along, axis=1)
    trial = lam_T + kT[:, None] * v
    trial_size = np.linalg.norm(trial, axis=1)
    projected = trial * np.minimum(1.0, bound / np.where(trial_size > 0.0, trial_size,
                                                         1.0))[:, None]
    return FrictionResiduals(
        equilibrium=float(np.abs(imbalance).max(initial=0.0)) / F,
        contact=contact / F,
        cone=float(np.maximum(size - bound, 0.0).max(initial=0.0)) / F,
        stick=float(np.minimum(moves, np.maximum(bound - size, 0.0)).max(initial=0.0)) / F,
        opposing=float(np.minimum(moves, misdirected).max(initial=0.0)) / F,
        friction_law=float(np.linalg.norm(lam_T - projected, axis=1).max(initial=0.0)) / F,
        force_scale=F)


def check_tresca(model: FrictionModel, slip_bound, answer: FrictionAnswer,
                 previous_u=None) -> FrictionCheck:
    """The residuals and the error bound of an answer under Tresca's law (module docstring)."""
    return check(model, tresca(model, slip_bound), answer, previous_u)


def check_coulomb(model: FrictionModel, mu, answer: FrictionAnswer,
                  previous_u=None) -> FrictionCheck:
    """The residuals and Coulomb's verdict on an answer (module docstring)."""
    return check(model, coulomb(model, mu), answer, previous_u)


def check(model: FrictionModel, law: Law, answer: FrictionAnswer,
          previous_u=None) -> FrictionCheck:
    """The check of an answer under a law made already (module docstring)."""
    previous_u = model.previous(previous_u)
    residuals = _residuals(model, law, answer, previous_u)
    found = reference(model, law, answer, previous_u)
    u_free = answer.u[model.free]
    if found is None:
        U = displacement_scale(model, u_free, residuals.force_scale)
        verdict = (f"{law.kind}: no exact answer found on the answer's sets or "
                   f"{REFINE} corrections of them; only the residuals speak for it")
        return FrictionCheck(law.kind, residuals, np.inf, np.inf, U, False, REFINE, verdict)
    ref_u, ref_forces, force_error, move_error, changes = found
    F = max(residuals.force_scale, force_scale(model, law, ref_forces))
    U = displacement_scale(model, ref_u, F)
    force_bound = max(float(np.abs(answer.forces - ref_forces).max(initial=0.0)),
                      reaction_change(model, u_free - ref_u, answer.forces - ref_forces)
                      ) + force_error + reaction_reach(model, force_error, move_error)
    move_bound = float(np.abs(u_free - ref_u).max(initial=0.0)) + move_error
    verified = (force_bound <= VERIFIED * F and move_bound <= VERIFIED * U
                and residuals.worst <= VERIFIED)
    verdict = _verdict(law, force_bound / F, move_bound / U)
    return FrictionCheck(law.kind, residuals, force_bound, move_bound, U, verified, changes,
                         verdict, model.full(ref_u), ref_forces)


def reaction_change(model: FrictionModel, du: np.ndarray, dlam: np.ndarray) -> float:
    """The largest change of a reaction (a prescribed dof's force) that changes du of the free
    dofs and dλ of the forces make: K_pf du + C_pᵀ dλ_N + T_pᵀ dλ_T (force)."""
    source = model.source
    change = source.K_fp.T @ du
    lam_N, lam_T = split(model, dlam)
    if lam_N is not None and source.C_p is not None:
        change = change + source.C_p.T @ lam_N
    change = change + source.T_p.T @ lam_T.ravel()
    return float(np.abs(change).max(initial=0.0))


def reaction_reach(model: FrictionModel, force_error: float, move_error: float) -> float:
    """How far the reference's own errors (force_error in every force, move_error in every
    free displacement) can move a reaction: each prescribed dof's row sums of |K_pf| and of
    its rows' |entries| times them (force)."""
    source = model.source
    if not source.K_fp.shape[1]:
        return 0.0
    stiff = np.asarray(abs(source.K_fp).sum(axis=0)).ravel()
    rows = abs(source.T_p).sum(axis=0)
    if source.C_p is not None:
        rows = rows + abs(source.C_p).sum(axis=0)
    return float(stiff.max(initial=0.0)) * move_error + float(
        np.asarray(rows).ravel().max(initial=0.0)) * force_error


def displacement_scale(model: FrictionModel, u_free: np.ndarray, F: float) -> float:
    """U: the largest of the free displacements, the prescribed ones, and F times the largest
    row flexibility (what the force scale moves the softest row by: not zero where the answer
    does not move)."""
    flexibility = float(np.diag(model.flexibility).max(initial=0.0))
    return max(float(np.abs(u_free).max(initial=0.0)),
               float(np.abs(model.values).max(initial=0.0)), F * flexibility, 1e-300)


def _verdict(law: Law, force: float, move: float) -> str:
    """One line on what the bound means under each law."""
    within = f"within {force:.1e} of F in force and {move:.1e} of U in displacement"
    if law.kind == COULOMB:
        return (f"coulomb: an exact Coulomb solution with the answer's open/stick/slip sets "
                f"lies {within}; Coulomb solutions need not be unique, so this does not say "
                "there is no other, nor which one a loading process reaches")
    return f"tresca: the answer is {within} of the exact answer (convex: u is unique)"


def reference(model: FrictionModel, law: Law, answer: FrictionAnswer,
              previous_u: np.ndarray):
    """(u*, λ*, its force error, its displacement error, set corrections) on the answer's
    sets, corrected up to REFINE times; None where none meets every inequality."""
    targets = model.targets(previous_u)
    b = model.rows @ model.unloaded - targets
    forces = answer.forces
    reads = model.rows @ answer.u[model.free] - targets
    sets = read_sets(model, law, forces, reads)
    start = np.where(np.isfinite(forces), forces, 0.0)
    for changes in range(REFINE + 1):
        found, solved = solve_on_set(model, law, sets, b, start)
        if not solved:
            return None
        ref_u, found, force_error, move_error = _refined(model, law, sets, found, targets)
        ref_reads = model.rows @ ref_u - targets
        F = max(force_scale(model, law, found), force_scale(model, law, forces))
        missed = violations(model, law, sets, found, ref_reads)
        if missed.max(initial=0.0) <= ACCEPT * F:
            largest_flexibility = float(np.diag(model.flexibility).max(initial=0.0))
            worst = float(missed.max(initial=0.0))
            return (ref_u, found, force_error + worst, move_error + worst * largest_flexibility,
                    changes)
        sets, start = next_sets(model, law, found, ref_reads), found
    return None


def _refined(model: FrictionModel, law: Law, sets: Sets, forces: np.ndarray,
             targets: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The reference refined: u = K⁻¹(f − Gᵀλ) corrected by its residual (a product with K),
    the set's equations evaluated on the reads G u − h of that u, and λ corrected by their
    Jacobian; the last corrections (doubled) are the reference's own error."""
    u = model.displacement(forces)
    step_force = step_move = 0.0
    for _ in range(REFINE_STEPS):
        residual = model.K @ u - (model.load - model.rows.T @ forces)
        correction = model.factor.solve(residual)
        u = u - correction
        reads = model.rows @ u - targets
        equation, jacobian = equations(model, law, sets, forces, reads)
        step = newton_step(jacobian, equation)
        if step is None:
            step = np.zeros_like(forces)
        forces = forces - step
        move = model.factor.solve(model.rows.T @ step)
        u = u + move
        step_force = float(np.abs(step).max(initial=0.0))
        step_move = float(np.abs(correction).max(initial=0.0) + np.abs(move).max(initial=0.0))
    return u, forces, 2.0 * step_force, 2.0 * step_move
