"""What the user describes: elastic bars, their supports, point and distributed loads, rigid
walls and contacts between bars.

Units are SI throughout: m, m², N, Pa. Each bar numbers its nodes 0..n along +x; element e
joins its nodes e and e + 1; supports, loads and walls name a bar (default 0) and a node of
it. The algebra numbers every node of every bar in one sequence, bar after bar
(:meth:`Scene.global_node`); no element joins the last node of one bar to the first of the
next. Every value is checked when the scene is built, and an error names the field (as it is
spelled in the TOML file) and the value.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

import numpy as np

from contactqp.errors import SceneError

AreaRule = Literal["midpoint", "exact"]
WallSide = Literal["+", "-"]
AREA_RULES = ("midpoint", "exact")
WALL_SIDES = ("+", "-")


@dataclass(frozen=True)
class Units:
    """A consistent unit system (force = stress × area, stiffness = force / length): the
    names of its units, and the size of its length and stress units in SI (m, Pa). Every
    number of a scene is in its units, and so is every answer: the algebra needs no
    conversion."""

    name: str
    length: str
    area: str
    force: str
    stress: str
    metre: float  # one length unit, in m
    pascal: float  # one stress unit, in Pa

    @property
    def stiffness(self) -> str:
        """The unit of a stiffness (and of a distributed load): force per length."""
        return f"{self.force}/{self.length}"


UNIT_SYSTEMS = {
    "SI": Units("SI", "m", "m²", "N", "Pa", 1.0, 1.0),
    "mm-N-MPa": Units("mm-N-MPa", "mm", "mm²", "N", "MPa", 1e-3, 1e6),
}


# Every number of a scene is 0 or between 1/MAGNITUDE and MAGNITUDE in size: then every
# product the model and the check form (stiffness E·A/L, displacement load/stiffness, energy,
# a penalty 1e8 times a stiffness) stays far inside double precision, with no overflow.
MAGNITUDE = 1e30
MAX_ELEMENTS = 10_000_000  # every element costs ~1 kB across model, solve and check


def _in_range(name: str, number: float, tiny: bool = False) -> float:
    """``number`` if it is finite and 0 or within MAGNITUDE's range, else a SceneError.
    ``tiny``: any small size will do (a gap, a load: no product of the model grows from it)."""
    if not math.isfinite(number):
        raise SceneError(f"{name} must be finite, got {number!r}")
    if abs(number) > MAGNITUDE or (not tiny and number != 0.0 and abs(number) < 1 / MAGNITUDE):
        raise SceneError(f"{name} = {number!r} is outside the range contactqp computes in "
                         f"(0, or {1 / MAGNITUDE:.0e} to {MAGNITUDE:.0e} in size; choose other "
                         "units)")
    return number


def _is_number(value: Any) -> bool:
    return not isinstance(value, (bool, np.bool_)) and isinstance(
        value, (int, float, np.integer, np.floating))


def _positive_finite_array(name: str, values: Any) -> np.ndarray:
    """Return ``values`` as a read-only float array, all finite and > 0, else a SceneError
    (strings and booleans are not numbers, even where numpy would convert them)."""
    if isinstance(values, (str, bytes)):
        raise SceneError(f"{name} must be numbers, got {values!r}")
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise SceneError(f"{name} must be numbers, got {values!r}") from None
    if raw.dtype.kind not in "iuf":
        items = values if isinstance(values, (list, tuple)) else raw.reshape(-1)
        for i, value in enumerate(items):
            if not _is_number(value):
                shown = value.item() if isinstance(value, np.generic) else value
                raise SceneError(f"{name}[{i}] must be a number, got {shown!r}")
    if raw.size > MAX_ELEMENTS:
        raise SceneError(f"{name} has {raw.size} values; contactqp takes at most "
                         f"{MAX_ELEMENTS} elements in a scene")
    array = raw.astype(float).reshape(-1)
    bad = np.flatnonzero(~np.isfinite(array) | (array <= 0.0))
    if bad.size:
        i = int(bad[0])
        raise SceneError(f"{name}[{i}] must be a positive finite number, got {float(array[i])!r}")
    for i in (int(array.argmin()), int(array.argmax())) if array.size else ():
        _in_range(f"{name}[{i}]", float(array[i]))
    array.flags.writeable = False
    return array


def _number(name: str, value: Any, *, minimum: float | None = None, strict: bool = False,
            tiny: bool = False) -> float:
    """Return ``value`` as a finite float (optionally >= or > ``minimum``), else a SceneError;
    ``tiny`` as for :func:`_in_range`."""
    if not _is_number(value):
        raise SceneError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise SceneError(f"{name} must be finite, got {number!r}")
    if minimum is not None and (number <= minimum if strict else number < minimum):
        relation = ">" if strict else ">="
        raise SceneError(f"{name} must be {relation} {minimum:g}, got {number!r}")
    return _in_range(name, number, tiny)


def _node(name: str, value: Any, n_nodes: int, owner: str = "the bar") -> int:
    """Return ``value`` as a node index of a bar with ``n_nodes`` nodes, else a SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SceneError(f"{name} must be a whole node number, got {value!r}")
    if not 0 <= value < n_nodes:
        raise SceneError(f"{name} = {value}: {owner} has nodes 0 to {n_nodes - 1}")
    return int(value)


