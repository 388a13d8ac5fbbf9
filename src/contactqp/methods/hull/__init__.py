"""The active set of walls on a chain, by convex hulls: steps that do not grow with the mesh.

For a scene whose contacts are walls alone (any number of bars, supports and walls, on either
side of a node), the saddle-point system with a set of walls held is solved by statics in one
O(n) pass: with w = u_free − u (u_free = K⁻¹P, the bar with no contact), w is 0 at the
supports, equal to u_free − gap at a held wall, linear in the compliance φ = Σ L/(EA) between
held nodes and flat beyond the last one towards a free end (no force passes it). A held
wall's force is the kink of w there. The same equations as the textbook loop
(:mod:`contactqp.methods.lagrange`), a different way to choose the active set:

- a wall that pulls is released, as in the textbook loop;
- in each stretch of free nodes (between two held nodes, or a held node and a free end) where
  a node passes a wall, the walls added are the vertices of the greatest convex minorant of
  that stretch's signed gaps against φ: the held set that makes the stretch feasible with
  forces of the right sign at once, if its ends stay where they are. The minorant is an
  isotonic regression of the slopes, found as a lower hull (:mod:`contactqp.methods.hull.minorant`);
  a free end clips its slopes (no force beyond the last contact);
- the stretch is then settled within the same step: between its held nodes (old and new) u
  follows from statics alone, so where it now passes the other side's walls, that side's
  hull walls are added in each such sub-stretch, and so on until nothing in the stretch is
  passed. The set the loop ends with is the same as when each step settled one side, but
  for walls that touch with no force (held or not, either is exact).

The textbook loop adds every passed wall, so its active set crosses a contact patch a few
nodes per step (steps grow with the mesh); the hull adds a patch's walls in one step. Measured
on the builders' obstacle, channel and flat patch: 2 steps at every size from 10³ to 10⁶
walls (``benchmarks/run.py --cases contacts``; the channel took 6-7 when a step settled one
side). A set that comes back or more than ``max_iterations`` steps hands over to the
textbook loop from the set reached (reported in the Solution's info).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from contactqp.methods._active_set import DECISION_RTOL, default_max_iterations
from contactqp.methods.base import Solution
from contactqp.methods.hull.minorant import minorant_vertices
from contactqp.methods.hull.segments import Stretch, displacements
from contactqp.model import (
    Condensed,
    Model,
    largest,
    run_ends,
    run_starts,
    segment_reduce,
)


def applies(model: object, contact: str) -> bool:
    """The hull loop solves unilateral walls on the full formulation's chain (no bar
    contacts: a bar contact couples two chains)."""
    return (isinstance(model, Model) and contact == "inequality" and not model.scene.contacts
            and model.n_contacts > 0 and not model.floating)


class WallsOnChain:
    """The arrays of a walls-only scene along its global node numbering (module docstring)."""

    def __init__(self, model: Model, load_factor: float = 1.0) -> None:
        layout = model.layout
        self.model = model
        self.phi = layout.chained_compliance  # φ along the whole chain, increasing
        self.bar = layout.node_bar
        self.bars = len(model.scene.bars)
        self.support = layout.support_mask
        # scaled only when a condensed model scales its loads (a copy of each otherwise)
        scaled = (lambda a: a) if load_factor == 1.0 else (lambda a: load_factor * a)
        self.u_free = scaled(model.free_displacement_of_nodes)
        self.link_compliance = layout.link_compliance  # 1/k per link, inf across a junction
        # per side: the wall's gap and its row at each node (Layout.walls_by_side)
        self.bound = {side: bound for side, (bound, _) in layout.walls_by_side.items()}
        self.owner = {side: owner for side, (_, owner) in layout.walls_by_side.items()}
        # ... and the nodes that have a wall on each side, sorted: the steps read the chain
        # there only (one wall on 10⁶ nodes: no pass over the chain per side and step)
        self.wall_nodes = layout.wall_nodes_by_side
        self._wall_gaps: dict[int, np.ndarray] = {}
        self.n, self.n_rows = layout.n_nodes, model.n_contacts
        self.loads = P = scaled(layout.nodal_loads)
        self.running_load = scaled(layout.running_load)  # S_j = Σ_(i<=j) P_i
        self.compliance_load = scaled(layout.compliance_load)  # c_j S_j per link
        # the sides that have walls: a side without one is never passed
        self.sides = tuple(side for side in (1, -1) if self.wall_nodes[side].size)
        self.bar_first, self.bar_last = layout.bar_ends  # each node's bar's first and last
        # ‖P‖∞ and K's stiffest entry once per scene (each a pass over the chain)
        self.force_tolerance_base = layout.load_size if load_factor == 1.0 else largest(P)
        self.displacement_floor = max(largest(model.g),
                                      self.force_tolerance_base / model.stiffest)

    def statics(self, held: dict[int, np.ndarray]) -> tuple[np.ndarray, np.ndarray,
                                                           np.ndarray, np.ndarray]:
        """u with the walls ``held`` (side -> mask) at their gaps; returns (u, held node
        numbers in order, the force of each held node's wall (N, >= 0 when it pushes), the
        mask of the held nodes and supports). With no wall held the forces are left 0: only
        the supports' would be found, and a support's force is never read (it may pull)."""
        pinned = self.support | held[1] | held[-1]
        nodes = np.flatnonzero(pinned)
        plus, minus = held[1][nodes], held[-1][nodes]  # the held nodes' walls, not the chain's
        target = np.zeros(nodes.size)
        target[plus] = self.bound[1][nodes[plus]]
        target[minus] = -self.bound[-1][nodes[minus]]
        w_held = self.u_free[nodes]
        w_held -= target
        if self.bars > 1:  # each bar's first and last held node
            bar = self.bar[nodes]
            first, last = run_starts(bar), run_ends(bar)
        else:
            first, last = np.zeros(nodes.size, dtype=bool), np.zeros(nodes.size, dtype=bool)
            first[0] = last[-1] = True
        if w_held.any():
            u = self.displacements(pinned, nodes, w_held)
            u[nodes] = target  # exactly, not u_free − (u_free − target)
        else:  # the supports alone (the first step): u is u_free, read, not copied
            u = self.u_free
        if not (plus.any() or minus.any()):  # no wall held: no pass for the supports' forces
            return u, nodes, np.zeros(nodes.size), pinned
        # the forces by statics from the loads, never from differences of displacements
        # (a wall in a patch carries its node's load, q·h, while the displacements and the
        # element forces beside it are 10⁶ times larger; measured: slopes of w left 8e-5 of
        # the largest force at 10⁶ contacts). Between held neighbours a < b, elements a..b−1
        # carry N_e = N_a − (S_e − S_a), S the running sum of the nodal loads, and
        # Σ c_e N_e = u_b − u_a gives N_a; towards a free end N is the load beyond the cut.
        S = self.running_load
        c = self.link_compliance
        sum_c = segment_reduce(np.add, c, nodes)[:-1]
        sum_cS = segment_reduce(np.add, self.compliance_load, nodes)[:-1]
        S_a, S_before_b = S[nodes[:-1]], S[nodes[1:] - 1]
        # N_a = (target_b − target_a + Σ c S − S_a Σ c) / Σ c, in place (no array per term)
        right = np.empty(nodes.size)
        N_a = np.subtract(target[1:], target[:-1], out=right[:-1])
        with np.errstate(divide="ignore", invalid="ignore"):  # inf and NaN across a junction
            N_a += sum_cS
            N_a -= np.multiply(S_a, sum_c, out=sum_cS)
            N_a /= sum_c
        right[-1] = 0.0
        # the element forces just right and just left of every held node
        left = np.empty(nodes.size)
        left[0] = 0.0
        np.subtract(N_a, np.subtract(S_before_b, S_a, out=S_before_b), out=left[1:])
        head, tail = self.head_load(nodes[first]), self.tail_load(nodes[last])
        left[first] = head  # − the loads from the bar's start up to the element before
        right[last] = tail  # the loads beyond the node
        reaction = np.subtract(left, right, out=left)
        reaction -= self.loads[nodes]
        # a + wall pushes in -x (its force is −R), a - wall in +x
        force = np.negative(reaction, out=reaction, where=plus)
        return u, nodes, force, pinned

    def displacements(self, pinned: np.ndarray, nodes: np.ndarray, w_held: np.ndarray
                      ) -> np.ndarray:
        """u = u_free − w, w spread from ``w_held`` at the held ``nodes`` (the mask
        ``pinned``): :func:`contactqp.methods.hull.segments.displacements`."""
        return displacements(self.model.layout, self.u_free, pinned, nodes, w_held)

    def head_load(self, nodes: np.ndarray) -> np.ndarray:
        """The force in the element just left of each of ``nodes``, the first held node of its
        bar: minus the loads from the bar's start to the node before (0 at the bar's start)."""
        S, start = self.running_load, self.bar_first[nodes]
        before = np.where(start > 0, S[np.maximum(start - 1, 0)], 0.0)
        return np.where(nodes > start, -(S[np.maximum(nodes - 1, 0)] - before), 0.0)

    def tail_load(self, nodes: np.ndarray) -> np.ndarray:
        """The force in the element just right of each of ``nodes``, the last held node of its
        bar: the loads beyond it to the bar's end (0 at the bar's end)."""
        S = self.running_load
        return S[self.bar_last[nodes]] - S[nodes]

    def passed(self, side: int, u: np.ndarray, pinned: np.ndarray, tolerance: float
               ) -> np.ndarray:
        """The nodes (sorted) not held whose wall on ``side`` ``u`` passes by more than
        ``tolerance``."""
        nodes = self.wall_nodes[side]
        first = int(nodes[0])
        if nodes[-1] - first + 1 == nodes.size:  # one run of nodes (a wall at every node)
            at = slice(first, first + nodes.size)
            gap = (np.subtract if side > 0 else np.add)(self.wall_gap(side), u[at])
            gap = gap < -tolerance
            gap &= ~pinned[at]
            return np.flatnonzero(gap) + first
        gap = u[nodes]  # then the signed gap, bound − side·u, in its place
        gap = (np.subtract if side > 0 else np.add)(self.wall_gap(side), gap, out=gap)
        return nodes[(gap < -tolerance) & ~pinned[nodes]]

    def wall_gap(self, side: int) -> np.ndarray:
        """The gap of each wall on ``side``, in the order of :attr:`wall_nodes` (made on the
        first step that reads it)."""
        gaps = self._wall_gaps.get(side)
        if gaps is None:
            gaps = self._wall_gaps[side] = self.bound[side][self.wall_nodes[side]]
        return gaps

    def add_hull_walls(self, side: int, u: np.ndarray, held_nodes: np.ndarray,
                       passed: np.ndarray, tolerance: float) -> dict[int, list[np.ndarray]]:
        """The walls to add, per side: on ``side``, the vertices of each passed stretch's
        greatest convex minorant of its signed gaps (module docstring); ``held_nodes``: the
        held nodes and supports, ``passed``: the passed nodes, both sorted. Within each
        stretch the new walls are then settled at once (:meth:`settle`), which may add walls
        on the other side too."""
        bound, walled = self.bound[side], self.wall_nodes[side]
        adding: dict[int, list[np.ndarray]] = {1: [], -1: []}
        # each passed node's stretch, from the held nodes either side of it in its bar (by
        # bisection: no pass over the chain), else its bar's ends; every bar has a support
        after = np.searchsorted(held_nodes, passed)  # the first held node after each
        first = run_starts(after)  # the first passed node of each stretch
        if self.bars > 1:
            first |= run_starts(self.bar[passed])
        passed, after = passed[first], after[first]
        start, stop = self.bar_first[passed], self.bar_last[passed] + 1
        before = held_nodes[np.maximum(after - 1, 0)]
        anchored_left = (after > 0) & (before >= start)
        after = held_nodes[np.minimum(after, held_nodes.size - 1)]
        anchored_right = (after > passed) & (after < stop)
        for a, b, held_left, held_right in zip(np.where(anchored_left, before, start).tolist(),
                                               np.where(anchored_right, after, stop).tolist(),
                                               anchored_left.tolist(), anchored_right.tolist()):
            # nodes a..b-1 share the stretch; a is held (the left anchor) or a bar's start
            left = a if held_left else None
            right = b if held_right else None
            inner = a + 1 if left is not None else a
            nodes = walled[np.searchsorted(walled, inner): np.searchsorted(walled, b)]
            chosen = self.stretch_walls(side, nodes, bound[nodes] - side * u[nodes], left,
                                        right, tolerance)
            adding[side].append(chosen)
            ends = Stretch(inner, b, left, right,
                           None if left is None else self.u_free[left] - u[left],
                           None if right is None else self.u_free[right] - u[right])
            self.settle(side, chosen, ends, tolerance, adding)
        return adding

    def stretch_walls(self, side: int, nodes: np.ndarray, gaps: np.ndarray, left: int | None,
                      right: int | None, tolerance: float, phi: np.ndarray | None = None
                      ) -> np.ndarray:
        """The walls on ``side`` to add in one stretch: the vertices of the greatest convex
        minorant of the signed ``gaps`` (< 0 where passed) at its walled ``nodes`` (``phi``:
        φ there, if known), the held ends ``left`` and ``right`` (None: a free end) at 0,
        that are passed."""
        if nodes.size == 1:  # one wall in the stretch: the minorant's only vertex
            return nodes[gaps < -tolerance]
        first = int(left is not None)  # the points: the held ends, each array made once
        size = nodes.size + first + int(right is not None)
        x, y = np.empty(size), np.empty(size)
        inner = slice(first, first + nodes.size)
        if phi is None:
            np.take(self.phi, nodes, out=x[inner], mode="clip")
        else:
            x[inner] = phi
        y[inner] = gaps
        if left is not None:
            x[0], y[0] = self.phi[left], 0.0
        if right is not None:
            x[-1], y[-1] = self.phi[right], 0.0
        clip = 0 if left is not None and right is not None else (-1 if left is not None else 1)
        vertices = minorant_vertices(x, y, clip)
        vertices -= int(left is not None)
        vertices = vertices[(vertices >= 0) & (vertices < nodes.size)]
        return nodes[vertices[gaps[vertices] < -tolerance]]

    def passed_between(self, side: int, chosen: np.ndarray, ends: Stretch,
                       w_chosen: np.ndarray, tolerance: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[tuple[int, int, int]]]:
        """Where the walls on ``side`` in the stretch ``ends`` are passed once the nodes
        ``chosen`` (sorted, w = ``w_chosen`` there) are held too: (the stretch's walled nodes
        not chosen, φ and the signed gap at each, and (k, a, b) for each sub-stretch k between
        chosen k − 1 and k with a passed wall, its nodes ``nodes[a:b]``)."""
        walled = self.wall_nodes[side]
        nodes = walled[np.searchsorted(walled, ends.first): np.searchsorted(walled, ends.stop)]
        anchors, w = ends.anchors(chosen, w_chosen)
        every = nodes.size == ends.stop - ends.first  # a wall at every node: read in place
        if every:  # the chosen nodes' gaps are worked out too, and set aside below
            at = slice(ends.first, ends.stop)
            phi, u_free, bound = self.phi[at], self.u_free[at], self.bound[side][at]
        else:
            chosen_here = np.zeros(ends.stop - ends.first, dtype=bool)
            chosen_here[chosen - ends.first] = True
            free = ~chosen_here[nodes - ends.first]
            nodes = nodes[free]
            phi, u_free, bound = self.phi[nodes], self.u_free[nodes], self.bound[side][nodes]
        gaps = np.interp(phi, self.phi[anchors], w)  # w, then u, then the signed gap
        np.subtract(u_free, gaps, out=gaps)
        (np.subtract if side > 0 else np.add)(bound, gaps, out=gaps)
        passed = gaps < -tolerance
        if every:
            passed[chosen - ends.first] = False
        if not passed.any():
            return nodes, phi, gaps, []
        # each passed node's sub-stretch: how many chosen nodes lie before it
        parts = np.searchsorted(chosen, nodes[passed])
        parts = parts[run_starts(parts)].tolist()
        if every:  # sub-stretch k: the nodes strictly between chosen k − 1 and k
            spans = [(k, 0 if k == 0 else int(chosen[k - 1]) + 1 - ends.first,
                      nodes.size if k == chosen.size else int(chosen[k]) - ends.first)
                     for k in parts]
        else:  # the nodes are in order: each sub-stretch's are one slice of them
            spans = [(k, int(np.searchsorted(nodes, chosen[k - 1])) if k else 0,
                      int(np.searchsorted(nodes, chosen[k])) if k < chosen.size
                      else nodes.size) for k in parts]
        return nodes, phi, gaps, spans

    def settle(self, side: int, chosen: np.ndarray, ends: Stretch, tolerance: float,
               adding: dict[int, list[np.ndarray]]) -> None:
        """Add to ``adding`` the walls that the stretch ``ends`` needs once the walls
        ``chosen`` on ``side`` hold: the stretch's displacements between its held nodes follow
        from statics alone (linear in φ, module docstring), so where they now pass the other
        side's walls, that side's hull walls are added in each sub-stretch between held
        nodes, and so on, side after side, until nothing in the stretch is passed. A step
        then settles a stretch that the steps would otherwise settle one side at a time."""
        work = [(side, chosen, ends)]
        for _ in range(MAX_SETTLING):
            if not work:
                return
            side, chosen, ends = work.pop()
            other = -side
            if not chosen.size or other not in self.sides:
                continue
            w_chosen = self.u_free[chosen] - side * self.bound[side][chosen]
            nodes, phi, gaps, spans = self.passed_between(other, chosen, ends, w_chosen,
                                                          tolerance)
            for k, a, b in spans:
                sub = ends.between(chosen, k, w_chosen)
                found = self.stretch_walls(other, nodes[a:b], gaps[a:b], sub.left, sub.right,
                                           tolerance, phi[a:b])
                adding[other].append(found)
                work.append((other, found, sub))


MAX_SETTLING = 4096  # sub-stretches settled at most per stretch and step (the steps go on)


def solve_on_chain(model: Model | Condensed, contact: str, max_iterations: int | None = None
                   ) -> tuple[Solution | None, np.ndarray] | None:
    """:func:`solve_hull` on ``model``'s chain (a condensed model's full one, its loads as the
    condensed model scales them), or None where the hull does not apply (:func:`applies`).
    The Solution, if one is found, is in ``model``'s unknowns."""
    chain = model.full if isinstance(model, Condensed) else model
    if not applies(chain, contact):
        return None
    factor = model.load_factor if isinstance(model, Condensed) else 1.0
    solution, reached = solve_hull(chain, max_iterations=max_iterations, load_factor=factor)
    if solution is not None and chain is not model:  # the condensed unknowns: contact nodes' u
        solution = replace(solution, u_free=solution.u_free[model.nodes], u_nodes=None)
    return solution, reached


