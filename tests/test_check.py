"""The independent check (contactqp.check): hand-made right and wrong answers.

The scene is small enough to solve by hand. A cantilever of two 1 m elements, E = 200 GPa,
areas 1e-3 and 5e-4 m², so k_0 = 2e8 N/m and k_1 = 1e8 N/m, and the tip's compliance
f_2 = 1/k_0 + 1/k_1 = 1.5e-8 m/N. A "+" wall 0.15 mm beyond the tip (node 2), so g / f_2 = 1e4 N.

With F = 30 kN at the tip, the tip reaches the wall and λ = F − g/f_2 = 20 kN: both elements
carry F − λ = 10 kN, u = [0, 0.05, 0.15] mm, and the support pulls back with R = −10 kN.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import (
    HAND_GAP,
    default_compliance,
    hand_scene,
)
from contactqp import (
    TOLERANCES,
    Bar,
    BarContact,
    Load,
    Scene,
    Support,
    Tolerances,
    Wall,
    builders,
)
from contactqp.check.chain import section_residual
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

U_CONTACT = [0.0, 5e-5, 1.5e-4]  # m: 10 kN through k_0 = 2e8 N/m, then through k_1 = 1e8 N/m


def run_check(scene, u, contact_force, reactions, contact="inequality", **kwargs):
    return contactqp.check(scene, np.array(u, dtype=float), np.array(contact_force, dtype=float),
                           np.array(reactions, dtype=float), contact, **kwargs)


@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_hand_solution_is_verified(contact):
    found = run_check(hand_scene(), U_CONTACT, [2e4], [-1e4], contact)
    assert found.verified and found.physical
    assert found.message == ""
    # the hand numbers are decimal, not binary: a few ulp of round-off in every residual
    assert all(value <= 1e-12 for value in found.residuals.values() if value is not None)


def test_open_gap_with_no_force_is_verified():
    # 5 kN moves the tip by 5e3 · f_2 = 0.075 mm: half way to the wall
    found = run_check(hand_scene(force=5e3), [0.0, 2.5e-5, 7.5e-5], [0.0], [-5e3])
    assert found.verified and found.physical
    assert found.residuals["complementarity"] == 0.0  # λ = 0 exactly: nothing to multiply


def test_library_solution_of_the_hand_scene_is_the_hand_solution():
    result = contactqp.solve(hand_scene())
    # κ(K) ~ 10: a direct solve reproduces the hand numbers to a few ulp
    np.testing.assert_allclose(result.u, U_CONTACT, rtol=1e-12, atol=1e-12 * HAND_GAP)
    np.testing.assert_allclose(result.contact_force, [2e4], rtol=1e-12)  # as above
    np.testing.assert_allclose(result.reactions, [-1e4], rtol=1e-12)  # as above
    assert result.verified


def test_perturbed_displacement_fails_equilibrium():
    u = list(U_CONTACT)
    u[1] *= 1.001  # 0.05 µm more: the elements' forces change by k · 5e-8 m = 5 to 10 N
    found = run_check(hand_scene(), u, [2e4], [-1e4])
    assert not found.verified
    assert "equilibrium" in found.message
    assert "feasibility" not in found.message  # the tip did not move: still on the wall


def test_perturbation_within_a_loose_tolerance_is_accepted():
    u = list(U_CONTACT)
    u[1] *= 1.001  # about 10 N out of balance against a force scale of 30 kN: ~3e-4
    strict = run_check(hand_scene(), u, [2e4], [-1e4])
    # the imbalance moves node 1 by the 0.05 µm it was moved, 1.1e-4 of U = 0.45 mm (the
    # free tip displacement 30 kN · f_2), and the forces by tens of newtons
    assert strict.residuals["displacement"] == pytest.approx(5e-8 / 4.5e-4, rel=1e-6)
    assert not strict.verified and "displacement" in strict.message
    loose = Tolerances(equilibrium=1e-2, force=1e-2, displacement=1e-2)  # 30 times the above
    assert run_check(hand_scene(), u, [2e4], [-1e4], tolerances=loose).verified


def test_a_failure_names_the_tolerance_it_failed_as_given():
    # a user's tolerance printed with one digit (1.5e-7 as "2e-07") is not the tolerance the
    # residual failed: the message keeps three significant digits (the defaults read as before)
    u = list(U_CONTACT)
    u[1] *= 1.001  # the displacement residual is 1.1e-4 of U (the test above)
    strict = run_check(hand_scene(), u, [2e4], [-1e4])
    tolerance = 0.75 * strict.residuals["displacement"]
    tolerance = float(f"{tolerance:.2g}")  # e.g. 8.3e-05: two digits the old message lost
    assert f"{tolerance:.0e}" != f"{tolerance:.3g}"
    loose = Tolerances(equilibrium=1e-2, force=1e-2, displacement=tolerance)
    found = run_check(hand_scene(), u, [2e4], [-1e4], tolerances=loose)
    assert not found.verified
    assert f"displacement residual {strict.residuals['displacement']:.2e} > {tolerance:.3g}" in (
        found.message)


def test_wrong_sign_force_fails_sign_and_equilibrium():
    found = run_check(hand_scene(), U_CONTACT, [-2e4], [-1e4])
    assert not found.verified
    assert not found.physical
    assert "sign" in found.message
    assert "equilibrium" in found.message  # the flipped force no longer balances the load
    assert "pulls" in found.message


def test_pulling_wall_in_equilibrium_fails_only_sign():
    """F = 5 kN cannot reach the wall; holding the tip on it anyway takes λ = F − 1e4 = −5 kN:
    the same u and R as the contact answer, in perfect equilibrium, but the wall pulls."""
    scene = hand_scene(force=5e3)
    found = run_check(scene, U_CONTACT, [-5e3], [-1e4])
    assert not found.verified
    assert not found.physical
    assert found.message.startswith("sign residual")
    assert "equilibrium" not in found.message
    # sign residual = 5 kN pulled / force scale: the 5 kN load (from the scene alone, never
    # from the answer; an open gap is no force scale)
    assert found.residuals["sign"] == pytest.approx(5e3 / 5e3, rel=1e-12)  # a few ulp
    # equality contact allows the pull: verified, but not physical
    equality = run_check(scene, U_CONTACT, [-5e3], [-1e4], "equality")
    assert equality.verified
    assert not equality.physical
    assert "pulls" in equality.message


def test_penetrating_displacement_fails_feasibility():
    """The free answer, as if there were no wall: 30 kN through both elements."""
    u_free = [0.0, 1.5e-4, 4.5e-4]
    found = run_check(hand_scene(), u_free, [0.0], [-3e4])
    assert not found.verified
    assert "feasibility" in found.message
    assert "equilibrium" not in found.message  # it is in equilibrium, just past the wall
    # 0.3 mm past the wall, as the force it takes to push the tip back: 0.3 mm · s, s the
    # stiffness the tip sees with the support held, 1 / f_2 = 2e8/3 N/m: 20 kN of F = 30 kN
    assert found.residuals["feasibility"] == pytest.approx(2.0 / 3.0, rel=1e-12)  # a few ulp


def test_force_across_an_open_gap_fails_complementarity():
    """The contact answer checked against a wall 0.2 mm away: 20 kN pushed across 0.05 mm."""
    found = run_check(hand_scene(gap=2e-4), U_CONTACT, [2e4], [-1e4])
    assert not found.verified
    assert "complementarity" in found.message
    assert "feasibility" not in found.message and "equilibrium" not in found.message
    # min(λ, gap·s) / F = min(2e4, 5e-5 · s) / 3e4: F the 30 kN load, s the stiffness node 2
    # sees with the support held, 1 / (1/2e8 + 1/1e8) = 2e8/3 N/m, so gap·s = 10/3 kN and the
    # residual is 1/9; the 0.2 mm gap is not a scale
    assert found.residuals["complementarity"] == pytest.approx(1.0 / 9.0, rel=1e-12)  # ulps


def test_open_gap_fails_equality_feasibility():
    found = run_check(hand_scene(force=5e3), [0.0, 2.5e-5, 7.5e-5], [0.0], [-5e3], "equality")
    assert not found.verified
    assert "feasibility" in found.message
    assert found.residuals["complementarity"] is None and found.residuals["sign"] is None


@pytest.mark.parametrize("where", ["u", "contact_force", "reactions"])
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_nan_is_never_verified(where, contact):
    answer = {"u": list(U_CONTACT), "contact_force": [2e4], "reactions": [-1e4]}
    answer[where][-1] = math.nan
    found = run_check(hand_scene(), answer["u"], answer["contact_force"], answer["reactions"],
                      contact)
    assert not found.verified
    assert "not finite" in found.message


def test_nan_contact_force_is_not_called_physical():
    found = run_check(hand_scene(), U_CONTACT, [math.nan], [-1e4])
    assert not found.residuals["sign"] <= TOLERANCES.sign
    assert not found.physical
    assert "not finite" in found.message and "()" not in found.message


@settings(max_examples=200, deadline=None)
@given(st.integers(2, 12).flatmap(lambda n: st.tuples(
    st.just(n),
    st.lists(st.floats(-1e3, 1e3), min_size=n - 1, max_size=n - 1),
    st.lists(st.tuples(st.integers(0, n - 1), st.floats(-1e3, 1e3)), min_size=1, max_size=6))))
def test_section_residual_is_the_largest_cut(case):
    """Against the definition: cut j leaves nodes 0..j; residual N_j + Σ outside forces there
    (a dense cumulative sum here), and past the last node the whole bar's balance."""
    n, forces, outside = case
    nodes = np.array([node for node, _ in outside])
    values = np.array([value for _, value in outside])
    sections = np.cumsum(np.bincount(nodes, weights=values, minlength=n))
    sections[:-1] += forces
    expected = np.abs(sections).max()
    assert section_residual(np.array(forces), nodes, values) == pytest.approx(
        expected, rel=1e-12, abs=1e-9)