def _bar(name: str, value: Any, n_bars: int) -> int:
    """Return ``value`` as a bar index of a scene with ``n_bars`` bars, else a SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SceneError(f"{name} must be a whole bar number, got {value!r}")
    if not 0 <= value < n_bars:
        raise SceneError(f"{name} = {value}: the scene has bars 0 to {n_bars - 1}")
    return int(value)


def circle_areas(diameters_a: np.ndarray, diameters_b: np.ndarray, rule: str) -> np.ndarray:
    """Element areas (m²) of a circular section whose diameter runs from d_a to d_b linearly.

    ``"midpoint"``: the circle at mid-length, π((d_a + d_b)/2)²/4.
    ``"exact"``: π·d_a·d_b/4, the constant area with the same axial flexibility as the cone,
    since ∫₀ᴸ dx / (E·π·d(x)²/4) = 4L / (E·π·d_a·d_b) for d linear in x.
    """
    if rule == "midpoint":
        return np.pi * (0.5 * (diameters_a + diameters_b)) ** 2 / 4.0
    if rule == "exact":
        return np.pi * diameters_a * diameters_b / 4.0
    raise SceneError(f"bar.section.area_rule must be one of {AREA_RULES}, got {rule!r}")


@dataclass(frozen=True, eq=False)
class Bar:
    """Elements between consecutive nodes, each with a length (m), area (m²) and modulus (Pa).

    Build one with :meth:`from_areas` or :meth:`tapered_circle`; the arrays are read-only.
    """

    lengths: np.ndarray
    areas: np.ndarray
    youngs_modulus: np.ndarray
    yield_stress: float | None = None

    def __post_init__(self) -> None:
        lengths = _positive_finite_array("bar.lengths", self.lengths)
        areas = _positive_finite_array("bar.areas", self.areas)
        moduli = _positive_finite_array("material.youngs_modulus", self.youngs_modulus)
        if moduli.size not in (1, areas.size):
            raise SceneError(
                f"material.youngs_modulus must be one value or one per element ({areas.size}), "
                f"got {moduli.size}"
            )
        moduli = np.broadcast_to(moduli, areas.shape)
        if lengths.size != areas.size:
            raise SceneError(
                f"bar.lengths has {lengths.size} values but bar.areas has {areas.size}: "
                "give one length per element"
            )
        if areas.size == 0:
            raise SceneError("bar must have at least one element, got 0")
        if self.yield_stress is not None:
            object.__setattr__(
                self, "yield_stress",
                _number("material.yield_stress", self.yield_stress, minimum=0.0, strict=True),
            )
        object.__setattr__(self, "lengths", lengths)
        object.__setattr__(self, "areas", areas)
        object.__setattr__(self, "youngs_modulus", moduli)

    @classmethod
    def from_areas(
        cls,
        areas: Any,
        youngs_modulus: float,
        *,
        length: float | None = None,
        lengths: Any = None,
        yield_stress: float | None = None,
    ) -> Bar:
        """A bar from explicit element areas (m²), with equal elements over ``length`` (m) or
        explicit element ``lengths`` (m)."""
        areas = _positive_finite_array("bar.areas", areas)
        if (length is None) == (lengths is None):
            raise SceneError("bar needs exactly one of length (m) or lengths (one per element)")
        if lengths is None:
            total = _number("bar.length", length, minimum=0.0, strict=True)
            lengths = np.full(areas.size, total / max(areas.size, 1))
        return cls(lengths, areas, youngs_modulus, yield_stress)

    @classmethod
    def tapered_circle(
        cls,
        length: float,
        elements: int,
        diameter_start: float,
        diameter_end: float,
        youngs_modulus: float,
        *,
        area_rule: AreaRule = "midpoint",
        yield_stress: float | None = None,
    ) -> Bar:
        """Equal elements over a circular section tapering linearly from ``diameter_start``
        at x = 0 to ``diameter_end`` at x = ``length`` (m); areas by ``area_rule``."""
        total = _number("bar.length", length, minimum=0.0, strict=True)
        if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)) or elements < 1:
            raise SceneError(f"bar.elements must be a whole number >= 1, got {elements!r}")
        if elements > MAX_ELEMENTS:
            raise SceneError(f"bar.elements = {elements}: contactqp takes at most {MAX_ELEMENTS} "
                             "elements in a scene")
        d0 = _number("bar.section.diameter_start", diameter_start, minimum=0.0, strict=True)
        d1 = _number("bar.section.diameter_end", diameter_end, minimum=0.0, strict=True)
        edges = np.linspace(d0, d1, int(elements) + 1)
        areas = circle_areas(edges[:-1], edges[1:], area_rule)
        return cls(np.full(int(elements), total / int(elements)), areas, youngs_modulus, yield_stress)

    @property
    def n_elements(self) -> int:
        return int(self.areas.size)

    @property
    def n_nodes(self) -> int:
        return self.n_elements + 1

    @cached_property
    def stiffness(self) -> np.ndarray:
        """Axial stiffness E·A/L of each element (N/m)."""
        return self.youngs_modulus * self.areas / self.lengths

    @cached_property
    def compliance_from_node_0(self) -> np.ndarray:
        """Σ L/(EA) of the elements between node 0 and each node (m/N): kept with the bar,
        so that re-solving a scene (new loads, gaps or walls) does not add it up again."""
        compliance = np.zeros(self.n_nodes)
        np.cumsum(1.0 / self.stiffness, out=compliance[1:])
        compliance.flags.writeable = False
        return compliance

    @cached_property
    def node_x(self) -> np.ndarray:
        """Undeformed x of every node (m), node 0 at x = 0."""
        return np.concatenate(([0.0], np.cumsum(self.lengths)))


@dataclass(frozen=True)
class Support:
    """A node of bar ``bar`` held at zero displacement."""

    node: int
    bar: int = 0


@dataclass(frozen=True)
class Load:
    """A point load at a node of bar ``bar`` (N, positive in +x)."""

    node: int
    force: float
    bar: int = 0


@dataclass(frozen=True)
class DistributedLoad:
    """A uniform axial load ``intensity`` (N/m, positive in +x) on elements ``start`` to
    ``stop`` − 1 of bar ``bar`` (``stop`` None: to the bar's end). Each element passes
    intensity × length / 2 to each of its nodes: the consistent load of a linear element, with
    which the nodal displacements of a bar are exact."""

    intensity: float
    bar: int = 0
    start: int = 0
    stop: int | None = None


@dataclass(frozen=True)
class BarContact:
    """Contact between node ``node_a`` of bar ``bar_a`` and node ``node_b`` of bar ``bar_b``,
    ``gap`` (m, >= 0) apart, a facing b in +x: u_a − u_b <= gap. Its force λ >= 0 pushes a
    in −x and b in +x."""

    bar_a: int
    node_a: int
    bar_b: int
    node_b: int
    gap: float


@dataclass(frozen=True)
class Wall:
    """A rigid wall at a node, ``gap`` (m) away from it on ``side``. A negative gap is an
    interference: the node starts |gap| past the wall, which pushes it back (a press fit).

    ``side="+"``: the node may not move past u = +gap; the wall can only push in -x.
    ``side="-"``: the node may not move past u = -gap; the wall can only push in +x.
    """

    node: int
    gap: float
    side: WallSide = "+"
    bar: int = 0

    @property
    def sign(self) -> float:
        """+1 for a wall on the + side, -1 for the - side: the constraint is sign·u <= gap."""
        return 1.0 if self.side == "+" else -1.0


@dataclass(frozen=True, eq=False)
class Scene:
    """Bars with supports, loads, rigid walls and bar-to-bar contacts, checked on construction.

    ``bar`` is one :class:`Bar` or a sequence of them (kept as the Bar itself when there is
    one, else as a tuple; :attr:`bars` is always the tuple). Every bar needs a support.
    Contact rows, in this order everywhere (contact forces, penetrations): one per wall, then
    one per bar contact.
    """

    bar: Bar | tuple[Bar, ...]
    supports: tuple[Support, ...]
    loads: tuple[Load, ...] = ()
    walls: tuple[Wall, ...] = ()
    name: str = "scene"
    distributed: tuple[DistributedLoad, ...] = ()
    contacts: tuple[BarContact, ...] = ()
    units: str = "SI"

    def __post_init__(self) -> None:
        bars = (self.bar,) if isinstance(self.bar, Bar) else self.bar
        if isinstance(bars, (str, bytes)) or not isinstance(bars, (tuple, list)) or not bars:
            raise SceneError(f"bar must be a contactqp.Bar or a list of them, got {self.bar!r}")
        bars = tuple(_as(Bar, b, f"bar[{i}]" if len(bars) > 1 else "bar")
                     for i, b in enumerate(bars))
        object.__setattr__(self, "bar", bars[0] if len(bars) == 1 else bars)
        supports = tuple(_as(Support, s, f"support[{i}]") for i, s in enumerate(self.supports))
        loads = tuple(_as(Load, s, f"load[{i}]") for i, s in enumerate(self.loads))
        walls = tuple(_as(Wall, s, f"wall[{i}]") for i, s in enumerate(self.walls))
        distributed = tuple(_as(DistributedLoad, s, f"distributed_load[{i}]")
                            for i, s in enumerate(self.distributed))
        contacts = tuple(_as(BarContact, s, f"contact[{i}]") for i, s in enumerate(self.contacts))
        if not supports:
            raise SceneError("support: no support holds the bar; give at least one [[support]]")
        node = self._node_checker(bars)
        held: dict[int, int] = {}
        for i, s in enumerate(supports):
            at = node(f"support[{i}]", s.bar, s.node)
            if at in held:
                raise SceneError(f"support[{i}].node = {s.node} repeats support[{held[at]}]")
            held[at] = i
        for b in sorted(set(range(len(bars))) - {s.bar for s in supports}):
            raise SceneError(f"support: bar[{b}] has no support; every bar needs one [[support]] "
                             "(a bar held only by contact can move freely)")
        if len(held) == sum(b.n_nodes for b in bars):
            raise SceneError("support: every node is a support; nothing can move")
        for i, load in enumerate(loads):
            node(f"load[{i}]", load.bar, load.node)
            _number(f"load[{i}].force", load.force, tiny=True)
        for i, q in enumerate(distributed):
            name = f"distributed_load[{i}]"
            _number(f"{name}.intensity", q.intensity, tiny=True)
            n_elements = bars[_bar(f"{name}.bar", q.bar, len(bars))].n_elements
            stop = n_elements if q.stop is None else q.stop
            for key, value in (("start", q.start), ("stop", stop)):
                if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                    raise SceneError(f"{name}.{key} must be a whole element number, got {value!r}")
            if not 0 <= q.start < stop <= n_elements:
                raise SceneError(f"{name}: elements start = {q.start} to stop = {stop} (exclusive) "
                                 f"must satisfy 0 <= start < stop <= {n_elements}")
        seen: dict[tuple[int, str], int] = {}
        for i, wall in enumerate(walls):
            at = node(f"wall[{i}]", wall.bar, wall.node)
            _number(f"wall[{i}].gap", wall.gap, tiny=True)
            if wall.side not in WALL_SIDES:
                raise SceneError(f"wall[{i}].side must be '+' or '-', got {wall.side!r}")
            if at in held:
                raise SceneError(
                    f"wall[{i}].node = {wall.node} is support[{held[at]}]: a wall there carries no force"
                )
            if (at, wall.side) in seen:
                raise SceneError(
                    f"wall[{i}] repeats wall[{seen[at, wall.side]}] (node {wall.node}, side "
                    f"{wall.side!r}): keep the one with the smaller gap"
                )
            seen[at, wall.side] = i
        pairs: dict[tuple[int, int], int] = {}
        for i, c in enumerate(contacts):
            a = node(f"contact[{i}]", c.bar_a, c.node_a, suffix="_a")
            b = node(f"contact[{i}]", c.bar_b, c.node_b, suffix="_b")
            _number(f"contact[{i}].gap", c.gap, minimum=0.0, tiny=True)
            if a == b:
                raise SceneError(f"contact[{i}]: node_a and node_b are the same node")
            if a in held and b in held:
                raise SceneError(f"contact[{i}]: both nodes are supports; the contact carries no force")
            if (a, b) in pairs:
                raise SceneError(f"contact[{i}] repeats contact[{pairs[a, b]}]: keep the one with "
                                 "the smaller gap")
            pairs[a, b] = i
            if a in held or b in held:  # one end held: a wall on the other end
                free, side = (b, "-") if a in held else (a, "+")
                if (free, side) in seen:
                    raise SceneError(
                        f"contact[{i}] holds its free end like a {side!r} wall (its other end is "
                        f"a support) and repeats wall[{seen[free, side]}]: keep the one with the "
                        "smaller gap")
        object.__setattr__(self, "supports", supports)
        object.__setattr__(self, "loads", loads)
        object.__setattr__(self, "walls", walls)
        object.__setattr__(self, "distributed", distributed)
        object.__setattr__(self, "contacts", contacts)
        if not isinstance(self.name, str):
            raise SceneError(f"name must be text, got {self.name!r}")
        if self.units not in UNIT_SYSTEMS:
            raise SceneError(f"units must be one of {', '.join(map(repr, UNIT_SYSTEMS))}, "
                             f"got {self.units!r}")
        if sum(b.n_elements for b in bars) > MAX_ELEMENTS:
            raise SceneError(f"bar: {sum(b.n_elements for b in bars)} elements in all; contactqp "
                             f"takes at most {MAX_ELEMENTS} in a scene")
        conflict = impossible_constraints(self) or indeterminate_contacts(self)
        if conflict:
            raise SceneError(conflict)

    @cached_property
    def tight_cycles(self) -> tuple[tuple[int, ...], ...]:
        """The contact rows of every zero-weight loop through a bar contact
        (:func:`tight_cycles`)."""
        return tight_cycles(self)

    @property
    def unit(self) -> Units:
        """The scene's unit system (:data:`UNIT_SYSTEMS`)."""
        return UNIT_SYSTEMS[self.units]

    @staticmethod
    def _node_checker(bars: tuple[Bar, ...]):
        """A function (field name, bar, node) -> global node number, or a SceneError."""
        offsets = np.concatenate(([0], np.cumsum([b.n_nodes for b in bars])))

        def node(name: str, bar: Any, value: Any, suffix: str = "") -> int:
            b = _bar(f"{name}.bar{suffix}", bar, len(bars))
            owner = "the bar" if len(bars) == 1 else f"bar[{b}]"
            return int(offsets[b]) + _node(f"{name}.node{suffix}", value, bars[b].n_nodes, owner)

        return node

    @property
    def bars(self) -> tuple[Bar, ...]:
        """Every bar of the scene, in order (a tuple even when there is one)."""
        return (self.bar,) if isinstance(self.bar, Bar) else self.bar

    @cached_property
    def node_offsets(self) -> np.ndarray:
        """Global number of each bar's node 0, and the total node count last."""
        return np.concatenate(([0], np.cumsum([b.n_nodes for b in self.bars])))

    def global_node(self, bar: int, node: int) -> int:
        """The number of node ``node`` of bar ``bar`` in the scene's one node sequence."""
        return int(self.node_offsets[bar]) + int(node)

    @property
    def n_nodes(self) -> int:
        return int(self.node_offsets[-1])

    @property
    def n_elements(self) -> int:
        return self.n_nodes - len(self.bars)

    @property
    def n_contacts(self) -> int:
        """Contact rows: one per wall, then one per bar contact."""
        return len(self.walls) + len(self.contacts)

    @cached_property
    def junctions(self) -> np.ndarray:
        """Slots between consecutive global nodes that no element joins (a bar's last node
        and the next bar's first); slot j is between nodes j and j + 1."""
        return self.node_offsets[1:-1] - 1

    def _per_element(self, values: list[np.ndarray]) -> np.ndarray:
        array = np.concatenate(values) if len(values) > 1 else np.asarray(values[0])
        array.flags.writeable = False
        return array

    @cached_property
    def stiffness(self) -> np.ndarray:
        """E·A/L of every element of every bar, bar after bar (N/m)."""
        return self._per_element([b.stiffness for b in self.bars])

    @cached_property
    def areas(self) -> np.ndarray:
        """Area of every element of every bar, bar after bar (m²)."""
        return self._per_element([b.areas for b in self.bars])

    @cached_property
    def yield_stress(self) -> np.ndarray | None:
        """Yield stress of every element (Pa; NaN on a bar without one), None if no bar has one."""
        if all(b.yield_stress is None for b in self.bars):
            return None
        return self._per_element([np.full(b.n_elements, np.nan if b.yield_stress is None
                                          else b.yield_stress) for b in self.bars])

    @cached_property
    def compliance(self) -> np.ndarray:
        """Σ L/(EA) from its bar's node 0 to every node (m/N), bar after bar."""
        return self._per_element([b.compliance_from_node_0 for b in self.bars])

    @cached_property
    def slot_stiffness(self) -> np.ndarray:
        """Stiffness between global nodes j and j + 1 (N/m): the element's, 0 at a junction."""
        if len(self.bars) == 1:
            return self.stiffness
        slots = np.insert(self.stiffness, self.junctions - np.arange(self.junctions.size), 0.0)
        slots.flags.writeable = False
        return slots

    @cached_property
    def node_x(self) -> np.ndarray:
        """x of every node (m) for drawing: each bar starts where the one before ends."""
        xs, start = [], 0.0
        for b in self.bars:
            xs.append(start + b.node_x)
            start = float(xs[-1][-1])
        return np.concatenate(xs)

    @cached_property
    def support_nodes(self) -> np.ndarray:
        """Global node of each support, in scene order."""
        return np.array([self.global_node(s.bar, s.node) for s in self.supports], dtype=np.intp)

    @cached_property
    def load_nodes(self) -> np.ndarray:
        """Global node of each point load, in scene order."""
        return np.array([self.global_node(p.bar, p.node) for p in self.loads], dtype=np.intp)

    @cached_property
    def contact_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The contact rows C u <= g in global node numbering as (row, node, coefficient) of
        each nonzero, and g: a wall is sign·u_node <= gap, a bar contact u_a − u_b <= gap."""
        walls, contacts = self.walls, self.contacts
        n_walls = len(walls)
        offsets = self.node_offsets
        wall_nodes = np.array([offsets[w.bar] + w.node for w in walls], dtype=np.intp)
        signs = np.array([w.sign for w in walls], dtype=float)
        a = np.array([offsets[c.bar_a] + c.node_a for c in contacts], dtype=np.intp)
        b = np.array([offsets[c.bar_b] + c.node_b for c in contacts], dtype=np.intp)
        rows = np.concatenate((np.arange(n_walls), n_walls + np.arange(a.size),
                               n_walls + np.arange(b.size))).astype(np.intp)
        nodes = np.concatenate((wall_nodes, a, b)).astype(np.intp)
        values = np.concatenate((signs, np.ones(a.size), -np.ones(b.size)))
        gaps = np.array([w.gap for w in walls] + [c.gap for c in contacts], dtype=float)
        for array in (rows, nodes, values, gaps):
            array.flags.writeable = False
        return rows, nodes, values, gaps

    @property
    def gaps(self) -> np.ndarray:
        """g: the gap of every contact row (m)."""
        return self.contact_rows[3]

    def nodal_loads(self) -> np.ndarray:
        """The point loads and the distributed loads' consistent nodal forces summed per global
        node (N), length n_nodes."""
        p = self.distributed_nodal_loads()
        np.add.at(p, self.load_nodes, np.array([q.force for q in self.loads], dtype=float))
        return p

    def distributed_nodal_loads(self) -> np.ndarray:
        """The distributed loads' consistent nodal forces per global node (N): each element
        passes intensity × length / 2 to each of its two nodes."""
        p = np.zeros(self.n_nodes)
        for q in self.distributed:
            bar = self.bars[q.bar]
            stop = bar.n_elements if q.stop is None else q.stop
            half = 0.5 * float(q.intensity) * bar.lengths[q.start:stop]
            first = self.global_node(q.bar, q.start)
            p[first:first + half.size] += half
            p[first + 1:first + 1 + half.size] += half
        return p

    def load_point(self) -> int:
        """The global node whose displacement a load path follows: the first point load's
        node, else the node with the largest nodal load."""
        if self.loads:
            return int(self.load_nodes[0])
        return int(np.abs(self.nodal_loads()).argmax())

    def with_loads(self, loads: tuple[Load, ...],
                   distributed: tuple[DistributedLoad, ...] | None = None) -> Scene:
        """The same scene with other loads (point, and distributed when given)."""
        return replace(self, loads=tuple(loads),
                       distributed=self.distributed if distributed is None else tuple(distributed))

    def scaled_loads(self, factor: float) -> Scene:
        """The same scene with every load (point and distributed) times ``factor``."""
        factor = _number("load factor", factor)
        return self.with_loads(tuple(replace(p, force=factor * p.force) for p in self.loads),
                               tuple(replace(q, intensity=factor * q.intensity)
                                     for q in self.distributed))

    def with_walls(self, walls: tuple[Wall, ...]) -> Scene:
        """The same scene with other walls."""
        return replace(self, walls=tuple(walls))


def constraint_graph(scene: Scene) -> list[tuple[int, int, float, int, str]]:
    """The scene's walls and bar contacts as difference constraints x_v − x_w <= c, each an
    edge (w, v, c, contact row, what it says); vertex −1 is zero displacement, where the
    supports are merged."""
    unit = scene.unit.length
    supports = set(scene.support_nodes.tolist())

    def vertex(node: int) -> int:
        return -1 if node in supports else node

    edges = []
    for i, wall in enumerate(scene.walls):
        node = scene.global_node(wall.bar, wall.node)
        where = _where(scene, node)
        if wall.side == "+":
            edges.append((-1, node, wall.gap, i, f"wall[{i}] (u ≤ {wall.gap:.6g} {unit} at {where})"))
        else:
            edges.append((node, -1, wall.gap, i, f"wall[{i}] (u ≥ {0.0 - wall.gap:.6g} {unit} at {where})"))
    for i, c in enumerate(scene.contacts):
        a, b = scene.global_node(c.bar_a, c.node_a), scene.global_node(c.bar_b, c.node_b)
        edges.append((vertex(b), vertex(a), c.gap, len(scene.walls) + i,
                      (f"contact[{i}] (u at {_where(scene, a)} − u at {_where(scene, b)} ≤ "
                      f"{c.gap:.6g} {unit})")))
    return edges


def _where(scene: Scene, node: int) -> str:
    bar = int(np.searchsorted(scene.node_offsets, node, side="right") - 1)
    local = node - int(scene.node_offsets[bar])
    return f"node {local}" if len(scene.bars) == 1 else f"bar {bar} node {local}"


def _contact_subgraph(scene: Scene, edges: list) -> list:
    """The edges between bar-contact nodes and zero: the only ones on cycles longer than a
    node's own two walls."""
    ends = {v for edge in edges[len(scene.walls):] for v in edge[:2]}
    return [edge for edge in edges if edge[0] in ends | {-1} and edge[1] in ends | {-1}]


def impossible_constraints(scene: Scene) -> str:
    """Why no displacement satisfies the scene's supports, walls and bar contacts together,
    or "" when one does.

    They are difference constraints (:func:`constraint_graph`). Such a system has a solution
    exactly when its constraint graph has no cycle of negative total weight (Bellman–Ford);
    the cycle names the constraints that conflict. Only the nodes of bar contacts can lie on
    a longer cycle: any other walled node is checked on its own (its two walls' gaps must not
    sum below 0).
    """
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
    if not scene.contacts:
        return ""
    edges = _contact_subgraph(scene, constraint_graph(scene))
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
        names = ", ".join(edges[i][4] for i in [index] + [i for i, _ in path])
        return (f"{names} hold their nodes at one position in more than one way, with no gap "
                "to spare: the contact forces along that loop are not determined by rigid "
                "contact (give one of them a gap, or hold the node by a support)")
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


def wall_at_every_node(scene: Scene, gap: Any, side: WallSide = "+", bar: int = 0) -> Scene:
    """The scene with a wall at every node of bar ``bar`` that is not a support (the discrete
    obstacle problem): ``gap`` one value (m) or one per node of the bar (supports' ignored).
    Where the scene has a wall on that side already, the smaller gap is kept (both walls
    hold, so the nearer one is the constraint)."""
    b = _bar("obstacle.bar", bar, len(scene.bars))
    if side not in WALL_SIDES:
        raise SceneError(f"obstacle.side must be '+' or '-', got {side!r}")
    n = scene.bars[b].n_nodes
    gaps = np.asarray(gap, dtype=float)
    if gaps.ndim == 0:
        gaps = np.full(n, float(gaps))
    if gaps.shape != (n,):
        raise SceneError(f"obstacle.gap must be one value or one per node of bar[{b}] ({n}), "
                         f"got {gaps.size}")
    held = {s.node for s in scene.supports if s.bar == b}
    existing = {w.node: i for i, w in enumerate(scene.walls) if w.bar == b and w.side == side}
    walls = list(scene.walls)
    for node, i in existing.items():
        walls[i] = replace(walls[i], gap=min(walls[i].gap, float(gaps[node])))
    walls += [Wall(i, float(gaps[i]), side, b) for i in range(n)
              if i not in held and i not in existing]
    return scene.with_walls(tuple(walls))


def _as(kind: type, value: Any, name: str) -> Any:
    if not isinstance(value, kind):
        raise SceneError(f"{name} must be a contactqp.{kind.__name__}, got {value!r}")
    return value


# The default scene: a standard course problem.
SEED_LENGTH = 1.0  # m
SEED_ELEMENTS = 4
SEED_DIAMETERS = (0.040, 0.020)  # m, at x = 0 and x = L
SEED_MODULUS = 210e9  # Pa
SEED_YIELD = 200e6  # Pa
SEED_LOAD_NODE, SEED_LOAD = 2, 565486.67  # N
SEED_GAP = 1e-4  # m


def seed_scene(elements: int = SEED_ELEMENTS, area_rule: AreaRule = "midpoint") -> Scene:
    """The default scene: a 1 m tapered cantilever pushed into a wall 0.1 mm past its tip.

    Fixed at x = 0; circular section from 40 mm to 20 mm diameter; E = 210 GPa, yield stress
    200 MPa; four equal elements with the area of the circle at mid-length; 565486.67 N in +x
    at node 2 (mid-length); a rigid wall 0.1 mm beyond the tip in +x. ``elements`` (even) and
    ``area_rule`` re-mesh the same bar, for convergence studies.
    """
    if isinstance(elements, bool) or not isinstance(elements, int) or elements < 2 or elements % 2:
        raise SceneError(f"elements must be an even whole number >= 2 (load at mid-length), "
                         f"got {elements!r}")
    bar = Bar.tapered_circle(
        SEED_LENGTH, elements, *SEED_DIAMETERS, SEED_MODULUS,
        area_rule=area_rule, yield_stress=SEED_YIELD,
    )
    name = "seed: tapered cantilever against a wall"
    if (elements, area_rule) != (SEED_ELEMENTS, "midpoint"):
        name += f" ({elements} elements, {area_rule} areas)"
    return Scene(
        bar,
        supports=(Support(0),),
        loads=(Load(elements // 2, SEED_LOAD),),
        walls=(Wall(elements, SEED_GAP, "+"),),
        name=name,
    )


def needed_nodes(scene: Scene, bar: int = 0) -> np.ndarray:
    """The nodes bar ``bar`` needs (sorted node numbers of that bar): both ends, supports,
    loads, walls and bar-contact ends, and every node under a distributed load (a merged
    element of varying EA would spread the load differently)."""
    nodes = {0, scene.bars[bar].n_nodes - 1}
    nodes.update(s.node for s in scene.supports if s.bar == bar)
    nodes.update(p.node for p in scene.loads if p.bar == bar)
    nodes.update(w.node for w in scene.walls if w.bar == bar)
    nodes.update(c.node_a for c in scene.contacts if c.bar_a == bar)
    nodes.update(c.node_b for c in scene.contacts if c.bar_b == bar)
    for q in scene.distributed:
        if q.bar == bar:
            nodes.update(range(q.start, (scene.bars[bar].n_elements if q.stop is None
                                         else q.stop) + 1))
    return np.array(sorted(nodes))


def minimal(scene: Scene) -> Scene:
    """The same scene with nodes only where it needs them (:func:`needed_nodes`), bar by bar.

    The elements between two kept nodes become one element with their series flexibility
    Σ L/(EA), so displacements at the kept nodes, contact forces, reactions and element forces
    are exactly those of the original model (static condensation of unloaded nodes). Stresses
    are those of the merged element's equivalent area: for a taper meshed with
    ``area_rule="exact"`` that is the exact cone's, and one element per segment reproduces the
    continuum answer.
    """
    bars, numbers = [], []
    for b, bar in enumerate(scene.bars):
        kept = needed_nodes(scene, b)
        new_number = np.full(bar.n_nodes, -1)
        new_number[kept] = np.arange(kept.size)
        numbers.append(new_number)
        flexibility = bar.compliance_from_node_0[kept]
        x = bar.node_x[kept]
        lengths = np.diff(x)
        modulus = bar.youngs_modulus[np.searchsorted(bar.node_x, x[:-1], side="right") - 1]
        areas = lengths / (modulus * np.diff(flexibility))  # E A / L = 1 / Σ L/(EA)
        bars.append(Bar(lengths, areas, modulus, bar.yield_stress))
    def element(b: int, e: int | None) -> int | None:
        # a distributed load's elements keep all their nodes: element e starts at node e
        return None if e is None else int(numbers[b][e])

    return Scene(
        tuple(bars),
        tuple(replace(s, node=int(numbers[s.bar][s.node])) for s in scene.supports),
        tuple(replace(p, node=int(numbers[p.bar][p.node])) for p in scene.loads),
        tuple(replace(w, node=int(numbers[w.bar][w.node])) for w in scene.walls),
        name=f"{scene.name} (minimal mesh)",
        distributed=tuple(replace(q, start=element(q.bar, q.start), stop=element(q.bar, q.stop))
                          for q in scene.distributed),
        contacts=tuple(replace(c, node_a=int(numbers[c.bar_a][c.node_a]),
                               node_b=int(numbers[c.bar_b][c.node_b])) for c in scene.contacts),
        units=scene.units,
    )


def convert_units(scene: Scene, units: str) -> Scene:
    """The same physical scene in another unit system (:data:`UNIT_SYSTEMS`): lengths, areas,
    moduli, yield stresses, gaps and distributed loads converted; point loads stay in N."""
    if units not in UNIT_SYSTEMS:
        raise SceneError(f"units must be one of {', '.join(map(repr, UNIT_SYSTEMS))}, "
                         f"got {units!r}")
    old, new = scene.unit, UNIT_SYSTEMS[units]
    length, stress = old.metre / new.metre, old.pascal / new.pascal

    def bar(b: Bar) -> Bar:
        yield_stress = None if b.yield_stress is None else b.yield_stress * stress
        return Bar(b.lengths * length, b.areas * length**2, b.youngs_modulus * stress,
                   yield_stress)

    bars = tuple(bar(b) for b in scene.bars)
    return replace(
        scene, bar=bars[0] if len(bars) == 1 else bars, units=units,
        walls=tuple(replace(w, gap=w.gap * length) for w in scene.walls),
        contacts=tuple(replace(c, gap=c.gap * length) for c in scene.contacts),
        distributed=tuple(replace(q, intensity=q.intensity / length) for q in scene.distributed),
    )


# ---------------------------------------------------------------------------------------------
# TOML

_TOP_KEYS = {"name", "units", "material", "bar", "support", "load", "wall", "distributed_load",
             "contact",
             "obstacle"}
_MATERIAL_KEYS = {"youngs_modulus", "yield_stress"}
_BAR_KEYS = {"length", "lengths", "elements", "section", "areas", "material"}
_SECTION_KEYS = {"shape", "diameter_start", "diameter_end", "area_rule"}


def _table(data: Any, name: str, allowed: set[str], required: set[str] = frozenset()) -> dict:
    if not isinstance(data, dict):
        raise SceneError(f"{name} must be a table, got {data!r}")
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise SceneError(f"{name}.{unknown[0]}: unknown key (allowed: {', '.join(sorted(allowed))})")
    missing = sorted(required - set(data))
    if missing:
        raise SceneError(f"{name}.{missing[0]} is missing")
    return data


def _array_of_tables(data: dict, key: str, allowed: set[str], required: set[str]) -> list[dict]:
    items = data.get(key, [])
    if not isinstance(items, list):
        raise SceneError(f"{key} must be an array of tables ([[{key}]]), got {items!r}")
    return [_table(item, f"{key}[{i}]", allowed, required) for i, item in enumerate(items)]


def _bar_from_dict(bar_data: Any, name: str, material: dict | None) -> Bar:
    """One bar from its TOML table; its own ``material`` table, else the scene's."""
    bar_data = _table(bar_data, name, _BAR_KEYS)
    if "material" in bar_data:
        material = _table(bar_data["material"], f"{name}.material", _MATERIAL_KEYS,
                          {"youngs_modulus"})
        where = f"{name}.material"
    else:
        where = "material"
    if material is None:
        raise SceneError(f"{name}: no material; give [material] or {name}.material")
    modulus = _number(f"{where}.youngs_modulus", material["youngs_modulus"], minimum=0.0,
                      strict=True)
    yield_stress = material.get("yield_stress")
    if "areas" in bar_data:
        if "section" in bar_data or "elements" in bar_data:
            raise SceneError(f"{name}: give either areas or elements + section, not both")
        if not isinstance(bar_data["areas"], list):
            raise SceneError(f"{name}.areas must be a list of numbers, got {bar_data['areas']!r}")
        return Bar.from_areas(
            bar_data["areas"], modulus, length=bar_data.get("length"),
            lengths=bar_data.get("lengths"), yield_stress=yield_stress,
        )
    for key in ("length", "elements", "section"):
        if key not in bar_data:
            raise SceneError(f"{name}.{key} is missing (or give {name}.areas)")
    if "lengths" in bar_data:
        raise SceneError(f"{name}.lengths goes with {name}.areas; with {name}.section the "
                         f"elements are equal ({name}.length / {name}.elements)")
    section = _table(bar_data["section"], f"{name}.section", _SECTION_KEYS,
                     {"shape", "diameter_start", "diameter_end"})
    if section["shape"] != "circle":
        raise SceneError(f"{name}.section.shape must be 'circle', got {section['shape']!r}")
    return Bar.tapered_circle(
        bar_data["length"], bar_data["elements"], section["diameter_start"],
        section["diameter_end"], modulus, area_rule=section.get("area_rule", "midpoint"),
        yield_stress=yield_stress,
    )


def scene_from_dict(data: dict, name: str = "scene") -> Scene:
    """Build a scene from the parsed TOML structure documented in the README: one ``[bar]``
    or several ``[[bar]]`` (each may have its own ``material`` table)."""
    data = _table(data, "scene", _TOP_KEYS, {"bar"})
    material = None
    if "material" in data:
        material = _table(data["material"], "material", _MATERIAL_KEYS, {"youngs_modulus"})
    if isinstance(data["bar"], list):
        if not data["bar"]:
            raise SceneError("bar: [[bar]] is empty; give at least one bar")
        bars: Bar | tuple[Bar, ...] = tuple(_bar_from_dict(b, f"bar[{i}]", material)
                                            for i, b in enumerate(data["bar"]))
    else:
        bars = _bar_from_dict(data["bar"], "bar", material)
    supports = tuple(Support(s["node"], s.get("bar", 0))
                     for s in _array_of_tables(data, "support", {"node", "bar"}, {"node"}))
    loads = tuple(
        Load(s["node"], s["force"], s.get("bar", 0))
        for s in _array_of_tables(data, "load", {"node", "force", "bar"}, {"node", "force"})
    )
    walls = tuple(
        Wall(s["node"], s["gap"], s.get("side", "+"), s.get("bar", 0))
        for s in _array_of_tables(data, "wall", {"node", "gap", "side", "bar"}, {"node", "gap"})
    )
    distributed = tuple(
        DistributedLoad(q["intensity"], q.get("bar", 0), q.get("start", 0), q.get("stop"))
        for q in _array_of_tables(data, "distributed_load", {"intensity", "bar", "start", "stop"},
                                  {"intensity"})
    )
    contacts = tuple(
        BarContact(c["bar_a"], c["node_a"], c["bar_b"], c["node_b"], c["gap"])
        for c in _array_of_tables(data, "contact", {"bar_a", "node_a", "bar_b", "node_b", "gap"},
                                  {"bar_a", "node_a", "bar_b", "node_b", "gap"})
    )
    scene = Scene(bars, supports, loads, walls, name=str(data.get("name", name)),
                  units=data.get("units", "SI"),
                  distributed=distributed, contacts=contacts)
    for i, o in enumerate(_array_of_tables(data, "obstacle", {"gap", "side", "bar"}, {"gap"})):
        gap = o["gap"]
        if isinstance(gap, list):
            gap = [_number(f"obstacle[{i}].gap[{j}]", g, tiny=True) for j, g in enumerate(gap)]
        else:
            gap = _number(f"obstacle[{i}].gap", gap, tiny=True)
        scene = wall_at_every_node(scene, gap, o.get("side", "+"), o.get("bar", 0))
    return scene


def load_scene(path: str | Path) -> Scene:
    """Read a scene from a TOML file (format in the README)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"scene file {str(path)!r} does not exist") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"scene file {str(path)!r} cannot be read: {error}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError(f"scene file {str(path)!r} is not valid TOML: {error}") from None
    return scene_from_dict(data, name=path.stem)


def scene_to_toml(scene: Scene) -> str:
    """The scene as TOML text that :func:`load_scene` reads back (explicit areas and lengths;
    an obstacle as its walls)."""
    lines = [f"name = {json.dumps(scene.name)}",  # JSON strings are TOML
             f"units = {json.dumps(scene.units)}"]
    several = len(scene.bars) > 1
    for i, bar in enumerate(scene.bars):
        moduli = np.unique(bar.youngs_modulus)
        if moduli.size != 1:
            raise SceneError(f"scene_to_toml: bar[{i}] has several moduli, which have no TOML form")
        lines += ["", "[[bar]]" if several else "[bar]", f"areas = {[float(a) for a in bar.areas]!r}",
                  f"lengths = {[float(v) for v in bar.lengths]!r}",
                  "", "[bar.material]", f"youngs_modulus = {float(moduli[0])!r}"]
        if bar.yield_stress is not None:
            lines.append(f"yield_stress = {bar.yield_stress!r}")
    for s in scene.supports:
        lines += ["", "[[support]]", f"bar = {s.bar}", f"node = {s.node}"]
    for p in scene.loads:
        lines += ["", "[[load]]", f"bar = {p.bar}", f"node = {p.node}", f"force = {float(p.force)!r}"]
    for q in scene.distributed:
        lines += ["", "[[distributed_load]]", f"bar = {q.bar}", f"intensity = {float(q.intensity)!r}",
                  f"start = {q.start}"] + ([] if q.stop is None else [f"stop = {q.stop}"])
    for w in scene.walls:
        lines += ["", "[[wall]]", f"bar = {w.bar}", f"node = {w.node}", f"gap = {float(w.gap)!r}",
                  f'side = "{w.side}"']
    for c in scene.contacts:
        lines += ["", "[[contact]]", f"bar_a = {c.bar_a}", f"node_a = {c.node_a}",
                  f"bar_b = {c.bar_b}", f"node_b = {c.node_b}", f"gap = {float(c.gap)!r}"]
    return "\n".join(lines) + "\n"


__all__ = [
    "AREA_RULES",
    "UNIT_SYSTEMS",
    "Bar",
    "BarContact",
    "DistributedLoad",
    "Load",
    "Scene",
    "Support",
    "Units",
    "Wall",
    "circle_areas",
    "constraint_graph",
    "convert_units",
    "impossible_constraints",
    "load_scene",
    "minimal",
    "needed_nodes",
    "scene_from_dict",
    "scene_to_toml",
    "seed_scene",
    "tight_cycles",
    "wall_at_every_node",
]
