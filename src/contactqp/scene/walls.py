"""Many rigid walls given as arrays: :class:`Walls` (one node, gap, side and bar per wall),
which a scene and its layout read as arrays, with no Python object per wall; it still reads as
a sequence of :class:`~contactqp.scene.parts.Wall` (made on first use) wherever one is iterated.

:func:`validate_wall_set` is the scene's check of such a set together with the bars and supports
(nodes that exist, none at a support, one wall per node and side), in numpy passes, with the
same one-line messages as the check of Wall objects (contactqp.scene.validation).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from contactqp._validate import MAGNITUDE, is_number, shown
from contactqp.errors import SceneError
from contactqp.scene.parts import MAX_ELEMENTS, WALL_SIDES, Wall


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


def _refuse(name: str, values: Any, raw: np.ndarray, fits: Any, what: str) -> None:
    """A SceneError naming the first of ``values`` (as the user gave them) that ``fits``
    refuses, or the shape of a table given for a list."""
    if raw.ndim > 1:
        raise SceneError(f"{name} must be one value or a flat list (one per wall), got an "
                         f"array of shape {raw.shape}")
    if raw.ndim == 0:
        value = values.item() if isinstance(values, np.ndarray) else values
        if not fits(value):
            raise SceneError(f"{name} must be {what}, got {shown(value)}")
        return
    items = values if isinstance(values, (list, tuple)) else raw.tolist()
    for i, value in enumerate(items):
        if not fits(value):
            raise SceneError(f"{name}[{i}] must be {what}, got {shown(value)}")


def _is_whole(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _whole_numbers(name: str, values: Any, size: int | None) -> np.ndarray:
    """``values`` (one whole number, or one per wall) as a read-only intp array."""
    raw = np.asarray(values)
    if raw.shape == (0,):  # no walls: numpy reads an empty list as floats
        raw = raw.astype(np.intp)
    # a boolean in a list of numbers is read by numpy as 0 or 1: refused as Wall refuses it
    if raw.dtype.kind not in "iu" or raw.ndim > 1 or (
            isinstance(values, (list, tuple)) and any(isinstance(v, bool) for v in values)):
        _refuse(name, values, raw, _is_whole, "a whole number")
    if raw.ndim == 0 and size is None:
        raise SceneError(f"{name} must be a list of values (one per wall), got {shown(values)}")
    return _read_only(_sized(name, raw.astype(np.intp), size))


def _sized(name: str, values: np.ndarray, size: int | None) -> np.ndarray:
    """``values`` (a scalar, or 1-D) spread to ``size`` values, else a SceneError."""
    if size is None:
        if values.ndim != 1:
            raise SceneError(f"{name} must be a list of values (one per wall), got {shown(values)}")
        if values.size > MAX_ELEMENTS:
            raise SceneError(f"{name} has {values.size} values; contactqp takes at most "
                             f"{MAX_ELEMENTS} walls")
        return values
    if values.ndim == 0:
        return np.full(size, values)
    if values.shape != (size,):
        raise SceneError(f"{name} has {values.size} values: give one, or one per wall ({size})")
    return values


def checked_gaps(name: str, values: Any, size: int) -> np.ndarray:
    """Finite gaps within the range contactqp computes in, as a read-only float array."""
    raw = np.asarray(values)
    if raw.dtype.kind not in "iuf" or raw.ndim > 1 or (
            isinstance(values, (list, tuple)) and any(isinstance(v, bool) for v in values)):
        _refuse(name, values, raw, is_number, "a number")
    gaps = _sized(name, raw.astype(float), size)
    bad = np.flatnonzero(~np.isfinite(gaps) | (np.abs(gaps) > MAGNITUDE))
    if bad.size:
        i = int(bad[0])
        if not np.isfinite(gaps[i]):
            raise SceneError(f"{name}[{i}] must be finite, got {float(gaps[i])!r}")
        raise SceneError(f"{name}[{i}] = {float(gaps[i])!r} is outside the range contactqp "
                         f"computes in (at most {MAGNITUDE:.0e} in size; choose other units)")
    return _read_only(gaps)


def _sides(name: str, values: Any, size: int) -> np.ndarray:
    """Each wall's side, '+' or '-', as a read-only array of one-character text."""
    raw = np.asarray(values)
    if raw.dtype.kind != "U" or raw.ndim > 1 or not np.isin(raw, WALL_SIDES).all():
        _refuse(name, values, np.asarray(values, dtype=object), lambda side: isinstance(
            side, str) and side in WALL_SIDES, "'+' or '-'")
    return _read_only(_sized(name, raw.astype("<U1"), size))


