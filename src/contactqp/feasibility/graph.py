"""Whether a scene's supports, walls and bar contacts leave its nodes a position, and whether
rigid contact determines the contact forces: the constraint graph of the scene.

Supports (u = 0), walls (u <= g, −u <= g) and bar contacts (u_a − u_b <= g) are difference
constraints. Written as a graph (an edge w → v of weight c for each x_v − x_w <= c, the
supports merged into one zero node), they leave the nodes a position exactly when no cycle has
negative total weight (Bellman–Ford, whose cycle names the constraints that conflict); a loop
whose gaps add up to zero can hold with all its rows at once, and then the rows alone do not
tell how a force splits among them.
"""

from __future__ import annotations

import bisect
from typing import Any

import numpy as np

Scene = Any  # a contactqp.Scene: read here (its walls, contacts, supports), never imported


def _offsets(scene: Scene) -> list[int]:
    """Global number of each bar's node 0, and the node count last (once per call: a scene of
    10⁴ bars took 107 s to check when every node number summed the bars again)."""
    return np.concatenate(([0], np.cumsum([b.n_nodes for b in scene.bars]))).tolist()


def constraint_graph(scene: Scene) -> list[tuple[int, int, float, int, str]]:
    """The scene's walls and bar contacts as difference constraints x_v − x_w <= c, each an
    edge (w, v, c, contact row, what it says); vertex −1 is zero displacement, where the
    supports are merged."""
    unit = scene.unit.length
    offsets = _offsets(scene)
    supports = {offsets[s.bar] + s.node for s in scene.supports}

    def vertex(node: int) -> int:
        return -1 if node in supports else node

    edges = [_wall_edge(scene, i, offsets) for i in range(len(scene.walls))]
    for i, c in enumerate(scene.contacts):
        a, b = offsets[c.bar_a] + c.node_a, offsets[c.bar_b] + c.node_b
        edges.append((vertex(b), vertex(a), c.gap, len(scene.walls) + i,
                      (f"contact[{i}] (u at {_where(scene, a, offsets)} − u at "
                       f"{_where(scene, b, offsets)} ≤ "
                      f"{c.gap:.6g} {unit})")))
    return edges


def _wall_edge(scene: Scene, i: int, offsets: list[int]) -> tuple[int, int, float, int, str]:
    """Wall i as an edge of :func:`constraint_graph`."""
    wall, unit = scene.walls[i], scene.unit.length
    node = offsets[wall.bar] + wall.node
    where = _where(scene, node, offsets)
    if wall.side == "+":
        return (-1, node, wall.gap, i, f"wall[{i}] (u ≤ {wall.gap:.6g} {unit} at {where})")
    return (node, -1, wall.gap, i, f"wall[{i}] (u ≥ {0.0 - wall.gap:.6g} {unit} at {where})")


def _wall_arrays(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray, int] | None:
    """(global node, + side, gap) of every wall and the node count, or None where two walls
    hold one node from one side (the edge-by-edge path then speaks for them)."""
    offsets = _offsets(scene)
    walls = scene.walls
    node = np.array([offsets[w.bar] + w.node for w in walls], dtype=np.intp)
    plus = np.array([w.side == "+" for w in walls], dtype=bool)
    gap = np.array([w.gap for w in walls], dtype=float)
    key = 2 * node + plus
    if np.unique(key).size < key.size:
        return None
    return node, plus, gap, offsets[-1]


def _two_walls_conflict(scene: Scene) -> str | None:
    """:func:`impossible_constraints` of a scene with walls alone, in numpy: the first node
    (in the order of its first wall) whose two walls' gaps sum below 0; the messages made for
    that node only (a batch of 10⁴ cases made 10⁴ walls' messages to find none). None where
    two walls hold one node from one side."""
    arrays = _wall_arrays(scene)
    if arrays is None:
        return None
    node, plus, gap, n_nodes = arrays
    upper, lower = np.full(n_nodes, np.inf), np.full(n_nodes, np.inf)
    upper[node[plus]], lower[node[~plus]] = gap[plus], gap[~plus]
    bad = upper[node] + lower[node] < 0.0  # per wall: its node has no position
    if not bad.any():
        return ""
    first = int(np.flatnonzero(bad)[0])  # the node's first wall comes first among them
    offsets = _offsets(scene)
    texts = {1 if plus[i] else -1: _wall_edge(scene, i, offsets)[4]
             for i in np.flatnonzero(node == node[first]).tolist()}
    return (f"{texts[1]} and {texts[-1]} leave {_where(scene, int(node[first]))} no position "
            "(the gaps of its two walls sum below 0)")


