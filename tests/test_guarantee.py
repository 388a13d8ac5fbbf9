"""``verified`` means right: every method and solver, held to the check's bound on random scenes.

The guarantee (contactqp.check): a verified Result has every contact force within 1e-5·F of
the exact answer and every displacement within 1e-5·U (GUARANTEE), F and U the scene's own
scales; its ``force_error_bound`` (N) and ``displacement_error_bound`` (m) estimate the error.
The exact answer comes from contactqp.reference (statics in extended
precision for one bar with walls, exact rational arithmetic otherwise; itself tested against
closed forms, Fractions and brute force in test_reference.py), never from a method under test.

The scenes (contactqp.random_scenes): areas over five decades with stiff and soft elements side
by side, one to three bars, zero gaps, press fits, walls on both sides, bar contacts,
distributed loads. Each scene is solved by every method in every formulation it takes and by
every installed QP backend and solver (formulation, accuracy and scaling drawn per scene).
Under CI the examples are fixed (conftest); run locally, hypothesis draws fresh seeds.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import (
    runs,
)
from contactqp.model import contact_forces_on_nodes, element_forces, link_forces, support_reactions
from contactqp.model.chain import layout_of
from contactqp.random_scenes import random_scene
from contactqp.reference import (
    reference,
)

# The reference is exact to ~1e-13 of F and U (extended precision over at most a few dozen
# elements; exact for the rational path), and a bound computed in double precision from sums
# over as many elements rounds at ~1e-14: 1e-12 covers both.
ROUND_OFF = 1e-12


# A verified answer's error is within its own bounds, as its summary says, where its pushing
# rows are the exact answer's; where a row changes between pushing and open the bounds rest
# on measurement: hand-built answers reach just under twice the force bound (a review's
# constructions: an open wall that the exact answer closes, a push below the bound that the
# exact answer releases; both walls alone), and benchmarks/guarantee.py on 2026-11-26 found
# no verified run past its bound in 37 000 runs (seed 2026) and 70 000 more (seed 31337;
# seeds 8080, 4242, 777 and 5151 with bars held by contact alone), after the bounds took
# what a pushing bar contact's two ends pass on and what moves a group of them. Before,
# about one verified run in 5 000 was past them, by up to 1.4 times, and earlier checks by
# up to 3.6 times, all within the guarantee (GUARANTEE); these tests then allowed five times.
BOUND_FACTOR = 2.0


def solve_quietly(scene, method, options, formulation):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solvers' own warnings: the check decides
        return contactqp.solve(scene, method, "inequality", formulation, **options)


def assert_within_bound(result: contactqp.Result, exact) -> None:
    """A verified Result is within the guarantee, and within its own bounds (BOUND_FACTOR).
    Where rows repeat a constraint (walls on both sides of a node with the same position, a
    loop of rows with zero gaps) the exact answer fixes no row's own share, only what the rows
    put on each node, Cᵀλ (docs/howto/check.md): the forces are held row by row or node by
    node, whichever is closer."""
    F, U = result.force_scale, result.displacement_scale
    error = result.contact_force - exact.contact_force
    # each row's own error, or where rows share a node what they put on it: the smaller (rows
    # that repeat a constraint split a force as they may; rows that do not, each on its own)
    force_error = min(float(np.abs(error).max(initial=0.0)), float(np.abs(
        contact_forces_on_nodes(result.layout, error)).max(initial=0.0)))
    displacement_error = float(np.abs(result.u - exact.displacement).max())
    context = f"{result.label} {result.options}: {result.residuals}"
    assert force_error <= BOUND_FACTOR * result.force_error_bound + ROUND_OFF * F, context
    assert displacement_error <= (BOUND_FACTOR * result.displacement_error_bound
                                  + ROUND_OFF * U), context
    assert force_error <= contactqp.GUARANTEE[0] * F, context
    assert displacement_error <= contactqp.GUARANTEE[1] * U, context


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_every_verified_answer_is_within_its_bound(seed):
    within_bound(seed)


# Fresh seeds found this one: seed 1198665058, lemke (and DAQP, HiGHS) left a zero-gap bar
# contact 1.1e-7 m past with no force, where the exact answer has it and a touching wall at
# its soft end push with 1 955 N; verified with a force bound of 0.24 N (3.7e-4 of F off).
@pytest.mark.parametrize("seed", [1198665058])
def test_scenes_that_once_passed_their_bound_without_floating_bars_stay_within_it(seed):
    within_bound(seed)


def within_bound(seed: int) -> None:
    """Every method and solver on random_scene(seed): each verified answer within its bound
    and the guarantee."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng)
    exact = reference(scene)
    for method, options, formulation in runs(rng):
        try:
            result = solve_quietly(scene, method, options, formulation)
        except contactqp.ContactqpError:  # refused with a reason (e.g. strain for penalty)
            continue
        if result.verified:
            assert_within_bound(result, exact)


