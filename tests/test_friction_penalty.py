"""The penalty method and the augmented Lagrangian with friction (contactqp.friction.penalty):
the regularised law's own closed forms (a penetration λ_N/ε_N, a creep λ_T/ε_T), the
augmented Lagrangian reaching the law's exact answer, the frictional bed's closed form, and
the refusals.

Glossary: K stiffness, f load, C u ≤ g the normal rows, T the tangential rows (one per contact
in 2D), s the Tresca slip bound, μ Coulomb's coefficient, λ_N ≥ 0 the normal and λ_T the
friction force, ε the penalty (force/length).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

import contactqp
from contactqp.friction.bed import bed_displacement, frictional_bed, slip_length
from contactqp.friction.check import check_tresca
from contactqp.friction.law import tresca
from contactqp.friction.penalty import solve_penalised

K_NODE = np.array([[1.0, -0.5], [-0.5, 1.0]])  # one node (u_t, u_n) on the flat u_n ≥ 0
ON_FLAT = {"C": [[0.0, -1.0]], "g": [0.0], "T": [[1.0, 0.0]]}


def one_node(**law) -> contactqp.Problem:
    return contactqp.Problem(K_NODE, [2.5, -1.0], **ON_FLAT, **law)


def test_tresca_slipping_node_augmented_is_exact_and_penalty_leaves_its_penetration():
    """Tresca with s = 1.5 on the node pulled along (2.5) and pressed (1): it slips on the
    flat, u = (1, 0), λ_N = ½, λ_T = s (by hand: u_n = 0, K_tt u_t − f_t + s = 0 gives
    u_t = 1, and K_nt u_t − f_n − λ_N = 0 gives λ_N = ½). The penalty ε leaves the
    penetration λ_N/ε exactly: the regularised system K u + ε n nᵀ u = f − s t, solved here
    by hand with numpy."""
    problem = one_node(slip_bound=1.5)
    augmented = contactqp.solve(problem, "augmented")
    assert augmented.verified and augmented.status == "converged"
    np.testing.assert_allclose(augmented.u, [1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(augmented.contact_force, [0.5], rtol=1e-12)
    np.testing.assert_allclose(augmented.friction_force, [[1.5]], rtol=1e-12)
    assert list(augmented.state) == ["slip"]
    eps = 1e3
    penalty = contactqp.solve(problem, "penalty", penalty=eps)
    by_hand = np.linalg.solve(K_NODE + eps * np.outer([0.0, 1.0], [0.0, 1.0]),
                              [2.5 - 1.5, -1.0])
    np.testing.assert_allclose(penalty.u, by_hand, rtol=1e-12)
    np.testing.assert_allclose(penalty.contact_force, [-eps * by_hand[1]], rtol=1e-12)
    assert penalty.penetration[0] == pytest.approx(penalty.contact_force[0] / eps, rel=1e-12)
    assert not penalty.verified  # 5e-4 of a unit penetration: the check flags it


def test_tresca_sticking_node_penalty_creeps_by_the_friction_force_over_its_penalty():
    """s = 3 > the 2.5 that holds the node: it sticks, u = 0 exactly (λ_T = 2.5, λ_N = 1 by
    hand). The penalty lets it creep by λ_T/ε and sink by λ_N/ε: K u + ε u = f (both rows
    stiff springs), by hand."""
    problem = one_node(slip_bound=3.0)
    eps = 1e4
    penalty = contactqp.solve(problem, "penalty", penalty=eps)
    by_hand = np.linalg.solve(K_NODE + eps * np.eye(2), [2.5, -1.0])
    np.testing.assert_allclose(penalty.u, by_hand, rtol=1e-12)
    assert list(penalty.state) == ["stick"]
    np.testing.assert_allclose(penalty.friction_force, [[eps * by_hand[0]]], rtol=1e-12)
    augmented = contactqp.solve(problem, "augmented", penalty=eps)
    assert augmented.verified
    np.testing.assert_allclose(augmented.u, [0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(augmented.friction_force, [[2.5]], rtol=1e-10)
    np.testing.assert_allclose(augmented.contact_force, [1.0], rtol=1e-10)


def test_coulomb_sliding_block_augmented_slides_on_the_flat():
    """The block on springs k = 10 pressed by 2 and pulled by 5 > μP = 1 (μ = ½): Coulomb
    slides on the flat, u = (0.4, 0), λ_N = 2, λ_T = 1 (by hand: 10 u_t = 5 − μ·2)."""
    problem = contactqp.Problem(10.0 * np.eye(2), [5.0, -2.0], **ON_FLAT, mu=0.5)
    augmented = contactqp.solve(problem, "augmented")
    assert augmented.verified
    np.testing.assert_allclose(augmented.u, [0.4, 0.0], atol=1e-12)
    np.testing.assert_allclose(augmented.contact_force, [2.0], rtol=1e-10)
    np.testing.assert_allclose(augmented.friction_force, [[1.0]], rtol=1e-10)
    penalty = contactqp.solve(problem, "penalty")  # the default ε: 1e6 × the row's stiffness
    assert abs(penalty.u[0] - 0.4) <= 1e-5 * 0.4
    if penalty.verified:  # then within the bound it states
        assert abs(penalty.contact_force[0] - 2.0) <= penalty.force_error_bound
        assert np.abs(penalty.u - [0.4, 0.0]).max() <= penalty.displacement_error_bound


@pytest.mark.parametrize("force", [0.3, 0.6, 0.9])
def test_frictional_bed_by_the_augmented_lagrangian_is_the_closed_form(force):
    """The bar on the bed, nodes at x_s = F/τ (bed.py): the discrete answer is the closed form
    u = −τ(x_s − x)²/(2EA) at the nodes; the augmented Lagrangian reaches it to round-off, the
    penalty within what its creep allows, and the check's bound holds where it verifies."""
    bed = frictional_bed(length=1.0, axial_stiffness=2.0, elements=40, tau=1.5,
                         force=force * 1.5)
    exact = bed_displacement(bed.x, bed.force, bed.tau, bed.axial_stiffness)
    law = tresca(bed.model, bed.slip_bound)
    answer = solve_penalised(bed.model, law, None, True, {})
    assert answer.converged
    np.testing.assert_allclose(answer.u, exact, atol=1e-10 * np.abs(exact).max())
    assert slip_length(bed, answer) == pytest.approx(force, abs=1e-8)
    found = check_tresca(bed.model, bed.slip_bound, answer)
    assert found.verified
    penalty = solve_penalised(bed.model, law, None, False, {})
    found = check_tresca(bed.model, bed.slip_bound, penalty)
    error = np.abs(penalty.u - exact).max()
    assert error <= 1e-4 * np.abs(exact).max()
    if found.verified:
        assert error <= found.displacement_error_bound


