"""What the check (contactqp.check.chain.certificate) works out along the chain: the runs of elements between
held nodes (:class:`Runs`), the stiffness each contact row sees with those nodes held, the
running sum of the outside forces (:class:`Running`), and what an answer's imbalance does
run by run with the held nodes fixed (:func:`propagate`).

The runs and the stiffnesses depend on the held nodes, the bars and the stiffnesses alone,
never on the load values, the gaps or the answer's values, so they are kept on the layout
(:attr:`contactqp.model.chain.layout_names.Layout.held_cache`, shared by the layouts of one prepared scene) for
the last few held sets: a scene solved again, ``prepared.solve`` and ``solve_many`` meet the
same sets again and again. What is kept is what would be computed, bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from contactqp.model import (
    LONG_SEGMENTS,
    Layout,
    count_up_to,
    largest,
    node_set,
    segment_reduce,
)

LONG_RUNS = LONG_SEGMENTS  # runs reduced one by one where at most one in this many is long
SHORT_RUNS = 16  # runs of the same length up to this are reduced one element at a time
KEPT_BYTES = 2**27  # what a layout keeps at most (128 MB; the oldest sets dropped first)
# propagate goes run by run where at most this many runs can sway (or one in LONG_RUNS): a
# run of one element held at both ends moves no node
FEW_SWAYING = 16
FEW_HELD = 64  # held sets up to this size are found by their bytes (a small scene's check
# asks for several kept sets, and summing and comparing cost 10-20 µs of its ~250)


def kept(layout: Layout, kind: Any, held: np.ndarray, make: Callable[[], Any]) -> Any:
    """``make()`` for the ``held`` nodes (sorted) and ``kind`` (anything else it depends on),
    or what it gave for the same before. A few nodes are found by their bytes; more by (kind,
    size, sum), confirmed element by element, so that a long held set is never hashed whole.
    What is kept is read-only."""
    cache = layout.held_cache
    if held.size <= FEW_HELD:  # the nodes' bytes are the key: no sum, no confirming
        key = (kind, held.dtype.str, held.tobytes())
        found = cache.get(key)
        if found is not None:
            return found[1]
    else:
        key = (kind, held.size, int(held.sum()))
        found = cache.get(key)
        if found is not None and np.array_equal(found[0], held):
            return found[1]
    value = make()
    size = held.nbytes + sum(a.nbytes for a in _arrays(value))
    while cache and sum(entry[2] for entry in cache.values()) + size > KEPT_BYTES:
        cache.pop(next(iter(cache)))
    if size <= KEPT_BYTES:
        cache[key] = (held.copy(), value, size)
    return value


def _arrays(value: Any) -> list[np.ndarray]:
    items = value.__dict__.values() if hasattr(value, "__dict__") else value
    return [item for item in items if isinstance(item, np.ndarray)]


@dataclass(frozen=True)
class Runs:
    """The runs of elements between held nodes in one bar (indices in
    :attr:`Layout.elements`): each run's first element and one past its last, whether it is
    held at its left and right end, its bar's first and last node, the sum of its
    compliances; and for each held node, the run just left and just right of it (−1 none)
    and its bar's first and last node."""

    starts: np.ndarray
    ends: np.ndarray
    left_held: np.ndarray
    right_held: np.ndarray
    first: np.ndarray
    last: np.ndarray
    compliance: np.ndarray
    run_of: np.ndarray
    held_start: np.ndarray
    held_end: np.ndarray
    at_first: np.ndarray  # the held nodes (places in held) that are their bar's first node
    at_last: np.ndarray  # ... and its last node
    first_links: np.ndarray  # each run's first element as a link (Layout.elements[0])
    long: np.ndarray  # the runs of more than one element
    swaying: np.ndarray  # the runs whose inner nodes can move: long, or held at one end only
    length: int  # the length of every run, where LONG_RUNS or more have one length (else 0)

    def reduce(self, ufunc: np.ufunc, values: np.ndarray) -> np.ndarray:
        """``ufunc.reduceat(values, starts)``: per run, over its elements. Where nearly every
        run is one element (a pressed patch: 9.5·10⁴ runs, one long), those are the values
        themselves and only the long runs are reduced, each by the same reduceat over its
        slice; where every run has the same few elements (a batch of cases: 10⁴ runs of 4),
        np.maximum and np.minimum go one element of every run at a time (reduceat: 0.18 ms,
        this: 0.02 ms; a sum is left to reduceat, which adds in another order). The same
        numbers bit for bit."""
        if 1 < self.length <= SHORT_RUNS and ufunc in (np.maximum, np.minimum):
            out = values[:: self.length].copy()
            for i in range(1, self.length):
                ufunc(out, values[i:: self.length], out=out)
            return out
        return segment_reduce(ufunc, values, self.starts, self.ends, self.long)