def test_a_contact_left_past_its_gap_onto_a_touching_wall_is_not_verified():
    """The mechanism of seed 1198665058, by hand. Bar 0 (1e10 N/m, load P at its tip) meets
    bar 1's tip (1e4 N/m) through a zero-gap bar contact, and bar 1's tip touches a wall
    (gap 0) on its far side; bar 2 (1e4 N/m, load P) moves 1 m and sets U. Exactly (statics:
    bar 1's tip cannot move, so bar 0's tip cannot either), the contact and the wall each
    push with P and nothing moves but bar 2. The answer with no contact force leaves bar 0's
    tip P/1e10 = 1e-6 m past bar 1's: a penetration of 1e-6 of U, whose force at the
    contact's soft end (1e4 N/m) is 1e-6 of F. Every residual passes, and the answer is P
    off: closing the contact by moving bar 1's tip pushes it into the wall, and pushing it
    back pushes bar 0's tip, across 1e10 N/m. The check must flag it."""
    P, E = 1e4, 1e11
    stiffness = (1e10, 1e4, 1e4)
    bars = tuple(contactqp.Bar(lengths=np.array([1.0]), areas=np.array([k / E]),
                               youngs_modulus=np.array([E])) for k in stiffness)
    scene = contactqp.Scene(
        bars=bars, supports=tuple(contactqp.Support(node=0, bar=b) for b in range(3)),
        loads=(contactqp.Load(node=1, force=P, bar=0), contactqp.Load(node=1, force=P, bar=2)),
        walls=(contactqp.Wall(node=1, gap=0.0, side="+", bar=1),),
        contacts=(contactqp.BarContact(bar_a=0, node_a=1, bar_b=1, node_b=1, gap=0.0),))
    exact = reference(scene)
    np.testing.assert_allclose(exact.contact_force, [P, P], rtol=1e-12)
    np.testing.assert_allclose(exact.displacement, [0, 0, 0, 0, 0, P / stiffness[2]], atol=1e-15)
    u = np.array([0.0, P / stiffness[0], 0.0, 0.0, 0.0, P / stiffness[2]])
    found = contactqp.check(scene, u, np.zeros(2))
    assert not found.verified
    assert found.force_error_bound >= P  # the answer is P off
    # and the same answer to the scene's problem (the general certificate), alike
    assert not contactqp.check(contactqp.problem_from_scene(scene), u, np.zeros(2)).verified
    for method in ("lagrange", "lemke", "augmented", "semismooth_newton", "qp"):
        result = solve_quietly(scene, method, {}, "full")
        if result.verified:
            assert_within_bound(result, exact)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_bars_held_only_by_contact_are_within_their_bound(seed):
    """The same guarantee where some bars have no support and are held by their walls and
    bar contacts alone (K singular); methods that need K⁻¹ refuse such a scene with a reason."""
    held_by_contact_within_bound(seed)


