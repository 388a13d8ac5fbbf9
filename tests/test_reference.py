"""The exact references (contactqp.reference): the statics path against the continuum, exact
rational arithmetic and scipy's bounded least squares; the rational path against closed forms
in Fractions, a brute force over active sets in float64, and the statics path. Each expected
value is computed here, independently.

Glossary: k = EA/L of an element (N/m), k₁, k₂ of the two bars of a pair, P point load (N),
q distributed load (N/m), g gap (m), λ contact force (N, one per contact row: walls, then bar
contacts), u displacement (m, one per global node), F and U the force and displacement scales
of a scene (N, m), under which a tolerance is stated.
"""

from __future__ import annotations

import itertools
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

import contactqp
from closed_forms import (
    E_STEEL,
    cantilever,
    clamped,
    cone_contact_force,
    exact,
    spring,
)
from contactqp import (
    Bar,
    BarContact,
    Load,
    Scene,
    SceneError,
    Support,
    Wall,
)
from contactqp.model import (
    Layout,
)
from contactqp.reference import reference, statics_reference
from contactqp.reference.exact import (
    ENUMERATION_BUDGET,
    MAX_EXACT_NODES,
    _ExactScene,
    _textbook_loop,
    rational_reference,
)
from contactqp.scene import DistributedLoad
from contactqp.scene_io import load_scene


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
    bar = Bar.from_areas(areas, E_STEEL, length=1.0)
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


def cycling_scene() -> Scene:
    """A scene on which the textbook loop cycles, active sets (rows) {0, 1, 3} → {3} →
    {0, 2, 3} → {0} → {0, 1, 3} (found by a random search): bar 0 (three elements, the
    first soft) held at node 0, pulled by −1 MN at its tip node 3; bar 1 held at node 0,
    pushed by 0.1 MN at node 1, which faces bar 0's tip across 0.1 mm; a "−" wall 0.1 mm
    from bar 0's node 1 and walls on both sides of bar 1's node 1."""
    return Scene((Bar.from_areas([1e-5, 1e-2, 1e-2], 2e11, length=1.0),
                  Bar.from_areas([1e-4], 2e11, length=1.0)),
                 (Support(0, 0), Support(0, 1)), (Load(3, -1e6, 0), Load(1, 1e5, 1)),
                 (Wall(1, 1e-4, "-", 0), Wall(1, 0.0, "+", 1), Wall(1, 1e-3, "-", 1)),
                 contacts=(BarContact(1, 1, 0, 3, 1e-4),))


def log_uniform(low: float, high: float):
    return st.floats(np.log10(low), np.log10(high)).map(lambda x: 10.0**x)