def solve_hull(model: Model, *, max_iterations: int | None = None, load_factor: float = 1.0
               ) -> tuple[Solution | None, np.ndarray]:
    """The hull loop (module docstring) on ``model`` with its loads times ``load_factor``.
    Returns (the Solution, an empty array) or, when the set cycles or the steps run out,
    (None, the active rows reached) for the textbook loop to finish from."""
    chain = WallsOnChain(model, load_factor)
    held = {1: np.zeros(chain.n, dtype=bool), -1: np.zeros(chain.n, dtype=bool)}
    limit = default_max_iterations(chain.n_rows) if max_iterations is None else max_iterations
    seen: set[bytes] = set()
    for step in range(1, limit + 1):
        u, nodes, force, pinned = chain.statics(held)
        scale = max(chain.force_tolerance_base, largest(force))
        force_tol = DECISION_RTOL * scale
        disp_tol = DECISION_RTOL * max(largest(u), chain.displacement_floor)
        pulling = nodes[(force < -force_tol) & ~chain.support[nodes]]  # a support may pull
        passed = {side: chain.passed(side, u, pinned, disp_tol) for side in chain.sides}
        if not pulling.size and not any(p.size for p in passed.values()):
            return _solution(chain, u, nodes, force, held, step), np.zeros(0)
        key = np.packbits(held[1]).tobytes() + np.packbits(held[-1]).tobytes()
        if key in seen:
            break
        seen.add(key)
        for side in (1, -1):
            held[side][pulling] = False
        for side, stretch in passed.items():
            if stretch.size:
                for held_side, found in chain.add_hull_walls(side, u, nodes, stretch,
                                                             disp_tol).items():
                    for new in found:
                        held[held_side][new] = True
        held[-1] &= ~held[1]
    active = np.zeros(chain.n_rows, dtype=bool)
    for side in (1, -1):
        active[chain.owner[side][held[side]]] = True
    return None, active


def _solution(chain: WallsOnChain, u: np.ndarray, nodes: np.ndarray, force: np.ndarray,
              held: dict[int, np.ndarray], steps: int) -> Solution:
    contact_force = np.zeros(chain.n_rows)
    for side in (1, -1):
        mine = held[side][nodes]
        contact_force[chain.owner[side][nodes[mine]]] = force[mine]
    free = chain.model.free
    if not (free.size and free[-1] - free[0] + 1 == free.size):
        return Solution(u[free], contact_force, solver="lagrange", iterations=steps,
                        info={"active_set": "hull"})
    # the free nodes are one range: u over every node is the Solution's, as a Result has it
    u = u.copy() if u is chain.u_free else u  # no wall held: its own copy
    u[chain.model.layout.support_nodes] = 0.0  # outside that range
    return Solution(u[free[0]: free[-1] + 1], contact_force, solver="lagrange",
                    iterations=steps, info={"active_set": "hull"}, u_nodes=u)