# Fresh seeds found these (CI's fixed examples do not reach them): seed 139, ProxQP carried
# 15.3 N round a loop of a wall, a bar contact and a wall (bound 3.5e-5 N); seed 39063, DAQP
# left a press fit of 2.1e-12 m open (6.2e-5 N off, bound 6.9e-7 N); seed 223347597, HiGHS
# left 13.3 N on a wall 8.4e-8 m open on a bar only contact holds (the chain's bound 0.17 N).
@pytest.mark.parametrize("seed", [139, 39063, 223347597])
def test_scenes_that_once_passed_their_bound_stay_within_it(seed):
    held_by_contact_within_bound(seed)


def held_by_contact_within_bound(seed: int) -> None:
    """Every method and solver on random_scene(seed, floating=0.6): each verified answer
    within its bound and the guarantee."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng, floating=0.6)
    try:
        exact = reference(scene)
    except contactqp.SceneError:  # too many rows for the exact path's last resort
        return
    for method, options, formulation in runs(rng):
        try:
            result = solve_quietly(scene, method, options, formulation)
        except contactqp.ContactqpError:
            continue
        if result.verified:
            assert_within_bound(result, exact)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_the_exact_methods_are_verified(seed):
    """The explicit Lagrange method is exact to round-off: the check must not flag it (a check
    that flags right answers is no check either). Without the extra stiffness contrast: with
    stiffnesses over 13 decades the saddle-point system reaches cond ~ 1e22 on some scenes,
    where no double-precision solve is exact and the check rightly says so."""
    scene = random_scene(np.random.default_rng(seed), max_bars=1, contrast=False)
    result = contactqp.solve(scene, "lagrange")
    assert result.verified and result.physical, result.message
    assert_within_bound(result, reference(scene))


def test_a_wall_that_pushes_less_than_the_force_bound_may_let_its_node_go():
    """Support, a stiff element (1e9 N/m) to node 1 (load −1e5 N), a soft one (100 N/m) to
    node 2 between a zero-gap "+" wall and a "−" wall 1e-5 m behind it. By hand: node 1 at
    −1e-4 m, and node 2, which only the soft element pulls, follows until the "−" wall holds
    it at −1e-5 m, pushing with 100·(1e-4 − 1e-5) = 9e-3 N. The answer a solver gave in a
    random scene (HiGHS, benchmarks/guarantee.py seed 4242 scene 231): node 2 left at 0 with
    the "+" wall pushing 1e-6 N. Its imbalance, 0.01 N, is 1e-7 of F and every force residual
    passes; the "+" wall's push is below the force bound, so node 2 may be free, and its move
    (0.01 N over the soft element's 100 N/m) is what the displacement residual must show."""
    ks, k, P, d = 1e9, 1e2, 1e5, 1e-5
    bar = contactqp.Bar.from_areas([ks / 2e11, k / 2e11], 2e11, length=2.0)
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(1, -P),),
                            (contactqp.Wall(2, 0.0, "+"), contactqp.Wall(2, d, "-")))
    exact_u = [0.0, -P / ks - k * (P / ks - d) / ks, -d]
    exact_force = k * (P / ks - d)  # ≈ 9e-3 N, the "−" wall's
    right = contactqp.check(scene, exact_u, [0.0, exact_force], [P - exact_force], "inequality")
    assert right.verified
    u, left = [0.0, -P / ks, 0.0], 1e-6
    found = contactqp.check(scene, u, [left, 0.0], [P + left], "inequality")
    assert found.residuals["equilibrium"] <= 1e-6 and found.residuals["force"] <= 1e-5
    assert not found.verified
    # node 2 is d = 0.1 U from where it belongs: the residual covers it
    assert found.residuals["displacement"] >= d / (P / ks)