def runs(layout: Layout, held: np.ndarray) -> Runs:
    """The :class:`Runs` of the ``held`` nodes (sorted, at least one), kept per held set."""
    return kept(layout, "runs", held, lambda: _runs(layout, held))


def _runs(layout: Layout, held: np.ndarray) -> Runs:
    element, compliance = layout.elements
    starts = _run_first_elements(layout, held)
    ends = np.append(starts[1:], element.size)
    # per run: is it held at its left end, at its right end (a held node in its own bar)
    count = count_at_or_before(layout.n_nodes, held, element[starts])  # held up to its start
    first, last = layout.element_bar_ends[0][starts], layout.element_bar_ends[1][starts]
    left_held = (count > 0) & (held[np.maximum(count - 1, 0)] >= first)
    right_held = (count < held.size) & (held[np.minimum(count, held.size - 1)] <= last)
    at = layout.element_position[np.concatenate((held - 1, held)).clip(0, element[-1])]
    run_of = count_at_or_before(element.size, starts, np.minimum(at, element.size - 1)) - 1
    lengths = ends - starts
    held_start, held_end = layout.bar_ends[0][held], layout.bar_ends[1][held]
    made = Runs(starts, ends, left_held, right_held, first, last,
                np.add.reduceat(compliance, starts), run_of, held_start, held_end,
                np.flatnonzero(held <= held_start), np.flatnonzero(held >= held_end),
                element[starts], np.flatnonzero(lengths > 1),
                np.flatnonzero((lengths > 1) | ~(left_held & right_held)),
                int(lengths[0]) if starts.size >= LONG_RUNS and np.all(lengths == lengths[0])
                else 0)
    for array in _arrays(made):
        array.flags.writeable = False
    return made


def _run_first_elements(layout: Layout, held: np.ndarray) -> np.ndarray:
    """The first element (index in :attr:`Layout.elements`) of every run of elements between
    held nodes in one bar: element 0, each bar's first and each element that starts at a held
    node. From the held nodes alone, with no pass over the chain when they are few."""
    n = layout.elements[0].size
    firsts = layout.element_position[layout.node_offsets[:-1]]
    marks = layout.element_position[held]  # n for a node past the last element
    starts = node_set(n + 1, [0], firsts, marks)
    return starts[:-1] if starts[-1] == n else starts


