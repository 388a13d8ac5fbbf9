"""The general certificate: an error bound that is measured, not guessed, for an answer to any
model (:mod:`contactqp.model.base`).

The error bound. The check reads the answer's contact set (rows that push, or touch within 1e-6
of U, save a row the answer gives exactly no force that does not pass its gap, where K leaves
no mode free), holds those rows on their gaps and solves the equality-constrained problem on
that set, exactly, with the model's set solve
(:meth:`~contactqp.model.base.ContactModel.set_solve`: a sparse model's Schur complement, a
chain's banded saddle-point system). Where that answer (u*, λ*) meets every sign and gap (to
ACCEPT of F and U), it satisfies every condition that defines the answer, and it is the exact
answer of the problem up to the solve's own error, which the check measures: r* = K u* − f +
Cᵀλ* by a product with K (not by the factorisation), carried to u by one solve and to λ through
W_AA. Where it does not, the set is corrected (rows that pull leave, rows that pass enter) up
to REFINE times. The bounds are then the distances ‖λ − λ*‖∞ (with the reactions) and ‖u −
u*‖∞, plus the solve's error and any sign or gap the reference misses by. Where no set is
found, there is no bound (and no verdict of verified: :mod:`contactqp.check.residuals`).
"""

from __future__ import annotations

import math

import numpy as np

from contactqp.errors import SolverError
from contactqp.linalg import magnitude
from contactqp.model.base import ContactModel

HOLD = 1e-6  # a row that pushes more than this × F, or touches within this × U, is in the set
ACCEPT = 1e-9  # the reference may miss a sign or a gap by this much of F or U (round-off)
REFINE = 4  # set corrections the check tries before it gives up
ROUND_OFF = 8.0 * np.finfo(float).eps  # of each product K u*, taken as a bound on its rounding
REFINE_STEPS = 3  # refinement steps of the reference on its set
TINY = 1e-14  # a correction below this of F and U is round-off: the refinement stops
GROWING = 1e-10  # corrections that grow past this of F or U: the reference is not resolved
STAGNANT = 4.0  # corrections that no longer shrink are noise: the reference is within 4 of them
NOISE = 10.0  # corrections that grow past this times the round-off floor's are not noise;
# a first correction under a NOISE-th of it is round-off, and no more are taken (on the 5 106-dof
# sphere a first correction of 1.9e-14 of F against a floor's 1.1e-11: the two corrections more
# took a tenth of lagrange's time with its check)
FLOOR_MOVED = 1e-6  # corrections that move the round-off floor by more than this of itself:
# the floor is solved again at the answer they moved to


def reference(model: ContactModel, lam: np.ndarray, pen: np.ndarray, equality: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, float, float, np.ndarray] | None:
    """(u*, λ*, its force error, its displacement error, the set's rows) on the answer's set,
    the set
    corrected up to REFINE times (module docstring); None when no set gives the exact answer
    or the reference's own refinement does not converge."""
    F, U = model.force_scale, model.displacement_scale
    touching = pen > -HOLD * U
    if not model.singular:  # a row the answer leaves with exactly no force starts free unless
        # it passes (an exact method's set is then the first; on the rows mesh a row touching
        # with none cost a set of its own: 0.52 s of lagrange's 3.3 s at 4 239 rows); where K
        # leaves modes free, touching rows with no force may be what holds them
        touching &= (lam != 0.0) | (pen > ACCEPT * U)
    active = equality | (lam > HOLD * F) | touching
    for _ in range(REFINE + 1):
        u_ref, lam_ref = model.on_set(active)
        refined = _refined(model, u_ref, lam_ref, np.flatnonzero(active))
        if refined is None:
            return None
        u_ref, lam_ref, force, move = refined
        pen_ref = model.C @ u_ref - model.g
        # only a pull within ACCEPT of F can be in the set for its give alone
        slight = active & ~equality & (lam_ref >= -ACCEPT * F)
        give = _give(model, np.where(slight, lam_ref, 0.0), ACCEPT * U)
        # a pull counts as a force, and as the displacement letting it go makes (a soft row:
        # random_scenes seed 2026, scene 623, a wall held 9.6e-11 F below 0 through an element
        # of 1.6e5 N/m moved its bar 5.9e-12 m, 1.6e-4 U, and the bound said 4.5e-9 U)
        pulls = active & ~equality & ((lam_ref < -ACCEPT * F) | (give > ACCEPT * U))
        passes = ~active & (pen_ref > ACCEPT * U)
        if not pulls.any() and not passes.any():
            missed_sign = float(np.maximum(-lam_ref[~equality], 0.0).max(initial=0.0))
            missed_gap = float(np.maximum(np.where(active, np.abs(pen_ref), pen_ref),
                                          0.0).max(initial=0.0))
            seen = float(model.row_stiffness.max(initial=0.0))
            return (u_ref, lam_ref, force + missed_sign + missed_gap * seen,
                    move + missed_gap + float(give.max(initial=0.0)), np.flatnonzero(active))
        active = (active & ~pulls) | passes
    return None


