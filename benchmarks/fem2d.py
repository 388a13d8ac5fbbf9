"""The 2D cases (scikit-fem, contactqp.fem) by every method and every installed QP solver:
time against one sparse factor-and-solve of K, and the force error against Lagrange.

    python benchmarks/run.py --cases fem [--quick] [--out DIR]

Cases: the Hertz cylinder (examples/hertz_cylinder.py: R = 10 mm, E = 210 GPa, ν = 0.3,
δ = 10 µm, contact strip 0.5 mm) at a coarse mesh (h = 0.05 mm along the strip: 7 646 dofs,
17 rows) and a medium one (h = 0.0125 mm: 19 214 dofs, 66 rows), and the block on a wavy
foundation (contactqp.fem.block_on_wavy_foundation: 1 722 dofs, 41 rows). ``--quick``: the
coarse cylinder and the block.

Runs: lagrange, penalty, augmented, lemke, pgs, semismooth_newton (min and Fischer–Burmeister)
and the QP method by every installed backend and solver (contactqp.available_qp_solvers():
Clarabel and OSQP direct, cvxpy with each solver, every qpsolvers solver), each at its default
settings. Each run goes to a forked child stopped after TIMEOUT s; a dense-matrix solver past
contactqp's DENSE_LIMIT unknowns, and a run whose time extrapolated from the previous case
(time ~ dofs^GROWTH) passes BUDGET, are skipped with the reason printed.

Per run: the wall time end to end (model, method, check; the median of a few repeats after a
first call when that call is fast), as a ratio to the floor: one SuperLU factor-and-solve of K
on the free dofs measured in the same run (the faster of COLAMD and minimum degree in
symmetric mode, benchmarks/hertz.py), and the check's share; the largest contact-force error
against Lagrange's verified answer, over the problem's force scale F; and the outcome as in
benchmarks/matrix.py (verified, flagged, claimed success but wrong, verified but wrong: right
means within 1e-5·F). Writes runs.json, table.md and speed_accuracy.png to DIR/fem.
"""

from __future__ import annotations

import json
import statistics
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import contactqp
from cases import in_child, machine
from contactqp.errors import OptionError, SolverError
from contactqp.methods import qp as qpmod
from hertz import ZONE
from hertz import floor as splu_floor
from matrix import WRONG, outcome

TIMEOUT = {False: 45.0, True: 10.0}  # s per run (full, --quick)
BUDGET = {False: 40.0, True: 5.0}  # s: an extrapolated time past this is skipped
GROWTH = 1.5  # time ~ dofs^GROWTH from one case to the next larger
ERROR_FLOOR = 1e-17  # a force error of exactly 0 is drawn here


@dataclass(frozen=True)
class Case:
    name: str
    build: Callable[[], contactqp.Problem]
    quick: bool


def cylinder(fine: float) -> contactqp.Problem:
    """The Hertz cylinder with element size ``fine`` (mm) along the contact strip."""
    from contactqp.fem import cylinder_on_flat

    return cylinder_on_flat(zone=ZONE, fine=fine).problem


def block() -> contactqp.Problem:
    from contactqp.fem import block_on_wavy_foundation

    return block_on_wavy_foundation()


CASES = (Case("block", block, True),  # smallest first: each case extrapolates the previous
         Case("cylinder coarse", lambda: cylinder(0.05), True),
         Case("cylinder medium", lambda: cylinder(0.0125), False))


@dataclass(frozen=True)
class Run:
    label: str
    method: str
    options: tuple[tuple[str, Any], ...] = ()
    dense: bool = False  # a solver that takes K dense


def runs() -> list[Run]:
    """Every method and every installed QP backend and solver, at default settings."""
    found = [Run(m, m) for m in ("lagrange", "penalty", "augmented", "lemke", "pgs",
                                 "semismooth_newton")]
    found.append(Run("semismooth_newton (FB)", "semismooth_newton",
                     (("ncp", "fischer-burmeister"),)))
    for info in qpmod.available_qp_solvers():
        if not info.available:
            print(f"skipped: qp {info.backend}/{info.solver} is not installed ({info.install})")
            continue
        label = (f"qp {info.backend}" if info.backend == info.solver
                 else f"qp {info.backend}/{info.solver}")
        found.append(Run(label, "qp", (("backend", info.backend), ("solver", info.solver)),
                         dense=(info.backend, info.solver) in qpmod.DENSE_SOLVERS))
    return found