@st.composite
def contact_scenes(draw, max_bars: int = 3, contacts: bool = True) -> Scene:
    """1 to ``max_bars`` bars of 1 to 6 elements, areas over five decades, lengths over one;
    one or two supports per bar; point loads and distributed loads of either sign; walls on
    one side or both (zero, open and press-fit gaps, and clamped pairs g₊ + g₋ = 0); one or
    two bar contacts when there are several bars (zero or open gaps, between any two nodes).
    At most 8 contact rows (the brute force's 2⁸ sets).
    Gaps are drawn relative to a displacement the loads can cause, so contacts open, close
    and touch."""
    bars = [Bar.from_areas(draw(st.lists(log_uniform(1e-6, 1e-1), min_size=n, max_size=n)), E_STEEL,
                           lengths=draw(st.lists(st.floats(0.1, 1.0), min_size=n, max_size=n)))
            for n in draw(st.lists(st.integers(1, 6), min_size=1, max_size=max_bars))]
    nodes = [(b, j) for b, bar in enumerate(bars) for j in range(bar.n_nodes)]
    held = {(b, j) for b, bar in enumerate(bars)
            for j in draw(st.sets(st.integers(0, bar.n_nodes - 1), min_size=1, max_size=2))}
    assume(len(held) < len(nodes))
    free = [node for node in nodes if node not in held]
    force = st.builds(lambda sign, size: sign * size, st.sampled_from([-1.0, 1.0]),
                      log_uniform(1e2, 1e6))
    loads = [Load(j, draw(force), b) for b, j in draw(st.lists(st.sampled_from(free), max_size=3))]
    distributed = []
    if draw(st.booleans()):
        b = draw(st.integers(0, len(bars) - 1))
        start = draw(st.integers(0, bars[b].n_elements - 1))
        stop = draw(st.integers(start + 1, bars[b].n_elements))
        distributed.append(DistributedLoad(10.0 * draw(force), b, start, stop))
    # the displacement the loads cause across the softest element
    total = sum(abs(p.force) for p in loads) + sum(abs(q.intensity) for q in distributed)
    scale = max(total, 1.0) / min(float(bar.element_stiffness.min()) for bar in bars)
    gap = st.one_of(st.just(0.0), st.floats(1e-3, 1.0).map(lambda f: f * scale),
                    st.floats(-0.3, -1e-3).map(lambda f: f * scale))
    walls = []
    for b, j in draw(st.lists(st.sampled_from(free), min_size=1, max_size=4, unique=True)):
        sides = draw(st.sampled_from(["+", "-", "+-"]))
        gaps = [draw(gap) for _ in sides]
        if len(gaps) == 2 and gaps[0] + gaps[1] < 0.0:  # room for the node: g₊ + g₋ >= 0
            gaps[1] = -gaps[0] if draw(st.booleans()) else abs(gaps[0]) + abs(gaps[1])
        walls += [Wall(j, g, side, b) for g, side in zip(gaps, sides)]
    pairs = []
    if contacts and len(bars) > 1:
        for _ in range(draw(st.integers(1, 2))):
            (ba, ja), (bb, jb) = draw(st.lists(st.sampled_from(nodes), min_size=2, max_size=2,
                                               unique=True))
            pairs.append(BarContact(ba, ja, bb, jb, draw(st.one_of(st.just(0.0), gap.map(abs)))))
    assume(len(walls) + len(pairs) <= 8)
    try:
        return Scene(tuple(bars), tuple(Support(j, b) for b, j in sorted(held)), tuple(loads),
                     tuple(walls), distributed=tuple(distributed), contacts=tuple(pairs))
    except SceneError:  # two contacts on one pair of nodes, or constraints with no solution
        assume(False)


