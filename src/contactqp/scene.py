"""What the user describes: one elastic bar, its supports, point loads and rigid walls.

Units are SI throughout: m, m², N, Pa. Nodes are numbered 0..n along the bar (+x); element e
joins nodes e and e + 1. Every value is checked when the scene is built, and an error names
the field (as it is spelled in the TOML file) and the value.
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

import numpy as np

from contactqp.errors import SceneError

AreaRule = Literal["midpoint", "exact"]
WallSide = Literal["+", "-"]
AREA_RULES = ("midpoint", "exact")
WALL_SIDES = ("+", "-")


def _positive_finite_array(name: str, values: Any) -> np.ndarray:
    """Return ``values`` as a read-only float array, all finite and > 0, else a SceneError."""
    try:
        array = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise SceneError(f"{name} must be numbers, got {values!r}") from None
    bad = np.flatnonzero(~np.isfinite(array) | (array <= 0.0))
    if bad.size:
        i = int(bad[0])
        raise SceneError(f"{name}[{i}] must be a positive finite number, got {float(array[i])!r}")
    array.flags.writeable = False
    return array


def _number(name: str, value: Any, *, minimum: float | None = None, strict: bool = False) -> float:
    """Return ``value`` as a finite float (optionally >= or > ``minimum``), else a SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SceneError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise SceneError(f"{name} must be finite, got {number!r}")
    if minimum is not None and (number <= minimum if strict else number < minimum):
        relation = ">" if strict else ">="
        raise SceneError(f"{name} must be {relation} {minimum:g}, got {number!r}")
    return number