@pytest.mark.parametrize("times", [10.0, 1e3, 1e6])
def test_the_natural_map_residual_of_the_penalty_is_its_closed_form(times):
    """One wall, penalty ε = k·s (s = 1/f₄ the stiffness the tip sees): the penetration is
    λ/ε with λ = (u_free − g)/(f₄ + 1/ε), so the scaled LCP's natural-map residual,
    |min(λ√f₄, −p/√f₄)| / |(g − u_free)/√f₄| = p / (u_free − g), is 1/(1 + k); and it is the
    same in mm as in m (the rows are scaled to a unit diagonal)."""
    stiffness = 1.0 / default_compliance(4)
    result = contactqp.solve(None, "penalty", penalty=times * stiffness)
    assert result.residuals["natural_map"] == pytest.approx(1.0 / (1.0 + times), rel=1e-6)
    in_mm = contactqp.convert_units(contactqp.default_scene(), "mm-N-MPa")
    result_mm = contactqp.solve(in_mm, "penalty", penalty=times * stiffness / 1e3)  # N/mm
    assert result_mm.residuals["natural_map"] == pytest.approx(
        result.residuals["natural_map"], rel=1e-9)
    assert result.verified == (times >= 1e6)  # reported beside the check, not part of it


def test_the_natural_map_residual_is_round_off_for_exact_answers_and_none_for_equality():
    assert contactqp.solve().residuals["natural_map"] <= 1e-15
    assert contactqp.solve(hand_scene(), "lemke").residuals["natural_map"] <= 1e-15
    assert contactqp.solve(contact="equality").residuals["natural_map"] is None


