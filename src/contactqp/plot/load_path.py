"""The load path: the load point's displacement and the sum of the contact forces over the
load factor, one curve per method (:func:`plot_load_path`)."""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from contactqp.curve import LoadPath
from contactqp.plot.common import (
    FAILED,
    bracket,
    engineering,
    stiffness_unit,
)
from contactqp.problem import Problem

LINE_STYLES = {"lagrange": ("k", "-", "o"), "equality": ("tab:red", "--", "v"),
               "penalty": ("tab:green", "-.", "s"), "augmented": ("tab:cyan", ":", "D"),
               "qp": ("tab:blue", (0, (1, 3)), "x"), "soft penalty": ("tab:purple", "-", "^")}


def plot_load_path(path: LoadPath, kink: float | None = None) -> Figure:
    """Over the load factor: the displacement of the load point (top) and the sum of the
    contact forces (bottom), one line per method; markers staggered so that methods whose
    curves coincide all show. A red × marks a step that failed its check, a red ring one
    where a contact pulls (equality contact before the wall is reached); dotted: the
    closed-form load factor ``kink`` at which the first contact closes. Methods that could
    not solve the scene (:attr:`LoadPath.failed`) are named under the chart."""
    figure = Figure(figsize=(11, 7), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    t, (force, length) = path.load_factor, path.scene.unit_names
    n = len(path.methods)
    for i, (name, method) in enumerate(path.methods.items()):
        colour, dash, marker = LINE_STYLES.get(name, (f"C{i}", "-", "o"))
        total = method.contact_force.sum(axis=1)
        for ax, y in ((top, method.load_point_displacement), (bottom, total)):
            ax.plot(t, y, color=colour, linestyle=dash, marker=marker, markevery=(i, n),
                    markersize=6, mfc="none", linewidth=1.5, gid=f"curve {name}",
                    label=f"{name}: {_describe(name, method)}")
            _mark_steps(ax, t, y, method.verified, method.physical)
    if kink is not None and np.isfinite(kink):
        for ax in (top, bottom):
            ax.axvline(kink, color="0.5", linestyle=":",
                       label=f"first contact closes (closed form): t = {kink:.4g}"
                       if ax is top else None)
    top.set_ylabel(f"displacement of {path.where}{bracket(length)}")
    bottom.set_ylabel(f"sum of contact forces{bracket(force)}")
    bottom.set_xlabel("load factor t (× every load"
                      + (" and prescribed value)" if isinstance(path.scene, Problem)
                         else " of the scene)"))
    # beside the panels, not in one: a curve that reaches its wall runs flat along the top
    top.legend(handles=[*top.get_legend_handles_labels()[0], *_step_legend()], fontsize=8,
               loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    if path.failed:
        top.set_title(textwrap.fill("no curve: " + "; ".join(
            f"{name}: {why}" for name, why in path.failed.items()), 110), fontsize=8,
            color="tab:red", loc="left")
    figure.suptitle(f"load path: {path.scene.name or 'problem'}")
    return figure


CURVE_NAMES = {"lagrange": "Lagrange multipliers", "equality": "Lagrange, equality contact",
               "penalty": "penalty, default ε", "augmented": "augmented Lagrangian"}


def _describe(name: str, method) -> str:
    """What a load path's method is, in words (its first step's method, solver and ε)."""
    first = method.results[0]
    if name in CURVE_NAMES:
        return CURVE_NAMES[name]
    if first.method == "penalty" and "penalty" in first.options:
        return f"penalty, ε = {engineering(first.options['penalty'], stiffness_unit(first.model.units))}"
    return first.label


def _mark_steps(ax: Axes, t: np.ndarray, y: np.ndarray, verified: np.ndarray,
                physical: np.ndarray) -> None:
    """A red × on the steps that failed their check, a red ring where a contact pulls."""
    ax.plot(t[~verified], y[~verified], gid="failed steps", **FAILED)
    pulls = verified & ~physical
    ax.plot(t[pulls], y[pulls], "o", color="tab:red", mfc="none", markersize=10, ls="",
            gid="pulling steps")


def _step_legend() -> list:
    return [Line2D([], [], label="step failed its check", **FAILED),
            Line2D([], [], color="tab:red", marker="o", mfc="none", markersize=10, ls="",
                   label="a contact pulls")]
