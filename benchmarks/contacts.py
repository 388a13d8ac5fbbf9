"""Many contacts: iterations and time against the number of contacts, every method, on three
obstacles (benchmarks/cases.py), from 10³ to 10⁶ contacts.

    obstacle   a wall beside every node, gaps 0.2 mm·(x/L)² + 10 µm·|sin 37x/L|, 565 kN at
               mid-length: a few small patches
    channel    walls on both sides of every node, a wavy channel 10 µm wide: most nodes touch
    patch      a flat wall 10 µm from every node, a uniform load pressing 95 % of the bar on it

Per run: the end-to-end time of contactqp.solve (the verified answer: build, method, check;
median of 3 below a second, after a first call that also lays the scene out) and its method
and check parts (Result.timings), all as ratios to the floor (one
banded factor-and-solve of K, same run); the iterations; the force error against the exact
reference (statics in extended precision, contactqp.reference, started from the rows the
first run found pushing: it certifies its answer whatever the start), relative to the largest
force. A run whose solve passes BUDGET, or would at the next size (PROJECTION times longer),
is not run at larger sizes (recorded); the next size's time is projected from the growth
measured over the last tenfold (PROJECTION times when there is none yet). Writes
contacts.json, contacts.png and contacts.md (the table docs/benchmarks.md shows).
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import contactqp
from cases import channel, flat_patch, floor, machine, median_time, obstacle
from contactqp.reference import reference

OBSTACLES: dict[str, Callable[[int], contactqp.Scene]] = {
    "obstacle": obstacle, "channel": channel, "patch": flat_patch}
RUNS = [("lagrange", {}), ("lagrange", {"active_set": "passed"}), ("augmented", {}),
        ("penalty", {}), ("qp", {"backend": "clarabel"}), ("qp", {"backend": "osqp"}),
        # the condensed chain (one unknown per contact node, tridiagonal): every QP backend
        ("augmented", {"formulation": "condensed"}),
        ("qp", {"backend": "clarabel", "formulation": "condensed"}),
        ("qp", {"backend": "osqp", "formulation": "condensed"}),
        ("qp", {"backend": "cvxpy", "formulation": "condensed"}),
        ("qp", {"backend": "qpsolvers", "solver": "piqp", "formulation": "condensed"})]
BUDGET = 20.0  # s for one solve
PROJECTION = 30.0  # a tenfold larger case takes this much longer, until measured
GOAL = 10.0  # the goal: the verified answer at 10⁵ contacts within 10 floors


def label(method: str, options: dict) -> str:
    return "/".join([method, *map(str, options.values())]) if options else (
        "lagrange/hull" if method == "lagrange" else method)


def main(quick: bool, out: Path) -> None:
    sizes = [10**3, 10**4] if quick else [10**3, 10**4, 10**5, 10**6]
    rows: list[dict] = []
    print(f"{'obstacle':9} {'contacts':>8} {'run':22} {'time/floor':>10} {'method':>7} "
          f"{'iter':>6} {'force error':>11} verified")
    for name, build in OBSTACLES.items():
        stopped: dict[str, str] = {}
        previous: dict[str, float] = {}
        for n in sizes:
            start = time.perf_counter()
            scene = build(n)
            built = time.perf_counter() - start
            base = floor(scene, 5)
            exact = None
            for method, options in RUNS:
                run = label(method, options)
                if run in stopped:
                    rows.append({"obstacle": name, "contacts": n, "run": run,
                                 "skipped": stopped[run]})
                    continue
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        result = contactqp.solve(scene, method, **options)
                    except contactqp.ContactqpError as error:
                        rows.append({"obstacle": name, "contacts": n, "run": run,
                                     "failed": str(error)})
                        stopped[run] = f"failed at {n}"
                        continue
                    once = result.time
                    seconds = once
                    if once < 1.0:  # warm: the median of 3, and the parts of one more call
                        seconds = median_time(lambda s=scene, m=method, o=options:
                                              contactqp.solve(s, m, **o), 3)
                        result = contactqp.solve(scene, method, **options)
                if exact is None:
                    exact = reference(scene, start=result.contact_force > 0.0)
                scale = float(np.abs(exact.contact_force).max())
                error = float(np.abs(result.contact_force - exact.contact_force).max()) / scale
                row = {"obstacle": name, "contacts": n, "run": run, "seconds": seconds,
                       "ratio": seconds / base, "method_ratio": result.timings["solve"] / base,
                       "check_ratio": result.timings["check"] / base,
                       "first_call_ratio": once / base,
                       "iterations": result.iterations, "force_error": error,
                       "verified": bool(result.verified), "floor": base,
                       "scene_build": built,
                       "active": int(np.count_nonzero(exact.contact_force > 0.0))}
                rows.append(row)
                print(f"{name:9} {n:8d} {run:22} {seconds / base:10.1f} "
                      f"{row['method_ratio']:7.1f} {result.iterations:6d} {error:11.1e} "
                      f"{result.verified}", flush=True)
                growth = seconds / previous[run] if run in previous else PROJECTION
                previous[run] = seconds
                if seconds > BUDGET or seconds * growth > BUDGET:
                    stopped[run] = (f"{seconds:.2f} s at {n} contacts, {seconds * growth:.0f} s "
                                    f"projected at the next size (budget {BUDGET:.0f} s)")
    out.mkdir(parents=True, exist_ok=True)
    (out / "contacts.json").write_text(json.dumps({"machine": machine(), "data": rows},
                                                  indent=1))
    draw(rows, out / "contacts.png")
    (out / "contacts.md").write_text(table(rows))
    hull = [r for r in rows if r["run"] == "lagrange/hull" and r["contacts"] == 10**5]
    for r in hull:
        print(f"goal at 10⁵ contacts, {r['obstacle']}: verified answer in {r['ratio']:.1f} "
              f"floors (method {r['method_ratio']:.1f}, check {r['check_ratio']:.1f}; first "
              f"call {r['first_call_ratio']:.1f}), goal {GOAL:.0f}")


def table(rows: list[dict]) -> str:
    """The table docs/benchmarks.md shows: per obstacle and size, each run's time as floors end to end (the
    method alone / the Result and its check in brackets), its iterations, its force error
    and whether it was verified."""
    runs = [label(m, o) for m, o in RUNS]
    lines = ["| obstacle | contacts | " + " | ".join(runs) + " |",
             "|---|---|" + "---|" * len(runs)]
    for name in OBSTACLES:
        for n in sorted({r["contacts"] for r in rows if r["obstacle"] == name}):
            cells = []
            for run in runs:
                row = next((r for r in rows if r["obstacle"] == name and r["contacts"] == n
                            and r["run"] == run), None)
                if row is None or "seconds" not in row:
                    cells.append("–")
                    continue
                mark = "" if row["verified"] else ", flagged"
                cells.append(f"{row['ratio']:.0f} ({row['method_ratio']:.0f}/"
                             f"{row['check_ratio']:.0f}), "
                             f"{row['iterations']} it, {row['force_error']:.0e}{mark}")
            lines.append(f"| {name} | {n:.0e} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def draw(rows: list[dict], path: Path) -> None:
    """Iterations (top) and time / floor (bottom) against contacts, one column per obstacle;
    solid: the whole verified solve, dotted: the method alone (lagrange/hull)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"lagrange/hull": "tab:blue", "lagrange/passed": "tab:cyan",
               "augmented": "tab:green", "penalty": "tab:orange", "qp/clarabel": "tab:red",
               "qp/osqp": "tab:purple", "augmented/condensed": "olive",
               "qp/clarabel/condensed": "salmon", "qp/osqp/condensed": "orchid",
               "qp/cvxpy/condensed": "tab:brown", "qp/qpsolvers/piqp/condensed": "tab:gray"}
    figure, axes = plt.subplots(2, len(OBSTACLES), figsize=(14, 8), sharex=True)
    for column, name in enumerate(OBSTACLES):
        for run, colour in colours.items():
            mine = sorted((r for r in rows if r["obstacle"] == name and r["run"] == run
                           and "seconds" in r), key=lambda r: r["contacts"])
            if not mine:
                continue
            n = [r["contacts"] for r in mine]
            axes[0, column].plot(n, [r["iterations"] for r in mine], "o-", color=colour,
                                 label=run)
            axes[1, column].plot(n, [r["ratio"] for r in mine], "o-", color=colour, label=run)
            if run == "lagrange/hull":
                axes[1, column].plot(n, [r["method_ratio"] for r in mine], "o:", color=colour,
                                     label="lagrange/hull, method alone")
        axes[0, column].set_title(name)
        axes[1, column].axhline(GOAL, color="black", linewidth=0.8, linestyle="--")
        for row in (0, 1):
            axes[row, column].set_xscale("log")
            axes[row, column].set_yscale("log")
            axes[row, column].grid(True, which="major", alpha=0.3)
        axes[1, column].set_xlabel("contacts")
    axes[0, 0].set_ylabel("iterations")
    axes[1, 0].set_ylabel("time / one banded solve of K")
    handles, labels = axes[1, 0].get_legend_handles_labels()
    figure.legend(handles, labels, fontsize=7, loc="lower center", ncol=6)
    figure.suptitle("Many contacts: iterations and time against the number of contacts "
                    "(dashed: the goal, 10 floors)")
    figure.tight_layout(rect=(0, 0.07, 1, 1))
    figure.savefig(path, dpi=110)
    plt.close(figure)
