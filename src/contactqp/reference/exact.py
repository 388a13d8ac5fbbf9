"""**Exact rational arithmetic** (:func:`rational_reference`), for every scene (several bars,
bar-to-bar contacts, walls on both sides of a node, press fits, several supports), up to
``MAX_EXACT_NODES`` nodes. Every float of the scene converts exactly to a
:class:`fractions.Fraction` (stiffness E·A/L per element, consistent nodal loads, gaps), and
each active set A is solved exactly from its KKT system

    K u + C_Aᵀ λ_A = P,   C_A u = g_A,   u = 0 at the supports,

the minimum of ½uᵀKu − Pᵀu with the rows of A held as equalities, by Gaussian elimination on
sparse rows (K is tridiagonal per bar, a contact row has one or two entries; no element joins
consecutive bars).

For both paths A is found by the textbook loop: add every penetrated row, drop every pulling
one. The answer is returned only with its certificate: every active row pushes (λ >= 0) and no
inactive row is penetrated (exactly, on the rational path). The energy is strictly convex
where every bar has a support, so a certified A gives the unique displacements; a bar with no
support (held only by its contacts) can move as a whole, and then only the active sets whose
rows hold it can be solved (the loop starts from every row, and a set that leaves such a bar
free ends the loop: the next path takes over), and the answer is unique where the loads press
every such bar against its contacts (:func:`contactqp.model.chain.floating.unheld_bars`).

On the rational path the contact rows are the edges of a graph whose vertices are the free
nodes and GROUND (the supports): a wall joins its node to GROUND, a bar contact its two nodes.
A set of rows is linearly independent exactly when its edges form a forest, and A is kept
one: a penetrated row that closes a cycle takes the place of a row of the cycle that must
open for it (:meth:`_ExactScene.exchange`), and a row whose cycle is consistent (the second
wall of a node clamped between gaps summing to exactly 0) is never penetrated, so it stays
inactive with λ = 0: only the wall the net force pushes against carries it. The contact
forces are unique unless active rows are dependent, and then they are a basic (forest)
solution. Should the loop come back to an active set (it can cycle once bar contacts join
the walls) or run out of steps, the primal active-set method takes over, which ends in exact
arithmetic barring degenerate cycles; should ``max_steps`` cut that short too, every
independent active set is tried, the smallest first, when 2^rows · nodes² is at most
``ENUMERATION_BUDGET``. Otherwise, and when nothing certifies (only a scene whose walls leave
a node no position), a SceneError.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from itertools import combinations

import numpy as np

from contactqp.errors import SceneError
from contactqp.model.chain.numbering import layout_of
from contactqp.scene import Scene

# Exact arithmetic on a chain grows its numbers by ~53 bits per element, and a solve's cost
# with them: ~0.5 s at 400 nodes (0.07 s at 200, 2 ms at 20); a loop takes a few solves.
MAX_EXACT_NODES = 400
# The last resort tries up to 2^rows active sets, each a solve costing ~nodes²: at most
# 10 rows on 40 nodes (seconds), 4 rows at MAX_EXACT_NODES.
ENUMERATION_BUDGET = 2**10 * 40**2
GROUND = -1  # the vertex of the supports in the graph of contact rows


@dataclass(frozen=True)
class Reference:
    """The answer of either exact path (this one, and contactqp.reference's statics, which
    imports it from here: the two modules import one way). The exact contact forces of a scene (N, one per contact row, scene order: walls, then
    bar contacts), displacements (m, one per global node), the active sets solved and the
    unit round-off used (0.0 for exact rational arithmetic)."""

    contact_force: np.ndarray
    displacement: np.ndarray
    steps: int
    precision: float


def solve_exact(equations: list[dict[int, Fraction]], rhs: list[Fraction]) -> list[Fraction]:
    """x with Σ_c equations[i][c]·x[c] = rhs[i] for every i, columns 0..n−1, n equations, by
    Gaussian elimination in exact arithmetic: column by column, the pivot the shortest row
    that has the column (few entries, little fill). The rows are changed in place.

    Raises ArithmeticError when the system is singular.
    """
    n = len(equations)
    rows_with: list[set[int]] = [set() for _ in range(n)]  # column -> rows that have it
    for i, row in enumerate(equations):
        for column in row:
            rows_with[column].add(i)
    pivots = []
    for column in range(n):
        if not rows_with[column]:
            raise ArithmeticError(f"singular system: no pivot for column {column}")
        p = min(rows_with[column], key=lambda i: (len(equations[i]), i))
        pivot = equations[p]
        for c in pivot:
            rows_with[c].discard(p)
        pivots.append(p)
        for i in list(rows_with[column]):
            row = equations[i]
            factor = row.pop(column) / pivot[column]
            rows_with[column].discard(i)
            for c, value in pivot.items():
                if c == column:
                    continue
                new = row.get(c, 0) - factor * value
                if new:
                    row[c] = new
                    rows_with[c].add(i)
                elif c in row:
                    del row[c]
                    rows_with[c].discard(i)
            rhs[i] -= factor * rhs[p]
    x: list[Fraction] = [Fraction(0)] * n
    for column in reversed(range(n)):  # a pivot row holds its column and later ones only
        row = equations[pivots[column]]
        rest = sum((value * x[c] for c, value in row.items() if c != column), Fraction(0))
        x[column] = (rhs[pivots[column]] - rest) / row[column]
    return x


Answer = tuple[list[Fraction], list[Fraction]]  # (u per node, λ per row), certified


@dataclass
class _ExactScene:
    """A scene's data in exact rationals, global node numbering, and the solves so far."""

    name: str
    n_nodes: int
    held: frozenset[int]
    links: list[Fraction]  # stiffness between nodes j and j + 1 (0 at a junction)
    loads: list[Fraction]
    rows: list[tuple[tuple[int, int], ...]]  # (node, ±1) terms of each contact row
    gaps: list[Fraction]
    floating: bool = False  # some bar has no support: K alone is singular
    solves: int = 0

    @classmethod
    def of(cls, scene: Scene) -> _ExactScene:
        layout = layout_of(scene)
        rows: list[list[tuple[int, int]]] = [[] for _ in range(scene.n_contacts)]
        row_ids, nodes, values, gaps = layout.rows
        for r, node, value in zip(row_ids.tolist(), nodes.tolist(), values.tolist()):
            rows[r].append((node, int(value)))
        return cls(scene.name, layout.n_nodes, frozenset(layout.support_nodes.tolist()),
                   [Fraction(k) for k in layout.link_stiffness.tolist()],
                   [Fraction(p) for p in layout.nodal_loads.tolist()],
                   [tuple(r) for r in rows], [Fraction(g) for g in gaps.tolist()],
                   bool(layout.floating_bars.size))

    def edge(self, r: int) -> tuple[int, int]:
        """Row r as an edge (tail, head) of the graph of rows, row r = e_head − e_tail: a "+"
        wall runs from GROUND to its node, a "−" wall back, a bar contact from b to a; a
        supported node is GROUND."""
        ends = {sign: GROUND if node in self.held else node for node, sign in self.rows[r]}
        return ends.get(-1, GROUND), ends.get(1, GROUND)

    def path(self, rows: Sequence[int], start: int, end: int) -> list[tuple[int, bool]] | None:
        """The rows (each with True where it is passed tail to head) of the path from vertex
        ``start`` to ``end`` in the forest ``rows``, or None when they are not joined."""
        around: dict[int, list[tuple[int, int, bool]]] = {}
        for r in rows:
            tail, head = self.edge(r)
            around.setdefault(tail, []).append((head, r, True))
            around.setdefault(head, []).append((tail, r, False))
        came: dict[int, tuple[int, int, bool]] = {start: (start, -1, True)}
        queue = [start]
        for vertex in queue:
            for other, r, forward in around.get(vertex, ()):
                if other not in came:
                    came[other] = (vertex, r, forward)
                    queue.append(other)
        if end not in came:
            return None
        steps = []
        while end != start:
            end, r, forward = came[end]
            steps.append((r, forward))
        return steps[::-1]

    def exchange(self, kept: Sequence[int], penetrated: Sequence[int], lam: Sequence[Fraction]
                 ) -> list[int]:
        """The forest ``kept`` with every row of ``penetrated`` added. A penetrated row that
        closes a cycle replaces the least loaded row of the cycle that it relieves: row r =
        Σ ±(rows of the path from its tail to its head), + where the path passes a row tail to
        head, and with every row of the path tight, C_r u = Σ ± g > g_r, so only a + row
        opening can make room (a cycle with none is a negative cycle: an impossible scene)."""
        active = list(kept)
        for r in penetrated:
            path = self.path(active, *self.edge(r))
            relieved = [i for i, forward in path or () if forward]
            if relieved:
                active.remove(min(relieved, key=lambda i: (lam[i], i)))
            if path is None or relieved:
                active.append(r)
        return active

    def forest(self, rows: Sequence[int]) -> list[int]:
        """The rows, in order, that do not close a cycle with those before them: a maximal
        linearly independent subset."""
        parent: dict[int, int] = {}

        def root(v: int) -> int:
            while parent.get(v, v) != v:
                v = parent[v]
            return v

        kept = []
        for r in rows:
            a, b = (root(v) for v in self.edge(r))
            if a != b:
                parent[a] = b
                kept.append(r)
        return kept

    def solve(self, active: Sequence[int]) -> tuple[list[Fraction], list[Fraction]]:
        """(u per node, λ per row, 0 off ``active``) of the KKT system of the independent
        rows ``active``: K u + C_Aᵀ λ_A = P at the free nodes, C_A u = g_A."""
        self.solves += 1
        free = [j for j in range(self.n_nodes) if j not in self.held]
        # unknowns in chain order, each λ after the last node of its row: little fill
        keys = [(j, 0, 0) for j in free] + [(max(n for n, _ in self.rows[r]), 1, r)
                                            for r in active]
        column = {key: c for c, key in enumerate(sorted(keys))}
        node_column = {j: column[j, 0, 0] for j in free}
        equation_of = {j: i for i, j in enumerate(free)}
        equations: list[dict[int, Fraction]] = []
        rhs: list[Fraction] = []
        for j in free:
            row: dict[int, Fraction] = {}
            left = self.links[j - 1] if j > 0 else Fraction(0)
            right = self.links[j] if j + 1 < self.n_nodes else Fraction(0)
            if left + right:
                row[node_column[j]] = left + right
            for neighbour, k in ((j - 1, left), (j + 1, right)):
                if k and neighbour in node_column:
                    row[node_column[neighbour]] = -k
            equations.append(row)
            rhs.append(self.loads[j])
        for r in active:
            multiplier = column[max(n for n, _ in self.rows[r]), 1, r]
            constraint: dict[int, Fraction] = {}
            for node, sign in self.rows[r]:
                if node in node_column:
                    equations[equation_of[node]][multiplier] = Fraction(sign)
                    constraint[node_column[node]] = Fraction(sign)
            equations.append(constraint)
            rhs.append(self.gaps[r])
        x = solve_exact(equations, rhs)
        u = [Fraction(0)] * self.n_nodes
        for j in free:
            u[j] = x[node_column[j]]
        lam = [Fraction(0)] * len(self.rows)
        for r in active:
            lam[r] = x[column[max(n for n, _ in self.rows[r]), 1, r]]
        return u, lam

    def rows_times(self, u: list[Fraction]) -> list[Fraction]:
        """C u: each row's combination of the displacements ``u`` (m)."""
        return [sum((sign * u[node] for node, sign in terms), Fraction(0)) for terms in self.rows]

    def penetration(self, u: list[Fraction]) -> list[Fraction]:
        """C u − g per row (m): > 0 where a row is penetrated."""
        return [value - gap for value, gap in zip(self.rows_times(u), self.gaps)]

    def certified(self, u: list[Fraction], lam: list[Fraction], active: Sequence[int]) -> bool:
        """Whether (u, λ) solves the scene, exactly: every active row pushes (λ >= 0) and no
        inactive row is penetrated (u satisfies K u + Cᵀ λ = P by construction)."""
        penetration = self.penetration(u)
        return all(lam[r] >= 0 for r in active) and all(
            penetration[r] <= 0 for r in range(len(self.rows)) if r not in active)

    def feasible_point(self) -> list[Fraction]:
        """A u that satisfies every row, 0 at the supports: the rows are difference
        constraints u_head − u_tail <= g, solved by shortest paths (Bellman–Ford from a source
        joined to every vertex by a path of length 0), shifted to put GROUND at 0. Raises
        SceneError on a cycle of negative length, which leaves no u at all."""
        edges = [(*self.edge(r), gap) for r, gap in enumerate(self.gaps)]
        distance = {v: Fraction(0) for tail, head, _ in edges for v in (tail, head)}
        for _ in range(len(distance) + 1):
            changed = False
            for tail, head, gap in edges:
                if distance[tail] + gap < distance[head]:
                    distance[head], changed = distance[tail] + gap, True
            if not changed:
                break
        else:
            raise SceneError(f"scene {self.name!r}: its walls and contacts leave some node no "
                             "position (their gaps around a cycle sum below 0, in exact "
                             "arithmetic)")
        u = [Fraction(0)] * self.n_nodes
        for v, d in distance.items():
            if v != GROUND:
                u[v] = d - distance.get(GROUND, Fraction(0))
        return u


