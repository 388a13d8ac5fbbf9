"""The independent check of an answer to a user's problem (K, f, C, g): residuals as forces and
displacements against the problem's scales, and an error bound that is measured, not guessed.

Residuals (dimensionless; F and U the problem's scales, :class:`~contactqp.model.sparse.
SparseModel`: F from f and the prescribed motions, U from K⁻¹f, the prescribed motions and the
press fits, never from the answer; s_i = c_iᵀK c_i / (c_iᵀc_i)² per row, at least the stiffness
the row sees; p_i = C_i u − g_i the penetration):

    equilibrium      ‖K u − f + Cᵀλ‖∞ / F over the free dofs (the reactions at the prescribed
                     dofs are what it leaves there, so they balance by construction)
    feasibility      max p_i⁺ · s_i / F: the force it takes to push a row back (an equality
                     row: |p_i| · s_i)
    complementarity  max min(λ_i⁺, (−p_i)⁺ · s_i) / F: a row may push or stand open, not both
    sign             max λ_i⁻ / F over the inequality rows: how hard a row pulls
    force            force_error_bound / F, displacement: displacement_error_bound / U (below)
    natural_map      Siconos's measure on the LCP scaled by s (reported, not part of verified)

The error bound. The check reads the answer's contact set (rows that push, or touch within
1e-6 of U), holds those rows on their gaps and solves the equality-constrained problem on that
set, exactly, with the model's factorisation (:func:`contactqp.methods.schur.on_set`). Where
that answer (u*, λ*) meets every sign and gap (to ACCEPT of F and U), it satisfies every
condition that defines the answer, and it is the exact answer of the problem up to the solve's
own error, which the check measures: r* = K u* − f + Cᵀλ* by a product with K (not by the
factorisation), carried to u by one solve and to λ through W_AA. Where it does not, the set is
corrected (rows that pull leave, rows that pass enter) up to REFINE times. The bounds are then
the distances ‖λ − λ*‖∞ (with the reactions) and ‖u − u*‖∞, plus the solve's error and any
sign or gap the reference misses by. Where no set is found, the answer is not verified.
Verified: every residual within :data:`contactqp.TOLERANCES` (the scene's tolerances; force
and displacement bounds at most 1e-5 of F and U, :data:`contactqp.GUARANTEE`).
"""

from __future__ import annotations

import math

import numpy as np

from contactqp.check import TOLERANCES, Check, Tolerances, natural_map
from contactqp.errors import SolverError
from contactqp.methods.schur import correction, on_set, redundant
from contactqp.model.sparse import SparseModel

HOLD = 1e-6  # a row that pushes more than this × F, or touches within this × U, is in the set
ACCEPT = 1e-9  # the reference may miss a sign or a gap by this much of F or U (round-off)
REFINE = 4  # set corrections the check tries before it gives up
ROUND_OFF = 8.0 * np.finfo(float).eps  # of each product K u*, taken as a bound on its rounding
REFINE_STEPS = 3  # refinement steps of the reference on its set
TINY = 1e-14  # a correction below this of F and U is round-off: the refinement stops
GROWING = 1e-10  # corrections that grow past this of F or U: the reference is not resolved
STAGNANT = 4.0  # corrections that no longer shrink are noise: the reference is within 4 of them


def residuals(model: SparseModel, u: np.ndarray, lam: np.ndarray, equality: np.ndarray
              ) -> tuple[dict[str, float], np.ndarray]:
    """(the residuals of the module docstring but force and displacement, the penetration)."""
    F, s = model.force_scale, model.row_stiffness
    pen = model.C @ u - model.g
    unilateral = ~equality
    balance = model.K @ u - model.P + model.C.T @ lam
    passed = np.where(equality, np.abs(pen), np.maximum(pen, 0.0)) * s
    both = np.minimum(np.maximum(lam, 0.0), np.maximum(-pen, 0.0) * s)
    found = {"equilibrium": float(np.abs(balance).max(initial=0.0)) / F,
             "feasibility": float(passed.max(initial=0.0)) / F,
             "complementarity": float(both[unilateral].max(initial=0.0)) / F,
             "sign": float(np.maximum(-lam[unilateral], 0.0).max(initial=0.0)) / F}
    if equality.all():
        del found["complementarity"], found["sign"]
    return found, pen


