"""What the user describes: elastic bars, their supports, point and distributed loads, rigid
walls and contacts between bars, in one unit system. Description and validation only: the
algebra (numbering, K, P, C, g) is contactqp.model's.

A bar's elements each have a length, an area and a modulus: given one area per element, one
area for all, or a section (:class:`Circle`, :class:`HollowCircle`, :class:`Rectangle`, each
dimension constant or tapering linearly) from which :func:`section_areas` makes them.

Each bar numbers its nodes 0..n along +x; element e joins its nodes e and e + 1; supports,
loads and walls name a bar (default 0) and a node of it. Every value is checked when the
scene is built, and an error names the field (as it is spelled in the TOML file) and the
value; a scene whose walls and contacts leave a node no position, or whose contact forces
rigid contact would leave undetermined, is refused (contactqp.feasibility).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np

from contactqp.errors import OptionError, SceneError
from contactqp.units import UNIT_SYSTEMS, Units
from contactqp.values import (
    number,
    one_of,
    positive_numbers,
    text,
    value_array,
    whole_number,
)

if TYPE_CHECKING:
    from contactqp.model.layout import Layout

AreaRule = Literal["midpoint", "exact"]
WallSide = Literal["+", "-"]
AREA_RULES = ("midpoint", "exact")
WALL_SIDES = ("+", "-")
MAX_ELEMENTS = 10_000_000  # every element costs ~1 kB across model, solve and check
Ends = tuple[float, float]  # a dimension at x = 0 and at x = L (m)
Dimension = float | Ends
"""A section's dimension (m): one number along the whole bar, or a pair (at x = 0, at x = L)
between which it tapers linearly."""
_PAIRS = (tuple, list, np.ndarray)  # what a tapered dimension may be given as


def _dimension(name: str, value: Any, zero_allowed: bool = False) -> tuple[float, float]:
    """``value`` (a number, or a pair (start, end)) as its two ends, each a number > 0 (>= 0
    where ``zero_allowed``); a pair's ends are named ``name_start`` and ``name_end``,
    as a scene file spells them."""
    strict = not zero_allowed
    if isinstance(value, _PAIRS):
        if len(value) != 2:
            raise SceneError(f"{name} must be one number or a pair (start, end), got {value!r}")
        return (number(f"{name}_start", value[0], minimum=0.0, strict=strict),
                number(f"{name}_end", value[1], minimum=0.0, strict=strict))
    one = number(name, value, minimum=0.0, strict=strict)
    return one, one


def _key(name: str, value: Any, end: int) -> str:
    """How a scene file spells end ``end`` (0 or 1) of dimension ``name`` given as ``value``."""
    return f"{name}{('_start', '_end')[end]}" if isinstance(value, _PAIRS) else name


@dataclass(frozen=True)
class Circle:
    """A solid circular section of ``diameter`` (m): one number, or (at x = 0, at x = L)."""

    diameter: Dimension
    shape: ClassVar[str] = "circle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        d = _dimension(f"{name}.diameter", self.diameter)
        return math.pi / 4.0, d, d  # A = π/4 · d · d


@dataclass(frozen=True)
class HollowCircle:
    """A tube: a circle of ``outer_diameter`` with a concentric hole of ``inner_diameter``
    (m; 0: no hole), each one number or (at x = 0, at x = L); inner < outer at both ends."""

    outer_diameter: Dimension
    inner_diameter: Dimension
    shape: ClassVar[str] = "hollow_circle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        outer = _dimension(f"{name}.outer_diameter", self.outer_diameter)
        inner = _dimension(f"{name}.inner_diameter", self.inner_diameter, True)
        for end in (0, 1):
            if not inner[end] < outer[end]:
                raise SceneError(
                    f"{name}.{_key('inner_diameter', self.inner_diameter, end)} = "
                    f"{inner[end]!r} is not less than "
                    f"{_key('outer_diameter', self.outer_diameter, end)} = {outer[end]!r}")
        # A = π/4 · (D − d)(D + d): a product of two linear factors, as a rectangle's is
        return (math.pi / 4.0, (outer[0] - inner[0], outer[1] - inner[1]),
                (outer[0] + inner[0], outer[1] + inner[1]))


@dataclass(frozen=True)
class Rectangle:
    """A solid rectangular section ``width`` × ``height`` (m), each one number or
    (at x = 0, at x = L)."""

    width: Dimension
    height: Dimension
    shape: ClassVar[str] = "rectangle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        return (1.0, _dimension(f"{name}.width", self.width),
                _dimension(f"{name}.height", self.height))


Section = Circle | HollowCircle | Rectangle
SECTIONS: dict[str, type[Section]] = {kind.shape: kind for kind in (Circle, HollowCircle, Rectangle)}


def section_areas(section: Section, elements: int, rule: str,
                  name: str = "bar.section") -> np.ndarray:
    """Element areas (m²) of ``elements`` equal elements along ``section``; ``name``: how
    messages name the section (as a scene file spells it).

    Every section's area is c·p(x)·q(x) with p and q linear in x (a circle d·d, a tube
    (D − d)(D + d), a rectangle w·h). ``rule``:

    ``"midpoint"``: the section at each element's mid-length, c·p_m·q_m.
    ``"exact"``: the constant area with the element's own axial compliance,
    L / ∫₀ᴸ dx/A(x) = c·M(p_b·q_a, p_a·q_b), M the logarithmic mean (x − y)/ln(x/y), since
    ∫₀¹ dt/(p(t)q(t)) = ln(p_b q_a/(p_a q_b))/(p_b q_a − p_a q_b). A circle: π·d_a·d_b/4; a
    rectangle tapered in width only: h·(w_b − w_a)/ln(w_b/w_a). A bar of exact elements has
    the compliance of the continuous taper, whatever the mesh.
    """
    if rule not in AREA_RULES:
        raise SceneError(f"{name}.area_rule must be one of {AREA_RULES}, got {rule!r}")
    if not isinstance(section, tuple(SECTIONS.values())):
        raise SceneError(f"{name} must be a contactqp.scene.Circle, HollowCircle or Rectangle, "
                         f"got {section!r}")
    scale, p_ends, q_ends = section._factors(name)
    p = np.linspace(*p_ends, elements + 1)
    q = np.linspace(*q_ends, elements + 1)
    if rule == "midpoint":
        return scale * (0.5 * (p[:-1] + p[1:]) * (0.5 * (q[:-1] + q[1:])))
    return scale * _log_mean(p[1:] * q[:-1], p[:-1] * q[1:])


def _log_mean(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(x − y)/ln(x/y) of positive x, y, and y where x = y: written y·u/log1p(u) with
    u = x/y − 1, which stays accurate as x → y, where the quotient itself is 0/0."""
    u = (x - y) / y
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = y * u / np.log1p(u)
    return np.where(u == 0.0, y, mean)