def test_a_force_left_on_a_weakly_active_wall_beside_a_soft_element_is_caught():
    """Support, a soft element (k₀), a zero-gap wall at node 1 that the exact answer leaves
    with no force (the loads beyond it cancel), then stiff elements. By hand: u = [0, 0, 0,
    −F/k₂], λ = 0, no reaction. A force f left on that wall compresses k₀ by f/k₀, which moves
    everything beyond by as much: with k₂/k₀ = 1e3, f = 0.5e-5·F moves the bar by 5e-3 of
    U = F/k₂. Every force residual passes it; the displacement residual does not (interior-
    point solvers leave such forces: the old check passed answers 1e-4 to 7e-4 off in u)."""
    soft, stiff = 1e-6, 1e-3  # m², E = 2e11, 1 m elements: k₀ = 2e5, k₁ = k₂ = 2e8 N/m
    k0, k2, F = 2e11 * soft, 2e11 * stiff, 1e4
    scene = contactqp.Scene(contactqp.Bar.from_areas([soft, stiff, stiff], 2e11, length=3.0),
                            (contactqp.Support(0),),
                            (contactqp.Load(2, F), contactqp.Load(3, -F)),
                            (contactqp.Wall(1, 0.0, "+"),))
    exact_u = np.array([0.0, 0.0, 0.0, -F / k2])
    right = contactqp.check(scene, exact_u, [0.0], [0.0], "inequality")
    assert right.verified and right.force_error_bound <= 1e-14 * F  # round-off only
    left = 0.5e-5 * F
    u = exact_u - np.array([0.0, 1.0, 1.0, 1.0]) * left / k0  # node 1 and all beyond it move
    found = contactqp.check(scene, u, [left], [left], "inequality")  # the support takes it back
    assert found.residuals["equilibrium"] <= 1e-12  # in balance
    # the wall stands off by f/k₀, and the force to close that against k₀ is f: min(f, f) / F
    assert found.residuals["complementarity"] == pytest.approx(0.5e-5, rel=1e-9)
    assert found.residuals["force"] <= 1e-5  # every force within 1e-5 F: the forces are right
    # the bar moved by f/k₀ against U = F/k₂, the free displacement of node 3; the wall pushes
    # with f, no more than the force bound, so it might be released and move by as much
    # again (bounds._release): the residual covers the move, and is at most twice it
    moved = (left / k0) / (F / k2)
    assert moved <= found.residuals["displacement"] <= 2.0 * moved * (1.0 + 1e-9)
    assert not found.verified and "displacement" in found.message


def test_the_issue_penalty_scene_is_flagged():
    """A stiff element holds the wall at node 1 (k₀ = 2.1e12 N/m), soft ones make u large:
    the textbook penalty ε = 1e14 N/m leaves s/ε = 2 % of the force, which the old check
    passed (it measured the penetration against u). Exact: both loads end at the wall,
    1.1e6 N."""
    scene = contactqp.Scene(
        contactqp.Bar.from_areas([1e-1, 1e-5, 1e-5], 210e9, lengths=[0.01, 0.3, 0.3]),
        (contactqp.Support(0),), (contactqp.Load(1, 1e6), contactqp.Load(3, 1e5)),
        (contactqp.Wall(1, 0.0, "+"),))
    textbook = contactqp.solve(scene, "penalty", penalty=1e14)
    k0 = 210e9 * 1e-1 / 0.01
    # λ_ε = P·ε/(ε + k₀): the wall node as a spring k₀ behind the penalty spring
    assert textbook.contact_force[0] == pytest.approx(1.1e6 * 1e14 / (1e14 + k0), rel=1e-9)
    assert not textbook.verified and "feasibility" in textbook.message
    default = contactqp.solve(scene, "penalty")  # ε = 1e6 x the stiffness the wall sees, k₀
    assert default.verified
    # the same closed form at ε = 1e6·k₀: 1.1e6 / (1 + 1e-6), a few ulp of round-off
    assert default.contact_force[0] == pytest.approx(1.1e6 * 1e6 / (1e6 + 1.0), rel=1e-12)


def test_the_forces_left_on_many_rows_add_up_where_a_bar_contact_ties_two_bars():
    """A random scene (the hypothesis example seed=525 of the test above): three bars, a bar
    contact between two of them, press fits of 1.9e11 N. Clarabel (qpsolvers, strain
    formulation, unscaled) leaves about 100 N on each of four rows whose exact force is 0;
    together they move the tied pair by 2.7e-4 m, 1.09e-5 of U. The displacement bound must
    cover that (it took the largest of those forces alone: 2.0e-4 m, verified)."""
    scene = contactqp.load_scene(Path(__file__).parent / "scenes"
                                 / "coupled_pair_many_small_forces.toml")
    result = solve_quietly(scene, "qp", {"backend": "qpsolvers", "solver": "clarabel",
                                         "accuracy": "high", "scale": False}, "strain")
    exact = reference(scene)
    error = float(np.abs(result.u - exact.displacement).max())
    assert error <= result.displacement_error_bound
    if result.verified:
        assert_within_bound(result, exact)



