"""The Result of a solve and its independent check.

A method hands back its displacements and contact forces (a :class:`Solution`); everything
else is derived here from those two alone, the same way for every method, and checked against
the scene: equilibrium at every node, feasibility at every wall, complementarity and the sign of
every contact force. No solver's own status is trusted; it is recorded beside the check.

Residuals (all dimensionless, ∞-norms):
    equilibrium      section equilibrium: at every cut through the bar, the element force from u
                     against the force that the loads, walls (W) and supports (R) on one side
                     need: ‖cumsum(K u − P − R − W)‖ / F, F the largest nodal force term
                     and at least the force the scene makes: the largest load, and
                     k_min × |gap| of a wall that starts past its node. cumsum(K u) is minus
                     the element forces, so it is evaluated run by run between loaded nodes
                     (:func:`section_residual`). The last cut is the balance of the whole bar. A per-node residual is not enough: n
                     residuals within tolerance add up along a long bar (OSQP on a
                     10⁴-element bar: 8e-7 per node, 0.56 % in the contact force)
    feasibility      inequality: max(0, max penetration) / U; equality: max |penetration| / U,
                     U the displacement scale max(‖u‖, F / k_max): the last term, F over
                     the stiffest element, keeps U physical when the exact answer is u = 0
                     (a closed zero gap) and ‖u‖ is round-off. Open gaps are not scales: a
                     far wall would hide a wrong force at a near one (measured: Clarabel,
                     81 N on a 1 N load pulling away from a zero-gap wall, once "verified"
                     because a second wall 0.19 mm away set U). Only in a scene with no
                     loads and no wall past its node (u = 0, λ = 0 exactly) do the gaps set
                     U, and k_min × largest gap F
    complementarity  max min(λᵢ⁺, gapᵢ⁺ · sᵢ) / F, gap = −penetration, x⁺ = max(x, 0)
                     (inequality contact): a wall may push or stand off, not both. A wall's
                     gap counts as the force it takes to close it, sᵢ the stiffness its node
                     sees with the supports and the pushing walls held (seen_stiffness; a bar
                     contact keeps sᵢ = F / U). With gap / U a wall's force could move to its
                     neighbour on a fine mesh unseen (Clarabel, 10⁵ walls: 3e-3 of the largest
                     force, verified). The product λᵢ·penetrationᵢ / (F·U)
                     is weaker: on a weakly active wall (zero gap, zero force) it passed a
                     QP answer 1.4e-4 F off (each factor ~1e-4, the product 1e-8)
    sign             max(0, −min λ) / F: how hard a wall pulls   (inequality contact)
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from contactqp.model import Model, element_forces, penetration, slot_forces, wall_forces
from contactqp.scene import Scene

_TINY = 1e-300


@dataclass(frozen=True)
class Tolerances:
    """Largest residuals a verified Result may have (dimensionless, see the module docstring).

    The explicit Lagrange method reaches ~1e-15. Equilibrium and sign are held to 1e-6 of the
    force scale. Feasibility and complementarity are held to 1e-5 of the displacement scale
    (10 nm on the default scene): that accepts the textbook penalty ε = 1e14, which leaves
    1.8e-6 there, and rejects ε <= 1e13 and first-order QP solvers at loose settings.
    """

    equilibrium: float = 1e-6
    feasibility: float = 1e-5
    complementarity: float = 1e-5
    sign: float = 1e-6


TOLERANCES = Tolerances()


@dataclass(frozen=True)
class Solution:
    """What a method returns: free-node displacements (m) and one contact force per contact
    row (N)."""

    u_free: np.ndarray
    contact_force: np.ndarray
    solver: str
    iterations: int = 1
    status: str = "solved"  # the solver's own claim, recorded, never trusted
    claimed_success: bool = True
    info: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Check:
    """The independent check of a Result."""

    residuals: dict[str, float | None]
    verified: bool
    physical: bool
    message: str


def external_forces(scene: Scene, contact_force: np.ndarray,
                    reactions: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(global node, force in +x, N) of every force on the bars from outside: the loads (point
    loads, then the distributed loads' nodal forces), the contacts' −Cᵀλ and the supports'
    reactions, one entry each (a node may repeat); and how many entries are loads."""
    rows, contact_nodes, values, _ = scene.contact_rows
    nodes, loads = scene.load_nodes, np.array([p.force for p in scene.loads], dtype=float)
    if scene.distributed:
        spread = scene.distributed_nodal_loads()
        at = np.flatnonzero(spread)
        nodes, loads = np.concatenate((nodes, at)), np.concatenate((loads, spread[at]))
    lam = np.asarray(contact_force, dtype=float).reshape(-1)
    all_nodes = np.concatenate((nodes, contact_nodes, scene.support_nodes)).astype(np.intp)
    forces = np.concatenate((loads, -values * lam[rows] if lam.size else np.zeros(rows.size),
                             np.asarray(reactions, dtype=float).reshape(-1)))
    return all_nodes, forces, int(loads.size)


