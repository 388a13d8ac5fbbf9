"""The bars: the undeformed and the deformed scene side by side, with supports, walls, bar
contacts and loads, and the verdict of the check (:func:`plot_bar`)."""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle

from contactqp.errors import OptionError
from contactqp.plot.common import (
    CONTACT,
    LOAD,
    SUPPORT,
    WALL,
    _axes,
    engineering,
    round_125,
)
from contactqp.result import Result

ROW_GAP = 0.6  # between the undeformed rows and the deformed ones, in rows
THICKEST = 0.28  # half the height of the thickest element, in rows


def bar_magnification(result: Result) -> float:
    """The default magnification of :func:`plot_bar`: a 1-2-5 number (:func:`round_125`) at
    which the largest displacement or gap is drawn at most a tenth of the longest bar."""
    largest = max(float(np.abs(result.u).max(initial=0.0)),
                  float(np.abs(result.layout.gaps).max(initial=0.0)))
    return round_125(0.1 * result.layout.longest_bar / largest) if largest > 0 else 1.0


def bar_positions(result: Result, magnification: float) -> tuple[np.ndarray, np.ndarray]:
    """(x of each bar's node 0, the row each bar is drawn on). A bar contact puts node_b
    ``gap`` × ``magnification`` beyond node_a; a bar no contact places starts at 0. Bars
    whose undeformed extents overlap are drawn on separate rows."""
    scene = result.scene
    starts: list[float | None] = [None] * len(scene.bars)
    for root in range(len(scene.bars)):
        if starts[root] is None:
            starts[root] = 0.0
            _place_through_contacts(scene, starts, magnification)
    lengths = np.array([b.node_x[-1] for b in scene.bars])
    tolerance = 1e-9 * float(lengths.max())
    rows: list[list[tuple[float, float]]] = []
    row_of = []
    for start, length in zip(starts, lengths):
        span = (start, start + length)
        row = next((r for r, taken in enumerate(rows) if all(
            span[1] <= lo + tolerance or span[0] >= hi - tolerance for lo, hi in taken)),
            len(rows))
        if row == len(rows):
            rows.append([])
        rows[row].append(span)
        row_of.append(row)
    return np.array(starts, dtype=float), np.array(row_of)


def _place_through_contacts(scene, starts: list, magnification: float) -> None:
    """Place every bar a chain of contacts joins to a placed one (``starts`` filled in)."""
    placed = True
    while placed:
        placed = False
        for c in scene.contacts:
            xa, xb = scene.bars[c.bar_a].node_x[c.node_a], scene.bars[c.bar_b].node_x[c.node_b]
            if starts[c.bar_a] is not None and starts[c.bar_b] is None:
                starts[c.bar_b] = starts[c.bar_a] + xa + magnification * c.gap - xb
                placed = True
            elif starts[c.bar_b] is not None and starts[c.bar_a] is None:
                starts[c.bar_a] = starts[c.bar_b] + xb - magnification * c.gap - xa
                placed = True


@dataclass(frozen=True, eq=False)
class _Sketch:
    """Where plot_bar draws each node: x (undeformed or deformed) and the y of its row."""

    result: Result
    magnification: float

    @cached_property
    def positions(self) -> tuple[np.ndarray, np.ndarray]:
        return bar_positions(self.result, self.magnification)

    @property
    def n_rows(self) -> int:
        return int(self.positions[1].max()) + 1

    def x(self, deformed: bool) -> np.ndarray:
        """x of every global node."""
        layout = self.result.layout
        local = np.concatenate([b.node_x for b in self.result.scene.bars])
        start = np.repeat(self.positions[0], np.diff(layout.node_offsets))
        return start + local + (self.magnification * self.result.u if deformed else 0.0)

    def y(self, deformed: bool) -> np.ndarray:
        """y of every global node's row: the undeformed rows from 0 down, then the deformed."""
        row = self.positions[1][self.result.layout.node_bar]
        return -(row + (self.n_rows + ROW_GAP if deformed else 0.0))

    @cached_property
    def half(self) -> np.ndarray:
        """Half the drawn height of each element (∝ √area, the thickest THICKEST rows)."""
        areas = self.result.layout.areas
        return np.maximum(THICKEST * np.sqrt(areas / areas.max()), 0.06)

    @cached_property
    def node_half(self) -> np.ndarray:
        """Half the drawn height at each global node: its thicker element's."""
        layout = self.result.layout
        half = np.zeros(layout.n_nodes)
        start = layout.elements[0]
        np.maximum.at(half, start, self.half)
        np.maximum.at(half, start + 1, self.half)
        return half

    @cached_property
    def width(self) -> float:
        """The x extent of everything drawn (for sizes of glyphs)."""
        x = np.concatenate((self.x(False), self.x(True), self.wall_x))
        return float(np.ptp(x)) or 1.0

    @cached_property
    def wall_x(self) -> np.ndarray:
        """x of every wall: its node's undeformed x plus sign × gap, magnified."""
        layout, scene = self.result.layout, self.result.scene
        x = self.x(False)
        return np.array([x[layout.node(w.bar, w.node)] + w.sign * self.magnification * w.gap
                         for w in scene.walls])


