"""Bars held only by contact: a bar with no support, pressed against a wall or another bar by
its loads. K is singular there (the bar can move as a whole); Lagrange multipliers, the penalty,
the augmented Lagrangian, the QP solvers and Nitsche solve such scenes, the methods that need K⁻¹ refuse
them, and a scene whose loads do not press such a bar against anything is a clear error.

Symbols: k_e = E·A_e/L_e, F a load (N), g a gap (m), λ a contact force (N). Every expected
number is statics by hand: the only outside forces on a bar with no support are its loads and
its contacts, so the contacts carry its net load.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import contactqp
from contactqp import Bar, BarContact, Load, Scene, Support, Wall
from contactqp.model.chain.floating import MAX_FLOATING_BARS, unheld_bars
from contactqp.reference import reference

E = 200e9
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
AREAS = [1e-3, 5e-4, 2e-4, 1e-4]  # k_e = E·A/0.25 m: 8e8, 4e8, 1.6e8, 8e7 N/m
BAR = Bar.from_areas(AREAS, E, length=1.0)
K_E = E * np.array(AREAS) / 0.25
# methods and options that solve bars held only by contact
SOLVING = [("lagrange", {}), ("penalty", {}), ("augmented", {}), ("qp", {"backend": "clarabel"}),
           ("qp", {"backend": "osqp", "accuracy": "high"}), ("qp", {"backend": "cvxpy"}),
           ("nitsche", {})]
# relative force tolerance per method: the explicit methods to round-off, the penalty to its
# s/ε ≈ 1e-6 (default ε = 1e6 × the stiffness the walls see), solvers to their settings
TOLERANCE = {"lagrange": 1e-12, "penalty": 1e-5, "augmented": 1e-10, "qp": 1e-5,
             "nitsche": 1e-10}


def free_bar(force: float = 1e3, gap: float = 1e-4) -> Scene:
    """BAR with no support, ``force`` at node 0, a "+" wall ``gap`` beyond node 4."""
    return Scene(BAR, (), (Load(0, force),), (Wall(4, gap, "+"),), name="free bar")


@pytest.mark.parametrize(("method", "options"), SOLVING)
def test_a_free_bar_pressed_against_a_wall_carries_its_whole_load(method, options):
    F, g = 1e3, 1e-4
    result = contactqp.solve(free_bar(F, g), method, **options)
    assert result.verified, result.message
    assert result.contact_force[0] == pytest.approx(F, rel=TOLERANCE[method])
    # node 4 at the wall (the penalty: λ/ε past it), each element shortened by F/k_e
    tip = result.u[4]
    # the penalty and Nitsche leave a penetration λ/ε, λ/γ
    assert tip == pytest.approx(g, rel=1e-3 if method in ("penalty", "nitsche") else 1e-6)
    expected = tip + np.cumsum((F / K_E)[::-1])[::-1]  # u_j = u_4 + Σ_(e>=j) F/k_e
    np.testing.assert_allclose(result.u[:4], expected, rtol=1e-6)


@pytest.mark.parametrize(("method", "options"), SOLVING)
def test_two_bars_between_walls(method, options):
    """Bar 0 (load F1 at node 1) between a "−" wall at its node 0 and a contact from its node
    4 to bar 1's node 0; bar 1 (load F2 at node 2) against a "+" wall at its node 4. With F1 > 0
    and F1 + F2 > 0 both are pushed to the "+" wall: the contact carries F1, the "+" wall
    F1 + F2, the "−" wall nothing. (No load on a contact node: Nitsche reads the contact force
    from the stress of the element there.)"""
    F1, F2 = 1e3, -3e2
    scene = Scene((BAR, BAR), (), (Load(1, F1, 0), Load(2, F2, 1)),
                  (Wall(0, 2e-4, "-", 0), Wall(4, 1e-4, "+", 1)),
                  contacts=(BarContact(0, 4, 1, 0, 5e-5),))
    result = contactqp.solve(scene, method, **options)
    assert result.verified, result.message
    tolerance = TOLERANCE[method] * (F1 + F2)
    np.testing.assert_allclose(result.contact_force, [0.0, F1 + F2, F1], atol=tolerance)


@pytest.mark.parametrize(("method", "options"), SOLVING)
def test_a_free_bar_pressed_against_a_supported_one(method, options):
    """Bar 1 held at its node 4; bar 0, free, pushed by F at its node 1 onto bar 1's node 0
    across a gap g: the contact carries F, and bar 1's node 0 moves F·Σ1/k_e."""
    F, g = 7e2, 5e-5
    scene = Scene((BAR, BAR), (Support(4, 1),), (Load(1, F, 0),),
                  contacts=(BarContact(0, 4, 1, 0, g),))
    result = contactqp.solve(scene, method, **options)
    assert result.verified, result.message
    assert result.contact_force[0] == pytest.approx(F, rel=TOLERANCE[method])
    assert result.u[5] == pytest.approx(F * np.sum(1.0 / K_E), rel=1e-5)


