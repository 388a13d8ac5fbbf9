"""The condensed formulation agrees with the full one and with the explicit Lagrange solution.

Glossary: K stiffness of the free nodes, C wall rows, g gaps, λ contact forces (N). The
condensed model keeps only the nodes with walls: S = B K⁻¹ Bᵀ their flexibility; every method
solved on it must give the λ and u of the full model.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import contactqp
from contactqp.model import build_model, condense, wall_forces

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
    loads = [contactqp.Load(i, draw(st.floats(-1e6, 1e6))) for i in
             draw(st.lists(st.sampled_from(free), min_size=1, max_size=3, unique=True))]
    walls = []
    for node in draw(st.lists(st.sampled_from(free), min_size=1, max_size=4, unique=True)):
        for side in draw(st.sampled_from([("+",), ("-",), ("+", "-")])):
            walls.append(contactqp.Wall(node, draw(st.floats(0.0, 1e-3)), side))
    return contactqp.Scene(bar, tuple(contactqp.Support(s) for s in supports), tuple(loads),
                           tuple(walls))


@settings(max_examples=25, deadline=None)
@given(scenes())
def test_condensed_equals_full_for_the_explicit_methods(scene):
    full = contactqp.solve(scene)
    # forces below ~1e-12 k·gap are round-off to Lagrange's active-set decision (it ignores
    # penetrations below 1e-12 of the displacement scale), so the force scale includes k·gap
    largest_gap = max(w.gap for w in scene.walls)
    force_scale = max(np.abs(full.contact_force).max(), max(abs(p.force) for p in scene.loads),
                      scene.bar.stiffness.min() * largest_gap)
    # a displacement scale that stays physical when the exact u is 0 (a closed zero gap)
    disp_scale = max(np.abs(full.u).max(), force_scale / scene.bar.stiffness.max())
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
