"""The Hertz cylinder (contactqp.fem, scikit-fem): the refinement study and the speed of every
method against one sparse factor-and-solve of K.

    python benchmarks/hertz.py study [--sizes 10,20,...] [--chart docs/hertz_refinement.png]
    python benchmarks/hertz.py speed [--fine 0.00125] [--methods ...] [--backends ...]

study: the cylinder of examples/hertz_cylinder.py (R = 10 mm, E = 210 GPa, ν = 0.3, δ = 10 µm)
at element sizes h = zone / n along the contact strip (zone = 0.5 mm), solved by Lagrange;
prints a Markdown table of dofs, rows, h/a and the errors of a and p₀ against Hertz, with the
observed order of each error between successive meshes, and draws both errors against h.

speed: at one mesh, the floor (SuperLU factor-and-solve of K on the free dofs, with COLAMD and
with the minimum-degree ordering MMD_AT_PLUS_A in symmetric mode, as contactqp's sparse model
factorises; the faster of the two is the floor), then each
method and QP backend end to end (model, method, check), its time as a multiple of the floor,
the check's share, and whether the answer was verified.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import contactqp
from contactqp.fem import CylinderModel, cylinder_on_flat, measure

ZONE = 0.5  # mm, the contact strip: 2.5 a at δ = 10 µm
SIZES = (10, 20, 40, 80, 160, 320, 640)
METHODS = ("lagrange", "penalty", "augmented", "lemke", "pgs", "semismooth_newton")
BACKENDS = ("clarabel", "osqp")


def study(sizes: tuple[int, ...]) -> list[dict]:
    """One row per mesh: its size and the errors of a and p₀ against Hertz."""
    rows = []
    for n in sizes:
        model = cylinder_on_flat(zone=ZONE, fine=ZONE / n)
        start = time.perf_counter()
        result = contactqp.solve(model.problem, "lagrange")
        elapsed = time.perf_counter() - start
        comparison = measure(model, result.contact_force)
        rows.append({"h": ZONE / n, "dofs": model.problem.n, "rows": model.problem.m,
                     "a": comparison.hertz_half_width, "a_error": comparison.half_width_error,
                     "p0_error": comparison.peak_pressure_error, "seconds": elapsed,
                     "verified": result.verified})
    return rows


def order(errors: list[float], sizes: list[float], i: int) -> str:
    """The observed order log(e_{i-1}/e_i) / log(h_{i-1}/h_i), or '' for the first mesh."""
    if i == 0 or errors[i] == 0.0 or errors[i - 1] == 0.0:
        return ""
    return f"{np.log(abs(errors[i - 1] / errors[i])) / np.log(sizes[i - 1] / sizes[i]):.2f}"


def study_table(rows: list[dict]) -> str:
    """The refinement study as a Markdown table."""
    h = [row["h"] for row in rows]
    a_err = [row["a_error"] for row in rows]
    p_err = [row["p0_error"] for row in rows]
    header = ("| h (mm) | h/a | dofs | rows | a error | order | p₀ error | order | lagrange (s) "
              "| verified |")
    lines = [header, "|---|---|---|---|---|---|---|---|---|---|"]
    for i, row in enumerate(rows):
        lines.append(f"| {row['h']:.4g} | {row['h'] / row['a']:.3f} | {row['dofs']} | "
                     f"{row['rows']} | {row['a_error']:+.2%} | {order(a_err, h, i)} | "
                     f"{row['p0_error']:+.2%} | {order(p_err, h, i)} | {row['seconds']:.2f} | "
                     f"{row['verified']} |")
    return "\n".join(lines)


def study_chart(rows: list[dict], path: str) -> None:
    """|error| of a and p₀ against h/a, log-log, with a slope-1 guide."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.4, 4.0), layout="constrained")
    ax = figure.add_subplot()
    ratio = np.array([row["h"] / row["a"] for row in rows])
    for key, label in (("a_error", "half-width a"), ("p0_error", "peak pressure p₀")):
        ax.loglog(ratio, [abs(row[key]) for row in rows], "o-", label=label)
    for x, row in zip(ratio, rows):
        ax.annotate(f"{row['dofs']:,}", (x, abs(row["p0_error"])), textcoords="offset points",
                    xytext=(0, 6), ha="center", fontsize=7)
    guide = abs(rows[0]["p0_error"]) * ratio / ratio[0]
    ax.loglog(ratio, guide, ":", color="0.5", label="∝ h")
    ax.axhline(0.005, color="0.7", lw=0.8)
    ax.set_xlabel("h / a (element size along the contact over Hertz's half-width)")
    ax.set_ylabel("|relative error| against Hertz")
    ax.set_title("cylinder on a flat: refinement study (P1, plane strain; labels: dofs)")
    ax.legend()
    figure.savefig(path, dpi=110)


