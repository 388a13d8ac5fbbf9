"""The explicit Lagrange method (contactqp.methods.lagrange) against closed forms, exact rational
solutions and a brute force over active sets.

Symbols (SI units)
------------------
E         Young's modulus (Pa)
A_e, L_e  area (m²) and length (m) of element e, which joins nodes e and e + 1
k_e       E A_e / L_e, element stiffness of element e (N/m)
f_j       Σ_{e<j} L_e / (E A_e): compliance of a cantilever fixed at node 0, seen at node j
          (m/N)
F, a      a point load (N, +x) and its node
w, g, s   a wall's node, gap (m) and side sign (+1 for "+", -1 for "-"): s u_w <= g
λ         contact force, how hard the wall pushes the bar (N, >= 0 when physical)
R         reaction of a support: the force it applies to the bar in +x (N)
ε         penalty (N/m): λ_ε = (s u_free,w − g) / (f_w + 1/ε)
K, P      dense stiffness (N/m) and loads (N) of the free nodes, assembled here
C, g      one row per wall, s at the wall's node: the walls hold where C u <= g

Several walls are checked by brute force: every set of walls in contact is tried with a dense
numpy solve of [[K, Cᵀ], [C, 0]] [u; λ] = [P; g], and the one that satisfies the KKT conditions
is the answer.
"""

from __future__ import annotations

import tomllib
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import (
    DEFAULT_E,
    DEFAULT_F,
    DEFAULT_GAP,
    DEFAULT_LENGTHS,
    DEFAULT_LOAD_NODE,
    SEVERAL_WALLS,
    answer_scales,
    assert_normwise,
    brute_force,
    cantilever,
    default_areas,
    default_closed_form,
    default_scene_with,
    dense_algebra,
)
from contactqp import (
    Bar,
    Load,
    Scene,
    Support,
    Wall,
)
from contactqp.model import (
    Layout,
)
from contactqp.reference import reference


def assert_kkt(scene: Scene, result, rel: float) -> None:
    """The KKT conditions of the inequality problem, checked on a Result from scratch."""
    K_full, P_full, *_ = dense_algebra(scene)
    u, lam, reactions = result.u, result.contact_force, result.reactions
    supports = [s.node for s in scene.supports]
    assert np.all(u[supports] == 0.0)
    wall_force = np.zeros(Layout(scene).n_nodes)
    for wall, force in zip(scene.walls, lam):
        wall_force[wall.node] -= (1.0 if wall.side == "+" else -1.0) * force
    support_force = np.zeros(Layout(scene).n_nodes)
    support_force[supports] = reactions
    k_max = float(np.max(np.asarray(scene.bars[0].youngs_modulus) * scene.bars[0].areas / scene.bars[0].lengths))
    force_scale, u_scale = answer_scales(scene, u, lam)
    force_scale = max(force_scale, k_max * np.abs(u).max())  # the size of each term of K u
    assert np.abs(K_full @ u - P_full - wall_force - support_force).max() <= rel * force_scale
    penetration = np.array([(1.0 if w.side == "+" else -1.0) * u[w.node] - w.gap
                            for w in scene.walls])
    assert np.all(penetration <= rel * u_scale)
    assert np.all(lam >= -rel * force_scale)
    assert np.all(np.abs(lam * penetration) <= rel * force_scale * u_scale)


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


@pytest.mark.parametrize("area_rule", ["midpoint", "exact"])
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_seed_scene_lagrange_matches_closed_form(area_rule, contact):
    result = contactqp.solve(default_scene_with(area_rule), "lagrange", contact)
    u, lam = default_closed_form(area_rule, contact=contact)
    assert lam > 0.0  # the load drives the tip through the gap: contact closes either way
    # κ(K) ~ 10 on four elements: a direct solve agrees with the closed form to ~1e-15
    assert_normwise(result.u, u, rel=1e-12)
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-12)  # as above
    # the only support takes what the load and the wall leave: R = −(F − λ)
    assert result.reactions[0] == pytest.approx(-(DEFAULT_F - lam), rel=1e-12)  # as above
    # the tip sits on the wall: zero up to round-off of u (eps · max |u| ~ 1e-19 m)
    assert abs(result.penetration[0]) <= 1e-12 * max(abs(x) for x in u)
    assert result.verified and result.physical
    assert result.method == "lagrange" and result.contact == contact


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


