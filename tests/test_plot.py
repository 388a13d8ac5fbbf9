"""Charts (contactqp.plot): each draws on a Figure of its own, with no pyplot state, and draws
the scene as it is: tested on the artists (positions in data units, markers, labels), never
on pixels. Every expected position comes from the scene file or a closed form.

Glossary: m the magnification, g a gap (m), k = EA/L (N/m), F a load (N), λ a contact force
(N), t a load factor, t* the load factor at which the first contact closes.
"""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib
from dataclasses import replace
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

import contactqp
from closed_forms import (
    DEFAULT_F,
    DEFAULT_GAP,
    DEFAULT_LOAD_NODE,
    DEFAULT_WALL_NODE,
    EXAMPLES,
    default_closed_form,
    default_compliance,
)
from contactqp import plot
from contactqp.curve import first_contact_factor, load_path
from contactqp.scene_io import load_scene
from contactqp.studies import Run, mesh_convergence, nitsche_sweep, penalty_sweep

# the example scenes a bar chart draws (a scene on a frictional bed is solved as its problem:
# tests/test_bed_scene.py draws its traction)
EXAMPLE = {path.stem: path for path in EXAMPLES
           if "[[bed]]" not in path.read_text(encoding="utf-8")}


def example(name: str) -> tuple[contactqp.Scene, dict]:
    """The example's scene, and its file read independently of contactqp."""
    path = EXAMPLE[name]
    return load_scene(path), tomllib.loads(path.read_text())


def patch(ax, gid: str):
    (found,) = [p for p in ax.patches if p.get_gid() == gid]
    return found


def line(ax, gid: str):
    (found,) = [item for item in ax.lines if item.get_gid() == gid]
    return found


def edges(ax, gid: str) -> tuple[float, float]:
    """(left, right) x of a drawn element."""
    p = patch(ax, gid)
    return p.get_x(), p.get_x() + p.get_width()


def drawn(ax) -> FigureCanvasAgg:
    """Lay the figure out (Agg, no pyplot) so that texts have their extents."""
    canvas = FigureCanvasAgg(ax.figure)
    canvas.draw()
    return canvas


def magnification_in(ax) -> float:
    return float(ax.get_xlabel().rsplit("×", 1)[1])


def test_plot_imports_no_pyplot():
    code = "import sys, contactqp.plot; sys.exit('matplotlib.pyplot' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


@pytest.mark.parametrize("value, expected", [(909.0, 500.0), (102.0, 100.0), (250.0, 200.0),
                                             (1000.0, 1000.0), (0.37, 0.2), (19.9, 10.0)])
def test_magnifications_are_round_1_2_5_numbers(value, expected):
    assert plot.round_125(value) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("name", ["default", *EXAMPLE])
def test_the_default_magnification_is_the_largest_1_2_5_number_that_keeps_moves_small(name):
    """m = a·10ᵏ with a in {1, 2, 5}, the largest such that m × (largest displacement or gap)
    is at most a tenth of the longest bar."""
    scene = contactqp.default_scene() if name == "default" else load_scene(EXAMPLE[name])
    result = contactqp.solve(scene)
    m = magnification_in(plot.plot_bar(result))
    mantissa = m / 10.0 ** math.floor(math.log10(m))
    assert mantissa == pytest.approx(1.0) or mantissa == pytest.approx(2.0) or (
        mantissa == pytest.approx(5.0))
    largest = max(np.abs(result.u).max(), max(abs(g) for g in result.layout.gaps))
    longest = max(b.node_x[-1] for b in scene.bars)
    assert m * largest <= 0.1 * longest * (1 + 1e-12)
    following = m * (2.5 if mantissa == pytest.approx(2.0) else 2.0)  # the next 1-2-5 number
    assert following * largest > 0.1 * longest


