"""The hull's fast paths against the general ones they stand in for.

Glossary: u_free, the displacement with no wall held; w = u_free − u, spread linear in the
compliance φ between held nodes (:func:`contactqp.model.spread`); a stretch, the free nodes
between two held nodes (or a held node and a free end); settling a stretch, adding the other
side's hull walls in each of its sub-stretches within the same step.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from contactqp import Bar, DistributedLoad, Load, Scene, Support, Wall
from contactqp.methods import hull
from contactqp.methods.hull import minorant
from contactqp.model import spread
from contactqp.model.chain.model import scene_model
from contactqp.reference import reference


def _one_bar_channel(elements: int, support: int) -> Scene:
    """A bar with a wall on both sides of every node, supported at ``support`` (node 0 and
    the last node free when it is inside: the flat ends of spread), loaded both ways."""
    bar = Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9)
    x = np.linspace(0.0, 1.0, elements + 1)
    centre = 1e-5 * np.sin(7.0 * x)
    scene = Scene(bar, (Support(support),), (Load(elements // 3, 4e5), Load(elements, -2e5)))
    scene = contactqp.wall_at_every_node(scene, centre + 2e-6)
    return contactqp.wall_at_every_node(scene, 2e-6 - centre, "-")


@pytest.mark.parametrize("support", [0, 17, 60])
@pytest.mark.parametrize("fraction", [0.0, 0.05, 0.2, 0.6, 0.95])
def test_displacements_are_spread_bit_for_bit(support, fraction):
    """Every path of WallsOnChain.displacements (segment by segment for a few held nodes,
    numpy.interp over the chain, or at the free nodes alone for many) gives the numbers
    u_free − spread(...) gives at the nodes not held, to the last bit."""
    scene = _one_bar_channel(60, support)
    model = scene_model(scene)
    chain = hull.WallsOnChain(model)
    rng = np.random.default_rng(int(1000 * fraction) + support)
    for _ in range(5):
        pinned = chain.support | (rng.random(chain.n) < fraction)
        nodes = np.flatnonzero(pinned)
        w_held = rng.normal(size=nodes.size) * 1e-5
        w_held[chain.support[nodes]] = 0.0
        expected = chain.u_free - spread(model.layout, nodes, w_held)
        found = chain.displacements(pinned, nodes, w_held)
        assert np.array_equal(found[~pinned], expected[~pinned])


@pytest.mark.parametrize(("support", "one_run"), [(0, True), (40, False)])
def test_passed_walls_on_one_run_of_nodes_or_not(support, one_run):
    """passed() on one run of wall nodes (read in place, support at node 0) and on walls
    split by a support (gathered) finds what the definition finds: the nodes whose signed
    gap bound − side·u is below −tolerance, held nodes left out."""
    scene = _one_bar_channel(80, support)
    chain = hull.WallsOnChain(scene_model(scene))
    rng = np.random.default_rng(3)
    u = rng.normal(size=chain.n) * 3e-6
    pinned = chain.support | (rng.random(chain.n) < 0.3)
    for side in (1, -1):
        nodes = chain.wall_nodes[side]
        assert (nodes[-1] - nodes[0] + 1 == nodes.size) == one_run  # the path under test
        gaps = chain.bound[side][nodes] - side * u[nodes]
        expected = nodes[(gaps < -1e-7) & ~pinned[nodes]]
        assert expected.size  # something is passed
        assert np.array_equal(chain.passed(side, u, pinned, 1e-7), expected)


@pytest.mark.parametrize("support", [0, 17, 60])
def test_a_two_sided_channel_is_settled_in_few_steps_and_exactly(support):
    """A step settles a passed stretch on both sides (one side per step took 6-7 steps on
    the builders' channel): one step settles the bar, the next finds nothing to change
    (with the sub-stretches' ends read off by one held node: 3-4 steps); the answer is the
    exact one (reference, another method)."""
    scene = _one_bar_channel(60, support)
    result = contactqp.solve(scene, "lagrange", formulation="full")
    assert result.info.get("active_set") == "hull"
    assert result.iterations <= 2
    exact = reference(scene)
    assert np.abs(result.contact_force - exact.contact_force).max() <= (
        result.force_error_bound + 1e-12 * result.force_scale)
    assert result.verified, result.message


@pytest.mark.parametrize("contacts", [10**3, 10**4])
def test_the_builders_channel_settles_in_few_steps(contacts):
    """The wavy channel (issue 28's case): 6-7 steps one side at a time before, 2 now (the
    first settles the bar, the second finds nothing to change), the same forces as the
    textbook loop's (to the bounds)."""
    scene = contactqp.channel(contacts)
    result = contactqp.solve(scene, "lagrange", formulation="full")
    assert result.info.get("active_set") == "hull"
    assert result.iterations <= 2
    passed = contactqp.solve(scene, "lagrange", formulation="full", active_set="passed")
    assert np.abs(result.contact_force - passed.contact_force).max() <= (
        result.force_error_bound + passed.force_error_bound)


def test_stretches_in_two_bars_with_no_held_node_between():
    """Two bars, the first supported at its first node and the second at its last, both
    pushed onto their + walls: a passed node's stretch is found by bisection among the held
    nodes, and no held node lies between the two bars' passed nodes, so a stretch must end
    at its bar's end (measured: the + walls of nodes 4-22 passed on the first step). Both
    bars' stretches are settled on that step, so the second finds nothing to change; a
    stretch that ran on into the next bar would leave the second bar for a third step."""
    bars = tuple(Bar.tapered_circle(1.0, 12, 0.03, 0.02, 210e9) for _ in range(2))
    supports = (Support(0, 0), Support(12, 1))
    distributed = (DistributedLoad(2e6, 0), DistributedLoad(1.5e6, 1))
    wave = 2e-3 * np.sin(np.arange(12) * 1.3)
    walls = tuple(Wall(node + 1 - b, gap, side, b) for b in range(2) for node in range(12)
                  for gap, side in ((4e-3 + wave[node], "+"), (4e-3 - wave[node], "-")))
    scene = Scene(bars, supports, (), walls, distributed=distributed)
    result = contactqp.solve(scene, "lagrange", formulation="full")
    assert result.info.get("active_set") == "hull"
    exact = reference(scene)
    assert result.iterations == 2
    pressing = np.flatnonzero(exact.contact_force > 0)
    assert {scene.walls[i].bar for i in pressing} == {0, 1}  # walls in both bars press
    assert np.abs(result.contact_force - exact.contact_force).max() <= (
        result.force_error_bound + 1e-12 * result.force_scale)
    assert result.verified, result.message


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dropped", [0.0, 0.001, 0.3, 0.9])
def test_the_kept_points_slopes_are_their_own_division_bit_for_bit(seed, dropped):
    """The minorant's slopes between kept points (a point's step where its next point is
    kept, worked out again only across the dropped ones) are, to the last bit, the division
    diff(y[kept]) / diff(x[kept]) over the kept points gathered."""
    rng = np.random.default_rng(seed)
    n = 2000
    x = np.cumsum(rng.uniform(1e-3, 1.0, n))
    y = rng.normal(size=n) * 10.0 ** rng.uniform(-12, 3)
    kept = rng.uniform(size=n) >= dropped
    kept[[0, -1]] = True
    points = np.flatnonzero(kept)
    step = np.diff(y) / np.diff(x)
    expected = np.diff(y[points]) / np.diff(x[points])
    assert minorant._kept_slopes(x, y, step, kept).tobytes() == expected.tobytes()


@pytest.mark.parametrize("seed", range(6))
def test_a_joined_hull_s_slopes_are_its_corners_division_bit_for_bit(seed, monkeypatch):
    """A convex curve with bumps three points wide: one pruning pass leaves dents, the convex
    runs are joined by tangents (the path is checked to be taken), and the slopes returned
    are the division over the joined corners gathered, to the last bit; a run of consecutive
    corners is read as a view holding the gathered values, any other as the gather."""
    rng = np.random.default_rng(seed)
    n = 2000
    x = np.cumsum(rng.uniform(1e-3, 1.0, n))
    curve = (x - x.mean()) ** 2 * 1e-6
    for start in rng.choice(np.arange(10, n - 10), 5, replace=False):
        curve[start: start + 3] += [0.5, 1.0, 0.7]
    joins = []
    join = minorant._join_convex_runs
    monkeypatch.setattr(minorant, "_join_convex_runs", lambda *a: joins.append(1) or join(*a))
    corners, slope = minorant._hull_corners(x, curve)
    assert joins and 2 * corners.size >= n  # the joined path, slopes from the kept steps
    assert slope.tobytes() == (np.diff(curve[corners]) / np.diff(x[corners])).tobytes()
    run = np.arange(100, 140)
    view = minorant._read(x, run)
    assert view.base is not None and view.tobytes() == x[run].tobytes()
    assert minorant._read(x, corners).tobytes() == x[corners].tobytes()
