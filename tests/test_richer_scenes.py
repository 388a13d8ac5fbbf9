"""Several bars, bar-to-bar contact, distributed loads, a wall at every node, and load paths.

Glossary: k = EA/L of a one-element bar (N/m), g gap (m), P point load (N), q distributed
load (N/m), λ contact force (N), t load factor. Every expected value is a closed form or comes
from an independent method (scipy's bounded least squares for the obstacle problem).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear

import contactqp
from contactqp import Bar, Load, Scene, SceneError, Support, Wall
from contactqp.cli import main
from contactqp.curve import first_contact_factor, load_path
from contactqp.scene import BarContact, DistributedLoad, load_scene, wall_at_every_node

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))
E = 200e9


def spring(k: float, length: float = 1.0) -> Bar:
    """A one-element bar of stiffness k (N/m)."""
    return Bar.from_areas([k * length / E], E, length=length)


def two_bars(k1: float, k2: float, gap: float, load: float) -> Scene:
    """Bar 0 fixed at node 0, load at node 1; bar 1 fixed at node 1; bar 0 node 1 faces bar 1
    node 0 across ``gap``."""
    return Scene((spring(k1), spring(k2)), (Support(0, 0), Support(1, 1)), (Load(1, load, 0),),
                 contacts=(BarContact(0, 1, 1, 0, gap),))


TWO_BAR_RUNS = [("lagrange", "full", {}), ("lagrange", "condensed", {}), ("lagrange", "strain", {}),
                ("augmented", "full", {}), ("augmented", "condensed", {}),
                ("qp", "full", {"accuracy": "high"}), ("qp", "strain", {"accuracy": "high"}),
                ("qp", "full", {"backend": "osqp", "accuracy": "high"}),
                ("qp", "condensed", {"backend": "cvxpy"})]


@pytest.mark.parametrize("method,formulation,options", TWO_BAR_RUNS)
@pytest.mark.parametrize("k1,k2,gap,load", [(2e8, 5e7, 1e-4, 5e4), (1e6, 3e9, 2e-3, 7e3)])
def test_two_bars_closed_form(method, formulation, options, k1, k2, gap, load):
    exact = (load - k1 * gap) * k2 / (k1 + k2)  # bar 0 closes the gap, then both springs share
    assert exact > 0
    result = contactqp.solve(two_bars(k1, k2, gap, load), method, formulation=formulation, **options)
    assert result.verified, result.message
    assert result.contact_force[0] == pytest.approx(exact, rel=1e-7)
    # bar 1's support takes the contact force; bar 0's takes the rest of the load
    assert result.reactions == pytest.approx([-(load - exact), -exact], rel=1e-7)
    assert result.u[1] - result.u[2] == pytest.approx(gap, rel=1e-7)  # the gap is closed


def test_two_bars_open_gap_carries_nothing():
    k1, gap = 2e8, 1e-4
    result = contactqp.solve(two_bars(k1, 5e7, gap, 0.5 * k1 * gap))  # half the closing load
    assert result.verified
    assert result.contact_force[0] == 0.0
    assert result.penetration[0] == pytest.approx(-0.5 * gap)


def test_two_bars_penalty_leaves_its_penetration():
    k1, k2, gap, load, eps = 2e8, 5e7, 1e-4, 5e4, 1e10
    # u_a = (P − λ)/k1, u_b = λ/k2 and λ = ε (u_a − u_b − g) give
    # λ (1/ε + 1/k1 + 1/k2) = P/k1 − g, i.e. λ = (P − k1 g) / (1 + k1/k2 + k1/ε)
    exact = (load - k1 * gap) / (1 + k1 / k2 + k1 / eps)
    result = contactqp.solve(two_bars(k1, k2, gap, load), "penalty", penalty=eps)
    assert result.contact_force[0] == pytest.approx(exact, rel=1e-9)
    assert result.penetration[0] == pytest.approx(exact / eps, rel=1e-9)


@pytest.mark.parametrize("method", ["lagrange", "penalty", "augmented", "qp"])
def test_distributed_load_is_exact_at_the_nodes(method):
    """Uniform bar fixed at 0, q over its length: without the wall u(x) = q (L x − x²/2) / EA,
    exact at the nodes with consistent loads. A tip wall at gap g takes λ = (q L²/(2EA) − g)
    EA/L (the tip's compatibility), and u(x) loses λ x / EA."""
    q, L, area, n, gap = 4e4, 2.0, 1e-4, 10, 1e-4
    bar = Bar.from_areas(np.full(n, area), E, length=L)
    EA = E * area
    free_tip = q * L**2 / (2 * EA)
    scene = Scene(bar, (Support(0),), distributed=(DistributedLoad(q),),
                  walls=(Wall(n, gap),))
    result = contactqp.solve(scene, method)
    assert result.verified, result.message
    lam = (free_tip - gap) * EA / L
    # the penalty is off by its λ/ε, Clarabel at its default tolerances by ~1e-9
    rtol = {"penalty": 1e-6, "qp": 1e-7}.get(method, 1e-9)
    assert result.contact_force[0] == pytest.approx(lam, rel=rtol)
    x = bar.node_x
    exact = q * (L * x - x**2 / 2) / EA - lam * x / EA
    penetration = lam / 1e14 if method == "penalty" else 0.0  # the penalty's λ/ε at its default
    assert result.u == pytest.approx(exact, rel=1e-6, abs=1e-6 * gap + 1.01 * penetration)
    assert result.reactions[0] == pytest.approx(-(q * L - lam), rel=rtol)


def test_distributed_load_on_part_of_a_bar_and_its_nodal_forces():
    bar = Bar.from_areas([1e-4] * 4, E, lengths=[0.1, 0.2, 0.3, 0.4])
    scene = Scene(bar, (Support(0),), distributed=(DistributedLoad(1000.0, start=1, stop=3),))
    # element 1 (0.2 m) and 2 (0.3 m): 200 N and 300 N split half to each end
    assert scene.nodal_loads() == pytest.approx([0.0, 100.0, 250.0, 150.0, 0.0])
    result = contactqp.solve(scene)
    assert result.reactions[0] == pytest.approx(-500.0)
    # N(x) = q (0.6 − x) on the loaded part; an element's k·Δu is its mean over the element
    assert result.element_force == pytest.approx([500.0, 400.0, 150.0, 0.0], abs=1e-9)


def obstacle_reference(scene: Scene) -> np.ndarray:
    """The obstacle problem min ½uᵀKu − Pᵀu, u_i <= g_i (walls on the + side), solved as bounded
    least squares ‖R u − R⁻ᵀ P‖² (K = RᵀR) by scipy's BVLS: independent of contactqp's methods."""
    model = contactqp.build_model(scene)
    K = model.K.toarray()
    R = sla.cholesky(K)
    upper = np.full(model.n_free, np.inf)
    upper[model.C.indices] = model.g
    target = sla.solve_triangular(R, model.P, trans="T")
    return lsq_linear(R, target, bounds=(-np.inf, upper), method="bvls", tol=1e-14).x


def obstacle_scene(n: int) -> Scene:
    gaps = 2e-4 * np.linspace(0.0, 1.0, n + 1) ** 2 + 2e-5 * np.sin(np.arange(n + 1))
    return wall_at_every_node(contactqp.seed_scene(n), np.abs(gaps))


@pytest.mark.parametrize("method,options", [("lagrange", {}), ("augmented", {}), ("penalty", {"penalty": 1e18}),
                                            ("qp", {}), ("qp", {"backend": "osqp", "accuracy": "high"}),
                                            ("qp", {"backend": "cvxpy"})])
def test_wall_at_every_node_matches_bounded_least_squares(method, options):
    scene = obstacle_scene(40)
    assert len(scene.walls) == 40  # every node but the support
    u_ref = obstacle_reference(scene)
    result = contactqp.solve(scene, method, **options)
    assert result.verified or method == "penalty", result.message
    scale = np.abs(u_ref).max()
    assert np.abs(result.u[1:] - u_ref).max() <= 1e-6 * scale
    # λ is the force the wall must supply: K u − P at the walled nodes, from the reference u
    model = contactqp.build_model(scene)
    lam_ref = -(model.K @ u_ref - model.P)[model.C.indices]  # one + wall per row, rows in scene order
    assert np.abs(result.contact_force - lam_ref).max() <= 1e-6 * np.abs(lam_ref).max()


def test_wall_at_every_node_keeps_the_nearer_wall_and_checks_its_input():
    scene = contactqp.seed_scene()  # a wall 1e-4 beyond node 4
    near = wall_at_every_node(scene, 5e-5)
    assert [w.gap for w in near.walls if w.node == 4] == [5e-5]
    far = wall_at_every_node(scene, 1e-3)
    assert [w.gap for w in far.walls if w.node == 4] == [1e-4]
    with pytest.raises(SceneError, match=r"obstacle.gap must be one value or one per node of bar\[0\] \(5\), got 3"):
        wall_at_every_node(scene, [1e-4, 1e-4, 1e-4])
    with pytest.raises(SceneError, match="obstacle.bar = 2: the scene has bars 0 to 0"):
        wall_at_every_node(scene, 1e-4, bar=2)


@st.composite
def multi_bar_scenes(draw):
    """2 or 3 bars, each held by one or two supports, random loads (point and distributed),
    walls on both sides, and contacts between consecutive bars' facing ends."""
    bars, supports, loads, walls, contacts, distributed = [], [], [], [], [], []
    n_bars = draw(st.integers(2, 3))
    for b in range(n_bars):
        n = draw(st.integers(1, 5))
        areas = draw(st.lists(st.floats(1e-4, 1e-2), min_size=n, max_size=n))
        bars.append(Bar.from_areas(areas, 210e9, length=draw(st.floats(0.1, 2.0))))
        held = draw(st.sampled_from([(0,), (n,), (0, n)] if n > 1 else [(0,), (n,)]))
        supports += [Support(s, b) for s in held]
        free = [i for i in range(n + 1) if i not in held]
        # every bar loaded: a zero-gap wall on an unloaded bar is weakly active (gap 0, force
        # 0), where interior-point answers sit at the check's tolerance and are flagged there
        # (the documented degenerate case; see test_qp)
        sign = st.sampled_from([-1, 1])
        for node in draw(st.lists(st.sampled_from(free), min_size=1, max_size=2, unique=True)):
            loads.append(Load(node, draw(st.floats(1e3, 1e6)) * draw(sign), b))
        if draw(st.booleans()):
            distributed.append(DistributedLoad(draw(st.floats(1e3, 1e6)) * draw(sign), b))
        for node in draw(st.lists(st.sampled_from(free), max_size=2, unique=True)):
            walls.append(Wall(node, draw(st.one_of(st.just(0.0), st.floats(1e-6, 1e-3))),
                              draw(st.sampled_from("+-")), b))
        if b > 0:
            # facing ends, both free
            previous = bars[b - 1].n_nodes - 1
            if Support(previous, b - 1) not in supports and 0 not in held:
                contacts.append(BarContact(b - 1, previous, b, 0, draw(st.floats(0.0, 1e-3))))
    return Scene(tuple(bars), tuple(supports), tuple(loads), tuple(walls),
                 distributed=tuple(distributed), contacts=tuple(contacts))


@settings(max_examples=40, deadline=None)
@given(multi_bar_scenes())
def test_every_method_agrees_on_random_multi_bar_scenes(scene):
    reference = contactqp.solve(scene, "lagrange")
    assert reference.verified, reference.message
    force_scale = max(np.abs(reference.contact_force).max(initial=0.0),
                      np.abs(scene.nodal_loads()).max())
    disp_scale = max(np.abs(reference.u).max(), force_scale / scene.stiffness.max())
    for method, formulation, options in [("lagrange", "condensed", {}), ("lagrange", "strain", {}),
                                         ("augmented", "full", {}),
                                         ("qp", "full", {"accuracy": "high"}),
                                         ("qp", "condensed", {"backend": "osqp", "accuracy": "high"})]:
        other = contactqp.solve(scene, method, formulation=formulation, **options)
        if method == "qp" and not other.verified:
            continue  # right or flagged: a QP solver may stop short; the check must say so
        assert other.verified, (method, formulation, other.message)
        # net force per node: two walls on one node with zero gaps share the force arbitrarily.
        # A QP answer is held to 1e-4: with bars loaded 30x apart, Clarabel left 0.54 N on a
        # zero-gap wall of the lightly loaded bar, 1.9e-5 of the largest force (measured)
        rtol = 1e-4 if method == "qp" else 1e-6
        net = contactqp.model.wall_forces(scene, other.contact_force)
        net_ref = contactqp.model.wall_forces(scene, reference.contact_force)
        assert np.abs(net - net_ref).max() <= rtol * force_scale, (method, formulation)
        assert np.abs(other.u - reference.u).max() <= rtol * disp_scale, (method, formulation)


def test_scene_errors_name_the_field():
    one, two = spring(1e8), spring(2e8)
    cases = [
        (lambda: Scene((one, two), (Support(0, 0),)), r"support: bar\[1\] has no support"),
        (lambda: Scene((one, two), (Support(0, 0), Support(0, 2))),
         r"support\[1\].bar = 2: the scene has bars 0 to 1"),
        (lambda: Scene((one, two), (Support(0, 0), Support(5, 1))),
         r"support\[1\].node = 5: bar\[1\] has nodes 0 to 1"),
        (lambda: Scene((one, two), (Support(0, 0), Support(1, 1)),
                       contacts=(BarContact(0, 0, 1, 1, 1e-4),)),
         r"contact\[0\]: both nodes are supports"),
        (lambda: Scene((one, two), (Support(0, 0), Support(1, 1)),
                       contacts=(BarContact(0, 1, 1, 0, -1.0),)), r"contact\[0\].gap must be >= 0"),
        (lambda: Scene(one, (Support(0),), distributed=(DistributedLoad(1.0, start=1),)),
         r"distributed_load\[0\]: elements start = 1 to stop = 1"),
        (lambda: Scene(one, (Support(0),), distributed=(DistributedLoad(math.nan),)),
         r"distributed_load\[0\].intensity must be finite"),
        (lambda: Scene((one, "bar"), (Support(0),)), r"bar\[1\] must be a contactqp.Bar"),
    ]
    for build, message in cases:
        with pytest.raises(SceneError, match=message):
            build()


def test_load_path_kink_at_the_closed_form_load():
    """Default scene: the tip moves as node 2 does (nothing loads the elements past it), so the
    wall is reached at t* = g / (F Σ_{e<2} L_e/(E A_e)), areas at the mid-length diameters."""
    L_e, F, g = 0.25, 565486.67, 1e-4
    diameters = 0.040 - 0.020 * (np.array([0.5, 1.5]) * L_e)  # mid-length of elements 0 and 1
    flexibility = np.sum(L_e / (210e9 * np.pi * diameters**2 / 4))
    t_star = g / (F * flexibility)
    assert first_contact_factor(contactqp.seed_scene()) == pytest.approx(t_star, rel=1e-12)
    path = load_path(steps=41)
    t = path.load_factor
    assert t[0] == 0.0 and t[-1] == 1.0 and t.size == 41
    for name in ("lagrange", "penalty", "augmented", "qp", "soft penalty"):
        curve = path.methods[name]
        before, after = t < t_star - 1e-9, t > t_star + 1e-9
        # before the kink: no contact force, u = t F φ₂; after: the wall pushes
        assert np.all(curve.contact_force[before, 0] == pytest.approx(0.0, abs=1e-6 * F))
        assert curve.load_point_displacement[before] == pytest.approx(t[before] * F * flexibility,
                                                                      rel=1e-7, abs=1e-12)
        assert np.all(curve.contact_force[after, 0] > 0)
        # the two straight branches meet at t*
        slope, intercept = np.polyfit(t[after], curve.load_point_displacement[after], 1)
        kink = intercept / (F * flexibility - slope)
        assert kink == pytest.approx(t_star, rel=1e-6), name
    equality = path.methods["equality"]
    assert np.all(equality.contact_force[t < t_star - 1e-9, 0] < 0)  # the textbook wall pulls
    assert not equality.physical[0] and equality.physical[-1]
    assert path.methods["soft penalty"].penetration[-1, 0] > 1e-5  # it shows: λ/ε is large
    assert [r.info["cache"] for r in path.methods["qp"].results[2:]] == ["hit"] * 39


def test_load_path_steps_match_separate_solves():
    scene = load_scene(next(p for p in EXAMPLES if p.stem == "several_bars"))
    path = load_path(scene, steps=5, methods={"lagrange": ("lagrange", "inequality", {})})
    for t, result in zip(path.load_factor, path.methods["lagrange"].results):
        alone = contactqp.solve(scene.scaled_loads(t))
        assert result.verified
        assert result.contact_force == pytest.approx(alone.contact_force, rel=1e-10, abs=1e-6)
        assert result.u == pytest.approx(alone.u, rel=1e-10, abs=1e-15)


def test_curve_cli_json(capsys):
    assert main(["curve", "--steps", "4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["load_factor"] == pytest.approx([0, 1 / 3, 2 / 3, 1])
    for name in ("lagrange", "equality", "penalty", "qp"):
        entry = data["methods"][name]
        assert len(entry["load_point_displacement"]) == 4
        assert [len(row) for row in entry["contact_force"]] == [1] * 4
        assert [len(row) for row in entry["penetration"]] == [1] * 4
    assert main(["curve", "--steps", "1"]) == 2
    assert "steps must be a whole number >= 2" in capsys.readouterr().err


def test_curve_cli_table_and_chart(tmp_path, capsys):
    assert main(["curve", "--steps", "3", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "first contact closes at t = 0.0703" in out
    assert (tmp_path / "load_path.png").stat().st_size > 0


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_runs_and_round_trips(path, tmp_path):
    scene = load_scene(path)
    result = contactqp.solve(scene)
    assert result.verified, result.message
    copy = tmp_path / "copy.toml"
    copy.write_text(contactqp.scene_to_toml(scene))
    again = contactqp.solve(load_scene(copy))
    assert again.contact_force == pytest.approx(result.contact_force, rel=1e-12, abs=1e-9)
    assert main(["compare", str(path), "--no-charts"]) == 0


def test_examples_cover_every_feature():
    text = " ".join(p.read_text() for p in EXAMPLES)
    for table in ("[[bar]]", "[[contact]]", "[[distributed_load]]", "[[obstacle]]", "[bar.material]"):
        assert table in text
