"""Problems with friction through the public API: contactqp.Problem(K, f, C, g, T=T, mu=μ or
slip_bound=s), contactqp.solve(problem, method, previous=result), the Result's friction
forces, states and slips, the files, and every bad input in one line.

Glossary: K stiffness, f load, C/g normal rows and gaps, T tangential rows (d per contact),
s Tresca's slip bounds, μ Coulomb's coefficients, λ_N normal forces (acting as −Cᵀλ_N), λ_T
friction forces (acting as −Tᵀλ_T, along the slip), F the check's force scale, U its
displacement scale, P and Q the normal and tangential loads of Cattaneo–Mindlin, a the
contact half-width, c the stick zone's, p₀ the peak pressure, q the friction traction.

Every expected number comes from a closed form, exact rational arithmetic (the enumeration
of test_friction.exact_tresca) or another method; none is a printout of the code under test.
"""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
import qpsolvers
import scipy.sparse as sp

import contactqp
from contactqp.errors import OptionError, ProblemError
from test_friction import SEEDS, as_float, exact_tresca, integer_problem
from test_problem_hostile import one_line

# one node (u_t, u_n) on a flat u_n ≥ 0 (the row −u_n ≤ 0), the tangential row reading u_t
ON_FLAT = {"C": [[0.0, -1.0]], "g": [0.0], "T": [[1.0, 0.0]]}
# ECOS (on the dual box QP) ends with INACC_OFFSET here, its forces 1e-6 to 1e-5 of F off:
# bounded by the check, not verified
LOOSE = ("ecos",)
QP_ROUTES = ([("clarabel", None), ("clarabel-dual", None), ("cvxpy", None)]
             + [("qpsolvers", name) for name in qpsolvers.available_solvers])


def integer(seed: int, **law) -> contactqp.Problem:
    K, f, C, g, T, s = integer_problem(seed)
    return contactqp.Problem(K, f, C, g, T=T, **(law or {"slip_bound": s}))


# --------------------------------------------------------------------- the Problem's fields

def test_friction_fields_are_owned_read_only_copies_and_scalars_broadcast():
    T = np.array([[1.0, 0.0]])
    mu = np.array([0.4])
    problem = contactqp.Problem(np.eye(2), [1.0, -1.0], T=T, mu=mu, **{
        k: v for k, v in ON_FLAT.items() if k != "T"})
    T[0, 0], mu[0] = 7.0, 9.0
    assert problem.T.toarray().tolist() == [[1.0, 0.0]] and problem.mu.tolist() == [0.4]
    assert not problem.mu.flags.writeable and not problem.T.data.flags.writeable
    assert (problem.friction, problem.contacts, problem.d) == ("coulomb", 1, 1)
    three_d = contactqp.Problem(np.eye(3), [0, 0, -1.0], [[0, 0, -1.0]], [0.0],
                                T=[[1.0, 0, 0], [0, 1.0, 0]], slip_bound=2.0)
    assert (three_d.friction, three_d.d, three_d.slip_bound.tolist()) == ("tresca", 2, [2.0])
    assert contactqp.Problem(np.eye(2), [1.0, 0], **{k: v for k, v in ON_FLAT.items()
                                                      if k != "T"}).friction is None


@pytest.mark.parametrize("name", ["p.npz", "folder"])
@pytest.mark.parametrize("law", [{"mu": [0.5, 0.0, 2.0]}, {}], ids=["mu", "slip_bound"])
def test_friction_makes_the_round_trip_through_files(tmp_path, name, law):
    problem = integer(17, **law)
    back = contactqp.load_problem(contactqp.save_problem(problem, tmp_path / name))
    assert np.array_equal(back.T.toarray(), problem.T.toarray())
    for key in ("mu", "slip_bound"):
        mine, theirs = getattr(problem, key), getattr(back, key)
        assert (mine is None and theirs is None) or np.array_equal(mine, theirs)
    if not law:  # the same answer from the file: the exact rational one (Tresca, s)
        _, lam_N, lam_T = exact_tresca(17)[0]
        result = contactqp.solve(back)
        assert np.abs(result.friction_force[:, 0] - as_float(lam_T)).max() <= 1e-12 * 10
        assert np.abs(result.contact_force - as_float(lam_N)).max() <= 1e-12 * 10


