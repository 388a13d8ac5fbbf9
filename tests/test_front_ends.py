"""One meaning of ``verified`` on both front ends: the same answer, checked against a scene and
against the problem the scene compiles to (:func:`contactqp.problem_from_scene`), gets the
same residuals and the same verdict.

The scene's check reads the chain's own certificate first and keeps the smaller of its bound
and the general one (contactqp.check), so it may verify an answer the general certificate
cannot bound (it never refuses one the general certificate verifies); measured on 5 800
answers of random scenes by every method, the two verdicts differed once (a floating scene, a
qp answer). Expected values: the residuals are computed twice by different code paths (the
chain's numbering against the sparse model), and an answer verified by either check is held
to the exact reference (contactqp.reference, an enumeration of contact sets in exact KKT
solves), which calls neither check.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import contactqp
from contactqp.model import contact_forces_on_nodes
from contactqp.random_scenes import random_scene
from contactqp.reference import reference
from test_guarantee import assert_within_bound

RUNS = [("lagrange", {}), ("penalty", {}), ("augmented", {}), ("lemke", {}), ("pgs", {}),
        ("semismooth_newton", {}), ("qp", {})]
# residuals are relative to F or U, which both front ends compute from the same numbers
# in a different order: measured agreement ~1e-9 of the scale, 1.3e-8 on a floating scene
# (u₀ = K⁺(P − Cᵀμ) through the free modes; seed 2990572167)
SAME = 1e-8
SAME_SCALE = 1e-6


def solved(target, method, options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return contactqp.solve(target, method, **options)
        except contactqp.ContactqpError:  # refused alike on both (asserted below)
            return None


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1), st.sampled_from([0.0, 0.5]))
# fresh seeds that failed once: all gaps 0 (a crash in the rows' check), nothing loaded but a
# support (U by the model's size), a floating bar of stiffness contrast 1e7 (its free mode), a
# one-element floating bar whose free mode four inverse iterations did not resolve (SuperLU's
# zero pivot then, a RuntimeError)
@example(75063, 0.0)
@example(146, 0.0)
@example(704183, 0.5)
@example(1382, 0.5)
def test_the_same_answer_gets_the_same_verdict_from_a_scene_and_its_problem(seed, floating):
    rng = np.random.default_rng(seed)
    scene = random_scene(rng, floating=floating)
    try:
        problem = contactqp.problem_from_scene(scene)
    except contactqp.ContactqpError:
        return
    try:
        exact = reference(scene)
    except contactqp.SceneError:  # too many rows for the exact enumeration: no reference
        return
    for method, options in RUNS:
        result = solved(scene, method, options)
        if result is None or not np.all(np.isfinite(result.u)):
            continue
        context = f"seed {seed}, floating {floating}, {method}"
        as_scene = contactqp.check(scene, result.u, result.contact_force)
        as_problem = contactqp.check(problem, result.u, result.contact_force)
        assert as_scene.force_scale == pytest.approx(as_problem.force_scale,
                                                     rel=SAME_SCALE), context
        assert as_scene.displacement_scale == pytest.approx(as_problem.displacement_scale,
                                                            rel=SAME_SCALE), context
        for name in ("equilibrium", "feasibility", "complementarity", "sign"):
            a, b = as_scene.residuals[name], as_problem.residuals[name]
            assert (a is None) == (b is None), (name, context)
            if a is not None:
                assert abs(a - b) <= SAME + 1e-6 * max(a, b), (name, a, b, context)
        # never looser: what the general certificate verifies, the chain's does too
        if as_problem.verified:
            assert as_scene.verified, context
        if as_scene.verified:  # and what either verifies is right (row by row, or on Cᵀλ
            assert_within_bound(result, exact)  # where rows repeat a constraint)


@pytest.mark.parametrize("method", [name for name, _ in RUNS])
def test_the_default_scene_and_its_problem_solve_alike(method):
    """The course problem both ways: the same contact force (the closed form's, to the
    guarantee) and both verified."""
    scene = contactqp.default_scene()
    problem = contactqp.problem_from_scene(scene)
    a, b = solved(scene, method, {}), solved(problem, method, {})
    assert a.verified and b.verified
    F = a.force_scale
    exact = reference(scene).contact_force
    assert np.abs(a.contact_force - exact).max() <= contactqp.GUARANTEE[0] * F
    assert np.abs(b.contact_force - exact).max() <= contactqp.GUARANTEE[0] * F


ROOT = Path(__file__).parent.parent
# every scene file but those with a frictional bed (friction: tests/test_bed_scene.py)
SCENE_FILES = sorted(path for path in [*(ROOT / "examples").glob("*.toml"),
                                       *(ROOT / "tests" / "scenes").glob("*.toml")]
                     if "[[bed]]" not in path.read_text(encoding="utf-8"))


@pytest.fixture(scope="module", params=SCENE_FILES, ids=[p.stem for p in SCENE_FILES])
def scene_and_exact(request):
    scene = contactqp.load_scene(request.param)
    return scene, reference(scene)


@pytest.mark.parametrize("front", ["scene", "problem"])
@pytest.mark.parametrize("method", [name for name, _ in RUNS])
def test_every_method_on_both_front_ends(scene_and_exact, method, front):
    """One problem set through every method, as qpsolvers runs one set through every solver:
    the example scenes and the scenes that once made a method fail (tests/scenes), each as a
    scene and as the problem it compiles to. Where either front end verifies an answer, it is
    within its bound of the exact reference; the two front ends' answers check alike."""
    scene, exact = scene_and_exact
    target = scene if front == "scene" else contactqp.problem_from_scene(scene)
    result = solved(target, method, {})
    if result is None:  # refused: the other front end refuses too (one reason, one registry)
        other = scene if front == "problem" else contactqp.problem_from_scene(scene)
        assert solved(other, method, {}) is None or method in ("lemke", "pgs",
                                                               "semismooth_newton"), method
        return
    as_scene = contactqp.check(scene, result.u, result.contact_force)
    if result.verified or as_scene.verified:
        assert as_scene.verified  # never looser on the chain
        F, U = as_scene.force_scale, as_scene.displacement_scale
        error = result.contact_force - exact.contact_force
        # row by row, or on what the rows put on each node where rows repeat a constraint
        force_error = min(np.abs(error).max(initial=0.0), np.abs(
            contact_forces_on_nodes(scene.layout, error)).max(initial=0.0))
        assert force_error <= contactqp.GUARANTEE[0] * F, (method, front)
        assert np.abs(result.u - exact.displacement).max() <= contactqp.GUARANTEE[1] * U


def test_never_looser_on_a_chain_seed_41339():
    """Found by fresh seeds of the test above: the chain's own set solve found no reference
    for this qp answer where the sparse model's found one, so it was verified as a problem
    (7.5e-6 F) and not as a scene (the chain's 1.5e-5 F); the check now works the general
    certificate out on the scene's problem there."""
    scene = random_scene(np.random.default_rng(41339), floating=0.0)
    result = solved(scene, "qp", {})
    as_problem = contactqp.check(contactqp.problem_from_scene(scene), result.u,
                                 result.contact_force)
    as_scene = contactqp.check(scene, result.u, result.contact_force)
    assert as_scene.verified or not as_problem.verified