def _where(scene: Scene, node: int, offsets: list[int] | None = None) -> str:
    offsets = _offsets(scene) if offsets is None else offsets
    bar = bisect.bisect_right(offsets, node) - 1
    local = node - offsets[bar]
    return f"node {local}" if len(scene.bars) == 1 else f"bar {bar} node {local}"


def _contact_subgraph(scene: Scene, edges: list) -> list:
    """The edges between bar-contact nodes and zero: the only ones on cycles longer than a
    node's own two walls."""
    ends = {v for edge in edges[len(scene.walls):] for v in edge[:2]} | {-1}
    return [edge for edge in edges if edge[0] in ends and edge[1] in ends]


def impossible_constraints(scene: Scene) -> str:
    """Why no displacement satisfies the scene's supports, walls and bar contacts together,
    or "" when one does.

    They are difference constraints (:func:`constraint_graph`). Such a system has a solution
    exactly when its constraint graph has no cycle of negative total weight (Bellman–Ford);
    the cycle names the constraints that conflict. Only the nodes of bar contacts can lie on
    a longer cycle: any other walled node is checked on its own (its two walls' gaps must not
    sum below 0).
    """
    if not scene.contacts:
        quick = _two_walls_conflict(scene)
        if quick is not None:
            return quick
    unit = scene.unit.length
    edges = constraint_graph(scene)
    contact_nodes = {v for edge in edges[len(scene.walls):] for v in edge[:2]}
    sides: dict[int, dict[int, tuple[float, str]]] = {}
    for start, end, weight, _, text in edges[: len(scene.walls)]:
        node = end if start == -1 else start
        sides.setdefault(node, {})[1 if start == -1 else -1] = (weight, text)
    for node, pair in sides.items():
        if len(pair) == 2 and pair[1][0] + pair[-1][0] < 0.0 and node not in contact_nodes:
            return (f"{pair[1][1]} and {pair[-1][1]} leave {_where(scene, node)} no position "
                    "(the gaps of its two walls sum below 0)")
    if not scene.contacts:
        return ""
    _, cycle = shortest_paths(_contact_subgraph(scene, edges))
    if not cycle:
        return ""
    total = sum(edge[2] for edge in cycle)
    return (f"{', '.join(edge[4] for edge in cycle)} leave no position for the nodes they "
            f"hold (together they need 0 ≤ {total:.6g} {unit})")