def check(scene: Scene, u: np.ndarray, contact_force: np.ndarray, reactions: np.ndarray,
          contact: str, tolerances: Tolerances = TOLERANCES,
          element_force: np.ndarray | None = None) -> Check:
    """Check displacements (m, every node) and forces (N) against the scene, independently of
    how they were found. ``contact`` is "inequality" or "equality". ``element_force``: the
    element forces k_e·(u_(e+1) − u_e) when the caller has them already (else computed)."""
    forces = element_forces(scene, u) if element_force is None else element_force
    nodes, external, n_loads = external_forces(scene, contact_force, reactions)
    load_scale = _norm(external[:n_loads])
    gaps = scene.gaps
    # What makes forces: the loads, and walls that start past their node (k·|gap|, k the
    # softest element). Only when neither does (exact answer u = 0, every computed force
    # round-off) do the gaps set the scales. Open gaps otherwise stay out: a far wall's gap
    # would make U and F large and hide a wrong force at a near one.
    k_min, k_max = float(scene.stiffness.min()), float(scene.stiffness.max())
    source = max(load_scale, k_min * float(np.max(-gaps, initial=0.0)))
    unloaded = _norm(gaps) if source == 0.0 else 0.0
    force_scale = max(_norm(external), _norm(forces), source, k_min * unloaded, _TINY)
    disp_scale = max(_norm(u), force_scale / k_max, unloaded, _TINY)
    # section equilibrium: cutting element j leaves nodes 0..j, held by the outside forces on
    # them and the element's pull N_j; past the last node the cut is the whole bar's balance
    # (between bars no element joins the nodes: the cut there is the balance of the bars before)
    equilibrium = section_residual(slot_forces(scene, forces), nodes, external) / force_scale
    lam = np.asarray(contact_force, dtype=float)
    pen = penetration(scene, u)
    pulling = float(np.max(-lam, initial=0.0)) / force_scale  # NaN stays NaN: not physical
    if contact == "equality":
        feasibility = _norm(pen) / disp_scale
        residuals = {"equilibrium": equilibrium, "feasibility": feasibility,
                     "complementarity": None, "sign": None}
    else:
        feasibility = max(0.0, float(pen.max(initial=0.0))) / disp_scale
        # the natural residual min(λ, gap·s)/F per wall, not a product λ·gap (module
        # docstring); pulling and penetrating are the sign and feasibility residuals
        gap_force = np.maximum(-pen, 0.0) * force_scale / disp_scale
        n_walls = len(scene.walls)
        if n_walls:
            wall_nodes = scene.contact_rows[1][:n_walls]
            pushing = wall_nodes[lam[:n_walls] > tolerances.complementarity * force_scale]
            gap_force[:n_walls] = (np.maximum(-pen[:n_walls], 0.0)
                                   * seen_stiffness(scene, pushing, wall_nodes))
        complementarity = _norm(np.minimum(np.maximum(lam, 0.0), gap_force)) / force_scale
        residuals = {"equilibrium": equilibrium, "feasibility": feasibility,
                     "complementarity": complementarity, "sign": pulling}
    if not (math.isfinite(force_scale) and math.isfinite(disp_scale)):
        # a NaN or infinite u, λ or reaction: no scale, so no residual can pass
        residuals = {name: (None if value is None else math.inf)
                     for name, value in residuals.items()}
    failures = [
        f"{name} residual {value:.2e} > {getattr(tolerances, name):.0e}"
        for name, value in residuals.items()
        if value is not None and not value <= getattr(tolerances, name)  # NaN fails too
    ]
    physical = pulling <= tolerances.sign
    notes = list(failures)
    if not physical and not np.isfinite(lam).all():
        notes.append("non-physical: contact forces are not finite (the solver returned no "
                     "answer)")
    elif not physical:
        which = ", ".join(f"wall[{i}] {lam[i]:.6g} N" for i in np.flatnonzero(lam < 0))
        notes.append(f"non-physical: a wall pulls the bar ({which}); a rigid wall can only push")
    return Check(residuals, not failures, physical, "; ".join(notes))