def plot_bar(result: Result, ax: Axes | None = None, magnification: float | None = None) -> Axes:
    """The scene as it is before (top rows) and after loading (bottom rows): the bars, each
    element as tall as √ of its area; supports (black, hatched on the held side); loads
    (green arrows); walls (red, hatched on the wall's side: across the bar beyond an end
    node, as a stop above the bar at any other node); contacts between bars (purple: the face
    of node_a drawn at bar b's height); every displacement and gap magnified by
    ``magnification`` (default :func:`bar_magnification`, a 1-2-5 number). Bars whose
    extents overlap are drawn on separate rows. The deformed rows give each contact force
    that is not zero; the title says whether the answer was verified. An OptionError for a
    Result that has no scene (a problem's; a scene on a frictional bed is solved as one:
    :func:`~contactqp.plot.plot_traction` draws it)."""
    if getattr(result, "scene", None) is None:
        raise OptionError("plot_bar draws a bar scene's Result; this one is a problem's (a "
                          "scene on a frictional bed is solved as its problem: use "
                          "plot_traction)")
    ax = _axes(ax, (9, 3.2 + 0.9 * _rows(result)))
    sketch = _Sketch(result, bar_magnification(result) if magnification is None
                     else float(magnification))
    for deformed in (False, True):
        _draw_elements(ax, sketch, deformed)
        _draw_supports(ax, sketch, deformed)
        _draw_walls(ax, sketch, deformed)
        _draw_contacts(ax, sketch, deformed)
        _draw_point_loads(ax, sketch, deformed)
    _draw_distributed_loads(ax, sketch)
    _frame_bar_chart(ax, sketch)
    return ax


def _rows(result: Result) -> int:
    return 1 if len(result.scene.bars) == 1 else int(bar_positions(result, 1.0)[1].max()) + 1


def _draw_elements(ax: Axes, sketch: _Sketch, deformed: bool) -> None:
    layout = sketch.result.layout
    x, y = sketch.x(deformed), sketch.y(deformed)
    state = "deformed" if deformed else "undeformed"
    colour = "tab:blue" if deformed else "0.82"
    bar, first = layout.node_bar, layout.node_offsets
    for e, (j, half) in enumerate(zip(layout.elements[0], sketch.half)):
        b = int(bar[j])
        ax.add_patch(Rectangle((x[j], y[j] - half), x[j + 1] - x[j], 2 * half,
                               facecolor=colour, edgecolor="k", linewidth=0.5, alpha=0.9,
                               gid=f"{state} bar {b} element {j - first[b]}"))
    ax.plot(x, y, "k.", markersize=3, ls="")


def _hatch(ax: Axes, x: float, y0: float, y1: float, width: float, colour: str,
           gid: str) -> None:
    """A line from (x, y0) to (x, y1) with hatching ``width`` wide (negative: to the left)."""
    ax.plot([x, x], [y0, y1], color=colour, linewidth=2.2, gid=gid, solid_capstyle="butt")
    ax.add_patch(Rectangle((min(x, x + width), y0), abs(width), y1 - y0, facecolor="none",
                           edgecolor=colour, hatch="////", linewidth=0))


def _draw_supports(ax: Axes, sketch: _Sketch, deformed: bool) -> None:
    layout = sketch.result.layout
    x, y = sketch.x(deformed), sketch.y(deformed)
    first, last = layout.bar_ends
    w = 0.015 * sketch.width
    for i, j in enumerate(layout.support_nodes):
        reach = sketch.node_half[j] + 0.1
        side = -w if j == first[j] else (w if j == last[j] else 0.0)
        if side:
            _hatch(ax, x[j], y[j] - reach, y[j] + reach, side, SUPPORT, f"support {i}")
        else:  # an inner node: held from below
            ax.plot([x[j]] * 2, [y[j] - reach, y[j] + reach], color=SUPPORT, linewidth=2.2,
                    gid=f"support {i}")
            ax.add_patch(Rectangle((x[j] - w, y[j] - reach - 0.1), 2 * w, 0.1,
                                   facecolor="none", edgecolor=SUPPORT, hatch="////"))


