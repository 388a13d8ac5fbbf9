"""The independent check of an answer: the same for every method, reading only u, the contact
forces, the reactions and the model. No solver's own status is trusted.

What ``verified`` guarantees. The check reads an answer (u, λ) as the exact answer of a nearby
scene: the contacts that push are held where the answer puts them (their gaps moved by as much
as the answer penetrates or stands off there), the force on every other contact, and every
pulling force, is moved off it as a load, and what equilibrium leaves over is a load too. It
then works out, run by run between the held nodes, what those moves do to the forces and the
displacements: :attr:`Check.force_error_bound` (N) bounds the error of every contact force and
reaction, :attr:`Check.displacement_error_bound` (m) the error of every displacement. Verified,
every residual is within :data:`TOLERANCES`: the force bound is at most 1e-5·F and the
displacement bound at most 1e-5·U (:data:`GUARANTEE`). F and U come from the loads and the
prescribed gaps alone (:attr:`contactqp.model.Model.force_scale`,
:attr:`~contactqp.model.Model.displacement_scale`), never from the answer being judged. The
bounds are exact to first order within the answer's own set of pushing contacts; property
tests hold every method and solver to them against the exact reference on thousands of random
scenes (tests/test_guarantee.py, benchmarks/guarantee.py).

Residuals (dimensionless; s_i is the stiffness row i sees with the supports and the pushing
contacts held, :func:`contactqp.model.seen_stiffness`, a bar contact its two nodes' in series;
p_i = C_i u − g_i the penetration, gap_i = −p_i):
    equilibrium      max over every cut through every bar of |N_j + E_j| / F: N_j the element
                     force from u, E_j the outside forces (loads, contacts, supports) on the
                     nodes before the cut; the last cut is the balance of the whole scene.
                     A per-node residual would let n errors add up along a long bar (OSQP on a
                     10⁴-element bar: 8e-7 per node, 0.56 % in the contact force)
    feasibility      max p_i⁺ · s_i / F: the force it takes to push a penetrating node back
                     (equality contact: |p_i| · s_i). Measured against the displacement
                     instead, the penalty passed 2 % off where a stiff element holds the wall
                     and a soft stretch elsewhere makes u large
    complementarity  max min(λ_i⁺, gap_i⁺ · s_i) / F: a contact may push or stand off, not
                     both; a gap counts as the force it takes to close it (with gap / U, a
                     force moved to a neighbouring wall on a fine mesh passed unseen); and
                     min(λ₊, λ₋) of a node pushed from both sides
    sign             max λ_i⁻ / F: how hard a wall pulls
    force            force_error_bound / F: all of the above carried through the runs (small
                     forces left on many open walls add up where they land)
    displacement     displacement_error_bound / U. A force left on a weakly active wall (zero
                     gap, zero exact force) beside a soft element passes every force residual
                     and can still move the bar far more than its share of U
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from contactqp.bounds import error_bounds, largest_pull
from contactqp.errors import OptionError
from contactqp.model import (
    Layout,
    Model,
    element_forces,
    largest,
    link_forces,
    penetration,
    scene_model,
)
from contactqp.runs import Running
from contactqp.scene import Scene, row_names


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


def external_forces(layout: Layout, contact_force: np.ndarray,
                    reactions: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(global node, force in +x, N) of every force on the bars from outside: the loads (point
    loads, then the distributed loads' nodal forces), the contacts' −Cᵀλ and the supports'
    reactions, one entry each (a node may repeat); and how many entries are loads."""
    rows, _, values, _ = layout.rows
    loads = layout.load_entries[1]  # what depends on the loads alone: once per scene
    lam = np.asarray(contact_force, dtype=float).reshape(-1)
    all_nodes = layout.external_nodes
    reactions = np.asarray(reactions, dtype=float).reshape(-1)
    forces = np.empty(loads.size + rows.size + reactions.size)  # filled in place, part by part
    forces[:loads.size] = loads
    contacts = forces[loads.size: loads.size + rows.size]
    if lam.size:
        np.negative(np.multiply(values, lam[layout.by_entry], out=contacts), out=contacts)
    else:
        contacts[:] = 0.0
    forces[loads.size + rows.size:] = reactions
    return all_nodes, forces, int(loads.size)


