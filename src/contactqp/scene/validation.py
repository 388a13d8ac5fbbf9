"""The checks a :class:`~contactqp.scene.Scene` runs on its parts together: every bar and node
a support, load, wall or contact names exists, nothing is held twice, every bar is held by
something. Each error names the field as a scene file spells it, and the value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from contactqp._validate import MAGNITUDE, number, whole_number
from contactqp.errors import SceneError
from contactqp.scene.parts import WALL_SIDES, Bar, Wall
from contactqp.scene.walls import Walls, validate_wall_set

Scene = Any  # the Scene being built (contactqp.scene.scene), which imports this module


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


def _validate_supports(scene: Scene, node) -> dict[int, int]:
    """No node held twice, not every node held, and something to hold a bar that has no
    support (a wall or a bar contact: whether its loads press it against one is decided with
    the contact kind, :func:`contactqp.model.chain.floating.unheld_bars`): {node: support index}."""
    held: dict[int, int] = {}
    for i, s in enumerate(scene.supports):
        at = node(f"support[{i}]", s.bar, s.node)
        if at in held:
            raise SceneError(f"support[{i}].node = {s.node} repeats support[{held[at]}]")
        held[at] = i
    walls = scene.walls
    walled = (set(np.unique(walls.bars).tolist()) if isinstance(walls, Walls)
              else {w.bar for w in walls})
    touched = walled | {c.bar_a for c in scene.contacts} | {
        c.bar_b for c in scene.contacts}
    for b in sorted(set(range(len(scene.bars))) - {s.bar for s in scene.supports} - touched):
        raise SceneError(f"support: bar[{b}] has no support, no wall and no contact: nothing "
                         "holds it; give it a [[support]]")
    if len(held) == sum(b.n_nodes for b in scene.bars):
        raise SceneError("support: every node is a support; nothing can move")
    return held


def _validate_loads(scene: Scene, node) -> None:
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


def validate_wall_fields(name: str, wall: Wall) -> None:
    """A Wall's own fields (those that need no scene): a gap that is a finite number, a side
    '+' or '-', whole numbers for its node and bar."""
    whole_number(f"{name}.bar", wall.bar, 0, "bar number")
    whole_number(f"{name}.node", wall.node, None, "node number")
    number(f"{name}.gap", wall.gap, tiny=True)
    if wall.side not in WALL_SIDES:
        raise SceneError(f"{name}.side must be '+' or '-', got {wall.side!r}")


def _validate_walls(scene: Scene, node, held: dict[int, int]) -> dict[tuple[int, str], int]:
    """Walls on free nodes, one per side of a node: {(node, side): wall index} (for a
    :class:`Walls`, checked in numpy passes, and made only for a scene with bar contacts)."""
    if isinstance(scene.walls, Walls):
        return _validate_wall_set(scene, scene.walls, held)
    checked = _plain_walls(scene, held)
    if checked is not None:
        return checked
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


def _plain_walls(scene: Scene, held: dict[int, int]) -> dict[tuple[int, str], int] | None:
    """Many Wall objects whose fields have plain types (int node and bar, float gap, side '+'
    or '-') checked as one :class:`Walls` in numpy passes (a fifth of the time of the loop);
    None where any check fails, or for a few walls: the loop then names the first fault as it
    always has."""
    walls = scene.walls
    if len(walls) <= 16 or not all(type(w.node) is int and type(w.bar) is int and
                                   type(w.gap) is float and w.side in WALL_SIDES for w in walls):
        return None
    columns = Walls.of(walls)
    if not (np.abs(columns.gaps) <= MAGNITUDE).all():  # also False for NaN
        return None
    try:
        return _validate_wall_set(scene, columns, held)
    except SceneError:
        return None


def _validate_wall_set(scene: Scene, walls: Walls,
                    held: dict[int, int]) -> dict[tuple[int, str], int]:
    """:func:`validate_wall_set` of the scene's walls as a :class:`Walls`; {(node, side): wall
    index} only where bar contacts need it."""
    counts = np.array([b.n_nodes for b in scene.bars], dtype=np.intp)
    offsets = np.concatenate(([0], np.cumsum(counts)[:-1]))
    validate_wall_set(walls, counts, offsets, held)
    if not scene.contacts:
        return {}
    at = (offsets[walls.bars] + walls.nodes).tolist()
    return {(a, side): i for i, (a, side) in enumerate(zip(at, walls.sides.tolist()))}


def _validate_contacts(scene: Scene, node, held: dict[int, int],
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
