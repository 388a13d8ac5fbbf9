"""The :class:`Scene`: bars with their supports, loads, walls and bar contacts, in one unit
system, checked together when it is built (contactqp.scene.validation, and
contactqp.feasibility for whether the walls and contacts leave every node a position and
determine the contact forces); :func:`row_names`, how messages name its contact rows.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from contactqp._validate import number, one_of, text, value_array
from contactqp.errors import OptionError, SceneError
from contactqp.feasibility import impossible_constraints, indeterminate_contacts
from contactqp.scene.parts import (
    MAX_ELEMENTS,
    Bar,
    BarContact,
    Bed,
    DistributedLoad,
    Load,
    Support,
    Wall,
)
from contactqp.scene.validation import (
    _numbering,
    _validate_contacts,
    _validate_loads,
    _validate_supports,
    _validate_walls,
    validate_wall_fields,
)
from contactqp.scene.walls import ReadAsItems, Walls
from contactqp.units import UNIT_SYSTEMS, Units

# The chain model's numbering, registered by contactqp.model.chain.numbering when it is
# imported (import contactqp imports it): Scene.layout reads it through this, so that a scene
# imports nothing of the model that reads it
NUMBERING: list[Callable[[Any], Any]] = []
# What the chain model keeps in a scene (its numbering, its model), which a scene made from it
# with other values, or a scene's detached copy, leaves out
SCENE_MODEL = "_scene_model"  # where contactqp.model.chain.scene_model keeps a scene's model
KEPT = ("layout", SCENE_MODEL)


@dataclass(frozen=True, eq=False)
class Scene:
    """Bars with supports, loads, rigid walls and bar-to-bar contacts, checked on construction.

    ``bars``: one :class:`Bar` or a sequence of them (kept as a tuple either way). A bar
    with no support is held by its walls and bar contacts alone; its loads must press it
    against them (checked at the solve, :func:`contactqp.model.chain.floating.unheld_bars`). Contact rows, in this order everywhere (contact forces, penetrations):
    one per wall, then one per bar contact. ``units``: :data:`UNIT_SYSTEMS`.

    Parameters
    ----------
    bars : Bar or sequence of Bar
        The bars, numbered 0, 1, … in this order.
    supports : sequence of Support
        The nodes held at u = 0.
    loads : sequence of Load
        The point loads.
    walls : sequence of Wall, or Walls
        The rigid walls: :class:`Wall` objects, a :class:`Walls` (many walls as arrays, read
        with no object per wall), or a list of both (joined into one Walls, in order).
    name : str
        How tables, charts and messages name the scene.
    distributed : sequence of DistributedLoad
        The uniform axial loads.
    contacts : sequence of BarContact
        The contacts between bars.
    units : str
        ``"SI"`` (m, m², N, Pa; the default) or ``"mm-N-MPa"``.
    beds : sequence of Bed
        Frictional beds, at most one per bar (a scene with a bed is solved with friction by
        :func:`contactqp.solve`; it has no walls or bar contacts).

    Raises
    ------
    SceneError
        A bad value, a reference to a bar or node that does not exist, or constraints that leave
        a node no position (one line naming the field and the value).
    """

    bars: tuple[Bar, ...]
    supports: tuple[Support, ...]
    loads: tuple[Load, ...] = ()
    walls: tuple[Wall, ...] | Walls = ()
    name: str = "scene"
    distributed: tuple[DistributedLoad, ...] = ()
    contacts: tuple[BarContact, ...] = ()
    units: str = "SI"
    beds: tuple[Bed, ...] = ()

    def __post_init__(self) -> None:
        if isinstance(self.loads, ValuedLoads):  # a batch's scene, made again (replace)
            object.__setattr__(self, "loads", self.loads.items)
        for key, kind, plural in (("bars", Bar, "bar"), ("supports", Support, "support"),
                                  ("loads", Load, "load"),
                                  ("distributed", DistributedLoad, "distributed_load"),
                                  ("contacts", BarContact, "contact"), ("beds", Bed, "bed")):
            object.__setattr__(self, key, _items(getattr(self, key), kind, plural))
        object.__setattr__(self, "walls", _wall_items(self.walls))
        if not self.bars:
            raise SceneError("bar: no bar; give at least one [bar]")
        text("name", self.name)
        one_of("units", self.units, UNIT_SYSTEMS)
        total = sum(b.n_elements for b in self.bars)
        if total > MAX_ELEMENTS:
            raise SceneError(f"bar: {total} elements in all; contactqp takes at most "
                             f"{MAX_ELEMENTS} in a scene")
        node = _numbering(self.bars)
        held = _validate_supports(self, node)
        _validate_loads(self, node)
        walls = _validate_walls(self, node, held)
        _validate_contacts(self, node, held, walls)
        _validate_beds(self)
        conflict = _conflict(self)
        if conflict:
            raise SceneError(conflict)

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without what the chain model keeps in it (:data:`KEPT`: made again where
        read)."""
        return {k: v for k, v in self.__dict__.items() if k not in KEPT}

    @property
    def layout(self) -> Any:
        """The numbering of the scene's nodes and the arrays along it
        (:class:`~contactqp.model.Layout`), made once per scene by the chain model
        (:func:`contactqp.model.chain.layout_of`, which this reaches through
        :data:`NUMBERING`: a scene knows no numbering, and imports none)."""
        if not NUMBERING:
            raise SceneError("scene.layout needs the chain model: import contactqp")
        return NUMBERING[0](self)

    @property
    def unit(self) -> Units:
        """The scene's unit system (:data:`UNIT_SYSTEMS`)."""
        return UNIT_SYSTEMS[self.units]

    @property
    def unit_names(self) -> tuple[str, str]:
        """(force, length): the names of the scene's force and length units, as a problem's
        :attr:`~contactqp.problem.Problem.unit_names`."""
        return self.unit.force, self.unit.length

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

    def with_walls(self, walls: tuple[Wall, ...] | Walls) -> Scene:
        """The same scene with other walls (Wall objects, a :class:`Walls`, or both)."""
        return replace(self, walls=walls if isinstance(walls, Walls) else tuple(walls))

    def with_values(self, loads: Any = None, gaps: Any = None, *,
                    load_objects: bool = True) -> Scene:
        """The same scene with other load values and gaps, everything else kept: ``loads``
        one per point load (force) then one per distributed load (force per length), in
        scene order; ``gaps`` one per contact row (the walls, then the bar contacts); in the
        scene's units; None keeps them. The new scene is checked as any scene is (gaps that
        leave a node no position are refused); its layout shares every array that does not
        depend on the values with this scene's (:meth:`Layout.with_values`).
        ``load_objects=False`` keeps the point loads' forces as an array, their Load objects
        made only when they are read one by one (:attr:`load_forces` reads the array): for a
        batch's scene of many cases (:mod:`contactqp.many.batch`)."""
        changes: dict[str, Any] = {}
        if loads is not None:
            n_point = len(self.loads)
            values = value_array("loads", loads, (n_point + len(self.distributed),),
                                 "one per point load, then one per distributed load",
                                 OptionError)
            changes["loads"] = (_valued(self.loads, "force", values[:n_point]) if load_objects
                                else ValuedLoads(tuple(self.loads), values[:n_point]))
            changes["distributed"] = _valued(self.distributed, "intensity", values[n_point:])
        if gaps is not None:
            n_walls = len(self.walls)
            values = value_array("gaps", gaps, (self.n_contacts,),
                                 "one per wall, then one per bar contact", OptionError)
            changes["walls"] = (self.walls.with_gaps(values[:n_walls])
                                if isinstance(self.walls, Walls)
                                else _valued(self.walls, "gap", values[:n_walls]))
            changes["contacts"] = _valued(self.contacts, "gap", values[n_walls:])
        if not changes:
            return self
        # the bars, supports and where everything sits are this scene's, already checked, and
        # the values were checked above: only what gaps decide is checked again
        scene = detached(self)
        for name, value in changes.items():
            object.__setattr__(scene, name, value)
        if gaps is not None:
            conflict = _conflict(scene, self)
            if conflict:
                raise SceneError(conflict)
        # a numbering already made for this scene (contactqp.model.chain.layout_of) shares
        # with the new scene's every array that does not depend on the values
        if "layout" in self.__dict__:
            scene.__dict__["layout"] = self.__dict__["layout"].with_values(scene)
        return scene

    @property
    def load_forces(self) -> np.ndarray:
        """The point loads' forces in scene order, as an array (force)."""
        if isinstance(self.loads, ValuedLoads):
            return self.loads.forces
        return np.fromiter((p.force for p in self.loads), float, len(self.loads))

    @cached_property
    def _opposed_walls(self) -> tuple[np.ndarray, np.ndarray]:
        """The walls that share a node with a wall on its other side, as two arrays of rows
        paired (the earlier row first). Where the walls sit is all it reads: a scene made by
        :meth:`with_values` shares its scene's (:func:`_conflict`)."""
        walls = Walls.of(self.walls)
        offsets = np.concatenate(([0], np.cumsum([b.n_nodes for b in self.bars])))
        at = offsets[walls.bars] + walls.nodes
        # one wall per node and side (checked before): two walls at a node are one each side
        order = np.argsort(at, kind="stable")
        pair = np.flatnonzero(at[order][1:] == at[order][:-1])
        return order[pair], order[pair + 1]


