"""The scene's constraint graph (contactqp.feasibility): walls and contacts that leave a node no
position are refused with the constraints that conflict; equality contact that fixes a node
twice is refused.
"""

from __future__ import annotations

import pytest

import contactqp
from closed_forms import (
    BAR,
    DEFAULT_SCENE,
    default_scene_with,
)
from contactqp import (
    BarContact,
    OptionError,
    Scene,
    Support,
    Wall,
)


def two_bars_with(walls, contacts) -> Scene:
    return Scene((BAR, BAR), (Support(0, 0), Support(2, 1)), (), walls, contacts=contacts)


def test_equality_with_walls_on_both_sides_of_one_node_is_refused():
    scene = default_scene_with(walls=(Wall(3, 1e-4, "+"), Wall(3, 1e-4, "-")))
    with pytest.raises(OptionError, match=r"node 3"):
        contactqp.solve(scene, "lagrange", "equality")


@pytest.mark.parametrize(("plus", "minus"), [(-1e-4, -1e-4), (1e-4, -2e-4)])
def test_walls_that_leave_a_node_no_position_are_refused(plus, minus):
    """"+" wall: u <= plus; "−" wall: u >= −minus. No u when plus + minus < 0 (two press fits,
    or u <= 1e-4 and u >= 2e-4)."""
    with pytest.raises(contactqp.SceneError) as error:
        DEFAULT_SCENE.with_walls((Wall(4, plus, "+"), Wall(4, minus, "-")))
    message = str(error.value)
    assert f"wall[0] (u ≤ {plus:g} m at node 4)" in message
    assert f"wall[1] (u ≥ {-minus:g} m at node 4)" in message
    assert "no position" in message


def test_walls_that_just_clamp_a_node_are_a_scene():
    """plus + minus = 0: one position, u = plus, which both walls allow."""
    scene = DEFAULT_SCENE.with_walls((Wall(4, 1e-4, "+"), Wall(4, -1e-4, "-")))
    result = contactqp.solve(scene)
    assert result.u[4] == pytest.approx(1e-4, rel=1e-12)  # held at the one position
    assert result.verified


