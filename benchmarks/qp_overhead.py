"""What contactqp's QP method costs on top of the solver it calls.

    python benchmarks/qp_overhead.py [--repeats 50] [--elements 10000]

1. ``solve(method="qp", backend=B)`` end to end (model, scaling, solve, Result and its check)
   against B called directly on matrices built by hand beforehand (setup + solve only), on
   the default scene and on a fine bar. Goal: ratio <= 1.2.
2. cvxpy: a re-solve of a cached problem with a new load and gap against the first solve
   (building the problem and canonicalising it). Goal: the re-solve >= 10x faster.

Prints a table and writes benchmarks/out/qp_overhead.json. Times are medians of wall time.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import clarabel
import numpy as np
import osqp
import scipy.sparse as sp

import contactqp
from contactqp.methods import qp as qpmod
from timing import median_time  # benchmarks/ is on sys.path when a script runs

OUT = Path(__file__).parent / "out"




def fine_scene(elements: int) -> contactqp.Scene:
    seed = contactqp.seed_scene()
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9)
    return contactqp.Scene(
        bar, (contactqp.Support(0),), (contactqp.Load(elements // 2, seed.loads[0].force),),
        (contactqp.Wall(elements, seed.walls[0].gap, "+"),), name=f"fine {elements}",
    )


def hand_built(scene: contactqp.Scene) -> dict[str, Callable[[], object]]:
    """The solvers called directly on the scaled QP data, built once outside the timing."""
    qp = contactqp.qp_problem(scene)
    P = sp.csc_matrix(qp.K_upper)
    A = sp.csc_matrix(qp.C)
    lower = np.full(qp.g.size, -np.inf)
    osqp_settings = qpmod.accuracy_settings("osqp", "default", scaled=True)
    clarabel_settings = clarabel.DefaultSettings()
    clarabel_settings.verbose = False
    for key, value in qpmod.accuracy_settings("clarabel", "default", scaled=True).items():
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
    module = qpmod.BACKENDS["cvxpy"]
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--elements", type=int, default=10_000)
    args = parser.parse_args()
    scenes = [contactqp.seed_scene(), fine_scene(args.elements)]
    overhead = [row for scene in scenes for row in overhead_rows(scene, args.repeats)]
    resolves = [row for scene in scenes
                for row in cvxpy_rows(scene, args.repeats, ("CLARABEL", "OSQP"))]
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
    OUT.mkdir(exist_ok=True)
    (OUT / "qp_overhead.json").write_text(
        json.dumps({"overhead": overhead, "cvxpy_resolve": resolves}, indent=1)
    )


if __name__ == "__main__":
    main()