NODE_3D = {"C": [[0.0, 0.0, -1.0]], "g": [0.0], "T": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]}


@pytest.mark.parametrize("law", [{"slip_bound": 1.5}, {"mu": 0.3}])
def test_3d_node_slips_along_its_pull_by_the_closed_form(law):
    """One node (u_x, u_y, u_z), K = 2 I, on the flat u_z ≥ 0, pressed by 5 and pulled in the
    plane by (3, 4) (|f_t| = 5): it slips along (3, 4)/5 with the friction force b at the bound
    (b = s = 1.5, or μ·5 = 1.5), u_t = (5 − b)/2 · (3, 4)/5, λ_N = 5 (by hand: K u_t = f_t − b t̂).
    The augmented Lagrangian reaches it to round-off; the penalty ε leaves its penetration
    λ_N/ε exactly (the z row decouples: (2 + ε) u_z = −5)."""
    problem = contactqp.Problem(2.0 * np.eye(3), [3.0, 4.0, -5.0], **NODE_3D, **law)
    along = np.array([0.6, 0.8])
    augmented = contactqp.solve(problem, "augmented")
    assert augmented.verified and augmented.status == "converged", augmented.message
    # the augmented Lagrangian stops when λ changes by 1e-10 of F: u within that over ε
    np.testing.assert_allclose(augmented.u, [*(1.75 * along), 0.0], atol=1e-10)
    np.testing.assert_allclose(augmented.friction_force, [1.5 * along], rtol=1e-10)
    np.testing.assert_allclose(augmented.contact_force, [5.0], rtol=1e-10)
    assert list(augmented.state) == ["slip"]
    eps = 1e3
    penalty = contactqp.solve(problem, "penalty", penalty=eps)
    assert penalty.u[2] == pytest.approx(-5.0 / (2.0 + eps), rel=1e-12)
    lam_N = 5.0 * eps / (2.0 + eps)
    b = 1.5 if "slip_bound" in law else 0.3 * lam_N
    np.testing.assert_allclose(penalty.u[:2], (5.0 - b) / 2.0 * along, rtol=1e-12)
    np.testing.assert_allclose(penalty.friction_force, [b * along], rtol=1e-12)