def _draw_walls(ax: Axes, sketch: _Sketch, deformed: bool) -> None:
    """Walls do not move: the same x in both rows. Beyond an end node a wall crosses the bar's
    axis; at any other node it is a stop above the bar, and a tab on the node reaches it."""
    result = sketch.result
    layout = result.layout
    x, y = sketch.x(deformed), sketch.y(deformed)
    first, last = layout.bar_ends
    w = 0.02 * sketch.width
    for i, wall in enumerate(result.scene.walls):
        j = layout.node(wall.bar, wall.node)
        half = sketch.node_half[j]
        outside = j == (last[j] if wall.side == "+" else first[j])
        y0, y1 = (y[j] - half - 0.1, y[j] + half + 0.1) if outside else (
            y[j] + half + 0.04, y[j] + half + 0.4)
        state = "deformed" if deformed else "undeformed"
        _hatch(ax, sketch.wall_x[i], y0, y1, wall.sign * w, WALL, f"wall {i} {state}")
        if not outside:
            ax.plot([x[j]] * 2, [y[j], y0 + 0.12], color=WALL, linewidth=1.2)
        if deformed:
            _force_label(ax, sketch, result.contact_force[i], sketch.wall_x[i], y1)


def _draw_contacts(ax: Axes, sketch: _Sketch, deformed: bool) -> None:
    """A contact between bars: node_a's face drawn at bar b's height (with a lug from bar a
    when the two bars are on different rows), node_b ``gap`` (magnified) beyond it."""
    result = sketch.result
    layout = result.layout
    x, y = sketch.x(deformed), sketch.y(deformed)
    state = "deformed" if deformed else "undeformed"
    for i, c in enumerate(result.scene.contacts):
        a, b = layout.node(c.bar_a, c.node_a), layout.node(c.bar_b, c.node_b)
        reach = sketch.node_half[b] + 0.1
        if y[a] != y[b]:
            ax.plot([x[a]] * 2, [y[a], y[b]], color=CONTACT, linewidth=1.2)
        ax.plot([x[a]] * 2, [y[b] - reach, y[b] + reach], color=CONTACT, linewidth=2.2,
                gid=f"contact {i} {state}")
        ax.plot([x[b]], [y[b]], "o", color=CONTACT, markersize=4)
        if deformed:  # above the face; beside the lug, at the face's top, when there is one
            # (not halfway between the rows: a load arrow under bar a's node sits there)
            row = len(result.scene.walls) + i
            at = (x[a], y[b] + reach)
            _force_label(ax, sketch, result.contact_force[row], *at,
                         ha=None if y[a] == y[b] else "right")


def _force_label(ax: Axes, sketch: _Sketch, force: float, x: float, y: float,
                 ha: str | None = None) -> None:
    """The force a contact carries, above it; none where it carries nothing (an open
    contact); red and 'pulls' where it pulls (not physical)."""
    result = sketch.result
    tiny = 1e-9 * result.force_scale
    if abs(force) <= tiny:
        return
    centre = float(np.median(sketch.x(False)))
    text = engineering(force, result.scene.unit.force)
    ax.annotate(text if force > 0 else f"pulls: {text}", (x, y),
                xytext=(-3, 0) if ha == "right" else (0, 2),
                textcoords="offset points", fontsize=8, va="bottom",
                ha=ha or ("right" if x > centre else "left"),
                color="k" if force > 0 else "tab:red",
                fontweight="normal" if force > 0 else "bold")


def _draw_point_loads(ax: Axes, sketch: _Sketch, deformed: bool) -> None:
    """An arrow below the bar (walls and contact forces are above it) from the loaded node,
    along the load, labelled in the upper rows."""
    result = sketch.result
    layout = result.layout
    x, y = sketch.x(deformed), sketch.y(deformed)
    length = 0.06 * sketch.width
    for i, (j, load) in enumerate(zip(layout.load_nodes, result.scene.loads)):
        height = y[j] - sketch.node_half[j] - 0.12
        tip = x[j] + math.copysign(length, load.force)
        ax.annotate("", (tip, height), (x[j], height),
                    gid=f"load {i} {'deformed' if deformed else 'undeformed'}",
                    arrowprops={"arrowstyle": "-|>", "color": LOAD, "linewidth": 1.8})
        ax.plot([x[j]] * 2, [y[j], height], color=LOAD, linewidth=1)
        if not deformed:
            ax.annotate(engineering(load.force, result.scene.unit.force),
                        (0.5 * (x[j] + tip), height), xytext=(0, -2), textcoords="offset points",
                        ha="center", va="top", fontsize=8, color=LOAD)


