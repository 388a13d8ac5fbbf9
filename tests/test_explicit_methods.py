"""The explicit methods (Lagrange multipliers and penalty) against closed forms.

Symbols (SI units)
------------------
E         Young's modulus (Pa)
A_e, L_e  area (m²) and length (m) of element e, which joins nodes e and e + 1
k_e       E A_e / L_e, axial stiffness of element e (N/m)
f_j       Σ_{e<j} L_e / (E A_e): flexibility of a cantilever fixed at node 0, seen at node j
          (m/N); with the "exact" area rule, f(x) = 4x / (E π d_0 d(x)) for a cone
F, a      a point load (N, +x) and its node
u_free,j  displacement of node j with no wall: Σ_loads F f_min(a, j) (m)
w, g, s   a wall's node, gap (m) and side sign (+1 for "+", -1 for "-"): s u_w <= g
λ         contact force, how hard the wall pushes the bar (N, >= 0 when physical);
          one wall on a cantilever: λ = (s u_free,w − g) / f_w (clamped at 0 for inequality)
u_j       displacement of node j: u_free,j − s λ f_min(w, j) (m)
R         reaction of a support: the force it applies to the bar in +x (N)
ε         penalty stiffness (N/m): λ_ε = (s u_free,w − g) / (f_w + 1/ε),
          penetration λ_ε / ε, and (λ − λ_ε) / λ = 1 / (1 + ε f_w) ≈ 1 / (ε f_w)
K, P      dense stiffness (N/m) and loads (N) of the free nodes, assembled here
C, g      one row per wall, s at the wall's node: the walls hold where C u <= g

Several walls are checked by brute force: every set of walls in contact is tried with a dense
numpy solve of [[K, Cᵀ], [C, 0]] [u; λ] = [P; g], and the one that satisfies the KKT conditions
(C u <= g, λ >= 0) is the answer.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from contactqp import Bar, Load, OptionError, Scene, Support, Wall

# The seed scene, as the problem states it
SEED_E = 210e9  # Pa
SEED_YIELD = 200e6  # Pa
SEED_F, SEED_LOAD_NODE = 565486.67, 2  # N
SEED_GAP, SEED_WALL_NODE = 1e-4, 4  # m
SEED_LENGTHS = [0.25] * 4  # m
SEED_DIAMETERS = [0.040, 0.035, 0.030, 0.025, 0.020]  # m, at nodes 0..4


def seed_areas(area_rule: str) -> list[float]:
    """Element areas of the seed bar from its diameters (m²)."""
    pairs = itertools.pairwise(SEED_DIAMETERS)
    if area_rule == "midpoint":
        return [math.pi * ((da + db) / 2) ** 2 / 4 for da, db in pairs]
    return [math.pi * da * db / 4 for da, db in pairs]


def seed_scene_with(area_rule: str = "midpoint", force: float = SEED_F,
                    walls: tuple[Wall, ...] = (Wall(SEED_WALL_NODE, SEED_GAP, "+"),)) -> Scene:
    bar = Bar.tapered_circle(1.0, 4, 0.040, 0.020, SEED_E, area_rule=area_rule,
                             yield_stress=SEED_YIELD)
    return Scene(bar, (Support(0),), (Load(SEED_LOAD_NODE, force),), walls)


def cantilever(lengths, areas, modulus, loads, wall, *, contact="inequality", penalty=None):
    """Closed form (u at every node, λ) of a bar fixed at node 0 with one wall.

    Pure Python, so it runs on floats and on Fractions alike. ``loads`` is [(node, force)],
    ``wall`` is (node, gap, side); ``penalty`` ε adds the spring's flexibility 1/ε.
    """
    flex = list(itertools.accumulate(
        (length / (modulus * area) for length, area in zip(lengths, areas)), initial=0))
    nodes = range(len(flex))
    u_free = [sum(force * flex[min(a, j)] for a, force in loads) for j in nodes]
    w, gap, side = wall
    s = 1 if side == "+" else -1
    lam = (s * u_free[w] - gap) / (flex[w] + (0 if penalty is None else 1 / penalty))
    if contact == "inequality":
        lam = max(lam, 0 * lam)
    return [u_free[j] - s * lam * flex[min(w, j)] for j in nodes], lam


def seed_closed_form(area_rule="midpoint", force=SEED_F, contact="inequality", penalty=None):
    return cantilever(SEED_LENGTHS, seed_areas(area_rule), SEED_E, [(SEED_LOAD_NODE, force)],
                      (SEED_WALL_NODE, SEED_GAP, "+"), contact=contact, penalty=penalty)


def seed_flexibility(node: int, area_rule: str = "midpoint") -> float:
    """f_node of the seed bar (m/N)."""
    return sum(length / (SEED_E * area)
               for length, area in zip(SEED_LENGTHS[:node], seed_areas(area_rule)[:node]))


def assert_normwise(actual, expected, rel: float) -> None:
    """max |actual − expected| <= rel · max |expected|: how round-off shows in a solve."""
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    assert actual.shape == expected.shape
    assert np.abs(actual - expected).max(initial=0.0) <= rel * np.abs(expected).max(initial=0.0)


# --------------------------------------------------------------------------------------------
# Dense algebra and brute force, assembled here from the scene's data


def dense_algebra(scene: Scene):
    """(K_full, P_full, free nodes, K, P, C, g) with K_full and P_full over every node."""
    bar = scene.bar
    n = scene.n_nodes
    k = np.asarray(bar.youngs_modulus) * np.asarray(bar.areas) / np.asarray(bar.lengths)
    K_full = np.zeros((n, n))
    for e, ke in enumerate(k):
        K_full[e:e + 2, e:e + 2] += ke * np.array([[1.0, -1.0], [-1.0, 1.0]])
    P_full = np.zeros(n)
    for load in scene.loads:
        P_full[load.node] += load.force
    held = {s.node for s in scene.supports}
    free = [j for j in range(n) if j not in held]
    C = np.zeros((len(scene.walls), len(free)))
    for i, wall in enumerate(scene.walls):
        C[i, free.index(wall.node)] = 1.0 if wall.side == "+" else -1.0
    g = np.array([w.gap for w in scene.walls], dtype=float)
    return K_full, P_full, free, K_full[np.ix_(free, free)], P_full[free], C, g


def scales(scene: Scene, u: np.ndarray, lam: np.ndarray) -> tuple[float, float]:
    """(force scale N, displacement scale m) against which round-off is measured: the largest
    load or contact force, and the largest of |u|, the gaps and what that force does to the
    softest element (so the scale stays physical where the exact u is 0)."""
    bar = scene.bar
    force = max(np.abs(scene.nodal_loads()).max(), np.abs(lam).max(initial=0.0))
    k_min = float(np.min(np.asarray(bar.youngs_modulus) * bar.areas / bar.lengths))
    gaps = [w.gap for w in scene.walls]
    return force, max(np.abs(u).max(initial=0.0), max(gaps, default=0.0), force / k_min)


def brute_force(scene: Scene, contact: str = "inequality"):
    """(u at every node, λ, walls in contact) by trying every set of walls in contact."""
    _, _, free, K, P, C, g = dense_algebra(scene)
    m = g.size
    if contact == "equality":
        candidates = [tuple(range(m))]
    else:
        candidates = itertools.chain.from_iterable(
            itertools.combinations(range(m), r) for r in range(m + 1))
    for active in candidates:
        active = list(active)
        nodes = [scene.walls[i].node for i in active]
        if len(set(nodes)) < len(nodes):
            continue  # one node against walls on both sides: one of them suffices
        Ca = C[active]
        saddle = np.block([[K, Ca.T], [Ca, np.zeros((len(active), len(active)))]])
        x = np.linalg.solve(saddle, np.concatenate((P, g[active])))
        lam = np.zeros(m)
        lam[active] = x[len(free):]
        f_scale, u_scale = scales(scene, x[:len(free)], lam)
        # KKT within round-off of these small dense solves (κ ≲ 1e5, so ~1e-11)
        feasible = np.all(C @ x[:len(free)] - g <= 1e-9 * u_scale)
        pushing = np.all(lam >= -1e-9 * f_scale)
        if contact == "equality" or (feasible and pushing):
            u = np.zeros(scene.n_nodes)
            u[free] = x[:len(free)]
            return u, lam, active
    raise AssertionError("no set of walls in contact satisfies the KKT conditions")


def assert_kkt(scene: Scene, result, rel: float) -> None:
    """The KKT conditions of the inequality problem, checked on a Result from scratch."""
    K_full, P_full, *_ = dense_algebra(scene)
    u, lam, reactions = result.u, result.contact_force, result.reactions
    supports = [s.node for s in scene.supports]
    assert np.all(u[supports] == 0.0)
    wall_force = np.zeros(scene.n_nodes)
    for wall, force in zip(scene.walls, lam):
        wall_force[wall.node] -= (1.0 if wall.side == "+" else -1.0) * force
    support_force = np.zeros(scene.n_nodes)
    support_force[supports] = reactions
    k_max = float(np.max(np.asarray(scene.bar.youngs_modulus) * scene.bar.areas / scene.bar.lengths))
    force_scale, u_scale = scales(scene, u, lam)
    force_scale = max(force_scale, k_max * np.abs(u).max())  # the size of each term of K u
    assert np.abs(K_full @ u - P_full - wall_force - support_force).max() <= rel * force_scale
    penetration = np.array([(1.0 if w.side == "+" else -1.0) * u[w.node] - w.gap
                            for w in scene.walls])
    assert np.all(penetration <= rel * u_scale)
    assert np.all(lam >= -rel * force_scale)
    assert np.all(np.abs(lam * penetration) <= rel * force_scale * u_scale)


# --------------------------------------------------------------------------------------------
# The seed scene


@pytest.mark.parametrize("area_rule", ["midpoint", "exact"])
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_seed_scene_lagrange_matches_closed_form(area_rule, contact):
    result = contactqp.solve(seed_scene_with(area_rule), "lagrange", contact)
    u, lam = seed_closed_form(area_rule, contact=contact)
    assert lam > 0.0  # the load drives the tip through the gap: contact closes either way
    # κ(K) ~ 10 on four elements: a direct solve agrees with the closed form to ~1e-15
    assert_normwise(result.u, u, rel=1e-12)
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-12)  # as above
    # the only support takes what the load and the wall leave: R = −(F − λ)
    assert result.reactions[0] == pytest.approx(-(SEED_F - lam), rel=1e-12)  # as above
    # the tip sits on the wall: zero up to round-off of u (eps · max |u| ~ 1e-19 m)
    assert abs(result.penetration[0]) <= 1e-12 * max(abs(x) for x in u)
    assert result.verified and result.physical
    assert result.method == "lagrange" and result.contact == contact


def test_solve_without_a_scene_solves_the_seed_scene():
    result = contactqp.solve()
    u, lam = seed_closed_form()
    # κ(K) ~ 10: a direct solve is exact to ~1e-15
    assert_normwise(result.u, u, rel=1e-12)
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-12)  # as above


@pytest.mark.parametrize("method, rel", [
    ("lagrange", 1e-12),  # solve round-off ~ eps · k · |u| ≈ 1e-10 N against 5.7e5 N of load
    ("penalty", 1e-9),  # solve round-off ~ eps · ε · |u| ≈ 1e-6 N with ε = 1e14 N/m
])
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_seed_scene_equilibrium(method, rel, contact):
    scene = contactqp.seed_scene()
    result = contactqp.solve(scene, method, contact)
    wall_forces = [-(1.0 if w.side == "+" else -1.0) * lam
                   for w, lam in zip(scene.walls, result.contact_force)]
    total = sum(result.reactions) + sum(wall_forces) + sum(load.force for load in scene.loads)
    assert abs(total) <= rel * SEED_F


# --------------------------------------------------------------------------------------------
# Exact arithmetic


EXACT_CASES = {
    # lengths (m), areas (m²) and gaps are dyadic, E and loads integers: floats hold them exactly
    "load before a + wall": ([(2, Fraction(300000))], (3, Fraction(1, 8192), "+")),
    "load before a - wall": ([(2, Fraction(-300000))], (3, Fraction(1, 8192), "-")),
    "load beyond the wall": ([(3, Fraction(250000))], (1, Fraction(1, 16384), "+")),
    "two loads, open wall": ([(1, Fraction(1000)), (3, Fraction(-500))], (3, Fraction(1, 64), "+")),
}
EXACT_LENGTHS = [Fraction(1, 2), Fraction(1, 4), Fraction(1, 4)]
EXACT_AREAS = [Fraction(1, 1024), Fraction(3, 4096), Fraction(1, 2048)]
EXACT_E = Fraction(200_000_000_000)


@pytest.mark.parametrize("case", EXACT_CASES, ids=list(EXACT_CASES))
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_lagrange_matches_exact_rational_solution(case, contact):
    loads, wall = EXACT_CASES[case]
    u, lam = cantilever(EXACT_LENGTHS, EXACT_AREAS, EXACT_E, loads, wall, contact=contact)
    assert all(isinstance(x, Fraction) for x in [*u, lam])  # the reference is exact
    node, gap, side = wall
    s = 1 if side == "+" else -1
    reaction = -sum(force for _, force in loads) + s * lam
    element_force = [EXACT_E * a / length * (u[e + 1] - u[e])
                     for e, (length, a) in enumerate(zip(EXACT_LENGTHS, EXACT_AREAS))]

    bar = Bar.from_areas([float(a) for a in EXACT_AREAS], float(EXACT_E),
                         lengths=[float(x) for x in EXACT_LENGTHS])
    scene = Scene(bar, (Support(0),), tuple(Load(a, float(f)) for a, f in loads),
                  (Wall(node, float(gap), side),))
    result = contactqp.solve(scene, "lagrange", contact)
    # the inputs are exact in binary and κ(K) ~ 10: only a few roundings separate the two
    assert_normwise(result.u, [float(x) for x in u], rel=1e-12)
    assert_normwise(result.contact_force, [float(lam)], rel=1e-12)  # as above
    assert_normwise(result.reactions, [float(reaction)], rel=1e-12)  # as above
    assert_normwise(result.element_force, [float(x) for x in element_force], rel=1e-12)  # same
    assert_normwise(result.stress, [float(n / a) for n, a in zip(element_force, EXACT_AREAS)],
                    rel=1e-12)  # as above
    penetration = s * u[node] - gap
    # an exact zero when in contact: measure against the displacement scale instead
    assert abs(result.penetration[0] - float(penetration)) <= 1e-12 * float(max(map(abs, u)))


# --------------------------------------------------------------------------------------------
# Open contact: the load does not reach the wall


def small_force() -> float:
    """A load that moves the wall node only half way to the wall: F f_2 = g / 2."""
    return 0.5 * SEED_GAP / seed_flexibility(SEED_LOAD_NODE)


@pytest.mark.parametrize("method", ["lagrange", "penalty"])
def test_open_contact_inequality_leaves_the_gap_open(method):
    force = small_force()
    result = contactqp.solve(seed_scene_with(force=force), method, "inequality")
    u, lam = seed_closed_form(force=force)
    assert lam == 0.0
    assert result.contact_force[0] == 0.0  # no wall in contact: no force, not even round-off
    assert_normwise(result.u, u, rel=1e-12)  # κ(K) ~ 10: a direct solve is exact to ~1e-15
    # the gap stays open by half of itself; u_4 carries round-off of ~1e-16 relative
    assert result.penetration[0] == pytest.approx(-SEED_GAP / 2, rel=1e-12)
    assert result.reactions[0] == pytest.approx(-force, rel=1e-12)  # as above
    assert result.verified and result.physical
    assert result.warnings == ()  # far below yield, nothing to warn about


@pytest.mark.parametrize("method, penalty, rel", [
    ("lagrange", None, 1e-12),  # κ(K) ~ 10: a direct solve is exact to ~1e-15
    ("penalty", 1e14, 1e-9),  # κ(K + ε CᵀC) ~ ε f ~ 1e6: round-off ~1e-10
])
def test_open_contact_equality_pulls(method, penalty, rel):
    force = small_force()
    options = {} if penalty is None else {"penalty": penalty}
    result = contactqp.solve(seed_scene_with(force=force), method, "equality", **options)
    _, lam = seed_closed_form(force=force, contact="equality", penalty=penalty)
    assert lam < 0.0  # an equality holds the node at the wall by pulling it there
    assert result.contact_force[0] == pytest.approx(lam, rel=rel)
    assert result.physical is False
    assert "pull" in result.message
    assert "wall[0]" in result.message


# --------------------------------------------------------------------------------------------
# Several walls, both sides


def fixed_fixed_scene() -> Scene:
    """Fixed at both ends; pushed +x at node 2 and -x at node 4 into a "+" and a "-" wall;
    two more walls that stay open."""
    bar = Bar.from_areas([1e-3, 8e-4, 6e-4, 6e-4, 8e-4, 1e-3], 2e11, length=3.0)
    return Scene(
        bar, (Support(0), Support(6)), (Load(2, 2e5), Load(4, -2e5)),
        (Wall(2, 1e-4, "+"), Wall(4, 5e-5, "-"), Wall(5, 0.0, "+"), Wall(1, 2e-3, "-")),
    )


def cantilever_interior_walls_scene() -> Scene:
    """Fixed at node 0, uneven elements; a "+" wall at node 2 and a "-" wall at the tip are
    touched; a "+" wall at node 3 and a "-" wall at node 1 are not."""
    bar = Bar.from_areas([2e-3, 1.5e-3, 1e-3, 1e-3, 5e-4], 2e11,
                         lengths=[0.5, 0.5, 0.25, 0.25, 0.5])
    return Scene(
        bar, (Support(0),), (Load(2, 3e5), Load(5, -1e5)),
        (Wall(2, 1e-4, "+"), Wall(5, 2e-4, "-"), Wall(3, 1e-3, "+"), Wall(1, 0.0, "-")),
    )


SEVERAL_WALLS = [fixed_fixed_scene, cantilever_interior_walls_scene]


@pytest.mark.parametrize("make_scene", SEVERAL_WALLS)
def test_several_walls_lagrange_matches_brute_force(make_scene):
    scene = make_scene()
    u, lam, active = brute_force(scene)
    assert active == [0, 1]  # the scene is built so that one wall on each side is touched
    assert lam[0] > 0.0 and lam[1] > 0.0
    result = contactqp.solve(scene, "lagrange", "inequality")
    # two backward-stable solves of systems with κ ≲ 1e3: agreement to ~1e-13
    assert_normwise(result.u, u, rel=1e-10)
    assert_normwise(result.contact_force, lam, rel=1e-10)  # as above
    assert result.contact_force[2] == 0.0 and result.contact_force[3] == 0.0  # open: exactly 0
    assert_kkt(scene, result, rel=1e-10)  # residuals of a backward-stable solve: ~1e-15
    assert result.verified and result.physical


@pytest.mark.parametrize("make_scene", SEVERAL_WALLS)
def test_several_walls_equality_matches_brute_force(make_scene):
    scene = make_scene()
    u, lam, _ = brute_force(scene, "equality")
    result = contactqp.solve(scene, "lagrange", "equality")
    # two backward-stable solves of systems with κ ≲ 1e3: agreement to ~1e-13
    assert_normwise(result.u, u, rel=1e-10)
    assert_normwise(result.contact_force, lam, rel=1e-10)  # as above
    assert np.any(lam < 0.0)  # holding the open walls shut takes a pull
    assert result.physical is False


@pytest.mark.parametrize("make_scene", SEVERAL_WALLS)
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_several_walls_penalty_is_within_its_bound(make_scene, contact):
    """With walls A in contact, (F_AA + I/ε) λ_ε = F_AA λ for F_AA = C_A K⁻¹ C_Aᵀ, so
    ‖λ − λ_ε‖₂ <= ‖λ‖₂ / (ε · smallest eigenvalue of F_AA)."""
    scene = make_scene()
    eps = 1e14
    u, lam, active = brute_force(scene, contact)
    _, _, _, K, _, C, _ = dense_algebra(scene)
    Ca = C[active]
    smallest = np.linalg.eigvalsh(Ca @ np.linalg.solve(K, Ca.T)).min()
    bound = np.linalg.norm(lam) / (eps * smallest)
    result = contactqp.solve(scene, "penalty", contact, penalty=eps)
    # 1 % above the bound for the solve's own round-off (~1e-10 relative against ~1e-6 here)
    assert np.abs(result.contact_force - lam).max() <= 1.01 * bound
    # u_ε − u = K⁻¹ C_Aᵀ (λ − λ_ε): the same bound carried through K⁻¹ C_Aᵀ (1 % as above)
    u_bound = np.linalg.norm(np.linalg.solve(K, Ca.T), 2) * bound
    assert np.abs(result.u - u).max() <= 1.01 * u_bound


def test_equality_with_walls_on_both_sides_of_one_node_is_refused():
    scene = seed_scene_with(walls=(Wall(3, 1e-4, "+"), Wall(3, 1e-4, "-")))
    with pytest.raises(OptionError, match=r"node 3"):
        contactqp.solve(scene, "lagrange", "equality")


def test_walls_on_both_sides_of_one_node_with_inequality():
    # the "+" wall stops node 3; the "-" wall behind it stays open
    scene = seed_scene_with(walls=(Wall(3, 1e-4, "+"), Wall(3, 2e-4, "-")))
    u, _, active = brute_force(scene)
    assert active == [0]
    result = contactqp.solve(scene, "lagrange", "inequality")
    closed_u, closed_lam = cantilever(SEED_LENGTHS, seed_areas("midpoint"), SEED_E,
                                      [(SEED_LOAD_NODE, SEED_F)], (3, 1e-4, "+"))
    # κ(K) ~ 10: a direct solve is exact to ~1e-15
    assert_normwise(result.u, closed_u, rel=1e-12)
    assert_normwise(result.contact_force, [closed_lam, 0.0], rel=1e-12)  # as above
    assert_normwise(u, closed_u, rel=1e-12)  # the brute force agrees with the closed form too


# --------------------------------------------------------------------------------------------
# Penalty


PENALTIES = [1e8, 1e10, 1e12, 1e14]  # N/m; ε f_4 runs from ~1 to ~1e6 on the seed scene


@pytest.mark.parametrize("eps", PENALTIES)
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_penalty_force_matches_its_closed_form(eps, contact):
    result = contactqp.solve(None, "penalty", contact, penalty=eps)
    u, lam = seed_closed_form(contact=contact, penalty=eps)
    # κ(K + ε CᵀC) ~ 1 + ε f ≲ 1e6: round-off ≲ 1e-10 relative
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-9)
    assert_normwise(result.u, u, rel=1e-9)  # as above
    # the penalty leaves the node past the wall by λ / ε = (u_free − g) / (1 + ε f)
    assert result.penetration[0] == pytest.approx(lam / eps, rel=1e-9)  # as above


def test_penalty_converges_to_lagrange_as_one_over_eps_f():
    lagrange = contactqp.solve(None, "lagrange").contact_force[0]
    f = seed_flexibility(SEED_WALL_NODE)
    errors = []
    for eps in PENALTIES:
        penalty = contactqp.solve(None, "penalty", penalty=eps).contact_force[0]
        errors.append((lagrange - penalty) / lagrange)
        # λ_ε carries ~1e-11 relative round-off and the difference cancels it up by
        # 1 + ε f ≲ 1e6: ~1e-5 relative at ε = 1e14
        assert errors[-1] == pytest.approx(1.0 / (1.0 + eps * f), rel=1e-4)
    assert all(e > 0.0 for e in errors)  # the spring always gives a little
    assert errors == sorted(errors, reverse=True)


def test_penalty_inequality_acts_only_on_penetrated_walls():
    # the tip wall is passed; a far "+" wall at node 3 and a "-" wall at node 1 are not
    walls = (Wall(4, SEED_GAP, "+"), Wall(3, 5e-3, "+"), Wall(1, 0.0, "-"))
    scene = seed_scene_with(walls=walls)
    eps = 1e14
    u, lam = seed_closed_form(penalty=eps)
    result = contactqp.solve(scene, "penalty", "inequality", penalty=eps)
    assert result.contact_force[1] == 0.0 and result.contact_force[2] == 0.0  # open: no spring
    # κ(K + ε CᵀC) ~ 1 + ε f ≲ 1e6: round-off ≲ 1e-10 relative
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-9)
    assert_normwise(result.u, u, rel=1e-9)  # as above: as if the open walls were not there
    assert result.penetration[1] < 0.0 and result.penetration[2] < 0.0
    # the equality path springs every wall: node 1 is pulled back onto its wall
    bilateral = contactqp.solve(scene, "penalty", "equality", penalty=eps)
    assert bilateral.contact_force[2] < 0.0


def test_penalty_with_no_penetration_is_the_free_solution():
    force = small_force()
    u, _ = seed_closed_form(force=force)
    result = contactqp.solve(seed_scene_with(force=force), "penalty", "inequality")
    assert result.contact_force.tolist() == [0.0]
    assert_normwise(result.u, u, rel=1e-12)  # no spring: κ(K) ~ 10, exact to ~1e-15


@pytest.mark.parametrize("bad", [0.0, -1e14, math.nan, math.inf, "stiff"])
def test_penalty_must_be_a_positive_finite_number(bad):
    with pytest.raises(OptionError, match="penalty"):
        contactqp.solve(None, "penalty", penalty=bad)


@pytest.mark.parametrize("kwargs, names", [
    ({"method": "newton"}, "method"),
    ({"contact": "bilateral"}, "contact"),
    ({"method": "lagrange", "penalty": 1e14}, "penalty"),
])
def test_unknown_method_contact_or_option(kwargs, names):
    with pytest.raises(OptionError, match=names):
        contactqp.solve(None, **kwargs)


# --------------------------------------------------------------------------------------------
# Random small scenes


@st.composite
def small_scenes(draw) -> Scene:
    """1 to 5 elements, random supports, loads of 1 N to 1 MN both ways, walls on free nodes."""
    n_elements = draw(st.integers(1, 5))
    n_nodes = n_elements + 1
    lengths = draw(st.lists(st.floats(0.1, 2.0), min_size=n_elements, max_size=n_elements))
    areas = draw(st.lists(st.floats(1e-4, 1e-2), min_size=n_elements, max_size=n_elements))
    modulus = draw(st.sampled_from([7e10, 2.1e11]))
    held = draw(st.sets(st.integers(0, n_nodes - 1), min_size=1, max_size=n_nodes - 1))
    free = [j for j in range(n_nodes) if j not in held]
    loads = draw(st.lists(
        st.builds(Load, st.integers(0, n_nodes - 1),
                  st.one_of(st.floats(1.0, 1e6), st.floats(-1e6, -1.0))),
        min_size=1, max_size=3))
    walls = draw(st.lists(
        st.builds(Wall, st.sampled_from(free), st.floats(0.0, 1e-3), st.sampled_from("+-")),
        max_size=4, unique_by=lambda w: (w.node, w.side)))
    # a node clamped between two zero gaps is a known failure: see test_clamped_node
    clamped = {w.node for w in walls if w.side == "+" and any(
        v.node == w.node and v.side == "-" and v.gap + w.gap < 1e-12 for v in walls)}
    walls = [w for w in walls if w.node not in clamped]
    bar = Bar.from_areas(areas, modulus, lengths=lengths)
    return Scene(bar, tuple(Support(j) for j in sorted(held)), tuple(loads), tuple(walls))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=small_scenes())
def test_random_scenes_lagrange_satisfies_kkt_and_matches_brute_force(scene):
    result = contactqp.solve(scene, "lagrange", "inequality")
    # residuals of a backward-stable solve, κ(K) ≲ 1e5 here: ~1e-15 of the force scale
    assert_kkt(scene, result, rel=1e-10)
    u, lam, _ = brute_force(scene)
    # two backward-stable solves, κ ≲ 1e5: agreement to ~1e-11 of the largest value
    force_scale, u_scale = scales(scene, u, lam)
    assert np.abs(result.u - u).max() <= 1e-8 * u_scale
    assert np.abs(result.contact_force - lam).max(initial=0.0) <= 1e-8 * force_scale  # as above
    assert result.verified and result.physical


@pytest.mark.parametrize("method", ["lagrange", "penalty"])
@pytest.mark.parametrize("walls", [(), (Wall(1, 0.0, "+"), Wall(2, 0.0, "-"))])
def test_unloaded_bar_stays_put(method, walls):
    scene = Scene(Bar.from_areas([1e-4, 2e-4], 2e11, length=1.0), (Support(0),), (), walls)
    result = contactqp.solve(scene, method)
    assert result.u.tolist() == [0.0, 0.0, 0.0]  # zero right-hand side: exactly zero
    assert result.contact_force.tolist() == [0.0] * len(walls)
    assert result.verified and result.physical


def test_clamped_node():
    """Node 1 between two zero-gap walls, node 2 pushed into a zero-gap wall: u = 0 everywhere
    and the wall at node 2 carries the whole load."""
    for force in (1e5, 2e5, 3e5):
        for areas in ([1e-3, 1e-3], [1e-4, 1e-3]):
            scene = Scene(Bar.from_areas(areas, 2e11, length=2.0), (Support(0),),
                          (Load(2, force),),
                          (Wall(1, 0.0, "+"), Wall(1, 0.0, "-"), Wall(2, 0.0, "+")))
            u, lam, _ = brute_force(scene)
            assert lam.tolist() == [0.0, 0.0, force] and not np.any(u)  # the design
            result = contactqp.solve(scene, "lagrange", "inequality")
            # u = 0 exactly in the answer: round-off against what F does to the softest
            # element (L = 1 m), F L / (E A)
            assert np.abs(result.u).max() <= 1e-12 * force * 1.0 / (2e11 * min(areas))
            # the load itself reaches the wall: round-off of a solve with κ ~ 10
            assert_normwise(result.contact_force, lam, rel=1e-12)


# --------------------------------------------------------------------------------------------
# A long bar and a warning


def test_hundred_thousand_elements_match_the_cone():
    """Exact-rule elements have the cone's flexibility f(x) = 4x / (E π d_0 d(x)) at every
    node, so the closed form needs no sum at all."""
    n = 10**5
    d0, d1 = 0.040, 0.020
    bar = Bar.tapered_circle(1.0, n, d0, d1, SEED_E, area_rule="exact")
    scene = Scene(bar, (Support(0),), (Load(n // 2, SEED_F),), (Wall(n, SEED_GAP, "+"),))
    result = contactqp.solve(scene, "lagrange", "inequality")

    def flexibility(x):
        return 4.0 * x / (SEED_E * np.pi * d0 * (d0 + (d1 - d0) * x))

    x = np.arange(n + 1) / n
    lam = (SEED_F * flexibility(0.5) - SEED_GAP) / flexibility(1.0)
    u = SEED_F * flexibility(np.minimum(x, 0.5)) - lam * flexibility(x)
    # κ(K) grows as n² (~1e10 here): worst-case round-off of a backward-stable solve is
    # κ · eps ≈ 1e-6
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-6)
    assert_normwise(result.u, u, rel=1e-6)  # as above
    assert result.u.size == n + 1


def test_seed_scene_warns_of_stress_beyond_yield():
    result = contactqp.solve()
    _, lam = seed_closed_form()
    areas = seed_areas("midpoint")
    # elements 0 and 1 carry F − λ in tension, 2 and 3 carry λ in compression
    forces = [SEED_F - lam, SEED_F - lam, -lam, -lam]
    stress = [force / area for force, area in zip(forces, areas)]
    worst = max(range(4), key=lambda e: abs(stress[e]))
    ratio = abs(stress[worst]) / SEED_YIELD
    assert ratio > 1.0
    # κ(K) ~ 10 on four elements: a direct solve is exact to ~1e-15
    assert_normwise(result.stress, stress, rel=1e-12)
    assert result.stress_ratio == pytest.approx(ratio, rel=1e-12)  # as above
    assert len(result.warnings) == 1
    warning = result.warnings[0]
    assert "yield" in warning
    assert f"element {worst}" in warning
    assert f"{stress[worst] / 1e6:.1f} MPa" in warning
    assert result.verified  # a warning is not a failed check