def _equal_lengths(name: str, length: Any, elements: Any) -> np.ndarray:
    """``elements`` equal element lengths (m) over ``length`` (m), both checked."""
    total = number(f"{name}.length", length, minimum=0.0, strict=True)
    elements = whole_number(f"{name}.elements", elements, 1)
    if elements > MAX_ELEMENTS:
        raise SceneError(f"{name}.elements = {elements}: contactqp takes at most {MAX_ELEMENTS} "
                         "elements in a scene")
    return np.full(elements, total / elements)


@dataclass(frozen=True, eq=False)
class Bar:
    """Elements between consecutive nodes, each with a length (m), area (m²) and modulus (Pa),
    and the bar's yield stress (Pa, optional: only compared with the stresses, which are
    flagged beyond it).

    Build one with :meth:`uniform` (one area), :meth:`from_section` (a circle, tube or
    rectangle, uniform or tapered), :meth:`tapered_circle` or :meth:`from_areas` (one area per
    element); the arrays are read-only. Each constructor takes ``name``: how its messages name
    the bar (``"bar[1]"``, as a scene file does).

    Parameters
    ----------
    lengths : array_like
        The element lengths (m), positive.
    areas : array_like
        The element areas (m²), positive.
    youngs_modulus : array_like
        Young's modulus of each element (Pa), positive.
    yield_stress : float, optional
        The yield stress (Pa).

    Raises
    ------
    SceneError
        Arrays of different lengths, or a value that is not a positive finite number.
    """

    lengths: np.ndarray
    areas: np.ndarray
    youngs_modulus: np.ndarray
    yield_stress: float | None = None

    def __post_init__(self) -> None:
        self._check("bar")

    @classmethod
    def _named(cls, name: str, lengths: Any, areas: Any, youngs_modulus: Any,
               yield_stress: Any) -> Bar:
        """A bar made without __init__, so that its one check names it ``name``."""
        bar = object.__new__(cls)
        for key, value in (("lengths", lengths), ("areas", areas),
                           ("youngs_modulus", youngs_modulus), ("yield_stress", yield_stress)):
            object.__setattr__(bar, key, value)
        bar._check(name)
        return bar

    def _check(self, name: str) -> None:
        """Check every value, naming the field as ``name``'s table in a scene file spells it,
        and keep the arrays read-only."""
        lengths = positive_numbers(f"{name}.lengths", self.lengths, MAX_ELEMENTS)
        areas = positive_numbers(f"{name}.areas", self.areas, MAX_ELEMENTS)
        moduli = positive_numbers("material.youngs_modulus", self.youngs_modulus,
                                  MAX_ELEMENTS)
        if moduli.size not in (1, areas.size):
            raise SceneError(
                f"material.youngs_modulus must be one value or one per element ({areas.size}), "
                f"got {moduli.size}"
            )
        moduli = np.broadcast_to(moduli, areas.shape)
        if areas.size == 0:
            raise SceneError(f"{name} must have at least one element, got 0")
        if lengths.size != areas.size:
            raise SceneError(
                f"{name}.lengths has {lengths.size} values but {name}.areas has {areas.size}: "
                "give one length per element"
            )
        if self.yield_stress is not None:
            object.__setattr__(
                self, "yield_stress",
                number("material.yield_stress", self.yield_stress, minimum=0.0, strict=True),
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
        name: str = "bar",
    ) -> Bar:
        """A bar from explicit element areas (m²), with equal elements over ``length`` (m) or
        explicit element ``lengths`` (m)."""
        areas = positive_numbers(f"{name}.areas", areas, MAX_ELEMENTS)
        if (length is None) == (lengths is None):
            raise SceneError(f"{name} needs exactly one of length (m) or lengths (one per "
                             "element)")
        if lengths is None:
            lengths = _equal_lengths(name, length, max(areas.size, 1))
        return cls._named(name, lengths, areas, youngs_modulus, yield_stress)

    @classmethod
    def uniform(
        cls,
        area: float,
        youngs_modulus: float,
        *,
        length: float | None = None,
        elements: int | None = None,
        lengths: Any = None,
        yield_stress: float | None = None,
        name: str = "bar",
    ) -> Bar:
        """A bar of one ``area`` (m²) in every element: ``elements`` equal elements over
        ``length`` (m), or explicit element ``lengths`` (m)."""
        area = number(f"{name}.area", area, minimum=0.0, strict=True)
        if lengths is not None and length is None and elements is None:
            lengths = positive_numbers(f"{name}.lengths", lengths, MAX_ELEMENTS)
        elif lengths is None and length is not None and elements is not None:
            lengths = _equal_lengths(name, length, elements)
        else:
            raise SceneError(f"{name} with one area needs length (m) and elements, or lengths "
                             "(m, one per element)")
        return cls._named(name, lengths, np.full(lengths.size, area), youngs_modulus,
                          yield_stress)

    @classmethod
    def from_section(
        cls,
        section: Section,
        youngs_modulus: float,
        *,
        length: float,
        elements: int,
        area_rule: AreaRule = "midpoint",
        yield_stress: float | None = None,
        name: str = "bar",
    ) -> Bar:
        """``elements`` equal elements over ``length`` (m) of a :class:`Circle`,
        :class:`HollowCircle` or :class:`Rectangle` section, each dimension constant or
        tapering linearly from x = 0 to x = ``length``; areas by ``area_rule``
        (:func:`section_areas`: ``"midpoint"`` or ``"exact"``)."""
        lengths = _equal_lengths(name, length, elements)
        areas = section_areas(section, lengths.size, area_rule, f"{name}.section")
        return cls._named(name, lengths, areas, youngs_modulus, yield_stress)

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
        name: str = "bar",
    ) -> Bar:
        """Equal elements over a circular section tapering linearly from ``diameter_start``
        at x = 0 to ``diameter_end`` at x = ``length`` (m); areas by ``area_rule``: the same
        as :meth:`from_section` with ``Circle((diameter_start, diameter_end))``."""
        return cls.from_section(Circle((diameter_start, diameter_end)), youngs_modulus,
                                length=length, elements=elements, area_rule=area_rule,
                                yield_stress=yield_stress, name=name)

    @property
    def n_elements(self) -> int:
        return int(self.areas.size)

    @property
    def n_nodes(self) -> int:
        return self.n_elements + 1

    @cached_property
    def element_stiffness(self) -> np.ndarray:
        """k_e = E·A/L of each element (N/m)."""
        return self.youngs_modulus * self.areas / self.lengths

    @cached_property
    def compliance(self) -> np.ndarray:
        """Σ L/(EA) of the elements between node 0 and each node (m/N): kept with the bar,
        so that re-solving a scene (new loads, gaps or walls) does not add it up again."""
        compliance = np.zeros(self.n_nodes)
        np.cumsum(1.0 / self.element_stiffness, out=compliance[1:])
        compliance.flags.writeable = False
        return compliance

    @cached_property
    def node_x(self) -> np.ndarray:
        """Undeformed x of every node (m), node 0 at x = 0."""
        return np.concatenate(([0.0], np.cumsum(self.lengths)))