def floor(problem: contactqp.Problem, repeats: int = 3) -> float:
    """One SuperLU factor-and-solve of K (seconds): the median of ``repeats`` with each
    ordering, the faster ordering (benchmarks/hertz.py)."""
    return min(statistics.median(splu_floor(problem, ordering) for _ in range(repeats))
               for ordering in ("COLAMD", "MMD_AT_PLUS_A"))


def timed(problem: contactqp.Problem, run: Run, quick: bool
          ) -> tuple[contactqp.ProblemResult, float]:
    """The Result and the median time end to end (a first call, then repeats if fast)."""
    def call() -> contactqp.ProblemResult:
        return contactqp.solve(problem, run.method, **dict(run.options))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solvers' own warnings: the check decides
        start = time.perf_counter()
        result = call()
        times = [time.perf_counter() - start]
        repeats = (0 if times[0] > 1.0 else 1 if quick or times[0] > 0.3 else 3)
        for _ in range(repeats):
            start = time.perf_counter()
            result = call()
            times.append(time.perf_counter() - start)
    return result, statistics.median(times[1:] or times)


def measure(problem: contactqp.Problem, run: Run, exact: np.ndarray, base: float,
            quick: bool) -> dict[str, Any]:
    """One run's row: time, error, outcome (a refusal is a skip, a SolverError flagged)."""
    try:
        result, seconds = timed(problem, run, quick)
    except OptionError as error:
        return {"outcome": "skipped", "why": f"refused: {error}"}
    except SolverError as error:
        return {"outcome": "flagged", "why": f"raised: {error}"}
    error = float(np.abs(result.contact_force - exact).max(initial=0.0)) / result.force_scale
    error = error if np.isfinite(error) else float("inf")
    accepted = bool(result.verified and result.physical)
    return {"seconds": seconds, "ratio": seconds / base,
            "check_ratio": result.timings.get("check", float("nan")) / base,
            "force_error": error, "verified": accepted,
            "claimed_success": bool(result.claimed_success), "iterations": result.iterations,
            "outcome": outcome(accepted, bool(result.claimed_success), error <= WRONG),
            "why": "" if accepted else result.message[:200]}


def isolated(timeout: float, *args: Any) -> dict[str, Any]:
    """measure() in a forked child, stopped after ``timeout`` s (:func:`cases.in_child`)."""
    found = in_child(timeout, measure, *args)
    return found or {"outcome": "skipped", "why": f"time limit: stopped after {timeout:.0f} s"}


def skip_reason(run: Run, n_free: int, estimate: float | None, quick: bool) -> str | None:
    if run.dense and n_free > qpmod.DENSE_LIMIT:
        return f"dense solver: {n_free} unknowns > {qpmod.DENSE_LIMIT}"
    if estimate is not None and estimate > BUDGET[quick]:
        return f"over budget: about {estimate:.0f} s, from the previous case"
    return None


