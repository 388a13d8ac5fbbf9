"""Charts (matplotlib only; never imported by ``contactqp/__init__``). Functions return Axes."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from contactqp.result import Result
from contactqp.studies import PenaltySweep


def _axes(ax: Axes | None, size: tuple[float, float] = (8, 3.5)) -> Axes:
    """``ax``, or the axes of a new Figure (no pyplot: no global state, no GUI backend)."""
    return Figure(figsize=size, layout="constrained").subplots() if ax is None else ax


def plot_bar(result: Result, ax: Axes | None = None, magnification: float | None = None) -> Axes:
    """The undeformed bar (grey) and the deformed one (blue), displacements magnified, with the
    walls at their gaps (same magnification) and the supports."""
    ax = _axes(ax)
    bar = result.scene.bar
    x = bar.node_x
    largest = max(float(np.abs(result.u).max()), max((w.gap for w in result.scene.walls), default=0))
    if magnification is None:
        magnification = 0.1 * x[-1] / largest if largest > 0 else 1.0
    half = np.sqrt(bar.areas / np.pi)  # radius of the equivalent circle (m)
    depth = 2.5 * half.max()
    for row, (nodes, colour, name) in enumerate(
        ((x, "0.75", "undeformed"), (x + magnification * result.u, "tab:blue", "deformed"))
    ):
        y = -row * depth
        for e in range(bar.n_elements):
            ax.add_patch(Rectangle((nodes[e], y - half[e]), nodes[e + 1] - nodes[e], 2 * half[e],
                                   facecolor=colour, edgecolor="k", linewidth=0.5,
                                   label=name if e == 0 else None))
        ax.plot(nodes, np.full(nodes.size, y), "k.", markersize=4)
    top, bottom = half.max() * 1.3, -depth - half.max() * 1.3
    for i, wall in enumerate(result.scene.walls):
        at = x[wall.node] + wall.sign * magnification * wall.gap
        ax.plot([at, at], [bottom, top], color="tab:red", linewidth=2.5,
                label="wall" if i == 0 else None)
        ax.annotate(f"{result.contact_force[i]:.4g} N", (at, top), color="tab:red",
                    ha="left" if wall.side == "+" else "right", va="bottom", fontsize=8)
    for s in result.scene.supports:
        ax.plot([x[s.node]] * 2, [bottom, top], color="k", linewidth=4,
                label="support" if s is result.scene.supports[0] else None)
    ax.set_xlim(x[0] - 0.05 * x[-1], x[-1] * 1.05 + magnification * largest)
    ax.set_ylim(bottom * 1.2, top * 1.6)
    ax.set_xlabel(f"x (m); displacements and gaps magnified ×{magnification:.3g}")
    ax.set_yticks([])
    ax.set_title(f"{result.scene.name}: {result.label}, {result.contact} contact")
    ax.legend(loc="lower right", fontsize=8, ncols=4)
    return ax


def plot_penalty_sweep(sweep: PenaltySweep, ax: Axes | None = None) -> Axes:
    """Penetration (left axis) and contact-force error against Lagrange (right axis) over ε."""
    ax = _axes(ax, (7, 4))
    ok = np.isfinite(sweep.penetration) & (sweep.penetration > 0)
    ax.loglog(sweep.penalties[ok], sweep.penetration[ok], "o-", color="tab:blue",
              label="penetration (m)")
    ax.set_xlabel("penalty ε (N/m)")
    ax.set_ylabel("largest penetration (m)", color="tab:blue")
    twin = ax.twinx()
    good = np.isfinite(sweep.force_error) & (sweep.force_error > 0)
    twin.loglog(sweep.penalties[good], sweep.force_error[good], "s--", color="tab:red",
                label="force error")
    twin.set_ylabel("relative contact-force error vs Lagrange", color="tab:red")
    twin.axvline(sweep.penalties[sweep.best], color="0.5", linestyle=":")
    twin.annotate("round-off takes over →", (sweep.penalties[sweep.best], sweep.force_error[good].max()
                  if good.any() else 1), fontsize=8, ha="left", va="top", color="0.3")
    ax.set_title(f"penalty sweep: {sweep.reference.scene.name}")
    return ax


def save(ax: Axes, path) -> str:
    """Write the figure of ``ax`` as PNG; returns the path."""
    ax.figure.savefig(path, dpi=120)
    return str(path)