def test_two_bars_are_drawn_apart_by_the_gap_and_touch_when_the_contact_closes():
    """two_bars: bar 0 (1 m, k0 = 2e8 N/m) then, g = 0.1 mm beyond its end, bar 1 (k1 = 5e7
    N/m); F = 50 kN. Closed: λ = (F − k0 g) k1/(k0 + k1) = 6 kN, u_a = (F − λ)/k0."""
    scene, data = example("two_bars")
    gap, m = data["contact"][0]["gap"], 500.0
    ax = plot.plot_bar(contactqp.solve(scene), magnification=m)
    assert magnification_in(ax) == m
    (_, end_0), (start_1, _) = (edges(ax, "undeformed bar 0 element 0"),
                                edges(ax, "undeformed bar 1 element 0"))
    assert start_1 - end_0 == pytest.approx(gap * m, rel=1e-9)
    assert patch(ax, "undeformed bar 0 element 0").get_y() + patch(
        ax, "undeformed bar 0 element 0").get_height() / 2 == pytest.approx(
        patch(ax, "undeformed bar 1 element 0").get_y()
        + patch(ax, "undeformed bar 1 element 0").get_height() / 2)  # one row: end to end
    k0, k1, F = 200e9 * 1e-3 / 1.0, 200e9 * 2.5e-4 / 1.0, 50e3
    lam = (F - k0 * gap) * k1 / (k0 + k1)
    (_, end_0), (start_1, _) = (edges(ax, "deformed bar 0 element 0"),
                                edges(ax, "deformed bar 1 element 0"))
    assert end_0 == pytest.approx(1.0 + m * (F - lam) / k0, rel=1e-12)
    assert start_1 == pytest.approx(end_0, abs=m * 1e-12)  # closed: the bars touch
    face = line(ax, "contact 0 undeformed").get_xdata()
    assert face[0] == pytest.approx(end_0 - m * (F - lam) / k0, rel=1e-12)  # node a's face
    assert "6 kN" in {t.get_text() for t in ax.texts}  # the contact force, labelled


def test_several_bars_are_drawn_on_rows_with_their_gaps_and_the_minus_wall_beside_the_bar():
    """several_bars: bar 1 starts g₀ (magnified) beyond bar 0's end; bar 2 starts g₁ beyond
    bar 1's node 1 (0.1 m into bar 1), so it overlaps bar 1 and is drawn on a row of its own;
    the − wall sits g_w before bar 1's node 2 and is drawn above the bar, not across it."""
    scene, data = example("several_bars")
    m = 200.0
    ax = plot.plot_bar(contactqp.solve(scene), magnification=m)
    bar_0, bar_1 = data["bar"][:2]
    g0, g1 = data["contact"][0]["gap"], data["contact"][1]["gap"]
    start_1 = bar_0["length"] + m * g0
    node_1 = start_1 + bar_1["length"] / len(bar_1["areas"])
    assert edges(ax, "undeformed bar 1 element 0")[0] == pytest.approx(start_1, rel=1e-12)
    assert edges(ax, "undeformed bar 2 element 0")[0] == pytest.approx(node_1 + m * g1,
                                                                       rel=1e-12)
    rows = {b: patch(ax, f"undeformed bar {b} element 0").get_y()
            + patch(ax, f"undeformed bar {b} element 0").get_height() / 2 for b in range(3)}
    assert rows[0] == rows[1] != rows[2]
    wall = data["wall"][0]
    node_2 = start_1 + 2 * bar_1["length"] / len(bar_1["areas"])
    x, y = line(ax, "wall 0 undeformed").get_data()
    assert x[0] == pytest.approx(node_2 - m * wall["gap"], rel=1e-12)
    element = patch(ax, "undeformed bar 1 element 1")
    assert min(y) > element.get_y() + element.get_height()  # above the bar, not through it


def test_the_bar_chart_draws_the_load_from_its_node_along_it():
    ax = plot.plot_bar(contactqp.solve())
    (arrow,) = [t for t in ax.texts if t.get_gid() == "load 0 undeformed"]
    assert arrow.xy[0] > arrow.xyann[0]  # the default load pushes in +x
    assert arrow.xyann[0] == pytest.approx(0.25 * DEFAULT_LOAD_NODE)  # from the loaded node
    assert "565.5 kN" in {t.get_text() for t in ax.texts}


@pytest.mark.parametrize("name", ["default", *EXAMPLE])
def test_the_bar_chart_keeps_labels_and_legend_off_the_drawing(name):
    scene = contactqp.default_scene() if name == "default" else load_scene(EXAMPLE[name])
    ax = plot.plot_bar(contactqp.solve(scene))
    canvas = drawn(ax)
    frame = ax.get_window_extent(canvas.get_renderer())
    for text in ax.texts:
        box = text.get_window_extent(canvas.get_renderer())
        if text.get_text():
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1, text.get_text()
            assert frame.y0 <= box.y0 and box.y1 <= frame.y1, text.get_text()
    legend = ax.get_legend().get_window_extent(canvas.get_renderer())
    assert legend.x0 >= frame.x1  # beside the axes: it crosses no wall
    names = {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"undeformed", "deformed", "support", "load"} <= names
    assert ("wall (hatched side)" in names) == bool(scene.walls)
    assert "x (m)" in ax.get_xlabel()