def test_the_example_scene_file_matches_its_closed_form():
    """examples/held_by_contact.toml: k0 = k1 = 2e7 N/m, F = 20 kN through the contact; bar 0's
    tip at −F/k0, bar 1's node 0 a gap behind it, its loaded end F/k1 further."""
    scene = contactqp.load_scene(EXAMPLES / "held_by_contact.toml")
    result = contactqp.solve(scene)
    k, F, g = 2e7, 2e4, 5e-5
    assert result.verified, result.message
    assert result.contact_force[0] == pytest.approx(F, rel=1e-12)
    assert result.u[[2, 3, 5]] == pytest.approx([-F / k, -F / k - g, -2 * F / k - g], rel=1e-12)


def test_equality_contact_holds_a_free_bar_that_its_load_pulls_away():
    """With equality contact the wall may pull: it holds the bar against a load in −x."""
    F = 1e3
    scene = free_bar(-F)
    assert unheld_bars(scene, "equality") == ""
    result = contactqp.solve(scene, "lagrange", "equality")
    assert result.verified, result.message
    assert result.contact_force[0] == pytest.approx(-F, rel=1e-12)
    with pytest.raises(contactqp.SceneError, match=r"nothing holds bar\[0\] against its load "
                                                   r"of -1000 N.*−x"):
        contactqp.solve(scene, "lagrange")


def test_a_free_bar_with_nothing_in_the_way_of_its_load_is_an_error():
    scene = Scene((BAR, BAR), (Support(0, 0),), (Load(2, 5e2, 1),),
                  contacts=(BarContact(0, 4, 1, 0, 1e-4),))  # bar 1 is pushed away from bar 0
    for method in ("lagrange", "penalty", "qp"):
        with pytest.raises(contactqp.SceneError, match=r"nothing holds bar\[1\] against its "
                                                       r"load of 500 N.*\+x"):
            contactqp.solve(scene, method)
    with pytest.raises(contactqp.SceneError, match=r"nothing holds bar\[1\]"):
        reference(scene)


def test_bars_whose_loads_cancel_are_not_determined():
    """Two free bars in contact, pushed into each other by equal and opposite loads, between
    walls with room: they may sit anywhere between the walls."""
    scene = Scene((BAR, BAR), (), (Load(0, 1e3, 0), Load(4, -1e3, 1)),
                  (Wall(0, 1e-4, "-", 0), Wall(4, 1e-4, "+", 1)),
                  contacts=(BarContact(0, 4, 1, 0, 0.0),))
    with pytest.raises(contactqp.SceneError, match=r"nothing presses bar\[0\] and bar\[1\] "
                                                   r"against a wall or bar contact: its loads "
                                                   r"sum to 0 N"):
        contactqp.solve(scene, "lagrange")


def test_a_bar_with_no_support_wall_or_contact_is_refused_when_built():
    with pytest.raises(contactqp.SceneError, match=r"support: bar\[1\] has no support, no wall "
                                                   r"and no contact"):
        Scene((BAR, BAR), (Support(0, 0),))


def test_too_many_free_bars_are_refused_with_the_limit():
    n = MAX_FLOATING_BARS + 1
    bars = (BAR,) * n
    contacts = tuple(BarContact(i, 4, i + 1, 0, 0.0) for i in range(n - 1))
    scene = Scene(bars, (), (Load(0, 1.0, 0),), (Wall(4, 0.0, "+", n - 1),), contacts=contacts)
    assert f"at most {MAX_FLOATING_BARS} bars" in unheld_bars(scene)


@pytest.mark.parametrize("method", ["lemke", "pgs", "semismooth_newton"])
def test_methods_that_need_the_inverse_of_K_refuse_with_the_reason(method):
    with pytest.raises(contactqp.SolverError, match=r"bar\[0\] has no support, so K is singular"):
        contactqp.solve(free_bar(), method)
    with pytest.raises(contactqp.SolverError, match=r"lagrange, penalty, augmented, qp and "
                                                    r"nitsche can"):
        contactqp.solve(free_bar(), "lagrange", formulation="condensed")


def test_a_prepared_free_bar_refuses_loads_that_pull_it_away():
    prepared = contactqp.prepare(free_bar(), "lagrange")
    assert prepared.solve(loads=[2e3]).contact_force[0] == pytest.approx(2e3, rel=1e-12)
    with pytest.raises(contactqp.SceneError, match=r"nothing holds bar\[0\]"):
        prepared.solve(loads=[-2e3])


