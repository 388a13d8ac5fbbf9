"""Scaling in the number of contacts: the default scene's tapered bar with a wall beside every
node (the discrete obstacle problem), 10² … 10⁵ contacts, every method.

The gaps g(x) = 0.2 mm·(x/L)² + 10 µm·|sin(37 x/L)| make contact patches that depend on the
mesh, not one degenerate flat patch. Times are medians, in seconds and as ratios to one banded
factor-and-solve of K in the same run, end to end (model, method, Result, check). The force
error is the largest contact-force difference against Lagrange (exact active set), relative
to its largest contact force. A method whose time at one size passes BUDGET is not run at the
next sizes (recorded with the reason).

    python benchmarks/many_walls.py [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from functools import partial
from pathlib import Path

import numpy as np

import contactqp
from contactqp.model import CONDENSE_LIMIT
from scale import floor, tapered_scene  # benchmarks/ is on sys.path when a script runs
from timing import median_time

RUNS = [
    ("lagrange", {}),
    ("penalty", {}),
    ("augmented", {}),
    ("qp", {"backend": "clarabel"}),
    ("qp", {"backend": "osqp"}),
    ("qp", {"backend": "cvxpy"}),
]
BUDGET = 60.0  # s for one solve; beyond it the method is not run at larger sizes


def obstacle(elements: int) -> contactqp.Scene:
    x = np.linspace(0.0, 1.0, elements + 1)
    gaps = 2e-4 * x**2 + 1e-5 * np.abs(np.sin(37.0 * x))
    return contactqp.wall_at_every_node(tapered_scene(elements).with_walls(()), gaps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10² and 10³ contacts only")
    parser.add_argument("--out", default="benchmarks/out", help="folder for many_walls.json")
    args = parser.parse_args()
    sizes = [10**2, 10**3] if args.quick else [10**2, 10**3, 10**4, 10**5]
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
        for method, options in RUNS:
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
    print(f"condensed formulation: refused above {CONDENSE_LIMIT} contact nodes "
          "(a dense flexibility), so every run here is 'full'")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "many_walls.json").write_text(json.dumps(
        {"machine": platform.platform(), "processor": platform.processor(),
         "date": time.strftime("%Y-%m-%d"), "runs": rows}, indent=2))
    print(f"written: {out / 'many_walls.json'}")


if __name__ == "__main__":
    main()