def _node(name: str, value: Any, n_nodes: int) -> int:
    """Return ``value`` as a node index of a bar with ``n_nodes`` nodes, else a SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SceneError(f"{name} must be a whole node number, got {value!r}")
    if not 0 <= value < n_nodes:
        raise SceneError(f"{name} = {value}: the bar has nodes 0 to {n_nodes - 1}")
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
    """A node held at zero displacement."""

    node: int


@dataclass(frozen=True)
class Load:
    """A point load at a node (N, positive in +x)."""

    node: int
    force: float


@dataclass(frozen=True)
class Wall:
    """A rigid wall at a node, ``gap`` (m, >= 0) away from it on ``side``.

    ``side="+"``: the node may not move past u = +gap; the wall can only push in -x.
    ``side="-"``: the node may not move past u = -gap; the wall can only push in +x.
    """

    node: int
    gap: float
    side: WallSide = "+"

    @property
    def sign(self) -> float:
        """+1 for a wall on the + side, -1 for the - side: the constraint is sign·u <= gap."""
        return 1.0 if self.side == "+" else -1.0


@dataclass(frozen=True, eq=False)
class Scene:
    """A bar with supports, point loads and rigid walls, checked on construction."""

    bar: Bar
    supports: tuple[Support, ...]
    loads: tuple[Load, ...] = ()
    walls: tuple[Wall, ...] = ()
    name: str = "scene"

    def __post_init__(self) -> None:
        if not isinstance(self.bar, Bar):
            raise SceneError(f"bar must be a contactqp.Bar, got {type(self.bar).__name__}")
        n = self.bar.n_nodes
        supports = tuple(_as(Support, s, f"support[{i}]") for i, s in enumerate(self.supports))
        loads = tuple(_as(Load, s, f"load[{i}]") for i, s in enumerate(self.loads))
        walls = tuple(_as(Wall, s, f"wall[{i}]") for i, s in enumerate(self.walls))
        if not supports:
            raise SceneError("support: no support holds the bar; give at least one [[support]]")
        held: dict[int, int] = {}
        for i, s in enumerate(supports):
            node = _node(f"support[{i}].node", s.node, n)
            if node in held:
                raise SceneError(f"support[{i}].node = {node} repeats support[{held[node]}]")
            held[node] = i
        if len(held) == n:
            raise SceneError(f"support: every node (0 to {n - 1}) is a support; nothing can move")
        for i, load in enumerate(loads):
            _node(f"load[{i}].node", load.node, n)
            _number(f"load[{i}].force", load.force)
        seen: dict[tuple[int, str], int] = {}
        for i, wall in enumerate(walls):
            node = _node(f"wall[{i}].node", wall.node, n)
            _number(f"wall[{i}].gap", wall.gap, minimum=0.0)
            if wall.side not in WALL_SIDES:
                raise SceneError(f"wall[{i}].side must be '+' or '-', got {wall.side!r}")
            if node in held:
                raise SceneError(
                    f"wall[{i}].node = {node} is support[{held[node]}]: a wall there carries no force"
                )
            if (node, wall.side) in seen:
                raise SceneError(
                    f"wall[{i}] repeats wall[{seen[node, wall.side]}] (node {node}, side "
                    f"{wall.side!r}): keep the one with the smaller gap"
                )
            seen[node, wall.side] = i
        object.__setattr__(self, "supports", supports)
        object.__setattr__(self, "loads", loads)
        object.__setattr__(self, "walls", walls)

    @property
    def n_nodes(self) -> int:
        return self.bar.n_nodes

    def nodal_loads(self) -> np.ndarray:
        """The point loads summed per node (N), length n_nodes."""
        p = np.zeros(self.n_nodes)
        for load in self.loads:
            p[load.node] += float(load.force)
        return p

    def with_loads(self, loads: tuple[Load, ...]) -> Scene:
        """The same scene with other loads."""
        return Scene(self.bar, self.supports, tuple(loads), self.walls, self.name)

    def with_walls(self, walls: tuple[Wall, ...]) -> Scene:
        """The same scene with other walls."""
        return Scene(self.bar, self.supports, self.loads, tuple(walls), self.name)


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


def needed_nodes(scene: Scene) -> np.ndarray:
    """The nodes a scene needs: both ends, supports, loads and walls (sorted node numbers)."""
    nodes = {0, scene.n_nodes - 1}
    nodes.update(s.node for s in scene.supports)
    nodes.update(p.node for p in scene.loads)
    nodes.update(w.node for w in scene.walls)
    return np.array(sorted(nodes))


def minimal(scene: Scene) -> Scene:
    """The same scene with nodes only where it needs them (:func:`needed_nodes`).

    The elements between two kept nodes become one element with their series flexibility
    Σ L/(EA), so displacements at the kept nodes, contact forces, reactions and element forces
    are exactly those of the original model (static condensation of unloaded nodes). Stresses
    are those of the merged element's equivalent area: for a taper meshed with
    ``area_rule="exact"`` that is the exact cone's, and one element per segment reproduces the
    continuum answer.
    """
    kept = needed_nodes(scene)
    new_number = np.full(scene.n_nodes, -1)
    new_number[kept] = np.arange(kept.size)
    bar = scene.bar
    flexibility = np.concatenate(([0.0], np.cumsum(1.0 / bar.stiffness)))[kept]
    x = bar.node_x[kept]
    lengths = np.diff(x)
    modulus = bar.youngs_modulus[np.searchsorted(bar.node_x, x[:-1], side="right") - 1]
    areas = lengths / (modulus * np.diff(flexibility))  # E A / L = 1 / Σ L/(EA)
    merged = Bar(lengths, areas, modulus, bar.yield_stress)
    return Scene(
        merged,
        tuple(Support(int(new_number[s.node])) for s in scene.supports),
        tuple(Load(int(new_number[p.node]), p.force) for p in scene.loads),
        tuple(Wall(int(new_number[w.node]), w.gap, w.side) for w in scene.walls),
        name=f"{scene.name} (minimal mesh)",
    )


# ---------------------------------------------------------------------------------------------
# TOML

_TOP_KEYS = {"name", "material", "bar", "support", "load", "wall"}
_MATERIAL_KEYS = {"youngs_modulus", "yield_stress"}
_BAR_KEYS = {"length", "lengths", "elements", "section", "areas"}
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


def scene_from_dict(data: dict, name: str = "scene") -> Scene:
    """Build a scene from the parsed TOML structure documented in the README."""
    data = _table(data, "scene", _TOP_KEYS, {"material", "bar"})
    material = _table(data["material"], "material", _MATERIAL_KEYS, {"youngs_modulus"})
    modulus = _number("material.youngs_modulus", material["youngs_modulus"], minimum=0.0, strict=True)
    yield_stress = material.get("yield_stress")
    bar_data = _table(data["bar"], "bar", _BAR_KEYS)
    if "areas" in bar_data:
        if "section" in bar_data or "elements" in bar_data:
            raise SceneError("bar: give either areas or elements + section, not both")
        if not isinstance(bar_data["areas"], list):
            raise SceneError(f"bar.areas must be a list of numbers, got {bar_data['areas']!r}")
        bar = Bar.from_areas(
            bar_data["areas"], modulus, length=bar_data.get("length"),
            lengths=bar_data.get("lengths"), yield_stress=yield_stress,
        )
    else:
        for key in ("length", "elements", "section"):
            if key not in bar_data:
                raise SceneError(f"bar.{key} is missing (or give bar.areas)")
        if "lengths" in bar_data:
            raise SceneError("bar.lengths goes with bar.areas; with bar.section the elements are "
                             "equal (bar.length / bar.elements)")
        section = _table(bar_data["section"], "bar.section", _SECTION_KEYS,
                         {"shape", "diameter_start", "diameter_end"})
        if section["shape"] != "circle":
            raise SceneError(f"bar.section.shape must be 'circle', got {section['shape']!r}")
        bar = Bar.tapered_circle(
            bar_data["length"], bar_data["elements"], section["diameter_start"],
            section["diameter_end"], modulus, area_rule=section.get("area_rule", "midpoint"),
            yield_stress=yield_stress,
        )
    supports = tuple(Support(s["node"]) for s in _array_of_tables(data, "support", {"node"}, {"node"}))
    loads = tuple(
        Load(s["node"], s["force"])
        for s in _array_of_tables(data, "load", {"node", "force"}, {"node", "force"})
    )
    walls = tuple(
        Wall(s["node"], s["gap"], s.get("side", "+"))
        for s in _array_of_tables(data, "wall", {"node", "gap", "side"}, {"node", "gap"})
    )
    return Scene(bar, supports, loads, walls, name=str(data.get("name", name)))


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
    """The scene as TOML text that :func:`load_scene` reads back (explicit areas and lengths)."""
    bar = scene.bar
    moduli = np.unique(bar.youngs_modulus)
    if moduli.size != 1:
        raise SceneError("scene_to_toml: a bar with several moduli has no TOML form yet")
    lines = [f"name = {json.dumps(scene.name)}", "", "[material]",  # JSON strings are TOML
             f"youngs_modulus = {float(moduli[0])!r}"]
    if bar.yield_stress is not None:
        lines.append(f"yield_stress = {bar.yield_stress!r}")
    lines += ["", "[bar]", f"areas = {[float(a) for a in bar.areas]!r}",
              f"lengths = {[float(v) for v in bar.lengths]!r}"]
    for s in scene.supports:
        lines += ["", "[[support]]", f"node = {s.node}"]
    for p in scene.loads:
        lines += ["", "[[load]]", f"node = {p.node}", f"force = {float(p.force)!r}"]
    for w in scene.walls:
        lines += ["", "[[wall]]", f"node = {w.node}", f"gap = {float(w.gap)!r}", f'side = "{w.side}"']
    return "\n".join(lines) + "\n"


__all__ = [
    "AREA_RULES", "Bar", "Load", "Scene", "Support", "Wall", "circle_areas", "load_scene",
    "minimal", "needed_nodes", "scene_from_dict", "scene_to_toml", "seed_scene",
]