@dataclass(frozen=True)
class Support:
    """A node of bar ``bar`` held at zero displacement.

    Parameters
    ----------
    node : int
        The node (0 at x = 0).
    bar : int
        The bar (default 0).
    """

    node: int
    bar: int = 0


@dataclass(frozen=True)
class Load:
    """A point load at a node of bar ``bar`` (N, positive in +x).

    Parameters
    ----------
    node : int
        The node.
    force : float
        The force (N), positive in +x.
    bar : int
        The bar (default 0).
    """

    node: int
    force: float
    bar: int = 0


@dataclass(frozen=True)
class DistributedLoad:
    """A uniform axial load ``intensity`` (N/m, positive in +x) on elements ``start`` to
    ``stop`` − 1 of bar ``bar`` (``stop`` None: to the bar's end). Each element passes
    intensity × length / 2 to each of its nodes: the consistent load of a linear element, with
    which the nodal displacements of a bar are exact.

    Parameters
    ----------
    intensity : float
        The load per length (N/m), positive in +x.
    bar : int
        The bar (default 0).
    start : int
        The first element loaded (default 0).
    stop : int, optional
        One past the last element loaded (default: the bar's end).
    """

    intensity: float
    bar: int = 0
    start: int = 0
    stop: int | None = None


@dataclass(frozen=True)
class BarContact:
    """Contact between node ``node_a`` of bar ``bar_a`` and node ``node_b`` of bar ``bar_b``,
    ``gap`` (m) apart, a facing b in +x: u_a − u_b <= gap. Its force λ >= 0 pushes a in −x
    and b in +x. A negative gap is an interference: the two nodes start abs(gap) into each other
    and the contact pushes them apart (a press fit between bars).

    Parameters
    ----------
    bar_a : int
        The bar of node a.
    node_a : int
        Node a, on the −x side of the contact.
    bar_b : int
        The bar of node b.
    node_b : int
        Node b, on the +x side.
    gap : float
        The distance between the two nodes (m); negative: a press fit.
    """

    bar_a: int
    node_a: int
    bar_b: int
    node_b: int
    gap: float