@pytest.mark.parametrize("method", ["lagrange", "penalty", "qp"])
def test_a_batch_of_free_bar_cases_carries_each_load(method):
    """Free bars are solved case by case (the cases engine needs K⁻¹); each case's wall
    carries its own load, and a case whose load pulls the bar away names the case."""
    prepared = contactqp.prepare(free_bar(), method)
    loads = np.array([[1e3], [2e3], [5e2]])
    batch = prepared.solve_many(loads=loads)
    assert batch.verified.all()
    np.testing.assert_allclose(batch.contact_force[:, 0], loads[:, 0], rtol=1e-5)
    with pytest.raises(contactqp.SceneError, match=r"case 1: nothing holds bar\[0\]"):
        prepared.solve_many(loads=np.array([[1e3], [-1e3]]))


def test_the_load_path_of_a_free_bar_starts_one_step_in():
    """With no load nothing fixes where a free bar is, so its curve starts at t = 1/steps; at
    every step the wall carries t·F, and the first contact factor is 0."""
    F, steps = 1e3, 4
    path = contactqp.load_path(free_bar(F), steps=steps,
                               methods={"lagrange": ("lagrange", "inequality", {})})
    np.testing.assert_allclose(path.load_factor, [0.25, 0.5, 0.75, 1.0])
    lagrange = path.methods["lagrange"]
    assert lagrange.verified.all()
    np.testing.assert_allclose(lagrange.contact_force[:, 0], path.load_factor * F, rtol=1e-12)
    assert contactqp.first_contact_factor(free_bar(F)) == 0.0


def test_an_answer_that_leaves_a_free_bar_unheld_is_not_verified():
    """u and λ = 0 balance nothing; and an answer that puts the bar anywhere with λ = F on a
    wall it does not touch says nothing about where the bar is."""
    scene = free_bar()
    found = contactqp.check(scene, np.zeros(5), [0.0], [], "inequality")
    assert not found.verified
    exact = reference(scene)
    shifted = exact.displacement - 1e-3  # the bar 1 mm short of the wall, still λ = F
    found = contactqp.check(scene, shifted, exact.contact_force, [], "inequality")
    assert not found.verified


def _two_bars_between_walls() -> Scene:
    return Scene((BAR, BAR), (), (Load(1, 1e3, 0), Load(2, -3e2, 1)),
                 (Wall(0, 2e-4, "-", 0), Wall(4, 1e-4, "+", 1)),
                 contacts=(BarContact(0, 4, 1, 0, 5e-5),))


@pytest.mark.parametrize("scene", [free_bar(), _two_bars_between_walls()],
                         ids=["free bar", "two bars between walls"])
@pytest.mark.parametrize("theta", [1.0, 0.0, -1.0])
def test_nitsche_never_hands_a_singular_system_to_the_linear_solve(monkeypatch, scene, theta):
    """Nitsche's Newton steps on bars held only by contact: a contact set that leaves a bar
    free makes its system singular, and what LAPACK returns for a singular system differs
    between machines (this scene passed on one CPU and failed on another with the same
    numpy and scipy). Every matrix the method solves is checked here, in dense numpy, to be
    far from singular (condition number below 1e10; a set that leaves a bar free gives about
    1e17), so the outcome cannot depend on the LAPACK build."""
    from contactqp.methods import nitsche

    conditions = []
    solve = nitsche.linalg.solve

    def recording(matrix, rhs, **options):
        conditions.append(np.linalg.cond(matrix.toarray()))
        return solve(matrix, rhs, **options)

    monkeypatch.setattr(nitsche.linalg, "solve", recording)
    result = contactqp.solve(scene, "nitsche", theta=theta)
    assert conditions and max(conditions) < 1e10, conditions
    assert result.verified, result.message
    np.testing.assert_allclose(result.contact_force, reference(scene).contact_force,
                               rtol=0, atol=1e-10 * 1e3)


# --- a bar wedged between walls that leave it no room: unloaded, yet its place is forced.
# With no load the bar does not deform, so every node sits at the + wall's gap g₊
# (= −g₋), and no wall needs to push: u = g₊ everywhere, λ = 0.
WEDGED = {
    "two zero-gap walls at one node": (
        Scene(Bar.uniform(1e-4, E, length=1.0, elements=2), (),
              walls=(Wall(2, 0.0, "+"), Wall(2, 0.0, "-"))), 0.0),
    "walls at both ends, shifted": (
        Scene(Bar.uniform(1e-4, E, length=1.0, elements=2), (),
              walls=(Wall(2, 1e-3, "+"), Wall(0, -1e-3, "-"))), 1e-3),
}


@pytest.mark.parametrize("name", list(WEDGED))
@pytest.mark.parametrize("method", ["lagrange", "penalty", "augmented"])
def test_an_unloaded_bar_wedged_between_walls_sits_where_they_leave_it(name, method):
    """Refused as "position not determined" before, although u = g₊ is forced."""
    scene, at = WEDGED[name]
    assert unheld_bars(scene) == ""
    result = contactqp.solve(scene, method)
    assert result.verified and result.physical
    assert np.array_equal(result.u, np.full(3, at))
    assert np.array_equal(result.contact_force, np.zeros(2))


