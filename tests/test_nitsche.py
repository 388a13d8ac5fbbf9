"""Nitsche's method for walls at a bar's end (contactqp.methods.nitsche).

Expected numbers: the default scene's closed form (Nitsche is consistent: where the end node
carries no load its answer is the discrete Signorini answer for every γ₀ and θ), Nitsche's
equations assembled here in dense numpy from the bar's geometry (closed_forms.dense_algebra),
and Lagrange multipliers as γ₀ → ∞.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from closed_forms import DEFAULT_SCENE, default_closed_form, dense_algebra
from contactqp import Load, Scene, Wall

THETAS = [1.0, 0.0, -1.0]


def loaded_tip() -> Scene:
    """The default scene with 200 kN more at the tip (node 4, the wall's node): the end node
    carries a load, so Nitsche's element force is not the contact force there."""
    return Scene(DEFAULT_SCENE.bars, DEFAULT_SCENE.supports,
                 (*DEFAULT_SCENE.loads, Load(4, 2e5)), DEFAULT_SCENE.walls)


def dense_nitsche(scene: Scene, gamma0: float, theta: float) -> tuple[np.ndarray, float]:
    """(u at the free nodes, λ) of Nitsche's system with the tip wall held, in dense numpy:
    K u − θ s ẽᵀu − ẽ sᵀu + γ ẽẽᵀu = P − g (θ s − γ ẽ), s = k(e_tip − e_before), ẽ = e_tip,
    γ = γ₀ k, λ = −(s·u − γ (u_tip − g))."""
    _, _, free, K, P, _, g = dense_algebra(scene)
    k = -K[-1, -2]  # the last element's stiffness
    s = np.zeros(len(free))
    s[-1], s[-2] = k, -k
    e = np.zeros(len(free))
    e[-1] = 1.0
    gamma = gamma0 * k
    J = K - theta * np.outer(s, e) - np.outer(e, s) + gamma * np.outer(e, e)
    u = np.linalg.solve(J, P - g[0] * (theta * s - gamma * e))
    return u, -(s @ u - gamma * (u[-1] - g[0]))


# symmetric Nitsche needs γ₀ above its threshold (1 here: below, the active system is not
# positive definite); the other forms take any γ₀ > 0
@pytest.mark.parametrize(("theta", "gamma0"), [(t, g) for t in THETAS for g in (0.5, 10.0, 1e4)
                                               if not (t == 1.0 and g < 1.0)])
def test_where_the_end_node_is_unloaded_nitsche_is_the_closed_form(theta, gamma0):
    u, lam = default_closed_form()
    result = contactqp.solve(None, "nitsche", gamma0=gamma0, theta=theta)
    assert result.verified and result.claimed_success
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-12)
    np.testing.assert_allclose(result.u, u, rtol=0, atol=1e-12 * np.abs(u).max())


@pytest.mark.parametrize("theta", THETAS)
@pytest.mark.parametrize("gamma0", [3.0, 100.0])
def test_a_loaded_end_node_gives_nitsches_own_answer(theta, gamma0):
    """The tip carries 200 kN: Nitsche's answer is that of its own equations (assembled here),
    not the discrete Signorini answer, and the check says so: it penetrates."""
    u, lam = dense_nitsche(loaded_tip(), gamma0, theta)
    result = contactqp.solve(loaded_tip(), "nitsche", gamma0=gamma0, theta=theta)
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-10)
    np.testing.assert_allclose(result.u[1:], u, rtol=0, atol=1e-10 * np.abs(u).max())
    assert result.penetration[0] > 0.0 and not result.verified


@pytest.mark.parametrize("theta", THETAS)
def test_as_gamma0_grows_nitsche_tends_to_the_lagrange_answer(theta):
    """Force and penetration errors on the loaded tip fall as 1/γ₀ (the skew and incomplete
    forms; the symmetric one has the exact force already), and at γ₀ = 1e8 the answer is
    verified."""
    exact = contactqp.solve(loaded_tip(), "lagrange")
    errors, depths = [], []
    for gamma0 in (1e2, 1e4, 1e6):
        result = contactqp.solve(loaded_tip(), "nitsche", gamma0=gamma0, theta=theta)
        errors.append(abs(result.contact_force[0] - exact.contact_force[0]))
        depths.append(result.penetration[0])
    assert depths[1] == pytest.approx(depths[0] / 100, rel=0.05)
    assert depths[2] == pytest.approx(depths[1] / 100, rel=0.05)
    if theta != 1.0:
        assert errors[1] == pytest.approx(errors[0] / 100, rel=0.05)
    assert contactqp.solve(loaded_tip(), "nitsche", gamma0=1e8, theta=theta).verified


