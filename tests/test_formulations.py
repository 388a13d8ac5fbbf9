"""The condensed and strain formulations agree with the full one and with the explicit
Lagrange solution.

Glossary: K stiffness of the free nodes, C wall rows, g gaps, λ contact forces (N). The
condensed model keeps only the nodes with walls: S = B K⁻¹ Bᵀ their flexibility; every method
solved on it must give the λ and u of the full model. The strain formulation has unknowns
u and e (element elongations, m) tied by B u − e = 0, energy ½ Σ k_e e², k_e = EA/L; the
multipliers of the tie rows are the element forces N = k_e (u_j − u_i).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp
from contactqp.methods import qp as qpmod
from contactqp.model import build_model, condense, element_forces, elongation_rows, wall_forces
from test_qp import PAIRS, SCENES, SOC_REWRITE, force_rtol, require

METHODS = [("lagrange", {}), ("augmented", {}), ("qp", {"backend": "clarabel", "accuracy": "high"}),
           ("qp", {"backend": "osqp", "accuracy": "high"})]


@st.composite
def scenes(draw):
    """A bar fixed at one or both ends, random loads, walls on random free nodes, both sides."""
    n = draw(st.integers(2, 12))
    areas = draw(st.lists(st.floats(1e-4, 1e-2), min_size=n, max_size=n))
    lengths = draw(st.lists(st.floats(0.05, 2.0), min_size=n, max_size=n))
    bar = contactqp.Bar.from_areas(areas, 210e9, lengths=lengths)
    supports = (0, n) if draw(st.booleans()) else (0,)
    free = [i for i in range(n + 1) if i not in supports]
    # |load| >= 1 N: an unloaded scene with closed gaps has u = 0 and no scale at all, where a
    # QP solver's absolute tolerance is the whole answer (the check flags it; not tested here)
    magnitude = st.floats(1.0, 1e6)
    loads = [contactqp.Load(i, draw(magnitude) * draw(st.sampled_from([-1.0, 1.0]))) for i in
             draw(st.lists(st.sampled_from(free), min_size=1, max_size=3, unique=True))]
    walls = []
    for node in draw(st.lists(st.sampled_from(free), min_size=1, max_size=4, unique=True)):
        for side in draw(st.sampled_from([("+",), ("-",), ("+", "-")])):
            # a closed gap (0) or at least 1 µm: two walls 1e-12 m apart pin a node to within
            # round-off of its displacement, where "which wall pushes" is not decidable
            gap = draw(st.one_of(st.just(0.0), st.floats(1e-6, 1e-3)))
            walls.append(contactqp.Wall(node, gap, side))
    return contactqp.Scene(bar, tuple(contactqp.Support(s) for s in supports), tuple(loads),
                           tuple(walls))


def scales(scene, full):
    """(force, displacement) scales of a full-formulation Result for the tolerances.

    Forces below ~1e-12 k·gap are round-off to Lagrange's active-set decision (it ignores
    penetrations below 1e-12 of the displacement scale), so the force scale includes k·gap;
    the displacement scale stays physical when the exact u is 0 (a closed zero gap)."""
    largest_gap = max(w.gap for w in scene.walls)
    force_scale = max(np.abs(full.contact_force).max(), max(abs(p.force) for p in scene.loads),
                      scene.bar.stiffness.min() * largest_gap)
    return force_scale, max(np.abs(full.u).max(), force_scale / scene.bar.stiffness.max())


@settings(max_examples=25, deadline=None)
@given(scenes())
def test_condensed_equals_full_for_the_explicit_methods(scene):
    full = contactqp.solve(scene)
    force_scale, disp_scale = scales(scene, full)
    for method in ("lagrange", "augmented"):
        condensed = contactqp.solve(scene, method, formulation="condensed")
        assert condensed.verified, condensed.message
        # both are exact up to round-off of a dense inverse of S (cond(S) <= ~1e8 here)
        # the net wall force on each node: a node clamped between two zero-gap walls may carry
        # any equal pair λ₊ = λ₋ >= 0 (they cancel), so only the net force is unique
        assert np.allclose(wall_forces(scene, condensed.contact_force),
                           wall_forces(scene, full.contact_force), rtol=1e-7,
                           atol=1e-9 * force_scale)
        assert np.allclose(condensed.u, full.u, rtol=1e-7, atol=1e-9 * disp_scale)


@pytest.mark.parametrize(("method", "options"), METHODS)
@pytest.mark.parametrize("contact", contactqp.CONTACT_KINDS)
def test_condensed_seed_scene_every_method(method, options, contact):
    reference = contactqp.solve(contact=contact)
    result = contactqp.solve(method=method, contact=contact, formulation="condensed", **options)
    # exact methods to round-off; QP solvers at accuracy="high" to ~1e-8 of the force
    assert result.contact_force == pytest.approx(reference.contact_force, rel=1e-7)
    assert result.u == pytest.approx(reference.u, rel=1e-7, abs=1e-15)
    assert result.verified


def test_condensed_model_is_the_flexibility_at_the_walls():
    model = build_model(contactqp.seed_scene())
    small = condense(model).model
    dense_inverse = np.linalg.inv(model.K.toarray())
    wall = model.C.indices[0]
    # one wall: S = (K⁻¹)_ww, computed here by a dense inverse
    assert small.K.toarray() == pytest.approx(1.0 / dense_inverse[wall, wall], rel=1e-12)
    assert small.P == pytest.approx(small.K.toarray()[0, 0] * (dense_inverse @ model.P)[wall],
                                    rel=1e-12)


def test_condensed_with_too_many_contact_nodes_is_refused():
    bar = contactqp.Bar.from_areas(np.full(2500, 1e-3), 1e9, length=1.0)
    walls = tuple(contactqp.Wall(i, 1e-3) for i in range(1, 2501))
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (), walls)
    with pytest.raises(contactqp.OptionError, match="2500 contact nodes"):
        contactqp.solve(scene, formulation="condensed")


def test_unknown_formulation_names_the_value():
    with pytest.raises(contactqp.OptionError, match="'sparse'"):
        contactqp.solve(formulation="sparse")


# ---------------------------------------------------------------------------------------------
# The strain formulation

STRAIN_METHODS = [("lagrange", {}), ("qp", {"backend": "clarabel", "accuracy": "high"}),
                  ("qp", {"backend": "osqp", "accuracy": "high"})]
# Solvers that need a positive definite Hessian: the strain Hessian diag(0, k_e) is singular in
# u, so they raise, and the Result must say so (not verified), never a silent answer.
NEEDS_DEFINITE_HESSIAN = {("qpsolvers", "quadprog"), ("qpsolvers", "ecos")}


@settings(max_examples=20, deadline=None)
@given(scenes())
def test_strain_and_condensed_equal_full(scene):
    full = contactqp.solve(scene)
    force_scale, disp_scale = scales(scene, full)
    runs = [("lagrange", "strain", {}, 1e-7), ("lagrange", "condensed", {}, 1e-7),
            # an interior-point solver at accuracy="high" is ~1e-8 off (force_rtol), but on a
            # weakly active wall (gap 0 and λ = 0: degenerate complementarity) it stops when
            # λ·s reaches its gap tolerance 1e-10 with λ and s each ~√1e-10 = 1e-5 (scaled);
            # in the QP's own scales (U = ‖K⁻¹P‖∞ may exceed ‖u‖ tenfold when walls hold the
            # bar back); 1e-3 allows that and a factor 10 for the KKT conditioning. A wrong
            # tie row or scale would be O(1) off.
            ("qp", "strain", {"backend": "clarabel", "accuracy": "high"}, 1e-3),
            ("qp", "condensed", {"backend": "clarabel", "accuracy": "high"}, 1e-3)]
    for method, formulation, options, rtol in runs:
        result = contactqp.solve(scene, method, formulation=formulation, **options)
        if method == "qp" and not result.verified:
            # a QP solver may fail on a degenerate scene (a node clamped between zero-gap walls
            # has an unbounded set of duals λ₊ = λ₋; an interior-point method can stall there):
            # the promise is that the Result says so, and that it then claims nothing or the
            # check contradicts the claim in a warning
            assert result.message
            assert not result.claimed_success or result.warnings
            continue
        assert result.verified, (method, formulation, result.message)
        # net wall force per node (a node clamped between two zero-gap walls: λ₊ = λ₋ arbitrary)
        assert np.allclose(wall_forces(scene, result.contact_force),
                           wall_forces(scene, full.contact_force), rtol=0,
                           atol=rtol * force_scale), (method, formulation)
        assert np.allclose(result.u, full.u, rtol=0, atol=rtol * disp_scale), (method, formulation)


@pytest.mark.parametrize(("method", "options"), STRAIN_METHODS)
@pytest.mark.parametrize("contact", contactqp.CONTACT_KINDS)
def test_strain_tie_multipliers_are_the_element_forces(method, options, contact):
    reference = contactqp.solve(contact=contact)
    result = contactqp.solve(method=method, contact=contact, formulation="strain", **options)
    assert result.verified, result.message
    assert result.contact_force == pytest.approx(reference.contact_force, rel=1e-7)
    # N = k_e Δu from the Lagrange displacements: an independent computation of the same forces
    expected = element_forces(contactqp.seed_scene().bar, reference.u)
    force_scale = np.abs(expected).max()
    np.testing.assert_allclose(result.info["element_force"], expected, rtol=0,
                               atol=1e-7 * force_scale)


@pytest.mark.parametrize("row", PAIRS)
@pytest.mark.parametrize("scene_name", ["seed", "several_walls", "both_sides"])
def test_strain_every_solver_right_or_flagged(row, scene_name):
    """Every installed solver on the strain QP: the dual is Lagrange's λ (to the solver's
    accuracy, see test_qp.force_rtol), or the Result says it failed; never a quiet wrong answer."""
    require(row)
    scene = SCENES[scene_name]()
    reference = contactqp.solve(scene)
    result = contactqp.solve(scene, method="qp", formulation="strain", backend=row.backend,
                             solver=row.solver, accuracy="high")
    if (row.backend, row.solver) in NEEDS_DEFINITE_HESSIAN:
        assert not result.verified
        assert "positive definite" in result.status
        return
    force_scale = max(np.abs(reference.contact_force).max(), np.abs(scene.nodal_loads()).max())
    np.testing.assert_allclose(result.contact_force, reference.contact_force, rtol=0,
                               atol=force_rtol(row.backend, row.solver) * force_scale)
    assert result.verified or (row.backend, row.solver) in SOC_REWRITE, result.message


def test_strain_qp_data():
    """x = [u; e]: Hessian diag(0, k_e/k), ties B u − e = 0; at the Lagrange solution the
    scaled KKT conditions hold with the tie multipliers = element forces / F."""
    scene = contactqp.seed_scene()
    reference = contactqp.solve(scene)
    qp = contactqp.qp_problem(scene, formulation="strain")
    n, m = 4, 4
    k = scene.bar.youngs_modulus * scene.bar.areas / scene.bar.lengths
    stiffness_scale = qp.force_scale / qp.displacement_scale
    assert qp.K.toarray() == pytest.approx(np.diag(np.concatenate((np.zeros(n), k))) / stiffness_scale)
    u = reference.u[1:]
    e = np.diff(reference.u)
    x = np.concatenate((u, e)) / qp.displacement_scale
    assert np.abs(qp.ties @ x).max() < 1e-12 * np.abs(x).max()
    mu = np.concatenate((k * e, reference.contact_force)) / qp.force_scale
    stationarity = qp.K @ x + qp.q + qp.rows().T @ mu
    assert np.abs(stationarity).max() < 1e-9
    assert qp.n == n + m and qp.n_displacements == n and qp.n_ties == m


def test_elongation_rows_drop_supported_nodes():
    bar = contactqp.Bar.from_areas([1e-4] * 3, 1e9, length=3.0)
    scene = contactqp.Scene(bar, (contactqp.Support(0), contactqp.Support(3)), (), ())
    # free nodes 1, 2: e0 = u1, e1 = u2 − u1, e2 = −u2
    assert elongation_rows(build_model(scene)).toarray() == pytest.approx(
        np.array([[1.0, 0.0], [-1.0, 1.0], [0.0, -1.0]]))


@pytest.mark.parametrize("method", ["penalty", "augmented"])
def test_strain_with_a_penalty_method_is_refused(method):
    with pytest.raises(contactqp.OptionError, match="formulation='strain'.*lagrange, qp"):
        contactqp.solve(method=method, formulation="strain")


def test_unknown_qp_formulation_names_the_value():
    with pytest.raises(contactqp.OptionError, match="'weak'"):
        qpmod.qp_from_model(build_model(contactqp.seed_scene()), formulation="weak")


# ---------------------------------------------------------------------------------------------
# A chain held by one support: K⁻¹ by statics


@pytest.mark.parametrize("support", [0, 3, 7])
@pytest.mark.parametrize("columns", [1, 3, 40])
def test_determinate_chain_solve_is_the_inverse_of_K(support, columns):
    """K⁻¹ from statics (the Green's function for a few loaded rows, cumulative sums for
    many) against a dense solve with the assembled K: κ(K) <= ~1e3 here, so 1e-12."""
    rng = np.random.default_rng(support + columns)
    bar = contactqp.Bar.from_areas(rng.uniform(1e-4, 1e-3, 40), 2e11, length=2.0)
    scene = contactqp.Scene(bar, (contactqp.Support(support),), (), ())
    model = build_model(scene)
    rhs = np.zeros((model.n_free, columns))
    rows = rng.choice(model.n_free, size=min(columns, model.n_free), replace=False)
    rhs[rows, np.arange(rows.size) % columns] = rng.normal(size=rows.size)
    if columns == 40:
        rhs = rng.normal(size=rhs.shape)  # every row loaded: the cumulative-sum path
    expected = np.linalg.solve(model.K.toarray(), rhs)
    np.testing.assert_allclose(model.solve_K(rhs), expected, rtol=0,
                               atol=1e-12 * np.abs(expected).max())


def test_a_million_element_bar_is_exact_to_round_off():
    """Exact areas: the discrete tip flexibility is the cone's ∫dx/(EA), so the condensed
    contact force equals the continuum closed form up to round-off. Assembling K and
    factoring it (two supports' path) loses ~3e-8 here; statics loses ~n·ε."""
    from contactqp.studies import cone_contact_force
    n = 200_000
    bar = contactqp.Bar.tapered_circle(1.0, n, 0.040, 0.020, 210e9, area_rule="exact")
    seed = contactqp.seed_scene()
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(n // 2, seed.loads[0].force),),
                            (contactqp.Wall(n, seed.walls[0].gap, "+"),))
    result = contactqp.solve(scene, formulation="condensed")
    assert result.verified
    assert result.contact_force[0] == pytest.approx(cone_contact_force(), rel=1e-12)
