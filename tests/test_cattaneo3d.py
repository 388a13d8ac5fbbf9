"""Cattaneo–Mindlin in 3D: two identical elastic spheres pressed by P, then pulled sideways
by Q < μP under Coulomb's law, against the closed forms (contactqp.friction.cattaneo3d).

Glossary: R the spheres' radius, E, ν, G = E/(2(1 + ν)) their material, μ the friction
coefficient, P the normal and Q the tangential load of the whole pair, a the radius of the
circle of contact, c the stick zone's, δ the caps' relative tangential shift (the tangential
compliance), h the element size at the contact. Closed forms (Johnson, *Contact Mechanics*,
§4.2 and §7.2), written out here, not taken from the module:

    a³ = 3PR(1 − ν²)/(4E),   c/a = (1 − Q/(μP))^(1/3),
    δ = (3μP/(16a)) · 2(2 − ν)/G · [1 − (1 − Q/(μP))^(2/3)].

Lengths in mm, forces in N. a/R = 0.01: the closed forms are those of half-spaces, and a
sphere is more compliant than a half-space (it lacks the material between the contact plane
and its curved surface), so the caps' shift exceeds the closed form's δ by a share that grows
with a/R: measured about +3 % per 0.01 of a/R (docs/friction.md, "Cattaneo–Mindlin in 3D").

Every answer is verified, the shears included. Before the check gave a 3D slip with no
direction of its own the set's direction, most shears were not: their force scale F was set
by the caps' pull, 10⁴ times the largest contact force, so a pair slipping by less than
10⁻⁶ F / k read as sticking, and the corrected set's Newton step started from a zero slip.
F is now the frictionless check's rule (the reactions a prescribed motion takes with no
contact force: nothing, for the caps' rigid motion), so the contact forces set it.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import contactqp
from contactqp.friction.cattaneo3d import cattaneo_spheres, shear_path

pytest.importorskip("skfem", reason='scikit-fem is not installed (pip install "contactqp[fem]")')

R, E, NU, MU = 10.0, 210e3, 0.3, 0.3
A = 0.01 * R  # the contact radius aimed at
APPROACH = 2.0 * A**2 / R * 1.03  # Hertz's 2a²/R for the pair, and 3 % for the caps' depth
TARGETS = (0.2, 0.5, 0.8)  # Q/(μP)


def closed_forms(P: float, Q: float) -> tuple[float, float, float]:
    """(a, c/a, δ) of the closed forms for the whole pair's P and Q."""
    a = (3.0 * P * R * (1.0 - NU**2) / (4.0 * E)) ** (1.0 / 3.0)
    G = E / (2.0 * (1.0 + NU))
    x = Q / (MU * P)
    delta = 3.0 * MU * P / (16.0 * a) * 2.0 * (2.0 - NU) / G * (1.0 - (1.0 - x) ** (2.0 / 3.0))
    return a, (1.0 - x) ** (1.0 / 3.0), delta


def read_path(spheres, path):
    """Per shear: (Q/(μP), c/a, (c/a)_closed, δ, δ_closed), P and Q of the whole pair read
    from the Result here (twice the half model's sums), c from the sticking pairs' area
    (πc²/2 on the half) and δ from the caps' displacement."""
    rows = []
    for result in path.sheared:
        P = 2.0 * result.contact_force.sum()
        Q = 2.0 * result.friction_force[:, 0].sum()
        a, ratio, delta = closed_forms(P, Q)
        sticking = result.state == "stick"
        c = math.sqrt(2.0 * spheres.tributary[sticking].sum() / math.pi)
        shift = result.u[spheres.cap_dofs[0]] - result.u[spheres.cap_dofs[1]]
        rows.append((Q / (MU * P), c / a, ratio, shift, delta))
    return rows


