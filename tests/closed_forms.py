"""Closed forms, scenes and helpers shared by several test modules.

Every expected number here comes from the problem statement: closed forms, exact arithmetic,
dense numpy solves of matrices assembled here, or scipy's quadrature; the only library
answers used are those of :mod:`contactqp.reference` (the exact reference), as a yardstick for
the solvers' errors. Scenes are built with the library's constructors, never solved by it.

Glossary: E Young's modulus (Pa), A area (m²), L length (m), k = EA/L a stiffness (N/m),
f a compliance Σ L/(EA) (m/N), F a point load (N), g a gap (m), λ a contact force (N),
u the displacements (m), K, P, C, g the stiffness, loads, contact rows and gaps.
"""

from __future__ import annotations

import copy
import itertools
import math
import subprocess
import sys
from dataclasses import replace
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import contactqp
from contactqp import Bar, Load, Scene, Support, Wall
from contactqp.methods import qp as qpmod
from contactqp.model import Layout
from contactqp.reference import reference

# --- the default scene, as the problem states it: a 1 m steel cone, 40 mm to 20 mm, fixed at
# node 0, loaded at mid-length (node 2), a "+" wall 0.1 mm beyond the tip (node 4)
DEFAULT_E = 210e9  # Pa
DEFAULT_YIELD = 200e6  # Pa
DEFAULT_F, DEFAULT_LOAD_NODE = 565486.67, 2  # N
DEFAULT_GAP, DEFAULT_WALL_NODE = 1e-4, 4  # m
DEFAULT_LENGTH = 1.0  # m
DEFAULT_LENGTHS = [0.25] * 4  # m
DEFAULT_DIAMETERS = [0.040, 0.035, 0.030, 0.025, 0.020]  # m, at nodes 0..4
DEFAULT_DIAMETERS_MM = [40.0, 35.0, 30.0, 25.0, 20.0]  # the same, in mm

E_STEEL = 210e9  # Pa
E_SPRINGS = 200e9  # Pa, of spring()'s one-element bars and the distributed-load bars
HAND_GAP = 1.5e-4  # m, the wall of hand_scene


# --- the cone in the continuum
def diameter(x: float) -> float:
    return 0.040 - 0.020 * x / DEFAULT_LENGTH


def cone_compliance(a: float, b: float) -> float:
    value, _ = quad(lambda x: 1.0 / (DEFAULT_E * math.pi * diameter(x) ** 2 / 4.0), a, b,
                    epsabs=0.0, epsrel=1e-13)
    return value


def continuum_force() -> float:
    """The default scene's contact force in the continuum: (F f(0, L/2) − g) / f(0, L), f the
    cone's compliance integrated numerically (scipy.integrate.quad, not the library)."""
    return (DEFAULT_F * cone_compliance(0.0, DEFAULT_LENGTH / 2) - DEFAULT_GAP) / cone_compliance(
        0.0, DEFAULT_LENGTH)


def cone_contact_force() -> float:
    """The same force from the closed form of the cone's compliance: with d linear,
    f(a, b) = ∫ₐᵇ 4 dx / (E π d(x)²) = 4 (b − a) / (E π d(a) d(b))."""
    def compliance(a: float, b: float) -> float:
        return 4.0 * (b - a) / (DEFAULT_E * math.pi * diameter(a) * diameter(b))

    return (DEFAULT_F * compliance(0.0, DEFAULT_LENGTH / 2) - DEFAULT_GAP) / compliance(
        0.0, DEFAULT_LENGTH)


def cone_like_f() -> float:
    """f of the default 4-element midpoint mesh, from the element areas computed here."""
    mids = [0.0375, 0.0325, 0.0275, 0.0225]
    return sum(0.25 / (DEFAULT_E * math.pi * d**2 / 4) for d in mids)


# --- the default scene, discrete: closed forms
def default_areas(area_rule: str) -> list[float]:
    """Element areas of the default bar from its diameters (m²)."""
    pairs = itertools.pairwise(DEFAULT_DIAMETERS)
    if area_rule == "midpoint":
        return [math.pi * ((da + db) / 2) ** 2 / 4 for da, db in pairs]
    return [math.pi * da * db / 4 for da, db in pairs]