def check(model: Model | Scene, u: np.ndarray, contact_force: np.ndarray, reactions: np.ndarray,
          contact: str, tolerances: Tolerances = TOLERANCES,
          element_force: np.ndarray | None = None, natural: bool = True,
          link_force: np.ndarray | None = None) -> Check:
    """Check displacements (every node) and forces against a model (or a scene, whose model is
    built), independently of how they were found. ``contact`` is "inequality" or "equality".
    ``element_force``: the element forces k_e·(u_(e+1) − u_e) when the caller has them (and
    ``link_force``, the same on the links between nodes, 0 between bars).

    Parameters
    ----------
    model : Model or Scene
        What the answer is checked against.
    u : array_like
        The displacement of every node (the global numbering of :class:`Layout`).
    contact_force : array_like
        The force of every contact row (walls, then bar contacts).
    reactions : array_like
        The force of every support, in +x.
    contact : str
        ``"inequality"`` or ``"equality"``.
    tolerances : Tolerances
        The residuals' tolerances (default :data:`contactqp.TOLERANCES`).
    element_force : array_like, optional
        The element forces, when the caller has them.
    natural : bool
        Whether to work out the natural-map residual (not part of ``verified``); False
        leaves it NaN (a batch works it out case by case).
    link_force : array_like, optional
        The element forces on the links between nodes (0 between bars), when the caller has
        them (:func:`contactqp.model.link_forces` of ``element_force``).

    Returns
    -------
    Check
        ``verified``, ``physical``, the residuals, the error bounds and the message, as a
        Result carries them.

    Raises
    ------
    OptionError
        A bad contact kind, or an array of the wrong length for the model.
    """
    model = model if isinstance(model, Model) else scene_model(model)
    layout = model.layout
    if contact not in ("inequality", "equality"):
        raise OptionError(f"contact must be inequality or equality; got {contact!r}")
    u = np.asarray(u, dtype=float).reshape(-1)
    lam = np.asarray(contact_force, dtype=float).reshape(-1)
    reactions = np.asarray(reactions, dtype=float).reshape(-1)
    _shape("u", u, layout.n_nodes)
    _shape("contact_force", lam, layout.n_contacts)
    _shape("reactions", reactions, len(layout.scene.supports))
    F, U = model.force_scale, model.displacement_scale
    forces = element_forces(layout, u) if element_force is None else element_force
    links = link_forces(layout, forces) if link_force is None else link_force
    nodes, external, _ = external_forces(layout, lam, reactions)
    u_size = largest(u)  # ‖u‖∞, inf where u has a NaN or an infinite value; read again below
    finite = math.isfinite(u_size) and all(np.isfinite(a).all() for a in (lam, reactions))
    if not finite:  # a NaN or infinite answer: no residual can pass
        return _failed(contact, lam, F, U, tolerances)
    # E_j, the outside forces on nodes 0..j, once for both (at every node where they are many)
    outside = Running.of(layout.n_nodes, nodes, external)
    r_max, links_size = section_residual_and_size(
        links, nodes, external, outside.levels if outside.steps is None else None)
    bounds = error_bounds(layout, u, lam, links, nodes, external, r_max, contact, F, U,
                          tolerances.complementarity, outside, u_size, links_size)
    residuals = {name: value for name, value in bounds.residuals.items()}
    failures = [
        f"{name} residual {value:.2e} > {getattr(tolerances, name):.3g}"
        for name, value in residuals.items()
        if value is not None and not value <= getattr(tolerances, name)
    ]
    # the LCP needs K⁻¹, which a scene with a bar held only by contact does not have
    residuals["natural_map"] = (
        None if contact == "equality" or model.floating
        else _natural_residual(model, lam, bounds.penetration) if natural else math.nan)
    pulling = largest_pull(lam) / F
    physical = pulling <= tolerances.sign
    notes = list(failures)
    if not physical:
        notes.append(f"non-physical: a wall pulls the bar ({_pulling(layout, lam)}); a rigid "
                     "wall can only push")
    return Check(residuals, not failures, physical, "; ".join(notes),
                 bounds.force_error_bound, bounds.displacement_error_bound, F, U,
                 bounds.penetration)


