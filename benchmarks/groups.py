"""The benchmark groups besides the matrix (benchmarks/matrix.py), each a function that prints
a table and writes a JSON file into the output folder; benchmarks/run.py runs them by name.

    taper      how the methods scale: the tapered bar with 10² … 10⁶ elements (exact areas),
               one wall at the tip, full, strain and condensed formulations; the force error
               against the continuum (exact areas make the two the same)
    walls      scaling in the number of contacts: a wall beside every node (the discrete
               obstacle problem), 10² … 10⁵ contacts, every method; a method whose solve
               passes BUDGET is not run at the larger sizes (recorded with the reason)
    overhead   what the QP method costs on top of the solver it calls: solve(method="qp")
               end to end against Clarabel and OSQP called directly on matrices built
               beforehand; a cvxpy re-solve with a new load and gap against its first solve;
               and start-up (import contactqp, --help, --version) against a process that
               imports numpy and scipy.sparse
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import clarabel
import numpy as np
import osqp
import scipy.sparse as sp

import contactqp
from cases import floor, machine, median_time, obstacle, tapered_scene
from contactqp.methods import qp as qpmod
from contactqp.methods.qp.settings import accuracy_settings

# taper: (method, options, {formulation: largest size it is run at}); condensed at every size
TAPER_RUNS = [
    ("lagrange", {}, {"full": 10**6, "strain": 10**5}),
    ("penalty", {}, {"full": 10**6}),
    ("augmented", {}, {"full": 10**6}),
    ("qp", {"backend": "clarabel"}, {"full": 10**4, "strain": 10**5}),
    ("qp", {"backend": "osqp"}, {"full": 10**4, "strain": 10**5}),
]
FORMULATIONS = ("full", "strain", "condensed")
WALL_RUNS = [("lagrange", {}), ("penalty", {}), ("augmented", {}), ("qp", {"backend": "clarabel"}),
             ("qp", {"backend": "osqp"}), ("qp", {"backend": "cvxpy"})]
BUDGET = 60.0  # s for one solve; beyond it the method is not run at larger sizes


def _write(out: Path, name: str, data: object) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / name).write_text(json.dumps({"machine": machine(), "data": data}, indent=1))
    print(f"written: {out / name}")


def cone_force() -> float:
    """The continuum contact force of the default scene (N), the tapered bar's closed form:
    λ = (F·f(0, L/2) − g) / f(0, L), f(a, b) = 4(b − a)/(E·π·d(a)·d(b))."""
    def f(a: float, b: float) -> float:
        def d(x: float) -> float:
            return 0.040 + (0.020 - 0.040) * x
        return 4.0 * (b - a) / (210e9 * np.pi * d(a) * d(b))
    return (565486.67 * f(0.0, 0.5) - 1e-4) / f(0.0, 1.0)


def taper(quick: bool, out: Path) -> None:
    sizes = [10**2, 10**4, 10**5] if quick else [10**2, 10**4, 10**5, 10**6]
    repeats = 3 if quick else 7
    rows = []
    exact = cone_force()
    print(f"{'elements':>9} {'run':>22} {'formulation':>11} {'time (s)':>9} {'/floor':>7} "
          f"{'force error':>11} {'verified':>8} {'iterations':>10}")
    for n in sizes:
        scene = tapered_scene(n)
        base = floor(scene, repeats)
        print(f"{n:>9} {'floor: pbsv on K':>22} {'':>11} {base:9.4f} {1.0:7.2f}")
        for method, options, limits in TAPER_RUNS:
            for formulation in FORMULATIONS:
                label = "/".join([method, *options.values()])
                if formulation != "condensed" and formulation not in limits:
                    continue  # penalty and augmented have no strain formulation
                limit = limits.get(formulation, n)
                if n > limit:
                    rows.append({"elements": n, "run": label, "formulation": formulation,
                                 "skipped": f"{formulation} formulation above {limit} elements: "
                                            "a solve of n (or 2n) unknowns, seconds to minutes"})
                    continue
                result = contactqp.solve(scene, method, formulation=formulation, **options)
                seconds = median_time(
                    partial(contactqp.solve, scene, method, formulation=formulation, **options),
                    repeats)
                error = abs(float(result.contact_force[0]) - exact) / exact
                rows.append({"elements": n, "run": label, "formulation": formulation,
                             "seconds": seconds, "floor_seconds": base, "ratio": seconds / base,
                             "force_error": error, "verified": result.verified,
                             "iterations": result.iterations})
                print(f"{n:>9} {label:>22} {formulation:>11} {seconds:9.4f} {seconds / base:7.2f} "
                      f"{error:11.1e} {result.verified!s:>8} {result.iterations:>10}")
    _write(out, "taper.json", rows)



def walls(quick: bool, out: Path) -> None:
    sizes = [10**2, 10**3] if quick else [10**2, 10**3, 10**4, 10**5]
    rows, over_budget = [], {}
    print(f"{'contacts':>8} {'run':28} {'time (s)':>9} {'/floor':>8} {'iter':>6} "
          f"{'force error':>11} verified")
    for n in sizes:
        scene = obstacle(n)
        base = floor(scene, 5)
        start = time.perf_counter()
        reference = contactqp.solve(scene, "lagrange")
        reference_time = time.perf_counter() - start
        lam_scale = float(np.abs(reference.contact_force).max())
        for method, options in WALL_RUNS:
            label = "/".join([method, *options.values()])
            if label in over_budget:
                rows.append({"contacts": n, "run": label, "skipped": over_budget[label]})
                print(f"{n:8d} {label:28} skipped: {over_budget[label]}")
                continue
            start = time.perf_counter()
            result = contactqp.solve(scene, method, **options)
            once = time.perf_counter() - start
            if method == "lagrange":
                once = min(once, reference_time)
            run = partial(contactqp.solve, scene, method, **options)
            seconds = median_time(run, 3 if once < 1.0 else 1) if once < 10.0 else once
            error = float(np.abs(result.contact_force - reference.contact_force).max()) / lam_scale
            rows.append({"contacts": n, "run": label, "seconds": seconds, "ratio": seconds / base,
                         "iterations": result.iterations, "force_error": error,
                         "verified": result.verified, "claimed_success": result.claimed_success,
                         "active": int(np.count_nonzero(result.contact_force > 0))})
            print(f"{n:8d} {label:28} {seconds:9.3f} {seconds / base:8.0f} "
                  f"{result.iterations:6d} {error:11.1e} {result.verified}")
            if seconds > BUDGET:
                over_budget[label] = f"{seconds:.0f} s at {n} contacts (budget {BUDGET:.0f} s)"
        rows.append({"contacts": n, "run": "floor (pbsv on K)", "seconds": base})
    print("every run here is 'full'; the condensed chain and the hull: --cases contacts")
    _write(out, "walls.json", rows)



def hand_built(scene: contactqp.Scene) -> dict[str, Callable[[], object]]:
    """The solvers called directly on the scaled QP data, built once outside the timing."""
    qp = contactqp.qp_problem(scene)
    P = sp.csc_matrix(qp.K_upper)
    A = sp.csc_matrix(qp.C)
    lower = np.full(qp.g.size, -np.inf)
    osqp_settings = accuracy_settings("osqp", "default", scaled=True)
    clarabel_settings = clarabel.DefaultSettings()
    clarabel_settings.verbose = False
    for key, value in accuracy_settings("clarabel", "default", scaled=True).items():
        setattr(clarabel_settings, key, value)

    def run_osqp() -> object:
        engine = osqp.OSQP()
        engine.setup(P, qp.q, A, lower, qp.g, verbose=False, **osqp_settings)
        return engine.solve()

    def run_clarabel() -> object:
        cones = [clarabel.NonnegativeConeT(qp.g.size)]
        return clarabel.DefaultSolver(P, qp.q, A, qp.g, cones, clarabel_settings).solve()

    return {"osqp": run_osqp, "clarabel": run_clarabel}


def overhead_rows(scene: contactqp.Scene, repeats: int) -> list[dict]:
    rows = []
    direct = hand_built(scene)
    for backend in ("osqp", "clarabel"):
        ours = median_time(
            lambda backend=backend: contactqp.solve(scene, method="qp", backend=backend), repeats
        )
        theirs = median_time(direct[backend], repeats)
        rows.append({"scene": scene.name, "backend": backend, "contactqp_s": ours,
                     "direct_s": theirs, "ratio": ours / theirs, "goal": "<= 1.2"})
    return rows


def cvxpy_rows(scene: contactqp.Scene, repeats: int, solvers: tuple[str, ...]) -> list[dict]:
    module = qpmod.backend_module("cvxpy")
    model = contactqp.build_model(scene)
    rows = []
    for solver in solvers:
        def first(solver: str = solver) -> object:
            module.clear_cache()
            return qpmod.solve_qp(model, "inequality", backend="cvxpy", solver=solver)

        first_time = median_time(first, max(3, repeats // 10))
        first()
        loads = tuple(contactqp.Load(p.node, 1.1 * p.force) for p in scene.loads)
        walls = tuple(contactqp.Wall(w.node, 0.9 * w.gap, w.side) for w in scene.walls)
        changed = contactqp.build_model(scene.with_loads(loads).with_walls(walls))

        def again(changed: contactqp.Model = changed, solver: str = solver) -> object:
            solution = qpmod.solve_qp(changed, "inequality", backend="cvxpy", solver=solver)
            assert solution.info["cache"] == "hit"
            return solution

        again_time = median_time(again, repeats)
        # the part DPP saves: building + canonicalising (first) vs setting parameters (again)
        setup_first = first().info["time_setup"]
        setup_again = again().info["time_setup"]
        rows.append({"scene": scene.name, "solver": solver, "first_s": first_time,
                     "resolve_s": again_time, "speedup": first_time / again_time,
                     "setup_first_s": setup_first, "setup_resolve_s": setup_again,
                     "setup_speedup": setup_first / setup_again, "goal": ">= 10"})
    return rows


STARTUP = {  # what is timed, as a fresh process each time
    "floor: python -c 'import numpy, scipy.sparse'": [sys.executable, "-c",
                                                     "import numpy, scipy.sparse"],
    "python -c 'import contactqp'": [sys.executable, "-c", "import contactqp"],
    "python -m contactqp --help": [sys.executable, "-m", "contactqp", "--help"],
    "python -m contactqp --version": [sys.executable, "-m", "contactqp", "--version"],
}
STARTUP_GOAL = 1.5  # --help within 1.5x of importing numpy and scipy.sparse


def startup_rows(repeats: int) -> list[dict]:
    """Start-up: the median wall time of fresh processes, each as a ratio to the floor (a
    process that imports numpy and scipy.sparse), measured in the same run."""
    def run(command: list[str]) -> float:
        start = time.perf_counter()
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - start

    times = {name: sorted(run(command) for _ in range(repeats))[repeats // 2]
             for name, command in STARTUP.items()}
    base = next(iter(times.values()))
    return [{"command": name, "seconds": t, "ratio": t / base,
             "goal": f"<= {STARTUP_GOAL}" if "--help" in name else ""}
            for name, t in times.items()]


def overhead(quick: bool, out: Path) -> None:
    repeats, elements = (10, 10_000) if quick else (50, 10_000)
    startup = startup_rows(5 if quick else 15)
    print(f"{'start-up':40} {'ms':>7} {'/ floor':>8}")
    for r in startup:
        print(f"{r['command']:40} {1e3 * r['seconds']:7.0f} {r['ratio']:8.2f} {r['goal']}")
    print()
    scenes = [contactqp.default_scene(), tapered_scene(elements, "midpoint")]
    overhead = [row for scene in scenes for row in overhead_rows(scene, repeats)]
    resolves = [row for scene in scenes
                for row in cvxpy_rows(scene, repeats, ("CLARABEL", "OSQP"))]
    print(f"{'scene':42} {'backend':9} {'contactqp ms':>12} {'direct ms':>10} {'ratio':>6}")
    for r in overhead:
        print(f"{r['scene']:42} {r['backend']:9} {1e3 * r['contactqp_s']:12.3f} "
              f"{1e3 * r['direct_s']:10.3f} {r['ratio']:6.2f}")
    print(f"\n{'scene':42} {'cvxpy solver':12} {'first ms':>9} {'re-solve ms':>11} "
          f"{'speedup':>8} {'setup first ms':>14} {'setup again ms':>14} {'speedup':>8}")
    for r in resolves:
        print(f"{r['scene']:42} {r['solver']:12} {1e3 * r['first_s']:9.2f} "
              f"{1e3 * r['resolve_s']:11.2f} {r['speedup']:8.1f} "
              f"{1e3 * r['setup_first_s']:14.2f} {1e3 * r['setup_resolve_s']:14.2f} "
              f"{r['setup_speedup']:8.1f}")
    _write(out, "overhead.json", {"startup": startup, "overhead": overhead,
                                  "cvxpy_resolve": resolves})



GROUPS: dict[str, Callable[[bool, Path], None]] = {"taper": taper, "walls": walls,
                                                   "overhead": overhead}
