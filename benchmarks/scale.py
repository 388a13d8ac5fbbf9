"""How the explicit methods scale: a tapered bar of 10² … 10⁶ elements, one wall at the tip.

Times are medians over repeats, in seconds and as ratios to a floor measured in the same run:
one banded Cholesky factor-and-solve of K (LAPACK pbsv through scipy.linalg.solveh_banded).
``solve`` times include building the scene's model and the independent check.

    python benchmarks/scale.py [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

import contactqp
from contactqp.model import build_model


def tapered_scene(elements: int) -> contactqp.Scene:
    """The default scene's bar, load and wall, with ``elements`` elements (load at mid-length)."""
    bar = contactqp.Bar.tapered_circle(1.0, elements, 0.040, 0.020, 210e9, area_rule="exact")
    return contactqp.Scene(bar, (contactqp.Support(0),),
                           (contactqp.Load(elements // 2, 565486.67),),
                           (contactqp.Wall(elements, 1e-4, "+"),), name=f"taper-{elements}")


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


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
    print(f"{'elements':>9} {'method':>9} {'contact':>10} {'time (s)':>10} {'/floor':>8} {'verified':>8}")
    for n in sizes:
        scene = tapered_scene(n)
        base = floor(scene, repeats)
        print(f"{n:>9} {'floor':>9} {'':>10} {base:10.4f} {1.0:8.1f}")
        for method in ("lagrange", "penalty"):
            for contact in contactqp.CONTACT_KINDS:
                result = contactqp.solve(scene, method, contact)
                seconds = median_time(lambda: contactqp.solve(scene, method, contact), repeats)
                rows.append({"elements": n, "method": method, "contact": contact,
                             "seconds": seconds, "floor_seconds": base, "ratio": seconds / base,
                             "verified": result.verified,
                             "contact_force": float(result.contact_force[0])})
                print(f"{n:>9} {method:>9} {contact:>10} {seconds:10.4f} {seconds / base:8.1f} "
                      f"{str(result.verified):>8}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    meta = {"machine": platform.machine(), "processor": platform.processor(),
            "python": platform.python_version(), "numpy": np.__version__,
            "date": time.strftime("%Y-%m-%d")}
    (out / "scale.json").write_text(json.dumps({"meta": meta, "runs": rows}, indent=2))
    print(f"wrote {out / 'scale.json'}")


if __name__ == "__main__":
    main()