def run_case(case: Case, quick: bool, previous: dict[str, tuple[int, float]]
             ) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The case's description and one row per run; ``previous`` (label -> (dofs, seconds))
    carries each run's time to the next case's budget."""
    problem = case.build()
    n_free = problem.n - problem.prescribed.size
    reference = contactqp.solve(problem, "lagrange")
    base = floor(problem)
    described = {"case": case.name, "dofs": problem.n, "free_dofs": n_free, "rows": problem.m,
                 "floor_seconds": base, "force_scale": reference.force_scale,
                 "reference_verified": bool(reference.verified),
                 "reference_error_bound": reference.force_error_bound / reference.force_scale,
                 "pushing_rows": int(np.count_nonzero(reference.contact_force > 0))}
    print(f"{case.name}: {problem.n} dofs, {problem.m} rows, floor {base * 1e3:.1f} ms")
    rows = []
    for run in runs():
        before = previous.get(run.label)
        estimate = None if before is None else before[1] * (n_free / before[0]) ** GROWTH
        reason = skip_reason(run, n_free, estimate, quick)
        found = ({"outcome": "skipped", "why": reason} if reason else
                 isolated(TIMEOUT[quick], problem, run, reference.contact_force, base, quick))
        if "seconds" in found:
            previous[run.label] = (n_free, found["seconds"])
        elif found["why"].startswith("time limit"):
            previous[run.label] = (n_free, TIMEOUT[quick])
        rows.append({"case": case.name, "run": run.label, "method": run.method, **found})
        print(f"  {line(rows[-1])}", flush=True)
    return described, rows


def line(row: dict[str, Any]) -> str:
    if "seconds" not in row:
        return f"{row['run']:28s} {row['outcome']}: {row['why'][:110]}"
    return (f"{row['run']:28s} {row['ratio']:8.2f} x floor  error {row['force_error']:.1e}  "
            f"{row['outcome']}")


def cell(row: dict[str, Any]) -> str:
    """A run on one case, for the table: time / floor, force error / F, outcome."""
    if "seconds" not in row:
        return f"{row['outcome']} ({short_reason(row['why'])})"
    verdict = row["outcome"] if row["outcome"] != "verified" else "**verified**"
    return f"{row['ratio']:.3g}× · {row['force_error']:.0e} · {verdict}"


def short_reason(why: str) -> str:
    """Why a run has no time, in a few words (the whole reason is in runs.json)."""
    for key, words in (("dense solver", "dense solver"), ("over budget", "over budget"),
                       ("time limit", "time limit"), ("singular", "singular"),
                       ("dense flexibility", "past the LCP size")):
        if key in why:
            return words
    return why[:40].replace("|", "/")


def table(cases: list[dict[str, Any]], rows: list[dict[str, Any]]) -> str:
    """Markdown: one line per run, one column per case."""
    head = " | ".join(f"{c['case']} ({c['dofs']:,} dofs, {c['rows']} rows; floor "
                      f"{c['floor_seconds'] * 1e3:.0f} ms)".replace(",", " ", 1) for c in cases)
    lines = [f"| run | {head} |", "|---" * (len(cases) + 1) + "|"]
    for label in dict.fromkeys(r["run"] for r in rows):
        found = {r["case"]: r for r in rows if r["run"] == label}
        lines.append(f"| {label} | " + " | ".join(cell(found[c["case"]]) for c in cases) + " |")
    counts = {name: sum(r["outcome"] == name for r in rows) for name in
              dict.fromkeys(r["outcome"] for r in rows)}
    return ("\n".join(lines) + "\n\nEach cell: time end to end / the floor · largest "
            "contact-force error against Lagrange / F · outcome. "
            + ", ".join(f"{n} {name}" for name, n in counts.items()) + ".\n")


FAMILIES = {"lagrange": "tab:blue", "penalty": "tab:orange", "augmented": "tab:green",
            "lemke, pgs, semismooth Newton": "tab:pink", "qp, direct": "tab:red",
            "qp cvxpy": "tab:brown", "qp qpsolvers": "tab:gray"}


def family(row: dict[str, Any]) -> str:
    if row["method"] in ("lemke", "pgs", "semismooth_newton"):
        return "lemke, pgs, semismooth Newton"
    if row["method"] != "qp":
        return row["method"]
    backend = row["run"].split()[1].split("/")[0]
    return f"qp {backend}" if backend in ("cvxpy", "qpsolvers") else "qp, direct"


def chart(cases: list[dict[str, Any]], rows: list[dict[str, Any]], path: Path,
          families: dict[str, str] = FAMILIES, family: Callable[[dict], str] = family,
          title: str = "2D cases (scikit-fem): every method and QP solver, time against force "
                       "error", reference: str = "Lagrange") -> None:
    """Time / floor against force error / F, one panel per case (two columns; the legend in
    a spare panel); filled: verified, hollow: flagged; each point named. ``families``: a
    colour per family of runs, ``family`` a row's; ``reference``: what the error is against
    (benchmarks/friction_group.py draws its runs with its own)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    lines = -(-(len(cases) + 1) // 2)  # the cases and the legend, two to a line
    figure = Figure(figsize=(11.0, 4.6 * lines), layout="constrained")
    axes = list(figure.subplots(lines, 2, squeeze=False).flat)
    named = [panel(ax, case, [r for r in rows if r["case"] == case["case"]],
                   lambda r: families[family(r)], reference)
             for ax, case in zip(axes, cases)]
    spare = axes[len(cases)]
    spare.axis("off")
    spare.legend(handles=legend_handles(families), loc="center", fontsize=9, frameon=False)
    for ax in axes[len(cases) + 1:]:
        ax.set_visible(False)
    figure.suptitle(f"{title} (error 0 drawn at {ERROR_FLOOR:.0e}, no answer at "
                    f"{NO_ANSWER:g})", fontsize=10)
    figure.draw_without_rendering()  # the layout set, and then frozen: names placed in it
    figure.set_layout_engine("none")
    for ax, points in zip(axes, named):
        name_points(ax, points)
    figure.savefig(path, dpi=110)


NO_ANSWER = 10.0  # where a run with no finite answer is drawn (force error / F)


def panel(ax: Any, case: dict[str, Any], rows: list[dict[str, Any]],
          colour_of: Callable[[dict], str], reference: str) -> list[tuple[float, float, str]]:
    """One case's runs: a point per run that has a time; the points, to be named."""
    points = []
    for r in rows:
        if "seconds" not in r:
            continue
        colour = colour_of(r)
        x = min(max(r["force_error"], ERROR_FLOOR), NO_ANSWER)
        ax.scatter(x, r["ratio"], s=34, marker="o" if r["outcome"] in ("verified", "flagged")
                   else "X", facecolors=colour if r["verified"] else "none", edgecolors=colour,
                   linewidths=1.3, zorder=3)
        points.append((x, r["ratio"], r["run"].removeprefix("qp ")))
    ax.set(xscale="log", yscale="log", xlim=(ERROR_FLOOR / 10, 1e4),
           ylim=(0.7, 1.6 * max([p[1] for p in points], default=10.0)))
    ax.axvline(WRONG, color="k", ls="--", lw=0.8)
    ax.axhline(1.0, color="k", ls=":", lw=0.8)
    ax.set(xlabel=f"largest contact-force error / F (against {reference})",
           ylabel="time end to end / the floor",
           title=f"{case['case']}: {case['dofs']:,} dofs, {case['rows']} rows (floor "
                 f"{case['floor_seconds'] * 1e3:.3g} ms)")
    return points


def legend_handles(families: dict[str, str]) -> list[Any]:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=c, marker="o", ls="", label=name)
               for name, c in families.items()]
    return handles + [
        Line2D([], [], color="k", marker="o", ls="", label="verified"),
        Line2D([], [], color="k", marker="o", ls="", markerfacecolor="none",
               label="flagged by the check"),
        Line2D([], [], color="k", marker="X", ls="", markerfacecolor="none",
               label="the solver claimed success; wrong (flagged)"),
        Line2D([], [], color="k", ls="--", label=f"right: within {WRONG:.0e}·F"),
        Line2D([], [], color="k", ls=":", label="the floor: one SuperLU factor-and-solve")]


