"""Contact forces that move nothing: forces that push a node from both sides at once, and
forces carried round a loop of rows (walls and bar contacts) that the exact answer leaves
open. No displacement shows them, so the check (:mod:`contactqp.bounds`) counts them apart:
each is wrong in every row it is on."""

from __future__ import annotations

import numpy as np

from contactqp.model import Layout, largest


def opposed_forces(layout: Layout, lam: np.ndarray) -> float:
    """The largest common part of contact forces that oppose each other (N): a node cannot be
    pushed from both sides at once, whatever the gaps (walls on both sides of it); nor can a
    loop of walls and bar contacts whose gaps sum to zero carry a force all the way round.
    min(Σλ₊, Σλ₋) at a node, and the smallest force around such a loop, is a set of forces
    that moves nothing and is wrong in every row it is on (where the gaps leave the nodes one
    position, the rows alone cannot tell how the force splits; the exact answer has one row of
    each loop free of it)."""
    force = np.maximum(lam, 0.0)
    up_nodes, up_rows, down_nodes, down_rows = layout.opposed_entries  # places, not nodes
    common = 0.0
    if up_nodes.size:
        size = int(up_nodes.max()) + 1  # every such node has entries both ways
        plus = np.bincount(up_nodes, force[up_rows], minlength=size)
        minus = np.bincount(down_nodes, force[down_rows], minlength=size)
        common = largest(np.minimum(plus, minus))
    # a loop whose gaps sum to zero (Layout.tight_cycles) is one of the loops that
    # round_the_loops finds: its weakest row carries at least that loop's smallest force
    return max(common, round_the_loops(layout, force))


def round_the_loops(layout: Layout, force: np.ndarray) -> float:
    """What the pushing rows of an answer can carry round a loop of rows (N): rows that join
    held nodes, bar contacts among them, into a loop (two ways from a node to the ground, or
    round bars tied by contacts) split a force among their ways as the answer's own
    penetrations allow, where the exact answer, its gaps not adding up to zero, leaves one
    way open. The rows taken strongest first (a spanning forest, supports as the ground): each
    row that closes a loop is its weakest and carries at most its own force wrongly. Measured:
    ProxQP, random_scene seed 139, a wall and a bar contact to a second wall 3.4e-10 m apart
    on U = 17 m: 15.3 N on the contact that the exact answer leaves open, verified with a force
    bound of 3.5e-5 N. Scenes without bar contacts have no loop but a node's two sides
    (:func:`opposed_forces`)."""
    if not layout.scene.contacts:
        return 0.0
    rows, row_nodes, _, gaps = layout.rows
    ground = layout.n_nodes
    ends = np.full((gaps.size, 2), ground)  # a wall's other end is the ground
    second = np.ones(rows.size, dtype=bool)  # Layout.rows: a wall's entry, then each bar
    second[np.unique(rows, return_index=True)[1]] = False  # contact's a entries, then its b
    ends[rows[~second], 0] = row_nodes[~second]
    ends[rows[second], 1] = row_nodes[second]
    parent = list(range(layout.n_nodes + 1))

    def root(node: int) -> int:
        while parent[node] != node:
            parent[node] = parent[parent[node]]
            node = parent[node]
        return node

    for node in layout.support_nodes:
        parent[root(int(node))] = ground
    carried = 0.0
    for row in np.argsort(-force, kind="stable"):
        if not force[row] > 0.0:
            break
        a, b = root(int(ends[row, 0])), root(int(ends[row, 1]))
        if a == b:
            carried += float(force[row])
        else:
            parent[a] = b
    return carried
