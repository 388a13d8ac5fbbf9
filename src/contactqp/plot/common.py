"""What every chart shares: a Figure of its own for each chart, the log floor and the red ×
of a failed run, magnifications and engineering numbers a reader takes in at a glance, and
:func:`save`.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.transforms import blended_transform_factory

FLOOR = 1e-17  # errors of exactly 0 are drawn here, on a log axis
FAILED = {"marker": "x", "color": "tab:red", "markersize": 9, "mew": 2, "ls": ""}
PREFIXES = {-2: "µ", -1: "m", 0: "", 1: "k", 2: "M", 3: "G"}
WALL, SUPPORT, LOAD, CONTACT = "tab:red", "black", "tab:green", "tab:purple"


def _axes(ax: Axes | None, size: tuple[float, float] = (8, 3.5)) -> Axes:
    """``ax``, or the axes of a new Figure (no pyplot: no global state, no GUI backend)."""
    return Figure(figsize=size, layout="constrained").subplots() if ax is None else ax


def round_125(value: float) -> float:
    """The largest 1, 2 or 5 × 10ᵏ not above ``value`` (> 0): a magnification a reader can
    take in at a glance (×500, not ×909)."""
    power = 10.0 ** math.floor(math.log10(value))
    return max(step * power for step in (1.0, 2.0, 5.0) if step * power <= value * (1 + 1e-12))


def engineering(value: float, unit: str) -> str:
    """``value`` with 4 significant digits and an SI prefix on ``unit``: '175.9 kN', '6 kN'."""
    if value == 0.0 or not math.isfinite(value):
        return f"{value:g} {unit}"
    power = min(max(math.floor(math.log10(abs(value)) / 3), -2), 3)
    return f"{value / 1000.0 ** power:.4g} {PREFIXES[power]}{unit}"


def bracket(unit: str) -> str:
    """" (N)" after an axis label, or nothing where the unit has no name (a problem's)."""
    return f" ({unit})" if unit else ""


def stiffness_unit(units: tuple[str, str]) -> str:
    """The unit of a stiffness (penalty ε) from (force, length): "N/m", or "" unnamed."""
    force, length = units
    return f"{force}/{length}" if force and length else ""


def target_name(result) -> str:
    """The name of what ``result`` solved: its scene's, or its problem's (or "problem")."""
    target = result.scene if result.scene is not None else result.problem
    return target.name or "problem"


def _failed_at_bottom(ax: Axes, x: np.ndarray, label: str | None) -> None:
    """A red × at the bottom edge of ``ax`` for each x: a run that has no value to draw."""
    if len(x):
        ax.plot(x, np.full(len(x), 0.02), transform=blended_transform_factory(ax.transData,
                ax.transAxes), clip_on=False, label=label, **FAILED)


def save(chart: Axes | Figure, path) -> str:
    """Write the figure (of the axes) as PNG; returns the path."""
    (chart if isinstance(chart, Figure) else chart.figure).savefig(path, dpi=120)
    return str(path)
