"""A chain's own certificate: error bounds in O(n) for an answer to a bar scene's model,
reading only u, the contact forces, the reactions and the model (:func:`chain_bounds`).

The answer (u, λ) is read as the exact answer of a nearby scene: the contacts that push are
held where the answer puts them (their gaps moved by as much as the answer penetrates or
stands off there), the force on every other contact, and every pulling force, is moved off it
as a load, and what equilibrium leaves over is a load too. What those moves do to the forces
and the displacements is then worked out span by span between the held nodes
(:mod:`~contactqp.check.chain.spans`, :mod:`~contactqp.check.chain.certificate`), with the
forces that move nothing counted apart (:mod:`~contactqp.check.chain.self_stress`) and what
pushing bar contacts pass on between bars (:mod:`~contactqp.check.chain.bar_contacts`).
Internally the bounds read what equilibrium leaves over cut by cut through every bar,
max |N_j + E_j| (N_j the element force from u, E_j the outside forces on the nodes before
the cut): a per-node imbalance would let n errors add up along a long bar (OSQP on a
10⁴-element bar: 8e-7 per node, 0.56 % in the contact force), and the cuts carry them.

The bounds are exact to first order within the answer's own set of pushing contacts;
property tests hold every method and solver to them against the exact reference on thousands
of random scenes (tests/test_guarantee.py, benchmarks/guarantee.py). The verdict they enter is
the one of every model (:mod:`contactqp.check`, :mod:`contactqp.check.residuals`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from contactqp.check.chain.certificate import error_bounds
from contactqp.check.chain.spans import Running
from contactqp.check.residuals import Tolerances
from contactqp.errors import OptionError
from contactqp.model import (
    Layout,
    Model,
    element_forces,
    largest,
    link_forces,
    scene_model,
)
from contactqp.scene import Scene


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


def chain_bounds(model: Model, u: np.ndarray, lam: np.ndarray, reactions: np.ndarray,
                 contact: str, tolerances: Tolerances, element_force: np.ndarray | None = None,
                 link_force: np.ndarray | None = None, penetration: np.ndarray | None = None
                 ) -> tuple[float, float]:
    """The chain's own (force, displacement) bounds of an answer (module docstring): u every
    node's displacement, one force per row, every support's reaction, all finite and of the
    model's sizes (:func:`sized`). ``element_force`` and ``link_force``: the element forces,
    and the same on the links between nodes (0 between bars), and ``penetration`` C u − g per
    row, when the caller has them."""
    layout = model.layout
    F, U = model.force_scale, model.displacement_scale
    forces = element_forces(layout, u) if element_force is None else element_force
    links = link_forces(layout, forces) if link_force is None else link_force
    nodes, external, _ = external_forces(layout, lam, reactions)
    # E_j, the outside forces on nodes 0..j, once for both (at every node where they are many)
    outside = Running.of(layout.n_nodes, nodes, external)
    r_max, links_size = section_residual_and_size(
        links, nodes, external, outside.levels if outside.steps is None else None)
    bounds = error_bounds(layout, u, lam, links, nodes, external, r_max, contact, F, U,
                          tolerances.complementarity, outside, largest(u), links_size,
                          penetration)
    return bounds.force_error_bound, bounds.displacement_error_bound


def sized(model: Model | Scene, u: Any, contact_force: Any, reactions: Any
          ) -> tuple[Model, np.ndarray, np.ndarray, np.ndarray]:
    """(the model, u, λ, the reactions) as arrays of the model's sizes (an OptionError naming
    one that is not); the reactions from statics where not given."""
    model = model if isinstance(model, Model) else scene_model(model)
    layout = model.layout
    u = np.asarray(u, dtype=float).reshape(-1)
    lam = np.asarray(contact_force, dtype=float).reshape(-1)
    _shape("u", u, layout.n_nodes)
    _shape("contact_force", lam, layout.n_contacts)
    if reactions is None:
        reactions = model.reactions_of(u, lam)
    reactions = np.asarray(reactions, dtype=float).reshape(-1)
    _shape("reactions", reactions, len(layout.scene.supports))
    return model, u, lam, reactions


def _shape(name: str, values: np.ndarray, size: int) -> None:
    if values.size != size:
        raise OptionError(f"{name} must have {size} values for this scene, got {values.size}")


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


