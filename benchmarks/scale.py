"""How the methods scale: the default scene's tapered bar with 10² … 10⁶ elements (exact areas),
one wall at the tip, full, strain and condensed formulations.

Times are medians over repeats, in seconds and as ratios to a floor measured in the same run:
one banded Cholesky factor-and-solve of K (LAPACK pbsv through scipy.linalg.solveh_banded).
``solve`` times are end to end on a loaded scene: model, method, Result and its check. The
force error is against the continuum closed form (exact areas make the two the same).

    python benchmarks/scale.py [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from functools import partial
from pathlib import Path

import numpy as np
import scipy.linalg as sla

import contactqp
from contactqp.model import build_model
from contactqp.studies import cone_contact_force
from timing import median_time  # benchmarks/ is on sys.path when a script runs

# (method, options, {formulation: largest size it is run at}); condensed runs at every size
RUNS = [
    ("lagrange", {}, {"full": 10**6, "strain": 10**5}),
    ("penalty", {}, {"full": 10**6}),
    ("augmented", {}, {"full": 10**6}),
    ("qp", {"backend": "clarabel"}, {"full": 10**4, "strain": 10**5}),
    ("qp", {"backend": "osqp"}, {"full": 10**4, "strain": 10**5}),
]
FORMULATIONS = ("full", "strain", "condensed")


def tapered_scene(elements: int) -> contactqp.Scene:
    """The default scene's bar, load and wall, with ``elements`` elements (load at mid-length)."""
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9, area_rule="exact")
    return contactqp.Scene(bar, (contactqp.Support(0),),
                           (contactqp.Load(elements // 2, 565486.67),),
                           (contactqp.Wall(elements, 1e-4, "+"),), name=f"taper-{elements}")




def floor(scene: contactqp.Scene, repeats: int) -> float:
    """One banded factor-and-solve of K (K already in band storage)."""
    model = build_model(scene)
    band = np.zeros((2, model.n_free))
    band[0] = model.K.diagonal()
    band[1, :-1] = model.K.diagonal(-1)
    return median_time(lambda: sla.solveh_banded(band, model.P, lower=True), repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="stop at 10⁵ elements, fewer repeats")
    parser.add_argument("--out", default="benchmarks/out", help="folder for the JSON")
    args = parser.parse_args()
    sizes = [10**2, 10**4, 10**5] if args.quick else [10**2, 10**4, 10**5, 10**6]
    repeats = 3 if args.quick else 7
    rows = []
    exact = cone_contact_force()
    print(f"{'elements':>9} {'run':>22} {'formulation':>11} {'time (s)':>9} {'/floor':>7} "
          f"{'force error':>11} {'verified':>8} {'iterations':>10}")
    for n in sizes:
        scene = tapered_scene(n)
        base = floor(scene, repeats)
        print(f"{n:>9} {'floor: pbsv on K':>22} {'':>11} {base:9.4f} {1.0:7.2f}")
        for method, options, limits in RUNS:
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
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    meta = {"machine": platform.machine(), "processor": platform.processor(),
            "python": platform.python_version(), "numpy": np.__version__,
            "date": time.strftime("%Y-%m-%d")}
    (out / "scale.json").write_text(json.dumps({"meta": meta, "runs": rows}, indent=2))
    print(f"wrote {out / 'scale.json'}")


if __name__ == "__main__":
    main()