def test_a_message_names_the_hardest_pulls_and_counts_the_rest():
    """Equality contact on an obstacle of 100 walls pulls at most of them: the message names
    the five that pull hardest, hardest first, and counts the others (at 10⁴ walls it once
    listed every one, 224 kB)."""
    from contactqp.builders import obstacle

    result = contactqp.solve(obstacle(100), "lagrange", "equality")
    lam = result.contact_force
    pulling = np.flatnonzero(lam < 0)
    assert pulling.size > 5 and not result.physical
    hardest = pulling[np.argsort(lam[pulling], kind="stable")][:5]
    listed = ", ".join(f"wall[{i}] {lam[i]:.6g} N" for i in hardest)
    assert f"a contact pulls ({listed} and {pulling.size - 5} more)" in result.message


def test_a_force_carried_round_a_loop_of_rows_is_not_verified():
    """Node 2 of bar 0 (supported at node 0, F at node 2) against a wall at zero gap, and by a
    bar contact 1e-16 m open onto bar 1's node 0, itself 1e-16 m from a second wall: two ways
    from the node to the ground. The exact answer (statics: the nearer wall, zero gap, takes
    all of F; the reference agrees) leaves the other way open. An answer that sends 0.4 F the
    long way round, with every gap closed to 2e-16 m, balances every node and meets every
    residual but the force bound, which must count the force round the loop: the check once
    verified it with a bound of 1.2e-8 N (found as ProxQP's 15 N round such a loop on a
    random scene, seed 139)."""
    F, c, gap = 1e3, 400.0, 1e-16
    scene = Scene((Bar.from_areas([1e-4, 1e-4], 2e11, length=0.5),
                   Bar.from_areas([1e-4], 2e11, length=0.5)),
                  (Support(0, 0), Support(1, 1)), (Load(2, F, 0),),
                  (Wall(2, 0.0, "+", 0), Wall(0, gap, "+", 1)),
                  contacts=(BarContact(0, 2, 1, 0, gap),))
    from contactqp.reference import reference

    assert reference(scene).contact_force.tolist() == [F, 0.0, 0.0]
    found = contactqp.check(scene, np.zeros(5), [F - c, c, c], np.zeros(2), "inequality")
    assert not found.verified
    assert found.force_error_bound >= c