def test_walls_on_both_sides_of_one_node_with_inequality():
    # the "+" wall stops node 3; the "-" wall behind it stays open
    scene = default_scene_with(walls=(Wall(3, 1e-4, "+"), Wall(3, 2e-4, "-")))
    u, _, active = brute_force(scene)
    assert active == [0]
    result = contactqp.solve(scene, "lagrange", "inequality")
    closed_u, closed_lam = cantilever(DEFAULT_LENGTHS, default_areas("midpoint"), DEFAULT_E,
                                      [(DEFAULT_LOAD_NODE, DEFAULT_F)], (3, 1e-4, "+"))
    # κ(K) ~ 10: a direct solve is exact to ~1e-15
    assert_normwise(result.u, closed_u, rel=1e-12)
    assert_normwise(result.contact_force, [closed_lam, 0.0], rel=1e-12)  # as above
    assert_normwise(u, closed_u, rel=1e-12)  # the brute force agrees with the closed form too


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=small_scenes())
def test_random_scenes_lagrange_satisfies_kkt_and_matches_brute_force(scene):
    result = contactqp.solve(scene, "lagrange", "inequality")
    # residuals of a backward-stable solve, κ(K) ≲ 1e5 here: ~1e-15 of the force scale
    assert_kkt(scene, result, rel=1e-10)
    u, lam, _ = brute_force(scene)
    # two backward-stable solves, κ ≲ 1e5: agreement to ~1e-11 of the largest value
    force_scale, u_scale = answer_scales(scene, u, lam)
    assert np.abs(result.u - u).max() <= 1e-8 * u_scale
    assert np.abs(result.contact_force - lam).max(initial=0.0) <= 1e-8 * force_scale  # as above
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


