"""Case builders and timing, shared by every benchmark group (benchmarks/run.py).

Every time is a median wall time, and every speed is a ratio to a floor measured in the same
run: one banded Cholesky factor-and-solve of K (LAPACK pbsv through scipy.linalg.solveh_banded).
"""

from __future__ import annotations

import datetime
import math
import multiprocessing
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
from contactqp.builders import channel, flat_patch, obstacle  # noqa: F401 (the groups' scenes)
from contactqp.model import build_model

MATRIX_TIMEOUT = 20.0  # s: a matrix run is stopped after this long (then skipped, with why)


def median_time(function: Callable[[], object], repeats: int) -> float:
    """Median wall time (s) of ``repeats`` calls, after one untimed call that warms caches."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def in_child(timeout: float, function: Callable[..., Any], *args: Any) -> Any:
    """``function(*args)`` in a forked child, or None when it is not done after ``timeout``
    s (then the child is killed): a solver stuck in its C code cannot be interrupted from
    Python (SCS at accuracy "high" on 1e5 elements: 230 s)."""
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=lambda: send.send(function(*args)), daemon=True)
    child.start()
    send.close()
    found = receive.recv() if receive.poll(timeout) else None
    child.join(1.0)
    if child.is_alive():
        child.kill()
        child.join()
    receive.close()
    return found


def floor(scene: contactqp.Scene, repeats: int) -> float:
    """One banded factor-and-solve of K (K already in band storage; where a bar has no
    support, K with a spring on it, :attr:`contactqp.Model.held`: K alone is singular)."""
    model = build_model(scene).held
    band = model.band.copy()
    return median_time(lambda: sla.solveh_banded(band, model.P, lower=True), repeats)


def tapered_scene(elements: int, area_rule: str = "exact") -> contactqp.Scene:
    """The default scene's bar, load and wall, with ``elements`` elements (load at mid-length)."""
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9, area_rule=area_rule)
    return contactqp.Scene(bar, (contactqp.Support(0),),
                           (contactqp.Load(elements // 2, 565486.67),),
                           (contactqp.Wall(elements, 1e-4, "+"),), name=f"taper-{elements}")


def default_with(gap: float | None = None, load_factor: float = 1.0) -> contactqp.Scene:
    """The default scene with another gap at the tip, or its load scaled."""
    scene = contactqp.default_scene()
    if gap is not None:
        scene = scene.with_walls((Wall(4, gap),))
    return scene.scaled_loads(load_factor) if load_factor != 1.0 else scene


def free_bar() -> contactqp.Scene:
    """The default scene without its support: the load presses the bar against the wall,
    which carries all of it (K is singular: the bar is held by the contact alone)."""
    scene = contactqp.default_scene()
    return contactqp.Scene(scene.bars, (), scene.loads, scene.walls, name="free bar")


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
