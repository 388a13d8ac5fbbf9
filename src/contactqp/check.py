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
from dataclasses import dataclass

import numpy as np

from contactqp.errors import OptionError
from contactqp.model import (
    Layout,
    Model,
    build_model,
    element_forces,
    largest,
    link_forces,
    penetration,
    seen_stiffness,
)
from contactqp.scene import Scene


@dataclass(frozen=True)
class Tolerances:
    """Largest residuals a verified Result may have (dimensionless, see the module docstring).

    The explicit Lagrange method reaches ~1e-15. Equilibrium and sign are held to 1e-6 of F;
    feasibility, complementarity and displacement to 1e-5 (of F, F and U).
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


def external_forces(layout: Layout, contact_force: np.ndarray,
                    reactions: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(global node, force in +x, N) of every force on the bars from outside: the loads (point
    loads, then the distributed loads' nodal forces), the contacts' −Cᵀλ and the supports'
    reactions, one entry each (a node may repeat); and how many entries are loads."""
    rows, contact_nodes, values, _ = layout.rows
    nodes = layout.load_nodes
    loads = np.array([p.force for p in layout.scene.loads], dtype=float)
    if layout.scene.distributed:
        spread = layout.distributed_nodal_loads
        at = np.flatnonzero(spread)
        nodes, loads = np.concatenate((nodes, at)), np.concatenate((loads, spread[at]))
    lam = np.asarray(contact_force, dtype=float).reshape(-1)
    all_nodes = np.concatenate((nodes, contact_nodes, layout.support_nodes)).astype(np.intp)
    forces = np.concatenate((loads, -values * lam[rows] if lam.size else np.zeros(rows.size),
                             np.asarray(reactions, dtype=float).reshape(-1)))
    return all_nodes, forces, int(loads.size)


def check(model: Model | Scene, u: np.ndarray, contact_force: np.ndarray, reactions: np.ndarray,
          contact: str, tolerances: Tolerances = TOLERANCES,
          element_force: np.ndarray | None = None) -> Check:
    """Check displacements (every node) and forces against a model (or a scene, whose model is
    built), independently of how they were found. ``contact`` is "inequality" or "equality".
    ``element_force``: the element forces k_e·(u_(e+1) − u_e) when the caller has them."""
    model = model if isinstance(model, Model) else build_model(model)
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
    links = link_forces(layout, forces)
    nodes, external, _ = external_forces(layout, lam, reactions)
    finite = all(np.isfinite(a).all() for a in (u, lam, reactions))
    if not finite:  # a NaN or infinite answer: no residual can pass
        return _failed(contact, lam, F, U, tolerances)
    r_max = section_residual(links, nodes, external)
    bounds = error_bounds(layout, u, lam, links, nodes, external, r_max, contact, F, U,
                          tolerances)
    residuals = {name: value for name, value in bounds.residuals.items()}
    failures = [
        f"{name} residual {value:.2e} > {getattr(tolerances, name):.0e}"
        for name, value in residuals.items()
        if value is not None and not value <= getattr(tolerances, name)
    ]
    pulling = float(np.max(-lam, initial=0.0)) / F
    physical = pulling <= tolerances.sign
    notes = list(failures)
    if not physical:
        which = ", ".join(f"{_row_name(layout.scene, i)} {lam[i]:.6g} N"
                          for i in np.flatnonzero(lam < 0))
        notes.append(f"non-physical: a wall pulls the bar ({which}); a rigid wall can only push")
    return Check(residuals, not failures, physical, "; ".join(notes),
                 bounds.force_error_bound, bounds.displacement_error_bound, F, U)


def _shape(name: str, values: np.ndarray, size: int) -> None:
    if values.size != size:
        raise OptionError(f"{name} must have {size} values for this scene, got {values.size}")


def _row_name(scene: Scene, row: int) -> str:
    n_walls = len(scene.walls)
    return f"wall[{row}]" if row < n_walls else f"contact[{row - n_walls}]"