def test_a_folder_rewritten_without_friction_loses_its_T(tmp_path):
    contactqp.save_problem(integer(17), tmp_path / "folder")
    K, f, C, g, _, _ = integer_problem(17)
    contactqp.save_problem(contactqp.Problem(K, f, C, g), tmp_path / "folder")
    assert contactqp.load_problem(tmp_path / "folder").T is None


# ------------------------------------------------------------------- Tresca by every route

@pytest.mark.parametrize(("backend", "solver"), QP_ROUTES,
                         ids=[f"{b}-{s}" if s else b for b, s in QP_ROUTES])
@pytest.mark.parametrize("seed", SEEDS[:2])
def test_duals_are_the_friction_forces_through_the_public_api(seed, backend, solver):
    """solve(problem, "qp", backend=..., solver=...): the Result's friction forces (the QP's
    duals) and normal forces are the exact rational ones within the bound the Result states,
    and the answer is verified (ECOS: bounded only)."""
    options = {"backend": backend.removesuffix("-dual")}
    if solver:
        options["solver"] = solver
    if backend.endswith("-dual"):
        options["dual"] = True
    result = contactqp.solve(integer(seed), "qp", **options)
    u, lam_N, lam_T = exact_tresca(seed)[0]
    error = max(np.abs(result.friction_force[:, 0] - as_float(lam_T)).max(),
                np.abs(result.contact_force - as_float(lam_N)).max())
    assert error <= result.force_error_bound + 1e-12 * result.force_scale
    assert np.abs(result.u - as_float(u)).max() <= (result.displacement_error_bound
                                                    + 1e-12 * result.displacement_scale)
    assert result.verified or solver in LOOSE, result.summary()


@pytest.mark.parametrize("seed", SEEDS)
def test_lagrange_is_the_exact_answer_and_its_states_are_the_enumerations(seed):
    result = contactqp.solve(integer(seed))
    u, _, lam_T = exact_tresca(seed)[0]
    assert result.verified and result.friction == "tresca"
    assert np.abs(result.u - as_float(u)).max() <= 1e-12 * result.displacement_scale
    s = integer_problem(seed)[5]
    # the states of the exact answer: open where λ_N = 0 and the gap is open; slip where
    # |λ_T| = s and the slip is not zero
    _, _, C, g, T, _ = integer_problem(seed)
    gaps = [int(g[i]) - sum(int(C[i, k]) * u[k] for k in range(len(u))) for i in range(3)]
    slips = [sum(int(T[i, k]) * u[k] for k in range(len(u))) for i in range(3)]
    expected = ["open" if gaps[i] > 0 else "slip" if slips[i] != 0 and abs(lam_T[i]) == s[i]
                else "stick" for i in range(3)]
    assert list(result.state) == expected
    # stick: no slip in this increment (an open contact that moves, under Tresca, slips)
    assert result.stick.tolist() == [slip == 0 for slip in slips]
    np.testing.assert_allclose(result.slip[:, 0], as_float(slips), atol=1e-12)


def test_three_d_tresca_by_lagrange_and_by_the_cone_program_agree():
    """3D (two rows per contact): the exact route and Clarabel's SOCP, whose cone duals are
    the friction forces, agree within the bounds both Results state; ‖λ_T‖ ≤ s."""
    rng = np.random.default_rng(5)
    n = 12
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    C, T = np.zeros((4, n)), np.zeros((8, n))
    for i in range(4):
        C[i, 3 * i + 2], T[2 * i, 3 * i], T[2 * i + 1, 3 * i + 1] = -1.0, 1.0, 1.0
    f = np.zeros(n)
    f[2::3], f[0::3], f[1::3] = [-20, -15, -1, -10], [3, -8, 4, 1], [2, 5, -3, 0.5]
    s = np.array([2.0, 3.0, 1.0, 4.0])
    problem = contactqp.Problem(K, f, C, [0.0, 0.1, 0.5, 0.0], T=T, slip_bound=s)
    exact, cone = contactqp.solve(problem), contactqp.solve(problem, "qp")
    assert exact.verified and cone.verified
    assert exact.friction_force.shape == (4, 2)
    bound = exact.force_error_bound + cone.force_error_bound
    assert np.abs(exact.friction_force - cone.friction_force).max() <= bound
    assert np.all(np.linalg.norm(cone.friction_force, axis=1) <= s + bound)


# ------------------------------------------------------------ increments: previous=