def default_scene_with(area_rule: str = "midpoint", force: float = DEFAULT_F,
                       walls: tuple[Wall, ...] = (Wall(DEFAULT_WALL_NODE, DEFAULT_GAP, "+"),)
                       ) -> Scene:
    bar = Bar.tapered_circle(1.0, 4, 0.040, 0.020, DEFAULT_E, area_rule=area_rule,
                             yield_stress=DEFAULT_YIELD)
    return Scene(bar, (Support(0),), (Load(DEFAULT_LOAD_NODE, force),), walls)


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


def default_closed_form(area_rule="midpoint", force=DEFAULT_F, contact="inequality",
                        penalty=None):
    return cantilever(DEFAULT_LENGTHS, default_areas(area_rule), DEFAULT_E,
                      [(DEFAULT_LOAD_NODE, force)], (DEFAULT_WALL_NODE, DEFAULT_GAP, "+"),
                      contact=contact, penalty=penalty)


def default_compliance(node: int, area_rule: str = "midpoint") -> float:
    """f_node of the default bar (m/N)."""
    return sum(length / (DEFAULT_E * area)
               for length, area in zip(DEFAULT_LENGTHS[:node], default_areas(area_rule)[:node]))


def small_force() -> float:
    """A load that moves the wall node only half way to the wall: F f_2 = g / 2."""
    return 0.5 * DEFAULT_GAP / default_compliance(DEFAULT_LOAD_NODE)


# --- dense algebra and brute force
def assert_normwise(actual, expected, rel: float) -> None:
    """max |actual − expected| <= rel · max |expected|: how round-off shows in a solve."""
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    assert actual.shape == expected.shape
    assert np.abs(actual - expected).max(initial=0.0) <= rel * np.abs(expected).max(initial=0.0)


def dense_algebra(scene: Scene):
    """(K_full, P_full, free nodes, K, P, C, g) with K_full and P_full over every node."""
    bar = scene.bars[0]
    n = Layout(scene).n_nodes
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


def answer_scales(scene: Scene, u: np.ndarray, lam: np.ndarray) -> tuple[float, float]:
    """(force scale N, displacement scale m) against which round-off is measured: the largest
    load or contact force, and the largest of |u|, the gaps and what that force does to the
    softest element (so the scale stays physical where the exact u is 0)."""
    bar = scene.bars[0]
    force = max(np.abs(Layout(scene).nodal_loads).max(), np.abs(lam).max(initial=0.0))
    k_min = float(np.min(np.asarray(bar.youngs_modulus) * bar.areas / bar.lengths))
    gaps = [w.gap for w in scene.walls]
    return force, max(np.abs(u).max(initial=0.0), max(gaps, default=0.0), force / k_min)


def brute_force(scene: Scene, contact: str = "inequality"):
    """(u at every node, λ, walls in contact) by trying every set of walls in contact and
    keeping the one that violates the KKT conditions least. The exact answer is unique and
    meets them to round-off; a wrong set violates them by a physical amount, though that can be
    below a loose tolerance on a scene that mixes scales (hypothesis: 1 N against a stiff
    zero-gap wall, 1.8e-10 m, beside 640 kN on a soft element), so the least, not the first,
    is kept, and it must be within round-off."""
    _, _, free, K, P, C, g = dense_algebra(scene)
    m = g.size
    if contact == "equality":
        candidates = [tuple(range(m))]
    else:
        candidates = itertools.chain.from_iterable(
            itertools.combinations(range(m), r) for r in range(m + 1))
    best = None
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
        f_scale, u_scale = answer_scales(scene, x[:len(free)], lam)
        violation = 0.0 if contact == "equality" else max(
            (C @ x[:len(free)] - g).max(initial=0.0) / u_scale, -lam.min(initial=0.0) / f_scale)
        if best is None or violation < best[0]:
            u = np.zeros(Layout(scene).n_nodes)
            u[free] = x[:len(free)]
            best = (violation, u, lam, active)
    # KKT within round-off of these small dense solves (κ ≲ 1e5, so ~1e-11)
    if best is None or best[0] > 1e-9:
        raise AssertionError("no set of walls in contact satisfies the KKT conditions")
    return best[1], best[2], best[3]


def rational_solve(A: list[list[Fraction]], b: list[Fraction]) -> list[Fraction] | None:
    """x with A x = b by Gauss–Jordan in exact arithmetic; None where A is singular."""
    n = len(b)
    rows = [list(A[i]) + [b[i]] for i in range(n)]
    for col in range(n):
        pivot = next((r for r in range(col, n) if rows[r][col] != 0), None)
        if pivot is None:
            return None
        rows[col], rows[pivot] = rows[pivot], rows[col]
        head = rows[col][col]
        rows[col] = [v / head for v in rows[col]]
        for r in range(n):
            if r != col and rows[r][col] != 0:
                factor = rows[r][col]
                rows[r] = [a - factor * c for a, c in zip(rows[r], rows[col])]
    return [rows[i][n] for i in range(n)]