def test_a_conflict_through_a_bar_contact_names_every_constraint():
    """bar 0 node 2 pushed to u <= −1e-4, bar 1 node 0 to u >= 2e-4, and the contact
    u(1, 0) − u(0, 2) <= 0: 2e-4 <= u(1, 0) <= u(0, 2) <= −1e-4, impossible by 3e-4."""
    with pytest.raises(contactqp.SceneError) as error:
        two_bars_with((Wall(2, -1e-4, "+", 0), Wall(0, -2e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    message = str(error.value)
    for name in ("wall[0]", "wall[1]", "contact[0]"):
        assert name in message
    assert "0 ≤ -0.0003 m" in message


def test_the_same_walls_with_room_are_a_scene():
    scene = two_bars_with((Wall(2, -1e-4, "+", 0), Wall(0, 2e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    assert contactqp.solve(scene).verified


def test_equality_through_a_bar_contact_that_fixes_a_node_twice_is_refused():
    scene = two_bars_with((Wall(2, 1e-4, "+", 0), Wall(0, 1e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    with pytest.raises(contactqp.OptionError) as error:
        contactqp.solve(scene, contact="equality")
    assert all(name in str(error.value) for name in ("wall[0]", "wall[1]", "contact[0]"))


def test_two_bar_contacts_from_supported_ends_to_one_node_are_refused():
    """Random scene (seed 8): bar 1's node 0 held at u >= 0 by two bar contacts whose other
    ends are supports, and at u <= 0 by a wall. Each contact alone clamps the node with the
    wall (a one-way loop); together they split the wall's force any way, and a method and the
    exact reference disagreed about it, both verified."""
    with pytest.raises(contactqp.SceneError, match="not determined"):
        Scene((BAR, BAR, BAR), (Support(0, 0), Support(2, 1), Support(0, 2)), (),
              (Wall(0, 0.0, "+", 1),),
              contacts=(BarContact(2, 0, 1, 0, 0.0), BarContact(0, 0, 1, 0, 0.0)))


def test_two_zero_gap_loops_that_share_a_row_are_refused():
    """Random scene (seed 150610, every gap 0): bar 1's node 1 held at u <= 0 by a wall; a bar
    contact ties bar 0's node 1 (a wall holds it at u >= 0) to it, and another ties bar 0's
    supported node 0 to it. Each loop through the wall runs one way round, but together they
    let a force go round the wall, the two contacts and the other wall with the first wall
    free (rows facing both ways): the penalty and the reference split it 5.3e5 N apart, both
    verified, the same on every node."""
    with pytest.raises(contactqp.SceneError, match="more than one way") as refused:
        Scene((BAR, BAR), (Support(0, 0), Support(0, 1)), (),
              (Wall(1, 0.0, "-", 0), Wall(1, 0.0, "+", 1)),
              contacts=(BarContact(0, 1, 1, 1, 0.0), BarContact(0, 0, 1, 1, 0.0)))
    assert "wall[0]" in str(refused.value) and "contact[1]" in str(refused.value)


def test_two_zero_gap_loops_apart_are_a_scene():
    """The same with the second contact given a gap: one loop is left, one way round."""
    Scene((BAR, BAR), (Support(0, 0), Support(0, 1)), (),
          (Wall(1, 0.0, "-", 0), Wall(1, 0.0, "+", 1)),
          contacts=(BarContact(0, 1, 1, 1, 0.0), BarContact(0, 0, 1, 1, 1e-4)))


@pytest.mark.parametrize("seed", range(5))
def test_walls_alone_are_checked_as_the_constraint_graph_checks_them(seed):
    # a scene of walls alone is checked in numpy (feasibility._two_walls_conflict); the
    # constraint graph's edges, node by node, must find the same node and say the same
    import numpy as np

    from contactqp import Bar, Scene, Support, Wall
    from contactqp.feasibility import constraint_graph, impossible_constraints

    rng = np.random.default_rng(seed)
    bars = (Bar.uniform(1e-4, 2e11, length=1.0, elements=6),
            Bar.uniform(1e-4, 2e11, length=1.0, elements=4))
    nodes = [(b, n) for b in range(2) for n in range(1, bars[b].n_nodes)]  # 0: supports
    walls = []
    for b, n in nodes:
        for side in ("+", "-"):
            if rng.random() < 0.6:
                walls.append(Wall(n, 1.0, side, bar=b))
    scene = Scene(bars, (Support(0, bar=0), Support(0, bar=1)), (), tuple(walls))
    for _ in range(20):
        gaps = np.round(rng.normal(size=len(walls)) * 1e-4, 5)
        try:
            scene.with_values(gaps=gaps)
            found = ""
        except contactqp.SceneError as error:
            found = str(error)
        # the graph: the first node (by its first wall) whose + and - edges sum below 0
        sides: dict[int, dict[int, tuple[float, str]]] = {}
        for start, end, weight, _, text in constraint_graph(_with_gaps(scene, gaps)):
            node = end if start == -1 else start
            sides.setdefault(node, {})[1 if start == -1 else -1] = (weight, text)
        expected = next((f"{p[1][1]} and {p[-1][1]}" for p in sides.values()
                         if len(p) == 2 and p[1][0] + p[-1][0] < 0.0), "")
        assert (expected in found) if expected else found == ""
        assert impossible_constraints(_with_gaps(scene, gaps)) == (found if expected else "")


def _with_gaps(scene, gaps):
    """The scene with these gaps, unchecked (as Scene.with_values makes it before its check)."""
    import copy
    from dataclasses import replace

    made = copy.copy(scene)
    made.__dict__.pop("layout", None)
    object.__setattr__(made, "walls", tuple(replace(w, gap=float(g))
                                            for w, g in zip(scene.walls, gaps)))
    return made
