"""Scene builders: the default scene (the course problem), a wall at every node (the discrete
obstacle problem), the smallest mesh that reproduces a scene, and a scene in other units."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from contactqp._validate import whole_number
from contactqp.errors import SceneError
from contactqp.scene import (
    UNIT_SYSTEMS,
    WALL_SIDES,
    AreaRule,
    Bar,
    DistributedLoad,
    Load,
    Scene,
    Support,
    Wall,
    Walls,
    WallSide,
)
from contactqp.scene.walls import checked_gaps

# The default scene: a standard course problem.
DEFAULT_LENGTH = 1.0  # m
DEFAULT_ELEMENTS = 4
DEFAULT_DIAMETERS = (0.040, 0.020)  # m, at x = 0 and x = L
DEFAULT_MODULUS = 210e9  # Pa
DEFAULT_YIELD = 200e6  # Pa
DEFAULT_LOAD_NODE, DEFAULT_LOAD = 2, 565486.67  # N
DEFAULT_GAP = 1e-4  # m


def default_scene(elements: int = DEFAULT_ELEMENTS, area_rule: AreaRule = "midpoint") -> Scene:
    """The default scene: a 1 m tapered cantilever pushed into a wall 0.1 mm past its tip.

    Fixed at x = 0; circular section from 40 mm to 20 mm diameter; E = 210 GPa, yield stress
    200 MPa; four equal elements with the area of the circle at mid-length; 565486.67 N in +x
    at node 2 (mid-length); a rigid wall 0.1 mm beyond the tip in +x. ``elements`` (even) and
    ``area_rule`` re-mesh the same bar, for convergence studies.

    Parameters
    ----------
    elements : int
        The number of equal elements (even, so that the load stays at mid-length; default 4).
    area_rule : str
        ``"midpoint"`` (the course problem: the circle's area at mid-length) or ``"exact"`` (the
        constant area with the cone segment's flexibility).

    Returns
    -------
    Scene
        The scene, in SI units.

    Raises
    ------
    SceneError
        ``elements`` is not a positive even number, or ``area_rule`` is unknown.
    """
    elements = whole_number("elements", elements, 2)
    if elements % 2:
        raise SceneError(f"elements must be an even whole number >= 2 (load at mid-length), "
                         f"got {elements!r}")
    bar = Bar.tapered_circle(
        DEFAULT_LENGTH, elements, *DEFAULT_DIAMETERS, DEFAULT_MODULUS,
        area_rule=area_rule, yield_stress=DEFAULT_YIELD,
    )
    name = "default scene: tapered cantilever against a wall"
    if (elements, area_rule) != (DEFAULT_ELEMENTS, "midpoint"):
        name += f" ({elements} elements, {area_rule} areas)"
    return Scene(
        bar,
        supports=(Support(0),),
        loads=(Load(elements // 2, DEFAULT_LOAD),),
        walls=(Wall(elements, DEFAULT_GAP, "+"),),
        name=name,
    )


def obstacle(elements: int) -> Scene:
    """The default scene's bar (``elements`` exact-area elements, its load at mid-length)
    beside an obstacle: a + wall at every node, gaps g(x) = 0.2 mm·(x/L)² + 10 µm·abs(sin 37x/L).
    The discrete obstacle problem: a few contact patches, whose nodes depend on the mesh.

    Parameters
    ----------
    elements : int
        The number of elements (and of walls).

    Returns
    -------
    Scene
        The scene, in SI units.

    Raises
    ------
    SceneError
        ``elements`` is not a positive whole number.
    """
    elements = whole_number("elements", elements, 2)
    x = np.linspace(0.0, 1.0, elements + 1)
    gaps = 2e-4 * x**2 + 1e-5 * np.abs(np.sin(37.0 * x))
    return replace(wall_at_every_node(_tapered(elements, point_load=True), gaps),
                   name=f"obstacle ({elements} walls)")


def channel(contacts: int) -> Scene:
    """The default scene's bar in a narrow wavy channel: a wall on both sides of every node
    (``contacts`` walls, ``contacts``/2 elements), centre c(x) = 0.1 mm·sin(3πx/L) +
    0.15 mm·x/L, half-width 5 µm; most nodes end touching one side or the other.

    Parameters
    ----------
    contacts : int
        The number of walls (two per node: ``contacts``/2 elements).

    Returns
    -------
    Scene
        The scene, in SI units.

    Raises
    ------
    SceneError
        ``contacts`` is not a whole number of at least 4.
    """
    elements = max(whole_number("contacts", contacts, 4) // 2, 2)
    x = np.linspace(0.0, 1.0, elements + 1)
    centre, half = 1e-4 * np.sin(3.0 * np.pi * x) + 1.5e-4 * x, 5e-6
    scene = wall_at_every_node(_tapered(elements, point_load=True), centre + half)
    return replace(wall_at_every_node(scene, half - centre, "-"),
                   name=f"channel ({2 * elements} walls)")


def flat_patch(contacts: int) -> Scene:
    """The default scene's bar (``contacts`` elements) pressed onto a flat wall 10 µm from
    every node by a uniform load of 2 MN/m (no point load): 95 % of the nodes end in contact,
    in one patch.

    Parameters
    ----------
    contacts : int
        The number of elements (and of walls).

    Returns
    -------
    Scene
        The scene, in SI units.

    Raises
    ------
    SceneError
        ``contacts`` is not a positive whole number.
    """
    scene = _tapered(whole_number("contacts", contacts, 2), point_load=False)
    scene = replace(scene, distributed=(DistributedLoad(2e6),), name=f"flat patch ({contacts} walls)")
    return wall_at_every_node(scene, 1e-5)


def _tapered(elements: int, point_load: bool) -> Scene:
    bar = Bar.tapered_circle(DEFAULT_LENGTH, elements, *DEFAULT_DIAMETERS, DEFAULT_MODULUS,
                             area_rule="exact", yield_stress=DEFAULT_YIELD)
    loads = (Load(elements // 2, DEFAULT_LOAD),) if point_load else ()
    return Scene(bar, (Support(0),), loads)


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

    The elements between two kept nodes become one element with their series compliance
    Σ L/(EA), so displacements at the kept nodes, contact forces, reactions and element forces
    are exactly those of the original model (static condensation of unloaded nodes). Stresses
    are those of the merged element's equivalent area: for a taper meshed with
    ``area_rule="exact"`` that is the exact cone's, and one element per segment reproduces the
    continuum answer.

    Parameters
    ----------
    scene : Scene
        Any scene.

    Returns
    -------
    Scene
        The same scene on the fewest nodes.
    """
    bars, numbers = [], []
    for b, bar in enumerate(scene.bars):
        kept = needed_nodes(scene, b)
        new_number = np.full(bar.n_nodes, -1)
        new_number[kept] = np.arange(kept.size)
        numbers.append(new_number)
        compliance = bar.compliance[kept]
        x = bar.node_x[kept]
        lengths = np.diff(x)
        modulus = bar.youngs_modulus[np.searchsorted(bar.node_x, x[:-1], side="right") - 1]
        areas = lengths / (modulus * np.diff(compliance))  # E A / L = 1 / Σ L/(EA)
        bars.append(Bar(lengths, areas, modulus, bar.yield_stress))

    def element(b: int, e: int | None) -> int | None:
        # a distributed load's elements keep all their nodes: element e starts at node e
        return None if e is None else int(numbers[b][e])

    return Scene(
        tuple(bars),
        tuple(replace(s, node=int(numbers[s.bar][s.node])) for s in scene.supports),
        tuple(replace(p, node=int(numbers[p.bar][p.node])) for p in scene.loads),
        _renumbered(scene.walls, numbers),
        name=f"{scene.name} (minimal mesh)",
        distributed=tuple(replace(q, start=element(q.bar, q.start), stop=element(q.bar, q.stop))
                          for q in scene.distributed),
        contacts=tuple(replace(c, node_a=int(numbers[c.bar_a][c.node_a]),
                               node_b=int(numbers[c.bar_b][c.node_b])) for c in scene.contacts),
        units=scene.units,
    )


def _renumbered(walls: tuple[Wall, ...] | Walls, numbers: list[np.ndarray]) -> Any:
    """The walls at their nodes' new numbers (``numbers``: per bar, each old node's new one),
    a :class:`Walls` kept one."""
    if not isinstance(walls, Walls):
        return tuple(replace(w, node=int(numbers[w.bar][w.node])) for w in walls)
    starts = np.concatenate(([0], np.cumsum([n.size for n in numbers])))
    nodes = np.concatenate(numbers)[starts[walls.bars] + walls.nodes]
    return Walls(nodes, walls.gaps, walls.sides, walls.bars)


def convert_units(scene: Scene, units: str) -> Scene:
    """The same physical scene in another unit system (:data:`UNIT_SYSTEMS`): lengths, areas,
    moduli, yield stresses, gaps, distributed loads and beds' τ converted; point loads stay in N.

    Parameters
    ----------
    scene : Scene
        Any scene.
    units : str
        One of :data:`contactqp.UNIT_SYSTEMS`: ``"SI"`` or ``"mm-N-MPa"``.

    Returns
    -------
    Scene
        The same physical scene in ``units``.

    Raises
    ------
    SceneError
        ``units`` is not a known unit system.
    """
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
        scene, bars=bars, units=units,
        walls=(scene.walls.with_gaps(scene.walls.gaps * length)
               if isinstance(scene.walls, Walls)
               else tuple(replace(w, gap=w.gap * length) for w in scene.walls)),
        contacts=tuple(replace(c, gap=c.gap * length) for c in scene.contacts),
        distributed=tuple(replace(q, intensity=q.intensity / length) for q in scene.distributed),
        beds=tuple(replace(b, tau=b.tau / length) for b in scene.beds),
    )


