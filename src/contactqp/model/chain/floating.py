"""Bars with no support: whether their walls and bar contacts hold them against their loads
(:func:`unheld_bars`, refused with the reason before any method runs), and which bars their
walls wedge in place with no force at all (:func:`wedged_bars`, :func:`wedged_rows`). Reads a
scene and its layout; imports no other contactqp module."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from contactqp.model.chain.numbering import layout_of

if TYPE_CHECKING:
    from contactqp.scene import Scene


MAX_FLOATING_BARS = 12  # bars with no support a scene may have (their subsets are tried)


def unheld_bars(scene: Scene, contact: str = "inequality") -> str:
    """Why the walls and bar contacts do not hold the scene's bars that have no support
    against their loads, or "" when they do.

    Such a bar can move as a whole (K is singular there). Moving a set S of them together by
    t in +x changes the energy by −t·F(S), F(S) their net load, and keeps every row that
    joins S to the rest satisfied exactly when no wall on S's + side, and no bar contact from
    S to a bar outside it, stands in the way (S closed under "blocks +x"; for equality contact
    every row blocks both ways). If some such S has F(S) > 0 nothing holds it; with
    F(S) = 0 nothing presses it against a contact and its position is not determined; the
    same with −x. With unilateral contact, bars joined by bar contacts whose loads sum to 0
    are pressed against nothing outside them either (a press fit that squeezes them would hold
    them; such scenes are refused too). Every subset of up to :data:`MAX_FLOATING_BARS` bars is tried; the moves
    of sets are exactly the directions in which the energy has no minimum (order-preserving
    moves are sums of such sets' moves). A bar wedged by its walls (:func:`wedged_bars`) is
    held without a load."""
    layout = layout_of(scene)
    wedged = wedged_bars(scene)  # held by their walls' want of room, on nothing else
    floating = [b for b in layout.floating_bars.tolist() if b not in wedged]
    if not floating:
        return ""
    if len(floating) > MAX_FLOATING_BARS:
        return (f"support: {len(floating)} bars have no support; contactqp holds at most "
                f"{MAX_FLOATING_BARS} bars by contact alone")
    place = {b: i for i, b in enumerate(floating)}
    ground = len(floating)
    ahead = [0] * (ground + 1)  # bit masks: what blocks each bar's move in +x (ground: last)
    both_ways = contact == "equality"
    for a, b in zip(*layout.row_bars):  # the row stops bar a moving towards b in +x
        a, b = place.get(int(a), ground), place.get(int(b), ground)
        ahead[a] |= 1 << b
        if both_ways:
            ahead[b] |= 1 << a
    behind = [sum(1 << j for j in range(ground + 1) if ahead[j] >> i & 1)
              for i in range(ground + 1)]
    net = layout.bar_loads[floating].tolist()
    size = np.add.reduceat(np.abs(layout.nodal_loads), layout.node_offsets[:-1])[floating].tolist()
    for subset in sorted(range(1, 1 << ground), key=lambda m: (m.bit_count(), m)):
        members = [i for i in range(ground) if subset >> i & 1]
        force = sum(net[i] for i in members)
        round_off = 1e-12 * sum(size[i] for i in members)
        for blocks, direction, sign in ((ahead, "+x", 1.0), (behind, "−x", -1.0)):
            if any(blocks[i] & ~subset for i in members) or sign * force < -round_off:
                continue
            names = " and ".join(f"bar[{floating[i]}]" for i in members)
            unit = scene.unit.force
            if abs(force) <= round_off:
                return (f"nothing presses {names} against a wall or bar contact: its loads sum "
                        f"to 0 {unit} and it is free to move in {direction}, so its position "
                        "is not determined; give it a [[support]] or a load")
            return (f"nothing holds {names} against its load of {force:.6g} {unit}: no wall "
                    f"or bar contact stops it moving in {direction}")
        # unilateral contact: bars that touch each other and whose loads cancel are pressed
        # against nothing outside them, and may sit anywhere their walls leave them room
        if not both_ways and abs(force) <= round_off and _connected(subset, members, ahead,
                                                                   behind):
            names = " and ".join(f"bar[{floating[i]}]" for i in members)
            return (f"nothing presses {names} against a wall or bar contact: its loads sum to "
                    f"0 {scene.unit.force}, so its position between its walls and contacts is "
                    "not determined; give it a [[support]] or a load")
    return ""


def wedged_bars(scene: Scene) -> frozenset[int]:
    """The bars with no support, no load and no bar contact whose walls leave them no room:
    the smallest gap of their + walls and of their − walls sum to 0, so the only place for the
    bar, unloaded and so undeformed, is u = that + gap at every node (two zero-gap walls:
    u = 0). Their position is forced though nothing presses them, and their walls carry no
    force (any equal pair would do as well: the least one, 0, is the answer)."""
    layout = layout_of(scene)
    floating = set(layout.floating_bars.tolist())
    if not floating:
        return frozenset()
    loaded = np.add.reduceat(np.abs(layout.nodal_loads), layout.node_offsets[:-1]) > 0.0
    touched = {c.bar_a for c in scene.contacts} | {c.bar_b for c in scene.contacts}
    candidates = sorted(b for b in floating - touched if not loaded[b])
    if not candidates:
        return frozenset()
    bar = np.fromiter((w.bar for w in scene.walls), np.intp, len(scene.walls))
    plus = np.fromiter((w.side == "+" for w in scene.walls), bool, len(scene.walls))
    gap = np.fromiter((w.gap for w in scene.walls), float, len(scene.walls))
    wedged = []
    for b in candidates:
        ahead, behind = gap[(bar == b) & plus], gap[(bar == b) & ~plus]
        if ahead.size and behind.size:
            g_plus, g_minus = float(ahead.min()), float(behind.min())
            if abs(g_plus + g_minus) <= 1e-12 * max(abs(g_plus), abs(g_minus)):
                wedged.append(b)
    return frozenset(wedged)


def wedged_rows(scene: Scene) -> np.ndarray:
    """One bool per contact row: the walls of :func:`wedged_bars`, which hold their bar in
    place with no force (the check takes them as holding, as it does the rows that push)."""
    wedged = wedged_bars(scene)
    rows = np.zeros(scene.n_contacts, dtype=bool)
    if wedged:
        rows[: len(scene.walls)] = [w.bar in wedged for w in scene.walls]
    return rows


def _connected(subset: int, members: list[int], ahead: list[int], behind: list[int]) -> bool:
    """Whether the bars ``members`` (bit mask ``subset``) are joined by bar contacts among
    themselves (``ahead``/``behind``: the bit masks of what blocks each bar either way)."""
    reached, frontier = 1 << members[0], [members[0]]
    while frontier:
        i = frontier.pop()
        for j in members:
            if not reached >> j & 1 and (ahead[i] | behind[i]) >> j & 1:
                reached |= 1 << j
                frontier.append(j)
    return reached == subset


__all__ = ["MAX_FLOATING_BARS", "unheld_bars", "wedged_bars", "wedged_rows"]