def _failed(contact: str, lam: np.ndarray, F: float, U: float,
            tolerances: Tolerances) -> Check:
    """The Check of an answer with NaN or infinite values: every residual inf, not physical
    when a contact force is not finite."""
    names = ["equilibrium", "feasibility", "complementarity", "sign", "force", "displacement"]
    skip = {"complementarity", "sign"} if contact == "equality" else set()
    residuals = {name: (None if name in skip else math.inf) for name in names}
    notes = [f"{name} residual inf > {getattr(tolerances, name):.0e}"
             for name, value in residuals.items() if value is not None]
    physical = bool(np.isfinite(lam).all()) and float(np.max(-lam, initial=0.0)) <= (
        tolerances.sign * F)
    if not physical:
        notes.append("non-physical: contact forces are not finite (the solver returned no "
                     "answer)")
    return Check(residuals, False, physical, "; ".join(notes), math.inf, math.inf, F, U)


ROUND_OFF = 4.0 * np.finfo(float).eps  # a few units in the last place of what is stored


@dataclass(frozen=True)
class Bounds:
    residuals: dict[str, float | None]
    force_error_bound: float
    displacement_error_bound: float


def error_bounds(layout: Layout, u: np.ndarray, lam: np.ndarray, links: np.ndarray,
                 nodes: np.ndarray, external: np.ndarray, r_max: float, contact: str,
                 F: float, U: float, tolerances: Tolerances) -> Bounds:
    """The residuals and the error bounds of an answer (module docstring).

    The answer is exact for a nearby scene: the rows that push are held at where the answer
    puts them (their gaps moved by δ = |penetration|), the other rows' forces and every
    pulling force are moved off them as loads, and what equilibrium leaves over is a load too.
    With the held nodes fixed, those loads' effect is computed exactly, run by run between
    held nodes (:func:`propagate`); a held node moved by δ moves its runs by at most δ and
    changes the forces at itself and its held neighbours (:func:`gap_moves`)."""
    rows, row_nodes, _, gaps = layout.rows
    n_rows = gaps.size
    pen = penetration(layout, u)
    equality = contact == "equality"
    if equality:
        pushing = np.ones(n_rows, dtype=bool)
    else:
        held_rows = lam > tolerances.complementarity * F
        held = np.concatenate((layout.support_nodes, row_nodes[held_rows[rows]]))
        s = row_stiffness(layout, np.unique(held), held_rows)
        stand_off = np.maximum(-pen, 0.0)
        pushing = lam > stand_off * s  # closing its gap is the smaller move
    held = np.unique(np.concatenate((layout.support_nodes, row_nodes[pushing[rows]])))
    s, s_ends = row_stiffness(layout, held, pushing, ends=True)
    delta = np.abs(pen) if equality else np.where(pushing, np.abs(pen), np.maximum(pen, 0.0))
    moved = np.where(pushing, 0.0, lam)  # an open row's force (or a pull) becomes a load
    n_loads = external.size - row_nodes.size - layout.support_nodes.size
    kept_external = external.copy()  # the contacts of the nearby scene carry only the rest
    kept_external[n_loads:n_loads + row_nodes.size][~pushing[rows]] = 0.0
    force_error, sway = propagate(layout, held, links, nodes, kept_external)
    pair = 0.0 if equality else _both_sides(layout, lam)
    # an open row moved onto its wall (it penetrates) is held too, with no force of its own
    # closing a bar contact's gap δ moves each end by its share, δ·s/s_end (a wall's node: δ)
    with np.errstate(invalid="ignore"):
        end_moves = np.where(np.isfinite(s_ends), delta[rows] * s[rows] / s_ends, 0.0)
    gap_force, gap_move, moves = gap_moves(layout, held, row_nodes, end_moves, pushing)
    # ... and a held node that moves drags its run along: an open contact there whose gap is
    # smaller than that would close, and take what closing the rest of the move needs
    # (measured: quadprog left a wall 2.5e-12 m open beside one held 1.7e-11 m off, across
    # an element of 7e13 N/m, 963 N off and verified without this)
    closing = 0.0 if equality else _closing(layout, moves, row_nodes, rows,
                                            np.where(pushing, np.inf, np.maximum(-pen, 0.0)), s)
    force_bound = max(force_error, largest(moved)) + gap_force + pair + closing
    # a pushing bar contact is held at both ends above, but the two ends move together: the
    # force error it carries moves them by that force over the stiffness both bars give them
    # there, and its bars' forces and displacements by up to as much again (measured: without
    # the factor 2, up to 1.4 times the bound on random scenes of several bars)
    give = _contact_give(layout, held, pushing)
    coupled = 2.0 if give > 0.0 else 1.0
    displacement_bound = coupled * (sway + gap_move) + force_bound * give
    force_bound *= coupled
    # and the answer itself is only stored to a few units of round-off: a force of 2e8 N from
    # a press fit on a stiff element is one float step (3e-8 N) from any other
    force_bound += ROUND_OFF * max(largest(lam), largest(links), F)
    displacement_bound += ROUND_OFF * max(largest(u), U)
    feasibility = largest((np.abs(pen) if equality else np.maximum(pen, 0.0)) * s) / F
    residuals: dict[str, float | None] = {"equilibrium": r_max / F, "feasibility": feasibility}
    if equality:
        residuals.update(complementarity=None, sign=None)
    else:
        natural = np.minimum(np.maximum(lam, 0.0), np.maximum(-pen, 0.0) * s)
        residuals["complementarity"] = max(largest(natural), pair) / F
        residuals["sign"] = float(np.max(-lam, initial=0.0)) / F
    residuals["force"] = force_bound / F
    residuals["displacement"] = displacement_bound / U
    return Bounds(residuals, force_bound, displacement_bound)