def assert_path(spheres, path, stick_tolerance: float, compliance_tolerance: float) -> None:
    """The checks both sizes share: the targets met, the normal load unchanged by the shear
    (β = 0: the pair decouples, observed here), every answer verified and at Coulomb's law
    (residuals at round-off), c/a and δ within the tolerances of the closed forms; F is the
    contact forces' scale, not the caps' pull (1e4 times larger)."""
    assert path.pressed.verified, path.pressed.message
    pressed = path.pressed.contact_force.sum()
    # the caps' pull on the free dofs held at rest, K_fp u_p: the old F
    problem = spheres.problem(MU, APPROACH)
    held = np.zeros(problem.n)
    held[problem.prescribed] = problem.prescribed_values
    pull = float(np.abs(np.delete(problem.K @ held, problem.prescribed)).max())
    for result in path.sheared:
        assert result.force_scale <= 2.0 * result.contact_force.max() < 1e-3 * pull
        assert result.status == "converged" and result.iterations <= 2, result.status
        assert result.verified, result.message
        assert result.contact_force.sum() == pytest.approx(pressed, rel=1e-9)
        # at round-off of F, the largest contact force here (0.29 N on the coarse pair): the
        # equilibrium residual is the round-off of K u, whose terms are the body's stresses
        assert max(value for value in result.residuals.values() if value is not None) <= 1e-10
    rows = read_path(spheres, path)
    for (x, stick, stick_closed, shift, delta), target in zip(rows, TARGETS):
        assert x == pytest.approx(target, abs=0.02)
        assert stick == pytest.approx(stick_closed, rel=stick_tolerance), (x, stick)
        assert shift == pytest.approx(delta, rel=compliance_tolerance), (x, shift / delta)


def test_closed_forms_agree_with_the_module():
    """The module's closed forms are the ones written out above."""
    from contactqp.friction import cattaneo3d

    P, Q = 33.0, 0.4 * MU * 33.0
    a, ratio, delta = closed_forms(P, Q)
    assert cattaneo3d.contact_radius(P, R, E, NU) == pytest.approx(a, rel=1e-14)
    assert cattaneo3d.stick_ratio(Q, P, MU) == pytest.approx(ratio, rel=1e-14)
    assert cattaneo3d.compliance(Q, P, MU, R, E, NU) == pytest.approx(delta, rel=1e-14)
    # small Q: Mindlin's bonded circle, δ = Q(2 − ν)/(4Ga)
    small = 1e-6 * MU * P
    G = E / (2.0 * (1.0 + NU))
    assert cattaneo3d.compliance(small, P, MU, R, E, NU) == pytest.approx(
        small * (2.0 - NU) / (4.0 * G * a), rel=1e-5)


def test_the_half_spheres_are_mirror_images_paired_node_by_node():
    """The half sphere is symmetric about x = 0 with every tetrahedron positive; each pair's
    rows read the upper node against the same node of the lower body (n₁ dofs further):
    −u₁z + u₂z ≤ 2z, the gap of two spheres 2(R − √(R² − r²)), and u₁x − u₂x, u₁y − u₂y;
    the caps are held whole and u_y = 0 on the plane y = 0."""
    from contactqp.fem.sphere_mesh import volumes

    spheres = cattaneo_spheres(R, E, NU, zone=1.3 * A, fine=A / 3, growth=0.6)
    mesh = spheres.mesh
    assert volumes(mesh).min() > 0.0
    points = np.round(mesh.p, 12) + 0.0
    images = points * np.array([[-1.0], [1.0], [1.0]]) + 0.0
    assert np.array_equal(points[:, np.lexsort(points)], images[:, np.lexsort(images)])
    C, T, g = spheres.arrays["C"], spheres.arrays["T"], spheres.arrays["g"]
    n1 = spheres.dofs // 2
    m = spheres.r.size
    assert g == pytest.approx(2.0 * (R - np.sqrt(R**2 - spheres.r**2)), abs=1e-13)
    assert np.all(np.diff(spheres.r) >= 0.0) and spheres.r[0] == 0.0
    for rows, signs in ((C, (-1.0, 1.0)), (T, (1.0, -1.0))):
        dense = rows.toarray()
        assert np.all(np.count_nonzero(dense, axis=1) == 2)
        upper, lower = dense[:, :n1], dense[:, n1:]
        assert np.array_equal(upper, -lower)
        assert set(np.unique(upper[upper != 0])) == {signs[0]}
    assert C.shape == (m, 2 * n1) and T.shape == (2 * m, 2 * n1)
    _, y, z = mesh.p
    held = spheres.arrays["prescribed"]
    assert held.size == np.unique(held).size
    caps = np.count_nonzero(z > R - 1e-9)
    plane = np.count_nonzero((y < 1e-12) | (z > R - 1e-9))
    assert (spheres.caps, spheres.held) == (caps, plane)
    assert held.size == 2 * (2 * caps + plane)


