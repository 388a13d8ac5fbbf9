"""The four charts of benchmarks/run.py, drawn from its rows (matplotlib, Agg).

    python benchmarks/charts.py RUNS [OUT]   # redraw them and profiles.png/.md from RUNS

redraws a matrix run's charts from the data it wrote (RUNS: its runs.json, or runs.json.gz as
docs/benchmark/ keeps it) into OUT (default: RUNS's folder), without running it again.
"""

from __future__ import annotations

import gzip
import json
import sys
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.ticker import LogLocator, NullFormatter

ERROR_FLOOR = 1e-17  # errors of exactly 0 are drawn here
GROUPS = {  # colour per method or backend
    "lagrange": "tab:blue", "penalty": "tab:orange", "augmented": "tab:green",
    "qp clarabel": "tab:red", "qp osqp": "tab:purple", "qp cvxpy": "tab:brown",
    "qp qpsolvers": "tab:gray", "lemke": "tab:pink", "pgs": "tab:olive",
    "semismooth_newton": "tab:cyan", "nitsche": "gold",
}
MARKERS = {"full": "o", "strain": "s", "condensed": "^"}
OUTCOME_COLOURS = {"verified": "#4daf4a", "flagged": "#ffb347",
                   "claimed success, wrong": "#e41a1c", "verified, wrong": "#984ea3",
                   "skipped": "#d9d9d9"}
SEVERITY = ["skipped", "verified", "flagged", "claimed success, wrong", "verified, wrong"]


def group(row: dict[str, Any]) -> str:
    if row["method"] == "qp":
        return f"qp {row['backend']}"
    return row["method"]


