"""Friction (contactqp.friction): Tresca by every backend against exact rational answers, the
duals read as friction forces, 3D Tresca as a cone program, Coulomb's methods and their
failures, the load path, the frictional bed's closed form, and refusals.

Glossary: K stiffness, f load, C/g normal rows and gaps, T tangential rows, s Tresca's slip
bounds, μ Coulomb's coefficients, λ_N normal forces (acting as −Cᵀλ_N), λ_T friction forces
(acting as −Tᵀλ_T, along the slip), F the check's force scale, U its displacement scale.
"""

from __future__ import annotations

import functools
import importlib.util
import itertools
from fractions import Fraction

import numpy as np
import pytest
import qpsolvers

from contactqp.errors import OptionError, ProblemError
from contactqp.friction import (
    check_coulomb,
    check_tresca,
    friction_model,
    friction_residuals,
    solve_coulomb,
    solve_tresca,
)
from contactqp.friction.bed import bed_displacement, frictional_bed, slip_length
from contactqp.friction.examples import (
    all_answers,
    cycling_fixed_point,
    nonunique_coulomb,
    sliding_block,
)
from contactqp.friction.law import coulomb
from contactqp.friction.path import load_path
from contactqp.friction.qp import primal_qp

# seeds of small integer problems whose one answer mixes the states: (open slip, closed
# stick, open slip backwards), (open slip, closed slip, closed stick), (closed slip backwards,
# closed stick, open slip backwards), (closed slip backwards, closed stick, closed slip back)
SEEDS = (16, 17, 24, 0)
BACKENDS = ("active_set", "clarabel", "cvxpy", *qpsolvers.available_solvers,
            "qpsolvers:clarabel")
# ECOS (through qpsolvers, on the dual box QP) ends with INACC_OFFSET on these problems, its
# forces off by 1e-6 to 1e-5 of F: the check's bound contains that error and does not verify
LOOSE = ("ecos",)


def integer_problem(seed: int):
    """Three nodes (u_t, u_n) on a flat, K = BᵀB + 2I with small integer B: (K, f, C, g, T, s)
    as integer lists, so that the exact answer is rational."""
    rng = np.random.default_rng(seed)
    n, m = 6, 3
    B = rng.integers(-2, 3, (n, n))
    K = B.T @ B + 2 * np.eye(n, dtype=int)
    f = rng.integers(-6, 7, n)
    g = rng.integers(0, 2, m)
    s = rng.integers(1, 4, m)
    C, T = np.zeros((m, n), int), np.zeros((m, n), int)
    for i in range(m):
        C[i, 2 * i + 1], T[i, 2 * i] = -1, 1
    return K, f, C, g, T, s


def solve_rational(matrix, rhs):
    """Gaussian elimination in exact fractions; None where singular."""
    size = len(matrix)
    rows = [[Fraction(int(x)) if not isinstance(x, Fraction) else x for x in row] + [b]
            for row, b in zip(matrix, rhs)]
    for col in range(size):
        pivot = next((r for r in range(col, size) if rows[r][col] != 0), None)
        if pivot is None:
            return None
        rows[col], rows[pivot] = rows[pivot], rows[col]
        for r in range(size):
            if r != col and rows[r][col] != 0:
                factor = rows[r][col] / rows[col][col]
                rows[r] = [x - factor * y for x, y in zip(rows[r], rows[col])]
    return [rows[i][size] / rows[i][i] for i in range(size)]


