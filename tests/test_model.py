"""The model (contactqp.model): the layout's arrays (the nodal loads of a distributed load, the
stiffness a wall sees), the solves with K (statics and banded), the condensed problem and the
strain formulation's tie rows.

Glossary: K stiffness matrix of the free nodes, C contact rows, g gaps; S = B K⁻¹ Bᵀ the
compliance between the contact nodes (B selects them); B u − e = 0 the tie rows of the strain
formulation.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import contactqp
from closed_forms import (
    E_SPRINGS,
    cone_contact_force,
    exact,
    rational_solve,
)
from contactqp import (
    Bar,
    Scene,
    Support,
)
from contactqp.model import (
    Layout,
    build_model,
    condense,
    elongation_rows,
)
from contactqp.scene import DistributedLoad


def test_seen_stiffness_holds_the_supports_and_the_pushing_walls():
    from contactqp.model import seen_stiffness

    k = 2e11 * 1e-3 / 0.25  # four equal elements of EA/L = 8e8 N/m
    one = Scene(Bar.from_areas([1e-3] * 4, 2e11, length=1.0), (Support(0),))
    # node 2 held: node 2 itself sees the two elements to the support in series (k/2), node 3
    # one element back to node 2 and a free end (k), node 1 one element each way (2k)
    assert seen_stiffness(Layout(one), np.array([2]), np.array([1, 2, 3, 4])) == pytest.approx(
        [2 * k, k / 2, k, k / 2], rel=1e-12)
    # a second bar is not a neighbour: its support holds only its own nodes
    two = Scene((one.bars[0], one.bars[0]), (Support(0), Support(0, bar=1)))
    assert seen_stiffness(Layout(two), np.array([], dtype=int), np.array([4, 6])) == pytest.approx(
        [k / 4, k], rel=1e-12)  # bar 1 node 1: one element from its support


def test_condensed_model_is_the_flexibility_at_the_walls():
    model = build_model(contactqp.default_scene())
    small = condense(model)
    dense_inverse = np.linalg.inv(model.K.toarray())
    wall = model.C.indices[0]
    # one wall: S = (K⁻¹)_ww, computed here by a dense inverse
    assert small.K.toarray() == pytest.approx(1.0 / dense_inverse[wall, wall], rel=1e-12)
    assert small.P == pytest.approx(small.K.toarray()[0, 0] * (dense_inverse @ model.P)[wall],
                                    rel=1e-12)


def _condensed_loads(K: np.ndarray, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """P_n − K_ni K_ii⁻¹ P_i (n the nodes, i the rest), in exact rational arithmetic."""
    rest = np.setdiff1d(np.arange(P.size), nodes)
    x = rational_solve([exact(row) for row in K[np.ix_(rest, rest)]], exact(P[rest])) if (
        rest.size) else []
    return np.array([float(Fraction(float(P[a])) - sum(
        (Fraction(float(K[a, b])) * xb for b, xb in zip(rest, x)), Fraction(0))) for a in nodes])


@pytest.mark.parametrize("seed", [*range(30), 404007, 1230016])
def test_the_condensed_chain_is_the_inverse_of_the_flexibility(seed):
    """S⁻¹ (tridiagonal, from series compliances) against the dense inverse of B K⁻¹ Bᵀ, and
    the recovered displacements against dense K⁻¹(P − Cᵀλ), on random scenes (several bars,
    one or two supports, free ends, walls on either side, bar contacts) with random λ."""
    from contactqp.random_scenes import random_scene

    scene = random_scene(np.random.default_rng(seed), contrast=False)
    model = build_model(scene)
    small = condense(model)
    K = model.K.toarray()  # the full stiffness, solved densely here
    nodes = np.flatnonzero(np.abs(model.C.toarray()).sum(axis=0))
    flexibility = np.linalg.inv(K)[np.ix_(nodes, nodes)]
    expected = np.linalg.inv(flexibility)
    # a scene with no contact (seed 404007) condenses to no node: S⁻¹ is 0 x 0
    assert small.K.shape == expected.shape
    assert np.abs(small.K.toarray() - expected).max(initial=0.0) <= (
        1e-9 * np.abs(expected).max(initial=0.0))
    w0 = np.linalg.solve(K, model.P)[nodes]
    # S⁻¹ w₀ is P condensed onto the nodes, P_n − K_ni K_ii⁻¹ P_i, worked out in exact
    # arithmetic: the dense inverse of the inverse lost it (seed 1230016, K's condition number
    # 1.9e8: 3.5e-3 where it is 0 to 52 digits). It cancels: its round-off is relative to the
    # terms summed, |S⁻¹| |w₀|
    condensed = _condensed_loads(K, model.P, nodes)
    assert np.all(np.abs(small.P - condensed) <= 1e-8 * (np.abs(expected) @ np.abs(w0)))
    lam = np.random.default_rng(seed).uniform(0.0, 1e5, model.n_contacts)
    u = np.linalg.solve(K, model.P - model.C.T @ lam)
    assert np.abs(small.displacements(lam) - u).max() <= 1e-9 * np.abs(u).max()


def test_condensed_takes_any_number_of_contact_nodes():
    """2500 walls (the dense flexibility used to refuse more than 2000): the chain is banded,
    and its answer is the full formulation's."""
    bar = contactqp.Bar.from_areas(np.full(2500, 1e-3), 1e9, length=1.0)
    scene = contactqp.wall_at_every_node(contactqp.Scene(
        bar, (contactqp.Support(0),), (), distributed=(DistributedLoad(1e6),)), 1e-4)
    condensed = contactqp.solve(scene, formulation="condensed")
    full = contactqp.solve(scene, formulation="full")
    assert condensed.verified and full.verified
    assert np.abs(condensed.contact_force - full.contact_force).max() <= (
        condensed.force_error_bound + full.force_error_bound)