def test_the_slip_of_an_increment_is_measured_from_previous():
    """One node pressed by P = 10 on a flat, a tangential spring k = 4 to the ground,
    Tresca's s = μP = 5. Pulled by 7 from rest it slips by (7 − 5)/4 = 0.5; pulled back to 2
    from there it sticks where it is (|2 − 4·0.5| = 0 ≤ 5): u_t = 0.5, slip 0, λ_T = 0. From
    rest the same load of 2 sticks at u_t = 0 with λ_T = 2: the answer depends on the path."""
    def problem(pull: float) -> contactqp.Problem:
        return contactqp.Problem(4.0 * np.eye(2), [pull, -10.0], **ON_FLAT, slip_bound=5.0)

    first = contactqp.solve(problem(7.0))
    assert first.u[0] == pytest.approx(0.5, abs=1e-14) and first.state.tolist() == ["slip"]
    back = contactqp.solve(problem(2.0), previous=first)
    assert back.u[0] == pytest.approx(0.5, abs=1e-14) and back.state.tolist() == ["stick"]
    assert back.slip[0, 0] == pytest.approx(0.0, abs=1e-14)
    assert back.friction_force[0, 0] == pytest.approx(0.0, abs=1e-13)
    fresh = contactqp.solve(problem(2.0))
    assert fresh.u[0] == pytest.approx(0.0, abs=1e-14)
    assert fresh.friction_force[0, 0] == pytest.approx(2.0, abs=1e-13)
    by_array = contactqp.solve(problem(2.0), previous=first.u)  # a u will do as well
    assert by_array.u[0] == pytest.approx(0.5, abs=1e-14)


def test_normal_first_then_tangential_from_the_pressed_state():
    """Two nodes tied by a spring k = 1 (tangential dofs 0 and 2, normal 1 and 3), each on
    the flat, each held tangentially to the ground by k₀ = 1; μ = 0.5. Pressed by P = 4 each
    (increment 1: no tangential load, no friction), then node 0 pulled by Q = 3 (increment
    2). With Coulomb's bound μP = 2 per node: node 0 carries what it can (2) and slips; the
    rest, 1, reaches node 1 through the springs. Closed form: node 0's u₀ and node 1's u₂ solve
    2u₀ − u₂ = 3 − 2 and −u₀ + 2u₂ = −λ_T1 with node 1 sticking (u₂ = 0): u₀ = ½, λ_T1 = ½ < 2."""
    K = np.zeros((4, 4))
    K[np.ix_([0, 2], [0, 2])] = [[2.0, -1.0], [-1.0, 2.0]]
    K[1, 1] = K[3, 3] = 1.0
    C = [[0, -1.0, 0, 0], [0, 0, 0, -1.0]]
    T = [[1.0, 0, 0, 0], [0, 0, 1.0, 0]]
    pressed = contactqp.Problem(K, [0, -4.0, 0, -4.0], C, [0, 0], T=T, mu=0.5)
    normal = contactqp.solve(pressed)
    assert np.allclose(normal.contact_force, [4.0, 4.0]) and np.allclose(normal.u, 0.0)
    pulled = contactqp.solve(pressed.with_values(f=[3.0, -4.0, 0, -4.0]), previous=normal)
    assert pulled.verified and pulled.state.tolist() == ["slip", "stick"]
    np.testing.assert_allclose(pulled.u, [0.5, 0, 0, 0], atol=1e-14)
    np.testing.assert_allclose(pulled.friction_force[:, 0], [2.0, 0.5], atol=1e-13)


# ---------------------------------------------------------- Cattaneo–Mindlin in 2D

