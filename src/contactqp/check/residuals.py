"""What ``verified`` means, on every front end alike: the tolerances, the residuals of an
answer (one definition, read off the model's protocol, :mod:`contactqp.model.base`), and the
verdict that the residuals and a certificate's error bounds give together.

Residuals (dimensionless; F and U the model's scales, s_i = 1/(c_i K⁻¹ c_iᵀ) the stiffness row i
sees with the supports held (0 where it moves a mode K leaves free; worked out only for the
rows whose residual the cheaper bound c_iᵀK c_i/(c_iᵀc_i)² puts above 1e-9 of F), p_i = C_i u −
g_i the penetration):

    equilibrium      max over the free dofs of |K u − P + Cᵀλ| / F: what the answer's forces
                     leave out of balance
    feasibility      max p_i⁺ · s_i / F: the force it takes to push a row back (an equality
                     row: |p_i| · s_i)
    complementarity  max min(λ_i⁺, (−p_i)⁺ · s_i) / F over inequality rows: a row may push or
                     stand open, not both
    sign             max λ_i⁻ / F over inequality rows: how hard a row pulls
    force            the force error bound / F: every contact force and reaction within it
    displacement     the displacement error bound / U: every displacement within it
    natural_map      Siconos's measure on the LCP, each row scaled by c_iᵀK c_i/(c_iᵀc_i)²
                     (reported, not part of verified; None where K leaves a mode free or
                     rows are equalities)

The bounds come from a certificate (:mod:`contactqp.check.on_set` for every model, and on a
chain first its own O(n) one, :mod:`contactqp.check.chain`). Verified: every residual within
:data:`TOLERANCES`, so every contact force and reaction is within 1e-5·F and every
displacement within 1e-5·U of the exact answer (:data:`GUARANTEE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from contactqp.model.base import ContactModel, natural_top


@dataclass(frozen=True)
class Tolerances:
    """Largest residuals a verified Result may have (dimensionless, see the module docstring).

    The explicit Lagrange method reaches ~1e-15. Equilibrium and sign are held to 1e-6 of F;
    feasibility, complementarity and displacement to 1e-5 (of F, F and U).

    Parameters
    ----------
    equilibrium : float
        Of the section equilibrium residual, relative to F (default 1e-6).
    feasibility : float
        Of the penetration as a force, relative to F (default 1e-5).
    complementarity : float
        Relative to F (default 1e-5).
    sign : float
        Of a pulling contact force, relative to F (default 1e-6).
    force : float
        Of the force error bound, relative to F (default 1e-5).
    displacement : float
        Of the displacement error bound, relative to U (default 1e-5).
    """

    equilibrium: float = 1e-6
    feasibility: float = 1e-5
    complementarity: float = 1e-5
    sign: float = 1e-6
    force: float = 1e-5
    displacement: float = 1e-5


TOLERANCES = Tolerances()

# What ``verified`` guarantees, relative to F and U (module docstring)
GUARANTEE = (TOLERANCES.force, TOLERANCES.displacement)


@dataclass(frozen=True)
class Check:
    """The independent check of a Result: the residuals (module docstring), whether all are
    within tolerance, whether no wall pulls, what failed, and the error bounds they give."""

    residuals: dict[str, float | None]
    verified: bool
    physical: bool
    message: str
    force_error_bound: float  # N: every contact force and reaction within this of exact
    displacement_error_bound: float  # m: every displacement within this of exact
    force_scale: float  # F (N)
    displacement_scale: float  # U (m)
    # C u − g per row (m) as the residuals read it, for the caller that reports it too (None
    # for an answer with a NaN or an infinite value)
    penetration: np.ndarray | None = field(default=None, repr=False, compare=False)


ORDER = ("equilibrium", "feasibility", "complementarity", "sign", "force", "displacement",
         "natural_map")


def residuals(model: ContactModel, u_free: np.ndarray, lam: np.ndarray, equality: np.ndarray,
              imbalance: float | None = None, limits: tuple[float, float] | None = None
              ) -> tuple[dict[str, float | None], np.ndarray]:
    """(the residuals of the module docstring but force and displacement, the penetration)
    of an answer (free-dof displacements, one force per row); ``equality`` per row.
    ``imbalance``: ‖K u − P + Cᵀλ‖∞ where the caller has worked it out (a chain, from the
    element forces it has).

    Each row's force residuals are read first with the bound s̄ ≥ s (no solve); only where
    one of them passes SIGNIFICANT of F (or is not a number) are they read again with the
    row's own s (:meth:`~contactqp.model.base.ContactModel.seen_stiffness`). ``limits``: the
    feasibility and complementarity residuals (forces) past which the answer is not verified
    whatever the other rows: the rows are then read again largest bound first, FIRST_ROWS and
    four times as many each time after, and once a row passes its limit with its own s the
    rest keep their bounds (upper bounds: the verdict is decided, and on a sparse model each
    row's s is a solve; an answer 1e-4 off on 10⁴ rows and 3.3·10⁵ dofs asked 10⁴ solves)."""
    F = model.force_scale
    pen = model.C_times(u_free)
    pen -= model.g
    bound = model.row_stiffness
    if equality.any():
        passed, both, pulling = _row_forces(pen, lam, bound, equality)
        top_passed = np.maximum.reduce(passed, initial=0.0)  # NaN where a row's is
        top_both = np.maximum.reduce(both, initial=0.0)
    else:  # every row unilateral (a scene's, most problems'): the largest of each, fused
        seen = pen * bound  # p·s̄: pushed past (+) or standing open (−), as a force
        top_passed = np.maximum.reduce(seen, initial=0.0)  # max p⁺·s̄ (s̄ >= 0)
        t = np.negative(lam)
        pulling = float(np.maximum.reduce(t, initial=0.0))
        np.maximum(t, seen, out=t)  # max(−λ, p·s̄): min(λ⁺, (−p)⁺·s̄) = max(0, −that)
        top_both = 0.0 - np.minimum.reduce(t, initial=0.0)  # NaN where a row's is
        passed = both = None  # made where a row is read again
    if not (top_passed <= SIGNIFICANT * F and top_both <= SIGNIFICANT * F):
        if passed is None:
            passed, both, pulling = _row_forces(pen, lam, bound, equality)
        pushing = np.maximum(lam, 0.0)
        largest = np.maximum(passed, both)
        rows = np.flatnonzero(~(largest <= SIGNIFICANT * F))
        size = rows.size
        if limits is not None and rows.size > FIRST_ROWS:  # largest bound first (NaN first)
            rows = rows[np.argsort(-np.nan_to_num(largest[rows], nan=np.inf), kind="stable")]
            size = FIRST_ROWS
        start = 0
        while start < rows.size:
            chunk = rows[start:start + size]
            s = model.seen_stiffness(chunk)
            p = pen[chunk]
            past = np.where(equality[chunk], np.abs(p), np.maximum(p, 0.0))
            standing = np.where(equality[chunk], 0.0, np.maximum(-p, 0.0))
            passed[chunk] = past * s
            both[chunk] = np.minimum(pushing[chunk], standing * s)
            start, size = start + size, 4 * size
            if limits is not None and (np.fmax.reduce(passed[chunk], initial=0.0) > limits[0]
                                       or np.fmax.reduce(both[chunk], initial=0.0) > limits[1]):
                break  # not verified whatever the rest: they keep their bounds
        top_passed = np.fmax.reduce(passed, initial=0.0)  # 0·∞ counts 0
        top_both = np.fmax.reduce(both, initial=0.0)
    found: dict[str, float | None] = {
        "equilibrium": (model.largest_imbalance(u_free, lam) if imbalance is None
                        else imbalance) / F,
        "feasibility": float(top_passed) / F,
        "complementarity": float(top_both) / F,  # 0 on equalities
        "sign": pulling / F}
    if equality.all():
        found["complementarity"] = found["sign"] = None
    return found, pen


def _row_forces(pen: np.ndarray, lam: np.ndarray, bound: np.ndarray, equality: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, float]:
    """(p⁺·s̄ per row, min(λ⁺, (−p)⁺·s̄) per row, the largest pull) of the penetration ``pen``
    and bounds ``bound`` (an equality row: |p|·s̄, and 0 for the second)."""
    pushing = np.maximum(lam, 0.0)
    unilateral = ~equality
    passed = np.where(equality, np.abs(pen), np.maximum(pen, 0.0))
    both = np.where(unilateral, np.maximum(-pen, 0.0), 0.0)
    pulling = float((-lam[unilateral]).max(initial=0.0))
    passed *= bound  # p⁺·s̄
    both *= bound  # (−p)⁺·s̄, then min(λ⁺, (−p)⁺·s̄)
    np.minimum(pushing, both, out=both)
    return passed, both, pulling


SIGNIFICANT = 1e-9  # of F: a row whose residual s̄ puts below this needs no solve for its s
FIRST_ROWS = 16  # rows read with their own s first, where limits say when to stop (each a
# solve on a sparse model: 0.1 s at 3.3·10⁵ dofs, as much in a block of columns as alone)


def natural_residual(model: ContactModel, lam: np.ndarray, pen: np.ndarray,
                     equality: np.ndarray) -> float | None:
    """:func:`~contactqp.model.base.natural_map` of an answer, each row scaled by its s (None
    where rows are equalities or K leaves a mode free: the LCP needs K⁻¹)."""
    if equality.any() or model.singular:
        return None
    return float(natural_top(lam, -pen, model.row_roots)) / model.free_gap_size


def verdict(model: ContactModel, found: dict[str, float | None], lam: np.ndarray,
            equality: np.ndarray, force_bound: float, displacement_bound: float,
            tolerances: Tolerances, why: str = "",
            penetration: np.ndarray | None = None) -> Check:
    """The Check of residuals ``found`` (force and displacement from the bounds): verified
    where every one is within ``tolerances`` (``why``: a certificate that found no bound)."""
    F, U = model.force_scale, model.displacement_scale
    found = {**found, "force": force_bound / F, "displacement": displacement_bound / U}
    failures = [f"{name} residual {value:.2e} > {getattr(tolerances, name):.3g}"
                for name, value in found.items()
                if name != "natural_map" and value is not None
                and not value <= getattr(tolerances, name)]
    if why:
        failures.append(why)
    # a row that is unilateral by its kind may only push, even where the contact asked for
    # holds it on its gap (the textbook equality form): a pull there is not physical
    unilateral = ~model.equality
    if equality.any() or found.get("sign") is None:
        pulling = float(np.maximum(-lam[unilateral], 0.0).max(initial=0.0)) / F
    else:  # every row unilateral: the sign residual is that pull (:func:`residuals`)
        pulling = found["sign"]
    physical = pulling <= tolerances.sign
    notes = list(failures)
    if not physical:
        rows = np.flatnonzero(unilateral & (lam < -tolerances.sign * F))
        rows = rows[np.argsort(lam[rows], kind="stable")]
        more = rows.size - LISTED_PULLS
        force = f" {model.units[0]}" if model.units[0] else ""
        notes.append("non-physical: a contact pulls (" + ", ".join(
            f"{model.row_names[i]} {lam[i]:.6g}{force}" for i in rows[:LISTED_PULLS])
            + (f" and {more} more" if more > 0 else "") + "); a rigid wall can only push")
    ordered = {name: found.get(name) for name in ORDER}
    return Check(ordered, not failures, physical, "; ".join(notes), force_bound,
                 displacement_bound, F, U, penetration)


LISTED_PULLS = 5  # a message names the rows that pull hardest, not every one (10⁴ made 224 kB)


def not_finite(model: ContactModel, equality: np.ndarray, lam: np.ndarray) -> Check:
    """The Check of an answer with a NaN or an infinite value: every residual inf."""
    F, U = model.force_scale, model.displacement_scale
    names = ["equilibrium", "feasibility", "complementarity", "sign", "force", "displacement"]
    skip = {"complementarity", "sign"} if equality.all() else set()
    found: dict[str, float | None] = {name: (None if name in skip else math.inf)
                                      for name in names}
    found["natural_map"] = None
    physical = bool(np.isfinite(lam).all()) and float(
        np.max(-lam[~model.equality], initial=0.0)) <= TOLERANCES.sign * F
    message = "the answer is not finite (the method returned no answer)"
    if not physical:
        message += "; non-physical: contact forces are not finite"
    return Check(found, False, physical, message, math.inf, math.inf, F, U)


__all__ = ["GUARANTEE", "TOLERANCES", "Check", "Tolerances", "natural_residual", "not_finite",
           "residuals", "verdict"]