def test_elongation_rows_drop_supported_nodes():
    bar = contactqp.Bar.from_areas([1e-4] * 3, 1e9, length=3.0)
    scene = contactqp.Scene(bar, (contactqp.Support(0), contactqp.Support(3)), (), ())
    # free nodes 1, 2: e0 = u1, e1 = u2 − u1, e2 = −u2
    assert elongation_rows(build_model(scene)).toarray() == pytest.approx(
        np.array([[1.0, 0.0], [-1.0, 1.0], [0.0, -1.0]]))


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


@pytest.mark.parametrize("pushed", [1, 5, 16, 17])
def test_energy_of_a_push_from_the_greens_function_is_the_dense_one(pushed):
    """pᵀK⁻¹p (the force scale's first step) read from the Green's function of the pushed
    nodes alone, two bars each held at an inner support, against a dense solve with the
    assembled K; 17 pushed nodes take the solve path."""
    rng = np.random.default_rng(pushed)
    bars = tuple(contactqp.Bar.from_areas(rng.uniform(1e-4, 1e-3, 20), 2e11, length=1.0)
                 for _ in range(2))
    scene = contactqp.Scene(bars, (contactqp.Support(7, bar=0), contactqp.Support(12, bar=1)),
                            (), ())
    model = build_model(scene)
    assert model.determinate is not None
    push = np.zeros(model.n_free)
    push[rng.choice(model.n_free, size=pushed, replace=False)] = rng.normal(size=pushed)
    expected = float(push @ np.linalg.solve(model.K.toarray(), push))
    assert model.energy_of(push) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_reactions_with_no_contact_are_each_bars_loads_when_one_support_holds_it(seed):
    """The force scale's ‖R₀‖∞ on a chain whose every bar has one support (read as each bar's
    net load) against the supports' reactions worked out by statics from u₀ = K⁻¹P, and
    against the loads summed by hand; two bars, inner supports, random loads and walls."""
    rng = np.random.default_rng(seed)
    bars = tuple(contactqp.Bar.from_areas(rng.uniform(1e-4, 1e-3, 12), 2e11, length=1.0)
                 for _ in range(2))
    loads = tuple(contactqp.Load(int(rng.integers(13)), float(rng.normal(0.0, 1e5)), bar=b)
                  for b in (0, 0, 1))
    walls = (contactqp.Wall(12, 1e-6, "+", bar=0), contactqp.Wall(0, 1e-6, "-", bar=1))
    scene = contactqp.Scene(bars, (contactqp.Support(int(rng.integers(1, 12)), bar=0),
                                   contactqp.Support(int(rng.integers(1, 12)), bar=1)),
                            loads, walls)
    model = build_model(scene)
    assert model.determinate is not None
    u0 = model.full_displacements(model.free_displacement)
    statics = np.abs(model.reactions_of(u0, np.zeros(model.n_contacts))).max()
    by_hand = max(abs(sum(p.force for p in loads if p.bar == b)) for b in (0, 1))
    assert model.scale_terms().reactions == pytest.approx(statics, rel=1e-9, abs=1e-9)
    assert model.scale_terms().reactions == pytest.approx(by_hand, rel=1e-12)