def brute_force_float(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, λ, C_f) of min ½uᵀKu − Pᵀu subject to C u <= g and u = 0 at the supports, in
    float64, by trying every linearly independent set of active rows (dense KKT solve, C
    scaled to K's size) and keeping the one that satisfies the KKT conditions best; K and C
    assembled here from the bars, walls and contacts. C_f: C's columns of the free nodes."""
    offsets = np.cumsum([0] + [bar.n_nodes for bar in scene.bars])
    n = int(offsets[-1])
    K = np.zeros((n, n))
    for b, bar in enumerate(scene.bars):
        for e, k in enumerate(bar.youngs_modulus * bar.areas / bar.lengths):
            i = offsets[b] + e
            K[i:i + 2, i:i + 2] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    C = np.zeros((len(scene.walls) + len(scene.contacts), n))
    for r, w in enumerate(scene.walls):
        C[r, offsets[w.bar] + w.node] = 1.0 if w.side == "+" else -1.0
    for r, c in enumerate(scene.contacts, start=len(scene.walls)):
        C[r, offsets[c.bar_a] + c.node_a] += 1.0
        C[r, offsets[c.bar_b] + c.node_b] -= 1.0
    g = np.array([w.gap for w in scene.walls] + [c.gap for c in scene.contacts])
    P = Layout(scene).nodal_loads
    free = np.ones(n, dtype=bool)
    free[[offsets[s.bar] + s.node for s in scene.supports]] = False
    Kf, Cf, Pf = K[np.ix_(free, free)], C[:, free], P[free]
    size = np.abs(K).max()
    force = max(np.abs(P).sum(), 1.0)
    length = max(force / np.diag(Kf).min(), np.abs(g).max(initial=0.0))
    best = None
    for m in range(len(g) + 1):
        for active in map(list, itertools.combinations(range(len(g)), m)):
            if m and np.linalg.matrix_rank(Cf[active]) < m:
                continue
            kkt = np.block([[Kf, size * Cf[active].T], [size * Cf[active], np.zeros((m, m))]])
            x = np.linalg.solve(kkt, np.r_[Pf, size * g[active]])
            u = np.zeros(n)
            u[free] = x[:free.sum()]
            lam = np.zeros(len(g))
            lam[active] = size * x[free.sum():]
            inactive = np.setdiff1d(np.arange(len(g)), active)
            violation = max(np.max(-lam[active] / force, initial=0.0),
                            np.max((C[inactive] @ u - g[inactive]) / length, initial=0.0))
            if best is None or violation < best[0]:
                best = (violation, u, lam)
    assert best[0] <= 1e-9, best[0]  # a KKT point, to round-off
    return best[1], best[2], Cf


TOLERANCE = 1e-7


def test_matches_the_continuum_on_a_bar_with_exact_areas():
    # exact areas make every node of the discrete bar exact: λ = (F f(0, L/2) − g) / f(0, L)
    bar = Bar.tapered_circle(1.0, 10_000, 0.040, 0.020, E_STEEL, area_rule="exact")
    scene = Scene(bar, (Support(0),), (Load(5_000, 565486.67),), (Wall(10_000, 1e-4),))
    exact = cone_contact_force()
    assert reference(scene).contact_force[0] == pytest.approx(exact, rel=1e-14)


@pytest.mark.parametrize(("load", "gap", "side"), [(3.0e5, 2e-4, "+"), (-3.0e5, 2e-4, "-"),
                                                   (3.0e5, 5e-2, "+"), (4.0e5, -1e-4, "+")])
def test_matches_exact_rational_arithmetic(load, gap, side):
    areas = [1.1e-3, 8.3e-4, 5.9e-4, 4.0e-4, 3.3e-4]
    lengths = [0.2, 0.3, 0.1, 0.25, 0.15]
    scene = Scene(Bar.from_areas(areas, E_STEEL, lengths=lengths), (Support(0),), (Load(2, load),),
                  (Wall(5, gap, side),))
    # the closed form in Fractions, from the same float data read exactly
    u, lam = cantilever([Fraction(x) for x in lengths], [Fraction(a) for a in areas],
                        Fraction(E_STEEL), [(2, Fraction(load))], (5, Fraction(gap), side))
    found = reference(scene)
    assert found.contact_force[0] == pytest.approx(float(lam), rel=1e-15, abs=1e-12)
    assert found.displacement == pytest.approx([float(x) for x in u], rel=1e-15, abs=1e-20)


@given(wall_scenes())
def test_matches_bounded_least_squares_on_random_bars(scene):
    u_free, lam = bounded_least_squares(scene)
    # scipy's BVLS (1.17) can divide 0 by 0 when a step lands a variable exactly on a bound
    # (u = 0 against zero-gap walls); such a scene is left to the rational path's tests
    assume(np.all(np.isfinite(u_free)))
    found = reference(scene)
    free = np.setdiff1d(np.arange(Layout(scene).n_nodes), Layout(scene).support_nodes)
    # u may be exactly 0 (a closed zero gap): then the load over the stiffest element is the scale
    scale_u = max(np.abs(u_free).max(), np.abs(Layout(scene).nodal_loads).max() / Layout(scene).element_stiffness.max())
    assert np.abs(found.displacement[free] - u_free).max() <= 1e-8 * scale_u
    scale_f = max(np.abs(Layout(scene).nodal_loads).max(), np.abs(lam).max())
    assert np.abs(found.contact_force - lam).max() <= 1e-8 * scale_f
    assert found.contact_force.min() >= 0.0  # a certified answer: the walls only push


def test_the_touching_wall_carries_nothing():
    # the load that brings node 4 exactly to the wall: F · f(0, node 2) = g
    scene = contactqp.default_scene()
    k = Layout(scene).element_stiffness
    touching = 1e-4 / float(sum(Fraction(1) / Fraction(x) for x in k[:2]))
    found = reference(scene.with_loads((Load(2, touching),)))
    assert abs(found.contact_force[0]) <= 1e-12 * touching


@pytest.mark.parametrize(("k1", "k2", "gap", "load"), [(2e8, 5e7, 1e-4, 5e4), (1e6, 3e9, 2e-3, 7e3),
                                                       (2e8, 5e7, 1e-4, 1e4)])
def test_two_bars_closed_form(k1, k2, gap, load):
    """Bar 0 held at node 0 and pushed by P at node 1, which faces node 0 of bar 1 (held at
    its node 1) across g: λ = (P − k₁g)·k₂/(k₁ + k₂) once P > k₁g, else 0 and u_a = P/k₁."""
    scene = Scene((spring(k1), spring(k2)), (Support(0, 0), Support(1, 1)), (Load(1, load, 0),),
                  contacts=(BarContact(0, 1, 1, 0, gap),))
    found = reference(scene)
    # in Fractions from the scene's own float data, read exactly: the rational path must give
    # the same exact number, so both round to the same double
    k1_, k2_ = exact(Layout(scene).element_stiffness)
    P, g = Fraction(load), Fraction(gap)
    lam = max((P - k1_ * g) * k2_ / (k1_ + k2_), Fraction(0))
    assert found.contact_force.tolist() == [float(lam)]
    assert found.displacement.tolist() == [0.0, float((P - lam) / k1_), float(lam / k2_), 0.0]
    assert found.precision == 0.0
    # the closed form in floats, for the reader: the same to round-off (a few ulp)
    assert found.contact_force[0] == pytest.approx(max((load - k1 * gap) * k2 / (k1 + k2), 0.0),
                                                   rel=1e-14)


def test_the_two_bar_example_carries_its_stated_force():
    # examples/two_bars.toml: λ = (50e3 − 2e8 · 1e-4) · 5e7 / 2.5e8 = 6000 N, to the rounding
    # of E·A/L in floats (~1e-16)
    scene = load_scene(Path(__file__).parent.parent / "examples" / "two_bars.toml")
    assert reference(scene).contact_force[0] == pytest.approx(6000.0, rel=1e-14)


@pytest.mark.parametrize("path", [statics_reference, rational_reference])
def test_distributed_load_with_a_wall(path):
    """Uniform bar held at x = 0 under q over its length L, a wall g past its tip: the free tip
    would move qL²/(2EA) (consistent nodal loads make the nodes exact), so
    λ = (qL²/(2EA) − g)·EA/L and u(x) = q(Lx − x²/2)/EA − λx/EA."""
    q, L, area, n, gap = 4e4, 2.0, 1e-4, 10, 1e-4
    bar = Bar.from_areas(np.full(n, area), E_STEEL, length=L)
    scene = Scene(bar, (Support(0),), distributed=(DistributedLoad(q),), walls=(Wall(n, gap),))
    EA = E_STEEL * area
    lam = (q * L**2 / (2 * EA) - gap) * EA / L
    found = path(scene)
    # the scene's floats (L/n, E·A/(L/n), q·L_e/2) are rounded at 1.1e-16 each; λ sums ten
    # elements' worth and loses a factor 1.03 to cancellation (qL²/(2EA) = 40 g): ≲ 1e-14
    assert found.contact_force[0] == pytest.approx(lam, rel=1e-13)
    x = bar.node_x
    assert found.displacement == pytest.approx(q * (L * x - x**2 / 2) / EA - lam * x / EA,
                                               rel=1e-13, abs=1e-13 * gap)


@pytest.mark.parametrize("path", [statics_reference, rational_reference])
@pytest.mark.parametrize(("load", "forces"), [
    (Load(2, 1e5), [0.0, 0.0, 1e5]),  # node 2 pushed into its wall: node 1 carries nothing
    (Load(1, 3e5), [3e5, 0.0, 0.0]),  # node 1 pushed in +x: the "+" wall takes it
    (Load(1, -3e5), [0.0, 3e5, 0.0]),  # node 1 pushed in −x: the "−" wall takes it
])
def test_clamped_pair_only_the_wall_pushed_against_carries_the_load(path, load, forces):
    """Walls "+" and "−" at one node with gaps summing to 0 are dependent rows; the answer is
    the one where the wall the net force pushes against takes all of it (the convention of
    test_clamped_node), and nothing moves: every value is exact, with no round-off."""
    found = path(clamped(load))
    assert found.contact_force.tolist() == forces
    assert not np.any(found.displacement)


def test_clamped_pair_loaded_through_a_bar_contact():
    """Bar 1 (held at its node 1) pushes its node 0 with −F into node 1 of bar 0, clamped
    between zero-gap walls, across a zero gap: bar 1's element carries nothing (both its
    nodes stay at 0), so the contact passes F, and the "−" wall takes it."""
    force = 2.5e5
    scene = Scene((spring(1e8), spring(3e8)), (Support(0, 0), Support(1, 1)),
                  (Load(0, -force, 1),), (Wall(1, 0.0, "+", 0), Wall(1, 0.0, "-", 0)),
                  contacts=(BarContact(0, 1, 1, 0, 0.0),))
    found = reference(scene)
    assert found.contact_force.tolist() == [0.0, force, force]
    assert not np.any(found.displacement)


@pytest.mark.parametrize("max_steps", [None, 1])
def test_a_scene_where_the_textbook_loop_cycles(max_steps):
    """The answer: bar 0's node 1 on its wall (u₁ = −g_w) and the contact closed
    (u₅ − u₃ = g_c). With k_s = 1/(1/k₁ + 1/k₂) the series stiffness of bar 0's elements 1
    and 2, k₃ bar 1's: equilibrium k_s (u₃ − u₁) = P₃ + λ_c at the tip, k₃ u₅ = P₅ − λ_c at
    bar 1's node 1, and the wall's λ_w = k₀ u₁ − (P₃ + λ_c) at node 1 give
    λ_c = (P₅/k₃ + g_w − P₃/k_s − g_c) / (1/k₃ + 1/k_s). By default the primal loop finds
    it; ``max_steps=1`` cuts both loops short, and every active set is tried instead."""
    scene = cycling_scene()
    assert _textbook_loop(_ExactScene.of(scene), 100) is None  # the loop does cycle here
    k0, k1, k2, k3 = exact(Layout(scene).element_stiffness)
    ks = 1 / (1 / k1 + 1 / k2)
    P3, P5, gw, gc = Fraction(-1e6), Fraction(1e5), Fraction(1e-4), Fraction(1e-4)
    lam_c = (P5 / k3 + gw - P3 / ks - gc) / (1 / k3 + 1 / ks)
    u1 = -gw
    lam_w = k0 * u1 - (P3 + lam_c)
    u = [0, u1, u1 + (P3 + lam_c) / k1, u1 + (P3 + lam_c) / ks, 0, (P5 - lam_c) / k3]
    found = reference(scene, max_steps)
    assert found.contact_force.tolist() == [float(lam_w), 0.0, 0.0, float(lam_c)]
    assert found.displacement.tolist() == [float(x) for x in u]


def test_refuses_to_enumerate_too_many_rows():
    # with max_steps=1 neither loop finishes, and 2^24 active sets on 14 nodes exceed the budget
    bars = (Bar.from_areas([1e-4] * 6, E_STEEL, length=1.0),) * 2
    walls = tuple(Wall(j, 1e-5 * j, side, b) for b in (0, 1) for j in range(1, 7)
                  for side in "+-")
    scene = Scene(bars, (Support(0, 0), Support(0, 1)), (Load(6, 1e6, 0), Load(6, -1e6, 1)),
                  walls)
    assert 2**24 * 14**2 > ENUMERATION_BUDGET
    with pytest.raises(SceneError, match="24 contact rows on 14 nodes are too many"):
        rational_reference(scene, max_steps=1)
    assert reference(scene).contact_force.min() >= 0.0  # the default steps suffice


def test_refuses_scenes_beyond_the_rational_size_limit():
    n = MAX_EXACT_NODES // 2
    bars = (Bar.from_areas([1e-4] * n, E_STEEL, length=1.0),) * 2  # 2(n + 1) nodes
    scene = Scene(bars, (Support(0, 0), Support(0, 1)), contacts=(BarContact(0, n, 1, 0, 0.0),))
    with pytest.raises(SceneError) as raised:
        reference(scene)
    assert f"has {2 * n + 2} nodes" in str(raised.value)
    assert f"at most {MAX_EXACT_NODES}" in str(raised.value)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.filter_too_much])
