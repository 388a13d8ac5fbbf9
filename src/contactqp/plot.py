"""Charts (matplotlib only; never imported by ``contactqp/__init__``). Functions return Axes."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from contactqp.curve import LoadPath
from contactqp.result import Result
from contactqp.studies import MeshConvergence, NitscheSweep, PenaltySweep


def _axes(ax: Axes | None, size: tuple[float, float] = (8, 3.5)) -> Axes:
    """``ax``, or the axes of a new Figure (no pyplot: no global state, no GUI backend)."""
    return Figure(figsize=size, layout="constrained").subplots() if ax is None else ax


def plot_bar(result: Result, ax: Axes | None = None, magnification: float | None = None) -> Axes:
    """The undeformed bar (grey) and the deformed one (blue), displacements magnified, with the
    walls at their gaps (same magnification) and the supports."""
    ax = _axes(ax)
    scene, layout = result.scene, result.layout
    x = layout.node_x  # the bars end to end
    first = np.delete(np.arange(layout.n_nodes - 1), layout.junctions)  # each element's first node
    largest = max(float(np.abs(result.u).max()), max((w.gap for w in result.scene.walls), default=0))
    if magnification is None:
        magnification = 0.1 * x[-1] / largest if largest > 0 else 1.0
    half = np.sqrt(layout.areas / np.pi)  # radius of the equivalent circle
    depth = 2.5 * half.max()
    for row, (nodes, colour, name) in enumerate(
        ((x, "0.75", "undeformed"), (x + magnification * result.u, "tab:blue", "deformed"))
    ):
        y = -row * depth
        for e, j in enumerate(first):
            ax.add_patch(Rectangle((nodes[j], y - half[e]), nodes[j + 1] - nodes[j], 2 * half[e],
                                   facecolor=colour, edgecolor="k", linewidth=0.5,
                                   label=name if e == 0 else None))
        ax.plot(nodes, np.full(nodes.size, y), "k.", markersize=4)
    top, bottom = half.max() * 1.3, -depth - half.max() * 1.3
    for i, wall in enumerate(result.scene.walls):
        at = x[layout.node(wall.bar, wall.node)] + wall.sign * magnification * wall.gap
        ax.plot([at, at], [bottom, top], color="tab:red", linewidth=2.5,
                label="wall" if i == 0 else None)
        ax.annotate(f"{result.contact_force[i]:.4g} N", (at, top), color="tab:red",
                    ha="left" if wall.side == "+" else "right", va="bottom", fontsize=8)
    for s in result.scene.supports:
        ax.plot([x[layout.node(s.bar, s.node)]] * 2, [bottom, top], color="k", linewidth=4,
                label="support" if s is result.scene.supports[0] else None)
    ax.set_xlim(x[0] - 0.05 * x[-1], x[-1] * 1.05 + magnification * largest)
    ax.set_ylim(bottom * 1.2, top * 1.6)
    ax.set_xlabel(f"x ({scene.unit.length}); displacements and gaps magnified "
                  f"×{magnification:.3g}")
    ax.set_yticks([])
    ax.set_title(f"{result.scene.name}: {result.label}, {result.contact} contact")
    ax.legend(loc="lower right", fontsize=8, ncols=4)
    return ax


def plot_penalty_sweep(sweep: PenaltySweep) -> Figure:
    """Two panels over ε: the penalty's penetration; the contact-force error against Lagrange
    of the penalty and of the augmented Lagrangian method (with its number of updates)."""
    figure = Figure(figsize=(11, 4.2), layout="constrained")
    left, right = figure.subplots(1, 2)
    eps = sweep.penalties
    ok = np.isfinite(sweep.penetration) & (sweep.penetration > 0)
    left.loglog(eps[ok], sweep.penetration[ok], "o-", color="tab:blue")
    unit = sweep.reference.scene.unit
    left.set_xlabel(f"penalty ε ({unit.stiffness})")
    left.set_ylabel(f"largest penetration ({unit.length})")
    left.set_title("penalty: penetration ≈ λ/ε")
    floor = 1e-17  # errors of exactly 0 are drawn here, on a log axis
    for errors, style, name in ((sweep.force_error, "s--", "penalty"),
                                (sweep.augmented_error, "o-", "augmented Lagrangian")):
        good = np.isfinite(errors)
        right.loglog(eps[good], np.maximum(errors[good], floor), style, label=name)
    for x, y, n in zip(eps, sweep.augmented_error, sweep.augmented_iterations):
        if np.isfinite(y):
            right.annotate(str(n), (x, max(y, floor)), textcoords="offset points", xytext=(0, 6),
                           fontsize=7, ha="center", color="tab:orange")
    right.axvline(eps[sweep.best], color="0.5", linestyle=":")
    right.annotate("round-off takes over → ", (eps[sweep.best], 1.0), fontsize=8, va="top",
                   ha="right", color="0.3")
    right.set_xlabel(f"penalty ε ({unit.stiffness})")
    right.set_ylabel("relative contact-force error vs Lagrange")
    right.set_title("force error (numbers: augmented updates)")
    right.legend(fontsize=8)
    figure.suptitle(f"penalty sweep: {sweep.reference.scene.name}")
    return figure


def plot_nitsche_sweep(sweep: NitscheSweep) -> Figure:
    """Two panels over γ₀, one line per θ: Nitsche's penetration, and its contact-force error
    against Lagrange multipliers (filled markers: verified; open: flagged)."""
    figure = Figure(figsize=(11, 4.2), layout="constrained")
    left, right = figure.subplots(1, 2)
    unit = sweep.reference.scene.unit
    floor = 1e-17  # zero errors are drawn here, on a log axis
    for i, theta in enumerate(sweep.thetas):
        name, colour = f"θ = {theta:g}", f"C{i}"
        for ax, values in ((left, sweep.penetration[i]), (right, sweep.force_error[i])):
            ran = np.isfinite(values)
            y = np.maximum(values, floor)
            ax.loglog(sweep.gamma0[ran], y[ran], "-", color=colour, label=name)
            for ok, face in ((sweep.verified[i] & ran, colour), (~sweep.verified[i] & ran, "none")):
                ax.loglog(sweep.gamma0[ok], y[ok], "o", color=colour, mfc=face, ls="")
    left.set(xlabel="γ₀ (γ = γ₀·EA/h)", ylabel=f"largest penetration ({unit.length})",
             title="Nitsche: penetration ≈ the end node's load / γ")
    right.set(xlabel="γ₀ (γ = γ₀·EA/h)", ylabel="relative contact-force error vs Lagrange",
              title="force error (filled: verified, open: flagged)")
    left.legend(fontsize=8)
    figure.suptitle(f"Nitsche sweep: {sweep.reference.scene.name}")
    return figure


def plot_mesh_convergence(study: MeshConvergence, ax: Axes | None = None) -> Axes:
    """Contact-force error against the continuum over the number of elements, both area rules,
    with an O(h²) guide through the midpoint rule's first point."""
    ax = _axes(ax, (6, 4.2))
    floor = 1e-17  # exact zeros drawn here on the log axis
    n = study.elements
    for rule, style in (("midpoint", "o-"), ("exact", "s-")):
        ax.loglog(n, np.maximum(study.errors[rule], floor), style, label=f"area rule {rule!r}")
    first = study.errors["midpoint"][0]
    ax.loglog(n, first * (n[0] / n) ** 2, "k:", label="O(h²)")
    ax.set_xlabel("elements")
    ax.set_ylabel("relative contact-force error vs the continuum")
    ax.set_title("tapered bar: midpoint areas O(h²), exact areas exact")
    ax.legend(fontsize=8)
    return ax