class ReadAsItems:
    """A set kept as arrays that reads as the tuple of its objects, ``items`` (made on first
    use): iterated, indexed and added to a tuple as that tuple is."""

    def __iter__(self):
        return iter(self.items)

    def __getitem__(self, index: Any) -> Any:
        return self.items[index]

    def __add__(self, other: Any) -> tuple:
        return self.items + tuple(other)

    def __radd__(self, other: Any) -> tuple:
        return tuple(other) + self.items


@dataclass(frozen=True, eq=False)
class Walls(ReadAsItems):
    """Rigid walls given as arrays, one entry per wall: wall i is at node ``nodes[i]`` of bar
    ``bars[i]``, ``gaps[i]`` (m) away on side ``sides[i]``, exactly as ``Wall(nodes[i],
    gaps[i], sides[i], bars[i])`` (:class:`~contactqp.scene.Wall`) and in that row order.
    For scenes with many walls: a scene and its layout read the arrays, with no object per
    wall; iterated or indexed, it gives Wall objects (made once, on first use).

    Parameters
    ----------
    nodes : array_like of int
        The node of each wall.
    gaps : float or array_like
        One gap (m) for all, or one per wall; negative: a press fit.
    sides : str or array_like of str
        ``"+"`` (the default) or ``"-"``: one for all, or one per wall.
    bars : int or array_like of int
        One bar for all (default 0), or one per wall.
    name : str
        How messages name the set's fields (``"walls[0]"`` in a scene file).

    Raises
    ------
    SceneError
        A field that is not one value nor one per wall, a node or bar that is not a whole
        number, a gap that is not finite, a side not '+' or '-' (one line naming the field).
    """

    nodes: np.ndarray
    gaps: np.ndarray
    sides: np.ndarray = "+"  # type: ignore[assignment]
    bars: np.ndarray = 0  # type: ignore[assignment]
    name: str = "walls"

    def __post_init__(self) -> None:
        nodes = _whole_numbers(f"{self.name}.nodes", self.nodes, None)
        n = nodes.size
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "gaps", checked_gaps(f"{self.name}.gaps", self.gaps, n))
        object.__setattr__(self, "sides", _sides(f"{self.name}.sides", self.sides, n))
        object.__setattr__(self, "bars", _whole_numbers(f"{self.name}.bars", self.bars, n))

    @classmethod
    def of(cls, walls: Any) -> Walls:
        """One set of ``walls`` in order: :class:`Walls` and Wall objects (whose fields are
        checked already, contactqp.scene.validation.validate_wall_fields), each run of Wall
        objects read column by column."""
        if isinstance(walls, Walls):  # not iterated: that would make its Wall objects
            return walls
        parts: list[Walls] = []
        run: list[Wall] = []
        for wall in walls:
            if isinstance(wall, Walls):
                parts += [cls._of_objects(run), wall] if run else [wall]
                run = []
            else:
                run.append(wall)
        if run or not parts:
            parts.append(cls._of_objects(run))
        if len(parts) == 1:
            return parts[0]
        return cls._made(*(np.concatenate([getattr(p, key) for p in parts])
                           for key in ("nodes", "gaps", "sides", "bars")))

    @classmethod
    def _of_objects(cls, walls: list[Wall]) -> Walls:
        n = len(walls)
        return cls._made(np.fromiter((w.node for w in walls), np.intp, n),
                         np.fromiter((w.gap for w in walls), float, n),
                         np.array([w.side for w in walls], dtype="<U1").reshape(n),
                         np.fromiter((w.bar for w in walls), np.intp, n))

    @classmethod
    def _made(cls, nodes: np.ndarray, gaps: np.ndarray, sides: np.ndarray, bars: np.ndarray,
              name: str = "walls") -> Walls:
        """A set from arrays already checked (no second pass over them)."""
        made = object.__new__(cls)
        for key, value in (("nodes", nodes), ("gaps", gaps), ("sides", sides), ("bars", bars)):
            object.__setattr__(made, key, _read_only(value))
        object.__setattr__(made, "name", name)
        return made

    def with_gaps(self, gaps: np.ndarray) -> Walls:
        """The same walls with other gaps (``gaps``: checked floats, one per wall)."""
        made = object.__new__(type(self))
        made.__dict__.update(self.__dict__)
        made.__dict__.pop("items", None)
        made.__dict__["gaps"] = _read_only(np.array(gaps, dtype=float))
        return made

    def tiled(self, copies: int, bars: int) -> Walls:
        """These walls repeated ``copies`` times, one copy after another, copy c on the bars
        ``c·bars`` further on (a batch's scene: :func:`contactqp.many.batch.tiled_scene`)."""
        shift = bars * np.arange(copies, dtype=np.intp)[:, None]
        return self._made(np.tile(self.nodes, copies), np.tile(self.gaps, copies),
                          np.tile(self.sides, copies), (self.bars + shift).ravel(), self.name)

    @cached_property
    def signs(self) -> np.ndarray:
        """+1.0 for a wall on the + side, −1.0 for the − side: each row is sign·u <= gap."""
        return _read_only(np.where(self.sides == "+", 1.0, -1.0))

    @cached_property
    def items(self) -> tuple[Wall, ...]:
        """The walls as :class:`Wall` objects, in order (made on first use)."""
        return tuple(map(Wall, self.nodes.tolist(), self.gaps.tolist(), self.sides.tolist(),
                         self.bars.tolist()))

    def __len__(self) -> int:
        return int(self.nodes.size)

    def __bool__(self) -> bool:
        return bool(self.nodes.size)

    def __eq__(self, other: object) -> bool:
        """Equal to another set with the same arrays, or to a tuple of the same Walls."""
        if isinstance(other, Walls):
            return all(np.array_equal(getattr(self, k), getattr(other, k))
                       for k in ("nodes", "gaps", "sides", "bars"))
        if isinstance(other, tuple):
            return self.items == other
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"Walls({len(self)} walls)"


