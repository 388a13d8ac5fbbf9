"""A user's problem solved by every method and checked: no verified answer past its bound.

The exact answers are independent of contactqp: random spring networks with integer
stiffnesses and loads, rows with 1-4 integer coefficients and dyadic gaps (exact in binary), so
that every number is a Fraction and the active sets are enumerated in exact arithmetic
(:func:`exact_answer`). Glossary: K stiffness, f loads, C rows, g gaps, u displacements, λ
contact forces (λ >= 0, acting as −Cᵀλ), F and U the problem's force and displacement scales.
"""

from fractions import Fraction
from itertools import combinations

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp.errors import OptionError, ProblemError, SolverError
from contactqp.methods.complementarity import LCP_ROWS

# the bound holds up to the round-off of comparing floats with the exact answer: a few
# hundred units in the last place of F and U (the check's residual r* = K u* − f + Cᵀλ* is
# itself computed in floating point)
ROUND_OFF = 1e-13


def solve_exactly(A: list[list[Fraction]], b: list[Fraction]) -> list[Fraction] | None:
    """Gaussian elimination in fractions; None when the matrix is singular."""
    n = len(b)
    M = [row[:] + [b[i]] for i, row in enumerate(A)]
    for col in range(n):
        pivot = next((r for r in range(col, n) if M[r][col] != 0), None)
        if pivot is None:
            return None
        M[col], M[pivot] = M[pivot], M[col]
        for r in range(n):
            if r != col and M[r][col] != 0:
                factor = M[r][col] / M[col][col]
                M[r] = [a - factor * p for a, p in zip(M[r], M[col])]
    return [M[i][n] / M[i][i] for i in range(n)]


class Infeasible(AssertionError):
    """No u satisfies the rows (a draw to skip)."""


def exact_answer(problem: contactqp.Problem) -> tuple[np.ndarray, np.ndarray]:
    """(u, λ) by enumerating the sets of rows held on their gaps, in exact arithmetic: the
    first set whose KKT solution pulls on no row and passes no gap."""
    K, C = problem.K.toarray(), problem.C.toarray()
    free = [i for i in range(problem.n) if i not in set(problem.prescribed.tolist())]
    fixed = dict(zip(problem.prescribed.tolist(), map(Fraction, problem.prescribed_values)))
    Kf = [[Fraction(K[i, j]) for j in free] for i in free]
    P = [Fraction(problem.f[i]) - sum(Fraction(K[i, d]) * v for d, v in fixed.items())
         for i in free]
    Cf = [[Fraction(C[r, j]) for j in free] for r in range(problem.m)]
    g = [Fraction(x) for x in problem.g]
    equality = [r for r in range(problem.m) if problem.kinds[r] == "equality"]
    others = [r for r in range(problem.m) if r not in equality]
    for size in range(len(others) + 1):
        for chosen in combinations(others, size):
            rows = equality + list(chosen)
            n, k = len(free), len(rows)
            A = [Kf[i] + [Cf[r][i] for r in rows] for i in range(n)]
            A += [Cf[r] + [Fraction(0)] * k for r in rows]
            x = solve_exactly(A, P + [g[r] for r in rows])
            if x is None:
                continue
            u, lam_rows = x[:n], x[n:]
            lam = [Fraction(0)] * problem.m
            for r, value in zip(rows, lam_rows):
                lam[r] = value
            gaps_ok = all(sum(c * v for c, v in zip(Cf[r], u)) <= g[r] for r in others)
            if gaps_ok and all(lam[r] >= 0 for r in chosen):
                full = np.zeros(problem.n)
                full[free] = [float(v) for v in u]
                for d, v in fixed.items():
                    full[d] = float(v)
                return full, np.array([float(v) for v in lam])
    raise Infeasible("no set of rows gives the exact answer: no u satisfies the rows")