def test_hundred_thousand_elements_match_the_cone():
    """Exact-rule elements have the cone's flexibility f(x) = 4x / (E π d_0 d(x)) at every
    node, so the closed form needs no sum at all."""
    n = 10**5
    d0, d1 = 0.040, 0.020
    bar = Bar.tapered_circle(1.0, n, d0, d1, DEFAULT_E, area_rule="exact")
    scene = Scene(bar, (Support(0),), (Load(n // 2, DEFAULT_F),), (Wall(n, DEFAULT_GAP, "+"),))
    result = contactqp.solve(scene, "lagrange", "inequality")

    def flexibility(x):
        return 4.0 * x / (DEFAULT_E * np.pi * d0 * (d0 + (d1 - d0) * x))

    x = np.arange(n + 1) / n
    lam = (DEFAULT_F * flexibility(0.5) - DEFAULT_GAP) / flexibility(1.0)
    u = DEFAULT_F * flexibility(np.minimum(x, 0.5)) - lam * flexibility(x)
    # κ(K) grows as n² (~1e10 here): worst-case round-off of a backward-stable solve is
    # κ · eps ≈ 1e-6
    assert result.contact_force[0] == pytest.approx(lam, rel=1e-6)
    assert_normwise(result.u, u, rel=1e-6)  # as above
    assert result.u.size == n + 1


# Two scenes of the random family (benchmarks/guarantee.py, seed 31337, scenes 19 and 59) on
# which the passed-walls loop comes back to a set it left: zero gaps close a loop of walls and
# a bar contact, so the rows that hold a node are dependent
CYCLING = {
    "zero_gap_loop": """
name = "scene"
units = "SI"

[[bar]]
areas = [0.00013389772541784665, 0.007312543603997317]
lengths = [0.9313730756403275, 0.44993454541551814]

[bar.material]
youngs_modulus = 88677844009.55197

[[bar]]
areas = [0.00015269552332161114, 0.002073493284888239, 0.1549599175198053, 0.0007855747887408018, 0.5288993073601695]
lengths = [0.5615457729251414, 0.9213738830385658, 0.03546036545150994, 0.3789506447557248, 0.20019982009154103]

[bar.material]
youngs_modulus = 4513340291.806324

[[support]]
bar = 0
node = 0

[[support]]
bar = 1
node = 0

[[load]]
bar = 0
node = 2
force = 10000.0

[[wall]]
bar = 0
node = 1
gap = 5.579668652272821e-06
side = "+"

[[wall]]
bar = 0
node = 1
gap = 0.0
side = "-"

[[wall]]
bar = 1
node = 2
gap = 1.4340351653308452e-07
side = "+"

[[wall]]
bar = 1
node = 2
gap = 1.3695031125782963e-06
side = "-"

[[wall]]
bar = 1
node = 3
gap = 0.0007142954417839772
side = "+"

[[wall]]
bar = 1
node = 4
gap = 0.0
side = "+"

[[wall]]
bar = 1
node = 4
gap = 0.00027769123001497765
side = "-"

[[wall]]
bar = 1
node = 5
gap = 7.626025011765716e-07
side = "-"

[[contact]]
bar_a = 0
node_a = 1
bar_b = 1
node_b = 4
gap = 0.0

[[contact]]
bar_a = 0
node_a = 0
bar_b = 1
node_b = 1
gap = 1.101794938565112e-06
""",
    "two_bar_contacts": """
name = "scene"
units = "SI"

[[bar]]
areas = [0.003350749021219802, 0.12706452928822093, 7.977180213672064e-05, 0.4405743517104145, 1.0, 0.6885966146770691, 1.5589894773830672e-07]
lengths = [0.16508691013761986, 0.03230538659143007, 0.037600807620538454, 0.17972300995771057, 0.6733136644972876, 0.4111713880373968, 0.43554321479070235]

[bar.material]
youngs_modulus = 1560072223.5504606

[[bar]]
areas = [6.201702948298693e-05]
lengths = [0.0293040933735256]

[bar.material]
youngs_modulus = 22758887280.95651

[[support]]
bar = 0
node = 0

[[support]]
bar = 1
node = 0

[[load]]
bar = 1
node = 1
force = -117.15363696072582

[[wall]]
bar = 0
node = 2
gap = 2.433624675918706e-08
side = "-"

[[wall]]
bar = 0
node = 4
gap = 1.002392848601085e-09
side = "-"

[[wall]]
bar = 1
node = 1
gap = 0.0
side = "+"

[[wall]]
bar = 1
node = 1
gap = 1.5596344361381534e-07
side = "-"

[[contact]]
bar_a = 0
node_a = 4
bar_b = 1
node_b = 1
gap = 7.2953151008680835e-09

[[contact]]
bar_a = 0
node_a = 1
bar_b = 1
node_b = 0
gap = 5.017364663542049e-09
""",
}


@pytest.mark.parametrize("formulation", ["full", "condensed", "strain"])
@pytest.mark.parametrize("name", sorted(CYCLING))
def test_a_cycling_active_set_hands_over_to_lemke_and_is_right(name, formulation):
    scene = contactqp.scene_from_dict(tomllib.loads(CYCLING[name]))
    result = contactqp.solve(scene, "lagrange", formulation=formulation)
    assert "Lemke" in result.info["active_set"] and result.verified
    exact = reference(scene)
    assert np.abs(result.contact_force - exact.contact_force).max() <= 1e-12 * result.force_scale
    assert np.abs(result.u - exact.displacement).max() <= 1e-12 * result.displacement_scale


# A scene of the random family (seed 2026, scene 631) on which the loop settles on a set that
# leaves a wall passed: the row that would hold it depends on rows already held
SETTLED_PASSED = """
name = "scene"
units = "SI"

[[bar]]
areas = [0.22887079924674733, 0.056484722824039324, 8.04014345469624e-06, 0.008739082787067082, 0.00017075932630454863, 1.0330775011274484e-05]
lengths = [0.1477755266917365, 0.1558129911450877, 0.06979562923038451, 0.2363284087921522, 0.855073737447604, 0.07117762311242538]

[bar.material]
youngs_modulus = 4497303062.1543665

[[bar]]
areas = [0.00040396894826021074, 0.00041590432730578396, 0.6362673538366711]
lengths = [0.15790532851188965, 0.25314296679693055, 0.13276935937807727]

[bar.material]
youngs_modulus = 662757468243.939

[[bar]]
areas = [0.04404828943857155, 0.007346062502168844, 2.7477740597441995e-06, 0.000295709773006797, 2.8489225480434045e-07, 1.0]
lengths = [0.15014603890371525, 0.013578914320270906, 0.02596446368952993, 0.0972327919218874, 0.777916666739439, 0.0392809877487751]

[bar.material]
youngs_modulus = 443971439689.8842

[[support]]
bar = 0
node = 0

[[support]]
bar = 1
node = 0

[[support]]
bar = 2
node = 0

[[load]]
bar = 1
node = 2
force = 2110.1533912313757

[[distributed_load]]
bar = 2
intensity = -170967.96343180252
start = 0

[[wall]]
bar = 0
node = 3
gap = 0.0
side = "+"

[[wall]]
bar = 0
node = 3
gap = 0.006019709061829061
side = "-"

[[wall]]
bar = 0
node = 4
gap = 0.7984183144991903
side = "-"

[[wall]]
bar = 1
node = 1
gap = 0.0
side = "+"

[[wall]]
bar = 1
node = 1
gap = 0.1802307513764362
side = "-"

[[wall]]
bar = 1
node = 2
gap = 0.0
side = "-"

[[wall]]
bar = 2
node = 1
gap = 0.004593335440989482
side = "-"

[[wall]]
bar = 2
node = 2
gap = 0.0
side = "+"

[[wall]]
bar = 2
node = 2
gap = 0.0
side = "-"

[[wall]]
bar = 2
node = 3
gap = 0.00016424461483302544
side = "+"

[[contact]]
bar_a = 0
node_a = 3
bar_b = 2
node_b = 2
gap = 0.5988276092429249
"""


def test_a_set_that_settles_with_a_wall_passed_hands_over_to_lemke():
    scene = contactqp.scene_from_dict(tomllib.loads(SETTLED_PASSED))
    result = contactqp.solve(scene, "lagrange", formulation="full")
    assert "still passed" in result.info["active_set"] and result.verified
    exact = reference(scene)
    assert np.abs(result.contact_force - exact.contact_force).max() <= 1e-9 * result.force_scale
