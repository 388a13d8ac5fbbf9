"""The matrix's runs in the QP-solver world's terms (qpbenchmark, Siconos/fclib): per method and
solver over the whole case set, its success rate, the rate at which it claims success and is
wrong, how often its claim matches reality, the shifted geometric mean of its time normalised
to the best, and Dolan–Moré performance profiles of time and of accuracy.

Each compared setting is one fixed configuration across the cases (qpbenchmark compares
solvers per setting): the QP solvers in the full formulation, scaled, at accuracy "default"
and at "high"; every other method with its own defaults (the penalty at ε = 1e14 N/m, the
textbook's). A run succeeds in qpbenchmark's sense when the solver says so
(``claimed_success``); contactqp's sense is ``verified`` (the check) and right is the force
within 1e-5·F of the exact reference. Time metrics (qpbenchmark's definitions): the shifted
geometric mean with shift 10 (seconds) of the run times, a run that is not verified charged
the time limit (matrix.TIMEOUT); the performance profile ρ_s(τ) is the share of cases on which
setting s is verified within τ times the fastest verified setting (Dolan and Moré 2002).
Writes profiles.md and profiles.png into the matrix's folder.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

SHIFT = 10.0  # s, qpbenchmark's shift for times


def settings(row: dict[str, Any]) -> str | None:
    """The compared setting a run belongs to, or None (other formulations and scalings)."""
    if row["contact"] != "inequality":
        return None
    if row["method"] == "qp":
        if row["formulation"] != "full" or row["scaling"] != "scaled":
            return None
        return f"{row['row']} ({row['accuracy']})"
    if row["method"] == "penalty":
        return "penalty ε=1e14" if row.get("epsilon") == 1e14 and (
            row["formulation"] == "full") else None
    return row["row"] if row["formulation"] == "full" else None


def shifted_geometric_mean(values: np.ndarray, shift: float = SHIFT) -> float:
    """exp(mean(log(v + shift))) − shift (qpbenchmark's shgeom)."""
    return float(np.exp(np.mean(np.log(values + shift))) - shift)


def metrics(rows: list[dict[str, Any]], limit: float) -> tuple[list[dict[str, Any]],
                                                               dict[str, np.ndarray],
                                                               dict[str, np.ndarray]]:
    """(one row of metrics per setting; per setting its time and force error per case, inf
    where not verified), over every case (a skipped run, refused or over the time budget,
    counts as a failure, as qpbenchmark counts a solver that does not finish)."""
    by_setting: dict[str, dict[str, dict[str, Any]]] = {}
    for r in rows:
        name = settings(r)
        if name is not None:
            by_setting.setdefault(name, {})[r["case"]] = r
    cases = sorted({r["case"] for r in rows})
    missing = {"outcome": "skipped"}
    table, times, errors = [], {}, {}
    for name, runs in by_setting.items():
        chosen = [runs.get(c, missing) for c in cases]
        verified = np.array([r["outcome"] == "verified" for r in chosen])
        claimed = np.array([bool(r.get("claimed_success")) for r in chosen])
        right = np.array([r.get("force_error", math.inf) <= 1e-5 for r in chosen])
        seconds = np.array([r.get("seconds", limit) for r in chosen])
        times[name] = np.where(verified, seconds, np.inf)
        errors[name] = np.where(verified, [max(r.get("force_error", 0.0), 1e-17) for r in chosen],
                                np.inf)
        table.append({"setting": name, "cases": len(cases),
                      "success": claimed.mean(), "verified": verified.mean(),
                      "claimed_wrong": (claimed & ~right).mean(),
                      "correct": (claimed == right).mean(),
                      "shgeom": shifted_geometric_mean(np.where(verified, seconds, limit))})
    best = min(row["shgeom"] for row in table)
    for row in table:
        row["shgeom_ratio"] = row["shgeom"] / best
    table.sort(key=lambda row: (row["shgeom_ratio"], row["setting"]))
    return table, times, errors


def profile(values: dict[str, np.ndarray], taus: np.ndarray) -> dict[str, np.ndarray]:
    """ρ_s(τ): per setting the share of cases with value ≤ τ × the best setting's there."""
    stacked = np.vstack(list(values.values()))
    best = stacked.min(axis=0)
    usable = np.isfinite(best)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratios = stacked[:, usable] / best[usable]
    return {name: (ratios[i][:, None] <= taus[None, :]).mean(axis=0)
            for i, name in enumerate(values)}


def write(rows: list[dict[str, Any]], out: Path, limit: float) -> None:
    table, times, errors = metrics(rows, limit)
    lines = [f"Over {table[0]['cases']} cases; time limit {limit:g} s; shift {SHIFT:g} s.", "",
             ("| setting | success (claimed) | verified | claimed success, wrong | correct claim "
              "| shifted geometric mean of time (× best) |"),
             "|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['setting']} | {100 * r['success']:.0f} % | "
                     f"{100 * r['verified']:.0f} % | {100 * r['claimed_wrong']:.0f} % | "
                     f"{100 * r['correct']:.0f} % | {r['shgeom_ratio']:.2f} |")
    (out / "profiles.md").write_text("\n".join(lines) + "\n")
    from matplotlib.figure import Figure  # matplotlib only when writing

    # two groups of lines a reader can tell apart: contactqp's methods (with the QP through
    # its direct backends), and every QP solver through qpsolvers, both at default accuracy
    groups = {"methods": [n for n in times if not n.startswith("qp ")
                          or n in ("qp clarabel (default)", "qp osqp (default)")],
              "QP solvers via qpsolvers, default":
                  [n for n in times if n.startswith("qp qpsolvers/") and n.endswith("(default)")]}
    # one column per group, its legend below it (inside the panels it covered the curves)
    figure = Figure(figsize=(12, 9.5), layout="constrained")
    taus = np.logspace(0, 4, 200)
    for column, (group, names) in zip(figure.subfigures(1, 2), groups.items()):
        panels = column.subplots(2, 1)
        for ax, (values, what) in zip(panels, ((times, "time"), (errors, "force error"))):
            curves = profile({n: values[n] for n in names}, taus)
            for i, (name, share) in enumerate(curves.items()):
                ax.semilogx(taus, share, label=name, color=f"C{i % 10}",
                            ls=("-", "--")[i // 10 % 2], lw=1.2)
            ax.set(xlabel=f"τ: within τ × the best {what} of the group",
                   ylabel="share of cases verified", ylim=(0, 1.02),
                   title=f"{group}: profile of {what}")
        column.legend(*panels[0].get_legend_handles_labels(), loc="outside lower center",
                      ncol=2, fontsize=7)
    figure.savefig(out / "profiles.png", dpi=110)