def test_an_open_contact_tied_across_a_stiff_element_sees_that_element():
    """A random scene (benchmarks/guarantee.py, seed 2026, scene 889): bar 0's node 4 touches
    bar 1's nodes 4 and 5 through two zero-gap bar contacts, and bar 1's element 4–5 is very
    stiff. Exactly, both contacts push (the second with 6178 N, carrying the load beyond the
    element). The penalty (ε = 1e14) leaves the second open and the stiff element carrying it
    on a stretch of its penetration; the open contact's stiffness, taken as its two ends in
    series (the soft one), passed it: verified, 2e-3 of F off. The end tied by the pushing
    contact is held: the check must flag it or the answer must be right."""
    scene = contactqp.load_scene(Path(__file__).parent / "scenes"
                                 / "zero_gap_contacts_across_a_stiff_element.toml")
    exact = reference(scene)
    # by hand: the two contacts tie nodes 4 and 5 of bar 1 together, so its element 4–5 does
    # not stretch and carries nothing: the second contact takes node 5's share of the
    # distributed load, q·h/2
    q, h = scene.distributed[0].intensity, scene.bars[1].lengths[-1]
    assert exact.contact_force[-1] == pytest.approx(q * h / 2, rel=1e-9)
    result = solve_quietly(scene, "penalty", {"penalty": 1e14}, "full")
    if result.verified:
        assert_within_bound(result, exact)
    else:
        assert abs(result.contact_force[-1] - exact.contact_force[-1]) > 1e-5 * (
            result.force_scale)  # flagged, and rightly


def checked_nearby(scene: contactqp.Scene, extra: tuple[contactqp.Load, ...]):
    """(the check, u, λ) of the exact answer of ``scene`` with the loads ``extra`` added (a
    nearby scene), read as an answer to ``scene`` itself (the reactions from equilibrium)."""
    nearby = reference(replace(scene, loads=scene.loads + extra))
    u, lam = np.array(nearby.displacement), np.array(nearby.contact_force)
    layout = layout_of(scene)
    reactions = support_reactions(layout, link_forces(layout, element_forces(layout, u)), lam)
    return contactqp.check(scene, u, lam, reactions, "inequality"), u, lam