def propagate(layout: Layout, held: np.ndarray, links: np.ndarray, nodes: np.ndarray,
              external: np.ndarray) -> tuple[float, float]:
    """What the imbalance of an answer does with the ``held`` nodes (sorted) fixed: (the
    largest force error at a held node, N; the largest displacement error, m).

    r_j, the residual of cut j (element force from u against the outside forces ``external``
    on the nodes before it), is a load pattern: its jumps are the nodal imbalances. Between
    two held nodes the exact answer of the imbalanced scene has element forces N_j − (c − r_j)
    ... i.e. its element force errors are c − r_j, with c such that the run's elongation
    errors (c − r_j)/k_j add up to nothing; a run held at one end only (a bar's tail or head)
    has c the cut residual past the bar's free end. The displacement error is the running sum
    of the elongation errors from the held end, and a held node's force error is the jump of c
    across it."""
    offsets = layout.node_offsets
    outside = np.cumsum(np.bincount(nodes, external, minlength=layout.n_nodes))
    k = layout.link_stiffness
    element = np.flatnonzero(k > 0.0)
    if element.size == 0:
        return 0.0, 0.0
    r = (links + outside[:-1])[element]
    flexibility = 1.0 / k[element]
    bar = np.searchsorted(offsets, element, side="right") - 1
    position = np.searchsorted(held, element, side="right")  # held nodes at or before the start
    first, last = offsets[bar], offsets[bar + 1] - 1
    left_held = (position > 0) & (held[np.maximum(position - 1, 0)] >= first)
    right_held = (position < held.size) & (held[np.minimum(position, held.size - 1)] <= last)
    run = position * len(layout.scene.bars) + bar
    starts = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    ends = np.r_[starts[1:], run.size]
    size = np.diff(np.r_[starts, run.size])
    before_bar = np.where(first > 0, outside[np.maximum(first - 1, 0)], 0.0)
    after_bar = outside[last]
    # c per run: weighted mean (held at both ends), the free end's cut residual otherwise
    both = left_held[starts] & right_held[starts]
    mean = np.add.reduceat(r * flexibility, starts) / np.add.reduceat(flexibility, starts)
    c_run = np.where(both, mean, np.where(left_held[starts], after_bar[starts], before_bar[starts]))
    c = np.repeat(c_run, size)
    elongation = (c - r) * flexibility
    total = np.cumsum(elongation)
    base = np.repeat(total[starts] - elongation[starts], size)  # the sum before each run
    from_left = total - base  # displacement of each element's end node, from the left end
    tail_end = np.repeat(total[ends - 1], size)
    from_right = tail_end - total + elongation  # of each element's start node, from the right
    anchored_left = np.repeat(left_held[starts], size)
    sway = largest(np.where(anchored_left, from_left, from_right))
    # force error at each held node: the jump of c between the elements on either side of it
    # (past a bar's end, the cut residual there)
    held_bar = np.searchsorted(offsets, held, side="right") - 1
    start, end = offsets[held_bar], offsets[held_bar + 1] - 1
    at = np.searchsorted(element, np.r_[held - 1, held].clip(0, element[-1]))
    c_at = c[np.minimum(at, c.size - 1)]
    c_left = np.where(held > start, c_at[: held.size],
                      np.where(start > 0, outside[np.maximum(start - 1, 0)], 0.0))
    c_right = np.where(held < end, c_at[held.size:], outside[end])
    return largest(c_left - c_right), sway


