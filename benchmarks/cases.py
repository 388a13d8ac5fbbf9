"""Case builders and timing, shared by every benchmark group (benchmarks/run.py).

Every time is a median wall time, and every speed is a ratio to a floor measured in the same
run: one banded Cholesky factor-and-solve of K (LAPACK pbsv through scipy.linalg.solveh_banded).
"""

from __future__ import annotations

import datetime
import math
import os
import platform
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.linalg as sla

import contactqp
from contactqp import Load, Wall
from contactqp.model import build_model


def median_time(function: Callable[[], object], repeats: int) -> float:
    """Median wall time (s) of ``repeats`` calls, after one untimed call that warms caches."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def floor(scene: contactqp.Scene, repeats: int) -> float:
    """One banded factor-and-solve of K (K already in band storage)."""
    model = build_model(scene)
    band = model.band.copy()
    return median_time(lambda: sla.solveh_banded(band, model.P, lower=True), repeats)


def tapered_scene(elements: int, area_rule: str = "exact") -> contactqp.Scene:
    """The default scene's bar, load and wall, with ``elements`` elements (load at mid-length)."""
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9, area_rule=area_rule)
    return contactqp.Scene(bar, (contactqp.Support(0),),
                           (contactqp.Load(elements // 2, 565486.67),),
                           (contactqp.Wall(elements, 1e-4, "+"),), name=f"taper-{elements}")


def obstacle(elements: int) -> contactqp.Scene:
    """The tapered bar beside an obstacle: a wall at every node, gaps
    g(x) = 0.2 mm·(x/L)² + 10 µm·|sin(37 x/L)| (patches that depend on the mesh)."""
    x = np.linspace(0.0, 1.0, elements + 1)
    gaps = 2e-4 * x**2 + 1e-5 * np.abs(np.sin(37.0 * x))
    return contactqp.wall_at_every_node(tapered_scene(elements).with_walls(()), gaps)


def channel(contacts: int) -> contactqp.Scene:
    """The tapered bar in a narrow wavy channel, a wall on both sides of every node
    (``contacts`` walls, ``contacts``/2 elements): centre c(x) = 0.1 mm·sin(3πx/L) + 0.15 mm·x/L,
    half-width 5 µm, so that most nodes touch one side or the other."""
    elements = max(contacts // 2, 2)
    x = np.linspace(0.0, 1.0, elements + 1)
    centre, half = 1e-4 * np.sin(3.0 * np.pi * x) + 1.5e-4 * x, 5e-6
    scene = contactqp.wall_at_every_node(tapered_scene(elements).with_walls(()), centre + half)
    return contactqp.wall_at_every_node(scene, half - centre, "-")


def flat_patch(contacts: int) -> contactqp.Scene:
    """The tapered bar pressed onto a flat wall at every node, 10 µm away, by a uniform load
    of 2 MN/m along it (no point load): 95 % of the nodes end in contact, one patch."""
    bar = contactqp.Bar.tapered_circle(1.0, contacts, 0.040, 0.020, 210e9)
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (),
                            distributed=(contactqp.DistributedLoad(2e6),),
                            name=f"patch-{contacts}")
    return contactqp.wall_at_every_node(scene, 1e-5)


def default_with(gap: float | None = None, load_factor: float = 1.0) -> contactqp.Scene:
    """The default scene with another gap at the tip, or its load scaled."""
    scene = contactqp.default_scene()
    if gap is not None:
        scene = scene.with_walls((Wall(4, gap),))
    return scene.scaled_loads(load_factor) if load_factor != 1.0 else scene


def touching() -> contactqp.Scene:
    """The default scene with the load that brings node 4 exactly onto the wall: F·f₂ = g,
    f₂ = Σ 1/k over the two elements before the load (the bar beyond it is unstressed)."""
    scene = contactqp.default_scene()
    compliance = math.fsum(1.0 / scene.bars[0].element_stiffness[:2])
    return scene.with_loads((Load(2, scene.walls[0].gap / compliance),))


def machine() -> dict[str, Any]:
    """What the numbers were measured on."""
    import scipy

    return {"date": datetime.date.today().isoformat(), "python": platform.python_version(),
            "platform": platform.platform(), "processor": platform.processor(),
            "cpus": os.cpu_count(), "numpy": np.__version__, "scipy": scipy.__version__,
            "contactqp": contactqp.__version__,
            "longdouble_eps": float(np.finfo(np.longdouble).eps)}
