"""Charts (contactqp.plot): each returns its Axes on a Figure of its own, with no pyplot state,
and draws what it is given."""

from __future__ import annotations

import matplotlib

import contactqp
from contactqp import plot
from contactqp.studies import nitsche_sweep, penalty_sweep


def test_the_bar_chart_draws_the_bars_the_walls_and_the_supports():
    result = contactqp.solve()
    ax = plot.plot_bar(result)
    assert isinstance(ax, matplotlib.axes.Axes) and ax.figure is not None
    labels = {text.get_text() for text in ax.get_legend().get_texts()}
    assert {"undeformed", "deformed", "wall", "support"} <= labels
    assert "x (m)" in ax.get_xlabel()


def test_the_penalty_chart_labels_its_axes_in_the_scenes_units():
    scene = contactqp.convert_units(contactqp.default_scene(), "mm-N-MPa")
    figure = plot.plot_penalty_sweep(penalty_sweep(scene, penalties=(1e8, 1e11)))
    labels = [ax.get_xlabel() for ax in figure.axes]
    assert labels and all("N/mm" in label for label in labels)
    assert any("(mm)" in ax.get_ylabel() for ax in figure.axes)


def test_the_nitsche_chart_draws_one_line_per_theta_on_both_panels():
    figure = plot.plot_nitsche_sweep(nitsche_sweep(gamma0=(10.0, 1e6)))
    assert len(figure.axes) == 2
    for ax in figure.axes:
        assert "γ₀" in ax.get_xlabel()
    names = {text.get_text() for text in figure.axes[0].get_legend().get_texts()}
    assert names == {"θ = 1", "θ = 0", "θ = -1"}
