"""Lemke's method against brute force: every complementary basis of a small LCP tried."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import contactqp
from contactqp.methods.lemke import lemke
from contactqp.random_scenes import random_scene
from contactqp.reference import reference


def brute_force(M: np.ndarray, q: np.ndarray) -> list[np.ndarray]:
    """Every solution z of w = M z + q >= 0, z >= 0, wᵀz = 0 with a nonsingular basis: for each
    set S, z_S = −M_SS⁻¹ q_S, z = 0 elsewhere, kept when z >= 0 and w >= 0."""
    n = q.size
    found = []
    for size in range(n + 1):
        for chosen in itertools.combinations(range(n), size):
            S = list(chosen)
            z = np.zeros(n)
            if S:
                block = M[np.ix_(S, S)]
                if abs(np.linalg.det(block)) < 1e-12:
                    continue
                z[S] = np.linalg.solve(block, -q[S])
            w = M @ z + q
            if z.min() >= -1e-9 and w.min() >= -1e-9:
                found.append(z)
    return found


def assert_solves(M: np.ndarray, q: np.ndarray, z: np.ndarray) -> None:
    w = M @ z + q
    scale = np.abs(q).max()
    assert z.min() >= 0.0 and w.min() >= -1e-10 * scale
    assert abs(w @ z) <= 1e-10 * scale * max(np.abs(z).max(), 1.0)


@pytest.mark.parametrize("seed", range(40))
def test_a_positive_definite_lcp_has_one_solution_and_lemke_finds_it(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 7))
    A = rng.normal(size=(n, n))
    M = A @ A.T + 0.1 * np.eye(n)
    q = rng.normal(size=n)
    z, _ = lemke(M, q)
    (expected,) = brute_force(M, q)
    np.testing.assert_allclose(z, expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("seed", range(40))
def test_a_semidefinite_lcp_with_ties_and_zeros_is_solved(seed):
    """Rank-deficient M (a contact problem with dependent rows), zero entries of q (zero gaps,
    the degenerate pivots): a solution, and its w = Mz + q is the one every solution has."""
    rng = np.random.default_rng(1000 + seed)
    n = int(rng.integers(2, 7))
    A = rng.normal(size=(n, int(rng.integers(1, n))))
    A[:, 0] = np.round(A[:, 0])  # repeated values: ties in the ratio test
    M = A @ A.T
    x = np.maximum(rng.normal(size=n), 0.0)  # a feasible point makes the LCP solvable
    q = -M @ x + np.where(rng.random(n) < 0.5, 0.0, np.abs(rng.normal(size=n)))
    z, _ = lemke(M, q)
    assert_solves(M, q, z)
    expected = brute_force(M, q)
    assert expected, "the brute force finds a solution"
    np.testing.assert_allclose(M @ z + q, M @ expected[0] + q, rtol=0,
                               atol=1e-8 * np.abs(q).max())


def test_nothing_to_do_when_every_gap_stays_open():
    z, pivots = lemke(np.eye(3), np.array([1.0, 0.0, 2.0]))
    assert z.tolist() == [0.0, 0.0, 0.0] and pivots == 0


def test_an_lcp_without_solution_ends_in_a_ray():
    """w = 0·z − 1 >= 0 has no solution: a clear error, not an answer."""
    with pytest.raises(contactqp.SolverError, match="secondary ray"):
        lemke(np.zeros((1, 1)), np.array([-1.0]))


def test_the_scale_of_the_numbers_does_not_matter():
    """A contact's flexibility is ~1e-9 m/N and its gap ~1e-4 m: the answer scales exactly."""
    rng = np.random.default_rng(5)
    A = rng.normal(size=(4, 4))
    M, q = A @ A.T + np.eye(4), rng.normal(size=4)
    z, _ = lemke(M, q)
    z_scaled, _ = lemke(1e-9 * M, 1e-4 * q)
    np.testing.assert_allclose(z_scaled, 1e5 * z, rtol=1e-12)


@pytest.mark.parametrize("q", [[-1.0, -1e-13], [-1e-13, -1.0], [-1.0, -1.0]])
def test_a_contact_far_more_flexible_than_another_is_pivoted_like_any(q):
    """M = diag(1, 1e-13): every contact closes, z = −q / diag(M). Scaled by its largest entry
    alone, M's small diagonal fell below the pivot tolerance: z = (1, 0) for q = (−1, −1e-13),
    and a ray for q = (−1e-13, −1)."""
    M, q = np.diag([1.0, 1e-13]), np.array(q)
    z, _ = lemke(M, q)
    expected = -q / np.diag(M)
    np.testing.assert_allclose(z, expected, rtol=0, atol=1e-9 * np.abs(expected).max())



def test_press_fits_that_need_small_pivots_end_in_the_exact_answer():
    # random_scene seed 3361 (found by a fresh hypothesis draw): walls on both sides of nodes
    # and press fits whose forces (1.1e12 N) are 10⁵ times the gaps' scale in the scaled LCP;
    # its pivots fall below 1e-9, where the first two tolerances saw a false secondary ray.
    # The answer comes back, within round-off of the largest force of the exact reference
    # (the check flags it: 1e-11 of 1e12 N is 12 N, far past 1e-5 of F = 4.9e6 N, and its
    # force bound holds the error)
    scene = random_scene(np.random.default_rng(3361))
    exact = reference(scene)
    result = contactqp.solve(scene, "lemke")
    error = np.abs(result.contact_force - exact.contact_force).max()
    assert error <= 1e-9 * np.abs(exact.contact_force).max()
    assert error <= result.force_error_bound


def test_a_small_force_beside_a_large_one_is_not_left_out():
    # random_scene(877, max_bars=1, contrast=False), a fresh draw of test_complementarity's
    # exactness test: the exact answer has 0.35 N on one wall beside 6.3e6 N on another. At
    # the pivot tolerance 1e-9 Lemke skipped the pivot that loads it, left its gap passed by
    # 2.3e-10 of q (accepted under the old 1e-8), and was 0.35 N off; the answer is now tried
    # at the next tolerances until a gap is passed by no more than round-off
    scene = random_scene(np.random.default_rng(877), max_bars=1, contrast=False)
    exact = reference(scene)
    result = contactqp.solve(scene, "lemke")
    largest = np.abs(exact.contact_force).max()
    assert np.abs(result.contact_force - exact.contact_force).max() <= 1e-9 * largest
    assert result.verified