@pytest.mark.parametrize("builder", ["random", "flat_patch", "channel"])
def test_the_check_writes_into_none_of_its_inputs(builder):
    # the check works in place in its own arrays (every array over the chain costs pages);
    # the answer it is given, read-only here, must come out as it went in, and the verdict
    # be the same as for writable copies
    if builder == "random":
        scenes = [random_scene(np.random.default_rng(seed), contacts=bool(seed % 2))
                  for seed in range(12)]
    else:
        scenes = [getattr(builders, builder)(300)]
    for scene in scenes:
        result = contactqp.solve(scene)
        inputs = [np.array(result.u), np.array(result.contact_force),
                  np.array(result.reactions)]
        frozen = [a.copy() for a in inputs]
        for a in frozen:
            a.flags.writeable = False
        found = contactqp.check(scene, *frozen, "inequality")
        for before, after in zip(inputs, frozen):
            np.testing.assert_array_equal(before, after)
        again = contactqp.check(scene, *inputs, "inequality")
        assert (found.verified, found.residuals) == (again.verified, again.residuals)
        assert found.verified == result.verified


@pytest.mark.parametrize("front", ["scene", "problem"])
def test_a_tiny_pull_through_a_soft_row_counts_as_the_move_it_makes(front):
    """tests/scenes/a_touching_wall_on_a_soft_unloaded_bar.toml: bar 0 carries no load, so its
    exact displacement is 0; an answer that puts its free nodes on the wall beside node 2
    (5.9e-12 m away) balances only with a pull of 9.6e-7 N there (1e-10 F), which the
    general certificate once accepted as round-off: the bound said 4.5e-9 U where the answer is
    1.6e-4 U off. The bound must cover the error, so the answer is not verified."""
    path = Path(__file__).parent / "scenes" / "a_touching_wall_on_a_soft_unloaded_bar.toml"
    scene = contactqp.load_scene(path)
    exact = reference(scene)
    u = exact.displacement.copy()
    u[1:4] = -scene.walls[0].gap  # bar 0's free nodes (its node 0 is supported) on the wall
    target = scene if front == "scene" else contactqp.problem_from_scene(scene)
    found = contactqp.check(target, u, exact.contact_force)
    error = float(np.abs(u - exact.displacement).max())
    assert error == pytest.approx(scene.walls[0].gap)  # by construction
    assert found.displacement_error_bound >= error * (1 - 1e-6)
    assert not found.verified


