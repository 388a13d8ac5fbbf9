"""Survey every installed QP backend/solver: scaled or SI, default or high accuracy, on the
default scene and on a fine bar. Each case runs in its own process with a time limit.

    python benchmarks/qp_survey.py [--elements 10000] [--timeout 120] [--jobs 2]

Prints a table and writes benchmarks/out/qp_survey.json. A case is "right" when its contact
forces are within 1e-6 (relative) of the explicit Lagrange method's.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

import contactqp
from contactqp.methods import qp as qpmod

OUT = Path(__file__).parent / "out"
SCALINGS = ("structure", "diagonal", "none")


def fine_scene(elements: int) -> contactqp.Scene:
    """The default scene with ``elements`` equal elements: load at mid-length, wall at the tip."""
    seed = contactqp.seed_scene()
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9)
    load = contactqp.Load(elements // 2, seed.loads[0].force)
    wall = contactqp.Wall(elements, seed.walls[0].gap, "+")
    return contactqp.Scene(bar, (contactqp.Support(0),), (load,), (wall,), name=f"fine {elements}")


def diagonal_scales(model: contactqp.Model) -> tuple[float, float]:
    """The rejected alternative: k = largest diagonal of K, U = max(gap, |K⁻¹P|)."""
    from contactqp import linalg
    u0 = linalg.solve(model.K, model.P, spd=True)
    U = max(float(np.abs(model.g).max(initial=0.0)), float(np.abs(u0).max()))
    return U, float(model.K.diagonal().max()) * U


def one_case(scene_name: str, elements: int, backend: str, solver: str, scaling: str,
             accuracy: str) -> dict:
    scene = contactqp.seed_scene() if scene_name == "seed" else fine_scene(elements)
    reference = contactqp.solve(scene, method="lagrange")
    if scaling == "diagonal":
        qpmod.scales = diagonal_scales
    result = contactqp.solve(scene, method="qp", backend=backend, solver=solver,
                             accuracy=accuracy, scale=scaling != "none")
    force_error = float(np.max(np.abs(result.contact_force - reference.contact_force))
                        / np.max(np.abs(reference.contact_force)))
    return {"scene": scene_name, "backend": backend, "solver": solver, "scaling": scaling,
            "accuracy": accuracy, "status": result.status, "claimed": result.claimed_success,
            "verified": result.verified, "force_error": force_error,
            "right": bool(force_error < 1e-6), "time": result.time,
            "iterations": result.iterations, "message": result.message}


def run(case: tuple, timeout: float) -> dict:
    command = [sys.executable, __file__, "--case", json.dumps(case)]
    keys = ("scene", "elements", "backend", "solver", "scaling", "accuracy")
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                              check=False)
    except subprocess.TimeoutExpired:
        return {**dict(zip(keys, case)), "status": f"timeout {timeout:g} s", "claimed": None,
                "verified": False, "force_error": float("nan"), "right": False,
                "time": timeout, "iterations": 0, "message": ""}
    lines = done.stdout.strip().splitlines()
    if done.returncode or not lines:
        return {**dict(zip(keys, case)), "status": f"crashed: {done.stderr[-300:]}",
                "claimed": None, "verified": False, "force_error": float("nan"),
                "right": False, "time": float("nan"), "iterations": 0, "message": ""}
    return json.loads(lines[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--elements", type=int, default=10_000)
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--scenes", default="seed,fine")
    parser.add_argument("--scalings", default=",".join(SCALINGS))
    parser.add_argument("--case", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        print(json.dumps(one_case(*json.loads(args.case))))
        return
    pairs = [(r.backend, r.solver) for r in contactqp.available_qp_solvers() if r.available]
    cases = [(scene, args.elements, b, s, scaling, accuracy)
             for scene in args.scenes.split(",") for b, s in pairs
             for scaling in args.scalings.split(",") for accuracy in ("default", "high")]
    print(f"{'scene':6} {'backend/solver':22} {'scaling':9} {'accuracy':8} {'claimed':7} "
          f"{'verified':8} {'force err':>9} {'time s':>7}  status", flush=True)
    with ThreadPoolExecutor(args.jobs) as pool:
        rows = []
        for r in pool.map(lambda case: run(case, args.timeout), cases):
            rows.append(r)
            print(f"{r['scene']:6} {r['backend'] + '/' + r['solver']:22} {r['scaling']:9} "
                  f"{r['accuracy']:8} {r['claimed']!s:7} {r['verified']!s:8} "
                  f"{r['force_error']:9.1e} {r['time']:7.2f}  {r['status'][:60]}", flush=True)
    OUT.mkdir(exist_ok=True)
    (OUT / f"qp_survey_{args.scenes.replace(',', '_')}.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