def _ran(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows that ran to a Result (not skipped, not raised)."""
    return [r for r in rows if "seconds" in r]


def pareto_front(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The runs no other run beats in both time and force error, fastest first."""
    front, best = [], float("inf")
    for r in sorted(runs, key=lambda r: (r["seconds"], r["force_error"])):
        if r["force_error"] < best:
            front.append(r)
            best = r["force_error"]
    return front


def speed_accuracy(rows, case_rows, out: Path, wrong: float) -> None:
    sizes = [c for c in case_rows if c["case"] == "default" or c["case"].startswith("taper")]
    columns = min(3, len(sizes))
    lines = -(-len(sizes) // columns)
    # one time axis and one error axis for every panel: each floor sits at its own time (a
    # panel scaled to its own runs put the floor at its left frame whatever its time) and a
    # panel spans decades, labelled at whole decades only
    fig, axes = plt.subplots(lines, columns, figsize=(4.4 * columns, 3.8 * lines + 0.9),
                             squeeze=False, sharex=True, sharey=True)
    for ax in axes.flat[len(sizes):]:
        ax.set_visible(False)
    for ax, case in zip(axes.flat, sizes):
        # per method or backend, its Pareto front of the verified runs (no other of its runs
        # both faster and more accurate), marked by formulation; every run is in runs.csv
        verified: dict[str, list[dict[str, Any]]] = {}
        for r in _ran(rows):
            if r["case"] == case["case"] and r["outcome"] == "verified":
                verified.setdefault(group(r), []).append(r)
        for name, runs in verified.items():
            front = pareto_front(runs)
            colour = GROUPS[name]
            ax.plot([r["seconds"] for r in front],
                    [max(r["force_error"], ERROR_FLOOR) for r in front], "-", color=colour,
                    lw=1, alpha=0.7)
            for r in front:
                ax.scatter(r["seconds"], max(r["force_error"], ERROR_FLOOR),
                           marker=MARKERS[r["formulation"]], s=26, color=colour)
        ax.axvline(case["floor_seconds"], color="k", ls=":", lw=1)
        ax.axhline(wrong, color="k", ls="--", lw=0.7)
        ax.set(xscale="log", yscale="log", title=f"{case['case']} ({case['elements']} elements)")
        ax.xaxis.set_major_locator(LogLocator(numticks=12))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_major_locator(LogLocator(numticks=8))
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(labelbottom=True)  # sharex keeps only the last row's labels
        ax.set_xlabel("time (s), end to end")
    for row in axes:
        row[0].set_ylabel("contact-force error (relative)")
    handles = [Line2D([], [], color=c, marker="o", ls="", label=g) for g, c in GROUPS.items()]
    handles += [Line2D([], [], color="k", marker=m, ls="", label=f)
                for f, m in MARKERS.items()]
    handles += [Line2D([], [], color="k", ls=":", label="floor: one factor-and-solve of K"),
                Line2D([], [], color="k", ls="--", label=f"wrong above {wrong:.0e}")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=8)
    fig.suptitle("Speed against accuracy: each method's or backend's Pareto front of verified "
                 f"runs (every run: runs.csv; error 0 drawn at {ERROR_FLOOR:.0e})", fontsize=10)
    fig.tight_layout(rect=(0, 0.9 / fig.get_figheight(), 1, 0.95))
    fig.savefig(out / "speed_accuracy.png", dpi=110)
    plt.close(fig)


def time_vs_elements(rows, case_rows, out: Path) -> None:
    """Per method or backend, its fastest verified run at each size (marker: formulation)."""
    sizes = sorted((c for c in case_rows if c["case"] == "default" or
                    c["case"].startswith("taper")), key=lambda c: c["elements"])
    fig, ax = plt.subplots(figsize=(9.5, 5))
    for name, colour in GROUPS.items():
        points = []
        for case in sizes:
            ok = [r for r in rows if r["case"] == case["case"] and r["outcome"] == "verified"
                  and group(r) == name]
            if ok:
                best = min(ok, key=lambda r: r["seconds"])
                points.append((case["elements"], best["seconds"], best["formulation"]))
        if points:
            ax.plot([p[0] for p in points], [p[1] for p in points], color=colour, lw=1.2,
                    label=name)
            for x, y, formulation in points:
                ax.plot(x, y, MARKERS[formulation], color=colour, ms=5)
    ax.plot([c["elements"] for c in sizes], [c["floor_seconds"] for c in sizes], "k:", lw=2,
            label="floor: one factor-and-solve of K")
    handles, _ = ax.get_legend_handles_labels()
    handles += [Line2D([], [], color="k", marker=m, ls="", label=f) for f, m in MARKERS.items()]
    # beside the axes: inside, eleven methods and the floor cover the curves they name
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set(xscale="log", yscale="log", xlabel="elements",
           ylabel="fastest verified run (s), end to end",
           title="Time against size: the tapered bar, one wall")
    fig.tight_layout()
    fig.savefig(out / "time_vs_elements.png", dpi=110)
    plt.close(fig)


def penalty(rows, case_rows, out: Path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    cases = [c["case"] for c in case_rows if c["case"] in ("default", "taper 1e2", "taper 1e4",
                                                           "taper 1e6")]
    for i, case in enumerate(cases):
        for formulation, ls in (("full", "-"), ("condensed", "--")):
            runs = sorted((r for r in _ran(rows) if r["case"] == case and r["method"] == "penalty"
                           and r["formulation"] == formulation), key=lambda r: r["epsilon"])
            if not runs:
                continue
            eps = [r["epsilon"] for r in runs]
            colour = f"C{i}"
            left.plot(eps, [max(r["max_penetration"], ERROR_FLOOR) for r in runs], ls=ls,
                      color=colour, marker="o", ms=3, label=f"{case}, {formulation}")
            right.plot(eps, [max(r["force_error"], ERROR_FLOOR) for r in runs], ls=ls,
                       color=colour, marker="o", ms=3, label=f"{case}, {formulation}")
            for r in runs:
                if r["outcome"] != "verified":
                    right.plot(r["epsilon"], max(r["force_error"], ERROR_FLOOR), "x",
                               color=colour, ms=8)
    left.set(xscale="log", yscale="log", xlabel="penalty ε (N/m)",
             ylabel="largest penetration (m)", title="Penetration λ/ε")
    right.set(xscale="log", yscale="log", xlabel="penalty ε (N/m)",
              ylabel="contact-force error (relative)",
              title="Force error: s/ε, then round-off (x: not verified)")
    right.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "penalty.png", dpi=110)
    plt.close(fig)


def stability_map(rows, case_rows, out: Path) -> None:
    cases = [c["case"] for c in case_rows]
    labels = list(dict.fromkeys(r["row"] for r in rows))
    grid = [[0] * len(cases) for _ in labels]
    text = [[""] * len(cases) for _ in labels]
    for i, label in enumerate(labels):
        for j, case in enumerate(cases):
            cell = [r for r in rows if r["row"] == label and r["case"] == case]
            grid[i][j] = max(SEVERITY.index(r["outcome"]) for r in cell)
            ran = [r for r in cell if r["outcome"] != "skipped"]  # raised ones count as run
            good = sum(r["outcome"] == "verified" for r in ran)
            text[i][j] = f"{good}/{len(ran)}" if ran else "–"
    # cells as small as their text allows, so that the page, which shows the chart at its
    # column's width, keeps the text readable (at 1 inch a column it was shrunk to 3 px)
    fig, ax = plt.subplots(figsize=(0.6 * len(cases) + 4.2, 0.25 * len(labels) + 1.8))
    ax.imshow(grid, cmap=ListedColormap([OUTCOME_COLOURS[s] for s in SEVERITY]), vmin=-0.5,
              vmax=len(SEVERITY) - 0.5, aspect="auto")
    for i in range(len(labels)):
        for j in range(len(cases)):
            ax.text(j, i, text[i][j], ha="center", va="center", fontsize=7.5)
    ax.set_xticks(range(len(cases)), cases, rotation=40, ha="right", fontsize=8.5)
    ax.set_yticks(range(len(labels)), labels, fontsize=8.5)
    handles = [Line2D([], [], marker="s", ls="", ms=9, color=OUTCOME_COLOURS[s], label=s)
               for s in SEVERITY]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=8)
    ax.set_title("Stability map: the worst outcome over formulations, scaling, accuracy and ε\n"
                 "(text: verified-and-right runs / runs)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "stability_map.png", dpi=110)
    plt.close(fig)


def draw_all(rows: list[dict[str, Any]], case_rows: list[dict[str, Any]], out: Path,
             wrong: float) -> None:
    speed_accuracy(rows, case_rows, out, wrong)
    for draw in (time_vs_elements, penalty, stability_map):
        draw(rows, case_rows, out)


def redraw(runs: Path, out: Path) -> None:
    """Draw a matrix run's charts again into ``out`` from the runs.json it wrote (or its
    gzip, runs.json.gz, as docs/benchmark/ keeps it)."""
    import profiles
    from cases import MATRIX_TIMEOUT

    data = runs.read_bytes()
    document = json.loads(gzip.decompress(data) if runs.suffix == ".gz" else data)
    draw_all(document["runs"], document["cases"], out, document["wrong_above"])
    profiles.write(document["runs"], out, MATRIX_TIMEOUT)


if __name__ == "__main__":
    runs = Path(sys.argv[1])
    redraw(runs, Path(sys.argv[2]) if len(sys.argv) > 2 else runs.parent)