def _contact_give(layout: Layout, held: np.ndarray, pushing: np.ndarray) -> float:
    """The largest 1/(s_a + s_b) (m/N) over the pushing bar contacts: how far a unit force
    error moves the two ends of a contact together, s_a and s_b the stiffness each end sees
    in its own bar with the other held nodes fixed (a supported end does not move)."""
    n_walls = len(layout.scene.walls)
    give = 0.0
    for i, c in enumerate(layout.scene.contacts):
        if not pushing[n_walls + i]:
            continue
        ends = np.array([layout.node(c.bar_a, c.node_a),
                         layout.node(c.bar_b, c.node_b)])
        if np.isin(ends, layout.support_nodes).any():
            continue
        stiffness = seen_stiffness(layout, np.setdiff1d(held, ends), ends)
        give = max(give, 1.0 / float(stiffness.sum()))
    return give


def gap_moves(layout: Layout, held: np.ndarray, nodes: np.ndarray, delta: np.ndarray,
              pushing: np.ndarray) -> tuple[float, float, tuple[np.ndarray, np.ndarray]]:
    """What moving the contact nodes ``nodes`` by ``delta`` (m) with the other held nodes fixed
    does: (the largest force change at a held node, N; the largest move, m; each held node's
    move). A node moved by δ
    between held neighbours at compliances c_l and c_r changes its own force by
    δ(1/c_l + 1/c_r) and each neighbour's by δ/c. The two ends of a pushing bar contact move
    together: each moves by its own δ and the other end's. A moved node that is not held (an
    open contact that penetrates) counts as held."""
    moving = np.unique(np.concatenate((held, nodes[delta > 0.0])))
    if moving.size == 0:
        return 0.0, 0.0, (moving, np.zeros(0))
    by_node = np.zeros(moving.size)
    listed = np.isin(nodes, moving)
    np.maximum.at(by_node, np.searchsorted(moving, nodes[listed]), delta[listed])
    n_walls = len(layout.scene.walls)
    tied = [(int(np.searchsorted(moving, layout.node(c.bar_a, c.node_a))),
             int(np.searchsorted(moving, layout.node(c.bar_b, c.node_b))))
            for i, c in enumerate(layout.scene.contacts) if pushing[n_walls + i]]
    if tied:  # every node of a chain of tied nodes moves by up to the sum of their moves
        group = list(range(moving.size))

        def root(i: int) -> int:
            while group[i] != i:
                i = group[i]
            return i

        for a, b in tied:
            group[root(a)] = root(b)
        members = np.array([root(i) for i in range(moving.size)])
        by_node = np.bincount(members, by_node, minlength=moving.size)[members]
    bar = np.searchsorted(layout.node_offsets, moving, side="right") - 1
    same = bar[1:] == bar[:-1]
    with np.errstate(divide="ignore"):
        link = np.where(same, 1.0 / np.diff(layout.compliance[moving]), 0.0)  # 1/c to the next
    to_left, to_right = np.r_[0.0, link], np.r_[link, 0.0]
    shifted_left, shifted_right = np.r_[0.0, by_node[:-1]], np.r_[by_node[1:], 0.0]
    change = (by_node * (to_left + to_right) + shifted_left * to_left + shifted_right * to_right)
    return largest(change), largest(by_node), (moving, by_node)