def test_cattaneo_mindlin_spheres_coarse():
    """A coarse pair (25 110 dofs, 205 pairs, h = a/5, growth 0.4), about 20 s: pressed,
    then sheared to Q/(μP) ≈ 0.2, 0.5, 0.8 in increments by the exact route (Coulomb's fixed
    point, one iteration: the pair decouples).

    Measured on this mesh: c/a −1.6 % to +1.8 % off the closed form, δ +1.8 % to +2.2 %.
    Asserted: c/a within 3 %: c is read from whole pairs, h = a/5, and one mirrored pair of
    pairs more or less moves it by 1.4 % (on this density at other a/R the reading was off by
    up to 3.3 %). δ within 3.5 %: the finite spheres add about +3 % at a/R = 0.01 and this
    mesh's stiffness about −1 % (the a/R sweep in docs/friction.md). The issue's goal, 5 %
    for both, is for 2·10⁵ dofs (the test below)."""
    spheres = cattaneo_spheres(R, E, NU, zone=1.3 * A, fine=A / 5, growth=0.4)
    path = shear_path(spheres, MU, APPROACH, TARGETS, contactqp.solve)
    assert_path(spheres, path, stick_tolerance=0.03, compliance_tolerance=0.035)


@pytest.mark.skipif(os.environ.get("CONTACTQP_SLOW") != "1",
                    reason="12 to 20 minutes and 9 GB (2·10⁵ dofs): CONTACTQP_SLOW=1 runs it")
def test_cattaneo_mindlin_spheres_at_two_hundred_thousand_dofs():
    """The issue's size: 207 432 dofs, 807 pairs, h = a/10, growth 0.18. Measured: 11.7 min
    on the two cores, 19 min with other jobs on them (the pressed state's SuperLU
    factorisation most of it), 8.8 GB.

    Measured: c/a +0.5 % to +0.7 % off the closed form, δ +2.9 % to +3.3 %. Asserted: c/a
    within 2 % (h = a/10: a mirrored pair of pairs moves c by about 0.35 %) and δ within 4 %
    (the finite spheres' +3 % at a/R = 0.01 and the mesh's last half per cent; the issue's
    goal is 5 % for both)."""
    spheres = cattaneo_spheres(R, E, NU, zone=1.3 * A, fine=A / 10, growth=0.18)
    assert spheres.dofs > 2e5
    path = shear_path(spheres, MU, APPROACH, TARGETS, contactqp.solve)
    assert_path(spheres, path, stick_tolerance=0.02, compliance_tolerance=0.04)


def test_augmented_lagrangian_in_3d_reads_the_exact_routes_c_and_delta():
    """The augmented Lagrangian with friction in 3D (Newton with the radial return's
    consistent tangent) on the coarse pair, the same path: every answer verified and the
    same c/a and δ as the exact route (another method) to 1e-6. The penalty at its default ε
    is not asserted: on this pair it does not settle on the pressed state (docs/friction.md)."""
    spheres = cattaneo_spheres(R, E, NU, zone=1.3 * A, fine=A / 5, growth=0.4)
    exact = read_path(spheres, shear_path(spheres, MU, APPROACH, TARGETS, contactqp.solve))
    path = shear_path(spheres, MU, APPROACH, TARGETS, contactqp.solve, "augmented")
    assert path.pressed.verified, path.pressed.message
    assert all(result.verified for result in path.sheared)
    for found, reference in zip(read_path(spheres, path), exact):
        np.testing.assert_allclose(found, reference, rtol=1e-6)
