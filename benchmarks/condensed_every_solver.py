"""Issue 4's goal, every method and every installed QP backend/solver: the condensed formulation
on the 10⁶-element tapered bar (one wall), end to end, as a ratio to one banded factor-and-solve
of K measured in the same run, and the contact-force error against the continuum.

    python benchmarks/condensed_every_solver.py [--elements 1000000] [--repeats 5]
"""

from __future__ import annotations

import argparse
from functools import partial

import contactqp
from contactqp.studies import cone_contact_force
from scale import floor, tapered_scene  # benchmarks/ is on sys.path when a script runs
from timing import median_time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=10**6)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    scene, exact = tapered_scene(args.elements), cone_contact_force()
    base = floor(scene, args.repeats)
    runs = [(m, {}) for m in ("lagrange", "augmented", "penalty")]
    runs += [("penalty", {"penalty": 1e18})]
    runs += [("qp", {"backend": r.backend, "solver": r.solver, "accuracy": a})
             for r in contactqp.available_qp_solvers() if r.available for a in ("default", "high")]
    print(f"floor (pbsv on K): {base * 1e3:.1f} ms")
    print(f"{'run':45} {'/floor':>7} {'force error':>11} {'verified':>8}")
    for method, options in runs:
        run = partial(contactqp.solve, scene, method, formulation="condensed", **options)
        result = run()
        ratio = median_time(run, args.repeats) / base
        error = abs(float(result.contact_force[0]) - exact) / exact
        label = "/".join([method, *(str(v) for v in options.values())])
        print(f"{label:45} {ratio:7.2f} {error:11.1e} {result.verified!s:>8}")


if __name__ == "__main__":
    main()