def _closing(layout: Layout, moves: tuple[np.ndarray, np.ndarray], row_nodes: np.ndarray,
             rows: np.ndarray, stand_off: np.ndarray, s: np.ndarray) -> float:
    """The largest force an open contact would take if the held nodes at the ends of its run
    moved as ``moves`` says ((sorted nodes, move of each, m)): (move − its stand-off)⁺ × the
    stiffness it sees."""
    held, shift = moves
    if held.size == 0 or not np.isfinite(stand_off).any():
        return 0.0
    bar = np.searchsorted(layout.node_offsets, row_nodes, side="right") - 1
    held_bar = np.searchsorted(layout.node_offsets, held, side="right") - 1
    after = np.searchsorted(held, row_nodes, side="right")
    left, right = np.maximum(after - 1, 0), np.minimum(after, held.size - 1)
    induced = np.maximum(np.where((after > 0) & (held_bar[left] == bar), shift[left], 0.0),
                         np.where((after < held.size) & (held_bar[right] == bar), shift[right],
                                  0.0))
    per_row = np.zeros(stand_off.size)
    np.maximum.at(per_row, rows, induced)
    return largest(np.maximum(per_row - stand_off, 0.0) * np.where(np.isfinite(stand_off), s, 0.0))


def row_stiffness(layout: Layout, held: np.ndarray, pushing: np.ndarray,
                  ends: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The stiffness (N/m) each contact row sees with the supports and ``held`` nodes fixed:
    a wall, its node's (:func:`seen_stiffness`); a bar contact, its two nodes' in series (an
    end held by a support or by a ``pushing`` wall is rigid: only the other end moves; both
    held, neither counts as rigid). With
    ``ends``, also the stiffness of each end (per nonzero of :attr:`Scene.contact_rows`)."""
    rows, row_nodes, _, gaps = layout.rows
    node_stiffness = seen_stiffness(layout, held, row_nodes)
    n_walls = len(layout.scene.walls)
    rigid = np.concatenate((layout.support_nodes, row_nodes[:n_walls][pushing[:n_walls]]))
    fixed = (rows >= n_walls) & np.isin(row_nodes, rigid)
    # both ends held: the contact closes only as a wall gives, at that end's own stiffness
    fixed &= np.bincount(rows[fixed], minlength=gaps.size)[rows] < 2
    node_stiffness[fixed] = np.inf
    with np.errstate(divide="ignore"):
        row = 1.0 / np.bincount(rows, 1.0 / node_stiffness, minlength=gaps.size)
    return (row, node_stiffness) if ends else row


def _both_sides(layout: Layout, lam: np.ndarray) -> float:
    """The largest common part of contact forces that oppose each other (N): a node cannot be
    pushed from both sides at once, whatever the gaps (walls on both sides of it); nor can a
    loop of walls and bar contacts whose gaps sum to zero carry a force all the way round.
    min(Σλ₊, Σλ₋) at a node, and the smallest force around such a loop, is a set of forces
    that moves nothing and is wrong in every row it is on (where the gaps leave the nodes one
    position, the rows alone cannot tell how the force splits; the exact answer has one row of
    each loop free of it)."""
    rows, nodes, coefficients, gaps = layout.rows
    force = np.maximum(lam, 0.0)
    free = ~np.isin(nodes, layout.support_nodes)
    entries = np.bincount(rows[free], minlength=gaps.size)
    single = free & (entries[rows] == 1)  # a wall, or a contact with one end held
    plus = np.zeros(layout.n_nodes)
    minus = np.zeros(layout.n_nodes)
    np.add.at(plus, nodes[single & (coefficients > 0)], force[rows[single & (coefficients > 0)]])
    np.add.at(minus, nodes[single & (coefficients < 0)], force[rows[single & (coefficients < 0)]])
    common = largest(np.minimum(plus, minus))
    for cycle in layout.tight_cycles:  # loops through bar contacts (Layout.tight_cycles)
        common = max(common, float(force[list(cycle)].min()))
    return common


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
    return max(largest(top), largest(bottom), balance)