def random_problem(seed: int, degenerate: str = "") -> contactqp.Problem:
    """A spring network of 5-9 dofs (a random tree plus extra springs, integer stiffnesses),
    grounded or held by a prescribed dof, integer loads, 1-6 rows of 1-4 integer
    coefficients on the free dofs, gaps in eighths. ``degenerate``: "touching" adds a row
    that the exact answer touches with zero force; "redundant" adds the sum of two rows
    that push, with the sum of their gaps."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 10))
    K = np.zeros((n, n))
    edges = [(int(rng.integers(0, i)), i) for i in range(1, n)]
    edges += [tuple(int(v) for v in rng.choice(n, 2, replace=False)) for _ in range(n // 2)]
    for i, j in edges:
        k = float(rng.integers(1, 10))
        K[i, i] += k
        K[j, j] += k
        K[i, j] -= k
        K[j, i] -= k
    prescribed = [int(rng.integers(0, n))] if rng.random() < 0.5 else []
    if not prescribed:
        for i in rng.choice(n, int(rng.integers(1, 3)), replace=False):
            K[i, i] += float(rng.integers(1, 5))
    free = [i for i in range(n) if i not in prescribed]
    rows = []
    count = int(rng.integers(1, 7))
    while len(rows) < count:
        row = np.zeros(n)
        dofs = rng.choice(free, min(len(free), int(rng.integers(1, 5))), replace=False)
        row[dofs] = rng.choice([-2.0, -1.0, 1.0, 2.0], dofs.size)
        unit = row / np.linalg.norm(row)
        if all(abs(abs(unit @ r) / np.linalg.norm(r) - 1.0) > 1e-9 for r in rows):
            rows.append(row)
    C = np.array(rows)
    f = rng.integers(-9, 10, n).astype(float)
    g = rng.integers(-2, 6, len(rows)) / 8.0
    values = [float(rng.integers(-4, 5)) / 4.0] if prescribed else None
    problem = contactqp.Problem(sp.csr_array(K), f, sp.csr_array(C), g, prescribed=prescribed,
                                prescribed_values=values)
    return _degenerate(problem, degenerate, rng) if degenerate else problem


def _degenerate(problem, kind, rng):
    try:
        u, lam = exact_answer(problem)
    except Infeasible:
        return None
    C, g = problem.C.toarray(), problem.g
    if kind == "touching":
        row = np.zeros(problem.n)
        free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
        row[rng.choice(free, min(2, free.size), replace=False)] = [1.0, -1.0][:min(2, free.size)]
        new, gap = row, float(row @ u)  # the exact answer touches it, with no force
    else:
        pushing = np.flatnonzero(lam > 0)
        if pushing.size < 2:
            return None
        a, b = pushing[:2]
        new, gap = C[a] + C[b], g[a] + g[b]
    unit = new / np.linalg.norm(new)
    if any(abs(abs(unit @ r) / np.linalg.norm(r) - 1.0) < 1e-9 for r in C):
        return None  # the row is there already: draw again
    return contactqp.Problem(problem.K, problem.f, sp.csr_array(np.vstack((C, new))),
                             np.append(g, gap), prescribed=problem.prescribed,
                             prescribed_values=problem.prescribed_values)


SETTINGS = [("lagrange", {}), ("penalty", {}), ("augmented", {}), ("lemke", {}), ("pgs", {}),
            ("semismooth_newton", {}), ("semismooth_newton", {"ncp": "fischer-burmeister"}),
            ("qp", {"backend": "clarabel"}), ("qp", {"backend": "osqp"}),
            ("qp", {"backend": "osqp", "accuracy": "high"})]
QPSOLVERS = ["daqp", "quadprog", "proxqp", "piqp", "highs", "ecos", "scs", "cvxopt"]
try:
    INSTALLED = {s.solver for s in contactqp.available_qp_solvers()
                 if s.available and s.backend == "qpsolvers"}
except Exception:  # noqa: BLE001 - the test then covers the backends above
    INSTALLED = set()
SETTINGS += [("qp", {"backend": "qpsolvers", "solver": s}) for s in QPSOLVERS if s in INSTALLED]


def dependent(problem, u, lam) -> bool:
    """Whether the rows the exact answer holds (pushing or touching) are linearly dependent:
    then λ is not unique, only the forces on the dofs, Cᵀλ."""
    C = problem.C.toarray()
    held = (lam > 0) | (np.abs(C @ u - problem.g) <= 1e-12 * max(1.0, np.abs(problem.g).max()))
    return bool(np.linalg.matrix_rank(C[held]) < np.count_nonzero(held)) if held.any() else False


def assert_within_bounds(result, u, lam, redundant=None):
    """A verified answer is within its own bounds (and the guarantee) of the exact one; where
    the rows held are dependent (``redundant``; None: worked out), on the forces Cᵀλ."""
    if not result.verified:
        return False
    F, U = result.force_scale, result.displacement_scale
    if redundant is None:
        redundant = dependent(result.problem, u, lam)
    if redundant:  # λ is not unique: compare the forces on the dofs, Cᵀλ
        C = result.problem.C
        error = float(np.abs(C.T @ (result.contact_force - lam)).max())
        allowed = result.force_error_bound * float(abs(C).sum(axis=0).max())
    else:
        error, allowed = float(np.abs(result.contact_force - lam).max(initial=0.0)), (
            result.force_error_bound)
    assert error <= allowed + ROUND_OFF * F, (result.label, error, allowed)
    moved = float(np.abs(result.u - u).max())
    assert moved <= result.displacement_error_bound + ROUND_OFF * U, (result.label, moved)
    assert result.force_error_bound <= 1e-5 * F and result.displacement_error_bound <= 1e-5 * U
    return True


def solved_or_refused(problem, method: str, options: dict, u, lam) -> bool:
    """assert_within_bounds of the method's answer, or False where it refuses in one line
    (a SolverError: augmented's active set cycles on random_problem(1010000), four rows held
    that nearly repeat each other's constraint; lagrange solves it)."""
    try:
        result = contactqp.solve(problem, method, **options)
    except SolverError as refusal:
        assert "\n" not in str(refusal)
        return False
    return assert_within_bounds(result, u, lam)


@pytest.mark.parametrize("seed", range(12))
def test_no_verified_answer_past_its_bound(seed):
    problem = random_problem(seed)
    u, lam = exact_answer(problem)
    verified = [solved_or_refused(problem, method, options, u, lam)
                for method, options in SETTINGS]
    assert verified[0]  # Lagrange is exact: its answer is verified


@pytest.mark.parametrize("kind", ["touching", "redundant"])
@pytest.mark.parametrize("seed", [*range(6), 404005])
def test_degenerate_rows(seed, kind):
    problem, draw = None, 100 + 10 * seed
    while problem is None:  # the first draw from here that takes the row (two that push);
        try:  # a draw whose rows no u meets is refused, with its certificate: the next one
            problem = random_problem(draw, kind)
        except ProblemError:
            problem = None
        draw += 1
    u, lam = exact_answer(problem)
    for method, options in SETTINGS[:8]:
        try:
            result = contactqp.solve(problem, method, **options)
        except SolverError:  # a method may refuse a singular W; it claims nothing
            continue
        assert_within_bounds(result, u, lam)


def test_mixed_equality_rows_by_lagrange_penalty_and_augmented():
    base = random_problem(7)
    kinds = ["equality"] + ["inequality"] * (base.m - 1)
    problem = contactqp.Problem(base.K, base.f, base.C, base.g, prescribed=base.prescribed,
                                prescribed_values=base.prescribed_values, kinds=kinds)
    u, lam = exact_answer(problem)
    for method in ("lagrange", "penalty", "augmented"):
        assert_within_bounds(contactqp.solve(problem, method), u, lam)
    assert contactqp.solve(problem).verified
    with pytest.raises(OptionError, match="mixes"):
        contactqp.solve(problem, "lemke")


def test_a_wrong_answer_is_not_verified():
    problem = random_problem(3)
    right = contactqp.solve(problem)
    lam = right.contact_force * 1.01 + 1e-3 * right.force_scale  # 1 % off, every row pushing
    found = contactqp.check(problem, right.u, lam)
    assert not found.verified and found.force_error_bound > 1e-3 * right.force_scale


def test_nitsche_and_chain_options_are_refused_with_the_reason():
    problem = random_problem(1)
    with pytest.raises(OptionError, match="nitsche needs the traction"):
        contactqp.solve(problem, "nitsche")
    with pytest.raises(OptionError, match="applies to bar scenes only"):
        contactqp.solve(problem, "lagrange", active_set="hull")
    with pytest.raises(OptionError, match="formulation"):
        contactqp.solve(problem, "lagrange", formulation="condensed")


def test_the_lcp_methods_refuse_beyond_their_stated_size():
    n = LCP_ROWS + 1  # a row on every dof: one row more than W may have
    K = sp.diags_array(np.full(n, 2.0)).tocsr()
    problem = contactqp.Problem(K, np.ones(n), sp.eye_array(n, format="csr"), np.full(n, 0.1))
    with pytest.raises(SolverError, match="use lagrange") as refusal:  # lemke's limit is lower
        contactqp.solve(problem, "pgs")
    # the problem's own words: its rows, not a bar scene's nodes
    message = str(refusal.value)
    assert f"this problem has {n} contact rows" in message
    assert "scene" not in message and "node" not in message
    # a wall at 0.1 holds each dof: λ = 1 − 2·0.1; semismooth Newton (min) past the LCP's size
    # takes set solves, without W
    for method in ("penalty", "semismooth_newton"):
        result = contactqp.solve(problem, method)
        assert result.verified and np.allclose(result.contact_force, 0.8, rtol=1e-5), method
    assert result.info["route"] == "set solves"


def test_the_result_reads_like_a_scene_result():
    result = contactqp.solve(random_problem(2))
    text = result.summary()
    assert "verified" in text and "residuals" in text
    data = result.to_dict()
    assert data["contact_force"] == pytest.approx(result.contact_force.tolist())
    assert set(data) >= {"u", "reactions", "penetration", "verified", "force_error_bound"}
    assert '"verified"' in result.to_json()


def test_a_model_held_by_contact_alone():
    """Three unit springs in a row, no support: a load of 1 at dof 3 pushes the chain towards
    a wall at dof 0 (u_0 >= 0). K is singular; the wall holds it: λ = 1, u = [0, −1, −2, −3]
    (each spring shortened by the force it carries)."""
    n = 4
    K = sp.diags_array([-np.ones(n - 1), np.r_[1.0, 2.0, 2.0, 1.0], -np.ones(n - 1)],
                       offsets=[-1, 0, 1]).tocsr()
    C = sp.csr_array(([-1.0], ([0], [0])), shape=(1, n))
    problem = contactqp.Problem(K, -np.eye(n)[n - 1], C, [0.0])
    for method, options in [("lagrange", {}), ("qp", {}), ("qp", {"backend": "osqp"})]:
        result = contactqp.solve(problem, method, **options)
        assert_within_bounds(result, np.array([0.0, -1.0, -2.0, -3.0]), np.array([1.0]))
        assert result.verified or method != "lagrange"
    for method in ("lemke", "pgs", "semismooth_newton"):
        with pytest.raises(SolverError, match="needs K⁻¹") as refusal:
            contactqp.solve(problem, method)
        assert "scene" not in str(refusal.value) and "node" not in str(refusal.value)