def floor(problem: contactqp.Problem, ordering: str) -> float:
    """One SuperLU factor-and-solve of K on the free dofs (seconds): COLAMD with scipy's
    defaults, or a minimum-degree ordering in symmetric mode (diagonal pivots), as
    contactqp's sparse model factorises. (Minimum degree with scipy's default threshold
    pivoting took 437 s at 88 198 dofs, 100x COLAMD: it is not a floor anyone would use.)"""
    free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
    K = sp.csc_matrix(problem.K[free][:, free])
    start = time.perf_counter()
    if ordering == "COLAMD":
        spla.splu(K).solve(np.ones(free.size))
    else:
        spla.splu(K, permc_spec=ordering, diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True}).solve(np.ones(free.size))
    return time.perf_counter() - start


def timed(problem: contactqp.Problem, method: str, **options) -> tuple[float, object]:
    """Seconds end to end and the Result (or the error's text)."""
    start = time.perf_counter()
    try:
        result = contactqp.solve(problem, method, **options)
    except contactqp.ContactqpError as error:
        return time.perf_counter() - start, str(error)
    return time.perf_counter() - start, result


def speed(fine: float, methods: tuple[str, ...], backends: tuple[str, ...]) -> None:
    """Print the floor and each method's time as a multiple of it (module docstring)."""
    model = cylinder_on_flat(zone=ZONE, fine=fine)
    problem = model.problem
    print(f"{problem.n} dofs, {problem.m} contact rows, h = {fine:g} mm")
    mmd = floor(problem, "MMD_AT_PLUS_A")
    colamd = floor(problem, "COLAMD")
    base = min(mmd, colamd)
    print(f"floor: SuperLU factor-and-solve {mmd:.3f} s (MMD_AT_PLUS_A, symmetric mode), "
          f"{colamd:.3f} s (COLAMD); ratios below are to the faster, {base:.3f} s")
    runs = [(m, {}) for m in methods] + [("qp", {"backend": b}) for b in backends]
    for method, options in runs:
        label = method + (f" ({options['backend']})" if options else "")
        seconds, result = timed(problem, method, **options)
        if isinstance(result, str):
            print(f"  {label:22s} refused/failed in {seconds:.2f} s: {result}")
            continue
        check = result.timings.get("check", float("nan"))
        print(f"  {label:22s} {seconds:8.2f} s = {seconds / base:6.2f} x floor; check "
              f"{check:.3f} s = {check / base:.2f} x; verified {result.verified}; "
              f"{hertz_errors(model, result)}")


def hertz_errors(model: CylinderModel, result) -> str:
    """The errors of a and p₀ against Hertz (forces within the check's bound of zero read as
    zero), or why they cannot be read."""
    bound = result.force_error_bound
    try:
        comparison = measure(model, result.contact_force, bound if np.isfinite(bound) else 0.0)
    except ValueError as error:
        return str(error)
    return f"a {comparison.half_width_error:+.2%}, p0 {comparison.peak_pressure_error:+.2%}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("study", "speed"))
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)),
                        help="study: n of h = zone / n, comma-separated")
    parser.add_argument("--chart", default="", help="study: save the chart here (PNG)")
    parser.add_argument("--fine", type=float, default=ZONE / 400, help="speed: h (mm)")
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--backends", default=",".join(BACKENDS))
    args = parser.parse_args()
    if args.what == "study":
        rows = study(tuple(int(n) for n in args.sizes.split(",")))
        print(study_table(rows))
        if args.chart:
            study_chart(rows, args.chart)
    else:
        speed(args.fine, tuple(filter(None, args.methods.split(","))),
              tuple(filter(None, args.backends.split(","))))


if __name__ == "__main__":
    main()
