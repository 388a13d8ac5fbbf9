"""What is computed from a scene's :class:`~contactqp.model.chain.layout_names.Layout` (its numbering and the
arrays along the chain): element, link and contact forces and penetrations from the
displacements, the displacement that forces at a few nodes cause (:func:`spread`), sets of
nodes, the stiffness a node sees (:func:`seen_stiffness`), the scale of the loads' forces
(:func:`load_force_scale`), and the groups of bars that contact rows join (:func:`bar_groups`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

Layout = Any  # the numbering (contactqp.model.chain.numbering.Layout), which imports this module


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


def wall_arrays(layout: Layout) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """:attr:`Layout.walls_by_side`: per side, the gap of the wall at every global node (inf
    where none) and its row (−1 where none)."""
    rows = layout.rows
    walls = len(layout.scene.walls)
    node, sign, gap = rows.node[:walls], rows.coefficient[:walls], rows.gap[:walls]
    sides = {}
    for side in (1, -1):
        order = np.flatnonzero((sign == side) & ~layout.support_mask[node])
        bound = np.full(layout.n_nodes, np.inf)
        bound[node[order]] = gap[order]
        owner = np.full(layout.n_nodes, -1, dtype=np.intp)
        owner[node[order]] = order
        sides[side] = (_read_only(bound), _read_only(owner))
    return sides


def element_forces(layout: Layout, u: np.ndarray) -> np.ndarray:
    """Axial force of every element (N, tension positive) from the nodal displacements,
    bar after bar."""
    stretch = np.diff(u)
    if layout.junctions.size:
        stretch = np.delete(stretch, layout.junctions)
    return np.multiply(layout.element_stiffness, stretch, out=stretch)  # no second array


def link_forces(layout: Layout, forces: np.ndarray) -> np.ndarray:
    """Element forces placed on the links between global nodes j and j + 1 (0 at a junction)."""
    if not layout.junctions.size:
        return forces
    element = layout.elements[0]
    if element.size != np.size(forces):  # not one force per element: as np.insert places it
        return np.insert(forces, layout.junctions - np.arange(layout.junctions.size), 0.0)
    links = np.zeros(layout.n_nodes - 1)  # placed (np.insert: 10x slower on a batch)
    links[element] = forces
    return links


def contact_forces_on_nodes(layout: Layout, contact_force: np.ndarray) -> np.ndarray:
    """Force of the walls and bar contacts on each node in +x (N): −Cᵀλ in node numbering."""
    rows = layout.rows
    return np.bincount(rows.node, -rows.coefficient * np.asarray(contact_force, dtype=float)
                       [rows.row], minlength=layout.n_nodes)


def penetration(layout: Layout, u: np.ndarray) -> np.ndarray:
    """How far each contact is closed past its gap, C u − g: positive = penetrated."""
    rows = layout.rows
    if rows.row.size == rows.gap.size:  # walls only: one entry per row, in row order
        return rows.coefficient * u[rows.node] - rows.gap
    return np.bincount(rows.row, rows.coefficient * u[rows.node],
                       minlength=rows.gap.size) - rows.gap


def spread(layout: Layout, anchors: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The displacement of every node that forces at the nodes ``anchors`` alone cause (sorted
    global nodes, every support among them), from its ``values`` there (0 at a support):
    linear in the compliance φ between two anchors of a bar, constant beyond a bar's outermost
    anchor towards its free end (no force passes there). O(n) (numpy.interp)."""
    offsets = layout.node_offsets
    phi = layout.chained_compliance
    bar = layout.bar_of(anchors)
    first, last = run_starts(bar), run_ends(bar)
    xp = np.concatenate((phi[offsets[:-1][bar[first]]], phi[anchors],
                         phi[offsets[1:][bar[last]] - 1]))
    fp = np.concatenate((values[first], values, values[last]))
    order = np.argsort(xp, kind="stable")
    return np.interp(phi, xp[order], fp[order])


def run_starts(values: np.ndarray) -> np.ndarray:
    """Whether each entry starts a run of equal values (the first always does)."""
    starts = np.empty(values.size, dtype=bool)
    starts[:1] = True
    np.not_equal(values[1:], values[:-1], out=starts[1:])
    return starts


def run_ends(values: np.ndarray) -> np.ndarray:
    """Whether each entry ends a run of equal values (the last always does)."""
    ends = np.empty(values.size, dtype=bool)
    ends[-1:] = True
    np.not_equal(values[1:], values[:-1], out=ends[:-1])
    return ends