def test_a_million_element_bar_is_exact_to_round_off():
    """Exact areas: the discrete tip flexibility is the cone's ∫dx/(EA), so the condensed
    contact force equals the continuum closed form up to round-off. Assembling K and
    factoring it (two supports' path) loses ~3e-8 here; statics loses ~n·ε."""
    n = 200_000
    bar = contactqp.Bar.tapered_circle(1.0, n, 0.040, 0.020, 210e9, area_rule="exact")
    seed = contactqp.default_scene()
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(n // 2, seed.loads[0].force),),
                            (contactqp.Wall(n, seed.walls[0].gap, "+"),))
    result = contactqp.solve(scene, formulation="condensed")
    assert result.verified
    assert result.contact_force[0] == pytest.approx(cone_contact_force(), rel=1e-12)


def test_distributed_load_on_part_of_a_bar_and_its_nodal_forces():
    bar = Bar.from_areas([1e-4] * 4, E_SPRINGS, lengths=[0.1, 0.2, 0.3, 0.4])
    scene = Scene(bar, (Support(0),), distributed=(DistributedLoad(1000.0, start=1, stop=3),))
    # element 1 (0.2 m) and 2 (0.3 m): 200 N and 300 N split half to each end
    assert Layout(scene).nodal_loads == pytest.approx([0.0, 100.0, 250.0, 150.0, 0.0])
    result = contactqp.solve(scene)
    assert result.reactions[0] == pytest.approx(-500.0)
    # N(x) = q (0.6 − x) on the loaded part; an element's k·Δu is its mean over the element
    assert result.element_force == pytest.approx([500.0, 400.0, 150.0, 0.0], abs=1e-9)


@pytest.mark.parametrize("method", ["lagrange", "penalty", "augmented", "pgs"])
def test_a_scene_keeps_its_model_and_a_second_solve_is_a_fresh_one_bit_for_bit(method):
    # solve() builds a scene's model once (contactqp.model.scene_model) and a second solve
    # reuses it and all it has worked out: the Result must be the one a copy of the scene,
    # built from nothing, gives, to the last bit
    from dataclasses import replace

    from contactqp.model import scene_model
    from contactqp.random_scenes import random_scene

    seed = int(np.random.default_rng().integers(2**32))  # fresh scenes; seed in the message
    rng = np.random.default_rng(seed)
    for _ in range(15):
        scene = random_scene(rng)
        try:
            first = contactqp.solve(scene, method)
        except contactqp.SolverError:
            continue
        again = contactqp.solve(scene, method)
        fresh = contactqp.solve(replace(scene), method)  # a new object: its own model
        assert again.model is first.model is scene_model(scene)
        assert fresh.model is not first.model
        assert not first.model.band.flags.writeable  # nobody changes what the next reads
        for name in ("u", "contact_force", "reactions", "penetration", "element_force"):
            assert np.array_equal(getattr(again, name), getattr(fresh, name)), (name, seed)
        assert again.residuals == fresh.residuals, seed
        assert (again.verified, again.force_error_bound, again.displacement_error_bound) == (
            fresh.verified, fresh.force_error_bound, fresh.displacement_error_bound), seed