def test_cattaneo_mindlin_two_cylinders_stick_zone_and_traction():
    """Two identical plane-strain cylinders (R = 10, E = 210e3, ν = 0.3, Dundurs' β = 0),
    pressed to a/R ≈ 0.03 and then sheared by moving the caps sideways, Coulomb μ = 0.3, each
    shear an increment from the pressed state. Closed forms (Johnson §7.1): a² = 4PR(1 −
    ν²)/(πE), p₀ = 2P/(πa), c/a = √(1 − Q/(μP)), q = μp₀[√(1 − x²/a²) − (c/a)√(1 − x²/c²)].

    This mesh (28 340 dofs, 97 pairs, pair spacing h = 0.026a at the contact) ran in about
    9 s. The stick zone's edge is read between the last sticking and the first slipping pair
    (±h/2); measured: c/a within 1.1 % at Q/μP = 0.2, 0.5, 0.8 (0.36h, 0.05h, 0.08h), and q
    within 0.13 % of its peak for |x| ≤ 0.9c. Asserted: |c − c_Cattaneo| ≤ h (the reading's
    h/2 and as much again for the mesh) and q within 1 % of its peak (the goal at 10⁵ dofs
    is 3 %; docs/friction.md has those numbers)."""
    pytest.importorskip("skfem", reason='scikit-fem is not installed (pip install "contactqp[fem]")')
    from contactqp.friction.cattaneo import cattaneo_cylinders

    R, E, nu, mu = 10.0, 210e3, 0.3, 0.3
    a_target = 0.03 * R
    cylinders = cattaneo_cylinders(R, E, nu, zone=1.25 * a_target, fine=a_target / 25,
                                   growth=0.1)
    x = cylinders.x
    edges = np.concatenate([x[:1], 0.5 * (x[1:] + x[:-1]), x[-1:]])
    tributary = np.diff(edges)
    problem = contactqp.Problem(**cylinders.arrays, mu=mu,
                                prescribed_values=cylinders.cap_values(0.0377, 0.0))
    normal = contactqp.solve(problem)
    assert normal.verified and np.abs(normal.friction_force).max() <= 1e-9 * normal.force_scale
    for shift in (0.00345, 0.00877, 0.01434):
        sheared = problem.with_values(prescribed_values=cylinders.cap_values(0.0377, shift))
        result = contactqp.solve(sheared, previous=normal)
        assert result.verified, result.message
        P, Q = result.contact_force.sum(), result.friction_force.sum()
        a = math.sqrt(4.0 * P * R * (1.0 - nu**2) / (math.pi * E))
        p0 = 2.0 * P / (math.pi * a)
        ratio = math.sqrt(1.0 - Q / (mu * P))
        sticking = x[result.state == "stick"]
        right = 0.5 * (sticking.max() + x[x > sticking.max()].min())
        left = 0.5 * (sticking.min() + x[x < sticking.min()].max())
        c = 0.5 * (right - left)
        h = float(np.diff(x)[np.abs(x[1:]) <= a].max())
        assert abs(c - ratio * a) <= h, (Q / (mu * P), c / a, ratio)
        q = result.friction_force[:, 0] / tributary
        inside = np.abs(x) <= 0.9 * ratio * a
        closed = mu * p0 * (np.sqrt(np.clip(1.0 - (x / a) ** 2, 0, None))
                            - ratio * np.sqrt(np.clip(1.0 - (x / (ratio * a)) ** 2, 0, None)))
        peak = mu * p0 * math.sqrt(1.0 - ratio**2)  # q's largest, at x = ±c
        assert np.abs(q - closed)[inside].max() <= 0.01 * peak


# ---------------------------------------------------------------- the frictional bed

@pytest.mark.parametrize(("method", "options"), [("lagrange", {}), ("qp", {}),
                                                 ("qp", {"backend": "osqp"})])
def test_frictional_bed_through_the_problem(method, options):
    """A bar (EA = 1, L = 1, 10 elements) on a bed of τ = 1 per length, pulled by F = 0.5 at
    x = 0, its far end held: contacts without a normal row (C with no rows), one tangential
    row per node, Tresca's bound τ × the node's length. The closed form: it slips over
    x_s = F/τ = 0.5 (a node), u = −τ(x_s − x)²/(2EA) there, zero beyond; exact at the nodes
    where a node falls at x_s (to 1e-9, the issue's goal; OSQP to its own accuracy)."""
    N, h = 10, 0.1
    K = sp.diags([np.r_[1.0, np.full(N - 1, 2.0), 1.0] / h, np.full(N, -1.0 / h),
                  np.full(N, -1.0 / h)], [0, -1, 1])
    f = np.zeros(N + 1)
    f[0] = -0.5
    bound = np.r_[h / 2, np.full(N - 1, h)]
    problem = contactqp.Problem(K, f, np.zeros((0, N + 1)), [], T=sp.eye(N, N + 1),
                                slip_bound=bound, prescribed=[N])
    assert (problem.contacts, problem.d) == (N, 1)
    result = contactqp.solve(problem, method, **options)
    x = np.linspace(0.0, 1.0, N + 1)
    exact = -np.clip(0.5 - x, 0.0, None) ** 2 / 2.0
    tolerance = 1e-9 if options.get("backend") != "osqp" else 1e-6
    assert np.abs(result.u - exact).max() <= tolerance
    assert result.state.tolist() == ["slip"] * 5 + ["stick"] * 5
    assert result.reactions[0] == pytest.approx(0.0, abs=tolerance)  # the bed holds all of F
    assert result.friction_force.sum() == pytest.approx(-0.5, abs=tolerance)


