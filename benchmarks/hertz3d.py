"""The Hertz sphere (contactqp.fem.sphere_on_flat, scikit-fem): the refinement study of
docs/hertz.md ("Hertz in 3D").

    python benchmarks/hertz3d.py [--levels 1,2,3,4] [--save DIR] [--table-only]
    python benchmarks/hertz3d.py --meshes 0.025:0.25,0.025:0.35 [--save DIR] [--table-only]

The sphere of R = 10 mm (E = 210 GPa, ν = 0.3) pushed down by δ = 10 µm (a ≈ 0.32 mm =
0.032 R), rows over the disk of radius zone = 0.5 mm, on the meshes of level k: every
allowed element size fine + growth · d scaled by 2^(−k/2), fine = 0.1 · 2^(−k/2) mm and
growth = 0.6 · 2^(−k/2) (the whole graded mesh refined by √2 in size per level, about 2.8
times the nodes), solved by Lagrange. Prints one line per mesh as it is solved, then a
Markdown table of dofs, rows, rows in contact, the errors of a and p₀ (and of the lowest
row's pressure) against Hertz with the observed order between successive meshes, the times,
and whether the answer was verified. With --save, each mesh's contact forces and rows go to
DIR/level<k>.npz, which --table-only reads back instead of solving. --meshes gives the meshes
as fine:growth pairs instead of levels (DIR/fine<fine>_growth<growth>.npz): at one fine and
several growths, it shows what the grading alone does to a and p₀.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np

import contactqp
from contactqp.fem import SphereModel, measure_sphere, sphere_load, sphere_on_flat

R, E, NU, APPROACH, ZONE = 10.0, 210e3, 0.3, 0.01, 0.5  # mm, MPa, -, mm, mm
FINE, GROWTH = 0.1, 0.6  # level 0; each level divides both by √2


def level_sizes(k: int) -> tuple[float, float]:
    """(fine, growth) of level k."""
    scale = 2.0 ** (-k / 2)
    return FINE * scale, GROWTH * scale


def solve_mesh(name: str, fine: float, growth: float, save: pathlib.Path | None) -> dict:
    """Build, solve and measure one mesh; one row of the table."""
    start = time.perf_counter()
    model = sphere_on_flat(R, E, NU, approach=APPROACH, zone=ZONE, fine=fine, growth=growth)
    built = time.perf_counter() - start
    start = time.perf_counter()
    result = contactqp.solve(model.problem, "lagrange")
    solved = time.perf_counter() - start
    timings = [result.timings.get(key, np.nan) for key in ("build", "solve", "check")]
    if save is not None:
        save.mkdir(parents=True, exist_ok=True)
        np.savez(save / f"{name}.npz", force=result.contact_force, x=model.x, y=model.y,
                 r=model.r, tributary=model.tributary, zone_edge=model.zone_edge,
                 dofs=model.problem.n, built=built, solved=solved, verified=result.verified,
                 timings=np.array(timings))
    return row(fine, growth, model, result.contact_force, model.problem.n, built, solved,
               result.verified, timings)


def row(fine: float, growth: float, model: SphereModel, force: np.ndarray, dofs: int,
        built: float, solved: float, verified: bool, timings: list[float]) -> dict:
    comparison = measure_sphere(model, force)
    return {"h": fine, "growth": growth, "a": comparison.hertz_contact_radius,
            "dofs": dofs, "rows": force.size, "contact": int(np.count_nonzero(force > 0)),
            "a_error": comparison.contact_radius_error,
            "p0_error": comparison.peak_pressure_error,
            "centre_error": comparison.centre_pressure_error,
            "load_error": comparison.load / sphere_load(APPROACH, R, E, NU) - 1.0,
            "built": built, "solved": solved, "verified": verified, "timings": timings}


class Saved:
    """A SphereModel's rows read back from a saved mesh (what measure reads)."""

    def __init__(self, data) -> None:
        self.x, self.y, self.r = data["x"], data["y"], data["r"]
        self.tributary, self.zone_edge = data["tributary"], data["zone_edge"]
        self.radius, self.young, self.poisson = R, E, NU


def read_mesh(name: str, fine: float, growth: float, save: pathlib.Path) -> dict:
    data = np.load(save / f"{name}.npz")
    return row(fine, growth, Saved(data), data["force"], int(data["dofs"]), float(data["built"]),
               float(data["solved"]), bool(data["verified"]), list(data["timings"]))


def order(errors: list[float], sizes: list[float], i: int) -> str:
    """The observed order log(e_{i-1}/e_i) / log(h_{i-1}/h_i), or '' for the first mesh and
    where h did not change."""
    if i == 0 or errors[i] == 0.0 or errors[i - 1] == 0.0 or sizes[i] == sizes[i - 1]:
        return ""
    return f"{np.log(abs(errors[i - 1] / errors[i])) / np.log(sizes[i - 1] / sizes[i]):.2f}"


def table(rows: list[dict]) -> str:
    h = [r["h"] for r in rows]
    a_err, p_err = [r["a_error"] for r in rows], [r["p0_error"] for r in rows]
    header = ("| h (mm) | h/a | growth | dofs | rows | in contact | a error | order | p₀ error "
              "| order | lowest row's p | P vs Hertz(δ) | mesh (s) | lagrange (s) | verified |")
    lines = [header, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(rows):
        lines.append(
            f"| {r['h']:.4g} | {r['h'] / r['a']:.3f} | {r['growth']:.3g} | {r['dofs']} | "
            f"{r['rows']} | {r['contact']} | {r['a_error']:+.2%} | {order(a_err, h, i)} | "
            f"{r['p0_error']:+.2%} | {order(p_err, h, i)} | {r['centre_error']:+.2%} | "
            f"{r['load_error']:+.2%} | {r['built']:.1f} | {r['solved']:.1f} | "
            f"{r['verified']} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--levels", default="1,2,3,4", help="levels k, comma-separated")
    parser.add_argument("--meshes", default="", help="fine:growth pairs, comma-separated")
    parser.add_argument("--save", default="", help="keep each mesh's forces in this folder")
    parser.add_argument("--table-only", action="store_true", help="read the saved meshes")
    args = parser.parse_args()
    save = pathlib.Path(args.save) if args.save else None
    if args.meshes:
        meshes = [(f"fine{fine}_growth{growth}", float(fine), float(growth))
                  for fine, growth in (pair.split(":") for pair in args.meshes.split(","))]
    else:
        meshes = [(f"level{k}", *level_sizes(k)) for k in map(int, args.levels.split(","))]
    rows = []
    for name, fine, growth in meshes:
        r = (read_mesh(name, fine, growth, save) if args.table_only
             else solve_mesh(name, fine, growth, save))
        rows.append(r)
        build, solve, check = r["timings"]
        print(f"{name}: {r['dofs']} dofs, {r['rows']} rows ({r['contact']} in contact), "
              f"a {r['a_error']:+.3%}, p0 {r['p0_error']:+.3%} (lowest row "
              f"{r['centre_error']:+.3%}), mesh {r['built']:.1f} s, lagrange {r['solved']:.1f} s "
              f"(model {build:.1f}, method {solve:.1f}, check {check:.1f}), verified "
              f"{r['verified']}", flush=True)
    print(table(rows))


if __name__ == "__main__":
    main()
