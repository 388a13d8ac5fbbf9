"""Contact forces that move nothing: forces that push a node from both sides at once, and
forces carried round a loop of rows (walls and bar contacts) that the exact answer leaves
open; and the force that a contact left past its gap with none may take round such a loop
(:func:`rerouted_forces`). No displacement shows them, so the check (:mod:`contactqp.check.chain.certificate`)
counts them apart: each is wrong in every row it is on."""

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
    up_nodes, up_rows, down_nodes, down_rows = layout.opposed_entries  # places, not nodes
    common = 0.0
    if up_nodes.size:  # λ₊ of the rows read (no array of λ₊ over every row)
        size = int(up_nodes.max()) + 1  # every such node has entries both ways
        up, down = lam[up_rows], lam[down_rows]
        plus = _per_place(up_nodes, np.maximum(up, 0.0, out=up), size)
        minus = _per_place(down_nodes, np.maximum(down, 0.0, out=down), size)
        common = largest(np.minimum(plus, minus))
    # a loop whose gaps sum to zero (Layout.tight_cycles) is one of the loops that
    # round_the_loops finds: its weakest row carries at least that loop's smallest force
    return max(common, round_the_loops(layout, lam))


def _per_place(places: np.ndarray, forces: np.ndarray, size: int) -> np.ndarray:
    """np.bincount(places, forces, minlength=size): placed where each place has one entry (a
    channel: one wall each side of every node; bincount took 0.7 ms for 5·10⁴), 0.0 + f as
    bincount adds it (no −0.0), the same numbers bit for bit."""
    # every place has an entry (Layout.opposed_entries keeps only nodes pushed both ways), so
    # as many entries as places means one each
    if places.size != size:  # a place with several entries: their sum
        return np.bincount(places, forces, minlength=size)
    total = np.zeros(size)
    total[places] = forces
    total += 0.0
    return total


def round_the_loops(layout: Layout, lam: np.ndarray) -> float:
    """What the pushing rows of an answer (forces ``lam``, λ⁺ read) can carry round a loop of
    rows (N): rows that join held nodes, bar contacts among them, into a loop (two ways from a
    node to the ground, or round bars tied by contacts) split a force among their ways as the
    answer's own penetrations allow, where the exact answer, its gaps not adding up to zero,
    leaves one way open. The rows taken strongest first (a spanning forest, supports as the
    ground): each row that closes a loop is its weakest and carries at most its own force
    wrongly. Measured:
    ProxQP, random_scene seed 139, a wall and a bar contact to a second wall 3.4e-10 m apart
    on U = 17 m: 15.3 N on the contact that the exact answer leaves open, verified with a force
    bound of 3.5e-5 N. Scenes without bar contacts have no loop but a node's two sides
    (:func:`opposed_forces`)."""
    if not layout.scene.contacts:
        return 0.0
    force = np.maximum(lam, 0.0)
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


def rerouted_forces(layout: Layout, lam: np.ndarray, pen: np.ndarray, pushing: np.ndarray,
                    u: np.ndarray, U: float) -> float:
    """What contacts that do not push but are past their gaps may take from the rows that
    hold their ends (N). Closing such a contact moves its ends; where an end is held by a
    pushing row that the move opens (its entry at the node has the same sign as the
    contact's), the exact answer may release that row and send its force round the loop
    through the contact, with hardly any move (the gap moves, :func:`contactqp.check.chain.certificate.gap_moves`,
    keep every held node held and see only the elastic part). At each end the force the
    contact takes comes off such rows (the node's equilibrium, elements apart), so it is at
    most what they carry there: the least over the contact's ends (a wall's other end, the
    ground, any), summed over the contacts. (Measured: DAQP, random_scene seed 4246536 with
    free bars, a contact between two wall-held nodes 4.2e-7 m past with no force and its
    3 601 N on one of the walls, 4 % of F off, verified with a force bound of 0.12 N without
    this.) A penetration within round-off is not counted (ROUND_OFF_UNITS of the ends' u and
    the gap, and PAST_ROUND_OFF of U, the displacement scale): a loop whose gaps sum to zero
    leaves one, and its forces are :func:`opposed_forces`' (measured: exact answers 4e-19 m
    past, 5e-14 of U, where the stiffness spans eight decades). Scenes without bar contacts
    have no such loop but a node's two sides."""
    if not layout.scene.contacts:
        return 0.0
    rows, row_nodes, coefficients, gaps = layout.rows
    past = ~pushing & (pen > PAST_ROUND_OFF * U)
    if not past.any():
        return 0.0
    size = np.where(past, np.abs(gaps), 0.0)  # the largest of |g| and its nodes' |u|
    at = past[rows]
    np.maximum.at(size, rows[at], np.abs(u[row_nodes[at]]))
    past &= pen > ROUND_OFF_UNITS * np.finfo(float).eps * size
    # per node, what the pushing rows whose entries push it in +x (and in −x) carry
    force = np.where(pushing, np.maximum(lam, 0.0), 0.0)[rows]
    up = coefficients > 0.0
    plus = np.bincount(row_nodes[up], force[up], minlength=layout.n_nodes)
    minus = np.bincount(row_nodes[~up], force[~up], minlength=layout.n_nodes)
    capacity = np.where(up, plus[row_nodes], minus[row_nodes])  # per entry: what it opens
    taken = np.full(gaps.size, np.inf)  # a wall's ground end: any
    np.minimum.at(taken, rows, capacity)
    return float(taken[past].sum())


ROUND_OFF_UNITS = 64  # a penetration within this many units of round-off is not counted,
PAST_ROUND_OFF = 1e-9  # ... nor within this much of the displacement scale