# ------------------------------------------------------ Coulomb: more than one answer

def exact_coulomb_answers():
    """The three answers of the non-unique case in exact fractions, each checked against
    Coulomb's law here: K = [[1, −½], [−½, 1]], f = (5/2, −1), the node on the flat, μ = 3."""
    K = [[Fraction(1), Fraction(-1, 2)], [Fraction(-1, 2), Fraction(1)]]
    f = [Fraction(5, 2), Fraction(-1)]
    answers = {"open": ([Fraction(8, 3), Fraction(1, 3)], Fraction(0), Fraction(0)),
               "stick": ([Fraction(0), Fraction(0)], Fraction(1), Fraction(5, 2)),
               "slip": ([Fraction(1), Fraction(0)], Fraction(1, 2), Fraction(3, 2))}
    for state, (u, lam_N, lam_T) in answers.items():
        # K u − f + Cᵀλ_N + Tᵀλ_T = 0 with C = (0, −1), T = (1, 0)
        assert K[0][0] * u[0] + K[0][1] * u[1] - f[0] + lam_T == 0
        assert K[1][0] * u[0] + K[1][1] * u[1] - f[1] - lam_N == 0
        assert u[1] >= 0 and lam_N >= 0 and lam_N * u[1] == 0 and abs(lam_T) <= 3 * lam_N
        assert (u[0] == 0) if state == "stick" else (lam_T == 3 * lam_N and u[0] * lam_T >= 0)
    return answers


def test_coulomb_is_not_unique_and_the_verdict_says_so():
    answers = exact_coulomb_answers()
    problem = contactqp.Problem([[1.0, -0.5], [-0.5, 1.0]], [2.5, -1.0], **ON_FLAT, mu=3.0)
    seen = {}
    for method in ("lagrange", "cone", "relaxed", "semismooth_newton"):
        result = contactqp.solve(problem, method)
        assert result.verified and "need not be unique" in result.message
        state = result.state[0]
        u, lam_N, lam_T = answers[state]
        np.testing.assert_allclose(result.u, [float(v) for v in u], atol=1e-8)
        assert result.friction_force[0, 0] == pytest.approx(float(lam_T), abs=1e-8)
        assert result.contact_force[0] == pytest.approx(float(lam_N), abs=1e-8)
        seen[method] = state
    assert len(set(seen.values())) >= 2, seen  # the methods land on different answers
    # a Tresca problem is convex: with s = 3/2 (the slip answer's bound) it has one answer
    tresca = contactqp.Problem(problem.K, problem.f, **ON_FLAT, slip_bound=1.5)
    assert contactqp.solve(tresca).u.tolist() == pytest.approx([1.0, 0.0], abs=1e-14)


def test_summary_and_json_show_the_friction():
    result = contactqp.solve(integer(17))
    text = result.summary()
    assert "friction (tresca): 3 contacts" in text and "tresca friction on 3 contacts" in text
    data = __import__("json").loads(result.to_json())
    assert data["friction"] == "tresca" and len(data["friction_force"]) == 3
    assert data["state"] == list(result.state) and data["stick"] == result.stick.tolist()
    frictionless = contactqp.solve(contactqp.Problem(*integer_problem(17)[:4]))
    assert frictionless.friction_force is None and "friction" not in frictionless.to_dict()


# ------------------------------------------------------------------- one line each