@dataclass(frozen=True)
class Wall:
    """A rigid wall at a node, ``gap`` (m) away from it on ``side``. A negative gap is an
    interference: the node starts abs(gap) past the wall, which pushes it back (a press fit).

    ``side="+"``: the node may not move past u = +gap; the wall can only push in -x.
    ``side="-"``: the node may not move past u = -gap; the wall can only push in +x.

    Parameters
    ----------
    node : int
        The node.
    gap : float
        The distance from the node to the wall (m); negative: a press fit.
    side : str
        ``"+"`` (the default) or ``"-"``.
    bar : int
        The bar (default 0).
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

    ``bars``: one :class:`Bar` or a sequence of them (kept as a tuple either way). A bar
    with no support is held by its walls and bar contacts alone; its loads must press it
    against them (checked at the solve, :func:`contactqp.feasibility.unheld_bars`). Contact rows, in this order everywhere (contact forces, penetrations):
    one per wall, then one per bar contact. ``units``: :data:`UNIT_SYSTEMS`.

    Parameters
    ----------
    bars : Bar or sequence of Bar
        The bars, numbered 0, 1, … in this order.
    supports : sequence of Support
        The nodes held at u = 0.
    loads : sequence of Load
        The point loads.
    walls : sequence of Wall
        The rigid walls.
    name : str
        How tables, charts and messages name the scene.
    distributed : sequence of DistributedLoad
        The uniform axial loads.
    contacts : sequence of BarContact
        The contacts between bars.
    units : str
        ``"SI"`` (m, m², N, Pa; the default) or ``"mm-N-MPa"``.

    Raises
    ------
    SceneError
        A bad value, a reference to a bar or node that does not exist, or constraints that leave
        a node no position (one line naming the field and the value).
    """

    bars: tuple[Bar, ...]
    supports: tuple[Support, ...]
    loads: tuple[Load, ...] = ()
    walls: tuple[Wall, ...] = ()
    name: str = "scene"
    distributed: tuple[DistributedLoad, ...] = ()
    contacts: tuple[BarContact, ...] = ()
    units: str = "SI"

    def __post_init__(self) -> None:
        for key, kind, plural in (("bars", Bar, "bar"), ("supports", Support, "support"),
                                  ("loads", Load, "load"), ("walls", Wall, "wall"),
                                  ("distributed", DistributedLoad, "distributed_load"),
                                  ("contacts", BarContact, "contact")):
            object.__setattr__(self, key, _items(getattr(self, key), kind, plural))
        if not self.bars:
            raise SceneError("bar: no bar; give at least one [bar]")
        text("name", self.name)
        one_of("units", self.units, UNIT_SYSTEMS)
        total = sum(b.n_elements for b in self.bars)
        if total > MAX_ELEMENTS:
            raise SceneError(f"bar: {total} elements in all; contactqp takes at most "
                             f"{MAX_ELEMENTS} in a scene")
        node = _numbering(self.bars)
        held = _check_supports(self, node)
        _check_loads(self, node)
        walls = _check_walls(self, node, held)
        _check_contacts(self, node, held, walls)
        from contactqp.feasibility import impossible_constraints, indeterminate_contacts

        conflict = impossible_constraints(self) or indeterminate_contacts(self)
        if conflict:
            raise SceneError(conflict)

    @cached_property
    def layout(self) -> Layout:
        """The numbering of the scene's nodes and the arrays along it
        (:class:`~contactqp.model.Layout`), made once per scene: a scene does not change."""
        from contactqp.model.layout import Layout

        return Layout(self)

    @property
    def unit(self) -> Units:
        """The scene's unit system (:data:`UNIT_SYSTEMS`)."""
        return UNIT_SYSTEMS[self.units]

    @property
    def n_contacts(self) -> int:
        """Contact rows: one per wall, then one per bar contact."""
        return len(self.walls) + len(self.contacts)

    @property
    def n_elements(self) -> int:
        """Elements of every bar together."""
        return sum(b.n_elements for b in self.bars)

    def with_loads(self, loads: tuple[Load, ...],
                   distributed: tuple[DistributedLoad, ...] | None = None) -> Scene:
        """The same scene with other loads (point, and distributed when given)."""
        return replace(self, loads=tuple(loads),
                       distributed=self.distributed if distributed is None else tuple(distributed))

    def scaled_loads(self, factor: float) -> Scene:
        """The same scene with every load (point and distributed) times ``factor``."""
        factor = number("load factor", factor)
        return self.with_loads(tuple(replace(p, force=factor * p.force) for p in self.loads),
                               tuple(replace(q, intensity=factor * q.intensity)
                                     for q in self.distributed))

    def with_walls(self, walls: tuple[Wall, ...]) -> Scene:
        """The same scene with other walls."""
        return replace(self, walls=tuple(walls))

    def with_values(self, loads: Any = None, gaps: Any = None) -> Scene:
        """The same scene with other load values and gaps, everything else kept: ``loads``
        one per point load (force) then one per distributed load (force per length), in
        scene order; ``gaps`` one per contact row (the walls, then the bar contacts); in the
        scene's units; None keeps them. The new scene is checked as any scene is (gaps that
        leave a node no position are refused); its layout shares every array that does not
        depend on the values with this scene's (:meth:`Layout.with_values`)."""
        changes: dict[str, tuple] = {}
        if loads is not None:
            n_point = len(self.loads)
            values = value_array("loads", loads, (n_point + len(self.distributed),),
                                 "one per point load, then one per distributed load",
                                 OptionError)
            changes["loads"] = _valued(self.loads, "force", values[:n_point])
            changes["distributed"] = _valued(self.distributed, "intensity", values[n_point:])
        if gaps is not None:
            n_walls = len(self.walls)
            values = value_array("gaps", gaps, (self.n_contacts,),
                                 "one per wall, then one per bar contact", OptionError)
            changes["walls"] = _valued(self.walls, "gap", values[:n_walls])
            changes["contacts"] = _valued(self.contacts, "gap", values[n_walls:])
        if not changes:
            return self
        # the bars, supports and where everything sits are this scene's, already checked, and
        # the values were checked above: only what gaps decide is checked again
        scene = copy.copy(self)
        scene.__dict__.pop("layout", None)
        for name, value in changes.items():
            object.__setattr__(scene, name, value)
        if gaps is not None:
            from contactqp.feasibility import impossible_constraints, indeterminate_contacts

            conflict = impossible_constraints(scene) or indeterminate_contacts(scene)
            if conflict:
                raise SceneError(conflict)
        if "layout" in self.__dict__:
            scene.__dict__["layout"] = self.layout.with_values(scene)
        return scene