def reference(model: SparseModel, lam: np.ndarray, pen: np.ndarray, equality: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, float, float, np.ndarray] | None:
    """(u*, λ*, its force error, its displacement error, the set's rows) on the answer's set,
    the set
    corrected up to REFINE times (module docstring); None when no set gives the exact answer
    or the reference's own refinement does not converge."""
    F, U = model.force_scale, model.displacement_scale
    active = equality | (lam > HOLD * F) | (pen > -HOLD * U)
    for _ in range(REFINE + 1):
        u_ref, lam_ref = on_set(model, active)
        refined = _refined(model, u_ref, lam_ref, np.flatnonzero(active))
        if refined is None:
            return None
        u_ref, lam_ref, force, move = refined
        pen_ref = model.C @ u_ref - model.g
        pulls = active & ~equality & (lam_ref < -ACCEPT * F)
        passes = ~active & (pen_ref > ACCEPT * U)
        if not pulls.any() and not passes.any():
            missed_sign = float(np.maximum(-lam_ref[~equality], 0.0).max(initial=0.0))
            missed_gap = float(np.maximum(np.where(active, np.abs(pen_ref), pen_ref),
                                          0.0).max(initial=0.0))
            seen = float(model.row_stiffness.max(initial=0.0))
            return (u_ref, lam_ref, force + missed_sign + missed_gap * seen,
                    move + missed_gap, np.flatnonzero(active))
        active = (active & ~pulls) | passes
    return None


