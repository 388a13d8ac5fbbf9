"""The hull active set (contactqp.methods.hull) inside lagrange: right on random obstacles
against the exact reference, the same answer as the textbook loop, and a step count that does
not grow with the mesh."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import imported_by
from contactqp import Bar, DistributedLoad, Load, Scene, SceneError, Support, Wall
from contactqp.methods.hull import minorant
from contactqp.methods.hull.minorant import minorant_slopes, minorant_vertices
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

GOAL = 1e-8  # the accuracy goal: forces within 1e-8 of the largest


# --- the minorant against a brute force in exact integer arithmetic: a point is a vertex of
# the greatest convex minorant when no chord between two other points passes through or below it
def brute_vertices(x: list[int], y: list[int], clip: int) -> set[int]:
    xs, ys = list(x), list(y)
    far = 10**9 * (x[-1] - x[0] + 1)
    if clip < 0:  # a free end on the right: a far point level with the lowest
        xs.append(x[-1] + far)
        ys.append(min(y))
    if clip > 0:
        xs.insert(0, x[0] - far)
        ys.insert(0, min(y))
    shift = 1 if clip > 0 else 0
    vertices = set()
    for i in range(len(x)):
        j = i + shift
        covered = any(
            (ys[j] - ys[a]) * (xs[b] - xs[a]) >= (ys[b] - ys[a]) * (xs[j] - xs[a])
            for a, b in itertools.combinations(range(len(xs)), 2)
            if a != j and b != j and xs[a] < xs[j] < xs[b])
        if not covered:
            vertices.add(i)
    return vertices


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 4), st.integers(-20, 20)), min_size=3, max_size=12),
       st.sampled_from([-1, 0, 1]))
def test_minorant_vertices_are_the_convex_hull(points, clip):
    x = list(itertools.accumulate(step for step, _ in points))
    y = [value for _, value in points]
    if clip <= 0:
        y[0] = 0  # a held left end
    if clip >= 0:
        y[-1] = 0  # a held right end
    found = set(minorant_vertices(np.array(x, float), np.array(y, float), clip).tolist())
    expected = brute_vertices(x, y, clip)
    for end, held in ((0, clip <= 0), (len(y) - 1, clip >= 0)):
        if held:  # a held end is no wall to add (the caller drops it)
            found.discard(end)
            expected.discard(end)
    assert found == expected


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 400))
def test_minorant_slopes_are_the_slopes_isotonic_regression(seed, n):
    # scipy's pooling of adjacent violators is the independent computation: the minorant's
    # slopes are the isotonic regression of the steps' slopes, weighted by the steps of x
    from scipy.optimize import isotonic_regression

    rng = np.random.default_rng(seed)
    x = np.cumsum(10.0 ** rng.uniform(-3.0, 1.0, n))
    y = rng.normal(size=n) * 10.0 ** rng.uniform(-5.0, 5.0)
    if rng.random() < 0.5:  # a smooth bowl with noise: most points are vertices
        y = (x - x.mean()) ** 2 + rng.normal(size=n) * 1e-2 * rng.random()
    dx = np.diff(x)
    expected = isotonic_regression(np.diff(y) / dx, weights=dx, increasing=True).x
    found = minorant_slopes(x, y)
    scale = np.abs(np.diff(y) / dx).max()
    np.testing.assert_allclose(found, expected, rtol=0.0, atol=1e-12 * scale)
    assert np.array_equal(np.flatnonzero(found[1:] != found[:-1]),
                          np.flatnonzero(expected[1:] != expected[:-1]))


def test_minorant_slopes_hand_a_lopsided_hull_to_scipy(monkeypatch):
    # every point of a convex curve is a vertex and takes log2(200) ~ 8 levels; allowed 2,
    # the scipy fallback finishes and gives the same slopes
    x = np.linspace(0.0, 1.0, 200)
    y = np.exp(8.0 * x)
    full = minorant_slopes(x, y)
    monkeypatch.setattr(minorant, "HULL_LEVELS", 2)
    monkeypatch.setattr(minorant, "PRUNING_PASSES", 0)
    np.testing.assert_allclose(minorant_slopes(x, y), full, rtol=1e-12)


def test_a_first_solve_with_passed_walls_does_not_import_scipy_optimize():
    # importing scipy.optimize costs 0.2-0.3 s on the first solve of a process: the hull's
    # minorant does without it (a fresh process, as a user's script starts)
    code = ("import contactqp\nfrom contactqp.builders import channel\n"
            "result = contactqp.solve(channel(2000))\n"
            "assert result.verified and result.info['active_set'] == 'hull'")
    assert imported_by(code, ("scipy.optimize",)) == []


# --- random obstacles, one bar: every kind the issue names, against the exact reference
@st.composite
def obstacle_scenes(draw):
    n = draw(st.integers(4, 60))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    stiffness = 10.0 ** rng.uniform(5.0, 5.0 + draw(st.sampled_from([0.0, 2.0, 5.0])), n)
    bar = Bar.from_areas(stiffness / 2e11, 2e11, lengths=np.ones(n))
    supports = {0} if rng.random() < 0.6 else {int(rng.integers(0, n + 1))}
    if rng.random() < 0.3:
        supports.add(int(rng.integers(0, n + 1)))
    free = [i for i in range(n + 1) if i not in supports]
    loads = tuple(Load(int(rng.choice(free)), float(rng.choice([-1, 1]) * 10 ** rng.uniform(3, 6)))
                  for _ in range(int(rng.integers(0, 3))))
    distributed = ((DistributedLoad(float(rng.choice([-1, 1]) * 10 ** rng.uniform(3, 6))),)
                   if rng.random() < 0.4 or not loads else ())
    scene = Scene(bar, tuple(Support(i) for i in sorted(supports)), loads,
                  distributed=distributed)
    u_free = contactqp.solve(scene).u
    scale = max(np.abs(u_free).max(), 1e-12)
    x = np.linspace(0.0, 1.0, n + 1)
    kind = draw(st.sampled_from(["one-sided", "channel", "flat", "touching"]))
    shape = scale * (rng.uniform(-0.5, 0.5) * x**2 + rng.uniform(0, 0.3) * np.abs(
        np.sin(rng.uniform(5, 40) * x)))
    walls = []
    for i in free:
        if kind == "touching":  # every node exactly on a wall where the loads leave it
            side = "+" if u_free[i] >= 0 else "-"
            walls.append(Wall(i, abs(u_free[i]) * float(rng.choice([0.5, 1.0, 1.0])), side))
        elif kind == "flat":
            walls.append(Wall(i, 0.2 * scale, "+" if u_free[i] >= 0 else "-"))  # where it goes
        else:
            walls.append(Wall(i, float(shape[i] + 0.1 * scale), "+"))
            if kind == "channel":
                walls.append(Wall(i, float(0.1 * scale - shape[i] + 0.02 * scale), "-"))
    return Scene(bar, scene.supports, loads, tuple(walls), distributed=distributed)


@settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
@given(obstacle_scenes())
def test_random_obstacles_match_the_exact_reference(scene):
    exact = reference(scene)
    result = contactqp.solve(scene, "lagrange", formulation="full")
    # the hull settles every obstacle by itself, except where walls touch with no force (the
    # exact answer neither presses nor leaves them, and round-off picks either): there its set
    # may come back, and the passed loop finishes from it (hypothesis: walls at zero gap on the
    # unloaded span between two supports, u = 0 there to 3.5e-11 of U = 7 m)
    touching = (exact.contact_force == 0.0) & (
        np.abs(result.penetration) <= 1e-9 * result.displacement_scale)
    assert result.info.get("active_set") == "hull" or (
        touching.any() and result.info["active_set"].startswith("hull, then passed"))
    largest = max(np.abs(exact.contact_force).max(), 1e-300)
    # the goal, plus round-off: a touching wall's exact force is 0, and both answers carry
    # ~1e-13 F there. A backward-stable float64 solve is off by about eps·κ(K)·F, and κ(K) is
    # at least the spread of the element stiffnesses: hypothesis found bars whose areas span
    # 4.8 decades (6.1e4) where a wall touching to the last bit of its gap carries 6.4e-8 N of
    # F = 1.4e4 N exactly (4.6e-12 F) and 0 in float64; 10 eps per unit of spread covers it.
    k = scene.bars[0].youngs_modulus * scene.bars[0].areas / scene.bars[0].lengths
    round_off = max(1e-12, 1e-15 * k.max() / k.min()) * result.force_scale
    assert np.abs(result.contact_force - exact.contact_force).max() <= (
        GOAL * largest + round_off)
    assert np.abs(result.u - exact.displacement).max() <= 1e-9 * result.displacement_scale
    assert result.verified, result.message


@pytest.mark.parametrize("seed", range(40))
def test_several_bars_with_walls_match_the_textbook_loop_and_the_reference(seed):
    rng = np.random.default_rng(seed)
    try:
        scene = random_scene(rng, contacts=False)
    except SceneError:
        pytest.skip("no valid scene drawn")
    hull = contactqp.solve(scene, "lagrange", formulation="full")
    passed = contactqp.solve(scene, "lagrange", formulation="full", active_set="passed")
    exact = reference(scene)
    for result in (hull, passed):
        assert np.abs(result.contact_force - exact.contact_force).max(initial=0.0) <= (
            result.force_error_bound + 1e-12 * result.force_scale)
    assert np.abs(hull.contact_force - passed.contact_force).max(initial=0.0) <= (
        hull.force_error_bound + passed.force_error_bound + 1e-12 * hull.force_scale)


# --- the step count on refinement sequences: flat, not growing with the mesh
@pytest.mark.parametrize("build", [contactqp.obstacle, contactqp.channel, contactqp.flat_patch])
def test_steps_do_not_grow_with_the_mesh(build):
    """10³, 10⁴, 10⁵ contacts: the textbook loop needs 6 → 151 steps on the obstacle and
    44 → 4 239 on the flat patch (issue 14); the hull at most a step more per tenfold and
    never more than 8 (measured: 2 on each, at each size; the channel took 6–7 when a step
    settled one side only)."""
    steps = []
    for n in (10**3, 10**4, 10**5):
        result = contactqp.solve(build(n), "lagrange")
        assert result.verified
        assert result.info.get("active_set") == "hull"
        steps.append(result.iterations)
    assert max(steps) <= 8
    assert all(b <= a + 1 for a, b in itertools.pairwise(steps))


def test_the_textbook_loop_needs_more_steps_on_a_patch():
    """What the hull saves, on the same scene: the textbook loop adds every passed wall, and
    its set crosses the patch a few nodes per step."""
    scene = contactqp.flat_patch(1000)
    hull, passed = (contactqp.solve(scene, "lagrange", formulation="full", active_set=a)
                    for a in ("hull", "passed"))
    assert passed.iterations >= 10 * hull.iterations
    assert np.abs(hull.contact_force - passed.contact_force).max(initial=0.0) <= (
        hull.force_error_bound + passed.force_error_bound)


def test_a_patch_against_statics():
    """A uniform load q on a uniform bar fixed at node 0, a flat + wall g from every node. If
    nodes c..n touch (u = g) and 1..c−1 do not, statics gives everything: elements before c
    carry N_e = N_0 − S_e (S_e the nodal loads on nodes 1..e), compatibility
    Σ_(e<c) N_e / k = g fixes N_0, node c's wall takes p_c − N_(c−1) and every later wall its
    own nodal load p_j. The answer is the c for which the free nodes stay off their walls and
    every wall pushes; computed here, not by the library."""
    n, q, E, A, L = 40, 1e5, 2e11, 1e-4, 1.0
    h = L / n
    k = E * A / h
    bar = Bar.from_areas(np.full(n, A), E, lengths=np.full(n, h))
    g = 0.6 * q * L**2 / (2 * E * A)  # 0.6 of the free tip's displacement
    scene = contactqp.wall_at_every_node(
        Scene(bar, (Support(0),), (), distributed=(DistributedLoad(q),)), g)
    p = np.full(n + 1, q * h)
    p[-1] = q * h / 2
    answers = []
    for c in range(1, n + 1):
        S = np.concatenate(([0.0], np.cumsum(p[1:c])))  # S_e for e = 0..c-1
        N0 = (g * k + S.sum()) / c
        N = N0 - S
        u = np.concatenate(([0.0], np.cumsum(N / k)))  # u_0..u_c
        forces = p.copy()
        forces[:c] = 0.0
        forces[c] = p[c] - N[-1]
        if (u[1:c] <= g).all() and (forces >= 0.0).all():
            answers.append(forces[1:])
    assert len(answers) == 1  # one c fits: the exact answer is unique
    result = contactqp.solve(scene, "lagrange", formulation="full")
    assert result.info.get("active_set") == "hull"
    assert np.abs(result.contact_force - answers[0]).max() <= 1e-9 * q * L
    assert result.verified


def test_the_option_is_checked():
    with pytest.raises(contactqp.OptionError, match="active_set"):
        contactqp.solve(contactqp.default_scene(), "lagrange", active_set="greedy")


def test_auto_condenses_a_long_bar_with_few_contacts_and_nothing_else():
    """formulation="auto": a 2048-element bar with one wall condensed for the methods that
    gain by it, and kept on the full chain for Lagrange (its hull active set), for the default
    scene (4 elements: condensing costs more than it saves) and for a wall at every node;
    the same answer as either formulation named."""
    long_bar = contactqp.Scene(
        contactqp.Bar.tapered_circle(1.0, 2048, 0.040, 0.020, 210e9),
        (contactqp.Support(0),), (contactqp.Load(1024, 565486.67),),
        (contactqp.Wall(2048, 1e-4),))
    for method in ("augmented", "penalty", "qp"):
        auto = contactqp.solve(long_bar, method)
        assert auto.options.get("formulation") == "condensed", method
        full = contactqp.solve(long_bar, method, formulation="full")
        assert abs(auto.contact_force[0] - full.contact_force[0]) <= (
            auto.force_error_bound + full.force_error_bound), method
    lagrange = contactqp.solve(long_bar)
    assert "formulation" not in lagrange.options and lagrange.info.get("active_set") == "hull"
    assert lagrange.options == contactqp.solve(long_bar, formulation="full").options
    for method in ("lagrange", "augmented", "penalty", "qp"):
        assert "formulation" not in contactqp.solve(contactqp.default_scene(), method).options
    many = contactqp.solve(contactqp.obstacle(1000), "augmented")
    assert "formulation" not in many.options


@pytest.mark.parametrize("seed", [21, 22, 23])
def test_the_hull_hands_every_node_its_u_as_placing_u_free_would(seed, monkeypatch):
    # the hull's Solution carries u over every node, which the Result takes as it is: it
    # must be what placing u_free among the supports gives, bit for bit (+0.0 at a support),
    # and the Result's own array, not one the next solve reuses
    from contactqp import result as result_module

    rng = np.random.default_rng(seed)
    scenes = [random_scene(rng, max_elements=60) for _ in range(12)]
    scenes.append(contactqp.default_scene())
    taken = 0
    real = result_module.checked

    def placing(model, solution, *args, **kwargs):
        return real(model, dataclasses.replace(solution, u_nodes=None), *args, **kwargs)

    for scene in scenes:
        first = contactqp.solve(scene, "lagrange")
        if first.info.get("active_set") != "hull":
            continue
        model = first.model
        placed = np.zeros(model.layout.n_nodes)
        placed[model.free] = first.u[model.free]
        assert np.array_equal(first.u, placed)
        assert not np.signbit(first.u[model.layout.support_nodes]).any()
        kept = first.u.copy()
        first.u[:] = np.nan  # a user writing into one Result's u
        again = contactqp.solve(scene, "lagrange")
        assert np.array_equal(again.u, kept)
        with monkeypatch.context() as patched:  # the Result without the hull's u
            patched.setattr(result_module, "checked", placing)
            placed_again = contactqp.solve(scene, "lagrange")
        assert np.array_equal(placed_again.u, kept)
        assert (placed_again.force_error_bound, placed_again.displacement_error_bound) == (
            again.force_error_bound, again.displacement_error_bound)
        taken += 1
    assert taken >= 5
