"""What an answer's residuals imply for its error: the bounds behind ``verified``.

The check (contactqp.check) reads an answer as the exact answer of a nearby scene: contacts
that push are held where the answer puts them, the force on every other contact (and every
pulling force) is moved off it as a load, and what equilibrium leaves over is a load too.
This module works out, run by run between held nodes, what those moves do to the contact
forces and the displacements (:func:`error_bounds`), in O(n).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.check.chain.bar_contacts import contact_give, pushing_pairs, through_pairs
from contactqp.check.chain.self_stress import opposed_forces, rerouted_forces
from contactqp.check.chain.spans import Running, count_at_or_before, kept, propagate
from contactqp.model import (
    Layout,
    bar_groups,
    in_set,
    largest,
    node_set,
    penetration,
    seen_stiffness,
)
from contactqp.model.chain.floating import wedged_bars, wedged_rows

ROUND_OFF = 4.0 * np.finfo(float).eps  # a few units in the last place of what is stored


@dataclass(frozen=True)
class Bounds:
    force_error_bound: float
    displacement_error_bound: float


def error_bounds(layout: Layout, u: np.ndarray, lam: np.ndarray, links: np.ndarray,
                 nodes: np.ndarray, external: np.ndarray, r_max: float, contact: str,
                 F: float, U: float, hold: float, outside: Running,
                 u_size: float | None = None, links_size: float | None = None,
                 pen: np.ndarray | None = None) -> Bounds:
    """The error bounds of an answer (module docstring; its residuals are the check's, read
    once for every model, :mod:`contactqp.check.residuals`); a contact whose force passes
    ``hold`` × F counts as pushing when the held nodes are chosen. ``outside``: the running
    sum of ``external`` over the nodes; ``u_size`` ‖u‖∞, ``links_size`` ‖links‖∞ and ``pen``
    C u − g per row, when the caller has them (read, not written).

    The answer is exact for a nearby scene: the rows that push are held at where the answer
    puts them (their gaps moved by δ = |penetration|), the other rows' forces and every
    pulling force are moved off them as loads, and what equilibrium leaves over is a load too.
    With the held nodes fixed, those loads' effect is computed exactly, run by run between
    held nodes (:func:`propagate`); a held node moved by δ moves its runs by at most δ and
    changes the forces at itself and its held neighbours (:func:`gap_moves`)."""
    rows, row_nodes, _, _ = layout.rows
    entry = layout.by_entry  # x[entry] is x[rows]
    pen = penetration(layout, u) if pen is None else pen
    equality = contact == "equality"
    pushing, chosen = _pushing(layout, lam, pen, hold * F, equality)
    if chosen is not None and np.array_equal(chosen[0], pushing):
        held, s, s_ends = chosen[1:]  # the same rows push: the same stiffnesses
    else:
        held = node_set(layout.n_nodes, layout.support_nodes, row_nodes[pushing[entry]])
        s, s_ends = row_stiffness(layout, held, pushing, ends=True)
    # in place where it can: each array over the rows is a fresh allocation (runs.propagate)
    delta = np.abs(pen) if equality else np.abs(pen, out=np.maximum(pen, 0.0), where=pushing)
    moved = np.where(pushing, 0.0, lam)  # an open row's force (or a pull) becomes a load
    n_loads = external.size - row_nodes.size - layout.support_nodes.size
    # the contacts of the nearby scene carry only the rest
    contact_part = slice(n_loads, n_loads + row_nodes.size)
    if np.any(moved):  # an open row has a force: its entries there (−C·λ, C = ±1) are not 0
        kept_external = external.copy()
        kept_external[contact_part][~pushing[entry]] = 0.0
        outside = Running.of(layout.n_nodes, nodes, kept_external)
    force_error, sway, jumps = propagate(layout, held, links, outside)
    pair = 0.0 if equality else opposed_forces(layout, lam)
    # an open row moved onto its wall (it penetrates) is held too, with no force of its own
    # closing a bar contact's gap δ moves each end by its share, δ·s/s_end (a wall's node: δ)
    if s_ends is s:  # walls alone: each row is its node, its share 1 (0 where rigid)
        end_moves = np.where(delta > 0.0, delta, 0.0)
        end_moves[np.isinf(s)] = 0.0
    else:
        with np.errstate(invalid="ignore", divide="ignore"):
            share = np.where(np.isinf(s_ends), 0.0,  # a rigid end does not move
                             np.where(s_ends > 0.0, s[entry] / s_ends, 1.0))
        end_moves = np.where(delta[entry] > 0.0, delta[entry] * np.minimum(share, 1.0), 0.0)
    gap_force, gap_move, moves = gap_moves(layout, held, row_nodes, end_moves, pushing)
    # gap⁺ = max(−pen, 0), in delta's array (read no more)
    standing = None if equality else np.maximum(np.negative(pen, out=delta), 0.0, out=delta)
    del delta
    # ... and a held node that moves drags its run along: an open contact there whose gap is
    # smaller than that would close, and take what closing the rest of the move needs
    # (measured: quadprog left a wall 2.5e-12 m open beside one held 1.7e-11 m off, across
    # an element of 7e13 N/m, 963 N off and verified without this)
    # (the ends of a bar contact that pushes, or that penetrates and is closed by the move,
    # move together: an open row at one end pushes both back)
    closing = 0.0 if equality else _closing(layout, moves, row_nodes, rows,
                                            np.where(pushing, np.inf, standing), held, s,
                                            pushing, (pushing | (pen > 0.0))
                                            if layout.scene.contacts else None)
    # ... and a contact past its gap with no force may take the force of a row that holds
    # its end, round the loop of rows (contactqp.check.chain.self_stress.rerouted_forces)
    rerouted = 0.0 if equality else rerouted_forces(layout, lam, pen, pushing, u, U)
    force_bound = max(force_error, largest(moved)) + gap_force + pair + closing + rerouted
    # a pushing bar contact is held at both ends above, but the two ends move together: the
    # force errors at its two ends move them by their sum over the stiffness both bars give
    # them there, and its bars' displacements by up to as much again (measured when the
    # forces took the same factor, before their own term below: without it, up to 1.4 times
    # the bound on random scenes of several bars)
    ends, moving, group = pushing_pairs(layout, pushing)
    give = contact_give(layout, held, ends, moving)
    coupled = 2.0 if give > 0.0 else 1.0
    # what moves a pair is the errors at both its ends, and a pair beside another pair moves
    # it too: in a group of bars they join, the errors at both ends of every such pair go on
    # through the runs into the held nodes beside them, in parts of at most the whole (the
    # springs between held nodes share a load, none pulls against it), so a held node or a
    # row takes at most its own error and all of those (measured: ECOS, random_scene 78 of
    # seed 2026, a wall beside a pushing contact 5.3e-3 N off, its own error 2.1e-3 N and the
    # contact's ends' 2.2e-3 and 0.9e-3 N, against 5.0e-3 N from twice the largest error)
    through = through_pairs(held, jumps, ends[moving], group,
                            gap_force + pair + closing + rerouted)
    force_bound += through
    # ... and that sum, not the largest error, moves the group (measured: three bars, two
    # contacts joined by a stiff stretch, each end e off: the group moved twice the bound
    # that the largest error gave); the forces moved off every other row all reach the held
    # pair through the runs: their sum, not the largest, is what can move it too (measured:
    # Clarabel, three bars tied by a contact, four rows ~100 N off each; the pair moved
    # 2.7e-4 m, the largest force alone bounded 2.0e-4 m, and the answer was verified
    # 1.09e-5·U off)
    # ... and so does what equilibrium leaves over in the elements between them and the
    # next held node, r_j beside c (propagate: an element's force error is c − r_j; measured:
    # the augmented method, a bar held by contact alone pressing on a free bar's node, 0.0096 N
    # off at the contact and 0.016 N left over along three elements, moved the pair 1.04e-9 m
    # against a bound of 6.2e-10 m from the contact's error alone)
    carried = (max(force_error, through) + float(np.abs(moved).sum()) + gap_force + pair
               + closing + rerouted + r_max)
    displacement_bound = coupled * (sway + gap_move) + carried * give
    # and the answer itself is only stored to a few units of round-off: a force of 2e8 N from
    # a press fit on a stiff element is one float step (3e-8 N) from any other
    force_bound += ROUND_OFF * max(largest(lam), largest(links) if links_size is None
                                   else links_size, F)
    displacement_bound += ROUND_OFF * max(largest(u) if u_size is None else u_size, U)
    if not equality:
        displacement_bound += _release(layout, held, pushing, lam, force_bound)
    if unpinned_bar(layout, pushing) is not None:  # the answer leaves a bar free to move
        displacement_bound = np.inf
    return Bounds(force_bound, displacement_bound)


def _pushing(layout: Layout, lam: np.ndarray, pen: np.ndarray, hold: float,
             equality: bool) -> tuple[np.ndarray, tuple | None]:
    """Which rows the nearby scene holds: every row for equality contact; else those whose
    force exceeds what closing their gap takes (the stiffness seen with the rows pushing
    more than ``hold`` held), so that closing the gap is the smaller move. Also (the rows
    taken as pushing for the stiffness, the held nodes, the row and end stiffnesses), for
    the caller to reuse when the same rows come out."""
    _, row_nodes, _, gaps = layout.rows
    if equality:
        return np.ones(gaps.size, dtype=bool), None
    wedged = _wedged(layout)  # walls that hold a bar in place with no force
    strong = (lam > hold) | wedged
    held = node_set(layout.n_nodes, layout.support_nodes, row_nodes[strong[layout.by_entry]])
    s, s_ends = row_stiffness(layout, held, strong, ends=True)
    closing = np.negative(pen)  # gap⁺·s, what closing each gap takes, in one array
    pushing = np.greater(lam, np.multiply(np.maximum(closing, 0.0, out=closing), s, out=closing))
    pushing |= wedged
    return pushing, (strong, held, s, s_ends)


def _wedged(layout: Layout) -> np.ndarray:
    """:func:`contactqp.model.chain.floating.wedged_rows` of the scene (all False where every bar has
    a support, without looking at the walls)."""
    if not layout.floating_bars.size:
        return np.zeros(layout.rows[3].size, dtype=bool)
    return wedged_rows(layout.scene)


def _release(layout: Layout, held: np.ndarray, pushing: np.ndarray, lam: np.ndarray,
             force_bound: float) -> float:
    """How far a held node may move because its wall's push is not certain (m): a row that
    pushes with less than the force bound might pull in the exact answer, and then the node
    it holds is free to move, by up to the force bound over the stiffness it sees with every
    surely held node fixed (inf where nothing else holds it). The bounds above hold the
    answer's own set of pushing rows; this is what a wrong member of that set can cost.
    (Measured: HiGHS left a wall pushing with 7e-6 N where the exact answer has the wall on
    the node's other side 1.7e-7 m away, across an element of 6400 N/m; force bound 6e-3 N,
    displacement bound 3e-11 m, verified and 9e-4 of U off without this.)"""
    unsure = pushing & (lam <= force_bound) & ~_wedged(layout)  # wedged: held whatever λ
    if not unsure.any():
        return 0.0
    row_nodes = layout.rows.node
    sure = pushing & ~unsure
    still = node_set(layout.n_nodes, layout.support_nodes, row_nodes[sure[layout.by_entry]])
    stiffness = row_stiffness(layout, still, sure)[unsure]
    with np.errstate(divide="ignore"):
        return float(np.max(force_bound / stiffness))


def unpinned_bar(layout: Layout, pushing: np.ndarray) -> int | None:
    """A bar with no support that the ``pushing`` rows do not join to a support or a wall
    (through other bars), or None: nothing in the answer fixes where such a bar is."""
    if not layout.floating_bars.size:
        return None
    labels = bar_groups(layout, pushing)
    loose = np.setdiff1d(np.flatnonzero(labels[:-1] != labels[-1]),
                         list(wedged_bars(layout.scene)))
    return int(loose[0]) if loose.size else None


def gap_moves(layout: Layout, held: np.ndarray, nodes: np.ndarray, delta: np.ndarray,
              pushing: np.ndarray) -> tuple[float, float, tuple[np.ndarray, np.ndarray]]:
    """What moving the contact nodes ``nodes`` by ``delta`` (m) with the other held nodes fixed
    does: (the largest force change at a held node, N; the largest move, m; each held node's
    move). A node moved by δ
    between held neighbours at compliances c_l and c_r changes its own force by
    δ(1/c_l + 1/c_r) and each neighbour's by δ/c. The two ends of a pushing bar contact move
    together: each moves by its own δ and the other end's. A moved node that is not held (an
    open contact that penetrates) counts as held."""
    moving = node_set(layout.n_nodes, held, nodes[delta > 0.0])
    if moving.size == 0:
        return 0.0, 0.0, (moving, np.zeros(0))
    listed, at, to_left, to_right = kept(layout, "moving", moving,
                                         lambda: _moving_links(layout, moving, nodes))
    by_node = np.zeros(moving.size)
    _largest_at(by_node, at, delta[listed])
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
    shifted_left = np.concatenate(([0.0], by_node[:-1]))
    shifted_right = np.append(by_node[1:], 0.0)
    # by_node·(1/c_l + 1/c_r) + left neighbour's move/c_l + right's/c_r, in two arrays
    change = np.add(to_left, to_right)
    change *= by_node
    term = np.multiply(shifted_left, to_left, out=shifted_left)
    change += term
    change += np.multiply(shifted_right, to_right, out=term)
    return largest(change), largest(by_node), (moving, by_node)


def _moving_links(layout: Layout, moving: np.ndarray, nodes: np.ndarray
                  ) -> tuple[np.ndarray, ...]:
    """For :func:`gap_moves`, from the moving nodes alone (kept per set, read-only): which
    of ``nodes`` move and the place of each among ``moving``, and each moving node's 1/c to
    its moving neighbour on the left and on the right in its bar (0 where none)."""
    index = np.full(layout.n_nodes, -1, dtype=np.intp)  # each moving node's place in moving
    index[moving] = np.arange(moving.size)
    place = index[nodes]
    listed = place >= 0
    bar = layout.bar_of(moving)
    same = bar[1:] == bar[:-1]
    with np.errstate(divide="ignore"):
        link = np.where(same, 1.0 / np.diff(layout.compliance[moving]), 0.0)  # 1/c to the next
    made = (listed, place[listed], np.concatenate(([0.0], link)), np.append(link, 0.0))
    for array in made:
        array.flags.writeable = False
    return made


def _largest_at(into: np.ndarray, at: np.ndarray, values: np.ndarray) -> None:
    """np.maximum.at(into, at, values) for ``values`` >= 0 (or NaN) into zeros: written
    directly, and only the entries a repeated place overwrote taken again by np.maximum.at
    (which costs ~0.1 µs an entry: 1 ms for the 10⁴ walls of a batch)."""
    into[at] = values
    lost = into[at] != values  # a later entry at the same place wrote over it
    if lost.any():
        np.maximum.at(into, at[lost], values[lost])


def _closing(layout: Layout, moves: tuple[np.ndarray, np.ndarray], row_nodes: np.ndarray,
             rows: np.ndarray, stand_off: np.ndarray, held_before: np.ndarray, s: np.ndarray,
             pushing: np.ndarray, tying: np.ndarray | None) -> float:
    """The largest force an open contact would take if the held nodes at the ends of its run
    moved as ``moves`` says ((sorted nodes, move of each, m)): (move − its stand-off)⁺ × the
    stiffness it sees with those nodes held (``s`` where they are ``held_before``), the ends of
    each ``tying`` bar contact moving as one (:func:`tied_row_stiffness`; None: walls alone).
    (Measured: DAQP, a bar held by its walls alone, random_scene seed 39063: a press fit of
    2.1e-12 m across an element of 2.9e7 N/m left open, its wall's stiffness taken with the
    penetrating node free, through an element of 153 N/m: 6.2e-5 N off against a bound of
    6.9e-7 N. And lemke, random_scene seed 1198665058: a zero-gap bar contact 1.1e-7 m past
    with no force, closed by moving its soft end onto a touching wall; that wall's stiffness
    taken at its node alone, 1.1e6 N/m, where pushing the node back pushes the contact's
    other end too, across an element of 1.8e10 N/m: 1 955 N off, verified with a force bound
    of 0.24 N.)"""
    held, shift = moves
    if held.size == 0 or not np.isfinite(stand_off).any():
        return 0.0
    if largest(shift) <= np.min(stand_off):  # no held node moves as far as any open gap
        return 0.0
    tied = None if tying is None else tied_row_stiffness(layout, held, pushing, tying)
    if tied is not None:
        s = tied
    elif held.size != held_before.size:  # a penetrating open row's node is held as well
        s = row_stiffness(layout, held, pushing)
    bar = layout.bar_of(row_nodes)
    held_bar = layout.bar_of(held)
    after = count_at_or_before(layout.n_nodes, held, row_nodes)
    left, right = np.maximum(after - 1, 0), np.minimum(after, held.size - 1)
    induced = np.maximum(np.where((after > 0) & (held_bar[left] == bar), shift[left], 0.0),
                         np.where((after < held.size) & (held_bar[right] == bar), shift[right],
                                  0.0))
    if rows.size == stand_off.size:  # one entry per row (walls): no two to take the max of
        per_row = np.zeros(stand_off.size)
        per_row[rows] = induced
    else:
        per_row = np.zeros(stand_off.size)
        _largest_at(per_row, rows, induced)
    excess = np.maximum(per_row - stand_off, 0.0)
    closes = (excess > 0.0) & np.isfinite(stand_off)  # (a rigid row that does not close: 0)
    return largest(np.where(closes, excess * s, 0.0))


def row_stiffness(layout: Layout, held: np.ndarray, pushing: np.ndarray,
                  ends: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The stiffness (N/m) each contact row sees with the supports and ``held`` nodes fixed:
    a wall, its node's (:func:`seen_stiffness`); a bar contact, its two nodes' in series (an
    end held by a support, a ``pushing`` wall or another pushing bar contact is rigid: only
    the other end moves; both held, neither counts as rigid). (Measured: an open zero-gap
    contact from a node that a pushing zero-gap contact ties to the same bar, beyond an
    element of 1e12 N/m; taking both ends in series, the soft one, the penalty passed with
    that contact's 6178 N carried by the stiff element instead, 2e-3 of F off.) With
    ``ends``, also the stiffness of each end (per nonzero of :attr:`Scene.contact_rows`)."""
    walls_only = len(layout.scene.walls) == layout.rows.gap.size
    # kept per held set (contactqp.check.chain.spans); with bar contacts the pushing rows decide too
    kind = "stiffness" if walls_only else ("stiffness", np.packbits(pushing).tobytes())
    row, node_stiffness = kept(layout, kind, held,
                               lambda: _row_stiffness(layout, held, pushing, walls_only))
    return (row, node_stiffness) if ends else row