def exact_problem_answer(K, f, C, g, prescribed=(), values=(), equality=()):
    """(u, λ) of min ½uᵀKu − fᵀu s.t. C u <= g (rows in ``equality``: C u = g),
    u[prescribed] = values, in exact rational arithmetic: every set of rows in contact is
    tried (equality rows always in), and the one whose KKT conditions hold exactly is kept.
    For small dense problems (every float read as the rational it is); K positive definite on
    the free dofs, or held by the rows in contact. Where rows are redundant (their forces not
    unique) the first set found is kept: compare Cᵀλ, not λ."""
    K = [[Fraction(float(v)) for v in row] for row in np.asarray(K, dtype=float)]
    f = exact(np.asarray(f, dtype=float))
    C = [[Fraction(float(v)) for v in row] for row in np.asarray(C, dtype=float).reshape(
        len(g), len(f))]
    g = exact(np.asarray(g, dtype=float))
    n, m = len(f), len(g)
    held = {int(d): Fraction(float(v)) for d, v in zip(prescribed, values)}
    free = [i for i in range(n) if i not in held]
    rhs_free = [f[i] - sum(K[i][d] * v for d, v in held.items()) for i in free]
    always = sorted(int(i) for i in equality)
    others = [i for i in range(m) if i not in always]
    for size in range(len(others) + 1):
        for chosen in itertools.combinations(others, size):
            active = always + list(chosen)
            k = len(active)
            A = [[K[i][j] for j in free] + [C[r][i] for r in active] for i in free]
            A += [[C[r][j] for j in free] + [Fraction(0)] * k for r in active]
            b = rhs_free + [g[r] - sum(C[r][d] * v for d, v in held.items()) for r in active]
            x = rational_solve(A, b)
            if x is None:
                continue
            u = [Fraction(0)] * n
            for d, v in held.items():
                u[d] = v
            for i, j in enumerate(free):
                u[j] = x[i]
            lam = [Fraction(0)] * m
            for i, r in enumerate(active):
                lam[r] = x[len(free) + i]
            gaps_met = all(sum(C[r][j] * u[j] for j in range(n)) <= g[r] for r in others)
            pushing = all(lam[r] >= 0 for r in others)
            if gaps_met and pushing:
                return (np.array([float(v) for v in u]), np.array([float(v) for v in lam]))
    raise AssertionError("no set of rows in contact meets the KKT conditions exactly")


def exact(values) -> list[Fraction]:
    return [Fraction(float(v)) for v in values]


def error(result: contactqp.Result, scene: Scene) -> float:
    """The result's largest contact-force error, relative to the exact reference's largest
    force (or the largest load where no wall pushes)."""
    exact = reference(scene).contact_force
    scale = np.abs(exact).max() or np.abs(Layout(scene).nodal_loads).max()
    return float(np.abs(result.contact_force - exact).max()) / scale


# --- scenes
DEFAULT_SCENE = contactqp.default_scene()

BAR = Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))


def hand_scene(force: float = 3e4, gap: float = HAND_GAP) -> Scene:
    bar = Bar.from_areas([1e-3, 5e-4], 2e11, lengths=[1.0, 1.0])
    return Scene(bar, (Support(0),), (Load(2, force),), (Wall(2, gap, "+"),))


def spring(k: float, length: float = 1.0) -> Bar:
    """A one-element bar of stiffness k (N/m)."""
    return Bar.from_areas([k * length / E_SPRINGS], E_SPRINGS, length=length)


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
    seed = contactqp.default_scene()
    return seed.with_walls((Wall(seed.walls[0].node, 5e-3, "+"),))


SCENES = {
    "seed": contactqp.default_scene,
    "several_walls": several_walls,
    "both_sides": both_sides,
    "open_gap": open_gap,
}


def clamped(load: Load) -> Scene:
    """Node 1 between two zero-gap walls, a zero-gap "+" wall at node 2 (test_clamped_node)."""
    return Scene(Bar.from_areas([1e-4, 1e-3], 2e11, length=2.0), (Support(0),), (load,),
                 (Wall(1, 0.0, "+"), Wall(1, 0.0, "-"), Wall(2, 0.0, "+")))


