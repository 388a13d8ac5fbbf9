"""Every failure the benchmark matrix finds is detected, never silently wrong.

The expected forces come from contactqp.reference (statics in extended precision, itself tested
against closed forms, exact arithmetic and scipy's BVLS in test_reference.py). "Right or
flagged": a run whose Result is verified and physical has its contact force within WRONG of the
reference (relative); any other run must say it is not verified (or not physical).
"""

from __future__ import annotations

import warnings
from fractions import Fraction

import numpy as np
import pytest
import scipy.linalg as sla

import contactqp
from closed_forms import INSTALLED_SOLVERS, error, touching
from contactqp import (
    Bar,
    Load,
    Scene,
    Support,
    Wall,
)
from contactqp.model import (
    Layout,
)
from contactqp.reference import (
    reference,
)

# Wrong: a force error above ten times the check's largest tolerance (1e-5). The check bounds
# residuals; a force error is a residual times a condition number of order 1-10 (CVXOPT through
# cvxpy: verified, 1.07e-5 off), the same rule as benchmarks/run.py
WRONG = 1e-4


SOLVER_IDS = [f"{s.backend}-{s.solver}" for s in INSTALLED_SOLVERS]


def press_fit() -> Scene:
    """The default scene, its node 4 starting 0.1 mm past the wall."""
    return contactqp.default_scene().with_walls((Wall(4, -1e-4),))


def far_wall() -> Scene:
    return contactqp.default_scene().with_walls((Wall(4, 2e-3),))