def seen_stiffness(scene: Scene, held: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """The stiffness (N/m) each of ``nodes`` (global) sees with the supports and the nodes
    ``held`` fixed: 1/c_left + 1/c_right, c the compliance Σ L/(EA) to the nearest fixed node
    on that side in the same bar (no term when there is none)."""
    offsets = scene.node_offsets
    phi = np.concatenate([bar.compliance_from_node_0 for bar in scene.bars])
    fixed = np.unique(np.concatenate((scene.support_nodes, held)))
    fixed_bar = np.searchsorted(offsets, fixed, side="right") - 1
    node_bar = np.searchsorted(offsets, nodes, side="right") - 1
    stiffness = np.zeros(nodes.size)
    for neighbour, sign in ((np.searchsorted(fixed, nodes, side="left") - 1, 1.0),
                            (np.searchsorted(fixed, nodes, side="right"), -1.0)):
        near = (neighbour >= 0) & (neighbour < fixed.size)
        near[near] &= fixed_bar[neighbour[near]] == node_bar[near]
        compliance = sign * (phi[nodes[near]] - phi[fixed[neighbour[near]]])
        stiffness[near] += 1.0 / compliance
    return stiffness


def section_residual(forces: np.ndarray, nodes: np.ndarray, external: np.ndarray) -> float:
    """max over the cuts of |N_j + E_j| (N): N_j the force of element j, E_j the outside
    forces on nodes 0..j, and the whole bar's balance |E_last|. E is a step function that
    changes only at loaded nodes, so each run of elements between them is one max and one
    min (numpy reduceat), without an O(n) cumulative sum."""
    order = np.argsort(nodes, kind="stable")
    steps, first = np.unique(nodes[order], return_index=True)
    totals = np.cumsum(external[order])[np.r_[first[1:], order.size] - 1]  # E after each step
    balance = abs(float(totals[-1])) if totals.size else 0.0
    if forces.size == 0:
        return balance
    # runs of elements [start, next start) with E constant; before the first step E = 0
    starts = np.unique(np.concatenate(([0], steps[steps < forces.size])))
    level = np.zeros(starts.size)
    level_at = np.searchsorted(steps, starts, side="right") - 1
    level[level_at >= 0] = totals[level_at[level_at >= 0]]
    top = np.maximum.reduceat(forces, starts) + level
    bottom = np.minimum.reduceat(forces, starts) + level
    return max(_norm(top), _norm(bottom), balance)


def _norm(values: np.ndarray) -> float:
    """∞-norm; inf when any value is NaN or infinite (two reductions, no temporaries)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return 0.0
    largest = max(float(values.max()), -float(values.min()))
    return largest if math.isfinite(largest) else math.inf


@dataclass(frozen=True, eq=False)
class Result:
    """Everything one solve found, in physical words, with its independent check.

    Attributes
    ----------
    u : displacement of every node (m, +x), supports included, bar after bar.
    contact_force : one per contact row (N): the walls in scene order, then the bar contacts;
        positive when the wall (the other bar) pushes.
    reactions : one per support in scene order (N), the force the support applies in +x.
    penetration : one per contact row (m), positive when the contact is closed past its gap.
    element_force, stress : axial force (N) and stress (Pa) of each element, bar after bar,
        tension positive.
    stress_ratio : largest |stress| over the yield stress (None without a yield stress).
    residuals, verified, physical, message : the independent check (see :func:`check`).
    status, claimed_success : what the solver itself said, recorded and not trusted.
    time : wall time of the whole solve (s); timings splits it into build and solve.
    info : what the method reported beyond u and λ (e.g. a QP's scales and the solver's own
        timings; in the strain formulation ``element_force``, the tie rows' multipliers, N).
    """

    scene: Scene
    method: str
    solver: str
    contact: str
    options: dict[str, Any]
    u: np.ndarray
    contact_force: np.ndarray
    reactions: np.ndarray
    penetration: np.ndarray
    element_force: np.ndarray
    stress: np.ndarray
    stress_ratio: float | None
    residuals: dict[str, float | None]
    verified: bool
    physical: bool
    message: str
    status: str
    claimed_success: bool
    iterations: int
    time: float
    timings: dict[str, float]
    warnings: tuple[str, ...]
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """method (and solver where it says more), e.g. 'penalty' or 'qp/osqp'."""
        return self.method if self.solver == self.method else f"{self.method}/{self.solver}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (plain floats and lists)."""
        return {
            "scene": self.scene.name, "method": self.method, "solver": self.solver,
            "contact": self.contact, "options": _plain(self.options),
            "u": _plain(self.u), "contact_force": _plain(self.contact_force),
            "reactions": _plain(self.reactions), "penetration": _plain(self.penetration),
            "element_force": _plain(self.element_force), "stress": _plain(self.stress),
            "stress_ratio": self.stress_ratio, "residuals": _plain(self.residuals),
            "verified": self.verified, "physical": self.physical, "message": self.message,
            "status": self.status, "claimed_success": self.claimed_success,
            "iterations": self.iterations, "time": self.time, "timings": _plain(self.timings),
            "warnings": list(self.warnings), "info": _plain(self.info),
        }

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)


def _plain(value: Any) -> Any:
    """numpy → Python, non-finite floats → None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def _support_reactions(scene: Scene, forces: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
    """The force (N, +x) each support applies: what equilibrium of its node leaves over from
    the elements on either side (``forces`` by slot, 0 between bars), the loads and the
    contacts there."""
    nodes = scene.support_nodes
    right = np.where(nodes < forces.size, forces[np.minimum(nodes, forces.size - 1)], 0.0)
    left = np.where(nodes > 0, forces[np.maximum(nodes - 1, 0)], 0.0)
    outside = scene.nodal_loads()[nodes]
    if scene.contacts:  # a bar contact may end at a support; walls may not
        outside = outside + wall_forces(scene, contact_force)[nodes]
    return left - right - outside


def make_result(model: Model, solution: Solution, *, method: str, contact: str,
                options: dict[str, Any], timings: dict[str, float],
                tolerances: Tolerances = TOLERANCES) -> Result:
    """Build the Result of a solution: derive every quantity from u and λ, then check it."""
    scene = model.scene
    u = model.full_displacements(np.asarray(solution.u_free, dtype=float))
    lam = np.asarray(solution.contact_force, dtype=float).reshape(-1)
    forces = element_forces(scene, u)
    # reactions are what equilibrium at the supports needs (the force of the elements on each
    # side, less loads and contacts there); the check then tests every section of every bar
    reactions = _support_reactions(scene, slot_forces(scene, forces), lam)
    stress = forces / scene.areas
    yield_stress = scene.yield_stress
    ratio = None if yield_stress is None else float(np.fmax.reduce(np.abs(stress) / yield_stress))
    found = check(scene, u, lam, reactions, contact, tolerances, element_force=forces)
    warnings: list[str] = []
    if ratio is not None and ratio > 1.0:
        e = int(np.nanargmax(np.abs(stress) / yield_stress))
        where = f"element {e}"
        if len(scene.bars) > 1:
            bar = int(np.searchsorted(np.cumsum([b.n_elements for b in scene.bars]), e, "right"))
            where = f"bar[{bar}] element {e - sum(b.n_elements for b in scene.bars[:bar])}"
        warnings.append(
            f"stress beyond yield: {where} carries {stress[e] / 1e6:.1f} MPa, "
            f"{ratio:.2f} x the yield stress {yield_stress[e] / 1e6:.0f} MPa (a linear-elastic "
            "answer past yield)"
        )
    if solution.claimed_success and not found.verified:
        warnings.append(f"{solution.solver} reported {solution.status!r} but the check failed")
    return Result(
        scene=scene, method=method, solver=solution.solver, contact=contact,
        options=dict(options), u=u, contact_force=lam, reactions=reactions,
        penetration=penetration(scene, u), element_force=forces, stress=stress,
        stress_ratio=ratio, residuals=found.residuals, verified=found.verified,
        physical=found.physical, message=found.message, status=solution.status,
        claimed_success=solution.claimed_success, iterations=solution.iterations,
        time=sum(timings.values()), timings=dict(timings), warnings=tuple(warnings),
        info=dict(solution.info),
    )
