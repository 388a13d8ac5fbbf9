"""The augmented Lagrangian method (contactqp.methods.augmented).

Glossary: F load (N), g gap (m), f = Σ L/(EA) compliance from the support to the wall (m/N),
λ = (F f₂ − g)/f the contact force (N) of a cantilever with one wall at its tip; ε penalty (N/m).
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from closed_forms import (
    cone_like_f,
)
from contactqp.methods.augmented import default_penalty
from contactqp.model import (
    build_model,
)


def coupled_walls() -> contactqp.Scene:
    """A soft element (1e-4 m² over 2 m) and then a short stiff one (7.8e-3 m² over 0.5 m, 330
    times stiffer) between two zero-gap walls: the walls' stiffest common mode stretches the
    stiff element."""
    bar = contactqp.Bar.from_areas([7.8125e-3, 1e-4, 7.8125e-3, 7.8125e-3], 2.1e11,
                                   lengths=[1.0, 2.0, 0.5, 1.0])
    loads = (contactqp.Load(1, -1.0), contactqp.Load(2, 1.0))
    walls = (contactqp.Wall(3, 0.0, "+"), contactqp.Wall(4, 0.0, "+"))
    return contactqp.Scene(bar, (contactqp.Support(0),), loads, walls)


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
    model = build_model(contactqp.default_scene())
    assert default_penalty(model) == pytest.approx(100 / cone_like_f(), rel=1e-12)


def test_augmented_default_penalty_does_not_grow_with_the_mesh():
    coarse, fine = (default_penalty(build_model(contactqp.default_scene(n, "exact"))) for n in (2, 2000))
    # exact areas: the same flexibility at the tip on every mesh, so the same ε
    assert fine == pytest.approx(coarse, rel=1e-9)
    result = contactqp.solve(contactqp.default_scene(20000, "exact"), method="augmented")
    assert result.verified and result.iterations <= 10


def test_augmented_with_a_hopeless_penalty_says_it_did_not_converge():
    result = contactqp.solve(method="augmented", penalty=1.0, max_iterations=5)
    assert not result.claimed_success and "not converged" in result.status
    assert not result.verified  # a 1 N/m penalty leaves the node 1.3 mm past the wall


def test_augmented_leaves_an_open_contact_open():
    scene = contactqp.default_scene().with_loads((contactqp.Load(2, 1000.0),))
    result = contactqp.solve(scene, method="augmented")
    assert result.contact_force[0] == 0.0 and result.penetration[0] < 0


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