def natural_map(forces: np.ndarray, gaps: np.ndarray, free: np.ndarray,
                roots: np.ndarray | None = None) -> float | np.ndarray:
    """The natural-map residual of the contact LCP (Siconos's measure, not part of
    ``verified``): ‖min(z, w)‖∞ / ‖q‖∞ (min(z, w) = z − (z − w)₊), z the contact forces, w the
    gaps they leave and q the gaps with no contact force. With ``roots`` r (√ of the compliance
    each row sees with the supports held, :func:`row_compliance_roots`) each row is scaled as
    the LCP scaled to a unit diagonal is, z = λ·r, w/r, q/r, so that the number is the same in
    every unit system. Over the last axis (one value per case for cases x rows)."""
    return _natural_top(forces, gaps, roots) / _natural_size(free, roots)


def _natural_top(forces: np.ndarray, gaps: np.ndarray, roots: np.ndarray | None,
                 own_gaps: bool = False) -> np.ndarray:
    """‖min(z, w)‖∞ of :func:`natural_map`, each row scaled by ``roots`` (if given);
    ``own_gaps``: ``gaps`` is the caller's scratch, scaled in place."""
    scaled = roots is not None
    if scaled:  # λ = D z and D w, D = diag(W)^-½ = 1/roots
        forces, gaps = forces * roots, np.divide(gaps, roots, out=gaps if own_gaps else None)
    with np.errstate(invalid="ignore"):  # in the scaled forces' array when there is one
        top = np.minimum(forces, gaps, out=forces if scaled else None)
        return np.nanmax(np.abs(top, out=top), axis=-1, initial=0.0)


def _natural_size(free: np.ndarray, roots: np.ndarray | None) -> np.ndarray:
    """‖q‖∞ of :func:`natural_map` (1 where it is 0), each row scaled by ``roots``."""
    if roots is not None:
        free = free / roots
    with np.errstate(invalid="ignore"):
        size = np.nanmax(np.abs(free), axis=-1, initial=0.0)
    return np.where(size > 0.0, size, 1.0)


def _natural_residual(model: Model, lam: np.ndarray, pen: np.ndarray) -> float:
    """:func:`natural_map` of an answer on ``model``, with what depends on the model alone
    (each row's scaling and the size of the free gaps it scales) kept on the model."""
    kept = model.__dict__.get("natural_scale")
    if kept is None:
        roots = row_compliance_roots(model.layout)
        kept = model.__dict__["natural_scale"] = (roots, _natural_size(free_gaps(model), roots))
    roots, size = kept
    return float(_natural_top(lam, np.negative(pen), roots, own_gaps=True) / size)


def free_gaps(model: Model) -> np.ndarray:
    """q = g − C K⁻¹P: the gap of every row with no contact force (m)."""
    return -penetration(model.layout, model.free_displacement_of_nodes)


def row_compliance_roots(layout: Layout) -> np.ndarray:
    """√ of the compliance each row sees with the supports held
    (:attr:`contactqp.model.Layout.row_compliance`; a bar contact's two ends in series); NaN
    where a row sees no stiffness or an infinite one (it is left out of :func:`natural_map`)."""
    return layout.row_compliance_roots  # made once per layout topology


def _shape(name: str, values: np.ndarray, size: int) -> None:
    if values.size != size:
        raise OptionError(f"{name} must have {size} values for this scene, got {values.size}")