K2, F2 = np.eye(2), [1.0, -1.0]
BAD_FIELDS = [
    ({"T": [[1.0, 0.0]]}, ("T is given without mu",)),
    ({"mu": 0.3}, ("mu is given without T",)),
    ({"slip_bound": 1.0}, ("slip_bound is given without T",)),
    ({"T": [[1.0, 0.0]], "mu": 0.3, "slip_bound": 1.0}, ("mu and slip_bound are both given",)),
    ({"T": [[1.0, 0.0]], "mu": -0.1}, ("mu[0] = -0.1 is negative",)),
    ({"T": [[1.0, 0.0]], "mu": float("nan")}, ("mu[0] must be finite",)),
    ({"T": [[1.0, 0.0]], "mu": 0.3 + 0.1j}, ("mu has complex values",)),
    ({"T": [[1.0, 0.0]], "mu": "0.3"}, ("mu must be an array of numbers",)),
    ({"T": [[1.0, 0.0]], "mu": True}, ("mu has boolean values",)),
    ({"T": [[1.0, 0.0]], "slip_bound": [1.0, 2.0]}, ("slip_bound has 2 entries for 1",)),
    ({"T": [[1.0, 0.0]], "slip_bound": [[1.0]]}, ("slip_bound must be one value",)),
    ({"T": [[1.0, 0.0]], "slip_bound": -2.0}, ("slip_bound[0] = -2.0 is negative",)),
    ({"T": [[1.0, 0.0]], "slip_bound": 1e300}, ("slip_bound[0] = 1e+300 is outside",)),
    ({"T": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], "mu": 0.3}, ("T has 3 rows for 1 contacts",)),
    ({"T": [[1.0, 0.0, 0.0]], "mu": 0.3}, ("T must be mx2",)),
    ({"T": [[np.inf, 0.0]], "mu": 0.3}, ("T[0, 0] must be finite",)),
    ({"T": [[1j, 0.0]], "mu": 0.3}, ("T has complex values",)),
    ({"T": np.zeros((0, 2)), "mu": 0.3}, ("T has 0 rows for 1 contacts",)),
    ({"T": [[1.0, 0.0]], "mu": 0.3, "kinds": ["equality"]}, ("kinds: row 0 is an equality",)),
]


@pytest.mark.parametrize(("fields", "words"), BAD_FIELDS, ids=[w[0][:30] for _, w in BAD_FIELDS])
def test_bad_friction_fields_are_one_line(fields, words):
    args = {"C": [[0.0, -1.0]], "g": [0.0], **fields}
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K2, F2, **args)
    one_line(raised.value, *words)


def test_a_bed_takes_tresca_only_and_its_contacts_from_the_bounds():
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K2, F2, np.zeros((0, 2)), [], T=np.eye(2), mu=0.3)
    one_line(raised.value, "mu needs normal rows C")
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K2, F2, np.zeros((0, 2)), [], T=np.eye(2)[:1].repeat(3, 0),
                          slip_bound=[1.0, 1.0])
    one_line(raised.value, "T has 3 rows for 2 contacts")


@pytest.mark.parametrize(("method", "options", "words"), [
    ("penalty", {"penalty": -1.0}, ("penalty must be",)),
    ("augmented", {"backend": "osqp"}, ("option 'backend' does not apply to augmented",)),
    ("lemke", {}, ("lemke solves the LCP of normal contact",)),
    ("pgs", {}, ("pgs solves the LCP",)),
    ("nitsche", {}, ("nitsche needs the traction",)),
    ("cone", {}, ("cone is one of Coulomb's methods", "use lagrange or qp")),
    ("relaxed", {}, ("relaxed is one of Coulomb's methods",)),
    ("nope", {}, ("method must be one of lagrange, qp",)),
    ("qp", {"backend": "mosek"}, ("backend must be one of",)),
    ("qp", {"backend": "qpsolvers"}, ("needs solver=",)),
    ("qp", {"dual": "yes"}, ("dual must be True or False",)),
    ("qp", {"settings": 3}, ("settings must be a dict",)),
    ("qp", {"max_iterations": 5}, ("option 'max_iterations' does not apply to qp with tresca",)),
    ("lagrange", {"penalty": 1.0}, ("option 'penalty' does not apply to lagrange",)),
])
def test_methods_that_cannot_take_the_problem_say_why_in_one_line(method, options, words):
    with pytest.raises(OptionError) as raised:
        contactqp.solve(integer(17), method, **options)
    one_line(raised.value, *words)