def rational_reference(scene: Scene, max_steps: int | None = None) -> Reference:
    """The solution of any scene of at most ``MAX_EXACT_NODES`` nodes, in exact rational
    arithmetic (module docstring). ``max_steps`` (default 2·rows + 10) bounds the textbook
    loop, and the primal loop after it; then every independent active set is tried when
    2^rows · nodes² is at most ``ENUMERATION_BUDGET``, else a SceneError."""
    n_nodes = layout_of(scene).n_nodes
    if n_nodes > MAX_EXACT_NODES:
        raise SceneError(f"scene {scene.name!r} has {n_nodes} nodes; the exact rational "
                         f"reference takes at most {MAX_EXACT_NODES} (one bar with walls only "
                         "takes the statics reference at any size)")
    exact = _ExactScene.of(scene)
    n_rows = len(exact.rows)
    max_steps = 2 * n_rows + 10 if max_steps is None else max_steps
    answer = _textbook_loop(exact, max_steps) or _primal_loop(exact, max_steps)
    if answer is None and 2**n_rows * n_nodes**2 > ENUMERATION_BUDGET:
        raise SceneError(f"scene {scene.name!r}: the exact reference found no certified answer "
                         f"in {exact.solves} steps, and its {n_rows} contact rows on "
                         f"{n_nodes} nodes are too many to try every active set "
                         f"(2^rows · nodes² = {2**n_rows * n_nodes**2:.3g} > "
                         f"{ENUMERATION_BUDGET:.3g}; e.g. 10 rows on 40 nodes)")
    answer = answer or _enumeration(exact)
    if answer is None:
        raise SceneError(f"scene {scene.name!r}: no active set of its {n_rows} contact rows "
                         "satisfies the contact conditions exactly; its walls and contacts may "
                         "leave some node no position")
    u, lam = answer
    # float(Fraction) rounds correctly: each value is the nearest double to the exact one
    return Reference(np.array([float(x) for x in lam], dtype=float),
                     np.array([float(x) for x in u], dtype=float), exact.solves, 0.0)


