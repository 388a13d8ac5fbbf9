"""The QP method: every installed backend and solver against the explicit Lagrange method and
against equilibrium computed here from the displacements alone.

Symbols
-------
u      nodal displacements (m); N = (EA/L)·Δu the element forces (N, tension positive)
λ      contact force of each wall (N), > 0 when the wall pushes the bar (L = Π + λᵀ(C D − g))
F_ref  the force scale of a comparison: the largest of |λ_ref| and the loads (N)
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import contactqp
from contactqp import Bar, Load, Scene, Support, Wall
from contactqp.errors import OptionError, SolverNotAvailable
from contactqp.methods import qp as qpmod

SOLVERS = contactqp.available_qp_solvers()
PAIRS = [pytest.param(r, id=f"{r.backend}-{r.solver}") for r in SOLVERS]
CONTACTS = ("inequality", "equality")
# Solvers that see the QP through cvxpy's or qpsolvers' second-order-cone rewrite of the
# objective (t >= ‖Lx‖²): a tolerance ε on that problem leaves an error ~√ε in x and λ.
SOC_REWRITE = {("cvxpy", "ECOS"), ("cvxpy", "CVXOPT"), ("qpsolvers", "ecos")}
TOLERANCE_KEYS = ("eps_abs", "tol_feas", "abstol", "primal_tol", "primal_feasibility_tolerance")


def force_rtol(backend: str, solver: str) -> float:
    """Relative error in λ that accuracy="high" allows (the tests' tolerance for a solver).

    The scaled QP and its multipliers are O(1) (see contactqp.methods.qp), so a solver that
    stops at residual ε leaves λ/F off by about ε times the condition number of the scaled
    KKT system, below 1e2 for the scenes here: rtol = 1e3·ε, and 1e-9 for an exact active-set
    method (ε = round-off). Through a cone rewrite, 10·√ε (SOC_REWRITE).
    """
    settings = qpmod.accuracy_settings(solver, "high", backend=backend)
    eps = min((settings[k] for k in TOLERANCE_KEYS if k in settings), default=1e-12)
    if (backend, solver) in SOC_REWRITE:
        return 10.0 * math.sqrt(eps)
    return max(1e3 * eps, 1e-9)


def require(row: contactqp.methods.qp.QPSolverInfo) -> None:
    if not row.available:
        pytest.skip(f"{row.backend}/{row.solver} is not installed: {row.install}")


def several_walls() -> Scene:
    """Six elements fixed at node 0, pushed and pulled: walls on both sides, one open."""
    bar = Bar.from_areas([4e-4, 4e-4, 3e-4, 3e-4, 2e-4, 2e-4], 200e9, length=1.2)
    loads = (Load(2, 3.0e5), Load(4, -1.0e5), Load(6, 2.0e5))
    walls = (
        Wall(2, 5e-4, "+"),   # closed: node 2 is pushed past 0.5 mm
        Wall(4, 2e-3, "-"),   # open: far behind node 4
        Wall(6, 1.5e-3, "+"),  # closed
        Wall(5, 5e-3, "+"),   # open
    )
    return Scene(bar, (Support(0),), loads, walls, name="several walls")


def both_sides() -> Scene:
    """Walls on both sides of one node (inequality only) and a second support at the end."""
    bar = Bar.from_areas([5e-4] * 5, 200e9, length=1.0)
    loads = (Load(2, -4.0e5), Load(3, 2.0e5))
    walls = (Wall(2, 3e-4, "+"), Wall(2, 2e-4, "-"), Wall(3, 1e-4, "+"))
    return Scene(bar, (Support(0), Support(5)), loads, walls, name="both sides")


def open_gap() -> Scene:
    """The default scene with the wall 5 mm away: the free tip moves 0.98 mm, the gap stays
    open."""
    seed = contactqp.seed_scene()
    return seed.with_walls((Wall(seed.walls[0].node, 5e-3, "+"),))


SCENES = {
    "seed": contactqp.seed_scene,
    "several_walls": several_walls,
    "both_sides": both_sides,
    "open_gap": open_gap,
}


def equilibrium_contact_forces(scene: Scene, u: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
    """The force the walls put on each walled node (N, +x), from u alone: the element forces
    on either side and the load there. Compared with the walls' −sign·λ summed per node."""
    k = scene.bar.youngs_modulus * scene.bar.areas / scene.bar.lengths
    N = np.concatenate(([0.0], k * np.diff(u), [0.0]))  # element forces, 0 past the ends
    loads = scene.nodal_loads()
    from_u, from_lambda = {}, {}
    for wall, lam in zip(scene.walls, contact_force):
        node = wall.node
        # node equilibrium: N_right − N_left + load + wall force = 0
        from_u[node] = -(N[node + 1] - N[node] + loads[node])
        from_lambda[node] = from_lambda.get(node, 0.0) - wall.sign * lam
    nodes = sorted(from_u)
    return np.array([from_u[n] for n in nodes]), np.array([from_lambda[n] for n in nodes])


# ---------------------------------------------------------------------------------------------
# Every backend and solver against Lagrange and equilibrium


# every scene with both kinds of contact, except equality at walls on both sides of one node
# (impossible: test_equality_at_two_walls_of_one_node)
CASES = [(name, contact) for contact in CONTACTS for name in SCENES
         if not (contact == "equality" and name == "both_sides")]


@pytest.mark.parametrize("row", PAIRS)
@pytest.mark.parametrize(("scene_name", "contact"), CASES)
def test_dual_is_the_contact_force(row, scene_name, contact):
    require(row)
    scene = SCENES[scene_name]()
    reference = contactqp.solve(scene, method="lagrange", contact=contact)
    result = contactqp.solve(scene, method="qp", contact=contact, backend=row.backend,
                             solver=row.solver, accuracy="high")
    rtol = force_rtol(row.backend, row.solver)
    force_scale = max(np.abs(reference.contact_force).max(), np.abs(scene.nodal_loads()).max())
    # λ from the dual equals Lagrange's λ to rtol of the force scale (force_rtol's docstring)
    np.testing.assert_allclose(result.contact_force, reference.contact_force, rtol=0,
                               atol=rtol * force_scale)
    # ... and equals the wall force that equilibrium at the wall node needs, computed from u
    from_u, from_lambda = equilibrium_contact_forces(scene, result.u, result.contact_force)
    np.testing.assert_allclose(from_lambda, from_u, rtol=0, atol=rtol * force_scale)
    # support reactions + wall forces balance the loads (the reactions come from u, so this is
    # the global balance of the displacements and the duals together)
    walls = sum(-w.sign * lam for w, lam in zip(scene.walls, result.contact_force))
    total = result.reactions.sum() + walls + scene.nodal_loads().sum()
    assert abs(total) <= rtol * force_scale
    # the independent check passes too, except through a cone rewrite, which stops short of
    # its 1e-6 equilibrium tolerance (measured: 1e-7 to 1e-5 of the force scale)
    assert result.verified or (row.backend, row.solver) in SOC_REWRITE, result.message
    # displacements: u to rtol of the displacement scale (largest |u| or gap)
    disp_scale = max(np.abs(reference.u).max(), max(w.gap for w in scene.walls))
    np.testing.assert_allclose(result.u, reference.u, rtol=0, atol=rtol * disp_scale)


def test_equality_at_two_walls_of_one_node():
    with pytest.raises(OptionError, match=r"cannot hold wall\[1\] \(node 2\) together with wall\[0\] \(node 2\)"):
        contactqp.solve(both_sides(), method="qp", contact="equality")


@pytest.mark.parametrize("row", PAIRS)
def test_open_gap(row):
    """Inequality: no force, the gap stays open. Equality on the same scene: the wall must
    pull the tip out to the wall (a negative λ), and the Result calls it non-physical."""
    require(row)
    scene = open_gap()
    options = {"backend": row.backend, "solver": row.solver, "accuracy": "high"}
    rtol = force_rtol(row.backend, row.solver)
    load = abs(scene.loads[0].force)
    free = contactqp.solve(scene, method="qp", contact="inequality", **options)
    assert abs(free.contact_force[0]) <= rtol * load
    gap = -free.penetration[0]
    assert gap > 0.5 * scene.walls[0].gap  # the tip moves ~1 mm of the 5 mm
    held = contactqp.solve(scene, method="qp", contact="equality", **options)
    reference = contactqp.solve(scene, method="lagrange", contact="equality")
    assert reference.contact_force[0] < 0
    assert held.contact_force[0] == pytest.approx(reference.contact_force[0], abs=rtol * load)
    assert not held.physical
    assert "pulls" in held.message


# ---------------------------------------------------------------------------------------------
# The dual sign of each backend, in one table


BACKEND_ROWS = [pytest.param(b, id=b) for b in qpmod.BACKEND_MODULES]


@pytest.mark.parametrize("backend", BACKEND_ROWS)
@pytest.mark.parametrize("contact", CONTACTS)
def test_dual_sign(backend, contact):
    """The backend's raw dual times DUAL_SIGNS is μ = λ/F with λ > 0 for a wall that pushes
    (inequality, the default scene) and λ < 0 for one that pulls (equality, open gap)."""
    if qpmod.BACKENDS[backend] is None:
        pytest.skip(f"backend {backend} is not installed: {qpmod.BACKEND_MODULES[backend][1]}")
    scene = contactqp.seed_scene() if contact == "inequality" else open_gap()
    model = contactqp.build_model(scene)
    module, solver = qpmod.resolve_solver(backend, None)
    qp = qpmod.qp_from_model(model, contact)
    raw = module.solve(qp, solver, qpmod.accuracy_settings(solver, "high"))
    reference = contactqp.solve(scene, method="lagrange", contact=contact).contact_force
    mu = reference / qp.force_scale
    assert np.sign(reference[0]) == (1 if contact == "inequality" else -1)
    # Clarabel at "high" is the default solver of three backends; OSQP polishes: 1e-6 of μ
    assert qpmod.DUAL_SIGNS[backend][contact] * raw.dual == pytest.approx(mu, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# The independent check catches solvers that claim success and are wrong


def long_bar(elements: int = 1000) -> Scene:
    """The default scene cut into ``elements`` equal elements (load at mid-length, wall at the
    tip): K reaches 2e11 N/m."""
    seed = contactqp.seed_scene()
    bar = Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9)
    return Scene(bar, (Support(0),), (Load(elements // 2, seed.loads[0].force),),
                 (Wall(elements, seed.walls[0].gap, "+"),), name=f"{elements} elements")


WRONG_BUT_CLAIMED = [
    # HiGHS in SI units on the default scene: the wall node stays at u = 0 with "optimal";
    # 7.6 % off in λ (measured, highspy 1.x through both front ends)
    pytest.param("qpsolvers", "highs", contactqp.seed_scene, "complementarity",
                 id="qpsolvers-highs-seed"),
    pytest.param("cvxpy", "HIGHS", contactqp.seed_scene, "complementarity", id="cvxpy-HIGHS-seed"),
    # QPALM at its own default tolerance (1e-4) in SI units: the tip 1.3 % past the wall
    pytest.param("qpsolvers", "qpalm", contactqp.seed_scene, "feasibility",
                 id="qpsolvers-qpalm-seed"),
    # OSQP at its default tolerance (1e-3) in SI units on 1000 elements: "solved", with an
    # equilibrium residual of 1e-3 (scaled, the same settings pass)
    pytest.param("osqp", "osqp", long_bar, "equilibrium", id="osqp-1000-elements"),
]


@pytest.mark.parametrize(("backend", "solver", "make_scene", "residual"), WRONG_BUT_CLAIMED)
def test_check_catches_a_false_success(backend, solver, make_scene, residual):
    """Default accuracy, scale=False: cases measured to claim success with a wrong answer."""
    row = next((r for r in SOLVERS if (r.backend, r.solver) == (backend, solver)), None)
    if row is None or not row.available:
        pytest.skip(f"{backend}/{solver} is not installed")
    result = contactqp.solve(make_scene(), method="qp", backend=backend, solver=solver,
                             scale=False)
    assert result.claimed_success
    assert not result.verified
    assert f"{residual} residual" in result.message
    assert any("but the check failed" in w for w in result.warnings)


def test_a_solver_that_raises_gives_nan_and_no_claim(monkeypatch):
    module = qpmod.BACKENDS["clarabel"]

    def explode(qp, solver, settings, verbose):
        raise RuntimeError("factorisation failed")

    monkeypatch.setattr(module, "solve", explode)
    result = contactqp.solve(method="qp", backend="clarabel")
    assert not result.claimed_success and not result.verified
    assert "raised RuntimeError: factorisation failed" in result.status
    assert np.isnan(result.contact_force).all()


# ---------------------------------------------------------------------------------------------
# The QP data


@pytest.mark.parametrize("scene_name", list(SCENES))
@pytest.mark.parametrize("contact", CONTACTS)
def test_qp_problem_matches_the_model(scene_name, contact):
    scene = SCENES[scene_name]()
    model = contactqp.build_model(scene)
    si = contactqp.qp_problem(scene, contact=contact, scale=False)
    assert (si.displacement_scale, si.force_scale) == (1.0, 1.0)
    assert abs(si.K - model.K).max() == 0.0
    np.testing.assert_array_equal(si.q, -model.P)
    assert abs(si.C - model.C).max() == 0.0
    np.testing.assert_array_equal(si.g, model.g)
    scaled = contactqp.qp_problem(scene, contact=contact)
    k, U, F = scaled.stiffness_scale, scaled.displacement_scale, scaled.force_scale
    assert k == pytest.approx(F / U, rel=1e-15)
    # K_SI = k·K̂, P = −F·q̂, g = U·ĝ, to round-off
    assert abs(k * scaled.K - model.K).max() <= 1e-14 * abs(model.K).max()
    np.testing.assert_allclose(-F * scaled.q, model.P, rtol=1e-14)
    np.testing.assert_allclose(U * scaled.g, model.g, rtol=1e-14)
    # the scaled data are O(1): what the scaling is for
    assert 0.1 <= np.abs(scaled.q).max() <= 10.0
    assert np.abs(scaled.g).max() <= 10.0


@pytest.mark.parametrize("scene_name", list(SCENES))
def test_scaling_round_trip_and_scaled_kkt(scene_name):
    """(u, λ) → (x, μ) → (u, λ) is the identity, and Lagrange's (u, λ) satisfies the scaled
    KKT condition K̂x + q̂ + Cᵀμ = 0: the scaled QP has the same solution, μ = λ/F."""
    scene = SCENES[scene_name]()
    reference = contactqp.solve(scene, method="lagrange")
    model = contactqp.build_model(scene)
    qp = contactqp.qp_problem(scene)
    u_free = reference.u[model.free]
    x, mu = qp.from_si(u_free, reference.contact_force)
    back_u, back_lambda = qp.to_si(x, mu)
    np.testing.assert_allclose(back_u, u_free, rtol=1e-15)
    np.testing.assert_allclose(back_lambda, reference.contact_force, rtol=1e-15)
    stationarity = qp.K @ x + qp.q + qp.C.T @ mu
    # round-off of the O(1) scaled terms (K̂ entries up to ~1e2 on these scenes)
    assert np.abs(stationarity).max() <= 1e-12
    assert np.abs(mu).max() <= 10.0  # multipliers O(1)


# ---------------------------------------------------------------------------------------------
# The registry and the options


def test_registry_lists_installed_pairs_and_pip_hints():
    rows = contactqp.available_qp_solvers()
    assert {("clarabel", "clarabel"), ("osqp", "osqp")} <= {(r.backend, r.solver) for r in rows}
    for row in rows:
        assert row.available == (row.install == "")
        if not row.available:
            assert row.install.startswith("pip install")


def test_missing_backend_raises_with_a_pip_hint(monkeypatch):
    monkeypatch.setitem(qpmod.BACKENDS, "osqp", None)
    monkeypatch.setitem(qpmod.MISSING, "osqp", "No module named 'osqp'")
    with pytest.raises(SolverNotAvailable, match=r"pip install osqp"):
        contactqp.solve(method="qp", backend="osqp")
    assert any(r.backend == "osqp" and not r.available for r in contactqp.available_qp_solvers())


def test_missing_solver_raises_with_a_pip_hint(monkeypatch):
    module = qpmod.BACKENDS["qpsolvers"]
    if module is None:
        pytest.skip("qpsolvers is not installed")
    installed = tuple(s for s in module.installed_solvers() if s != "highs")
    monkeypatch.setattr(module, "installed_solvers", lambda: installed)
    with pytest.raises(SolverNotAvailable, match=r"pip install highspy"):
        contactqp.solve(method="qp", backend="qpsolvers", solver="highs")


@pytest.mark.parametrize(("options", "words"), [
    ({"backend": "gurobi_direct"}, ["'gurobi_direct'", "clarabel", "cvxpy"]),
    ({"backend": "qpsolvers", "solver": "nosuch"}, ["'nosuch'", "clarabel", "osqp"]),
    ({"backend": "cvxpy", "solver": "NOSUCH"}, ["'NOSUCH'", "CLARABEL"]),
    ({"accuracy": "extreme"}, ["'extreme'", "default", "high"]),
    ({"scale": "yes"}, ["'yes'", "True or False"]),
])
def test_unknown_options_raise_option_error(options, words):
    with pytest.raises(OptionError) as raised:
        contactqp.solve(method="qp", **options)
    for word in words:
        assert word in str(raised.value)


def test_cvxpy_resolves_a_new_load_without_recanonicalising():
    if qpmod.BACKENDS["cvxpy"] is None:
        pytest.skip("cvxpy is not installed")
    qpmod.BACKENDS["cvxpy"].clear_cache()
    scene = several_walls()
    first = qpmod.solve_qp(contactqp.build_model(scene), "inequality", backend="cvxpy")
    assert first.info["cache"] == "miss"
    heavier = scene.with_loads(tuple(Load(p.node, 1.5 * p.force) for p in scene.loads))
    wider = heavier.with_walls(tuple(Wall(w.node, 2 * w.gap, w.side) for w in scene.walls))
    for changed in (heavier, wider):
        again = qpmod.solve_qp(contactqp.build_model(changed), "inequality", backend="cvxpy")
        assert again.info["cache"] == "hit"
        reference = contactqp.solve(changed, method="lagrange")
        # CLARABEL at "default" (gap and feasibility 1e-8 of the O(1) scaled problem)
        np.testing.assert_allclose(again.contact_force, reference.contact_force, rtol=0,
                                   atol=1e-6 * np.abs(reference.contact_force).max())


@pytest.mark.parametrize(("limit", "parameters"), [(10**9, "loads, gaps"), (40, "loads"),
                                                   (1, "none")])
def test_cvxpy_uses_constants_where_parameters_would_densify(monkeypatch, limit, parameters):
    # cvxpy densifies (unknowns + 2) x (parameter entries + 1) coefficients; over the limit a
    # vector is a constant and its values key the cache: a new value must not hit a stale one
    if qpmod.BACKENDS["cvxpy"] is None:
        pytest.skip("cvxpy is not installed")
    backend = qpmod.BACKENDS["cvxpy"]
    monkeypatch.setattr(backend, "DENSE_LIMIT", limit)
    backend.clear_cache()
    scene = several_walls()  # 6 unknowns, 3 loads, 4 walls: 8 x 4 = 32, 8 x 8 = 64 entries
    heavier = scene.with_loads(tuple(Load(p.node, 1.001 * p.force) for p in scene.loads))
    wider = heavier.with_walls(scene.walls[:-1] + (Wall(5, 6e-3, "+"),))  # the open wall
    # the same displacement scale U throughout, so a new load or gap changes the scaled q or g
    assert len({qpmod.scales(contactqp.build_model(s))[0] for s in (scene, heavier)}) == 1
    caches = []
    for changed in (scene, heavier, wider, wider):
        again = qpmod.solve_qp(contactqp.build_model(changed), "inequality", backend="cvxpy")
        assert again.info["parameters"] == parameters
        caches.append(again.info["cache"])
        reference = contactqp.solve(changed, method="lagrange")
        np.testing.assert_allclose(again.contact_force, reference.contact_force, rtol=0,
                                   atol=1e-6 * np.abs(reference.contact_force).max())
    expected = {"loads, gaps": ["miss", "hit", "hit", "hit"], "loads": ["miss", "hit", "miss",
                "hit"], "none": ["miss", "miss", "miss", "hit"]}[parameters]
    assert caches == expected


def test_dense_solvers_are_not_attempted_on_a_long_bar(monkeypatch):
    monkeypatch.setattr(qpmod, "DENSE_LIMIT", 3)
    row = next((r for r in SOLVERS if (r.backend, r.solver) == ("qpsolvers", "quadprog")), None)
    if row is None or not row.available:
        pytest.skip("quadprog is not installed")
    result = contactqp.solve(method="qp", backend="qpsolvers", solver="quadprog")
    assert not result.claimed_success and not result.verified
    assert result.status.startswith("not attempted")
