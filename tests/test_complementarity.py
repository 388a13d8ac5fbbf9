"""The complementarity methods (contactqp.methods.complementarity): Lemke, PGS/PSOR and
semismooth Newton on the LCP in the contact forces.

Expected answers: the default scene's closed form, the exact reference (contactqp.reference:
statics in extended precision or rational arithmetic, tested on its own in test_reference.py)
on random scenes, and, for the natural-map residual, the LCP formed here from dense matrices.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import DEFAULT_F, default_closed_form
from contactqp.builders import flat_patch
from contactqp.methods.complementarity import LEMKE_ROWS, NEWTON_FB_ROWS, PGS_WORK, pgs_sweeps
from contactqp.model import build_model
from contactqp.model.chain import layout_of
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

EXACT = [("lemke", {}), ("semismooth_newton", {"ncp": "min"}),
         ("semismooth_newton", {"ncp": "fischer-burmeister"})]
ITERATIVE = [("pgs", {}), ("pgs", {"relaxation": 1.5})]
ALL = EXACT + ITERATIVE
IDS = ["/".join([m, *map(str, o.values())]) for m, o in ALL]


@pytest.mark.parametrize(("method", "options"), ALL, ids=IDS)
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_the_default_scene_is_its_closed_form(method, options, contact):
    """λ = (F f₂ − g) / f₄ for both contact kinds (the wall is reached)."""
    u, lam = default_closed_form(contact=contact)
    result = contactqp.solve(None, method, contact, **options)
    assert result.verified
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-9)
    np.testing.assert_allclose(result.u, u, rtol=0, atol=1e-9 * np.abs(u).max())


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_lemke_and_newton_are_exact_where_lagrange_is(seed):
    """Random single bars without the extra stiffness contrast (where Lagrange multipliers are
    exact to round-off, test_guarantee.py): Lemke's pivots and Newton on min and on
    Fischer–Burmeister reach the exact reference (Lemke to round-off, Newton to its stopping
    residual, :data:`EXACT_TO`) or the round-off of the LCP they solve where that is larger,
    and are verified where that round-off is within the check's tolerance. The LCP's W = C K⁻¹ Cᵀ
    can be far worse conditioned than K: seed 13219 squeezes a stiff element (1.6e10 N/m)
    between a press fit and a wall behind a soft one (2.8e4 N/m), the walls push with
    5.5e10 N against F = 1.0e6 N, cond(W_AA) = 2e6, and both methods' forces are 6 N off
    (1.1e-10 of themselves, 6e-6 of F): rightly flagged, their error within the check's
    bound."""
    scene = random_scene(np.random.default_rng(seed), max_bars=1, contrast=False)
    exact = reference(scene)
    largest = np.abs(exact.contact_force).max(initial=0.0)
    roundoff = (LCP_ROUNDOFF * np.finfo(float).eps * largest
                * lcp_condition(scene, exact.contact_force > 0.0))
    for method, options in EXACT:
        result = contactqp.solve(scene, method, **options)
        error = np.abs(result.contact_force - exact.contact_force).max(initial=0.0)
        # Lemke to round-off, Newton to its stopping residual, of the largest force (press
        # fits can push far beyond F), or the LCP's round-off where W_AA is ill-conditioned
        allowed = EXACT_TO[method] * max(result.force_scale, largest)
        assert error <= max(allowed, roundoff), (seed, method, options, error)
        # the check reads a force's round-off again as the move it makes through a soft
        # element, times the stiffness a wall beside a stiff one sees (seed 3988435278: Lemke
        # 2.9e-4 N off, a clamped node 2e-9 m into its zero-gap wall beside 1.1e11 N/m,
        # 1.4e-5 of F: flagged, its error within the check's bound)
        stiffness = layout_of(scene).element_stiffness
        if roundoff * stiffness.max() / stiffness.min() <= 1e-7 * result.force_scale:
            assert result.verified, (seed, method, options, result.message)
        else:  # verified or not, the check's bound holds the error
            assert error <= result.force_error_bound, (seed, method, options)


# how close each gets, relative to the largest force: Lemke's pivots to round-off; Newton
# stops at a natural-map residual of 1e-13 (seed 92180405: Newton on min 7.6e-7 N off on
# F = 449 N, 1.7e-9 of F, verified)
EXACT_TO = {"lemke": 1e-9, "semismooth_newton": 1e-8}
LCP_ROUNDOFF = 1024  # units of round-off of the largest force per unit of cond(W_AA): the
# methods step through the whole LCP (Newton by least squares), not W_AA alone (seed
# 3771110771: Newton on min 2.7e-3 N off, 2.8e3 units of cond(W_AA) = 2.7e5, verified)


def lcp_condition(scene: contactqp.Scene, active: np.ndarray) -> float:
    """cond(W_AA) of the contact LCP, W = C K⁻¹ Cᵀ over the ``active`` rows (the exact
    answer's pushing ones, which set the forces), from dense matrices (1 with none)."""
    model = build_model(scene)
    if not active.any():
        return 1.0
    C = model.C.toarray()[active]
    return float(np.linalg.cond(C @ np.linalg.solve(model.K.toarray(), C.T)))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_every_method_is_right_where_verified_and_reports_its_residual(seed):
    """Random scenes with every family (several bars, bar contacts, walls on both sides, zero
    gaps, stiff beside soft): a verified answer is within the guarantee of the exact
    reference; and the natural-map residual the method stops on (of the LCP it formed) is the
    one the check reports from the answer alone."""
    scene = random_scene(np.random.default_rng(seed))
    exact = reference(scene)
    for method, options in ALL:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = contactqp.solve(scene, method, **options)
        # the check's natural map: each row scaled by s_i = c_iᵀK c_i / (c_iᵀc_i)², from the
        # answer alone (dense algebra here); the method's own is on its LCP's unit diagonal
        assert result.residuals["natural_map"] == pytest.approx(
            dense_natural_map(scene, result), rel=1e-6, abs=1e-12), (seed, method, options)
        if not result.verified:
            continue
        force_error = np.abs(result.contact_force - exact.contact_force).max(initial=0.0)
        displacement_error = np.abs(result.u - exact.displacement).max()
        assert force_error <= contactqp.GUARANTEE[0] * result.force_scale
        assert displacement_error <= contactqp.GUARANTEE[1] * result.displacement_scale


def dense_natural_map(scene, result) -> float:
    """‖min(z, w)‖∞ / ‖q‖∞ with z = λ/√s, w = gap·√s, q = free gap·√s, s_i = c_iᵀKc_i/(c_iᵀc_i)²
    (docs/howto/check.md), from dense algebra on the scene's model."""
    model = build_model(scene)
    K, C = model.K.toarray(), model.C.toarray()
    s = np.einsum("ij,jk,ik->i", C, K, C) / np.einsum("ij,ij->i", C, C) ** 2
    u = result.u[model.free]
    gap, free = model.g - C @ u, model.g - C @ np.linalg.solve(K, model.P)
    top = np.abs(np.minimum(result.contact_force / np.sqrt(s), gap * np.sqrt(s))).max(initial=0.0)
    size = np.abs(free * np.sqrt(s)).max(initial=0.0)
    return top / (size if size > 0 else 1.0)


def test_pgs_stops_at_its_cap_and_is_flagged():
    """A flat patch of 32 walls (95 % in contact): one sweep leaves the forces far off, and the
    iterate is returned as it is, not claimed, and flagged by the check; its natural-map
    residual is the one formed here from the dense W and q."""
    scene = flat_patch(32)
    result = contactqp.solve(scene, "pgs", max_iterations=1)
    assert not result.claimed_success and "stopped after 1 sweeps" in result.status
    assert not result.verified
    model = build_model(scene)
    K, C = model.K.toarray(), model.C.toarray()
    W = C @ np.linalg.solve(K, C.T)
    q = model.g - C @ np.linalg.solve(K, model.P)
    r = 1.0 / np.sqrt(np.diag(W))  # the unit-diagonal scaling: z = λ/r... as D = diag(W)^-½
    z, w = result.contact_force / r, (W @ result.contact_force + q) * r
    expected = np.abs(np.minimum(z, w)).max() / np.abs(q * r).max()
    assert result.info["natural_map"] == pytest.approx(expected, rel=1e-6)  # the method's own
    assert expected > 1e-3
    assert result.residuals["natural_map"] == pytest.approx(dense_natural_map(scene, result),
                                                            rel=1e-6)


@pytest.mark.parametrize("relaxation", [1.0, 1.5])
def test_pgs_sweeps_grow_with_the_mesh(relaxation):
    """The bar's condensed flexibility is far from diagonally dominant (each contact's
    neighbours see most of its flexibility): on a flat patch Gauss–Seidel, and PSOR alike,
    needs about twice the sweeps each time the mesh is refined (measured 103, 222, 443 at
    ω = 1; PSOR takes more, not fewer, here), and still reaches the answer."""
    runs = [contactqp.solve(flat_patch(n), "pgs", relaxation=relaxation) for n in (8, 16, 32)]
    sweeps = [run.iterations for run in runs]
    assert all(run.verified and run.claimed_success for run in runs)
    assert 1.5 * sweeps[0] < sweeps[1] and 1.5 * sweeps[1] < sweeps[2]


def test_semismooth_newton_on_min_takes_its_set_in_few_steps():
    """Newton on min is the primal–dual active set: on the default scene the first step finds
    the one wall, and the answer is exact."""
    result = contactqp.solve(None, "semismooth_newton")
    assert result.iterations == 1 and result.residuals["natural_map"] <= 1e-15
    assert result.contact_force[0] == pytest.approx(default_closed_form()[1], rel=1e-12)


def test_more_rows_than_the_dense_lcp_takes_is_a_clear_error():
    scene = flat_patch(2100)
    with pytest.raises(contactqp.SolverError, match="up to 2000 contact rows"):
        contactqp.solve(scene, "pgs")


@pytest.mark.parametrize(("method", "options", "limit"), [
    ("lemke", {}, LEMKE_ROWS), ("semismooth_newton", {"ncp": "fischer-burmeister"},
                                NEWTON_FB_ROWS)])
def test_methods_whose_steps_are_dense_refuse_more_rows_than_they_end_on_in_a_minute(
        method, options, limit):
    with pytest.raises(contactqp.SolverError, match=f"takes up to {limit} contact rows") as e:
        contactqp.solve(flat_patch(limit + 1), method, **options)
    assert "\n" not in str(e.value) and f"has {limit + 1}" in str(e.value)


def test_pgs_takes_the_sweeps_its_work_allows_and_refuses_more():
    scene = flat_patch(1500)  # 1500 rows: PGS_WORK allows 8888 sweeps
    budget = PGS_WORK // scene.n_contacts**2
    assert pgs_sweeps(scene.n_contacts, None) == min(budget, 10_000) < 10_000
    with pytest.raises(contactqp.OptionError, match=f"at most {budget} sweeps"):
        contactqp.solve(scene, "pgs", max_iterations=budget + 1)
    with pytest.raises(contactqp.OptionError, match="at most 1000000"):
        contactqp.solve(None, "pgs", max_iterations=10**9)


@pytest.mark.parametrize(("options", "message"), [
    ({"relaxation": 2.0}, r"relaxation must be in \(0, 2\)"),
    ({"relaxation": 0.0}, "relaxation"),
    ({"tolerance": -1.0}, "tolerance"),
    ({"max_iterations": 0}, "max_iterations"),
])
def test_bad_pgs_options_are_one_clear_error(options, message):
    with pytest.raises(contactqp.OptionError, match=message):
        contactqp.solve(None, "pgs", **options)


def test_a_bad_ncp_function_is_one_clear_error():
    with pytest.raises(contactqp.OptionError, match="ncp must be one of min, fischer-burmeister"):
        contactqp.solve(None, "semismooth_newton", ncp="fb")


def test_the_default_load_is_carried_by_wall_and_support():
    """Balance: the wall's force plus the support's reaction carry the load, for every
    method (an independent sum, not the check's)."""
    for method, options in ALL:
        result = contactqp.solve(None, method, **options)
        assert result.contact_force[0] - result.reactions[0] == pytest.approx(DEFAULT_F,
                                                                               rel=1e-9)


def test_semismooth_newton_past_the_lcps_size_takes_set_solves_without_w(monkeypatch):
    """Past LCP_ROWS (set to 0 here) semismooth Newton with "min" on a user's model takes its
    steps as the model's set solves, with no W: on the Hertz cylinder of contactqp.fem it
    ends in a few steps, verified, within its bound of the exact route's answer (lagrange, a
    different loop on the same sets), and says which route it took."""
    pytest.importorskip("skfem")
    from contactqp.fem import cylinder_on_flat
    from contactqp.methods import complementarity

    problem = cylinder_on_flat(fine=0.5).problem
    exact = contactqp.solve(problem, "lagrange")
    monkeypatch.setattr(complementarity, "LCP_ROWS", 0)
    found = contactqp.solve(problem, "semismooth_newton")
    assert found.info["route"] == "set solves"
    assert found.verified and found.status == "converged" and found.iterations <= 20
    reach = found.force_error_bound + exact.force_error_bound
    assert np.abs(found.contact_force - exact.contact_force).max() <= reach
    reach = found.displacement_error_bound + exact.displacement_error_bound
    assert np.abs(found.u - exact.u).max() <= reach


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_semismooth_newton_by_set_solves_is_right_where_verified(seed):
    """The set-solve route on random scenes handed over as problems (LCP_ROWS 0): where it
    says verified, its answer is within its bound of the exact enumeration; where its sets
    cycle (redundant rows of a chain, which the LCP route's held steps handle), it says so and
    is not verified."""
    from contactqp.methods import complementarity

    scene = random_scene(np.random.default_rng(seed))
    try:
        problem = contactqp.problem_from_scene(scene)
        exact = reference(scene)
    except contactqp.ContactqpError:
        return
    limit = complementarity.LCP_ROWS
    complementarity.LCP_ROWS = 0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = contactqp.solve(problem, "semismooth_newton")
    except contactqp.ContactqpError:
        return
    finally:
        complementarity.LCP_ROWS = limit
    if found.status != "converged":
        assert not found.verified or found.status == "the active set cycles"
    if found.verified:
        assert np.abs(found.contact_force - exact.contact_force).max(initial=0.0) <= (
            found.force_error_bound * (1 + 1e-9) + 1e-12 * found.force_scale)


@pytest.mark.parametrize("method", ["pgs", "lemke", "semismooth_newton"])
def test_the_lcp_of_a_users_model_keeps_no_columns_past_their_size(method, monkeypatch):
    """A user's model with CHOLMOD's factor forms W a block of rows at a time and keeps no
    K⁻¹Cᵀ, so the LCP_ENTRIES limit on that dense array does not hold it back (set to 1 here):
    pgs, lemke and semismooth Newton on W solve the Hertz cylinder of contactqp.fem, verified,
    within their bounds of lagrange's answer, without the columns (the chain's route that
    forms them is made to fail). With SuperLU's factor (CHOLMOD made absent), whose forward
    columns are dense on the dofs they reach, the limit still holds: pgs and lemke refuse,
    naming it, and semismooth Newton takes its set solves."""
    pytest.importorskip("skfem")
    pytest.importorskip("cvxopt")
    from contactqp.fem import cylinder_on_flat
    from contactqp.methods import complementarity
    from contactqp.model import factor

    problem = cylinder_on_flat(fine=0.5).problem
    exact = contactqp.solve(problem, "lagrange")
    monkeypatch.setattr(complementarity, "LCP_ENTRIES", 1)
    monkeypatch.setattr(complementarity, "SET_ROUTE_ROWS", 10**9)  # semismooth Newton on W
    monkeypatch.setattr(complementarity, "flexibility",
                        lambda problem: pytest.fail("K⁻¹Cᵀ formed"))
    found = contactqp.solve(problem, method)
    assert found.verified, found.message
    assert "route" not in found.info  # on W, not by set solves
    reach = found.force_error_bound + exact.force_error_bound
    assert np.abs(found.contact_force - exact.contact_force).max() <= reach
    reach = found.displacement_error_bound + exact.displacement_error_bound
    assert np.abs(found.u - exact.u).max() <= reach
    monkeypatch.setattr(factor, "cholmod_installed", lambda: False)
    fresh = cylinder_on_flat(fine=0.5).problem
    if method == "semismooth_newton":
        assert contactqp.solve(fresh, method).info["route"] == "set solves"
    else:
        with pytest.raises(contactqp.ContactqpError, match="and 1 entries"):
            contactqp.solve(fresh, method)


def test_pgs_past_its_rows_by_its_option(monkeypatch, capfd):
    """pgs refuses past LCP_ROWS (set to 10 here) with the reason and the option that lifts
    it; with max_rows at the problem's rows it forms W, sweeps past PGS_WORK's budget (set so
    it allows one sweep here) and is verified, its forces within their bounds of lagrange's;
    a W that would not fit in the memory available is one line; a max_rows under the rows
    refuses as the default does; bad values of max_rows are one line; nothing printed."""
    pytest.importorskip("skfem")
    from contactqp.fem import cylinder_on_flat
    from contactqp.methods import complementarity
    from contactqp.model import factor

    problem = cylinder_on_flat(fine=0.05).problem
    rows = problem.C.shape[0]
    assert rows > 10
    monkeypatch.setattr(complementarity, "LCP_ROWS", 10)
    monkeypatch.setattr(complementarity, "PGS_WORK", rows**2)
    with pytest.raises(contactqp.SolverError, match="up to 10 contact rows.*option max_rows"):
        contactqp.solve(problem, "pgs")
    with pytest.raises(contactqp.SolverError, match=f"up to {rows - 1} contact rows"):
        contactqp.solve(problem, "pgs", max_rows=rows - 1)
    exact = contactqp.solve(problem, "lagrange")
    found = contactqp.solve(problem, "pgs", max_rows=rows)
    assert found.verified and found.iterations > 1
    reach = found.force_error_bound + exact.force_error_bound
    assert np.abs(found.contact_force - exact.contact_force).max() <= reach
    monkeypatch.setattr(factor, "available_memory", lambda: 3 * 8 * rows**2 - 1)
    with pytest.raises(contactqp.SolverError, match=f"pgs with {rows} rows forms W"):
        contactqp.solve(problem, "pgs", max_rows=rows)
    for bad in (0, -3, 2.5, True, "many", float("nan"), None, [rows]):
        with pytest.raises(contactqp.OptionError, match="max_rows must be a whole number"):
            contactqp.solve(problem, "pgs", max_rows=bad)
    assert capfd.readouterr() == ("", "")
    from contactqp.cli import main

    assert main(["solve", "--method", "pgs", "--max-rows", "2", "--json"]) == 0  # 1 row
    capfd.readouterr()
    assert main(["solve", "--method", "pgs", "--max-rows", "0"]) == 2
    error = capfd.readouterr().err.strip()
    assert error.count("\n") == 0 and "max_rows must be a whole number >= 1, got 0" in error