def test_an_open_wall_carries_nothing():
    """Half the default load leaves the gap open: no contact force, the free displacement."""
    scene = DEFAULT_SCENE.scaled_loads(0.01)
    result = contactqp.solve(scene, "nitsche")
    assert result.contact_force[0] == 0.0 and result.verified
    assert result.penetration[0] < 0.0


@pytest.mark.parametrize(("walls", "message"), [
    ((Wall(2, 1e-4),), "wall\\[0\\] at bar 0 node 2 is at an interior node"),
    ((Wall(4, 1e-4, "-"),), "faces into the bar"),
])
def test_a_wall_off_the_boundary_is_refused_with_the_reason(walls, message):
    scene = Scene(DEFAULT_SCENE.bars, DEFAULT_SCENE.supports, DEFAULT_SCENE.loads, walls)
    with pytest.raises(contactqp.OptionError, match=message):
        contactqp.solve(scene, "nitsche")


def test_symmetric_nitsche_below_its_threshold_says_what_is_stable():
    with pytest.raises(contactqp.SolverError, match="θ = −1 is stable"):
        contactqp.solve(None, "nitsche", gamma0=1.0, theta=1.0)


def test_a_singular_system_with_a_large_gamma0_advises_a_smaller_one():
    """Round-off, not instability, makes a large γ₀'s system singular: "a larger γ₀" (as
    γ₀ = 1e300 was told) is no advice there."""
    from contactqp.methods.nitsche import DEFAULT_GAMMA0, _advice

    assert "a smaller γ₀" in _advice(1e20)
    assert "a larger γ₀" in _advice(DEFAULT_GAMMA0)


@pytest.mark.parametrize(("options", "message"), [
    ({"theta": 0.5}, "theta must be one of 1, 0, -1"),
    ({"gamma0": 0.0}, "gamma0"),
])
def test_bad_options_are_one_clear_error(options, message):
    with pytest.raises(contactqp.OptionError, match=message):
        contactqp.solve(None, "nitsche", **options)


BAR = contactqp.Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)  # k = 2e7 N/m per element


@pytest.mark.parametrize("theta", THETAS)
@pytest.mark.parametrize("gamma0", [2.0, 1e3])
def test_a_wall_at_the_first_node_is_a_boundary_too(theta, gamma0):
    """A bar held at its last node (2), −5 kN at node 1, a "−" wall 0.1 mm behind node 0: the
    unloaded first node follows node 1 to −0.25 mm and passes the wall; by hand
    λ = (0.25 − 0.1) mm / (1/k + 1/k) = 1500 N."""
    scene = Scene(BAR, (contactqp.Support(2),), (Load(1, -5e3),), (Wall(0, 1e-4, "-"),))
    result = contactqp.solve(scene, "nitsche", gamma0=gamma0, theta=theta)
    assert result.verified
    assert result.contact_force[0] == pytest.approx(1500.0, rel=1e-9)


@pytest.mark.parametrize("theta", THETAS)
@pytest.mark.parametrize("gamma0", [2.0, 1e3])
def test_a_contact_between_bar_ends_is_two_boundaries(theta, gamma0):
    """Bar 0 (k = 2e7, 2e7) held at node 0 with 5 kN at node 1; its tip 0.1 mm from bar 1's
    head (k = 6e7, 2e7, held at node 2). By hand: the tip reaches 0.25 mm freely, so
    λ = (0.25 − 0.1) mm / (1/2e7 + 1/2e7 + 1/6e7 + 1/2e7) = 900 N, for every γ₀ and θ (the
    end nodes carry no load)."""
    head = contactqp.Bar.from_areas([3e-4, 1e-4], 2e11, length=2.0)
    scene = Scene((BAR, head), (contactqp.Support(0, 0), contactqp.Support(2, 1)),
                  (Load(1, 5e3, 0),), (), contacts=(contactqp.BarContact(0, 2, 1, 0, 1e-4),))
    result = contactqp.solve(scene, "nitsche", gamma0=gamma0, theta=theta)
    assert result.verified
    assert result.contact_force[0] == pytest.approx(900.0, rel=1e-9)


def test_a_bar_contact_off_the_bar_ends_is_refused():
    scene = Scene((BAR, BAR), (contactqp.Support(0, 0), contactqp.Support(2, 1)),
                  (Load(1, 5e3, 0),), (), contacts=(contactqp.BarContact(0, 1, 1, 0, 1e-4),))
    with pytest.raises(contactqp.OptionError, match="contact between bar ends"):
        contactqp.solve(scene, "nitsche")
