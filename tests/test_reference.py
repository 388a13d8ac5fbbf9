"""The exact reference (contactqp.reference): against the continuum, exact rational arithmetic
and scipy's bounded least squares, each computed here independently."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

import contactqp
from contactqp import Bar, Load, Scene, SceneError, Support, Wall
from contactqp.reference import reference
from contactqp.scene import BarContact, DistributedLoad
from contactqp.studies import cone_contact_force
from test_explicit_methods import cantilever

E = 210e9


def test_matches_the_continuum_on_a_bar_with_exact_areas():
    # exact areas make every node of the discrete bar exact: λ = (F f(0, L/2) − g) / f(0, L)
    bar = Bar.tapered_circle(1.0, 10_000, 0.040, 0.020, E, area_rule="exact")
    scene = Scene(bar, (Support(0),), (Load(5_000, 565486.67),), (Wall(10_000, 1e-4),))
    exact = cone_contact_force()
    assert reference(scene).contact_force[0] == pytest.approx(exact, rel=1e-14)


@pytest.mark.parametrize(("load", "gap", "side"), [(3.0e5, 2e-4, "+"), (-3.0e5, 2e-4, "-"),
                                                   (3.0e5, 5e-2, "+"), (4.0e5, -1e-4, "+")])
def test_matches_exact_rational_arithmetic(load, gap, side):
    areas = [1.1e-3, 8.3e-4, 5.9e-4, 4.0e-4, 3.3e-4]
    lengths = [0.2, 0.3, 0.1, 0.25, 0.15]
    scene = Scene(Bar.from_areas(areas, E, lengths=lengths), (Support(0),), (Load(2, load),),
                  (Wall(5, gap, side),))
    # the closed form in Fractions, from the same float data read exactly
    u, lam = cantilever([Fraction(x) for x in lengths], [Fraction(a) for a in areas],
                        Fraction(E), [(2, Fraction(load))], (5, Fraction(gap), side))
    found = reference(scene)
    assert found.contact_force[0] == pytest.approx(float(lam), rel=1e-15, abs=1e-12)
    assert found.displacement == pytest.approx([float(x) for x in u], rel=1e-15, abs=1e-20)


def bounded_least_squares(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(u at the free nodes, λ per wall) of min ½uᵀKu − Pᵀu with every wall a bound on its
    node, by scipy's BVLS on ‖R u − R⁻ᵀP‖² (K = RᵀR)."""
    model = contactqp.build_model(scene)
    R = sla.cholesky(model.K.toarray())
    lower, upper = np.full(model.n_free, -np.inf), np.full(model.n_free, np.inf)
    rows = model.C.tocsr()
    for i in range(rows.shape[0]):
        column, sign = rows.indices[rows.indptr[i]], rows.data[rows.indptr[i]]
        if sign > 0:
            upper[column] = min(upper[column], model.g[i])
        else:
            lower[column] = max(lower[column], -model.g[i])
    target = sla.solve_triangular(R, model.P, trans="T")
    u = lsq_linear(R, target, bounds=(lower, upper), method="bvls", tol=1e-15).x
    residual = model.K @ u - model.P  # = −Cᵀλ: what the walls supply at their nodes
    lam = np.array([-rows.data[rows.indptr[i]] * residual[rows.indices[rows.indptr[i]]]
                    for i in range(rows.shape[0])])
    return u, lam


@st.composite
def wall_scenes(draw):
    n = draw(st.integers(3, 12))
    areas = draw(st.lists(st.floats(1e-4, 1e-3), min_size=n, max_size=n))
    bar = Bar.from_areas(areas, E, length=1.0)
    supports = sorted(set(draw(st.lists(st.integers(0, n), min_size=1, max_size=2))))
    free = [j for j in range(n + 1) if j not in supports]
    loads = tuple(Load(j, draw(st.floats(-5e5, 5e5).filter(lambda f: abs(f) > 1e3)))
                  for j in draw(st.lists(st.sampled_from(free), min_size=1, max_size=3,
                                         unique=True)))
    walls = tuple(Wall(j, draw(st.floats(-2e-4, 2e-3)), side)
                  for j in draw(st.lists(st.sampled_from(free), min_size=1, max_size=n,
                                         unique=True))
                  for side in draw(st.sampled_from([("+",), ("-",)])))
    distributed = (DistributedLoad(draw(st.floats(-1e6, 1e6))),) if draw(st.booleans()) else ()
    return Scene(bar, tuple(Support(j) for j in supports), loads, walls, distributed=distributed)


@given(wall_scenes())
def test_matches_bounded_least_squares_on_random_bars(scene):
    u_free, lam = bounded_least_squares(scene)
    found = reference(scene)
    free = np.setdiff1d(np.arange(scene.n_nodes), scene.support_nodes)
    # u may be exactly 0 (a closed zero gap): then the load over the stiffest element is the scale
    scale_u = max(np.abs(u_free).max(), np.abs(scene.nodal_loads()).max() / scene.stiffness.max())
    assert np.abs(found.displacement[free] - u_free).max() <= 1e-8 * scale_u
    scale_f = max(np.abs(scene.nodal_loads()).max(), np.abs(lam).max())
    assert np.abs(found.contact_force - lam).max() <= 1e-8 * scale_f
    assert found.contact_force.min() >= 0.0  # a certified answer: the walls only push


def test_the_touching_wall_carries_nothing():
    # the load that brings node 4 exactly to the wall: F · f(0, node 2) = g
    scene = contactqp.seed_scene()
    k = scene.stiffness
    touching = 1e-4 / float(sum(Fraction(1) / Fraction(x) for x in k[:2]))
    found = reference(scene.with_loads((Load(2, touching),)))
    assert abs(found.contact_force[0]) <= 1e-12 * touching


@pytest.mark.parametrize(("scene", "words"), [
    (Scene((Bar.from_areas([1e-4], E, length=1.0),) * 2, (Support(0, 0), Support(0, 1)),
           contacts=(BarContact(0, 1, 1, 1, 1e-3),)), ["2 bars", "1 bar contacts"]),
])
def test_refuses_scenes_outside_its_reach(scene, words):
    with pytest.raises(SceneError) as raised:
        reference(scene)
    for word in words:
        assert word in str(raised.value)