class ValuedLoads(ReadAsItems, Sequence):
    """A scene's point loads with other forces (:meth:`Scene.with_values` with
    ``load_objects=False``): the forces kept as an array, and read as a sequence of
    :class:`Load` (as the tuple of them would read) with the objects made on first use.

    Parameters
    ----------
    loads : tuple of Load
        The scene's point loads, already checked (where each sits).
    forces : numpy.ndarray
        One checked force per load, in order.
    """

    def __init__(self, loads: tuple[Load, ...], forces: np.ndarray) -> None:
        self.loads = loads
        self.forces = np.array(forces, dtype=float)
        self.forces.flags.writeable = False

    @cached_property
    def items(self) -> tuple[Load, ...]:
        """The loads as Load objects, in order (made on first use)."""
        return _valued(self.loads, "force", self.forces)

    def __len__(self) -> int:
        return len(self.loads)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (ValuedLoads, tuple)):
            return self.items == tuple(other)
        return NotImplemented

    def __repr__(self) -> str:
        return repr(self.items)


def side_by_side(scene: Scene, copies: int) -> Scene:
    """``scene`` repeated ``copies`` times as one scene: the copies' bars one after another,
    each copy's supports, loads, walls and bar contacts on its own bars (all the copies'
    walls, one :class:`Walls`, then all their bar contacts, copy after copy). Not checked
    again: each copy is ``scene`` (checked), on bars of its own, and nothing joins two copies;
    the caller keeps the copies' elements within :data:`MAX_ELEMENTS`."""
    n = len(scene.bars)

    def moved(items: Any, *names: str) -> tuple:
        made = []
        for copy_ in range(copies):
            for item in items:  # a copy field by field, as _valued makes them
                shifted = object.__new__(type(item))
                shifted.__dict__.update(item.__dict__)
                for name in names:
                    shifted.__dict__[name] = getattr(item, name) + copy_ * n
                made.append(shifted)
        return tuple(made)

    tiled = object.__new__(Scene)
    for name, value in (
            ("bars", scene.bars * copies), ("supports", moved(scene.supports, "bar")),
            ("loads", moved(scene.loads, "bar")),
            ("walls", Walls.of(scene.walls).tiled(copies, n) if scene.walls else ()),
            ("name", f"{scene.name} x {copies} cases"),
            ("distributed", moved(scene.distributed, "bar")),
            ("contacts", moved(scene.contacts, "bar_a", "bar_b")), ("units", scene.units)):
        object.__setattr__(tiled, name, value)
    return tiled


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