def indeterminate_contacts(scene: Scene) -> str:
    """Why the scene's contact forces would not be determined, or "" when they are.

    Rows that tie nodes along a loop whose gaps add up exactly (the walls and bar contacts of
    a loop, walked one way or the other) can all hold at once, and then a force can go round
    the loop: the rows cannot tell how it splits. Where the loop runs one way (the two walls of
    a clamped node, gaps summing to 0) the force all the way round is the common part, and the
    exact answer is the one without it (contactqp.result). Where the loop has rows facing both
    ways (a node held at the same position by a wall and, through a bar contact, by a wall of
    another bar), the split is arbitrary: such a scene is refused, with the rows on the loop.
    Found with a spanning forest of the ties, smallest gaps first: a tie between two nodes
    already in one tree closes a loop, which adds up when the tie's gap equals the difference
    the tree's path gives (loops of zero gaps are always found; a loop whose nonzero gaps add
    up is found when the forest holds the rest of it)."""
    if not scene.contacts and _wall_arrays(scene) is not None:
        return ""  # walls alone, each node held from each side once: no two rows in parallel
    all_edges = constraint_graph(scene)
    parallel = _parallel(all_edges)
    if parallel:
        return parallel
    if not scene.contacts:
        return ""
    edges = _contact_subgraph(scene, all_edges)
    tree: dict[int, list[tuple[int, float, int, str]]] = {}  # node -> (next, x_next − x, edge)
    parent: dict[int, int] = {}

    def root(node: int) -> int:
        while parent.setdefault(node, node) != node:
            node = parent[node]
        return node

    scale = max((abs(edge[2]) for edge in edges), default=0.0)
    # the smallest gaps first: loops of zero gaps (the common way for rows to add up) are then
    # closed within the forest of zero gaps, whatever other ties join the same nodes
    for index in sorted(range(len(edges)), key=lambda i: abs(edges[i][2])):
        a, b, weight = edges[index][:3]
        if root(a) != root(b):
            parent[root(a)] = root(b)
            tree.setdefault(a, []).append((b, 1, index))  # a → b follows the edge
            tree.setdefault(b, []).append((a, -1, index))
            continue
        path = _tree_path(tree, a, b)  # [(edge index, +1 along it / −1 against)]
        if abs(sum(sign * edges[i][2] for i, sign in path) - weight) > 1e-12 * scale:
            continue  # the loop's gaps do not add up: its rows never all hold at once
        if all(sign < 0 for _, sign in path):
            continue  # b → a along the path, then the edge a → b: one way round
        return _held_twice([edges[i][4] for i in [index] + [i for i, _ in path]])
    return _overlapping_loops(scene, edges)


def _held_twice(names: list[str]) -> str:
    return (f"{', '.join(names)} hold their nodes at one position in more than one way, with "
            "no gap to spare: the contact forces along that loop are not determined by rigid "
            "contact (give one of them a gap, or hold the node by a support)")


def _overlapping_loops(scene: Scene, edges: list) -> str:
    """Two one-way loops of zero total gap that share a row: each closes in the forest one way
    round, but the two together are a loop with rows facing both ways (the rows of one loop
    and not the other), along which a force goes round while the shared row stays free, so
    that the rule "one row of each loop carries none of it" leaves the split open (measured:
    a wall, a bar contact to a supported end and one to a walled node, all at zero gap;
    the penalty and the reference split 5.3e5 N differently, the same on every node)."""
    text = {edge[3]: edge[4] for edge in edges}
    loops = tight_cycles(scene)
    for i, first in enumerate(loops):
        for second in loops[i + 1:]:
            if set(first) & set(second):
                rows = sorted(set(first) ^ set(second))
                return _held_twice([text[row] for row in rows])
    return ""


def _parallel(edges: list) -> str:
    """Two rows that hold the same node (or pair of nodes) from the same side at the same gap:
    a loop of two rows facing both ways, which the spanning forest misses when each closes a
    one-way loop with a third row (two bar contacts from supported ends, and a wall on the
    other side of their node: random scene, seed 8). Their forces split arbitrarily."""
    seen: dict[tuple[int, int], tuple[float, str]] = {}
    scale = max((abs(edge[2]) for edge in edges), default=0.0)
    for start, end, gap, _, text in edges:
        other = seen.get((start, end))
        if other is not None and abs(other[0] - gap) <= 1e-12 * scale:
            return (f"{other[1]} and {text} hold the same node from the same side at the same "
                    "gap: how their force splits is not determined (keep one of them)")
        if other is None or gap < other[0]:
            seen[(start, end)] = (gap, text)
    return ""


def _tree_path(tree: dict, start: int, goal: int) -> list[tuple[int, int]]:
    """The edges of the forest ``tree`` from ``start`` to ``goal``, each with +1 where the path
    follows the edge's direction and −1 where it goes against it."""
    came: dict[int, tuple[int, int, int] | None] = {start: None}
    queue = [start]
    for node in queue:
        for following, sign, index in tree.get(node, []):
            if following not in came:
                came[following] = (node, sign, index)
                queue.append(following)
    path, node = [], goal
    while came[node] is not None:
        before, sign, index = came[node]
        path.append((index, sign))
        node = before
    return path[::-1]