def validate_wall_set(walls: Walls, node_counts: np.ndarray, offsets: np.ndarray,
                   held: dict[int, int]) -> None:
    """The scene's checks of a :class:`Walls` (as contactqp.scene.validation's of Wall
    objects, with its messages): every bar and node exists, no wall at a support, one wall per
    node and side. ``node_counts``: nodes of each bar; ``offsets``: global number of each
    bar's node 0; ``held``: {global node: support index}."""
    bars, nodes = walls.bars, walls.nodes
    n_bars = node_counts.size
    bad = np.flatnonzero((bars < 0) | (bars >= n_bars))
    if bad.size:
        i = int(bad[0])
        if bars[i] < 0:
            raise SceneError(f"wall[{i}].bar must be a whole bar number >= 0, got {bars[i]}")
        raise SceneError(f"wall[{i}].bar = {bars[i]}: the scene has bars 0 to {n_bars - 1}")
    bad = np.flatnonzero((nodes < 0) | (nodes >= node_counts[bars]))
    if bad.size:
        i = int(bad[0])
        owner = "the bar" if n_bars == 1 else f"bar[{bars[i]}]"
        raise SceneError(f"wall[{i}].node = {nodes[i]}: {owner} has nodes 0 to "
                         f"{node_counts[bars[i]] - 1}")
    at = offsets[bars] + nodes
    if held:
        support = np.fromiter(held, np.intp, len(held))
        bad = np.flatnonzero(np.isin(at, support))
        if bad.size:
            i = int(bad[0])
            raise SceneError(f"wall[{i}].node = {nodes[i]} is support[{held[int(at[i])]}]: a "
                             "wall there carries no force")
    _validate_repeats(walls, 2 * at + (walls.sides == "-"))


def _validate_repeats(walls: Walls, keys: np.ndarray) -> None:
    """One wall per node and side (``keys``: one number per (node, side))."""
    order = np.argsort(keys, kind="stable")
    repeated = np.flatnonzero(keys[order][1:] == keys[order][:-1])
    if repeated.size:
        # the first wall (in row order) that repeats an earlier one, and that earlier one
        i = int(order[repeated + 1].min())
        first = int(order[np.searchsorted(keys[order], keys[i])])  # stable: the earliest
        raise SceneError(f"wall[{i}] repeats wall[{first}] (node {walls.nodes[i]}, side "
                         f"{str(walls.sides[i])!r}): keep the one with the smaller gap")
