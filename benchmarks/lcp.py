"""The complementarity methods on the contact LCP: how their iterations grow with the mesh and
with the stiffness contrast (issue: PGS stalls where W is far from diagonally dominant, which
a condensed elastic bar is).

    mesh       a flat patch (a uniform load pressing the default bar onto a wall 10 µm from
               every node, 95 % in contact), 8 to 512 walls (quick: to 64)
    contrast   32 elements with walls at every node, every other element c times stiffer,
               c = 1, 1e2, 1e4, 1e6 (quick: 1 and 1e4)

Per run: iterations (pivots, sweeps or Newton steps), the end-to-end time of contactqp.solve
as a ratio to the floor (one banded factor-and-solve of K, same run), the force error against
Lagrange multipliers (exact to round-off, verified in every case here) relative to the largest
force, and whether the check verified the answer. Writes lcp.json and lcp.md.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

import contactqp
from cases import flat_patch, floor, machine, median_time

RUNS = [("lemke", {}), ("pgs", {}), ("pgs", {"relaxation": 1.5}), ("semismooth_newton", {}),
        ("semismooth_newton", {"ncp": "fischer-burmeister"}), ("lagrange", {})]


def contrast_scene(contrast: float, elements: int = 32) -> contactqp.Scene:
    """The flat patch of ``elements`` walls with every other element ``contrast`` times
    stiffer (its area times ``contrast``)."""
    scene = flat_patch(elements)
    bar = scene.bars[0]
    areas = bar.areas * np.where(np.arange(bar.n_elements) % 2 == 1, contrast, 1.0)
    stiffer = contactqp.Bar(bar.lengths, areas, bar.youngs_modulus, bar.yield_stress)
    return contactqp.Scene((stiffer,), scene.supports, scene.loads, scene.walls,
                           name=f"patch, contrast {contrast:g}", distributed=scene.distributed)


def label(method: str, options: dict) -> str:
    return "/".join([method, *map(str, options.values())])


def measure(scene: contactqp.Scene, case: dict, repeats: int) -> list[dict]:
    exact = contactqp.solve(scene, "lagrange")
    base = floor(scene, repeats)
    largest = max(float(np.abs(exact.contact_force).max()), exact.force_scale)
    rows = []
    for method, options in RUNS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = contactqp.solve(scene, method, **options)
            seconds = median_time(lambda m=method, o=options: contactqp.solve(scene, m, **o),
                                  repeats if result.time < 0.5 else 1)
        rows.append({**case, "run": label(method, options), "iterations": result.iterations,
                     "floors": seconds / base, "seconds": seconds,
                     "force_error": float(np.abs(result.contact_force
                                                 - exact.contact_force).max()) / largest,
                     "verified": result.verified, "status": result.status})
    return rows


def main(quick: bool, out: Path) -> None:
    sizes = (8, 16, 32, 64) if quick else (8, 16, 32, 64, 128, 256, 512)
    contrasts = (1.0, 1e4) if quick else (1.0, 1e2, 1e4, 1e6)
    repeats = 3 if quick else 5
    rows = []
    for n in sizes:
        rows += measure(flat_patch(n), {"study": "mesh", "walls": n}, repeats)
    for c in contrasts:
        rows += measure(contrast_scene(c), {"study": "contrast", "contrast": c}, repeats)
    runs = [label(m, o) for m, o in RUNS]
    lines = []
    for study, key, name in (("mesh", "walls", "walls"), ("contrast", "contrast", "contrast")):
        lines += [f"| {name} | " + " | ".join(runs) + " |", "|---" * (len(runs) + 1) + "|"]
        for value in dict.fromkeys(r[key] for r in rows if r["study"] == study):
            cells = []
            for run in runs:
                r = next(r for r in rows if r["study"] == study and r[key] == value
                         and r["run"] == run)
                cells.append(f"{r['iterations']} it, {r['floors']:.0f}×, {r['force_error']:.0e}"
                             + ("" if r["verified"] else ", flagged"))
            lines.append(f"| {value:g} | " + " | ".join(cells) + " |")
        lines.append("")
    table = "\n".join(lines)
    print(table)
    out.mkdir(parents=True, exist_ok=True)
    (out / "lcp.md").write_text(table + "\n")
    (out / "lcp.json").write_text(json.dumps({"machine": machine(), "rows": rows}, indent=1))