def _failed(contact: str, lam: np.ndarray, F: float, U: float,
            tolerances: Tolerances) -> Check:
    """The Check of an answer with NaN or infinite values: every residual inf, not physical
    when a contact force is not finite."""
    names = ["equilibrium", "feasibility", "complementarity", "sign", "force", "displacement"]
    skip = {"complementarity", "sign"} if contact == "equality" else set()
    residuals = {name: (None if name in skip else math.inf) for name in names}
    notes = [f"{name} residual inf > {getattr(tolerances, name):.3g}"
             for name, value in residuals.items() if value is not None]
    residuals["natural_map"] = None if contact == "equality" else math.inf
    physical = bool(np.isfinite(lam).all()) and float(np.max(-lam, initial=0.0)) <= (
        tolerances.sign * F)
    if not physical:
        notes.append("non-physical: contact forces are not finite (the solver returned no "
                     "answer)")
    return Check(residuals, False, physical, "; ".join(notes), math.inf, math.inf, F, U)


def section_residual(forces: np.ndarray, nodes: np.ndarray, external: np.ndarray,
                     outside: np.ndarray | None = None) -> float:
    """max over the cuts of |N_j + E_j| (N): N_j the force of element j, E_j the outside
    forces on nodes 0..j, and the whole bar's balance |E_last|. E is a step function that
    changes only at loaded nodes, so each run of elements between them is one max and one
    min (numpy reduceat), without an O(n) cumulative sum; with outside forces on more than
    an eighth of the nodes, one cumulative sum is cheaper than sorting them (``outside``:
    that sum, E_j for every node j, when the caller has it)."""
    return section_residual_and_size(forces, nodes, external, outside)[0]


def section_residual_and_size(forces: np.ndarray, nodes: np.ndarray, external: np.ndarray,
                              outside: np.ndarray | None = None) -> tuple[float, float | None]:
    """(:func:`section_residual`, ‖forces‖∞ where the runs' largest and smallest forces give
    it, else None): the check reads both, and the forces once."""
    if outside is not None or 8 * nodes.size > forces.size:
        if outside is None:
            outside = np.cumsum(np.bincount(nodes, external, minlength=forces.size + 1))
        return max(largest(forces + outside[:-1]), abs(float(outside[-1]))), None
    order = np.argsort(nodes, kind="stable")
    steps, first = np.unique(nodes[order], return_index=True)
    totals = np.cumsum(external[order])[np.append(first[1:], order.size) - 1]  # E after a step
    balance = abs(float(totals[-1])) if totals.size else 0.0
    if forces.size == 0:
        return balance, 0.0
    # runs of elements [start, next start) with E constant; before the first step E = 0
    starts = np.unique(np.concatenate(([0], steps[steps < forces.size])))
    level = np.zeros(starts.size)
    level_at = np.searchsorted(steps, starts, side="right") - 1
    level[level_at >= 0] = totals[level_at[level_at >= 0]]
    top, bottom = np.maximum.reduceat(forces, starts), np.minimum.reduceat(forces, starts)
    size = max(largest(top), largest(bottom))  # ‖forces‖∞
    return max(largest(top + level), largest(bottom + level), balance), size


LISTED_PULLS = 5  # a message names the rows that pull hardest, not every one (10⁴ made 224 kB)


def _pulling(layout, lam: np.ndarray) -> str:
    """The rows whose force pulls, hardest first: at most LISTED_PULLS named, and how many
    more."""
    rows = np.flatnonzero(lam < 0)
    rows = rows[np.argsort(lam[rows], kind="stable")]
    names = row_names(layout.scene)
    listed = ", ".join(f"{names[i]} {lam[i]:.6g} N" for i in rows[:LISTED_PULLS])
    more = rows.size - LISTED_PULLS
    return listed + (f" and {more} more" if more > 0 else "")