def row_names(scene: Scene) -> list[str]:
    """The name of each contact row as the scene file and the messages name it: wall[i] for
    the walls, then contact[j] for the bar contacts."""
    return ([f"wall[{i}]" for i in range(len(scene.walls))]
            + [f"contact[{j}]" for j in range(len(scene.contacts))])


def _valued(items: tuple, name: str, values: np.ndarray) -> tuple:
    """``items`` (frozen dataclasses, already checked) with field ``name`` set to ``values``
    (checked numbers): copies made field by field, 4x faster than dataclasses.replace, which
    runs __init__ again (a batch of 10⁴ cases makes 10⁴ of them)."""
    made = []
    for item, value in zip(items, values.tolist()):
        copy_ = object.__new__(type(item))
        copy_.__dict__.update(item.__dict__)
        copy_.__dict__[name] = value
        made.append(copy_)
    return tuple(made)


def _items(values: Any, kind: type, name: str) -> tuple:
    """``values`` (one ``kind`` or a sequence of them) as a tuple, else a SceneError."""
    if isinstance(values, kind):
        return (values,)
    if isinstance(values, (str, bytes)) or not isinstance(values, (tuple, list)):
        raise SceneError(f"{name} must be a contactqp.{kind.__name__} or a list of them, "
                         f"got {values!r}")
    for i, value in enumerate(values):
        if not isinstance(value, kind):
            raise SceneError(f"{name}[{i}] must be a contactqp.{kind.__name__}, got {value!r}")
    return tuple(values)