def count_at_or_before(n_nodes: int, held: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """np.searchsorted(held, nodes, side="right") for node numbers (``held`` sorted,
    distinct): by one running count over the chain when ``nodes`` are many."""
    if 8 * np.size(nodes) <= n_nodes:
        return np.searchsorted(held, nodes, side="right")
    mask = np.zeros(n_nodes, dtype=bool)
    mask[held] = True
    return count_up_to(mask)[nodes]


@dataclass(frozen=True)
class Running:
    """E_j, the running sum of the outside forces over the nodes 0..j: at every node
    (``steps`` None, ``levels`` E_j), or, where few nodes are loaded, as its steps (the
    loaded nodes, sorted, and E from each of them on; 0 before the first), so that the
    check makes no array over the chain for it (one wall on 10⁶ elements: two passes and two
    arrays of 8 MB fewer). Both give the same numbers bit for bit: the sum over the nodes in
    between adds exact zeros."""

    steps: np.ndarray | None
    levels: np.ndarray

    @classmethod
    def of(cls, n_nodes: int, nodes: np.ndarray, forces: np.ndarray) -> Running:
        """The running sum of ``forces`` at ``nodes`` (a node may repeat)."""
        if 8 * nodes.size > n_nodes:  # summed in place: no second array over the chain
            total = np.bincount(nodes, forces, minlength=n_nodes)
            return cls(None, np.cumsum(total, out=total))
        steps, inverse = np.unique(nodes, return_inverse=True)
        return cls(steps, np.cumsum(np.bincount(inverse.reshape(-1), forces,
                                                minlength=steps.size)))

    def at(self, nodes: np.ndarray | int) -> np.ndarray:
        """E at ``nodes``."""
        if self.steps is None:
            return self.levels[nodes]
        step = np.searchsorted(self.steps, nodes, side="right") - 1
        return np.where(step >= 0, self.levels[np.maximum(step, 0)], 0.0)

    def plus(self, links: np.ndarray, lo: int = 0, hi: int | None = None) -> np.ndarray:
        """links_j + E_j for the links j = lo … hi − 1 (every link by default; a new array)."""
        hi = links.size if hi is None else hi
        if self.steps is None:
            return links[lo:hi] + self.levels[lo:hi]
        total = np.empty(hi - lo)
        bounds = np.concatenate(([lo], np.clip(self.steps, lo, hi), [hi]))
        levels = np.concatenate(([0.0], self.levels))
        for level, a, b in zip(levels.tolist(), bounds[:-1].tolist(), bounds[1:].tolist()):
            if a < b:
                np.add(links[a:b], level, out=total[a - lo:b - lo])
        return total


def propagate(layout: Layout, held: np.ndarray, links: np.ndarray,
              outside: Running) -> tuple[float, float, np.ndarray]:
    """What the imbalance of an answer does with the ``held`` nodes (sorted) fixed: (the
    largest force error at a held node, N; the largest displacement error, m; the force
    error at each held node, N).

    r_j, the residual of cut j (element force from u against ``outside``, the running sum of
    the outside forces over the nodes up to the cut), is a load pattern: its jumps are the
    nodal imbalances. Between two held nodes the exact answer of the imbalanced scene has
    element forces N_j − (c − r_j), i.e. its element force errors are c − r_j, with c such
    that the run's elongation errors (c − r_j)/k_j add up to nothing; a run held at one end
    only (a bar's tail or head) has c the cut residual past the bar's free end. The
    displacement error is the running sum of the elongation errors from the held end, and a
    held node's force error is the jump of c across it."""
    element, compliance = layout.elements
    if element.size == 0:
        return 0.0, 0.0, np.zeros(held.size)
    if held.size == 0:  # bars with no support, and nothing in the answer holds them
        return np.inf, np.inf, np.zeros(0)
    run = runs(layout, held)
    if run.swaying.size <= max(FEW_SWAYING, run.starts.size // LONG_RUNS):
        return _few_swaying(layout, held, links, outside, run)
    r = outside.plus(links)
    if element.size != r.size:  # junctions between bars: not every link is an element
        r = r[element]
    c_run = _run_levels(r, compliance, outside, run)
    sway = _sway(r, compliance, c_run, run)  # r reused there
    del r
    jumps = _held_jumps(held, c_run, outside, run)
    return largest(jumps), sway, jumps


# The helpers below work in place and drop what they no longer read: every array of a chain's
# length is a fresh allocation, whose pages cost a fault each on first touch (about 2 µs on
# the benchmark's VM, where a pressed patch's check took 4 000 faults a solve)


def _run_levels(r: np.ndarray, compliance: np.ndarray, outside: Running, run: Runs
                ) -> np.ndarray:
    """c per run (:func:`propagate`): the weighted mean of r over the run where it is held
    at both ends, the free end's cut residual otherwise."""
    weighted = r * compliance
    c = run.reduce(np.add, weighted)
    del weighted
    c /= run.compliance  # the mean (held at both ends)
    np.copyto(c, _free_end_levels(outside, run), where=~(run.left_held & run.right_held))
    return c


def _free_end_levels(outside: Running, run: Runs, index: Any = slice(None)) -> np.ndarray:
    """c of the runs ``index`` as if held at one end only: the cut residual past the bar's
    head where held at the left end, before the bar's tail otherwise (a new array)."""
    first, left_held = run.first[index], run.left_held[index]
    after_bar = outside.at(run.last[index])  # held at the left end only: past the bar's head
    before_bar = outside.at(np.maximum(first - 1, 0))  # ... at the right end only
    before_bar[first <= 0] = 0.0
    np.copyto(after_bar, before_bar, where=~left_held)
    return after_bar


def _few_swaying(layout: Layout, held: np.ndarray, links: np.ndarray, outside: Running,
                 run: Runs) -> tuple[float, float, np.ndarray]:
    """:func:`propagate` where few runs can sway (a pressed patch: 9.5·10⁴ runs, one long;
    one wall on a bar: one run), run by run over those alone. A run of one element held at
    both ends has c = r there, the mean of one value, and moves no node: r at each run's
    first element is every such c."""
    element, compliance = layout.elements
    first = run.first_links
    c_run = np.add(links[first], outside.at(first))
    sway = 0.0
    free_end = _free_end_levels(outside, run, run.swaying).tolist()
    for i, a, b, c in zip(run.swaying.tolist(), run.starts[run.swaying].tolist(),
                          run.ends[run.swaying].tolist(), free_end):
        # a run lies in one bar (runs start at every bar's first element): its elements are
        # the links lo … hi − 1, in order
        lo, hi = int(element[a]), int(element[b - 1]) + 1
        left = bool(run.left_held[i])
        r = outside.plus(links, lo, hi)
        if left and run.right_held[i]:  # the weighted mean of r, in one pass
            c = float(np.dot(r, compliance[a:b])) / float(run.compliance[i])
        c_run[i] = c
        sway = max(sway, _run_sway(r, compliance[a:b], c, left))
    jumps = _held_jumps(held, c_run, outside, run)
    return largest(jumps), sway, jumps


def _run_sway(r: np.ndarray, compliance: np.ndarray, c: float, left_held: bool) -> float:
    """:func:`_sway` for one run (``r`` overwritten): the running sum of its elongation
    errors from its start, the largest distance from the held end."""
    elongation = np.subtract(c, r, out=r)
    elongation *= compliance
    total = np.cumsum(elongation, out=elongation)
    top, bottom, tail = float(total.max()), float(total.min()), float(total[-1])
    if left_held:
        return max(abs(top), abs(bottom))
    return max(abs(tail - top), abs(tail - bottom), abs(tail))


def _held_jumps(held: np.ndarray, c_run: np.ndarray, outside: Running, run: Runs
                ) -> np.ndarray:
    """The force error at each held node (:func:`propagate`): the jump of c between the
    elements on either side of it (past a bar's end, the cut residual there)."""
    c_left, c_right = c_run[run.run_of[: held.size]], c_run[run.run_of[held.size:]]
    if run.at_first.size:  # no run before a bar's first node: the cut residual before it
        start = run.held_start[run.at_first]
        c_left[run.at_first] = np.where(start > 0, outside.at(np.maximum(start - 1, 0)), 0.0)
    if run.at_last.size:  # ... and past its last
        c_right[run.at_last] = outside.at(run.held_end[run.at_last])
    return np.subtract(c_left, c_right, out=c_left)


def _sway(r: np.ndarray, compliance: np.ndarray, c_run: np.ndarray, run: Runs) -> float:
    """The largest displacement error (m) of :func:`propagate` (``r`` is overwritten): element
    e of a run stretches
    by (c − r_e)/k_e too much, and the nodes move by the running sum of that from the run's
    held end. The running sum over the chain once; per run only its largest and smallest
    value, since |x − a| over a run is largest at one of them (x − a is monotone in x, in
    floating point too)."""
    starts, ends = run.starts, run.ends
    c = c_run[0] if c_run.size == 1 else np.repeat(c_run, ends - starts)
    # in r's own array (the caller's r is not read again): no new array over the chain
    elongation = np.subtract(c, r, out=r)
    del c
    elongation *= compliance
    base = -elongation[starts]
    total = np.cumsum(elongation, out=elongation)
    base += total[starts]  # the sum before each run
    tail = total[ends - 1]  # ... and to its end
    top, bottom = run.reduce(np.maximum, total), run.reduce(np.minimum, total)
    # held at the left end: the nodes move by total − base; held only at the right end (a
    # bar's free head): by tail − (the sum before each element), base included and the run's
    # last value tail itself moving by 0
    from_left = np.subtract(top, base)
    np.abs(from_left, out=from_left)
    distance = np.subtract(bottom, base)
    np.maximum(from_left, np.abs(distance, out=distance), out=from_left)
    del distance
    # from_right, in top's own array: max(|tail − top|, |tail − bottom|, |tail − base|)
    from_right = np.abs(np.subtract(tail, top, out=top), out=top)
    np.maximum(from_right, np.abs(np.subtract(tail, bottom, out=bottom), out=bottom),
               out=from_right)
    np.maximum(from_right, np.abs(np.subtract(tail, base, out=base), out=base),
               out=from_right)
    np.copyto(from_right, from_left, where=run.left_held)
    return largest(from_right)


__all__ = ["KEPT_BYTES", "Running", "Runs", "count_at_or_before", "kept", "propagate", "runs"]
