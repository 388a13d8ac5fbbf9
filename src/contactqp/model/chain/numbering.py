"""A scene laid out as one chain of nodes: the numbering and the per-element and per-node
arrays every later stage reads (the model, the methods' helpers, the check, the reference and
the charts), computed once per scene.

The nodes of every bar are numbered in one sequence, bar after bar (:meth:`Layout.node`); no
element joins the last node of one bar to the first node of the next, so the chain has a
*junction* there (no element, zero stiffness). Contact rows: one per wall in scene order, then
one per bar contact, each written sign·u_node <= gap (a wall) or u_a − u_b <= gap (a bar
contact), with λ >= 0 the force with which the wall (the other bar) pushes.

What is computed from the numbering and these arrays (forces along the chain, seen stiffness,
the force scales, bar grouping) is :mod:`contactqp.model.chain.derived`'s.
"""

from __future__ import annotations

import weakref
from functools import cached_property
from typing import NamedTuple

import numpy as np

from contactqp.feasibility import tight_cycles
from contactqp.model.chain.arrays import SolvingArrays
from contactqp.model.chain.derived import (
    _read_only,
)
from contactqp.scene import Scene  # the numbering reads a scene; a scene knows none
from contactqp.scene.scene import NUMBERING, detached


class ContactRows(NamedTuple):
    """The contact rows C u <= g as (row, node, coefficient) of every nonzero of C in global
    node numbering (a wall has one, a bar contact two: +1 at a, −1 at b), and g per row."""

    row: np.ndarray
    node: np.ndarray
    coefficient: np.ndarray
    gap: np.ndarray


# The Layout's arrays that depend on the bars, the supports and where the loads and contacts
# sit, but not on the load values or the gaps: shared by Layout.with_values
TOPOLOGY = ("node_offsets", "node_bar", "bar_ends", "elements", "element_position",
            "element_bar_ends", "opposed_entries", "support_mask", "junctions",
            "element_stiffness", "areas", "yield_stress", "compliance", "chained_compliance",
            "link_compliance", "link_stiffness", "node_x", "support_nodes", "load_nodes",
            "longest_bar", "row_compliance", "row_bars", "floating_bars", "wall_nodes_by_side",
            "held_cache", "softest", "outside_nodes", "support_sides")


# ... and those that depend on the gaps but not on the load values: shared when only the
# load values change
SAME_GAPS = ("rows", "walls_by_side", "press_fit_forces", "press_fit_force")


def _gaps(scene: Scene) -> np.ndarray:
    """g, the gap of every contact row: the walls, then the bar contacts."""
    contacts = np.fromiter((c.gap for c in scene.contacts), float, len(scene.contacts))
    return np.concatenate((_wall_columns(scene.walls)[3], contacts))