def _conflict(scene: Scene, placed: Scene | None = None) -> str:
    """:func:`impossible_constraints`, then :func:`indeterminate_contacts`: why the scene's
    constraints leave a node no position or its contact forces undetermined, or "". A
    scene without bar contacts is first checked in numpy passes: with walls alone the only
    conflict is a node whose two walls' gaps sum below 0 (a wall repeating another is refused
    before); the graph, a Python object and a text per wall, is made only to name it.
    ``placed``: a scene whose walls sit where ``scene``'s do (:meth:`Scene.with_values`), whose
    pairs of opposed walls are kept (made once for all its values)."""
    walls = scene.walls
    # finding the pairs costs ~50 µs, the graph ~4 µs a wall: in a new scene a few Wall
    # objects go to the graph; with the pairs kept, the test costs a few µs
    if not scene.contacts and (placed is not None or isinstance(walls, Walls) or len(walls) > 16):
        first, second = (scene if placed is None else placed)._opposed_walls
        gaps = (walls.gaps if isinstance(walls, Walls)
                else np.fromiter((w.gap for w in walls), float, len(walls)))
        # at a node with a wall on each side, the room between them: the two gaps summed
        if not (gaps[first] + gaps[second] < 0.0).any():
            return ""
    return impossible_constraints(scene) or indeterminate_contacts(scene)