@pytest.mark.parametrize("name", ["default", *EXAMPLE])
def test_the_bar_chart_writes_no_force_label_over_a_load_arrow(name):
    """several_bars once put a bar contact's force halfway between its rows, where the load
    arrow under bar 0's end node is drawn: the label sat on the arrow."""
    scene = contactqp.default_scene() if name == "default" else load_scene(EXAMPLE[name])
    ax = plot.plot_bar(contactqp.solve(scene))
    renderer = drawn(ax).get_renderer()
    arrows = [t.arrow_patch.get_window_extent(renderer) for t in ax.texts
              if str(t.get_gid()).startswith("load ")]
    labels = [t for t in ax.texts if t.get_text() and t.get_color() != "tab:green"]
    for label in labels:
        box = label.get_window_extent(renderer)
        assert not any(box.overlaps(arrow) for arrow in arrows), label.get_text()


def test_the_bar_chart_says_when_the_answer_is_not_verified_or_a_wall_pulls():
    """A penalty of 1 N/m lets the bars pass through each other by ~all of the free move:
    the check refuses it. Equality contact at a hundredth of the load pulls the wall."""
    scene, _ = example("two_bars")
    flagged = contactqp.solve(scene, "penalty", penalty=1.0)
    assert not flagged.verified
    ax = plot.plot_bar(flagged)
    assert "NOT verified" in ax.get_title() and ax.title.get_color() == "tab:red"
    pulled = contactqp.solve(contactqp.default_scene().scaled_loads(0.01), "lagrange",
                             "equality")
    ax = plot.plot_bar(pulled)
    assert "verified, but" in ax.get_title()
    assert any(t.get_text().startswith("pulls: -") for t in ax.texts)


def test_the_penalty_chart_marks_the_textbook_eps_capped_runs_and_failed_runs():
    """ε = 1 N/m shrinks the augmented method's force error by ~1 − ε/k ≈ 1 − 1e-8 per update
    (k ~ 1e8 N/m the stiffness the wall sees): it stops at its cap of 100 updates; at 1e10 N/m
    it converges in a few."""
    sweep = penalty_sweep(penalties=(1.0, 1e10))
    figure = plot.plot_penalty_sweep(sweep)
    updates = figure.axes[2]
    for ax in figure.axes:
        assert any(list(item.get_xdata()) == [1e14, 1e14] for item in ax.lines)  # textbook ε
    (capped,) = [item for item in updates.lines
                 if item.get_label().startswith("stopped at its cap")]
    assert list(capped.get_xdata()) == [1.0] and list(capped.get_ydata()) == [100]
    title = figure.get_suptitle()
    assert sweep.reference.scene.name in title and "penalty method" in title
    assert "augmented Lagrangian" in title and "inequality contact" in title
    failed = replace(sweep, runs=(Run("penalty ε=1e+00", "inequality", None, "refused"),
                                  *sweep.runs[1:]),
                     force_error=np.array([np.nan, sweep.force_error[1]]),
                     penetration=np.array([np.nan, sweep.penetration[1]]))
    figure = plot.plot_penalty_sweep(failed)
    for ax in figure.axes[:2]:
        crosses = [item for item in ax.lines if item.get_marker() == "x" and len(item.get_xdata())]
        assert [list(c.get_xdata()) for c in crosses] == [[1.0]]


def test_the_penalty_chart_labels_its_axes_in_the_scenes_units():
    scene = contactqp.convert_units(contactqp.default_scene(), "mm-N-MPa")
    figure = plot.plot_penalty_sweep(penalty_sweep(scene, penalties=(1e8, 1e11)))
    labels = [ax.get_xlabel() for ax in figure.axes if ax.get_xlabel()]
    assert labels and all("N/mm" in label for label in labels)
    assert any("(mm)" in ax.get_ylabel() for ax in figure.axes)
    textbook = 1e14 * 1e-3  # N/m → N/mm
    assert any(list(item.get_xdata()) == [textbook] * 2 for item in figure.axes[0].lines)