def test_a_wrong_answer_on_many_rows_is_refused_after_a_few_rows_own_stiffness(monkeypatch):
    """Each row's own stiffness s = 1/W_ii is a solve on a user's model; an answer past its
    tolerance on many rows is refused once one row is past it with its own s, the others
    keeping their bounds s̄ ≥ s. Springs in parallel, K = diag(k), one row u_i >= g_i per dof
    (c_i = −1, g_i = −0.01): s_i = k_i exactly (W_ii = 1/k_i), so the answer u = 0, λ = 0
    passes every row by 0.01 and its feasibility residual is max k_i · 0.01 / F (closed form,
    F = ‖f‖∞ here: no support). The verdict and that residual are those of reading every row,
    but from the first FIRST_ROWS rows only (4 here, of 40); without the limits every row's
    own s is read. Before, the check of a peer's answer at 10⁴ rows ran for minutes."""
    import importlib

    import scipy.sparse as sp

    from contactqp.model.sparse import problem_model

    residuals_module = importlib.import_module("contactqp.check.residuals")

    rng = np.random.default_rng(3)
    n = 40
    k = rng.uniform(1.0, 5.0, n)
    f = rng.uniform(0.5, 1.0, n)  # pushes every dof away from its row: no contact force
    problem = contactqp.Problem(sp.diags_array(k).tocsr(), f,
                                sp.csr_array(-sp.eye_array(n)), np.full(n, -0.01))
    monkeypatch.setattr(residuals_module, "FIRST_ROWS", 4)
    model = problem_model(problem)
    asked = []
    seen = type(model).seen_stiffness
    monkeypatch.setattr(type(model), "seen_stiffness",
                        lambda self, rows: asked.append(rows.size) or seen(self, rows))
    found = contactqp.check(model, np.zeros(n), np.zeros(n))
    assert not found.verified
    # the residuals' read; the on-set certificate's reference pulls on every row by more
    # than its ACCEPT of F, so it lets them go with no row's own s
    assert asked == [4]
    assert found.residuals["feasibility"] == pytest.approx(
        (k * 0.01).max() / np.abs(f).max(), rel=1e-12)
    asked.clear()
    residuals_module.residuals(model, np.zeros(n), np.zeros(n), np.zeros(n, dtype=bool))
    assert asked == [n]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), equalities=st.integers(0, 3))
def test_the_force_residuals_are_their_definitions_row_by_row(seed, equalities):
    """Springs in parallel, K = diag(k), one row per dof (c_i = ±1): each row's own stiffness is
    s_i = k_i, and so is its bound s̄_i, so the feasibility, complementarity and sign residuals
    are their definitions, worked out here row by row in plain Python: max p⁺·k (|p|·k on an
    equality row), max min(λ⁺, (−p)⁺·k) and max λ⁻ over the inequality rows, each over F. The
    answers are random (rows past their gaps, open with a force, pulling; each by 0.1 to
    1e-14 of F), with or without equality rows (the residuals read the rows with masks
    there, in one pass without)."""
    import importlib

    import scipy.sparse as sp

    from contactqp.model.sparse import problem_model

    residuals_module = importlib.import_module("contactqp.check.residuals")
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    k = rng.uniform(0.5, 5.0, n) * 10.0 ** rng.integers(-3, 4)
    sign = rng.choice([-1.0, 1.0], n)
    problem = contactqp.Problem(sp.diags_array(k).tocsr(), rng.normal(size=n),
                                sp.csr_array(sp.diags_array(sign)), rng.normal(size=n) * 1e-2)
    model = problem_model(problem)
    equality = np.zeros(n, dtype=bool)
    equality[rng.permutation(n)[:equalities]] = True
    F = model.force_scale
    # residuals from 0.1·F down to 1e-14·F: below SIGNIFICANT = 1e-9 of F the rows are read
    # once, above it again with each row's own s
    size = F * 10.0 ** -rng.uniform(1, 14)
    p = list(rng.normal(size=n) * size / k)  # the penetration, as a force ~ size
    u = sign * (np.array(p) + problem.g)  # C u − g = p (sign² = 1)
    p = [sign[i] * u[i] - problem.g[i] for i in range(n)]  # as rounded
    lam = rng.normal(size=n) * size
    lam[rng.random(n) < 0.3] = 0.0
    found, pen = residuals_module.residuals(model, u, lam, equality)
    passed = [abs(p[i]) * k[i] if equality[i] else max(p[i], 0.0) * k[i] for i in range(n)]
    both = [min(max(lam[i], 0.0), max(-p[i], 0.0) * k[i]) for i in range(n) if not equality[i]]
    pulls = [max(-lam[i], 0.0) for i in range(n) if not equality[i]]
    np.testing.assert_allclose(pen, p, rtol=0, atol=1e-15)
    assert found["feasibility"] == pytest.approx(max(passed) / F, rel=1e-12)
    if equality.all():
        assert found["complementarity"] is None and found["sign"] is None
    else:
        assert found["complementarity"] == pytest.approx(max(both + [0.0]) / F, rel=1e-12,
                                                         abs=1e-300)
        assert found["sign"] == pytest.approx(max(pulls + [0.0]) / F, rel=1e-12, abs=1e-300)