def test_3d_node_sticks_and_the_penalty_creeps_by_its_force_over_epsilon():
    """Tresca s = 6 > |f_t| = 5: the node sticks, u = 0, λ_T = (3, 4), λ_N = 5 exactly; the
    penalty lets it creep by f/(2 + ε) in each direction (all three rows stiff springs)."""
    problem = contactqp.Problem(2.0 * np.eye(3), [3.0, 4.0, -5.0], **NODE_3D, slip_bound=6.0)
    eps = 1e4
    penalty = contactqp.solve(problem, "penalty", penalty=eps)
    np.testing.assert_allclose(penalty.u, np.array([3.0, 4.0, -5.0]) / (2.0 + eps), rtol=1e-12)
    assert list(penalty.state) == ["stick"]
    augmented = contactqp.solve(problem, "augmented", penalty=eps)
    assert augmented.verified
    np.testing.assert_allclose(augmented.u, 0.0, atol=1e-12)
    np.testing.assert_allclose(augmented.friction_force, [[3.0, 4.0]], rtol=1e-10)


def test_penalty_friction_refusals_are_one_line():
    """A bad penalty and an option the method does not take are refused in one line each."""
    for bad in (-1.0, 0.0, float("nan"), "stiff"):
        with pytest.raises(contactqp.OptionError, match="penalty") as error:
            contactqp.solve(one_node(slip_bound=1.0), "penalty", penalty=bad)
        assert "\n" not in str(error.value)
    with pytest.raises(contactqp.OptionError, match="tolerance"):
        contactqp.solve(one_node(slip_bound=1.0), "penalty", tolerance=1e-8)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["tresca", "coulomb"]))
@example(19, "tresca")  # 3D: a full Newton step swung a slip's direction for ever (now halved)
@example(31, "tresca")
def test_random_problems_verified_answers_are_within_their_bounds(seed, law):
    """Random problems, 2D or 3D by the seed's parity (nodes on a flat, SPD K coupling
    them): every verified penalty or augmented answer lies within its stated bounds of the
    exact route's (another method: the active set on the multipliers); the augmented
    Lagrangian converges. Coulomb with μ ≤ 0.4,
    where the answer is unique on these problems (the exact route's verdict says so)."""
    rng = np.random.default_rng(seed)
    d = 1 + seed % 2  # tangential rows per contact
    nodes = int(rng.integers(2, 7))
    n, m = (d + 1) * nodes, int(rng.integers(1, nodes + 1))
    A = rng.standard_normal((n, n))
    C, T = np.zeros((m, n)), np.zeros((d * m, n))
    for i, j in enumerate(rng.choice(nodes, m, replace=False)):
        C[i, (d + 1) * j + d] = -1.0
        for k in range(d):
            T[d * i + k, (d + 1) * j + k] = 1.0
    bound = ({"slip_bound": rng.uniform(0.0, 2.0, m)} if law == "tresca"
             else {"mu": rng.uniform(0.0, 0.4, m)})
    problem = contactqp.Problem(A @ A.T + n * np.eye(n), 3.0 * rng.standard_normal(n), C=C,
                                g=rng.uniform(0.0, 0.1, m), T=T, **bound)
    exact = contactqp.solve(problem, "lagrange")
    assume(exact.verified)
    for method in ("penalty", "augmented"):
        found = contactqp.solve(problem, method)
        if method == "augmented":
            assert found.status == "converged", (seed, found.message)
        if not found.verified or law == "coulomb" and not exact.verified:
            continue
        # the exact route's own bound: round-off for Tresca, its fixed point's 1e-10 of F
        # for Coulomb
        reach = found.displacement_error_bound + exact.displacement_error_bound
        assert np.abs(found.u - exact.u).max() <= reach * (1 + 1e-9) + 1e-15, (seed, method)
        off = max(np.abs(found.contact_force - exact.contact_force).max(),
                  np.abs(found.friction_force - exact.friction_force).max())
        reach = found.force_error_bound + exact.force_error_bound
        assert off <= reach * (1 + 1e-9) + 1e-12, (seed, method)