def tight_cycles(scene: Scene) -> tuple[tuple[int, ...], ...]:
    """The contact rows of every cycle of zero total weight through a bar contact: rows that
    can all hold at once and then fix their nodes twice, so that the rows alone cannot tell
    how a force splits among them (a common force around the cycle moves nothing). Each is
    found as a tight edge of the shortest-path tree closed by a path of tight edges."""
    if not scene.contacts:
        return ()
    edges = _contact_subgraph(scene, constraint_graph(scene))
    distance, _ = shortest_paths(edges)
    slack = 1e-12 * max((abs(edge[2]) for edge in edges), default=0.0)
    tight = [edge for edge in edges if edge[2] + distance[edge[0]] - distance[edge[1]] <= slack]
    found: set[tuple[int, ...]] = set()
    for closing in tight:
        came: dict[int, tuple | None] = {closing[1]: None}
        queue = [closing[1]]
        for node in queue:
            for edge in tight:
                if edge[0] == node and edge[1] not in came:
                    came[edge[1]] = edge
                    queue.append(edge[1])
        if closing[0] in came:
            rows, node = [closing[3]], closing[0]
            while came[node] is not None:
                rows.append(came[node][3])
                node = came[node][0]
            if len(rows) > 1:
                found.add(tuple(sorted(rows)))
    return tuple(sorted(found))


def shortest_paths(edges: list) -> tuple[dict[int, float], list]:
    """Bellman–Ford from a virtual source joined to every vertex by weight 0 over edges
    (from, to, weight, ...): (the distance of every vertex, []), or (…, the edges of a cycle of
    negative total weight) when there is one."""
    vertices = sorted({v for a, b, *_ in edges for v in (a, b)})
    distance = dict.fromkeys(vertices, 0.0)
    before: dict[int, tuple] = {}
    for _ in range(len(vertices)):
        changed = None
        for edge in edges:
            a, b, weight = edge[:3]
            if distance[a] + weight < distance[b]:
                distance[b] = distance[a] + weight
                before[b] = edge
                changed = b
        if changed is None:
            return distance, []
    node = changed
    for _ in range(len(vertices)):  # walk back into the cycle
        node = before[node][0]
    cycle, at = [], node
    while True:
        edge = before[at]
        cycle.append(edge)
        at = edge[0]
        if at == node:
            return distance, cycle[::-1]


def equality_conflict(scene: Scene) -> str:
    """Why contact="equality" cannot hold every row of the scene at once, or "" when it can.

    Equality contact ties every row: a support or a wall fixes a node, a bar contact ties two
    nodes. Two ties between the same nodes (walls on both sides of one node, two walls on
    nodes a bar contact ties, a loop of bar contacts) fix them twice: the saddle-point system
    is singular. The message names the ties that close the loop."""
    offsets = _offsets(scene)
    supports = {offsets[s.bar] + s.node for s in scene.supports}
    parent: dict[int, int] = {}
    tree: dict[int, list[tuple[int, int, int]]] = {}

    def root(node: int) -> int:
        while parent.setdefault(node, node) != node:
            node = parent[node]
        return node

    rows = [(-1, offsets[w.bar] + w.node, f"wall[{i}] (node {w.node})")
            for i, w in enumerate(scene.walls)]
    rows += [(offsets[c.bar_a] + c.node_a, offsets[c.bar_b] + c.node_b, f"contact[{i}]")
             for i, c in enumerate(scene.contacts)]
    for index, (a, b, name) in enumerate(rows):
        a, b = (-1 if a in supports else a), (-1 if b in supports else b)
        if root(a) == root(b):
            loop = [rows[i][2] for i, _ in _tree_path(tree, a, b)] or ["a support"]
            return (f"contact='equality' cannot hold {name} together with {', '.join(loop)}: "
                    "they fix the same nodes twice; use contact='inequality'")
        parent[root(a)] = root(b)
        tree.setdefault(a, []).append((b, 1, index))
        tree.setdefault(b, []).append((a, -1, index))
    return ""


__all__ = ["constraint_graph", "equality_conflict", "impossible_constraints",
           "indeterminate_contacts", "shortest_paths", "tight_cycles"]