def _refined(model: SparseModel, u: np.ndarray, lam: np.ndarray, rows: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """The reference refined on its set (iterative refinement: the residuals r* = K u* − P +
    Cᵀλ* by a product with K, not the factorisation, and C_A u* − g_A, their correction
    solved with it) and what
    it may still be off by (force, displacement): the last correction over 1 − ρ, ρ the
    ratio of the last two (the corrections' geometric tail; STAGNANT times it where they
    stay level, round-off noise), plus the correction that the
    round-off of r* itself, ROUND_OFF·(|K||u*| + |P| + |C|ᵀ|λ*|), would make. Measured: on a
    chain with elements 1e6 apart (a press fit into the stiff one) the first answer left a
    held row 2.3e-11 m open, 7e-10 of the force; refined, it is exact. None where the corrections grow (the factorisation cannot resolve
    the answer)."""
    sizes: list[tuple[float, float]] = []
    for _ in range(REFINE_STEPS):
        r = model.K @ u - model.P + model.C.T @ lam
        dlam, du = correction(model, rows, r, model.C[rows] @ u - model.g[rows])
        u, lam = u - du, lam.copy()
        lam[rows] -= dlam
        sizes.append((max(float(np.abs(dlam).max(initial=0.0)), _reaction(model, du)),
                      float(np.abs(du).max(initial=0.0))))
        if sizes[-1][0] <= TINY * model.force_scale and sizes[-1][1] <= (
                TINY * model.displacement_scale):
            break
    last = sizes[-1]
    if len(sizes) > 1:
        rho = max(last[0] / max(sizes[-2][0], 1e-300), last[1] / max(sizes[-2][1], 1e-300))
        if rho > 1.0 and (last[0] > GROWING * model.force_scale or
                          last[1] > GROWING * model.displacement_scale):
            return None  # growing corrections: the factorisation does not resolve the answer
        # shrinking: the geometric tail; level (round-off noise): STAGNANT times the level
        factor = 1.0 / (1.0 - rho) if rho < 0.5 else STAGNANT
        last = (factor * last[0], factor * last[1])
    floor = ROUND_OFF * (abs(model.K) @ np.abs(u) + np.abs(model.P)
                         + abs(model.C).T @ np.abs(lam))
    dlam, du = correction(model, rows, floor)
    force = last[0] + max(float(np.abs(dlam).max(initial=0.0)), _reaction(model, du))
    return u, lam, force, last[1] + float(np.abs(du).max(initial=0.0))


def _reaction(model: SparseModel, du: np.ndarray) -> float:
    """The largest change of a reaction that a change du of the free dofs makes."""
    problem = model.problem
    if not problem.prescribed.size:
        return 0.0
    return float(np.abs(problem.K[problem.prescribed][:, model.free] @ du).max())


def check_problem(model: SparseModel, u_free: np.ndarray, lam: np.ndarray,
                  contact: str = "inequality", tolerances: Tolerances = TOLERANCES) -> Check:
    """Check an answer (free-dof displacements, one force per row) against a sparse model
    (module docstring); ``contact="equality"`` holds every row on its gap."""
    F, U = model.force_scale, model.displacement_scale
    equality = model.equality | (contact == "equality")
    u_free, lam = np.asarray(u_free, dtype=float), np.asarray(lam, dtype=float)
    if not (np.isfinite(u_free).all() and np.isfinite(lam).all()):
        return _not_finite(equality, F, U)
    found, pen = residuals(model, u_free, lam, equality)
    try:
        exact = reference(model, lam, pen, equality)
    except SolverError:  # K singular, and the answer's rows do not hold what it leaves free
        exact = None
    if exact is None:
        force_bound = displacement_bound = math.inf
        why = "the check found no exact answer near this answer's contact set"
    else:
        u_ref, lam_ref, force_error, move_error, rows = exact
        u_full, ref_full = model.full_displacements(u_free), model.full_displacements(u_ref)
        reactions = model.reactions(u_full) - model.reactions(ref_full)
        # redundant rows: the exact answer fixes only their forces on the dofs, Cᵀλ (as a
        # loop of rows on a scene's node); the bound is then for those
        forces = (model.C.T @ (lam - lam_ref)) if redundant(model, rows) else lam - lam_ref
        force_bound = max(float(np.abs(forces).max(initial=0.0)),
                          float(np.abs(reactions).max(initial=0.0))) + force_error
        displacement_bound = float(np.abs(u_free - u_ref).max(initial=0.0)) + move_error
        why = ""
    found["force"], found["displacement"] = force_bound / F, displacement_bound / U
    failures = [f"{name} residual {value:.2e} > {getattr(tolerances, name):.3g}"
                for name, value in found.items() if not value <= getattr(tolerances, name)]
    if why:
        failures.append(why)
    found["natural_map"] = _natural_map(model, lam, pen, equality)
    pulling = float(np.maximum(-lam[~equality], 0.0).max(initial=0.0)) / F
    physical = pulling <= tolerances.sign
    notes = list(failures)
    if not physical:
        rows = np.flatnonzero(~equality & (lam < -tolerances.sign * F))
        notes.append("non-physical: a contact row pulls (" + ", ".join(
            f"{model.problem.names[i]} {lam[i]:.6g}" for i in rows[:5]) + ")")
    return Check(found, not failures, physical, "; ".join(notes), force_bound,
                 displacement_bound, F, U)


def _natural_map(model: SparseModel, lam: np.ndarray, pen: np.ndarray,
                 equality: np.ndarray) -> float | None:
    if equality.any() or model.factor is None:
        return None
    free_gaps = model.g - model.C @ model.free_displacement
    roots = 1.0 / np.sqrt(model.row_stiffness)
    return float(natural_map(lam, -pen, free_gaps, roots))


def _not_finite(equality: np.ndarray, F: float, U: float) -> Check:
    names = ["equilibrium", "feasibility", "complementarity", "sign", "force", "displacement"]
    if equality.all():
        names.remove("complementarity")
        names.remove("sign")
    found: dict[str, float | None] = {name: math.inf for name in names}
    found["natural_map"] = None
    message = "the answer is not finite (the method returned no answer)"
    return Check(found, False, False, message, math.inf, math.inf, F, U)


__all__ = ["ACCEPT", "HOLD", "REFINE", "check_problem", "reference", "residuals"]