def test_a_row_an_exact_answer_leaves_touching_with_no_force_costs_the_check_no_set():
    """Springs in parallel, K = diag(k), one row u_i <= g_i per dof (C = I), in numbers exact
    in binary: the free displacement f/k is 0.5 at dofs 0 and 1, on their gaps (touching, no
    force), past the gaps of dofs 2, 4 and 5 (forces f − k g = 0.5, 2, 2) and short of dof 3's.
    lagrange's answer is that exact answer, and its check solves one set, the pushing rows:
    the touching rows with exactly no force start outside it (on the rows mesh, one such row
    cost the check a set of its own, 0.52 s of 3.3 s). An answer that gives a row that must
    push exactly no force, on its gap, has that row enter the check's set and its force
    counted."""
    import scipy.sparse as sp

    from contactqp.model.sparse import problem_model

    k = np.array([2.0, 2.0, 2.0, 4.0, 4.0, 4.0])
    f = np.array([1.0, 1.0, 1.0, 4.0, 4.0, 4.0])
    g = np.array([0.5, 0.5, 0.25, 2.0, 0.5, 0.5])
    exact_u = np.minimum(f / k, g)
    exact_force = f - k * exact_u
    assert exact_u.tolist() == [0.5, 0.5, 0.25, 1.0, 0.5, 0.5]
    assert exact_force.tolist() == [0.0, 0.0, 0.5, 0.0, 2.0, 2.0]
    problem = contactqp.Problem(sp.diags_array(k).tocsr(), f, sp.eye_array(6, format="csr"), g)
    result = contactqp.solve(problem, method="lagrange")
    np.testing.assert_allclose(result.u, exact_u, rtol=0, atol=1e-15)
    np.testing.assert_allclose(result.contact_force, exact_force, rtol=0, atol=1e-15)
    assert result.contact_force[:2].tolist() == [0.0, 0.0]

    model = problem_model(problem)
    held = []
    solve_on = type(model).on_set

    def counted(self, active):
        held.append(np.flatnonzero(active).tolist())
        return solve_on(self, active)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(type(model), "on_set", counted)
        found = contactqp.check(model, result.u, result.contact_force)
        assert found.verified
        assert held == [[2, 4, 5]]

        held.clear()
        forged = exact_force.copy()
        forged[2] = 0.0  # row 2 on its gap with no force: dof 2 out of balance by 0.5
        found = contactqp.check(model, exact_u, forged)
        assert not found.verified
        assert found.force_error_bound >= 0.5
        assert held[0] == [4, 5] and 2 in held[-1]


@pytest.mark.parametrize("front", ["scene", "problem"])
def test_an_answer_out_of_balance_has_a_bound_that_covers_its_error(front):
    """The flat patch's exact answer (every node on its wall) with the largest contact force
    set to 0: u is exact, so the answer is off by that force alone, on that row. It is out of
    balance there and not verified, and its force bound must still cover the error. The
    chain's certificate holds to first order within the answer's own set of pushing rows,
    which this answer leaves: it said 51 316 N for an error of 1e5 N, and it was the bound
    given."""
    scene = builders.flat_patch(20)
    exact = reference(scene)
    lam = exact.contact_force.copy()
    row = int(np.argmax(lam))
    lam[row] = 0.0
    target = scene if front == "scene" else contactqp.problem_from_scene(scene)
    found = contactqp.check(target, exact.displacement, lam)
    assert not found.verified
    assert found.force_error_bound >= exact.contact_force[row] * (1 - 1e-9)
