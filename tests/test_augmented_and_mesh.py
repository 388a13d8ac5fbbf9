"""The augmented Lagrangian method, the minimal mesh and the area rules' convergence.

Glossary: F load (N), g gap (m), f = Σ L/(EA) flexibility from the support to the wall (m/N),
f₂ the same up to the load node, λ = (F f₂ − g)/f the contact force (N) of a cantilever with
one wall at its tip; ε penalty (N/m). For the cone (diameter d(x) linear), the continuum
flexibility of [a, b] is ∫ dx/(E π d(x)²/4), integrated here by quadrature.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad

import contactqp
from contactqp.methods.augmented import default_penalty
from contactqp.model import build_model
from contactqp.studies import penalty_sweep

E, F, GAP, LENGTH = 210e9, 565486.67, 1e-4, 1.0


def diameter(x: float) -> float:
    return 0.040 - 0.020 * x / LENGTH


def cone_flexibility(a: float, b: float) -> float:
    value, _ = quad(lambda x: 1.0 / (E * math.pi * diameter(x) ** 2 / 4.0), a, b,
                    epsabs=0.0, epsrel=1e-13)
    return value


def continuum_force() -> float:
    return (F * cone_flexibility(0.0, LENGTH / 2) - GAP) / cone_flexibility(0.0, LENGTH)


@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_augmented_reaches_the_lagrange_force_where_the_penalty_alone_cannot(contact):
    exact = contactqp.solve(contact=contact).contact_force[0]
    eps = 1e9  # ε f ≈ 7.5: the penalty alone is ~12 % off
    penalty = contactqp.solve(method="penalty", contact=contact, penalty=eps)
    augmented = contactqp.solve(method="augmented", contact=contact, penalty=eps)
    assert abs(penalty.contact_force[0] - exact) / exact > 0.1
    # converged to tolerance 1e-10 on the λ update, contraction 1/(1 + ε f) per update
    assert augmented.contact_force[0] == pytest.approx(exact, rel=1e-9)
    assert augmented.verified and augmented.iterations > 2


def test_augmented_default_penalty_converges_in_a_few_updates_to_round_off():
    exact = contactqp.solve().contact_force[0]
    result = contactqp.solve(method="augmented")
    assert result.contact_force[0] == pytest.approx(exact, rel=1e-12)  # round-off level
    assert result.iterations <= 10
    # the walls of the default scene see 1/f, f = Σ L/(EA) from the support to the tip
    model = build_model(contactqp.seed_scene())
    assert default_penalty(model) == pytest.approx(100 / cone_like_f(), rel=1e-12)


def test_augmented_default_penalty_does_not_grow_with_the_mesh():
    coarse, fine = (default_penalty(build_model(contactqp.seed_scene(n, "exact"))) for n in (2, 2000))
    # exact areas: the same flexibility at the tip on every mesh, so the same ε
    assert fine == pytest.approx(coarse, rel=1e-9)
    result = contactqp.solve(contactqp.seed_scene(20000, "exact"), method="augmented")
    assert result.verified and result.iterations <= 10


def test_augmented_with_a_hopeless_penalty_says_it_did_not_converge():
    result = contactqp.solve(method="augmented", penalty=1.0, max_iterations=5)
    assert not result.claimed_success and "not converged" in result.status
    assert not result.verified  # a 1 N/m penalty leaves the node 1.3 mm past the wall


def test_augmented_leaves_an_open_contact_open():
    scene = contactqp.seed_scene().with_loads((contactqp.Load(2, 1000.0),))
    result = contactqp.solve(scene, method="augmented")
    assert result.contact_force[0] == 0.0 and result.penetration[0] < 0


def test_penalty_sweep_shows_augmentation_beating_the_penalty():
    sweep = penalty_sweep()
    middle = list(sweep.penalties).index(1e10)
    # with ε f ≈ 75 the penalty is ~1 % off; the augmented updates remove the error
    assert sweep.force_error[middle] == pytest.approx(1 / (1 + 1e10 * cone_like_f()), rel=1e-3)
    assert sweep.augmented_error[middle] < 1e-10
    assert sweep.augmented_iterations[middle] > 1


def cone_like_f() -> float:
    """f of the default 4-element midpoint mesh, from the element areas computed here."""
    mids = [0.0375, 0.0325, 0.0275, 0.0225]
    return sum(0.25 / (E * math.pi * d**2 / 4) for d in mids)


@pytest.mark.parametrize("elements", [2, 4, 8])
def test_exact_area_rule_matches_the_cone_closed_form(elements):
    result = contactqp.solve(contactqp.seed_scene(elements, "exact"))
    # π d_a d_b / 4 per segment is the cone's exact flexibility: only round-off and the
    # quadrature (epsrel 1e-13) separate them
    assert result.contact_force[0] == pytest.approx(continuum_force(), rel=1e-12)


def test_midpoint_rule_converges_as_h_squared():
    errors = [abs(contactqp.solve(contactqp.seed_scene(n)).contact_force[0] - continuum_force())
              for n in (4, 8, 16, 32)]
    rates = [math.log2(a / b) for a, b in itertools.pairwise(errors)]
    # the midpoint rule's flexibility error is O(h²); the first halving is still pre-asymptotic
    assert rates == pytest.approx([2.0, 2.0, 2.0], abs=0.1)


@pytest.mark.parametrize("rule", ["midpoint", "exact"])
def test_minimal_mesh_reproduces_the_fine_model(rule):
    fine = contactqp.seed_scene(64, rule)
    small = contactqp.minimal(fine)
    assert small.bar.n_elements == 2  # nodes at the support, the load and the wall only
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


def coupled_walls() -> contactqp.Scene:
    """A soft element (1e-4 m² over 2 m) and then a short stiff one (7.8e-3 m² over 0.5 m, 330
    times stiffer) between two zero-gap walls: the walls' stiffest common mode stretches the
    stiff element."""
    bar = contactqp.Bar.from_areas([7.8125e-3, 1e-4, 7.8125e-3, 7.8125e-3], 2.1e11,
                                   lengths=[1.0, 2.0, 0.5, 1.0])
    loads = (contactqp.Load(1, -1.0), contactqp.Load(2, 1.0))
    walls = (contactqp.Wall(3, 0.0, "+"), contactqp.Wall(4, 0.0, "+"))
    return contactqp.Scene(bar, (contactqp.Support(0),), loads, walls)


def test_default_penalty_is_the_stiffest_mode_of_the_walls():
    scene = coupled_walls()
    model = build_model(scene)
    flexibility = np.linalg.inv(model.K.toarray())[np.ix_([2, 3], [2, 3])]  # nodes 3, 4
    stiffest = np.linalg.eigvalsh(np.linalg.inv(flexibility)).max()  # dense, independent
    assert default_penalty(model) == pytest.approx(100 * stiffest, rel=1e-9)
    result = contactqp.solve(scene, method="augmented")
    exact = contactqp.solve(scene)
    # every mode's error shrinks >= 101-fold per update: tolerance 1e-10 in a few updates
    assert result.verified and result.iterations <= 10
    assert result.contact_force == pytest.approx(exact.contact_force, rel=1e-8, abs=1e-12)
