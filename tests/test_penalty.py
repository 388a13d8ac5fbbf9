"""The penalty method (contactqp.methods.penalty) against its closed form λ_ε = (s u_free − g) /
(f + 1/ε) and its bound.

Symbols (SI units)
------------------
E         Young's modulus (Pa)
A_e, L_e  area (m²) and length (m) of element e, which joins nodes e and e + 1
k_e       E A_e / L_e, element stiffness of element e (N/m)
f_j       Σ_{e<j} L_e / (E A_e): compliance of a cantilever fixed at node 0, seen at node j
          (m/N)
F, a      a point load (N, +x) and its node
w, g, s   a wall's node, gap (m) and side sign (+1 for "+", -1 for "-"): s u_w <= g
λ         contact force, how hard the wall pushes the bar (N, >= 0 when physical)
R         reaction of a support: the force it applies to the bar in +x (N)
ε         penalty (N/m): λ_ε = (s u_free,w − g) / (f_w + 1/ε)
K, P      dense stiffness (N/m) and loads (N) of the free nodes, assembled here
C, g      one row per wall, s at the wall's node: the walls hold where C u <= g
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from closed_forms import (
    DEFAULT_GAP,
    DEFAULT_WALL_NODE,
    SEVERAL_WALLS,
    assert_normwise,
    brute_force,
    default_closed_form,
    default_compliance,
    default_scene_with,
    dense_algebra,
    small_force,
)
from contactqp import (
    Wall,
)

PENALTIES = [1e8, 1e10, 1e12, 1e14]  # N/m; ε f_4 runs from ~1 to ~1e6 on the seed scene


@pytest.mark.parametrize("make_scene", SEVERAL_WALLS)
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_several_walls_penalty_is_within_its_bound(make_scene, contact):
    """With walls A in contact, (F_AA + I/ε) λ_ε = F_AA λ for F_AA = C_A K⁻¹ C_Aᵀ, so
    ‖λ − λ_ε‖₂ <= ‖λ‖₂ / (ε · smallest eigenvalue of F_AA)."""
    scene = make_scene()
    eps = 1e14
    u, lam, active = brute_force(scene, contact)
    _, _, _, K, _, C, _ = dense_algebra(scene)
    Ca = C[active]
    smallest = np.linalg.eigvalsh(Ca @ np.linalg.solve(K, Ca.T)).min()
    bound = np.linalg.norm(lam) / (eps * smallest)
    result = contactqp.solve(scene, "penalty", contact, penalty=eps)
    # 1 % above the bound for the solve's own round-off (~1e-10 relative against ~1e-6 here)
    assert np.abs(result.contact_force - lam).max() <= 1.01 * bound
    # u_ε − u = K⁻¹ C_Aᵀ (λ − λ_ε): the same bound carried through K⁻¹ C_Aᵀ (1 % as above)
    u_bound = np.linalg.norm(np.linalg.solve(K, Ca.T), 2) * bound
    assert np.abs(result.u - u).max() <= 1.01 * u_bound


@pytest.mark.parametrize("eps", PENALTIES)
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_penalty_force_matches_its_closed_form(eps, contact):
    result = contactqp.solve(None, "penalty", contact, penalty=eps)
    u, lam = default_closed_form(contact=contact, penalty=eps)
    # κ(K + ε CᵀC) ~ 1 + ε f ≲ 1e6: round-off ≲ 1e-10 relative
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-9)
    assert_normwise(result.u, u, rel=1e-9)  # as above
    # the penalty leaves the node past the wall by λ / ε = (u_free − g) / (1 + ε f)
    assert result.penetration[0] == pytest.approx(lam / eps, rel=1e-9)  # as above


def test_penalty_converges_to_lagrange_as_one_over_eps_f():
    lagrange = contactqp.solve(None, "lagrange").contact_force[0]
    f = default_compliance(DEFAULT_WALL_NODE)
    errors = []
    for eps in PENALTIES:
        penalty = contactqp.solve(None, "penalty", penalty=eps).contact_force[0]
        errors.append((lagrange - penalty) / lagrange)
        # λ_ε carries ~1e-11 relative round-off and the difference cancels it up by
        # 1 + ε f ≲ 1e6: ~1e-5 relative at ε = 1e14
        assert errors[-1] == pytest.approx(1.0 / (1.0 + eps * f), rel=1e-4)
    assert all(e > 0.0 for e in errors)  # the spring always gives a little
    assert errors == sorted(errors, reverse=True)


def test_penalty_inequality_acts_only_on_penetrated_walls():
    # the tip wall is passed; a far "+" wall at node 3 and a "-" wall at node 1 are not
    walls = (Wall(4, DEFAULT_GAP, "+"), Wall(3, 5e-3, "+"), Wall(1, 0.0, "-"))
    scene = default_scene_with(walls=walls)
    eps = 1e14
    u, lam = default_closed_form(penalty=eps)
    result = contactqp.solve(scene, "penalty", "inequality", penalty=eps)
    assert result.contact_force[1] == 0.0 and result.contact_force[2] == 0.0  # open: no spring
    # κ(K + ε CᵀC) ~ 1 + ε f ≲ 1e6: round-off ≲ 1e-10 relative
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-9)
    assert_normwise(result.u, u, rel=1e-9)  # as above: as if the open walls were not there
    assert result.penetration[1] < 0.0 and result.penetration[2] < 0.0
    # the equality path springs every wall: node 1 is pulled back onto its wall
    bilateral = contactqp.solve(scene, "penalty", "equality", penalty=eps)
    assert bilateral.contact_force[2] < 0.0


def test_penalty_with_no_penetration_is_the_free_solution():
    force = small_force()
    u, _ = default_closed_form(force=force)
    result = contactqp.solve(default_scene_with(force=force), "penalty", "inequality")
    assert result.contact_force.tolist() == [0.0]
    assert_normwise(result.u, u, rel=1e-12)  # no spring: κ(K) ~ 10, exact to ~1e-15