def _wall_items(values: Any) -> tuple[Wall, ...] | Walls:
    """The scene's walls: Wall objects as a tuple (as before), a :class:`Walls` as it is, a
    list holding a Walls joined into one Walls (the Wall objects' fields checked first)."""
    if isinstance(values, Walls):
        return values
    if isinstance(values, (tuple, list)) and any(isinstance(v, Walls) for v in values):
        rows = 0
        for i, value in enumerate(values):
            if not isinstance(value, (Wall, Walls)):
                raise SceneError(f"wall[{i}] must be a contactqp.Wall or Walls, got {value!r}")
            if isinstance(value, Wall):
                validate_wall_fields(f"wall[{rows}]", value)
            rows += len(value) if isinstance(value, Walls) else 1
        return Walls.of(values)
    return _items(values, Wall, "wall")


def _validate_beds(scene: Scene) -> None:
    """Each bed on a bar of the scene, one per bar, τ positive and finite; a bed with walls or
    bar contacts is refused (their rows are normal rows without friction, the bed's friction
    rows have no normal: the friction model pairs one of each per contact)."""
    seen: set[int] = set()
    for i, bed in enumerate(scene.beds):
        bar = bed.bar
        if isinstance(bar, bool) or not isinstance(bar, (int, np.integer)) or not (
                0 <= bar < len(scene.bars)):
            raise SceneError(f"bed[{i}].bar = {bar!r}: no such bar (the scene has "
                             f"{len(scene.bars)})")
        if int(bar) in seen:
            raise SceneError(f"bed[{i}].bar = {bar}: that bar already lies on a bed")
        seen.add(int(bar))
        number(f"bed[{i}].tau", bed.tau, minimum=0.0, strict=True)
    if scene.beds and scene.n_contacts:
        raise SceneError(f"bed: a scene with a bed and {len(scene.walls)} walls, "
                         f"{len(scene.contacts)} bar contacts: walls and bar contacts beside a "
                         "frictional bed are not modelled; give the bed alone")


def detached(scene: Scene) -> Scene:
    """``scene`` without what the chain model keeps in it (:data:`KEPT`): a copy that shares
    its parts, which do not change. A scene's numbering holds its scene's detached copy, so
    that the two do not hold each other: that cycle kept each solve's model (42 MB for 10⁵
    elements) until Python's cyclic collector ran."""
    return copy.copy(scene)  # which leaves it out, as pickle does (Scene.__getstate__)


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