def test_the_nitsche_chart_draws_one_line_per_theta_and_marks_refused_solves():
    sweep = nitsche_sweep(gamma0=(10.0, 1e6))
    figure = plot.plot_nitsche_sweep(sweep)
    assert len(figure.axes) == 2
    for ax in figure.axes:
        assert "γ₀" in ax.get_xlabel()
    names = {text.get_text() for text in figure.axes[0].get_legend().get_texts()}
    assert {"θ = 1", "θ = 0", "θ = -1", "solve failed"} <= names
    assert "Nitsche" in figure.get_suptitle() and sweep.reference.scene.name in (
        figure.get_suptitle())
    refused = sweep.force_error.copy()
    refused[0, 0] = np.nan
    figure = plot.plot_nitsche_sweep(replace(sweep, force_error=refused))
    crosses = [item for item in figure.axes[1].lines
               if item.get_marker() == "x" and len(item.get_xdata())]
    assert [list(c.get_xdata()) for c in crosses] == [[10.0]]


def test_the_mesh_chart_names_its_scene_and_method():
    ax = plot.plot_mesh_convergence(mesh_convergence(elements=(2, 4)))
    assert "default scene" in ax.get_title() and "Lagrange" in ax.get_title()


def test_the_load_path_marks_failed_and_pulling_steps_and_draws_the_contact_force():
    """Default scene: before t* no contact force, then λ(t) = (t F f₂ − g)/f₄ (f the
    compliance from the support). Equality contact pulls before t* (ringed); the soft penalty
    (ε = the stiffness the wall sees) penetrates by λ/ε past t*, which the check refuses
    (crossed)."""
    steps = 11
    path = load_path(steps=steps)
    t = np.linspace(0.0, 1.0, steps)
    t_star = DEFAULT_GAP / (DEFAULT_F * default_compliance(DEFAULT_LOAD_NODE))
    figure = plot.plot_load_path(path, first_contact_factor(path.scene))
    top, bottom = figure.axes
    curves = [item for item in top.lines if str(item.get_gid()).startswith("curve ")]
    assert len(curves) == len(path.methods)
    assert len({(c.get_color(), str(c.get_linestyle()), c.get_marker()) for c in curves}) == (
        len(curves))  # every method its own look
    assert len({str(c.get_markevery()) for c in curves}) == len(curves)  # staggered markers
    pulls = [item for item in top.lines if item.get_gid() == "pulling steps"]
    assert np.allclose(np.concatenate([p.get_xdata() for p in pulls]), t[t < t_star])
    failed = [item for item in top.lines if item.get_gid() == "failed steps"]
    assert np.allclose(np.concatenate([f.get_xdata() for f in failed]), t[t > t_star])
    (lagrange,) = [item for item in bottom.lines if item.get_gid() == "curve lagrange"]
    expected = [default_closed_form(force=s * DEFAULT_F)[1] for s in t]
    assert lagrange.get_ydata() == pytest.approx(expected, rel=1e-9, abs=1e-6 * DEFAULT_F)
    assert "contact force" in bottom.get_ylabel()
    assert DEFAULT_WALL_NODE == 4  # the wall the closed form's f₄ is taken to


def test_the_load_path_legend_is_beside_the_curves():
    """wall_at_every_node: the load point reaches its wall early and its curve runs flat
    along the top of the panel, where a legend inside the panel would cover it."""
    figure = plot.plot_load_path(load_path(load_scene(EXAMPLE["wall_at_every_node"]),
                                           steps=5))
    top = figure.axes[0]
    renderer = drawn(top).get_renderer()
    legend = top.get_legend().get_window_extent(renderer)
    assert legend.x0 >= top.get_window_extent(renderer).x1


def test_the_penalty_chart_has_one_legend_off_the_update_cap():
    """The updates panel's legend sat on its own cap line: its mark joins the main legend."""
    figure = plot.plot_penalty_sweep(penalty_sweep(penalties=(1.0, 1e10)))
    assert figure.axes[2].get_legend() is None
    names = {t.get_text() for t in figure.axes[0].get_legend().get_texts()}
    assert "stopped at its cap: not converged" in names


def test_the_load_path_names_a_method_that_has_no_curve():
    scene = contactqp.Scene(contactqp.Bar.from_areas([1e-3], 210e9, length=1.0),
                            contactqp.Support(0), contactqp.Load(1, 5e4),
                            (contactqp.Wall(1, 1e-4, "+"), contactqp.Wall(1, 1e-4, "-")))
    figure = plot.plot_load_path(load_path(scene, steps=3))
    assert figure.axes[0].get_title(loc="left").startswith("no curve: equality")
    assert isinstance(figure.axes[0], matplotlib.axes.Axes)


def test_save_writes_a_png(tmp_path: Path):
    written = plot.save(plot.plot_bar(contactqp.solve()), tmp_path / "bar.png")
    assert Path(written).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
