"""Random scenes for property tests: the families that hold every method to the check's
guarantee (tests/test_guarantee.py, benchmarks/guarantee.py).

A scene is drawn from a numpy Generator, so a seed names it. The families are wide on
purpose: element areas over five decades with stiff and soft elements side by side, moduli
over three, lengths over two; one to three bars, each held by one or two supports (or, on request, by its contacts alone); point and
distributed loads of either sign; walls on one side or both, with zero gaps, small and large
open gaps and press fits (negative gaps); contacts between bars, with gaps and press fits too. Gaps are drawn relative to
the displacement the loads cause, so that contacts open, close and touch in every mix.
"""

from __future__ import annotations

import numpy as np

from contactqp.errors import SceneError
from contactqp.model import build_model
from contactqp.model.chain.floating import unheld_bars
from contactqp.scene import Bar, BarContact, DistributedLoad, Load, Scene, Support, Wall


def random_bar(rng: np.random.Generator, max_elements: int = 8, contrast: bool = True) -> Bar:
    """A bar of 1 to ``max_elements`` elements: areas log-uniform over 1e-7 to 1e-2 m², and
    with ``contrast`` half the bars with some elements made 1e2 to 1e5 times stiffer; E from
    1e9 to 1e12 Pa; lengths from 0.01 to 1 m."""
    n = int(rng.integers(1, max_elements + 1))
    areas = 10.0 ** rng.uniform(-7.0, -2.0, n)
    if contrast and rng.random() < 0.5:
        stiff = rng.random(n) < 0.5
        areas[stiff] = np.minimum(areas[stiff] * 10.0 ** rng.uniform(2.0, 5.0, stiff.sum()), 1.0)
    return Bar.from_areas(areas, float(10.0 ** rng.uniform(9.0, 12.0)),
                          lengths=10.0 ** rng.uniform(-2.0, 0.0, n))


def _gap(rng: np.random.Generator, scale: float) -> float:
    """Zero (30 %), an open gap from 1e-4 to 2 times ``scale`` (60 %), or a press fit of 1e-3
    to 0.3 times ``scale`` (10 %)."""
    draw = rng.random()
    if draw < 0.3:
        return 0.0
    if draw < 0.9:
        return float(scale * 10.0 ** rng.uniform(-4.0, 0.3))
    return -float(scale * 10.0 ** rng.uniform(-3.0, -0.5))


def random_scene(rng: np.random.Generator, max_bars: int = 3, max_elements: int = 8,
                 contacts: bool = True, contrast: bool = True, floating: float = 0.0) -> Scene:
    """A random scene (module docstring); redrawn until the scene is valid (a scene whose
    walls leave a node no position is refused by Scene itself). ``contrast``: stiff elements
    beside soft ones (element stiffnesses then span up to 1e13, beyond what a double-precision
    solve of the saddle-point system resolves on some scenes: a right method is flagged).
    ``floating``: the chance that a bar has no support (held only by its walls and bar
    contacts; a draw whose loads do not press it against them is redrawn)."""
    for _ in range(100):
        try:
            return _draw(rng, max_bars, max_elements, contacts, contrast, floating)
        except SceneError:
            continue
    raise SceneError("random_scene: no valid scene in 100 draws")


def _draw(rng: np.random.Generator, max_bars: int, max_elements: int, contacts: bool,
          contrast: bool, floating: float = 0.0) -> Scene:
    bars = tuple(random_bar(rng, max_elements, contrast)
                 for _ in range(int(rng.integers(1, max_bars + 1))))
    supports, loads, distributed = [], [], []
    for b, bar in enumerate(bars):
        nodes = bar.n_nodes
        held = {int(rng.integers(0, nodes))} if rng.random() < 0.3 else {0}
        if rng.random() < 0.3 and nodes > 2:
            held.add(int(rng.integers(1, nodes)))
        supports += [Support(node, b) for node in sorted(held)]
        free = [i for i in range(nodes) if i not in held]
        for _ in range(int(rng.integers(0, 3)) if free else 0):
            force = float(rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(2.0, 7.0))
            loads.append(Load(int(rng.choice(free)), force, b))
        if rng.random() < 0.2:
            distributed.append(
                DistributedLoad(float(rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(3.0, 7.0)), b))
    if not loads and not distributed:  # something must load the scene
        b = int(rng.integers(0, len(bars)))
        loads.append(Load(bars[b].n_nodes - 1 if Support(bars[b].n_nodes - 1, b) not in supports
                          else 0, 1e4, b))
    loaded = Scene(bars, tuple(supports), tuple(loads), distributed=tuple(distributed))
    model = build_model(loaded)
    scale = max(float(np.abs(model.free_displacement).max(initial=0.0)), 1e-9)
    if floating > 0.0:  # bars that lose their supports (drawn after the gaps' scale)
        loose = {b for b in range(len(bars)) if rng.random() < floating}
        supports = [s for s in supports if s.bar not in loose]
    held_nodes = {model.layout.node(s.bar, s.node) for s in supports}
    walls = []
    for b, bar in enumerate(bars):
        for node in range(bar.n_nodes):
            if model.layout.node(b, node) in held_nodes or rng.random() < 0.5:
                continue
            sides = ("+",) if rng.random() < 0.4 else ("-",) if rng.random() < 0.5 else ("+", "-")
            gaps = [_gap(rng, scale) for _ in sides]
            if len(gaps) == 2 and gaps[0] + gaps[1] < 0.0:  # room for the node: g₊ + g₋ >= 0
                gaps[1] = -gaps[0] if rng.random() < 0.5 else abs(gaps[1]) + max(-gaps[0], 0.0)
            walls += [Wall(node, g, side, b) for g, side in zip(gaps, sides)]
    between = _bar_contacts(rng, bars, scale) if contacts and len(bars) > 1 else []
    scene = Scene(loaded.bars, tuple(supports), loaded.loads, tuple(walls),
                  distributed=loaded.distributed, contacts=tuple(between))
    unheld = unheld_bars(scene) if floating > 0.0 else ""
    if unheld:
        raise SceneError(unheld)
    return scene


def _bar_contacts(rng: np.random.Generator, bars: tuple, scale: float) -> list[BarContact]:
    """One or two contacts between random nodes of two different bars, no pair twice."""
    between: list[BarContact] = []
    for _ in range(int(rng.integers(1, 3))):
        a, b = (int(i) for i in rng.choice(len(bars), size=2, replace=False))
        node_a, node_b = int(rng.integers(0, bars[a].n_nodes)), int(rng.integers(0, bars[b].n_nodes))
        if any((c.bar_a, c.node_a, c.bar_b, c.node_b) == (a, node_a, b, node_b) for c in between):
            continue
        between.append(BarContact(a, node_a, b, node_b, _gap(rng, scale)))
    return between


__all__ = ["random_bar", "random_scene"]