@pytest.mark.parametrize("signs", list(itertools.product((1.0, -1.0), repeat=3)))
def test_a_wall_beside_a_pushing_contact_takes_the_errors_at_both_its_ends(signs):
    """A random scene (benchmarks/guarantee.py, seed 2026, scene 78): bar 1 is pushed onto a
    wall at its node 1 by a load of 5.3e5 N, and its node 2 pushes bar 0's node 4 through a
    bar contact, across a stiff element (6e11 N/m) from the wall. ECOS left about 1e-3 N of
    imbalance at the wall, beside each end of the contact and past them, and was verified
    5.3e-3 N off at the wall against a bound of 5.0e-3 N (twice the largest error at a held
    node): the contact's two ends move together, so what both ends are off goes on into the
    wall. The same by hand: small loads e beside each end of the contact and at the wall make
    a nearby scene, whose exact answer the check reads as an answer to this one; with every
    sign the same the wall is 3e off, the sum of the three (no single error is more than e)."""
    scene = contactqp.load_scene(Path(__file__).parent / "scenes"
                                 / "wall_beside_a_pushing_contact.toml")
    exact = reference(scene)
    assert np.all(exact.contact_force[[5, 8]] > 0.0)  # the wall and the contact push
    e = 1e-9 * contactqp.solve(scene).force_scale
    # past bar 0's end of the contact, past bar 1's end, and at the wall
    extra = tuple(contactqp.Load(node=node, force=sign * e, bar=bar)
                  for (bar, node), sign in zip(((0, 5), (1, 3), (1, 1)), signs))
    found, _, lam = checked_nearby(scene, extra)
    error = float(np.abs(lam - exact.contact_force).max())
    assert found.verified
    assert error <= found.force_error_bound
    if signs[0] == signs[1] == signs[2]:
        assert error == pytest.approx(3.0 * e, rel=1e-3)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_wall_beyond_two_pushing_contacts_takes_the_errors_at_all_their_ends(sign):
    """Three bars in a row, pushed onto a wall at the far end: bar 0 (soft, supported at its
    node 0) pushes bar 1 through a bar contact, bar 1 pushes bar 2 through another, and bar 2
    is stiff to the wall. Small loads e past each end of both contacts and at the wall make a
    nearby scene; its exact answer, read as an answer to this one, has every held node at
    most e off with the others fixed, but both contacts move and pass on what all four ends
    are off: the wall is 5e off, nearly all of it through the stiff bars (bar 0 is 10⁴ times
    softer). The bound must hold the sum over the group of bars the contacts join."""
    E = 2e11
    bars = (contactqp.Bar(lengths=np.array([1.0, 1.0, 0.1]),
                          areas=np.array([1e-6, 1e-6, 1e-2]), youngs_modulus=np.full(3, E)),
            contactqp.Bar(lengths=np.full(3, 0.1), areas=np.full(3, 1e-2),
                          youngs_modulus=np.full(3, E)),
            contactqp.Bar(lengths=np.full(2, 0.1), areas=np.full(2, 1e-2),
                          youngs_modulus=np.full(2, E)))
    loads = (contactqp.Load(node=2, force=1e5, bar=0), contactqp.Load(node=1, force=1e3, bar=1),
             contactqp.Load(node=1, force=1e3, bar=2))
    scene = contactqp.Scene(
        bars=bars, supports=(contactqp.Support(node=0, bar=0),), loads=loads,
        walls=(contactqp.Wall(node=2, gap=0.0, side="+", bar=2),),
        contacts=(contactqp.BarContact(bar_a=0, node_a=2, bar_b=1, node_b=1, gap=0.0),
                  contactqp.BarContact(bar_a=1, node_a=2, bar_b=2, node_b=1, gap=0.0)))
    exact = reference(scene)
    assert np.all(exact.contact_force > 0.0)
    e = 1e-9 * contactqp.solve(scene).force_scale
    # past bar 0's end of the first contact, before and past bar 1's ends, before bar 2's end
    # of the second, at the wall
    extra = tuple(contactqp.Load(node=node, force=sign * e, bar=bar)
                  for bar, node in ((0, 3), (1, 0), (1, 3), (2, 0), (2, 2)))
    found, _, lam = checked_nearby(scene, extra)
    error = np.abs(lam - exact.contact_force)
    assert found.verified
    assert error[0] == pytest.approx(5.0 * e, rel=1e-3)  # the wall
    assert error.max() <= found.force_error_bound