@functools.cache
def exact_tresca(seed: int):
    """Every answer of the 2D Tresca problem, by enumerating the 6^m states (open or closed;
    stick, slip forwards, slip backwards) and solving each state's linear system in exact
    arithmetic: [(u, λ_N, λ_T)] as fractions. Tresca is convex: there must be one."""
    K, f, C, g, T, s = integer_problem(seed)
    n, m = K.shape[0], C.shape[0]
    found = []
    for states in itertools.product(itertools.product((False, True), (0, 1, -1)), repeat=m):
        closed = [c for c, _ in states]
        turn = [t for _, t in states]
        held = [i for i in range(m) if closed[i]]
        stick = [i for i in range(m) if turn[i] == 0]
        size = n + len(held) + len(stick)
        matrix = [[Fraction(0)] * size for _ in range(size)]
        rhs = [Fraction(0)] * size
        for r in range(n):
            matrix[r][:n] = [Fraction(int(x)) for x in K[r]]
            rhs[r] = Fraction(int(f[r])) - sum(int(T[i, r]) * turn[i] * int(s[i])
                                               for i in range(m))
            for j, i in enumerate(held):
                matrix[r][n + j] = Fraction(int(C[i, r]))
            for j, i in enumerate(stick):
                matrix[r][n + len(held) + j] = Fraction(int(T[i, r]))
        for j, i in enumerate(held):
            matrix[n + j][:n] = [Fraction(int(x)) for x in C[i]]
            rhs[n + j] = Fraction(int(g[i]))
        for j, i in enumerate(stick):
            matrix[n + len(held) + j][:n] = [Fraction(int(x)) for x in T[i]]
        z = solve_rational(matrix, rhs)
        if z is None:
            continue
        u = z[:n]
        gaps = [int(g[i]) - sum(int(C[i, k]) * u[k] for k in range(n)) for i in range(m)]
        slips = [sum(int(T[i, k]) * u[k] for k in range(n)) for i in range(m)]
        lam_N, lam_T = [Fraction(0)] * m, [Fraction(turn[i] * int(s[i])) for i in range(m)]
        for j, i in enumerate(held):
            lam_N[i] = z[n + j]
        for j, i in enumerate(stick):
            lam_T[i] = z[n + len(held) + j]
        if (all(lam_N[i] >= 0 for i in held) and all(gaps[i] >= 0 for i in range(m))
                and all(abs(lam_T[i]) <= int(s[i]) for i in stick)
                and all(turn[i] * slips[i] >= 0 for i in range(m) if turn[i])):
            found.append((u, lam_N, lam_T))
    return found


def as_float(values) -> np.ndarray:
    return np.array([float(v) for v in values])


@pytest.mark.parametrize("seed", SEEDS)
def test_tresca_has_one_exact_answer_that_mixes_states(seed):
    """The enumeration finds exactly one answer (Tresca is convex, K positive definite) and
    it has open, closed, sticking and slipping contacts between the seeds."""
    found = exact_tresca(seed)
    assert len(found) == 1


@pytest.mark.parametrize("method", BACKENDS)
@pytest.mark.parametrize("seed", SEEDS)
def test_duals_are_the_friction_forces_for_every_backend(seed, method):
    """Every backend's friction forces (the duals α − β of the rows on t, or the dual box
    QP's answer for quadprog and ECOS) agree with the exact rational λ_T, within the bound
    the check states for that answer; every backend's answer is verified (within 1e-6 of F
    and U)."""
    K, f, C, g, T, s = integer_problem(seed)
    model = friction_model(K, f, C, g, T)
    answer = solve_tresca(model, s, method=method)
    verdict = check_tresca(model, s, answer)
    u, lam_N, lam_T = exact_tresca(seed)[0]
    error = max(np.abs(answer.friction_force[:, 0] - as_float(lam_T)).max(),
                np.abs(answer.normal_force - as_float(lam_N)).max())
    # the bound is measured, not assumed: it must contain the true error (1e-12 of F for the
    # float rounding of the exact answer itself)
    assert error <= verdict.force_error_bound + 1e-12 * verdict.residuals.force_scale
    assert np.abs(answer.u - as_float(u)).max() <= (verdict.displacement_error_bound
                                                    + 1e-12 * verdict.displacement_scale)
    assert verdict.verified or method in LOOSE, (method, verdict.verdict, verdict.residuals)


def test_the_exact_route_is_exact():
    """The active set's answer is the exact rational one up to round-off (1e-13 of F)."""
    for seed in SEEDS:
        K, f, C, g, T, s = integer_problem(seed)
        answer = solve_tresca(friction_model(K, f, C, g, T), s)
        _, lam_N, lam_T = exact_tresca(seed)[0]
        scale = max(np.abs(f).max(), as_float(lam_N).max())
        assert np.abs(answer.friction_force[:, 0] - as_float(lam_T)).max() <= 1e-13 * scale
        assert answer.status == "solved"


