"""Scene builders (contactqp.builders): the default scene's numbers, the minimal mesh, the area
rules' convergence, a wall at every node.

Every expected number is computed here from the problem statement (diameters, lengths, the
cone's compliance ∫ dx/(E π d(x)²/4) by quadrature), never read back from the library.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import contactqp
from closed_forms import (
    DEFAULT_DIAMETERS_MM,
    E_STEEL,
    continuum_force,
)
from contactqp import (
    Load,
    SceneError,
    Support,
    Wall,
)
from contactqp.builders import wall_at_every_node
from contactqp.model import (
    Layout,
)


@pytest.mark.parametrize("elements", [2, 4, 8])
def test_exact_area_rule_matches_the_cone_closed_form(elements):
    result = contactqp.solve(contactqp.default_scene(elements, "exact"))
    # π d_a d_b / 4 per segment is the cone's exact flexibility: only round-off and the
    # quadrature (epsrel 1e-13) separate them
    assert result.contact_force[0] == pytest.approx(continuum_force(), rel=1e-12)


def test_midpoint_rule_converges_as_h_squared():
    errors = [abs(contactqp.solve(contactqp.default_scene(n)).contact_force[0] - continuum_force())
              for n in (4, 8, 16, 32)]
    rates = [math.log2(a / b) for a, b in itertools.pairwise(errors)]
    # the midpoint rule's flexibility error is O(h²); the first halving is still pre-asymptotic
    assert rates == pytest.approx([2.0, 2.0, 2.0], abs=0.1)


@pytest.mark.parametrize("rule", ["midpoint", "exact"])
def test_minimal_mesh_reproduces_the_fine_model(rule):
    fine = contactqp.default_scene(64, rule)
    small = contactqp.minimal(fine)
    assert small.bars[0].n_elements == 2  # nodes at the support, the load and the wall only
    a, b = contactqp.solve(fine), contactqp.solve(small)
    # series flexibility is exact condensation: equal up to summation round-off
    assert b.contact_force == pytest.approx(a.contact_force, rel=1e-12)
    assert b.reactions == pytest.approx(a.reactions, rel=1e-12)
    assert b.u == pytest.approx(a.u[[0, 32, 64]], rel=1e-12)
    if rule == "exact":
        assert b.contact_force[0] == pytest.approx(continuum_force(), rel=1e-12)


def test_minimal_keeps_walls_on_both_sides_and_renumbers():
    bar = contactqp.Bar.from_areas(np.linspace(1e-3, 2e-3, 10), 70e9, length=2.0)
    scene = contactqp.Scene(
        bar, (contactqp.Support(0), contactqp.Support(10)),
        (contactqp.Load(3, 2e5), contactqp.Load(7, -1e5)),
        (contactqp.Wall(3, 1e-5, "+"), contactqp.Wall(7, 2e-5, "-"), contactqp.Wall(5, 1e-6)))
    small = contactqp.minimal(scene)
    assert [w.node for w in small.walls] == [1, 3, 2]
    for contact in contactqp.CONTACT_KINDS:
        a, b = contactqp.solve(scene, contact=contact), contactqp.solve(small, contact=contact)
        assert b.contact_force == pytest.approx(a.contact_force, rel=1e-10, abs=1e-6)
        assert b.u == pytest.approx(a.u[[0, 3, 5, 7, 10]], rel=1e-10, abs=1e-18)


def test_wall_at_every_node_keeps_the_nearer_wall_and_checks_its_input():
    scene = contactqp.default_scene()  # a wall 1e-4 beyond node 4
    near = wall_at_every_node(scene, 5e-5)
    assert [w.gap for w in near.walls if w.node == 4] == [5e-5]
    far = wall_at_every_node(scene, 1e-3)
    assert [w.gap for w in far.walls if w.node == 4] == [1e-4]
    with pytest.raises(SceneError, match=r"obstacle.gap must be one value or one per node of bar\[0\] \(5\), got 3"):
        wall_at_every_node(scene, [1e-4, 1e-4, 1e-4])
    with pytest.raises(SceneError, match="obstacle.bar = 2: the scene has bars 0 to 0"):
        wall_at_every_node(scene, 1e-4, bar=2)


def test_seed_scene_numbers():
    scene = contactqp.default_scene()
    d_nodes = np.array(DEFAULT_DIAMETERS_MM) / 1000.0
    d_mid = (d_nodes[:-1] + d_nodes[1:]) / 2.0  # 37.5, 32.5, 27.5, 22.5 mm
    areas = math.pi * d_mid**2 / 4.0
    # same formula, diameters rounded differently (linspace vs literals): a few ulp
    np.testing.assert_allclose(scene.bars[0].areas, areas, rtol=1e-14)
    # 0.25 m and its multiples are exact in binary, so equality is exact
    assert scene.bars[0].lengths.tolist() == [0.25] * 4
    assert scene.bars[0].node_x.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert scene.bars[0].youngs_modulus.tolist() == [E_STEEL] * 4
    assert scene.bars[0].yield_stress == 200e6
    assert Layout(scene).n_nodes == 5
    # k = E A / L; one multiplication and division of the same operands: a few ulp
    np.testing.assert_allclose(scene.bars[0].element_stiffness, E_STEEL * areas / 0.25, rtol=1e-14)
    assert scene.supports == (Support(0),)
    assert scene.loads == (Load(2, 565486.67),)
    assert scene.walls == (Wall(4, 1e-4, "+"),)
    assert Layout(scene).nodal_loads.tolist() == [0.0, 0.0, 565486.67, 0.0, 0.0]


@pytest.mark.parametrize("elements", [2, 8, 64])
@pytest.mark.parametrize("area_rule", ["midpoint", "exact"])
def test_seed_scene_remeshed(elements, area_rule):
    scene = contactqp.default_scene(elements, area_rule)
    d = 0.040 - 0.020 * np.arange(elements + 1) / elements  # diameter at every node (m)
    if area_rule == "midpoint":
        areas = math.pi * ((d[:-1] + d[1:]) / 2.0) ** 2 / 4.0
    else:
        areas = math.pi * d[:-1] * d[1:] / 4.0
    # same formulas, diameters rounded differently (linspace vs this line): a few ulp
    np.testing.assert_allclose(scene.bars[0].areas, areas, rtol=1e-14)
    # lengths 1/elements: the same division either way, or exact for powers of two
    np.testing.assert_allclose(scene.bars[0].lengths, 1.0 / elements, rtol=1e-15)
    assert scene.loads == (Load(elements // 2, 565486.67),)  # still at mid-length
    assert scene.walls == (Wall(elements, 1e-4, "+"),)  # still beyond the tip


@pytest.mark.parametrize("elements", [0, 3, 2.0, True])
def test_seed_scene_needs_an_even_number_of_elements(elements):
    with pytest.raises(SceneError, match=r"elements.*got"):
        contactqp.default_scene(elements)