def plot_load_path(path: LoadPath, kink: float | None = None, ax: Axes | None = None) -> Axes:
    """Displacement of the load point against the load factor, one line per method, with the
    closed-form load factor ``kink`` at which the first contact closes (dotted)."""
    ax = _axes(ax, (7, 4.6))
    styles = {"lagrange": "k-", "equality": "r--", "penalty": "g-.", "augmented": "c:",
              "qp": "bx", "soft penalty": "m-"}
    for name, method in path.methods.items():
        ax.plot(path.load_factor, method.load_point_displacement,
                styles.get(name, "o-"), label=name, markersize=5, linewidth=1.5)
    if kink is not None and np.isfinite(kink):
        ax.axvline(kink, color="0.5", linestyle=":", label=f"first contact, closed form t = {kink:.4g}")
    ax.set_xlabel("load factor (× the scene's loads)")
    ax.set_ylabel(f"displacement of node {path.load_node} ({path.scene.unit.length})")
    ax.set_title(f"load path: {path.scene.name}")
    ax.legend(fontsize=8)
    return ax


def save(chart: Axes | Figure, path) -> str:
    """Write the figure (of the axes) as PNG; returns the path."""
    (chart if isinstance(chart, Figure) else chart.figure).savefig(path, dpi=120)
    return str(path)