def test_dual_of_the_primal_qp_reads_alpha_minus_beta():
    """The primal QP's stationarity in t is s − α − β = 0: the duals of the two rows on t
    add up to the bound and their difference is the friction force (Clarabel's duals)."""
    import clarabel
    import scipy.sparse as sp

    K, f, C, g, T, s = integer_problem(17)
    model = friction_model(K, f, C, g, T)
    law = coulomb(model, 0.0)  # only for its shape; the bounds below are Tresca's
    from contactqp.friction.law import tresca

    law = tresca(model, s)
    qp = primal_qp(model, law, np.zeros(3))
    options = clarabel.DefaultSettings()
    options.verbose = False
    found = clarabel.DefaultSolver(sp.csc_matrix(sp.triu(qp.P)), qp.q, sp.csc_matrix(qp.G),
                                   qp.h, [clarabel.NonnegativeConeT(qp.h.size)],
                                   options).solve()
    z = np.asarray(found.z)
    alpha, beta = z[3:6], z[6:9]
    _, _, lam_T = exact_tresca(17)[0]
    np.testing.assert_allclose(alpha + beta, s, atol=1e-7)
    np.testing.assert_allclose(alpha - beta, as_float(lam_T), atol=1e-7)


def three_d_problem():
    """Four nodes (u_x, u_y, u_n) with a random positive definite K: 3D Tresca's SOCP."""
    rng = np.random.default_rng(5)
    nodes = 4
    n = 3 * nodes
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    C, T = np.zeros((nodes, n)), np.zeros((2 * nodes, n))
    for i in range(nodes):
        C[i, 3 * i + 2], T[2 * i, 3 * i], T[2 * i + 1, 3 * i + 1] = -1.0, 1.0, 1.0
    f = np.zeros(n)
    f[2::3], f[0::3], f[1::3] = [-20, -15, -1, -10], [3, -8, 4, 1], [2, 5, -3, 0.5]
    return friction_model(K, f, C, [0.0, 0.1, 0.5, 0.0], T), [2.0, 3.0, 1.0, 4.0]


@pytest.mark.parametrize("method", ["active_set", "clarabel", "cvxpy"])
def test_three_d_tresca_is_a_cone_program_every_route_agrees(method):
    """3D Tresca (a disc per contact): the SOCP's cone duals are the friction forces, equal
    to the exact route's within each answer's bound; ‖λ_T‖ ≤ s, and s along the slip where
    it slips. cvxpy at its default tolerances (Clarabel's, on the gap) recovers the cone
    duals to about 1e-4 of F here: bounded, not verified."""
    model, s = three_d_problem()
    answer = solve_tresca(model, s, method=method)
    verdict = check_tresca(model, s, answer)
    exact = solve_tresca(model, s)
    assert list(exact.state) == ["slip", "slip", "open", "stick"]
    bound = verdict.force_error_bound
    assert np.abs(answer.forces - exact.forces).max() <= bound + 1e-12
    size = np.linalg.norm(answer.friction_force, axis=1)
    assert np.all(size <= np.array(s) + bound)
    for i in np.flatnonzero(exact.state == "slip"):
        along = exact.slip[i] / np.linalg.norm(exact.slip[i])
        np.testing.assert_allclose(answer.friction_force[i], s[i] * along, atol=bound + 1e-12)
    assert verdict.verified or method == "cvxpy"


def test_nonunique_coulomb_three_exact_answers_and_methods_disagree():
    """One node, μ = 3, three exact Coulomb answers (open, stick, slip: the closed forms in
    the example's docstring); each is verified by the Coulomb check, whose verdict says it
    need not be the only one; the fixed point and the cone sequence land on different ones."""
    model, mu = nonunique_coulomb()
    found = all_answers(model, coulomb(model, mu))
    by_u = sorted((tuple(np.round(u, 9)), tuple(np.round(lam, 9))) for u, lam in found)
    assert by_u == [((0.0, 0.0), (1.0, 2.5)), ((1.0, 0.0), (0.5, 1.5)),
                    ((round(8 / 3, 9), round(1 / 3, 9)), (0.0, 0.0))]
    fixed = solve_coulomb(model, mu, method="fixed_point")
    cone = solve_coulomb(model, mu, method="cone")
    assert fixed.state[0] == "open" and cone.state[0] == "stick"
    for answer in (fixed, cone):
        verdict = check_coulomb(model, mu, answer)
        assert verdict.verified and "need not be unique" in verdict.verdict