@pytest.mark.parametrize("block", [1, 2, 3, 131072])
@pytest.mark.parametrize("floating", [0.0, 0.5])
@pytest.mark.parametrize("seed", range(8))
def test_the_checks_imbalance_is_k_u_minus_p_plus_c_transpose_lambda(seed, floating, block,
                                                                     monkeypatch):
    """The check's equilibrium term on a chain (Model.largest_imbalance, from K's band or from
    the element forces, in blocks) against the sparse product K u − P + Cᵀλ, on random scenes
    (floating bars and bar contacts included), their exact answers and random ones."""
    import contactqp.model.chain.model as chain_model
    from contactqp.model import element_forces, link_forces, scene_model
    from contactqp.random_scenes import random_scene

    monkeypatch.setattr(chain_model, "IMBALANCE_BLOCK", block)
    rng = np.random.default_rng(seed)
    model = scene_model(random_scene(rng, floating=floating))  # seed 0, 0.5: a row's
    # indices unsorted (a bar contact's two nodes)
    scene = model.layout.scene
    solved = contactqp.solve(scene, "lagrange")  # balanced: a wrong entry stands out
    answers = [(model.free_part(solved.u), solved.contact_force),
               (rng.standard_normal(model.n_free) / model.band[0].max(),
                rng.standard_normal(model.n_contacts) * max(np.abs(model.P).max(initial=0), 1))]
    for u_free, lam in answers:
        exact = np.abs(model.K @ u_free - model.P + model.C.T @ lam).max(initial=0.0)
        u = model.full_displacements(u_free)
        links = link_forces(model.layout, element_forces(model.layout, u))
        assert np.array_equal(model.free_part(u), u_free)
        size = max(np.abs(lam).max(initial=0.0), np.abs(model.P).max(initial=0.0), 1.0)
        for found in (model.largest_imbalance(u_free, lam),
                      model.largest_imbalance(u_free, lam, links)):
            assert found == pytest.approx(exact, rel=1e-12, abs=1e-9 * size)


@pytest.mark.parametrize("block", [1, 7, 131072])
@pytest.mark.parametrize("build", ["obstacle", "channel", "flat_patch"])
@pytest.mark.parametrize("size", [5, 1500])
def test_the_imbalance_with_a_wall_at_every_node_is_k_u_minus_p_plus_c_transpose_lambda(
        build, size, block, monkeypatch):
    """As above, on the scenes with a wall beside every free node (one wall or two per node:
    C's entries one per row, every free node touched, so Cᵀλ adds node by node), as one run of
    free nodes up to SHORT_CHAIN and past it: their exact answers and random ones."""
    import contactqp.model.chain.model as chain_model
    from contactqp.model import element_forces, link_forces, scene_model

    monkeypatch.setattr(chain_model, "IMBALANCE_BLOCK", block)
    model = scene_model(getattr(contactqp.builders, build)(size))
    rng = np.random.default_rng(size)
    solved = contactqp.solve(model.layout.scene, "lagrange")
    answers = [(model.free_part(solved.u), solved.contact_force),
               (rng.standard_normal(model.n_free) / model.band[0].max(),
                rng.standard_normal(model.n_contacts) * max(np.abs(model.P).max(initial=0), 1))]
    for u_free, lam in answers:
        exact = np.abs(model.K @ u_free - model.P + model.C.T @ lam).max(initial=0.0)
        links = link_forces(model.layout, element_forces(model.layout,
                                                         model.full_displacements(u_free)))
        size_ = max(np.abs(lam).max(initial=0.0), np.abs(model.P).max(initial=0.0), 1.0)
        for found in (model.largest_imbalance(u_free, lam),
                      model.largest_imbalance(u_free, lam, links)):
            assert found == pytest.approx(exact, rel=1e-12, abs=1e-9 * size_)


@pytest.mark.parametrize("seed", range(30))
def test_a_chains_row_stiffness_from_its_band_is_the_sparse_products(seed):
    """Model.row_stiffness (from K's band, the rows' one or two nodes) against
    c_iᵀK c_i / (c_iᵀc_i)² by sparse products, on random scenes with bar contacts."""
    from contactqp.model import scene_model
    from contactqp.model.base import row_stiffness
    from contactqp.random_scenes import random_scene

    model = scene_model(random_scene(np.random.default_rng(seed), floating=0.5 * (seed % 2)))
    exact = row_stiffness(model.K, model.C)
    np.testing.assert_allclose(model.row_stiffness, exact, rtol=1e-13, atol=0.0)
    columns, place = model._contact_columns
    np.testing.assert_array_equal(columns[place], model._entries[1])
    np.testing.assert_array_equal(columns, np.unique(model._entries[1]))