def touching() -> Scene:
    """The default scene with the load that brings node 4 exactly to its wall: F·f₂ = g."""
    scene = contactqp.default_scene()
    flexibility = sum(Fraction(1) / Fraction(k) for k in Layout(scene).element_stiffness[:2])
    return scene.with_loads((Load(2, float(Fraction(scene.walls[0].gap) / flexibility)),))


def valid_data() -> dict:
    """A valid scene as the parsed TOML structure: 2 elements, nodes 0, 1, 2."""
    return {
        "name": "valid",
        "material": {"youngs_modulus": 2e11, "yield_stress": 2.5e8},
        "bar": {"areas": [1e-4, 2e-4], "length": 1.0},
        "support": [{"node": 0}],
        "load": [{"node": 2, "force": 1e3}],
        "wall": [{"node": 2, "gap": 1e-4, "side": "+"}],
    }


def with_value(data: dict, path: tuple, value) -> dict:
    """A deep copy of ``data`` with the item at ``path`` (keys and list indices) set."""
    data = copy.deepcopy(data)
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return data


# --- QP solvers: which are installed, and the accuracy to expect of each
QP_SOLVERS = contactqp.available_qp_solvers()
INSTALLED_SOLVERS = [s for s in QP_SOLVERS if s.available]
QP_PAIRS = [(s.backend, s.solver) for s in INSTALLED_SOLVERS]
PAIRS = [pytest.param(r, id=f"{r.backend}-{r.solver}") for r in QP_SOLVERS]

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


def runs(rng: np.random.Generator) -> list[tuple[str, dict, str]]:
    """(method, options, formulation) for every method and every installed QP solver."""
    out = [("lagrange", {}, f) for f in ("full", "condensed", "strain")]
    out += [("penalty", {}, f) for f in ("full", "condensed")]
    out += [("augmented", {}, f) for f in ("full", "condensed")]
    out += [("lemke", {}, str(rng.choice(["full", "condensed"]))),
            ("pgs", {"relaxation": float(rng.choice([1.0, 1.5]))}, "full"),
            ("semismooth_newton", {"ncp": str(rng.choice(["min", "fischer-burmeister"]))},
             str(rng.choice(["full", "condensed"]))),
            # walls at a bar's end only (any other scene is refused with the reason)
            ("nitsche", {"theta": float(rng.choice([1.0, 0.0, -1.0])),
                         "gamma0": float(10.0 ** rng.uniform(1.0, 8.0))}, "full")]
    for backend, solver in QP_PAIRS:
        out.append(("qp", {"backend": backend, "solver": solver,
                           "accuracy": str(rng.choice(["default", "high"])),
                           "scale": bool(rng.random() < 0.8)},
                    str(rng.choice(["full", "condensed", "strain"]))))
    return out


def rebuilt(scene: contactqp.Scene, loads: np.ndarray, gaps: np.ndarray) -> contactqp.Scene:
    """The scene with these values, built from its parts (independently of with_values)."""
    n_point, n_walls = len(scene.loads), len(scene.walls)
    return contactqp.Scene(
        scene.bars, scene.supports,
        tuple(replace(p, force=float(f)) for p, f in zip(scene.loads, loads[:n_point])),
        tuple(replace(w, gap=float(g)) for w, g in zip(scene.walls, gaps[:n_walls])),
        name=scene.name,
        distributed=tuple(replace(q, intensity=float(f))
                          for q, f in zip(scene.distributed, loads[n_point:])),
        contacts=tuple(replace(c, gap=float(g)) for c, g in zip(scene.contacts, gaps[n_walls:])),
        units=scene.units)


def values(scene: contactqp.Scene) -> tuple[np.ndarray, np.ndarray]:
    loads = np.array([p.force for p in scene.loads] + [q.intensity for q in scene.distributed])
    gaps = np.array([w.gap for w in scene.walls] + [c.gap for c in scene.contacts])
    return loads, gaps


def imported_by(code: str, modules: tuple[str, ...]) -> list[str]:
    """Which of ``modules`` a fresh Python process has imported once it has run ``code`` (a
    user's script starts in a fresh process; an import that costs time shows there)."""
    probe = f"{code}\nimport sys; print(','.join(m for m in {modules!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120, check=True)
    return [m for m in done.stdout.strip().split(",") if m]