def _numbering(bars: tuple[Bar, ...]):
    """A function (field name, bar, node, suffix) -> the node's number in the scene's one node
    sequence (bar after bar), or a SceneError naming the field."""
    offsets = np.concatenate(([0], np.cumsum([b.n_nodes for b in bars])))

    def node(name: str, bar: Any, value: Any, suffix: str = "") -> int:
        b = whole_number(f"{name}.bar{suffix}", bar, 0, "bar number")
        if b >= len(bars):
            raise SceneError(f"{name}.bar{suffix} = {b}: the scene has bars 0 to {len(bars) - 1}")
        n = whole_number(f"{name}.node{suffix}", value, None, "node number")
        if not 0 <= n < bars[b].n_nodes:
            owner = "the bar" if len(bars) == 1 else f"bar[{b}]"
            raise SceneError(f"{name}.node{suffix} = {n}: {owner} has nodes 0 to "
                             f"{bars[b].n_nodes - 1}")
        return int(offsets[b]) + n

    return node


def _check_supports(scene: Scene, node) -> dict[int, int]:
    """No node held twice, not every node held, and something to hold a bar that has no
    support (a wall or a bar contact: whether its loads press it against one is decided with
    the contact kind, :func:`contactqp.feasibility.unheld_bars`): {node: support index}."""
    held: dict[int, int] = {}
    for i, s in enumerate(scene.supports):
        at = node(f"support[{i}]", s.bar, s.node)
        if at in held:
            raise SceneError(f"support[{i}].node = {s.node} repeats support[{held[at]}]")
        held[at] = i
    touched = {w.bar for w in scene.walls} | {c.bar_a for c in scene.contacts} | {
        c.bar_b for c in scene.contacts}
    for b in sorted(set(range(len(scene.bars))) - {s.bar for s in scene.supports} - touched):
        raise SceneError(f"support: bar[{b}] has no support, no wall and no contact: nothing "
                         "holds it; give it a [[support]]")
    if len(held) == sum(b.n_nodes for b in scene.bars):
        raise SceneError("support: every node is a support; nothing can move")
    return held