@pytest.mark.parametrize(("call", "words"), [
    (lambda p: contactqp.solve(p, previous=np.zeros(5)), ("previous: an array of shape (5,)",)),
    (lambda p: contactqp.solve(p, previous="rest"), ("previous must be a Result",)),
    (lambda p: contactqp.solve(p, previous=contactqp.solve(contactqp.Problem(
        *integer_problem(17)[:4]))), ("previous: a Result of 6 dofs without friction",)),
    (lambda p: contactqp.solve(contactqp.Problem(*integer_problem(17)[:4]),
                               previous=np.zeros(6)), ("previous applies to problems with",)),
    (lambda p: contactqp.solve(p, contact="equality"), ("friction takes unilateral contact",)),
    (lambda p: contactqp.solve(p, formulation="strain"), ("applies to bar scenes",)),
    (lambda p: contactqp.solve(contactqp.Problem(K2, F2, **ON_FLAT, mu=0.3), "cone",
                               max_iterations=0), ("max_iterations must be a whole",)),
    (lambda p: contactqp.solve(contactqp.Problem(K2, F2, **ON_FLAT, mu=0.3), "cone",
                               tolerance=-1.0), ("tolerance",)),
])
def test_bad_calls_are_one_line(call, words):
    with pytest.raises(OptionError) as raised:
        call(integer(17))
    one_line(raised.value, *words)


def _bundle(tmp_path, **changes):
    problem = integer(17)
    T = problem.T
    arrays = {"K_data": problem.K.data, "K_indices": problem.K.indices,
              "K_indptr": problem.K.indptr, "C_data": problem.C.data,
              "C_indices": problem.C.indices, "C_indptr": problem.C.indptr,
              "C_shape": np.array(problem.C.shape), "f": problem.f, "g": problem.g,
              "T_data": T.data, "T_indices": T.indices, "T_indptr": T.indptr,
              "T_shape": np.array(T.shape), "slip_bound": problem.slip_bound}
    arrays.update(changes)
    np.savez(tmp_path / "p.npz", **{k: v for k, v in arrays.items() if v is not None})
    return tmp_path / "p.npz"


@pytest.mark.parametrize(("changes", "words"), [
    ({"T_indptr": None}, ("p.npz: has T_data but lacks T_indptr",)),
    ({"T_shape": np.array([3, 99])}, ("p.npz: T_shape is [3, 99]",)),
    ({"T_shape": np.array([10**12, 6])}, ("p.npz: T_shape",)),
    ({"T_indices": np.array([0, 2, 99])}, ("p.npz: T is a malformed CSR", "99")),
    ({"slip_bound": np.array([1.0, -1.0, 1.0])}, ("slip_bound[1] = -1.0 is negative",)),
    ({"slip_bound": np.array([1 + 1j, 1, 1])}, ("p.npz: slip_bound has dtype complex128",)),
    ({"slip_bound": None}, ("T is given without mu",)),
    ({"mu": np.array([0.5, 0.5, 0.5])}, ("mu and slip_bound are both given",)),
    ({"slip_bound": np.array(["a", "b", "c"])}, ("slip_bound must be an array of numbers",)),
])
def test_a_forged_friction_bundle_is_one_line(tmp_path, changes, words):
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(_bundle(tmp_path, **changes))
    one_line(raised.value, *words)


def test_a_forged_T_mtx_is_one_line(tmp_path):
    folder = contactqp.save_problem(integer(17), tmp_path / "folder")
    (folder / "T.mtx").write_text("%%MatrixMarket matrix coordinate real general\n3 4 1\n"
                                  "1 1 1.0\n")
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(folder)
    one_line(raised.value, "T.mtx has 4 columns but K.mtx is 6x6")
    (folder / "T.mtx").write_text("%%MatrixMarket matrix coordinate complex general\n3 6 1\n"
                                  "1 1 1.0 0\n")
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(folder)
    one_line(raised.value, "T.mtx holds complex values")


def test_no_backend_prints_anything_with_friction(capfd):
    """HiGHS wrote its banner to the terminal from C on every Tresca solve through
    qpsolvers; the library prints nothing unless asked."""
    problem = integer(17)
    with warnings.catch_warnings(record=True) as caught:  # nor warns (OSQP's raise_error)
        warnings.simplefilter("always")
        for solver in qpsolvers.available_solvers:
            contactqp.solve(problem, "qp", backend="qpsolvers", solver=solver)
        contactqp.solve(problem, "qp", backend="cvxpy")
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert [str(w.message) for w in caught] == []