@given(contact_scenes())
def test_rational_path_matches_brute_force_on_random_scenes(scene):
    found = rational_reference(scene)
    u, lam, C = brute_force_float(scene)
    F = max(np.abs(Layout(scene).nodal_loads).max(), np.abs(lam).max(initial=0.0), 1e-300)
    U = max(np.abs(u).max(), np.abs(Layout(scene).gaps).max(initial=0.0), F / Layout(scene).element_stiffness.max())
    # TOLERANCE: the float64 brute force is backward stable, its error ≲ eps·κ of F and U,
    # κ ≲ 1e6 (neighbouring stiffnesses: areas over five decades, lengths over one) × ≲ 20
    # nodes in a chain: ≲ 2e-9 (≤ 3e-10 seen over 5000 scenes); the rational answer is
    # exact, rounded once
    assert np.abs(found.displacement - u).max() <= TOLERANCE * U
    # the contact forces on the free nodes, C_fᵀλ = P − K u, are unique; λ itself is unless
    # active rows are dependent (a clamped pair, two zero-gap rows on one node, a cycle)
    assert np.abs(C.T @ (found.contact_force - lam)).max(initial=0.0) <= TOLERANCE * F
    free = np.setdiff1d(np.arange(Layout(scene).n_nodes), Layout(scene).support_nodes)
    tight = np.abs(C @ found.displacement[free] - Layout(scene).gaps) <= TOLERANCE * U
    # (numpy before 2.0 has no rank for a matrix with no rows)
    if not tight.any() or np.linalg.matrix_rank(C[tight]) == tight.sum():
        assert np.abs(found.contact_force - lam).max(initial=0.0) <= TOLERANCE * F
    assert found.contact_force.min(initial=0.0) >= 0.0  # certified exactly: rows only push


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.filter_too_much])
@given(contact_scenes(max_bars=1, contacts=False))
def test_rational_and_statics_paths_agree_on_one_bar(scene):
    rational, statics = rational_reference(scene), statics_reference(scene)
    F = max(np.abs(Layout(scene).nodal_loads).max(), np.abs(rational.contact_force).max(initial=0.0),
            1e-300)
    U = max(np.abs(rational.displacement).max(), np.abs(Layout(scene).gaps).max(initial=0.0),
            F / Layout(scene).element_stiffness.min())
    # the statics path sums ≤ 7 terms in longdouble (1.1e-19) and certifies to CERTIFICATE =
    # 1e-13 of F and U: a wall that touches to within that may go either way, by ≲ 1e-13
    assert np.abs(rational.displacement - statics.displacement).max() <= 1e-12 * U
    assert np.abs(rational.contact_force - statics.contact_force).max(initial=0.0) <= 1e-12 * F