def _check_loads(scene: Scene, node) -> None:
    """Point loads on nodes, distributed loads on elements of a bar, all finite numbers."""
    for i, load in enumerate(scene.loads):
        node(f"load[{i}]", load.bar, load.node)
        number(f"load[{i}].force", load.force, tiny=True)
    for i, q in enumerate(scene.distributed):
        name = f"distributed_load[{i}]"
        number(f"{name}.intensity", q.intensity, tiny=True)
        b = whole_number(f"{name}.bar", q.bar, 0, "bar number")
        if b >= len(scene.bars):
            raise SceneError(f"{name}.bar = {b}: the scene has bars 0 to {len(scene.bars) - 1}")
        n_elements = scene.bars[b].n_elements
        stop = n_elements if q.stop is None else q.stop
        for key, value in (("start", q.start), ("stop", stop)):
            whole_number(f"{name}.{key}", value, None, "element number")
        if not 0 <= q.start < stop <= n_elements:
            raise SceneError(f"{name}: elements start = {q.start} to stop = {stop} (exclusive) "
                             f"must satisfy 0 <= start < stop <= {n_elements}")


def _check_walls(scene: Scene, node, held: dict[int, int]) -> dict[tuple[int, str], int]:
    """Walls on free nodes, one per side of a node: {(node, side): wall index}."""
    seen: dict[tuple[int, str], int] = {}
    for i, wall in enumerate(scene.walls):
        at = node(f"wall[{i}]", wall.bar, wall.node)
        number(f"wall[{i}].gap", wall.gap, tiny=True)
        if wall.side not in WALL_SIDES:
            raise SceneError(f"wall[{i}].side must be '+' or '-', got {wall.side!r}")
        if at in held:
            raise SceneError(f"wall[{i}].node = {wall.node} is support[{held[at]}]: a wall "
                             "there carries no force")
        if (at, wall.side) in seen:
            raise SceneError(f"wall[{i}] repeats wall[{seen[at, wall.side]}] (node {wall.node}, "
                             f"side {wall.side!r}): keep the one with the smaller gap")
        seen[at, wall.side] = i
    return seen


def _check_contacts(scene: Scene, node, held: dict[int, int],
                    walls: dict[tuple[int, str], int]) -> None:
    """Contacts between two nodes, not both held, none repeating another or a wall."""
    pairs: dict[tuple[int, int], int] = {}
    for i, c in enumerate(scene.contacts):
        a = node(f"contact[{i}]", c.bar_a, c.node_a, suffix="_a")
        b = node(f"contact[{i}]", c.bar_b, c.node_b, suffix="_b")
        number(f"contact[{i}].gap", c.gap, tiny=True)
        if c.bar_a == c.bar_b:  # its own elements already join the two nodes
            raise SceneError(f"contact[{i}]: bar_a = bar_b = {c.bar_a}; a bar contact joins "
                             "two different bars (a wall holds a node of one bar)")
        if a in held and b in held:
            raise SceneError(f"contact[{i}]: both nodes are supports; the contact carries no force")
        if (a, b) in pairs:
            raise SceneError(f"contact[{i}] repeats contact[{pairs[a, b]}]: keep the one with "
                             "the smaller gap")
        pairs[a, b] = i
        if a in held or b in held:  # one end held: a wall on the other end
            free, side = (b, "-") if a in held else (a, "+")
            if (free, side) in walls:
                raise SceneError(
                    f"contact[{i}] holds its free end like a {side!r} wall (its other end is "
                    f"a support) and repeats wall[{walls[free, side]}]: keep the one with the "
                    "smaller gap")


__all__ = [
    "AREA_RULES", "MAX_ELEMENTS", "SECTIONS", "UNIT_SYSTEMS", "WALL_SIDES", "Bar", "BarContact",
    "Circle", "Dimension", "DistributedLoad", "HollowCircle", "Load", "Rectangle", "Scene",
    "Section", "Support", "Units", "Wall", "section_areas",
]