def wall_at_every_node(scene: Scene, gap: Any, side: WallSide = "+", bar: int = 0) -> Scene:
    """The scene with a wall at every node of bar ``bar`` that is not a support (the discrete
    obstacle problem): ``gap`` one value (m) or one per node of the bar (supports' ignored).
    Where the scene has a wall on that side already, the smaller gap is kept (both walls
    hold, so the nearer one is the constraint).

    Parameters
    ----------
    scene : Scene
        The scene to add the walls to.
    gap : float or array_like
        One gap, or one per node of the bar, in the scene's length unit.
    side : str
        ``"+"`` (the node may not pass the wall in +x, the default) or ``"-"``.
    bar : int
        The bar (default 0).

    Returns
    -------
    Scene
        A new scene; ``scene`` is unchanged.

    Raises
    ------
    SceneError
        A bad bar, side or gap (or one gap per node of the wrong length).
    """
    b = whole_number("obstacle.bar", bar, 0, "bar number")
    if b >= len(scene.bars):
        raise SceneError(f"obstacle.bar = {b}: the scene has bars 0 to {len(scene.bars) - 1}")
    if side not in WALL_SIDES:
        raise SceneError(f"obstacle.side must be '+' or '-', got {side!r}")
    n = scene.bars[b].n_nodes
    gaps = np.asarray(gap, dtype=float)
    if gaps.ndim == 0:
        gaps = np.full(n, float(gaps))
    if gaps.shape != (n,):
        raise SceneError(f"obstacle.gap must be one value or one per node of bar[{b}] ({n}), "
                         f"got {gaps.size}")
    gaps = checked_gaps("obstacle.gap", gaps, n)
    walls = Walls.of(scene.walls)
    # where the bar has a wall on that side already, the nearer one is kept (as min(old, new))
    mine = np.flatnonzero((walls.bars == b) & (walls.sides == side))
    old, new = walls.gaps[mine], gaps[walls.nodes[mine]]
    kept = walls.gaps.copy()
    kept[mine] = np.where(new < old, new, old)
    free = np.ones(n, dtype=bool)
    free[[s.node for s in scene.supports if s.bar == b]] = False
    free[walls.nodes[mine]] = False
    nodes = np.flatnonzero(free)
    added = Walls(nodes, gaps[nodes], side, b)
    return scene.with_walls(Walls.of((walls.with_gaps(kept), added)))


__all__ = ["DEFAULT_DIAMETERS", "DEFAULT_ELEMENTS", "DEFAULT_GAP", "DEFAULT_LENGTH",
           "DEFAULT_LOAD", "DEFAULT_LOAD_NODE", "DEFAULT_MODULUS", "DEFAULT_YIELD",
           "channel", "convert_units", "default_scene", "flat_patch", "minimal", "needed_nodes",
           "obstacle", "wall_at_every_node"]