def _textbook_loop(exact: _ExactScene, max_steps: int) -> Answer | None:
    """Add every penetrated row, drop every pulling one (module docstring); None when an
    active set comes back (the loop would cycle) or after ``max_steps`` solves."""
    tried: set[frozenset[int]] = set()
    # a bar with no support needs rows that hold it before K is invertible: start from all
    active: list[int] = exact.forest(range(len(exact.rows))) if exact.floating else []
    for _ in range(max_steps):
        if frozenset(active) in tried:
            return None
        tried.add(frozenset(active))
        try:
            u, lam = exact.solve(active)
        except ArithmeticError:  # the set leaves a bar with no support free to move
            return None
        if exact.certified(u, lam, active):
            return u, lam
        penetration = exact.penetration(u)
        penetrated = [r for r in range(len(exact.rows)) if r not in active and penetration[r] > 0]
        active = exact.exchange([r for r in active if lam[r] >= 0], penetrated, lam)
    return None


def _primal_loop(exact: _ExactScene, max_steps: int) -> Answer | None:
    """The primal active-set method (Nocedal & Wright, Numerical Optimization, algorithm
    16.3): from a feasible u (:meth:`_ExactScene.feasible_point`) and its tight rows as the
    working set (a forest of them), step towards the minimum with the working rows held as
    equalities, stopping at the first row in the way, which joins the set (it is
    independent of the set: the step moves along it, not along theirs); at the minimum,
    drop the most pulling row, or stop certified. Every step keeps u feasible and lowers the
    energy or adds a row, so in exact arithmetic it ends, barring degenerate cycles that
    ``max_steps`` solves cut short (None)."""
    u = exact.feasible_point()
    n_rows = len(exact.rows)
    working = exact.forest([r for r, p in enumerate(exact.penetration(u)) if p == 0])
    for _ in range(max_steps):
        try:
            target, lam = exact.solve(working)
        except ArithmeticError:  # the set leaves a bar with no support free to move
            return None
        direction = [t - x for t, x in zip(target, u)]
        if any(direction):
            slack = [-p for p in exact.penetration(u)]  # g − C u >= 0
            along = exact.rows_times(direction)
            step, blocking = Fraction(1), None
            for r in range(n_rows):
                if r not in working and along[r] > 0 and slack[r] < step * along[r]:
                    step, blocking = slack[r] / along[r], r
            u = [x + step * d for x, d in zip(u, direction)]
            if blocking is not None:
                working.append(blocking)
                continue
        pulling = [r for r in working if lam[r] < 0]
        if not pulling:
            return (u, lam) if exact.certified(u, lam, working) else None
        working.remove(min(pulling, key=lambda r: (lam[r], r)))
    return None


def _enumeration(exact: _ExactScene) -> Answer | None:
    """Every independent active set, the smallest first; the first certified one."""
    n_rows = len(exact.rows)
    for size in range(n_rows + 1):
        for subset in combinations(range(n_rows), size):
            if len(exact.forest(subset)) == size:
                try:
                    u, lam = exact.solve(subset)
                except ArithmeticError:  # a bar with no support is free to move
                    continue
                if exact.certified(u, lam, subset):
                    return u, lam
    return None