def _wall_columns(walls) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(bar, node, sign, gap) of every wall: the arrays of a
    :class:`~contactqp.scene.Walls`, else read from the Wall objects one by one."""
    if not isinstance(walls, tuple):  # a Walls: its arrays, no object per wall
        return walls.bars, walls.nodes, walls.signs, walls.gaps
    n = len(walls)
    plus = np.fromiter((w.side == "+" for w in walls), dtype=bool, count=n)
    return (np.fromiter((w.bar for w in walls), np.intp, n),
            np.fromiter((w.node for w in walls), np.intp, n),
            np.where(plus, 1.0, -1.0), np.fromiter((w.gap for w in walls), float, n))


class Layout(SolvingArrays):
    """The numbering of a scene's nodes and the arrays along it (module docstring).

    Parameters
    ----------
    scene : Scene
        The scene to number.
    """

    def __init__(self, scene: Scene) -> None:
        self.__dict__["_source"] = scene
        self.__dict__["_origin"] = None

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"a Layout does not change: cannot assign {name!r}")

    def __repr__(self) -> str:
        return f"Layout({self.scene!r})"

    def __reduce__(self) -> tuple:
        """Pickled as a layout of its scene's detached copy (a weak reference is not pickled;
        the arrays are made again where read)."""
        return (Layout, (self._source,))

    @classmethod
    def kept_by(cls, scene: Scene) -> Layout:
        """The layout ``scene`` keeps (:func:`layout_of`): it holds the scene weakly, and the
        scene's detached copy (:func:`contactqp.scene.scene.detached`) for when the scene is
        gone, so that the two do not hold each other."""
        layout = cls(detached(scene))
        layout.__dict__["_origin"] = weakref.ref(scene)
        return layout

    @property
    def scene(self) -> Scene:
        """The scene numbered: the object itself while anything holds it, else its detached
        copy (the same parts)."""
        scene = None if self._origin is None else self._origin()
        return self._source if scene is None else scene

    def with_values(self, scene: Scene) -> Layout:
        """The layout of ``scene``, which differs from this one's only in its load values and
        gaps (:meth:`Scene.with_values`): every array that does not depend on them
        (:data:`TOPOLOGY`, and the contact rows but their gaps) is shared, not made again."""
        layout = Layout.kept_by(scene)
        for name in TOPOLOGY:
            if name in self.__dict__:
                layout.__dict__[name] = self.__dict__[name]
        same_gaps = scene.walls is self.scene.walls and scene.contacts is self.scene.contacts
        for name in SAME_GAPS if same_gaps else ():  # new loads alone: made here once, so
            layout.__dict__[name] = getattr(self, name)  # that every later layout shares them
        if "rows" in self.__dict__ and not same_gaps:
            layout.__dict__["rows"] = self.rows._replace(gap=_read_only(_gaps(scene)))
        return layout

    @cached_property
    def node_offsets(self) -> np.ndarray:
        """Global number of each bar's node 0, and the total node count last."""
        return np.concatenate(([0], np.cumsum([b.n_nodes for b in self.scene.bars])))

    def node(self, bar: int, node: int) -> int:
        """The number of node ``node`` of bar ``bar`` in the one node sequence."""
        return int(self.node_offsets[bar]) + int(node)

    def bar_of(self, nodes: np.ndarray) -> np.ndarray:
        """The bar of each of ``nodes`` (global)."""
        if len(self.scene.bars) == 1:
            return np.zeros(np.shape(nodes), dtype=np.intp)
        return self.node_bar[nodes]

    @cached_property
    def row_bars(self) -> tuple[np.ndarray, np.ndarray]:
        """Per contact row, (the bar it stops moving in +x, the bar it stops moving in −x),
        −1 for the ground (a wall's fixed side): a "+" wall on bar w is (w, −1), a "−" wall
        (−1, w), a bar contact from a to b (a, b) (u_a − u_b <= g stops a moving towards b in
        +x, and b towards a in −x)."""
        contacts = self.scene.contacts
        bars, _, signs, _ = _wall_columns(self.scene.walls)
        ahead = np.concatenate((np.where(signs > 0, bars, -1),
                                np.array([c.bar_a for c in contacts], dtype=np.intp)))
        behind = np.concatenate((np.where(signs < 0, bars, -1),
                                 np.array([c.bar_b for c in contacts], dtype=np.intp)))
        return _read_only(ahead.astype(np.intp)), _read_only(behind.astype(np.intp))

    @cached_property
    def bar_loads(self) -> np.ndarray:
        """The net load on each bar (N, +x): its nodal loads summed."""
        return np.add.reduceat(self.nodal_loads, self.node_offsets[:-1])

    @cached_property
    def node_bar(self) -> np.ndarray:
        """The bar of every global node."""
        return _read_only(np.repeat(np.arange(len(self.scene.bars)), np.diff(self.node_offsets)))

    @cached_property
    def bar_ends(self) -> tuple[np.ndarray, np.ndarray]:
        """(first node, last node) of every global node's bar."""
        sizes = np.diff(self.node_offsets)
        return (_read_only(np.repeat(self.node_offsets[:-1], sizes)),
                _read_only(np.repeat(self.node_offsets[1:] - 1, sizes)))

    @cached_property
    def elements(self) -> tuple[np.ndarray, np.ndarray]:
        """(the links that are elements, as the global node each starts at; their
        compliance 1/k): every link but the junctions between bars."""
        element = np.flatnonzero(self.link_stiffness > 0.0)
        return _read_only(element), _read_only(1.0 / self.link_stiffness[element])

    @cached_property
    def element_position(self) -> np.ndarray:
        """For every global node j, the index in :attr:`elements` of the first element
        starting at or after j (np.searchsorted, once per scene)."""
        return _read_only(np.searchsorted(self.elements[0], np.arange(self.n_nodes)))

    @cached_property
    def element_bar_ends(self) -> tuple[np.ndarray, np.ndarray]:
        """(first node, last node) of the bar of every element (:attr:`elements`)."""
        element = self.elements[0]
        return _read_only(self.bar_ends[0][element]), _read_only(self.bar_ends[1][element])

    @cached_property
    def opposed_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The entries of C that act alone on a free node (a wall, or a bar contact with its
        other end at a support), at the nodes that have such entries pushing both ways: (nodes
        and rows pushing in −x, nodes and rows pushing in +x), each node given by its place
        among those nodes (so that a sum per node needs no array over the chain)."""
        rows, nodes, coefficients, gaps = self.rows
        free = ~self.support_mask[nodes]
        single = free & (np.bincount(rows[free], minlength=gaps.size)[rows] == 1)
        up, down = single & (coefficients > 0), single & (coefficients < 0)
        both = np.zeros(self.n_nodes, dtype=bool)
        both[nodes[up]] = True
        both &= np.bincount(nodes[down], minlength=self.n_nodes) > 0
        up &= both[nodes]
        down &= both[nodes]
        place = np.cumsum(both) - 1  # each node's place among the nodes pushed both ways
        return (_read_only(place[nodes[up]]), _read_only(rows[up]),
                _read_only(place[nodes[down]]), _read_only(rows[down]))

    @cached_property
    def support_mask(self) -> np.ndarray:
        """Whether each global node is held by a support."""
        mask = np.zeros(self.n_nodes, dtype=bool)
        mask[self.support_nodes] = True
        return _read_only(mask)

    @property
    def n_nodes(self) -> int:
        return int(self.node_offsets[-1])

    @property
    def n_elements(self) -> int:
        return self.n_nodes - len(self.scene.bars)

    @property
    def n_contacts(self) -> int:
        return self.scene.n_contacts

    @cached_property
    def junctions(self) -> np.ndarray:
        """Links j (between global nodes j and j + 1) that no element spans: a bar's last
        node and the next bar's first."""
        return self.node_offsets[1:-1] - 1

    def _per_element(self, values: list[np.ndarray]) -> np.ndarray:
        return _read_only(np.concatenate(values))

    @cached_property
    def element_stiffness(self) -> np.ndarray:
        """k_e = E·A/L of every element, bar after bar (N/m)."""
        return self._per_element([b.element_stiffness for b in self.scene.bars])

    @cached_property
    def areas(self) -> np.ndarray:
        """Area of every element, bar after bar."""
        return self._per_element([b.areas for b in self.scene.bars])

    @cached_property
    def yield_stress(self) -> np.ndarray | None:
        """Yield stress of every element (NaN on a bar without one), None if no bar has one."""
        bars = self.scene.bars
        if all(b.yield_stress is None for b in bars):
            return None
        return self._per_element([np.full(b.n_elements, np.nan if b.yield_stress is None
                                          else b.yield_stress) for b in bars])

    @cached_property
    def longest_bar(self) -> float:
        """The length of the longest bar (m)."""
        bars = {id(b): b for b in self.scene.bars}.values()  # a bar repeated counts once
        return max(float(b.lengths.sum()) for b in bars)

    @cached_property
    def compliance(self) -> np.ndarray:
        """Σ L/(EA) from its bar's node 0 to every node (m/N), bar after bar."""
        return self._per_element([b.compliance for b in self.scene.bars])

    @cached_property
    def chained_compliance(self) -> np.ndarray:
        """φ strictly increasing over the whole chain: each bar's :attr:`compliance`, shifted
        past the bar before by twice that bar's own (no node lies between bars), for
        interpolating along the chain (:func:`spread`)."""
        totals = np.array([b.compliance[-1] for b in self.scene.bars])
        shift = np.concatenate(([0.0], np.cumsum(2.0 * totals)))[:-1]
        return _read_only(self.compliance + np.repeat(shift, np.diff(self.node_offsets)))

    @cached_property
    def link_compliance(self) -> np.ndarray:
        """1/k of the link from global node j to j + 1 (m/N), inf at a junction, and one 0
        past the last node (for sums between nodes with numpy reduceat)."""
        with np.errstate(divide="ignore"):
            return _read_only(np.append(1.0 / self.link_stiffness, 0.0))

    @cached_property
    def link_stiffness(self) -> np.ndarray:
        """The stiffness between global nodes j and j + 1 (N/m): the element's, 0 at a
        junction."""
        return _read_only(np.insert(self.element_stiffness,
                                    self.junctions - np.arange(self.junctions.size), 0.0))

    @cached_property
    def support_sides(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """Per side of the supports (left, right): (each support's link on that side, −1 where
        none: past an end or between bars; the stiffness of the links there are)."""
        nodes, k = self.support_nodes, self.link_stiffness
        sides = []
        for link in (nodes - 1, nodes):
            inside = (link >= 0) & (link < k.size)
            inside[inside] = k[link[inside]] > 0.0
            sides.append((_read_only(np.where(inside, link, -1)), _read_only(k[link[inside]])))
        return tuple(sides)

    @cached_property
    def node_x(self) -> np.ndarray:
        """x of every node, for drawing: each bar starts where the one before ends."""
        xs, start = [], 0.0
        for b in self.scene.bars:
            xs.append(start + b.node_x)
            start = float(xs[-1][-1])
        return _read_only(np.concatenate(xs))

    @cached_property
    def floating_bars(self) -> np.ndarray:
        """The bars with no support, held only by their walls and bar contacts (K is then
        only positive semidefinite: each such bar can move as a whole), in order."""
        supported = np.zeros(len(self.scene.bars), dtype=bool)
        supported[self.node_bar[self.support_nodes]] = True
        return _read_only(np.flatnonzero(~supported))

    @cached_property
    def support_nodes(self) -> np.ndarray:
        """Global node of each support, in scene order."""
        return _read_only(np.array([self.node(s.bar, s.node) for s in self.scene.supports],
                                   dtype=np.intp))

    @cached_property
    def load_nodes(self) -> np.ndarray:
        """Global node of each point load, in scene order."""
        return _read_only(np.array([self.node(p.bar, p.node) for p in self.scene.loads],
                                   dtype=np.intp))

    @cached_property
    def rows(self) -> ContactRows:
        """The contact rows (:class:`ContactRows`)."""
        contacts = self.scene.contacts
        n_contacts = len(contacts)
        offsets = self.node_offsets

        def column(name: str) -> np.ndarray:
            return np.fromiter((getattr(c, name) for c in contacts), np.intp, n_contacts)

        wall_bars, wall_nodes, signs, _ = _wall_columns(self.scene.walls)
        n_walls = wall_nodes.size
        wall_nodes = offsets[wall_bars] + wall_nodes
        a = offsets[column("bar_a")] + column("node_a")
        b = offsets[column("bar_b")] + column("node_b")
        return ContactRows(
            _read_only(np.concatenate((np.arange(n_walls), n_walls + np.arange(n_contacts),
                                       n_walls + np.arange(n_contacts))).astype(np.intp)),
            _read_only(np.concatenate((wall_nodes, a, b)).astype(np.intp)),
            _read_only(np.concatenate((signs, np.ones(n_contacts), -np.ones(n_contacts)))),
            _read_only(_gaps(self.scene)))

    @property
    def by_entry(self) -> np.ndarray | slice:
        """The index that reads a value per row at each entry of :attr:`rows` (``x[by_entry]``
        is ``x[rows.row]``): with no bar contact each wall is one entry, in row order, and
        the index is a slice (a view, no copy over 10⁵ rows)."""
        return self.rows.row if self.scene.contacts else slice(None)

    @property
    def gaps(self) -> np.ndarray:
        """g: the gap of every contact row."""
        return self.rows.gap

    @cached_property
    def distributed_nodal_loads(self) -> np.ndarray:
        """The distributed loads' consistent nodal forces per global node (N): each element
        passes intensity × length / 2 to each of its two nodes."""
        p = np.zeros(self.n_nodes)
        for q in self.scene.distributed:
            bar = self.scene.bars[q.bar]
            stop = bar.n_elements if q.stop is None else q.stop
            half = 0.5 * float(q.intensity) * bar.lengths[q.start:stop]
            first = self.node(q.bar, q.start)
            p[first:first + half.size] += half
            p[first + 1:first + 1 + half.size] += half
        return _read_only(p)

    @cached_property
    def nodal_loads(self) -> np.ndarray:
        """The point loads and the distributed loads' nodal forces summed per global node (N)."""
        if not self.scene.distributed:  # the same sums, in the same order, from zero
            return _read_only(np.asarray(np.bincount(  # (no loads: integer zeros)
                self.load_nodes, self.scene.load_forces, minlength=self.n_nodes), dtype=float))
        p = self.distributed_nodal_loads.copy()
        np.add.at(p, self.load_nodes, self.scene.load_forces)  # ~0.1 µs a load
        return _read_only(p)

    def load_point(self) -> int:
        """The global node whose displacement a load path follows: the first point load's
        node, else the node with the largest nodal load."""
        if self.scene.loads:
            return int(self.load_nodes[0])
        return int(np.abs(self.nodal_loads).argmax())

    @cached_property
    def tight_cycles(self) -> tuple[tuple[int, ...], ...]:
        """The contact rows of every one-way loop through a bar contact whose gaps add up to
        zero (:func:`contactqp.feasibility.tight_cycles`)."""
        return tight_cycles(self.scene)


def layout_of(scene: Scene) -> Layout:
    """The :class:`Layout` of ``scene``, made once and kept with it (a scene does not change;
    :meth:`Scene.with_values` hands a scene with other values the numbering it shares)."""
    layout = scene.__dict__.get("layout")
    if layout is None:
        layout = scene.__dict__["layout"] = Layout.kept_by(scene)
    return layout


NUMBERING.append(layout_of)  # Scene.layout, without the scene importing the numbering