def tapered(elements: int) -> Scene:
    bar = Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9, area_rule="exact")
    return Scene(bar, (Support(0),), (Load(elements // 2, 565486.67),),
                 (Wall(elements, 1e-4),))


def assert_right_or_flagged(result: contactqp.Result, scene: Scene) -> float:
    found = error(result, scene)
    if result.verified and result.physical:
        assert found <= WRONG, f"{result.label}: verified but {found:.1e} off"
    else:
        assert result.message  # a flagged Result says what is off
    return found


def run_quietly(scene: Scene, method: str, **options) -> contactqp.Result:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return contactqp.solve(scene, method, **options)


TOUCHING_RUNS = [("lagrange", {}), ("augmented", {}), *[("penalty", {"penalty": e})
                                                        for e in (1e10, 1e14, 1e18, 1e22)]]


def obstacle(elements: int) -> Scene:
    """The tapered bar beside a wall at every node, gaps 0.2 mm (x/L)² + 10 µm |sin 37x/L|."""
    x = np.linspace(0.0, 1.0, elements + 1)
    gaps = 2e-4 * x**2 + 1e-5 * np.abs(np.sin(37.0 * x))
    return contactqp.wall_at_every_node(tapered(elements).with_walls(()), gaps)


@pytest.mark.parametrize("epsilon", [1e8, 1e10, 1e22])
def test_a_penalty_too_soft_or_too_stiff_is_flagged_and_augmented_recovers(epsilon):
    scene = contactqp.default_scene()
    penalty = contactqp.solve(scene, "penalty", penalty=epsilon)
    # too soft: the error is s/ε (s the stiffness the wall sees); too stiff: round-off of
    # K + εCᵀC, cond ~ ε/k_min. Either way it is wrong, and the check says so
    assert error(penalty, scene) > WRONG
    assert not penalty.verified and penalty.message
    augmented = contactqp.solve(scene, "augmented")
    assert augmented.verified and error(augmented, scene) <= 1e-10


@pytest.mark.parametrize("info", INSTALLED_SOLVERS, ids=SOLVER_IDS)
def test_every_solver_is_right_or_flagged_in_si_and_scaled_units(info):
    # SI: K ~ 1e9 N/m, u ~ 1e-4 m; HiGHS, quadprog, ECOS and QPALM break there (benchmark)
    for scene in (contactqp.default_scene(), press_fit(), far_wall()):
        for scale in (True, False):
            for formulation in ("full", "condensed"):
                result = run_quietly(scene, "qp", backend=info.backend, solver=info.solver,
                                     scale=scale, formulation=formulation)
                assert_right_or_flagged(result, scene)


def test_the_stiffness_condition_number_grows_like_n_squared():
    # why first-order solvers struggle on long bars: cond(K) ~ n² (dense eigenvalues here)
    conditions = []
    for n in (100, 400):
        K = contactqp.build_model(tapered(n)).K.toarray()
        eigenvalues = sla.eigvalsh(K)
        conditions.append(eigenvalues[-1] / eigenvalues[0])
    assert conditions[1] / conditions[0] == pytest.approx(16.0, rel=0.15)


@pytest.mark.parametrize(("backend", "solver"), [("osqp", None), ("cvxpy", "SCS"),
                                                 ("qpsolvers", "scs"), ("qpsolvers", "osqp")])
def test_first_order_solvers_on_a_long_bar_are_right_or_flagged(backend, solver):
    if not any(s.backend == backend and (solver is None or s.solver == solver) for s in INSTALLED_SOLVERS):
        pytest.skip(f"{backend}/{solver} is not installed")
    scene = tapered(10_000)
    for accuracy in ("default", "high"):
        result = run_quietly(scene, "qp", backend=backend, solver=solver, accuracy=accuracy)
        assert_right_or_flagged(result, scene)


@pytest.mark.parametrize(("method", "options"), [("lagrange", {}), ("penalty", {}),
                                                 ("qp", {}), ("qp", {"backend": "osqp"})])
def test_equality_contact_on_an_open_gap_pulls_and_says_so(method, options):
    scene = far_wall()
    assert reference(scene).contact_force[0] == 0.0  # the free tip stops short of the wall
    result = contactqp.solve(scene, method, contact="equality", **options)
    assert result.contact_force[0] < 0.0  # the wall pulls the node out to it
    assert not result.physical and "pull" in result.message


@pytest.mark.parametrize(("method", "options"), TOUCHING_RUNS)
@pytest.mark.parametrize("formulation", ["full", "condensed"])
def test_the_degenerate_touching_contact_never_raises_and_is_right_or_flagged(method, options,
                                                                           formulation):
    # zero force on an active constraint: the penalty's active-set loop cycled here (open:
    # penetrated by round-off; closed: pulled by round-off) before its decisions had a band
    scene = touching()
    assert reference(scene).contact_force[0] == 0.0
    result = contactqp.solve(scene, method, formulation=formulation, **options)
    assert_right_or_flagged(result, scene)
    if method != "penalty" or options["penalty"] <= 1e18:
        assert result.verified


@pytest.mark.parametrize("info", INSTALLED_SOLVERS, ids=SOLVER_IDS)
def test_every_solver_is_right_or_flagged_on_the_touching_contact(info):
    # interior-point solvers stop with λ ~ 1e-5 F on the touching wall: flagged, never verified
    scene = touching()
    for accuracy in ("default", "high"):
        result = run_quietly(scene, "qp", backend=info.backend, solver=info.solver,
                             accuracy=accuracy)
        assert_right_or_flagged(result, scene)


@pytest.mark.parametrize(("method", "options"), [("lagrange", {}), ("augmented", {}),
                                                 ("penalty", {"penalty": 1e16}), ("qp", {}),
                                                 ("qp", {"backend": "osqp"})])
def test_a_wall_that_starts_past_its_node_pushes_it_back(method, options):
    scene = press_fit()
    # closed form: the wall pushes node 4 back by 0.1 mm through the whole bar, and takes the
    # load's free tip displacement on top: λ = (F f₂ + 1e-4) / f₄
    k = Layout(scene).element_stiffness
    f2, f4 = (sum(Fraction(1) / Fraction(x) for x in k[:n]) for n in (2, 4))
    exact = float((Fraction(565486.67) * f2 + Fraction(1e-4)) / f4)
    result = contactqp.solve(scene, method, **options)
    assert result.verified
    # the penalty leaves s/ε = 1.3e-8 (s = 1.3e8 N/m, the stiffness the wall sees)
    assert result.contact_force[0] == pytest.approx(exact, rel=1e-7 if method == "penalty"
                                                    else 1e-8)
    assert result.u[4] == pytest.approx(-1e-4, rel=1e-6)


def test_many_walls_on_a_fine_mesh_are_right_or_flagged():
    # with gap / U in the complementarity, Clarabel's answer on 1e5 walls was verified with
    # 3e-3 of the largest force misplaced between neighbouring walls; here 3e4 walls
    scene = obstacle(30_000)
    for accuracy in ("default", "high"):
        assert_right_or_flagged(run_quietly(scene, "qp", accuracy=accuracy), scene)
    augmented = contactqp.solve(scene, "augmented")
    assert augmented.verified and error(augmented, scene) <= 1e-8
