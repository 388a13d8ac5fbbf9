"""What pushing bar contacts do to an answer's error (:mod:`contactqp.check.chain.certificate`): a pushing bar
contact holds its two ends a fixed distance apart, not in place, so they move together. A
force error at either end moves the pair by the sum of both over the stiffness the two bars
give it there (:func:`contact_give`), and that sum passes on through the runs into the held
nodes beside the pair, and through further contacts to every held node of the group of bars
they join (:func:`through_pairs`)."""

from __future__ import annotations

import numpy as np

from contactqp.model import Layout, in_set, seen_stiffness


def pushing_pairs(layout: Layout, pushing: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pushing bar contacts: their two ends (node numbers, one row each), whether each can
    move (neither end a support: a supported end does not move), and the group of bars each
    that can move is in, bars joined by those (one label for each of them)."""
    n_walls = len(layout.scene.walls)
    contacts = [c for i, c in enumerate(layout.scene.contacts) if pushing[n_walls + i]]
    if not contacts:  # walls alone: nothing made over the chain
        return np.zeros((0, 2), dtype=np.intp), np.zeros(0, dtype=bool), np.zeros(0, np.intp)
    ends = np.array([[layout.node(c.bar_a, c.node_a), layout.node(c.bar_b, c.node_b)]
                     for c in contacts], dtype=np.intp)
    moving = ~in_set(layout.n_nodes, ends, layout.support_nodes).any(axis=1)
    bars = np.array([[c.bar_a, c.bar_b] for c in contacts], dtype=np.intp)
    return ends, moving, _groups(len(layout.scene.bars), bars[moving])


def _groups(bars: int, joins: np.ndarray) -> np.ndarray:
    """The group of each of ``joins`` (pairs of bars, one row each): bars joined by them."""
    if len(joins) <= 1:
        return np.zeros(len(joins), dtype=np.intp)
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    graph = sp.coo_array((np.ones(len(joins)), (joins[:, 0], joins[:, 1])), shape=(bars, bars))
    return connected_components(graph, directed=False)[1][joins[:, 0]]


def contact_give(layout: Layout, held: np.ndarray, ends: np.ndarray, moving: np.ndarray
                 ) -> float:
    """The largest 1/(s_a + s_b) (m/N) over the pushing bar contacts that can move (``ends``
    and ``moving`` of :func:`pushing_pairs`): how far a unit force error moves the two ends
    of a contact together, s_a and s_b the stiffness each end sees in its own bar with the
    held nodes fixed, but the ends of every pushing bar contact. Another contact's ends are
    not fixed: they move with it, and where a stiff stretch of bar joins two contacts the
    pairs move as one (measured: the augmented method on a random scene, two contacts joined
    by elements of 1e10 N/m, the four ends moved 4.6e-13 m together against a bound of
    1.2e-15 m that held each pair by the other's ends)."""
    if not moving.any():
        return 0.0
    others = np.setdiff1d(held, ends)
    give = 0.0
    for pair in ends[moving]:
        stiffness = float(seen_stiffness(layout, others, pair).sum())
        give = max(give, 1.0 / stiffness if stiffness > 0.0 else np.inf)  # 0: nothing holds it
    return give


def through_pairs(held: np.ndarray, jumps: np.ndarray, ends: np.ndarray, group: np.ndarray,
                  moves: float) -> float:
    """The most force that moving bar contacts pass on to a held node or a row (N): in one
    group of bars, the errors at both ends of every such contact (``jumps`` at the ``held``
    nodes, and what ``moves``, the other terms of the bound, add at a node)."""
    if not ends.size:
        return 0.0
    at_ends = np.abs(jumps[np.searchsorted(held, ends)])
    return float(np.bincount(group, at_ends.sum(axis=1) + 2.0 * moves).max())


__all__ = ["contact_give", "pushing_pairs", "through_pairs"]