def test_a_group_of_contacts_moves_by_the_errors_at_all_their_ends():
    """Bar 0 (supported at both ends through soft elements) is pushed at its node 2 by bar 1
    and at its node 3 by bar 2 (each held by its own support through an element 10³ times
    softer still), through two bar contacts; bar 0's nodes 2 and 3 are joined by a stiff
    element, so the two contacts move as one. Loads e at all four contact ends, and −e beside
    each support so that no cut carries more than e: every held node is at most e off with
    the others fixed, but the group moves by what all four ends are off, twice what the
    displacement bound took from the largest error alone (a review's construction)."""
    E, soft, stiff = 2e11, 1e-6, 1e-2
    bars = (contactqp.Bar(lengths=np.array([0.1, 1.0, 0.1, 1.0, 0.1]),
                          areas=np.array([stiff, soft, stiff, soft, stiff]),
                          youngs_modulus=np.full(5, E)),
            contactqp.Bar(lengths=np.array([0.1, 1.0]), areas=np.array([stiff, soft * 1e-3]),
                          youngs_modulus=np.full(2, E)),
            contactqp.Bar(lengths=np.array([1.0, 0.1]), areas=np.array([soft * 1e-3, stiff]),
                          youngs_modulus=np.full(2, E)))
    loads = (contactqp.Load(node=2, force=1e3, bar=1), contactqp.Load(node=0, force=-1e3, bar=2),
             contactqp.Load(node=2, force=3e3, bar=0))
    scene = contactqp.Scene(
        bars=bars, loads=loads, walls=(),
        supports=(contactqp.Support(node=0, bar=0), contactqp.Support(node=5, bar=0),
                  contactqp.Support(node=0, bar=1), contactqp.Support(node=2, bar=2)),
        contacts=(contactqp.BarContact(bar_a=1, node_a=2, bar_b=0, node_b=2, gap=0.0),
                  contactqp.BarContact(bar_a=0, node_a=3, bar_b=2, node_b=0, gap=0.0)))
    exact = reference(scene)
    assert np.all(exact.contact_force > 0.0)
    e = 1e-9 * contactqp.solve(scene).force_scale
    extra = tuple(contactqp.Load(node=node, force=sign * e, bar=bar) for bar, node, sign in (
        (0, 1, -1), (0, 2, 1), (0, 3, 1), (0, 4, -1), (1, 1, -1), (1, 2, 1), (2, 0, 1), (2, 1, -1)))
    found, u, lam = checked_nearby(scene, extra)
    assert found.verified
    assert np.abs(u - exact.displacement).max() <= found.displacement_error_bound
    assert np.abs(lam - exact.contact_force).max() <= found.force_error_bound


def test_a_contact_left_past_its_gap_that_would_reroute_a_force_is_not_verified():
    # random_scene(seed 4246536, floating=0.6), a fresh draw of
    # test_bars_held_only_by_contact_are_within_their_bound: DAQP (through qpsolvers) left
    # the contact between bar 0's node 0 (held by wall 0) and bar 1's node 1 (held by wall 7)
    # 4.2e-7 m past with no force, and put its 3 601 N on wall 7 and wall 0; the exact answer
    # has the contact carrying it and wall 7 open by 4.2e-7 m. The same u to 4e-7 of U, 4 % of
    # F off, and verified with a force bound of 0.12 N: the gap moves keep every held node
    # held and see only the elastic part (contactqp.check.chain.self_stress.rerouted_forces). The same answer
    # made by hand from the exact one: bar 1 moved whole onto wall 7 (it is held at that node
    # alone), the contact's force sent round the loop of rows to the two walls
    scene = random_scene(np.random.default_rng(4246536), floating=0.6)
    layout = layout_of(scene)
    exact = reference(scene)
    u, lam = np.array(exact.displacement), np.array(exact.contact_force)
    reactions = support_reactions(layout, link_forces(layout, element_forces(layout, u)), lam)
    assert contactqp.check(scene, u, lam, reactions, "inequality").verified
    first, stop = layout.node_offsets[1], layout.node_offsets[2]
    u[first:stop] -= u[layout.node(1, 1)]  # wall 7 touching, the contact 4.2e-7 m past
    rerouted = lam[13]
    lam[13], lam[7], lam[0] = 0.0, lam[7] + rerouted, lam[0] + rerouted
    found = contactqp.check(scene, u, lam, reactions, "inequality")
    assert not found.verified
    assert found.force_error_bound >= rerouted  # the force it moved, within the bound


def test_daqps_answer_that_reroutes_a_force_is_flagged_or_within_its_bound():
    # the answer above as DAQP gives it, where DAQP is installed
    pytest.importorskip("daqp", reason="the qpsolvers backend DAQP (pip install daqp)")
    scene = random_scene(np.random.default_rng(4246536), floating=0.6)
    result = solve_quietly(scene, "qp", {"backend": "qpsolvers", "solver": "daqp"}, "full")
    if result.verified:
        assert_within_bound(result, reference(scene))