def test_nitsche_solves_a_bar_wedged_at_its_ends():
    scene, at = WEDGED["walls at both ends, shifted"]
    result = contactqp.solve(scene, "nitsche")
    assert result.verified
    np.testing.assert_allclose(result.u, np.full(3, at), rtol=1e-12)
    assert np.abs(result.contact_force).max() == 0.0


def test_a_wedged_bar_beside_a_loaded_one_leaves_that_one_its_closed_form():
    """Bar 0 supported at node 0, 1e3 N at node 2 and an open wall; bar 1 wedged: bar 0's
    tip moves F·L/(EA) = 1e3·1/(2e11·1e-4) = 5e-5 m, bar 1 stays at 0."""
    bars = (Bar.uniform(1e-4, 2e11, length=1.0, elements=2),
            Bar.uniform(1e-4, 2e11, length=1.0, elements=2))
    scene = Scene(bars, (Support(0, 0),), (Load(2, 1e3, 0),),
                  (Wall(2, 1e-4, "+", 0), Wall(1, 0.0, "+", 1), Wall(1, 0.0, "-", 1)))
    result = contactqp.solve(scene)
    assert result.verified
    np.testing.assert_allclose(result.u, [0.0, 2.5e-5, 5e-5, 0.0, 0.0, 0.0], rtol=1e-12,
                               atol=0.0)
    assert np.array_equal(result.contact_force, np.zeros(3))


@pytest.mark.parametrize(("walls", "load"), [
    ((Wall(2, 1e-4, "+"), Wall(2, 0.0, "-")), None),  # room 1e-4 m: anywhere in it
    ((Wall(2, 0.0, "+"), Wall(2, 0.0, "-")), Load(1, 0.0)),  # a zero load is no load
])
def test_a_free_bar_with_room_or_a_load_is_still_judged_by_its_load(walls, load):
    scene = Scene(Bar.uniform(1e-4, E, length=1.0, elements=2), (),
                  () if load is None else (load,), walls)
    message = unheld_bars(scene)
    if load is None:
        assert "its position between its walls and contacts is not determined" in message
    else:
        assert message == ""


def test_floating_bars_held_through_repeated_rows_by_lagrange():
    """Two bars with no support, held by walls and bar contacts whose zero gaps close a loop
    (random_scene seed 404007, floating 0.5; found by a fresh-seed property run): the chain's
    active set meets a singular set, and Lemke's handover needs K⁻¹. Lagrange then solves the
    scene as its problem, whose set solves take a K that contact holds, and hands the answer
    back to the chain, saying so: its answer is verified by the chain's check, within its
    bounds of the exact reference (rational arithmetic), with the scene's bar quantities;
    the same with the loop's own options and through a prepared scene (the handover is the
    method's, not the front end's)."""
    from contactqp.random_scenes import random_scene

    scene = random_scene(np.random.default_rng(404007), floating=0.5)
    exact = reference(scene)
    for found in (contactqp.solve(scene, "lagrange"),
                  contactqp.solve(scene, "lagrange", max_iterations=100, active_set="passed"),
                  contactqp.prepare(scene, "lagrange").solve()):
        assert found.verified and found.method == "lagrange"
        assert "then the scene as its problem" in found.info["active_set"]
        assert found.layout is not None  # the chain's Result, checked by the chain's check
        assert np.abs(found.contact_force - exact.contact_force).max() <= (
            found.force_error_bound)
        assert np.abs(found.u - exact.displacement).max() <= found.displacement_error_bound
        assert found.element_force is not None
        assert found.element_force.size == sum(bar.n_nodes - 1 for bar in scene.bars)


def test_a_zero_pivot_that_no_free_mode_explains_is_refused_in_one_line(monkeypatch):
    """A K that SuperLU finds exactly singular where the search for free modes came back
    empty (as four inverse iterations once left a one-element floating bar: random scene 1382,
    tests/test_front_ends.py) is a ProblemError of one line, not SuperLU's RuntimeError."""
    import contactqp.model.sparse as sparse_module

    monkeypatch.setattr(sparse_module, "free_modes", lambda *args, **kwargs: None)
    K = np.array([[1.0, -1.0], [-1.0, 1.0]])  # one spring, nothing holds it: a free mode
    problem = contactqp.Problem(K, [1.0, 0.0], [[1.0, 0.0]], [0.5])
    with pytest.raises(contactqp.ProblemError) as refused:
        contactqp.solve(problem, "lagrange")
    assert "\n" not in str(refused.value) and str(refused.value).startswith("K is singular")