def node_set(n_nodes: int, *nodes: np.ndarray) -> np.ndarray:
    """The sorted distinct node numbers in ``nodes`` (arrays of global node numbers), by a
    mask over the chain: O(n) without a sort (np.unique sorts or hashes, 5 ms at 10⁵); a few
    nodes on a long chain by sorting them instead (one wall on 10⁶ nodes: no 1 MB mask)."""
    parts = [np.asarray(part, dtype=np.intp).reshape(-1) for part in nodes]
    if parts and 8 * sum(part.size for part in parts) <= n_nodes:
        return np.unique(np.concatenate(parts))
    mask = np.zeros(n_nodes, dtype=bool)
    for part in parts:
        mask[part] = True
    return np.flatnonzero(mask)


def in_set(n_nodes: int, values: np.ndarray, members: np.ndarray) -> np.ndarray:
    """np.isin for node numbers: whether each of ``values`` is one of ``members``."""
    mask = np.zeros(n_nodes, dtype=bool)
    mask[np.asarray(members, dtype=np.intp)] = True
    return mask[np.asarray(values, dtype=np.intp)]


def seen_stiffness(layout: Layout, held: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """The seen stiffness (N/m) of each of ``nodes`` (global) with the supports and the nodes
    ``held`` fixed: 1/c_left + 1/c_right, c the compliance to the nearest fixed node on that
    side in the same bar (no term when there is none; a node does not hold itself)."""
    phi = layout.compliance
    n = layout.n_nodes
    nodes = np.asarray(nodes, dtype=np.intp)
    held = np.asarray(held, dtype=np.intp)
    if 8 * (nodes.size + held.size) <= n:  # few nodes: the nearest fixed ones by bisection
        return _seen_stiffness_few(layout, held, nodes)
    fixed = layout.support_mask.copy()
    fixed[held] = True
    at = np.flatnonzero(fixed)
    count = count_up_to(fixed)[nodes]  # fixed nodes at or before each node
    before = count - fixed[nodes]  # ... strictly before it
    left = at[np.maximum(before - 1, 0)] if at.size else nodes
    right = at[np.minimum(count, at.size - 1)] if at.size else nodes
    has_left, has_right = before > 0, count < at.size
    if len(layout.scene.bars) > 1:  # the nearest fixed node must be in the node's bar
        first, last = layout.bar_ends
        has_left &= left >= first[nodes]
        has_right &= right <= last[nodes]
    own = phi[nodes]
    with np.errstate(divide="ignore"):
        return (np.where(has_left, 1.0 / (own - phi[left]), 0.0)
                + np.where(has_right, 1.0 / (phi[right] - own), 0.0))


def segment_reduce(ufunc: np.ufunc, values: np.ndarray, starts: np.ndarray,
                   ends: np.ndarray | None = None, long: np.ndarray | None = None
                   ) -> np.ndarray:
    """``ufunc.reduceat(values, starts)`` (``starts`` increasing, the last segment to the end;
    ``ends`` and ``long``, the segments of more than one element, when the caller keeps
    them): where nearly every segment is one element (the held nodes of a pressed patch),
    those are the values themselves and only the long segments are reduced, each by the same
    reduceat over its slice (reduceat costs a call per segment: 0.35 ms for 9.5·10⁴ of them).
    The same numbers bit for bit."""
    if long is None:
        if LONG_SEGMENTS * starts.size < values.size:  # long on average: reduceat as it is
            return ufunc.reduceat(values, starts)
        ends = np.append(starts[1:], values.size)
        long = np.flatnonzero(ends - starts > 1)
    if long.size * LONG_SEGMENTS > starts.size:
        return ufunc.reduceat(values, starts)
    out = values[starts]
    for i, a, b in zip(long.tolist(), starts[long].tolist(), ends[long].tolist()):
        out[i] = ufunc.reduceat(values[a:b], [0])[0]
    return out


LONG_SEGMENTS = 64  # segments reduced one by one where at most one in this many is long


def count_up_to(mask: np.ndarray) -> np.ndarray:
    """How many of ``mask`` are set at or before each position: a running count in 32-bit
    integers where it fits (numpy's running sum of booleans into 64 bits is 15× slower)."""
    return np.cumsum(mask, dtype=np.int32 if mask.size < 2**31 else np.intp)


def _seen_stiffness_few(layout: Layout, held: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """:func:`seen_stiffness` for a few ``nodes``: the nearest fixed nodes by bisection."""
    phi = layout.compliance
    fixed = node_set(layout.n_nodes, layout.support_nodes, held)
    left = np.searchsorted(fixed, nodes, side="left") - 1
    right = np.searchsorted(fixed, nodes, side="right")
    neighbours = ((fixed[left.clip(0, max(fixed.size - 1, 0))] if fixed.size else left,
                   left >= 0, 1.0),
                  (fixed[right.clip(0, max(fixed.size - 1, 0))] if fixed.size else right,
                   right < fixed.size, -1.0))
    node_bar = layout.bar_of(nodes)
    stiffness = np.zeros(nodes.size)
    for neighbour, near, sign in neighbours:
        near = near.copy()
        near[near] &= layout.bar_of(neighbour[near]) == node_bar[near]
        stiffness[near] += 1.0 / (sign * (phi[nodes[near]] - phi[neighbour[near]]))
    return stiffness


def largest(values: np.ndarray) -> float:
    """∞-norm (0 for no values; inf when any value is NaN or infinite)."""
    values = np.asarray(values, dtype=float)
    if values.size <= TINY:  # a few numbers: Python's max is quicker than numpy's set-up
        numbers = values.ravel().tolist()
        if not all(map(math.isfinite, numbers)):
            return math.inf
        return float(max(map(abs, numbers), default=0.0))
    if values.size <= SMALL:  # one |x| and one reduction, without numpy's Python layers
        top = float(np.maximum.reduce(np.abs(values), axis=None))
    else:  # two reductions and no array of |x| over a long chain
        top = max(float(np.maximum.reduce(values, axis=None)),
                  -float(np.minimum.reduce(values, axis=None)))
    return top if math.isfinite(top) else math.inf


TINY = 16  # arrays up to this size are read as Python floats
SMALL = 1024  # arrays up to this size are cheaper to copy than to reduce twice


def load_force_scale(layout: Layout) -> float:
    """The largest force the scene's loads put through any cut of a bar (N): over every bar
    and every node, the resultant of the loads (point and distributed) on either side, and
    every nodal load itself. A distributed load counts whole, not per node."""
    return largest(load_force_terms(layout))


def load_force_terms(layout: Layout) -> np.ndarray:
    """Per node, the largest of |the loads' resultant on either side of it in its bar| and
    |its nodal load| (N): :func:`load_force_scale` is the largest over the nodes."""
    return bar_load_terms(layout.nodal_loads, layout.running_load, layout.node_offsets)


def bar_load_terms(loads: np.ndarray, running: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """:func:`load_force_terms` from the nodal ``loads``, their running sum along the chain
    and the bars' first nodes (``offsets``, the node count last), along the first axis: a
    batch gives nodes x cases and gets each case's terms, the same numbers as the case alone
    gives (its running sum starts at its own node 0)."""
    sizes = np.diff(offsets)
    left = running.copy()
    if sizes.size > 1:  # from each bar's node 0 (the first bar's is the chain's)
        left[offsets[1]:] -= np.repeat(left[offsets[1:-1] - 1], sizes[1:], axis=0)
    right = np.repeat(left[offsets[1:] - 1], sizes, axis=0)
    # in place: each array over the chain is a fresh allocation, and on a VM its pages cost
    right -= left
    np.abs(left, out=left)
    np.maximum(left, np.abs(right, out=right), out=left)
    return np.maximum(left, np.abs(loads, out=right), out=left)


def bar_groups(layout: Layout, rows: np.ndarray) -> np.ndarray:
    """The connected groups of bars when the contact rows ``rows`` (one bool per row) join
    them: a wall joins its bar, and a support its bar, to one more vertex, the ground (last).
    One label per bar, then the ground's: a bar labelled as the ground is held in place."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    scene = layout.scene
    bars = len(scene.bars)
    ahead, behind = layout.row_bars
    supported = np.array([s.bar for s in scene.supports], dtype=np.intp)
    a = np.concatenate((supported, ahead[rows]))
    b = np.concatenate((np.full(supported.size, bars), behind[rows]))
    a[a < 0], b[b < 0] = bars, bars  # a wall's fixed side: the ground
    graph = sp.coo_array((np.ones(a.size), (a, b)), shape=(bars + 1, bars + 1))
    return connected_components(graph, directed=False)[1]


__all__ = ["bar_groups", "bar_load_terms", "contact_forces_on_nodes", "count_up_to",
           "element_forces", "in_set", "largest", "link_forces", "load_force_scale",
           "load_force_terms", "node_set",
           "penetration", "run_ends", "run_starts", "seen_stiffness", "segment_reduce", "spread",
           "wall_arrays"]
