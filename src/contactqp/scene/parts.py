"""What a scene is made of: :class:`Bar` (elements, each with a length, an area and a
modulus), :class:`Support`, :class:`Load`, :class:`DistributedLoad`, :class:`Wall` and
:class:`BarContact`, each a frozen value that checks its own fields; the :class:`Scene` checks
how they fit together (contactqp.scene.scene).

Each bar numbers its nodes 0..n along +x; element e joins its nodes e and e + 1; supports,
loads and walls name a bar (default 0) and a node of it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import numpy as np

from contactqp._validate import number, positive_numbers, whole_number
from contactqp.errors import SceneError
from contactqp.scene.sections import (
    AreaRule,
    Circle,
    Section,
    section_areas,
)

WallSide = Literal["+", "-"]
WALL_SIDES = ("+", "-")
MAX_ELEMENTS = 10_000_000  # every element costs ~1 kB across model, solve and check


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
class Bed:
    """Bar ``bar`` lying along its whole length on a frictional bed, which resists its sliding
    up to ``tau`` per unit length (Tresca's law: a limit that does not depend on a normal
    force). Each node carries τ times its tributary length (half an element at each end);
    a scene with a bed is solved with friction (docs/friction.md, "The frictional bed").

    Parameters
    ----------
    tau : float
        τ, the largest friction force per unit length (N/m), positive.
    bar : int
        The bar (default 0).
    """

    tau: float
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