def test_fixed_point_cycles_visibly_and_the_active_set_finds_the_answer():
    """s ← μλ_N(s) cycles between the bounds 3 and 4.5 (the example's docstring): status
    'not converged', the history alternating; the active set on Coulomb's sets finds the one
    answer, s* = 3.6 (u_t = 0.4, λ_N = 1.2)."""
    model, mu = cycling_fixed_point()
    fixed = solve_coulomb(model, mu, method="fixed_point", options={"max_iterations": 12})
    assert fixed.status == "not converged" and fixed.iterations == 12
    assert np.allclose(fixed.history[2::2], fixed.history[2]) and fixed.history[-1] > 0.3
    assert not check_coulomb(model, mu, fixed).verified
    exact = solve_coulomb(model, mu, method="active_set")
    assert exact.status == "solved"
    np.testing.assert_allclose(exact.u, [0.4, 0.0], atol=1e-12)
    np.testing.assert_allclose([exact.normal_force[0], exact.friction_force[0, 0]], [1.2, 3.6])
    assert [len(all_answers(model, coulomb(model, mu)))] == [1]


def test_relaxation_lifts_a_sliding_block_off_the_flat():
    """Coulomb: the block slides on the flat, u = (0.4, 0), λ_N = 2 (fixed point and cone
    agree). The convex relaxation (σ = 0) keeps u_n = μu_t: u = (0.32, 0.16), λ_N = 3.6, a gap
    of 0.16 while pushing; its Coulomb check is not verified and names the contact residual."""
    model, mu = sliding_block()
    for method in ("fixed_point", "cone"):
        answer = solve_coulomb(model, mu, method=method)
        np.testing.assert_allclose(answer.u, [0.4, 0.0], atol=1e-8)
        np.testing.assert_allclose(answer.normal_force, [2.0], atol=1e-8)
    relaxed = solve_coulomb(model, mu, method="relaxed")
    np.testing.assert_allclose(relaxed.u, [0.32, 0.16], atol=1e-8)
    np.testing.assert_allclose(relaxed.normal_force, [3.6], atol=1e-7)
    assert relaxed.info["separation"] == pytest.approx(0.16, abs=1e-8)
    verdict = check_coulomb(model, mu, relaxed)
    assert not verdict.verified and verdict.residuals.contact > 0.05


@pytest.mark.parametrize("force", [0.5, 0.25])
def test_frictional_bed_exact_where_a_node_falls_at_the_slip_length(force):
    """x_s = F/τ on a node: the answer is the closed form at every node to round-off
    (within 1e-9 of it, the goal), and so is the slip length read from the pull-out."""
    bed = frictional_bed(length=1.0, axial_stiffness=2.0, elements=40, tau=1.5,
                         force=force * 1.5)
    answer = solve_tresca(bed.model, bed.slip_bound)
    exact = bed_displacement(bed.x, bed.force, bed.tau, bed.axial_stiffness)
    assert np.abs(answer.u - exact).max() <= 1e-9 * np.abs(exact).max()
    assert slip_length(bed, answer) == pytest.approx(force, abs=1e-9)
    assert check_tresca(bed.model, bed.slip_bound, answer).verified


def test_frictional_bed_error_falls_as_h_squared():
    """x_s off the nodes: the discrete answer is the parabola lowered by τ(x_k − x_s)²/(2EA)
    (bed.py), so the error is at most τh²/(2EA) and, with x_s at the same place within an
    element (N = 40, 160, 640: x_s/h = 21.2, 84.8, 339.2), it falls by 16 per 4 times finer."""
    errors = []
    for elements in (40, 160, 640):
        bed = frictional_bed(elements=elements, force=0.53)
        answer = solve_tresca(bed.model, bed.slip_bound)
        exact = bed_displacement(bed.x, bed.force, bed.tau, bed.axial_stiffness)
        error = np.abs(answer.u - exact).max()
        assert error <= (1.0 / elements) ** 2 / 2.0
        errors.append(error)
    assert errors[0] / errors[1] == pytest.approx(16.0, rel=1e-6)
    assert errors[1] / errors[2] == pytest.approx(16.0, rel=1e-6)


def test_floating_bed_by_a_qp_backend_equals_the_held_one():
    """Holding the far end (where the bar sticks anyway) changes nothing: Clarabel on the bar
    held by friction alone (K singular) gives the same displacements."""
    held = frictional_bed(elements=20, force=0.5)
    floating = frictional_bed(elements=20, force=0.5, floating=True)
    exact = solve_tresca(held.model, held.slip_bound)
    free = solve_tresca(floating.model, floating.slip_bound, method="clarabel")
    np.testing.assert_allclose(free.u, exact.u, atol=1e-8)