def name_points(ax: Any, points: list[tuple[float, float, str]]) -> None:
    """Each point's name beside it, moved up or down (in steps of a line) until it overlaps
    no name placed before it: runs of a family land together."""
    to_points = ax.transData.transform
    scale = 72.0 / ax.figure.dpi
    placed = []  # boxes in points (x0, y0, x1, y1): the markers first, then each name
    for x, y, _ in points:
        px, py = (value * scale for value in to_points((x, y)))
        placed.append((px - 3.5, py - 3.5, px + 3.5, py + 3.5))
    for x, y, name in sorted(points, key=lambda p: (-p[1], p[0])):
        px, py = (value * scale for value in to_points((x, y)))
        width = sum(4.7 if c.isupper() else 3.8 for c in name)  # 6.5-point text
        height = 7.5
        for shift in (0, *(s * k for k in range(1, 10) for s in (-1, 1))):
            box = (px + 4, py - 3 + shift * height, px + 4 + width, py - 3 + (shift + 1) * height)
            if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3]
                       for b in placed):
                break
        placed.append(box)
        ax.annotate(name, (x, y), xytext=(4, box[1] - py), textcoords="offset points",
                    fontsize=6.5, color="0.25", va="bottom",
                    arrowprops=None if shift == 0 else {"arrowstyle": "-", "color": "0.7",
                                                        "lw": 0.5})


def main(quick: bool, out: Path) -> None:
    """Run the group, write runs.json, table.md and speed_accuracy.png to ``out``."""
    start = time.perf_counter()
    previous: dict[str, tuple[int, float]] = {}
    cases, rows = [], []
    for case in CASES:
        if case.quick or not quick:
            described, found = run_case(case, quick, previous)
            cases.append(described)
            rows += found
    out.mkdir(parents=True, exist_ok=True)
    document = {"machine": machine(), "quick": quick, "wrong_above": WRONG,
                "timeout_seconds": TIMEOUT[quick], "cases": cases, "runs": rows}
    (out / "runs.json").write_text(json.dumps(document, indent=1))
    (out / "table.md").write_text(table(cases, rows))
    chart(cases, rows, out / "speed_accuracy.png")
    print(table(cases, rows))
    print(f"{len(rows)} runs in {time.perf_counter() - start:.0f} s; written: {out}/runs.json, "
          "table.md, speed_accuracy.png")
