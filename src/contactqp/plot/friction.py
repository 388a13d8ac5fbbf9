"""The traction along a frictional contact: per contact the normal force and the friction force
against its position, the contacts that stick shaded (:func:`plot_traction`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from contactqp.errors import OptionError
from contactqp.plot.common import _axes, bracket, target_name

STICK = "tab:green"


def plot_traction(result: Any, position: Any = None, ax: Axes | None = None,
                  direction: int = 0) -> Axes:
    """The forces along the contact of a Result with friction: the normal force λ_N (where
    the contacts have normal rows) and the friction force λ_T (its component ``direction``, one
    of the d per contact), each against the contacts' ``position``, with the contacts that
    stick shaded and those that slip marked.

    Parameters
    ----------
    result : Result
        A Result with friction (``result.friction`` not None).
    position : array_like, optional
        One coordinate per contact (a length); default the contacts' numbers.
    ax : Axes, optional
        Where to draw; default the axes of a new Figure.
    direction : int
        Which tangential direction of a 3D contact (0 or 1); 0 in 2D.

    Returns
    -------
    Axes
        Its lines carry the gids ``"normal force"``, ``"friction force"`` and
        ``"stick zone"`` (the shading, one patch per run of sticking contacts).

    Raises
    ------
    OptionError
        A Result without friction, a position of the wrong size, or a direction it has not.
    """
    if getattr(result, "friction", None) is None:
        raise OptionError("plot_traction draws a Result with friction; this one has none")
    friction = np.asarray(result.friction_force, dtype=float)
    count, d = friction.shape
    if not (isinstance(direction, (int, np.integer)) and 0 <= direction < d):
        raise OptionError(f"direction must be 0{' or 1' if d == 2 else ''} for this Result, "
                          f"got {direction!r}")
    x = (np.arange(count, dtype=float) if position is None
         else np.asarray(position, dtype=float).reshape(-1))
    if x.size != count:
        raise OptionError(f"position must have one value per contact ({count}), got {x.size}")
    force_unit, length_unit = result.model.units
    ax = _axes(ax)
    order = np.argsort(x, kind="stable")
    x, stick = x[order], np.asarray(result.stick)[order]
    state = np.asarray(result.state)[order]
    _shade_runs(ax, x, stick & (state != "open"))
    normal = np.asarray(result.contact_force, dtype=float)
    if normal.size == count:
        ax.plot(x, normal[order], "-", color="tab:blue", marker=".", gid="normal force",
                label="normal force λ_N")
    ax.plot(x, friction[order, direction], "-", color="tab:orange", marker=".",
            gid="friction force", label="friction force λ_T")
    slipping = state == "slip"
    ax.plot(x[slipping], friction[order, direction][slipping], "o", mfc="none",
            color="tab:orange", gid="slipping contacts")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel(f"position{bracket(length_unit)}" if position is not None else "contact")
    ax.set_ylabel(f"force{bracket(force_unit)}")
    verdict = "verified" if result.verified else "NOT verified"
    ax.set_title(f"{target_name(result)}: {result.friction} friction by {result.method} "
                 f"({verdict})", fontsize=10)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(color=STICK, alpha=0.15, label="stick zone"),
                Line2D([], [], marker="o", mfc="none", color="tab:orange", ls="",
                       label="slipping contact")]
    ax.legend(handles=handles, fontsize=8, loc="best")
    return ax


def _shade_runs(ax: Axes, x: np.ndarray, inside: np.ndarray) -> None:
    """A shaded band over each run of consecutive contacts in ``inside`` (halfway to the
    neighbours on each side)."""
    if not inside.any():
        return
    edges = np.concatenate(([x[0]], (x[:-1] + x[1:]) / 2.0, [x[-1]]))
    start = None
    for k, flag in enumerate(np.append(inside, False)):
        if flag and start is None:
            start = k
        elif not flag and start is not None:
            ax.axvspan(edges[start], edges[k], color=STICK, alpha=0.15, lw=0, gid="stick zone")
            start = None


__all__ = ["plot_traction"]