def test_load_path_slip_is_measured_from_the_previous_increment():
    """One node: pressed (increment 1), then pulled to 0.8 μP (2), then back to 0 (3). It
    sticks in 1 and 2 (slip zero), and in 3 too: unloading an elastic spring in stick does
    not slip back. Then pulled past μP (4): it slips by the excess, measured from 3's u."""
    K = np.array([[4.0, 0.0], [0.0, 4.0]])
    model = friction_model(K, [0.0, 0.0], [[0.0, -1.0]], [0.0], [[1.0, 0.0]],
                           prescribed=None)
    steps = [{"f": [0.0, -10.0]}, {"f": [4.0, -10.0]}, {"f": [0.0, -10.0]},
             {"f": [7.0, -10.0]}]
    path = load_path(model, steps, mu=0.5)
    assert [inc.answer.stick[0] for inc in path] == [True, True, True, False]
    assert path[3].answer.slip[0, 0] == pytest.approx((7.0 - 5.0) / 4.0)
    assert path[3].answer.u[0] == pytest.approx(0.5)
    for inc in path:
        assert check_coulomb(inc.model, 0.5, inc.answer, inc.previous_u).verified


def test_residuals_report_a_friction_force_past_its_bound():
    """An answer whose friction force is moved past its bound reports it in 'cone' and in
    the natural map, as the fraction of F it was moved by."""
    K, f, C, g, T, s = integer_problem(17)
    model = friction_model(K, f, C, g, T)
    answer = solve_tresca(model, s)
    import dataclasses

    pushed = answer.friction_force.copy()
    slipping = int(np.flatnonzero(answer.state == "slip")[0])
    pushed[slipping] *= 1.1
    wrong = dataclasses.replace(answer, friction_force=pushed)
    residuals = friction_residuals(model, wrong, slip_bound=s)
    moved = 0.1 * s[slipping] / residuals.force_scale
    assert residuals.cone == pytest.approx(moved)
    assert residuals.friction_law == pytest.approx(moved)


@pytest.mark.parametrize(("call", "message"), [
    (lambda m: solve_tresca(m, [1.0, -1.0, 1.0]), "slip_bound: -1 is negative"),
    (lambda m: solve_tresca(m, [1.0, 1.0]), "slip_bound: shape (2,)"),
    (lambda m: solve_tresca(m, 1.0, method="nope"), "method: 'nope' unknown"),
    (lambda m: solve_tresca(m, 1.0, method="osqp", options={"formulation": "x"}),
     "formulation: 'x'"),
    pytest.param(
        lambda m: solve_tresca(m, 1.0, method="quadprog", options={"formulation": "primal"}),
        "quadprog needs a positive definite Hessian", marks=pytest.mark.skipif(
            importlib.util.find_spec("quadprog") is None, reason="quadprog is not installed")),
    (lambda m: solve_coulomb(m, 0.3, method="clarabel"), "unknown for Coulomb"),
    (lambda m: solve_tresca(m, 1.0, options={"tolerance": 1}), "unknown for 'active_set'"),
    (lambda m: solve_tresca(m, 1.0, previous_u=np.zeros(3)), "previous_u: shape (3,)"),
])
def test_every_bad_input_is_one_line(call, message):
    K, f, C, g, T, _ = integer_problem(17)
    model = friction_model(K, f, C, g, T)
    with pytest.raises((ProblemError, OptionError)) as caught:
        call(model)
    assert message in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize(("arrays", "message"), [
    ({"T": np.zeros((4, 6))}, "T: 4 rows for 3 contacts"),
    ({"K": -np.eye(6)}, "K: not positive definite"),
    ({"K": np.triu(np.ones((6, 6)))}, "K: not symmetric"),
    ({"f": np.zeros(5)}, "f: shape (5,)"),
])
def test_bad_models_are_refused_in_one_line(arrays, message):
    K, f, C, g, T, _ = integer_problem(17)
    given = {"K": K, "f": f, "C": C, "g": g, "T": T, **arrays}
    with pytest.raises(ProblemError) as caught:
        model = friction_model(given["K"], given["f"], given["C"], given["g"], given["T"])
        solve_tresca(model, 1.0)
    assert message in str(caught.value)