def _give(model: ContactModel, lam: np.ndarray, beyond: float = math.inf) -> np.ndarray:
    """How far each row with a force below 0 moves when that force is let go: the force over
    the stiffness the row sees, 1/W_ii (at least what it sees with other rows held as well);
    infinite where the row moves a mode K leaves free, 0 on the other rows. Where the force
    over the bound s̄ ≥ 1/W_ii already passes ``beyond``, that lower bound, with no solve (on
    a sparse model each row's 1/W_ii is one)."""
    give = np.zeros(lam.size)
    bound = np.asarray(model.row_stiffness)
    with np.errstate(divide="ignore", invalid="ignore"):
        least = np.where((lam < 0.0) & (bound > 0.0), -lam / bound, 0.0)
    far = np.isfinite(least) & (least > beyond)
    give[far] = least[far]
    negative = np.flatnonzero((lam < 0.0) & ~far)
    if negative.size:
        stiffness = model.seen_stiffness(negative)
        with np.errstate(divide="ignore"):
            give[negative] = np.where(stiffness > 0.0, -lam[negative] / stiffness, np.inf)
    return give


def _refined(model: ContactModel, u: np.ndarray, lam: np.ndarray, rows: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """The reference refined on its set (iterative refinement: the residuals r* = K u* − P +
    Cᵀλ* by a product with K, not the factorisation, and C_A u* − g_A, their correction
    solved with it) and what it may still be off by (force, displacement): the last
    correction over 1 − ρ, ρ the ratio of the last two (the corrections' geometric tail;
    STAGNANT times it where they stay level, round-off noise), plus the correction that the
    round-off of r* itself, ROUND_OFF·(|K||u*| + |P| + |C|ᵀ|λ*|), would make (solved first: a
    first correction under a NOISE-th of it is round-off, STAGNANT times it is the tail, and
    no more are taken). Measured: on a chain with elements 1e6 apart (a press fit into the
    stiff one) the first answer left a held row 2.3e-11 m open, 7e-10 of the force; refined,
    it is exact. None where the corrections grow (the factorisation cannot resolve the
    answer)."""
    sizes: list[tuple[float, float]] = []
    C_A, gap = model.C[rows], model.g[rows]
    floor = _floor(model, u, lam)
    noise = _noise(model, rows, floor)
    settled = False  # the first correction a NOISE-th of the floor's or less: round-off
    for _ in range(REFINE_STEPS):
        r = model.K @ u - model.P + model.C.T @ lam
        du, dlam = model.set_solve(rows, r, C_A @ u - gap)
        u, lam = u - du, lam.copy()
        lam[rows] -= dlam
        sizes.append((max(float(np.abs(dlam).max(initial=0.0)), _reaction(model, du)),
                      float(np.abs(du).max(initial=0.0))))
        if sizes[-1][0] <= TINY * model.force_scale and sizes[-1][1] <= (
                TINY * model.displacement_scale):
            break
        settled = len(sizes) == 1 and sizes[0][0] <= noise[0] / NOISE and sizes[0][1] <= (
            noise[1] / NOISE)
        if settled:
            break
    if len(sizes) > 1:  # the floor at the answer the corrections moved to, where they moved
        moved = _floor(model, u, lam)  # it by more than FLOOR_MOVED of itself (one solve
        if np.any(np.abs(moved - floor) > FLOOR_MOVED * floor):  # more, measured again)
            noise = _noise(model, rows, moved)
    last = sizes[-1]
    if settled:  # level, as round-off noise is: STAGNANT times it
        last = (STAGNANT * last[0], STAGNANT * last[1])
    elif len(sizes) > 1:
        rho = max(last[0] / max(sizes[-2][0], 1e-300), last[1] / max(sizes[-2][1], 1e-300))
        # growing, past both the floor (round-off noise comes and goes under it: measured on
        # a scene with walls on both sides of a node, corrections 6e-11, 1.4e-11, 3.1e-11 m
        # where the floor moved 8e-11 m) and GROWING of F or U: the set solve does not
        # resolve the answer
        if rho > 1.0 and ((last[0] > max(GROWING * model.force_scale, NOISE * noise[0])) or
                          (last[1] > max(GROWING * model.displacement_scale,
                                         NOISE * noise[1]))):
            return None
        # shrinking: the geometric tail; level (round-off noise): STAGNANT times the level
        factor = 1.0 / (1.0 - rho) if rho < 0.5 else STAGNANT
        last = (factor * last[0], factor * last[1])
    return u, lam, last[0] + noise[0], last[1] + noise[1]


def _floor(model: ContactModel, u: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """ROUND_OFF·(|K||u*| + |P| + |C|ᵀ|λ*|): what the round-off of r* = K u* − P + Cᵀλ* may
    be, per free dof."""
    return ROUND_OFF * (magnitude(model.K) @ np.abs(u) + np.abs(model.P)
                        + magnitude(model.C).T @ np.abs(lam))


def _noise(model: ContactModel, rows: np.ndarray, floor: np.ndarray) -> tuple[float, float]:
    """(force, displacement) that the round-off ``floor`` (:func:`_floor`) moves, solved on
    the set: the floor no refinement gets under."""
    du, dlam = model.set_solve(rows, floor, np.zeros(rows.size))
    return (max(float(np.abs(dlam).max(initial=0.0)), _reaction(model, du)),
            float(np.abs(du).max(initial=0.0)))


def _reaction(model: ContactModel, du: np.ndarray) -> float:
    """The largest change of a reaction that a change du of the free dofs makes."""
    return float(np.abs(model.support_change(du)).max(initial=0.0))


def on_set_bounds(model: ContactModel, u_free: np.ndarray, lam: np.ndarray, pen: np.ndarray,
                  equality: np.ndarray) -> tuple[float, float, str]:
    """(force bound, displacement bound, "" or why there is none) of an answer (module
    docstring): its distance to the exact answer on its contact set, plus that answer's own
    error."""
    try:
        exact = reference(model, lam, pen, equality)
    except SolverError:  # K singular, and the answer's rows do not hold what it leaves free
        exact = None
    if exact is None:
        return math.inf, math.inf, "the check found no exact answer near this answer's contact set"
    u_ref, lam_ref, force_error, move_error, rows = exact
    reactions = model.support_change(u_free - u_ref) + _contact_at_supports(model, lam - lam_ref)
    # redundant rows: the exact answer fixes only their forces on the dofs, Cᵀλ (as a loop of
    # rows on a scene's node); the bound is then for those. The rows are the reference's and
    # the answer's own pushing ones: a loop with zero gaps (rows that add up to 0·u <= 0) left
    # the reference's set where its least-norm forces pulled on one row, and an answer that
    # carried 1.23 F round the loop, right on Cᵀλ, was flagged (the hostile audit's loop)
    # A force carried round such rows is exact only where it does no work on their gaps
    # (gᵀΔλ = 0: zero gaps, or walls on both sides at one position); round a loop whose gaps
    # do not cancel, 1e-16 m open the long way, the exact answer carries nothing
    # (tests/test_check.py)
    # The work is judged against the largest gap of the rows whose force differs times the
    # force moved: where the only gap of those rows sits on a row whose force differs by
    # round-off, gᵀΔλ is that round-off and so is |g|ᵀ|Δλ| (random_problem(1010015,
    # "redundant"), the engines' references holding different rows of a repeated
    # constraint: the amg engine's flagged an exact answer by its 0.10 of force moved)
    pushing = np.union1d(rows, np.flatnonzero(lam > HOLD * model.force_scale))
    forces = lam - lam_ref
    moved = forces != 0.0
    if model.redundant(pushing) and abs(float(model.g @ forces)) <= ACCEPT * float(
            np.abs(model.g[moved]).max(initial=0.0) * np.abs(forces).sum()):
        forces = model.C.T @ forces
    force_bound = max(float(np.abs(forces).max(initial=0.0)),
                      float(np.abs(reactions).max(initial=0.0))) + force_error
    return force_bound, float(np.abs(u_free - u_ref).max(initial=0.0)) + move_error, ""


def _contact_at_supports(model: ContactModel, dlam: np.ndarray) -> np.ndarray:
    """How a change of the contact forces changes the supports' forces directly: on a chain,
    a bar contact that ends at a support pushes on it; a problem's rows touch no prescribed
    dof (zeros)."""
    zero = np.zeros(model.n_free)
    return (model.reactions_of(model.full_displacements(zero), dlam)
            - model.reactions_of(model.full_displacements(zero), np.zeros_like(dlam)))


__all__ = ["ACCEPT", "HOLD", "REFINE", "on_set_bounds", "reference"]