def enumerated_tresca(K, f, C, g, T, s):
    """Every answer of a small 2D Tresca problem by enumerating the 6^m states (open or
    closed; stick, slip forwards, slip backwards), each state's KKT system solved by numpy
    and kept where it meets every inequality to 1e-9 (round-off): another method than any of
    contactqp's, and exact to about 1e-14 here."""
    import itertools

    n, m = K.shape[0], C.shape[0]
    found = []
    for states in itertools.product(itertools.product((False, True), (0, 1, -1)), repeat=m):
        held = [i for i, (closed, _) in enumerate(states) if closed]
        stick = [i for i, (_, turn) in enumerate(states) if turn == 0]
        turn = np.array([t for _, t in states], dtype=float)
        rows = np.vstack([C[held], T[stick]])
        k = rows.shape[0]
        matrix = np.block([[K, rows.T], [rows, np.zeros((k, k))]])
        rhs = np.concatenate([f - T.T @ (turn * s), g[held], np.zeros(len(stick))])
        try:
            z = np.linalg.solve(matrix, rhs)
        except np.linalg.LinAlgError:
            continue
        u, lam = z[:n], z[n:]
        lam_N, lam_T = np.zeros(m), turn * s
        lam_N[held] = lam[:len(held)]
        lam_T[stick] = lam[len(held):]
        scale = max(np.abs(f).max(), np.abs(lam).max(initial=0.0), s.max())
        slip = T @ u
        if (lam_N.min() >= -1e-9 * scale and (g - C @ u).min() >= -1e-9 * scale
                and np.all(np.abs(lam_T[stick]) <= s[stick] + 1e-9 * scale)
                and np.all(turn * slip >= -1e-9 * scale)):
            found.append((u, lam_N, lam_T))
    return found


@pytest.mark.parametrize("seed", range(20))
def test_no_random_tresca_answer_is_verified_past_its_bound(seed):
    """Random 2D Tresca problems (three nodes on a flat, K random positive definite): every
    Result's error against the enumerated answer lies within the bound it states, and a
    verified one within 1e-6 of F and U (the issue's goal for random friction problems)."""
    rng = np.random.default_rng(1000 + seed)
    B = rng.standard_normal((6, 6))
    K = B @ B.T + 0.5 * np.eye(6)
    f = rng.uniform(-6.0, 6.0, 6)
    C, T = np.zeros((3, 6)), np.zeros((3, 6))
    for i in range(3):
        C[i, 2 * i + 1], T[i, 2 * i] = -1.0, 1.0
    g, s = rng.uniform(0.0, 1.0, 3) * (rng.random(3) < 0.5), rng.uniform(0.5, 3.0, 3)
    answers = enumerated_tresca(K, f, C, g, T, s)
    assert len(answers) == 1  # convex, K positive definite: one answer
    u, lam_N, lam_T = answers[0]
    problem = contactqp.Problem(K, f, C, g, T=T, slip_bound=s)
    for method, options in (("lagrange", {}), ("qp", {}), ("qp", {"backend": "osqp"})):
        result = contactqp.solve(problem, method, **options)
        force = max(np.abs(result.contact_force - lam_N).max(),
                    np.abs(result.friction_force[:, 0] - lam_T).max())
        move = np.abs(result.u - u).max()
        F, U = result.force_scale, result.displacement_scale
        assert force <= result.force_error_bound + 1e-10 * F, (method, options)
        assert move <= result.displacement_error_bound + 1e-10 * U, (method, options)
        if result.verified:
            assert force <= 1e-6 * F + 1e-10 * F and move <= 1e-6 * U + 1e-10 * U


@pytest.mark.parametrize("call", [
    lambda p: contactqp.prepare(p, "lagrange"),
    lambda p: contactqp.first_contact_factor(p),
    lambda p: contactqp.compare(p),
    lambda p: contactqp.penalty_sweep(p),
    lambda p: contactqp.check(p, np.zeros(p.n), np.zeros(p.m)),
], ids=["prepare", "first_contact_factor", "compare", "penalty_sweep", "check"])
def test_what_cannot_take_friction_refuses_it_rather_than_drop_it(call):
    """The studies, prepare and the frictionless check would solve or judge the problem as if
    it had no friction: each refuses in one line instead."""
    problem = integer(3, mu=0.5)
    with pytest.raises(contactqp.OptionError, match=r"takes no friction: the problem has "
                                                    r"coulomb friction") as raised:
        call(problem)
    assert "\n" not in str(raised.value)