def tied_row_stiffness(layout: Layout, held: np.ndarray, pushing: np.ndarray,
                       tying: np.ndarray) -> np.ndarray | None:
    """:func:`row_stiffness` where the two ends of every ``tying`` bar contact (one bool per
    row) move as one: an end of another row at a node so tied sees the stiffness of the whole
    group of nodes the tying contacts join (the sum of theirs; its own where one of them is a
    support). A tying contact's own row keeps its ends' stiffness. None where no other row
    has an end at a tied node (nothing changes)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    rows, row_nodes, _, gaps = layout.rows
    ties = tying[rows] & (rows >= len(layout.scene.walls))
    if not ties.any():
        return None
    # a bar contact's two entries, in row order: its a end, then its b end (Layout.rows)
    ends = row_nodes[ties][np.argsort(rows[ties], kind="stable")]
    nodes, ends = np.unique(ends, return_inverse=True)  # the tied nodes; each end's place
    place = np.searchsorted(nodes, row_nodes)
    place[place == nodes.size] = 0
    at = (nodes[place] == row_nodes) & ~ties
    if not at.any():
        return None
    _, node_stiffness = row_stiffness(layout, held, pushing, ends=True)
    graph = sp.coo_array((np.ones(ends.size // 2), (ends[0::2], ends[1::2])),
                         shape=(nodes.size, nodes.size))
    label = connected_components(graph, directed=False)[1]
    group = np.bincount(label, seen_stiffness(layout, held, nodes))
    # a group with a support in it does not move: its moves are its rows' own penetrations,
    # and there each end keeps its own stiffness (a rigid group would make any round-off
    # move infinitely costly where zero gaps clamp a node between a wall and a supported node)
    grounded = np.zeros(group.size, dtype=bool)
    grounded[label[in_set(layout.n_nodes, nodes, layout.support_nodes)]] = True
    at &= np.isfinite(node_stiffness) & ~grounded[label[place]]
    node_stiffness = np.where(at, group[label[place]], node_stiffness)
    with np.errstate(divide="ignore"):
        return 1.0 / np.bincount(rows, 1.0 / node_stiffness, minlength=gaps.size)


def _row_stiffness(layout: Layout, held: np.ndarray, pushing: np.ndarray, walls_only: bool
                   ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`row_stiffness` made anew: (per row, per end), read-only."""
    rows, row_nodes, _, gaps = layout.rows
    node_stiffness = seen_stiffness(layout, held, row_nodes)
    node_stiffness.flags.writeable = False
    n_walls = len(layout.scene.walls)
    if walls_only:  # a row is its node
        return node_stiffness, node_stiffness
    rigid = np.concatenate((layout.support_nodes, row_nodes[:n_walls][pushing[:n_walls]],
                            row_nodes[(rows >= n_walls) & pushing[rows]]))
    fixed = (rows >= n_walls) & in_set(layout.n_nodes, row_nodes, rigid)
    # both ends held: the contact closes only as a wall gives, at that end's own stiffness
    fixed &= np.bincount(rows[fixed], minlength=gaps.size)[rows] < 2
    node_stiffness = np.where(fixed, np.inf, node_stiffness)
    with np.errstate(divide="ignore"):
        row = 1.0 / np.bincount(rows, 1.0 / node_stiffness, minlength=gaps.size)
    row.flags.writeable = node_stiffness.flags.writeable = False
    return row, node_stiffness