def _draw_distributed_loads(ax: Axes, sketch: _Sketch) -> None:
    """Small arrows below the elements a distributed load covers (upper rows), labelled q."""
    result = sketch.result
    layout, unit = result.layout, result.scene.unit
    x, y = sketch.x(False), sketch.y(False)
    for i, q in enumerate(result.scene.distributed):
        bar = result.scene.bars[q.bar]
        start = layout.node(q.bar, q.start)
        stop = layout.node(q.bar, bar.n_elements if q.stop is None else q.stop)
        height = y[start] - sketch.node_half[start:stop + 1].max() - 0.12
        length = math.copysign(min(0.04 * sketch.width, 0.5 * (x[stop] - x[start])), q.intensity)
        for tail in np.linspace(x[start], x[stop] - length, 6 if q.stop is None else 4):
            ax.annotate("", (tail + length, height), (tail, height), gid=f"distributed load {i}",
                        arrowprops={"arrowstyle": "-|>", "color": LOAD, "linewidth": 1})
        ax.annotate(f"q = {engineering(q.intensity, unit.stiffness)}",
                    (0.5 * (x[start] + x[stop]), height), xytext=(0, -3),
                    textcoords="offset points", ha="center", va="top", fontsize=8,
                    color=LOAD)


def _frame_bar_chart(ax: Axes, sketch: _Sketch) -> None:
    """Limits with room for the labels, the rows named, the title with the verdict, and the
    legend beside the axes (where it crosses nothing)."""
    result, m = sketch.result, sketch.magnification
    scene = result.scene
    x = np.concatenate((sketch.x(False), sketch.x(True), sketch.wall_x))
    margin = 0.08 * sketch.width
    ax.set_xlim(x.min() - margin, x.max() + margin)
    rows = sketch.n_rows
    ax.set_ylim(-(2 * rows + ROW_GAP - 1) - 0.75, 0.8)
    ticks, names = [], []
    for deformed, state in ((False, "undeformed"), (True, "deformed")):
        for row in range(rows):
            bars = np.flatnonzero(sketch.positions[1] == row)
            ticks.append(-(row + (rows + ROW_GAP if deformed else 0.0)))
            names.append(state if len(scene.bars) == 1 else
                         f"{state}\nbar{'s' if bars.size > 1 else ''} "
                         f"{', '.join(map(str, bars))}")
    ax.set_yticks(ticks, names, fontsize=8)
    ax.tick_params(axis="y", length=0)
    ax.set_xlabel(f"x ({scene.unit.length}); displacements and gaps magnified ×{m:g}")
    verdict, colour = _verdict(result)
    ax.set_title(f"{scene.name}\n{result.label}, {result.contact} contact: {verdict}",
                 fontsize=10, color=colour)
    ax.legend(handles=_bar_legend(result), loc="center left", bbox_to_anchor=(1.01, 0.5),
              fontsize=8, frameon=False)


def _verdict(result: Result) -> tuple[str, str]:
    """What the check found, short enough for a title (its first finding, then '…')."""
    first, *more = result.message.split("; ")
    found = textwrap.shorten(first + (" …" if more else ""), 90, placeholder=" …")
    if not result.verified:
        return f"NOT verified: {found}", "tab:red"
    if not result.physical:
        return f"verified, but {found}", "tab:red"
    return "verified; labels: contact forces", "k"


def _bar_legend(result: Result) -> list:
    scene = result.scene
    handles = [Patch(facecolor="0.82", edgecolor="k", label="undeformed"),
               Patch(facecolor="tab:blue", edgecolor="k", label="deformed"),
               Line2D([], [], color=SUPPORT, linewidth=2.2, label="support")]
    if scene.loads or scene.distributed:
        handles.append(Line2D([], [], color=LOAD, marker=">", label="load"))
    if scene.walls:
        handles.append(Line2D([], [], color=WALL, linewidth=2.2, label="wall (hatched side)"))
    if scene.contacts:
        handles.append(Line2D([], [], color=CONTACT, linewidth=2.2, marker="o", markersize=4,
                              label="contact: face of node a, node b"))
    return handles
