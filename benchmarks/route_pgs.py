"""PGS at 10⁴ rows in contact: what forming W and sweeping cost past pgs's own limits (issue
39; the measurement on docs/benchmarks.md, "PGS at 10⁴ rows").

    python benchmarks/route_pgs.py [--approach 0.04] [--cache DIR]

Takes the 2D rows sweep's cylinder of benchmarks/scale.py (330 752 dofs, 10 272 rows; at the
default δ = 40 µm every row of the zone is in contact) and runs ``contactqp.solve(problem,
"pgs", max_rows=rows)``: the option lifts the limits pgs keeps so that a run ends in about a
minute (LCP_ROWS, the rows it forms W for, and PGS_WORK, its sweeps x rows²), to PGS's own
tolerance or its 10 000 sweeps. Prints the time W took (a solve per row, through the model's
factor), the sweeps, the whole time, the check's verdict, and the largest difference from
lagrange's contact forces over their largest. Needs about 3 GB beside the model.
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

import contactqp
from contactqp.methods import complementarity
from scale import ROWS2D, Case, problem_of


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--approach", type=float, default=0.04, help="δ (mm)")
    parser.add_argument("--cache", type=Path, default=Path("benchmarks/out/scale/problems"),
                        help="where scale.py keeps its meshes (its default OUT/problems)")
    args = parser.parse_args()
    problem = problem_of(Case("rows2d", ROWS2D, args.approach, "full"), args.cache)
    rows = problem.C.shape[0]
    print(f"{problem.n} dofs, {rows} rows", flush=True)

    exact = contactqp.solve(problem, "lagrange")
    print(f"lagrange: {exact.time:.1f} s, {int(np.sum(exact.contact_force > 0))} rows in "
          f"contact, verified {exact.verified}", flush=True)

    seconds = {}
    form = complementarity.contact_lcp

    def timed_lcp(model, max_rows=None):
        start = time.perf_counter()
        found = form(model, max_rows)
        seconds["W"] = time.perf_counter() - start
        return found

    complementarity.contact_lcp = timed_lcp  # the time W takes, apart from the sweeps
    result = contactqp.solve(problem, "pgs", max_rows=rows)
    force = exact.contact_force
    difference = np.abs(result.contact_force - force).max() / np.abs(force).max()
    print(f"pgs: {result.time:.1f} s in all, W {seconds['W']:.1f} s, {result.iterations} "
          f"sweeps ({result.status}), natural map {result.info['natural_map']:.1e}, "
          f"verified {result.verified}, force error bound {result.force_error_bound:.1e}, "
          f"differs from lagrange by {difference:.1e} of its largest force; the check "
          f"{result.timings['check']:.1f} s; peak memory "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.1f} GB", flush=True)


if __name__ == "__main__":
    main()
