"""The studies' charts: the penalty sweep, Nitsche's sweep and mesh convergence, each
over its parameter on log axes."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from contactqp.methods.augmented import DEFAULT_MAX_ITERATIONS
from contactqp.methods.penalty import TEXTBOOK_PENALTY
from contactqp.plot.common import (
    FAILED,
    FLOOR,
    _axes,
    _failed_at_bottom,
    bracket,
    engineering,
    stiffness_unit,
    target_name,
)
from contactqp.studies import MeshConvergence, NitscheSweep, PenaltySweep, Run


def _run_marks(ax: Axes, x: np.ndarray, y: np.ndarray, runs: tuple[Run, ...], colour: str,
               style: str, name: str, zero: bool = True) -> None:
    """A line through the runs that ran, filled markers where verified, open where flagged,
    and a red × at the bottom where the solve raised. Values of 0 are drawn at FLOOR, or
    (``zero`` False: a penetration, where <= 0 means none) not at all."""
    failed = np.array([r.result is None for r in runs]) | np.isnan(y)
    ran = ~failed & (np.isfinite(y) if zero else y > 0.0)
    good = ran & np.array([r.result is not None and r.result.verified for r in runs])
    y = np.maximum(y, FLOOR)
    ax.loglog(x[ran], y[ran], style, color=colour, label=name, marker="none")
    ax.loglog(x[good], y[good], "o", color=colour, ls="", markersize=5)
    ax.loglog(x[ran & ~good], y[ran & ~good], "o", color=colour, mfc="white", ls="",
              markersize=6)
    _failed_at_bottom(ax, x[failed], None)
    if not ran.any():
        ax.text(0.5, 0.6, "nothing to draw: no contact penetrates" if not zero else
                "nothing to draw", transform=ax.transAxes, ha="center", color="0.3")


def _study_legend_extras() -> list:
    return [Line2D([], [], color="0.3", marker="o", ls="", label="verified"),
            Line2D([], [], color="0.3", marker="o", mfc="white", ls="",
                   label="flagged by the check"),
            Line2D([], [], label="solve failed", **FAILED)]


def plot_penalty_sweep(sweep: PenaltySweep) -> Figure:
    """Over ε: the penalty's largest penetration (left); the relative contact-force error
    against Lagrange multipliers of the penalty and of the augmented Lagrangian method at the
    same ε (right), and below it the augmented method's number of multiplier updates, runs
    stopped at the update cap in red. Dotted: the textbook ε (1e14 N/m, in the scene's units)
    and the ε beyond which round-off takes over."""
    figure = Figure(figsize=(12, 6), layout="constrained")
    grid = figure.add_gridspec(2, 2, height_ratios=(3, 1.3))
    left = figure.add_subplot(grid[:, 0])
    right = figure.add_subplot(grid[0, 1])
    updates = figure.add_subplot(grid[1, 1], sharex=right)
    eps, (_, length) = sweep.penalties, sweep.reference.model.units
    stiffness = stiffness_unit(sweep.reference.model.units)
    for ax in (left, right):  # set first: a panel may have nothing to draw but the ε marks
        ax.set(xscale="log", yscale="log", xlim=(eps.min() / 3, eps.max() * 3))
    _run_marks(left, eps, sweep.penetration, sweep.runs, "tab:blue", "--", "penalty",
               zero=False)
    _run_marks(right, eps, sweep.force_error, sweep.runs, "tab:blue", "--", "penalty")
    _run_marks(right, eps, sweep.augmented_error, sweep.augmented_runs, "tab:orange", "-",
               "augmented Lagrangian")
    _draw_updates(updates, eps, sweep)
    scene = sweep.reference.scene
    if scene is not None:  # the textbook ε is a number in N/m: a problem has no such number
        textbook = TEXTBOOK_PENALTY * scene.unit.metre
        for ax in (left, right, updates):
            ax.axvline(textbook, color="tab:green", linestyle=":", linewidth=1.5,
                       label=f"textbook ε = {textbook:.0e} {stiffness}" if ax is left else None)
    _mark_round_off(right, sweep)
    left.set(xlabel=f"penalty ε{bracket(stiffness)}",
             ylabel=f"largest penetration{bracket(length)}",
             title="penalty method: penetration ≈ contact force / ε")
    right.set(ylabel="relative contact-force error",
              title="contact-force error against Lagrange multipliers")
    right.tick_params(labelbottom=False)
    handles = [*right.get_legend_handles_labels()[0], *left.get_legend_handles_labels()[0][1:]]
    # the updates panel's own mark joins this legend: a legend of its own sat on its cap line
    capped = [h for h in updates.get_legend_handles_labels()[0] if len(h.get_xdata())]
    left.legend(handles=[*handles, *_study_legend_extras(), *capped], fontsize=8,
                loc="lower left")
    figure.suptitle(f"{target_name(sweep.reference)}: the penalty method and the augmented "
                    f"Lagrangian over ε, {sweep.reference.contact} contact")
    return figure


def _draw_updates(ax: Axes, eps: np.ndarray, sweep: PenaltySweep) -> None:
    """The augmented method's multiplier updates per ε; runs stopped at their cap in red."""
    runs = sweep.augmented_runs
    ran = np.array([r.result is not None for r in runs])
    capped = np.array([r.result is not None and not r.result.claimed_success for r in runs])
    n = sweep.augmented_iterations.astype(float)
    ax.semilogx(eps[ran], n[ran], "o-", color="tab:orange", markersize=4)
    ax.plot(eps[capped], n[capped], "s", color="tab:red", mfc="none", markersize=9,
            mew=1.5, ls="", label="stopped at its cap: not converged")
    _failed_at_bottom(ax, eps[~ran], None)
    caps = {r.result.options.get("max_iterations", DEFAULT_MAX_ITERATIONS)
            for r in runs if r.result is not None}
    for cap in caps:
        ax.axhline(cap, color="tab:red", linewidth=0.8, linestyle="--")
    ax.set(xlabel=f"penalty ε{bracket(stiffness_unit(sweep.reference.model.units))}",
           ylabel="augmented: updates", ylim=(0, 1.15 * max(caps | {1})))


def _mark_round_off(ax: Axes, sweep: PenaltySweep) -> None:
    """The ε of the penalty's smallest error, or why there is none."""
    if not np.any(sweep.reference.contact_force):
        ax.text(0.5, 0.6, "no contact carries a force: every ε gives the free answer",
                transform=ax.transAxes, ha="center", fontsize=9, color="0.3")
        return
    if np.any(np.isfinite(sweep.force_error)):
        best = sweep.penalties[sweep.best]
        ax.axvline(best, color="0.5", linestyle=":",
                   label=f"penalty's best ε = {best:.0e}: round-off takes over beyond")


def plot_nitsche_sweep(sweep: NitscheSweep) -> Figure:
    """Two panels over γ₀, one line per θ: Nitsche's penetration, and its contact-force error
    against Lagrange multipliers (filled markers: verified; open: flagged; red × at the
    bottom: the solve was refused, e.g. the symmetric form below its threshold)."""
    figure = Figure(figsize=(11, 4.6), layout="constrained")
    left, right = figure.subplots(1, 2)
    unit = sweep.reference.scene.unit
    for i, theta in enumerate(sweep.thetas):
        name, colour = f"θ = {theta:g}", f"C{i}"
        for ax, values in ((left, sweep.penetration[i]), (right, sweep.force_error[i])):
            ran = np.isfinite(values)
            y = np.maximum(values, FLOOR)
            ax.loglog(sweep.gamma0[ran], y[ran], "-", color=colour, label=name)
            for ok, face in ((sweep.verified[i] & ran, colour), (~sweep.verified[i] & ran,
                                                                 "white")):
                ax.loglog(sweep.gamma0[ok], y[ok], "o", color=colour, mfc=face, ls="")
            _failed_at_bottom(ax, sweep.gamma0[~ran], None)
    left.set(xlabel="γ₀ (γ = γ₀·EA/h)", ylabel=f"largest penetration ({unit.length})",
             title="penetration ≈ the end node's load / γ")
    right.set(xlabel="γ₀ (γ = γ₀·EA/h)", ylabel="relative contact-force error",
              title="contact-force error against Lagrange multipliers")
    left.legend(handles=[*left.get_legend_handles_labels()[0], *_study_legend_extras()],
                fontsize=8)
    figure.suptitle(f"Nitsche's method over γ₀: {sweep.reference.scene.name}")
    return figure


def plot_mesh_convergence(study: MeshConvergence, ax: Axes | None = None) -> Axes:
    """Lagrange multipliers' contact-force error against the continuum over the number of
    elements of the default scene's tapered bar, both area rules, with an O(h²) guide through
    the midpoint rule's first point; errors of exactly 0 drawn at 1e-17 as open markers."""
    ax = _axes(ax, (6.5, 4.6))
    n = study.elements
    for rule, marker in (("midpoint", "o"), ("exact", "s")):
        errors = study.errors[rule]
        line, = ax.loglog(n, np.maximum(errors, FLOOR), f"{marker}-",
                          label=f"area rule {rule!r}" + (": O(h²)" if rule == "midpoint"
                                                         else ": exact to round-off"))
        zero = errors == 0.0
        ax.loglog(n[zero], np.full(zero.sum(), FLOOR), marker, mfc="white",
                  color=line.get_color(), ls="", label="exactly 0" if zero.any() else None)
    first = study.errors["midpoint"][0]
    ax.loglog(n, first * (n[0] / n) ** 2, "k:", label="O(h²)")
    ax.set_xlabel("elements")
    ax.set_ylabel("relative contact-force error")
    ax.set_title(f"default scene (tapered bar; continuum λ = "
                 f"{engineering(study.exact_force, 'N')}):\nLagrange multipliers against the "
                 "continuum", fontsize=10)
    ax.legend(fontsize=8)
    return ax
