"""Speed against accuracy for every method and solver, and a map of where each fails.

Cases: the default scene; the tapered bar with 10² … 10⁶ elements and one wall; a wall
at every node (10² … 10⁵ contacts); an open contact; a contact that just touches; a closed
gap (gap 0); a press fit (the node starts 0.1 mm past the wall). Runs: every method (lagrange,
lagrange with equality contact, penalty over ε = 1e8 … 1e22, augmented, qp) × every installed
QP backend and solver × formulation (full, strain, condensed) × scaling (scaled, SI) ×
accuracy (default, high). Combinations that cannot fit are skipped with the reason recorded.

Per run: median wall time over repeats after a first (warming) call, end to end (model, method, Result and its check), and
its build/solve split; the ratio to a floor measured in the same run (one banded Cholesky
factor-and-solve of K); the contact-force error against ``contactqp.reference`` (statics in
extended precision, independent of the methods), relative to the scene's force scale F (the
largest force the loads put through the bar, ``Result.force_scale``: the scale of the check's
guarantee); the largest penetration; the check's residuals;
``verified``, ``physical`` and whether the solver claimed success. Outcomes:

    verified                 the check accepts it (verified and physical) and it is right
    flagged                  the check rejects it (or the method raised a SolverError), and the
                             solver did not claim success with a wrong answer
    claimed success, wrong   the solver claimed success and the answer is wrong (the check
                             caught it)
    verified, wrong          the check accepted a wrong answer: a failure of the check itself

"Right" means a force error <= WRONG = 1e-5 of F: what ``verified`` guarantees
(contactqp.GUARANTEE; the check bounds every contact force's error by its force_error_bound,
at most 1e-5·F when verified).

    python benchmarks/run.py [--quick] [--out DIR]          (the default group, "matrix")

writes runs.csv, runs.json, best.md and four charts (speed_accuracy.png, time_vs_elements.png,
penalty.png, stability_map.png) to DIR (default benchmarks/out/run). ``--quick`` runs the small
cases only (under 2 minutes on a 2-core machine); CI runs it and checks the outputs parse
(``python benchmarks/run.py --check DIR``).
"""

from __future__ import annotations

import csv
import json
import math
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import contactqp
from cases import (
    MATRIX_TIMEOUT,
    default_with,
    floor,
    free_bar,
    in_child,
    machine,
    obstacle,
    tapered_scene,
    touching,
)
from contactqp.errors import OptionError, SceneError, SolverError
from contactqp.methods import qp as qpmod
from contactqp.methods.complementarity import LCP_ENTRIES, LCP_ROWS, contact_lcp
from contactqp.reference import reference

WRONG = contactqp.GUARANTEE[0]  # a force error above this is a wrong answer (docstring)
EPSILONS = [10.0**e for e in range(8, 23, 2)]  # penalty ε (N/m)
FORMULATIONS = ("full", "strain", "condensed")
# timed calls after the first, from the first call's time (the first is the time when none)
REPEATS = {False: lambda first: 5 if first < 0.05 else 3 if first < 0.3 else 1 if first < 1.0
           else 0,
           True: lambda first: 3 if first < 0.05 else 1}
ISOLATE_FROM = 10**4  # elements: from this size every run goes to a forked child ...
TIMEOUT = MATRIX_TIMEOUT  # s: ... that is stopped after this long (then skipped, with why)
CONDITION_LIMIT = 2000  # unknowns up to which a case's condition numbers are computed (dense)
BUDGET = 5.0  # s: a run whose time, extrapolated from the previous size, exceeds it is skipped
GROWTH = 1.5  # the extrapolation: time ~ n^GROWTH (CVXOPT through cvxpy took 30 ms on 1e2
              # elements and 290 s on 1e4: linear extrapolation let it run)
OUTCOMES = ("verified", "flagged", "claimed success, wrong", "verified, wrong", "skipped")


@dataclass(frozen=True)
class Case:
    name: str
    family: str  # runs of one family at growing sizes share the budget extrapolation
    build: Callable[[], contactqp.Scene]
    quick: bool = False


CASES = [
    Case("default", "taper", contactqp.default_scene, quick=True),
    Case("taper 1e2", "taper", lambda: tapered_scene(10**2), quick=True),
    Case("taper 1e3", "taper", lambda: tapered_scene(10**3)),
    Case("taper 1e4", "taper", lambda: tapered_scene(10**4)),
    Case("taper 1e5", "taper", lambda: tapered_scene(10**5)),
    Case("taper 1e6", "taper", lambda: tapered_scene(10**6)),
    Case("walls 1e2", "walls", lambda: obstacle(10**2), quick=True),
    Case("walls 1e3", "walls", lambda: obstacle(10**3)),
    Case("walls 1e4", "walls", lambda: obstacle(10**4)),
    Case("walls 1e5", "walls", lambda: obstacle(10**5)),
    Case("open", "open", lambda: default_with(gap=2e-3), quick=True),
    Case("touching", "touching", touching, quick=True),
    Case("gap 0", "gap 0", lambda: default_with(gap=0.0), quick=True),
    Case("press fit", "press fit", lambda: default_with(gap=-1e-4), quick=True),
    Case("free bar", "free bar", free_bar, quick=True),
]


@dataclass(frozen=True)
class Spec:
    """One run configuration (the same across cases)."""

    method: str
    formulation: str = "full"
    contact: str = "inequality"
    backend: str = ""
    solver: str = ""
    scale: bool | None = None
    accuracy: str = ""
    epsilon: float | None = None
    options: dict[str, Any] = field(default_factory=dict, hash=False, compare=False)

    @property
    def row(self) -> str:
        """The stability map's row: method (and backend/solver)."""
        if self.method == "qp":
            return f"qp {self.backend}" + (f"/{self.solver}" if self.backend in
                                          ("cvxpy", "qpsolvers") else "")
        extras = "".join(f" {name}={self.options[name]}" for name in ("relaxation", "ncp")
                         if name in self.options)
        return self.method + extras + (" (equality)" if self.contact == "equality" else "")

    @property
    def label(self) -> str:
        parts = [self.row, self.formulation]
        if self.epsilon is not None:
            parts.append(f"ε={self.epsilon:.0e}")
        if self.scale is not None:
            parts += ["scaled" if self.scale else "SI", self.accuracy]
        return " ".join(parts)


def specs() -> list[Spec]:
    runs = [Spec("lagrange", f) for f in FORMULATIONS]
    runs.append(Spec("lagrange", "full", contact="equality"))
    runs += [Spec("penalty", f, epsilon=e, options={"penalty": e})
             for e in EPSILONS for f in ("full", "condensed")]
    runs += [Spec("augmented", f) for f in ("full", "condensed")]
    runs += [Spec("lemke"), Spec("pgs"), Spec("pgs", options={"relaxation": 1.5}),
             Spec("semismooth_newton"),
             Spec("semismooth_newton", options={"ncp": "fischer-burmeister"}), Spec("nitsche")]
    for info in qpmod.available_qp_solvers():
        if not info.available:
            print(f"skipped: qp {info.backend}/{info.solver} is not installed "
                  f"({info.install})", file=sys.stderr)
            continue
        for formulation in FORMULATIONS:
            for scale in (True, False):
                for accuracy in ("default", "high"):
                    runs.append(Spec("qp", formulation, backend=info.backend, solver=info.solver,
                                     scale=scale, accuracy=accuracy,
                                     options={"backend": info.backend, "solver": info.solver,
                                              "scale": scale, "accuracy": accuracy}))
    return runs


def skip_reason(spec: Spec, scene: contactqp.Scene, n_free: int,
                estimate: float | None) -> str | None:
    """Why ``spec`` cannot fit ``scene``, or None."""
    unknowns = scene.n_contacts if spec.formulation == "condensed" else n_free  # at most
    if spec.method in ("lemke", "pgs", "semismooth_newton") and (
            scene.n_contacts > LCP_ROWS or n_free * scene.n_contacts > LCP_ENTRIES):
        return f"the dense LCP takes up to {LCP_ROWS} rows and {LCP_ENTRIES} entries"
    if (spec.method == "qp" and (spec.backend, spec.solver) in qpmod.DENSE_SOLVERS
            and unknowns > qpmod.DENSE_LIMIT):
        return f"dense solver, {unknowns} unknowns > {qpmod.DENSE_LIMIT}"
    if estimate is not None and estimate > BUDGET:
        return f"over budget: about {estimate:.0f} s per solve, from the previous size"
    return None


def force_error(result: contactqp.Result, exact: np.ndarray) -> float:
    """The largest contact-force error over the scene's force scale F."""
    error = float(np.abs(result.contact_force - exact).max(initial=0.0)) / result.force_scale
    return error if math.isfinite(error) else math.inf


def outcome(accepted: bool, claimed: bool, right: bool) -> str:
    if accepted:
        return "verified" if right else "verified, wrong"
    return "claimed success, wrong" if claimed and not right else "flagged"


def run_one(spec: Spec, scene: contactqp.Scene, exact: np.ndarray, floor_s: float,
            quick: bool) -> dict[str, Any]:
    def call() -> contactqp.Result:
        return contactqp.solve(scene, spec.method, contact=spec.contact,
                               formulation=spec.formulation, **spec.options)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solvers' own warnings; the check decides
        start = time.perf_counter()
        result = call()  # the first call also warms caches (cvxpy: canonicalisation)
        first = time.perf_counter() - start
        repeats = REPEATS[quick](first)
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            result = call()
            times.append(time.perf_counter() - start)
        seconds = statistics.median(times) if times else first
    error = force_error(result, exact)
    right = error <= WRONG
    accepted = bool(result.verified and result.physical)
    info = result.info
    build = info.get("time_setup", result.timings.get("build"))
    solve = info.get("time_solve", result.timings.get("solve"))
    return {
        "seconds": seconds, "first_seconds": first, "ratio": seconds / floor_s,
        "build_seconds": build, "solve_seconds": solve,
        "force_error": error,
        "max_penetration": float(np.max(result.penetration, initial=-math.inf)),
        **{f"residual_{k}": v for k, v in result.residuals.items()},
        "verified": bool(result.verified), "physical": bool(result.physical),
        "claimed_success": bool(result.claimed_success), "status": str(result.status),
        "message": result.message,
        "iterations": int(result.iterations), "cache": info.get("cache", ""),
        "outcome": outcome(accepted, bool(result.claimed_success), right),
        "claimed_success_wrong": bool(result.claimed_success and not right),
    }


def run_caught(*args: Any) -> dict[str, Any]:
    """run_one, with contactqp's refusals as a skip and a SolverError as flagged."""
    try:
        return run_one(*args)
    except (OptionError, SceneError) as error:  # refused up front: cannot fit
        return {"skip_reason": f"{type(error).__name__}: {error}"}
    except SolverError as error:  # the method failed, and said so: flagged
        return {"outcome": "flagged", "status": f"raised: {error}", "verified": False,
                "claimed_success": False, "claimed_success_wrong": False}


def run_isolated(*args: Any) -> dict[str, Any]:
    """run_caught in a forked child, stopped after TIMEOUT s (:func:`cases.in_child`)."""
    found = in_child(TIMEOUT, run_caught, *args)
    return found if found is not None else {"skip_reason": f"timed out after {TIMEOUT:.0f} s"}


class Progress:
    """A progress bar on stderr (a line per tenth when stderr is not a terminal)."""

    def __init__(self, total: int) -> None:
        self.total, self.done, self.start = total, 0, time.perf_counter()
        self.tty = sys.stderr.isatty()
        self.last_tenth = -1

    def step(self, text: str) -> None:
        self.done += 1
        fraction = self.done / self.total
        elapsed = time.perf_counter() - self.start
        bar = "#" * int(30 * fraction) + "-" * (30 - int(30 * fraction))
        line = f"[{bar}] {self.done}/{self.total} {elapsed:5.0f} s  {text}"
        if self.tty:
            print(f"\r{line[:110]:110}", end="", file=sys.stderr, flush=True)
        elif int(10 * fraction) > self.last_tenth:
            self.last_tenth = int(10 * fraction)
            print(line, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.tty:
            print(file=sys.stderr)


def run(quick: bool) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    cases = [c for c in CASES if c.quick or not quick]
    all_specs = specs()
    progress = Progress(len(cases) * len(all_specs))
    rows, case_rows = [], []
    previous: dict[tuple[str, Spec], tuple[int, float]] = {}  # (family, spec) -> (n, seconds)
    for case in cases:
        scene = case.build()
        exact = reference(scene)
        model = contactqp.build_model(scene)
        floor_s = floor(scene, 5 if scene.n_elements < 10**5 else 3)
        case_rows.append({"case": case.name, "elements": scene.n_elements,
                          "contacts": scene.n_contacts, "floor_seconds": floor_s,
                          "reference_force_max": float(exact.contact_force.max(initial=0.0)),
                          "reference_active": int(np.count_nonzero(exact.contact_force > 0)),
                          "reference_steps": exact.steps, **conditioning(model)})
        for spec in all_specs:
            row = {"case": case.name, "elements": scene.n_elements,
                   "contacts": scene.n_contacts, "row": spec.row, "label": spec.label,
                   "method": spec.method, "contact": spec.contact, "backend": spec.backend,
                   "solver": spec.solver, "formulation": spec.formulation,
                   "scaling": "" if spec.scale is None else ("scaled" if spec.scale else "SI"),
                   "accuracy": spec.accuracy, "epsilon": spec.epsilon,
                   "floor_seconds": floor_s}
            before = previous.get((case.family, spec))
            estimate = (None if before is None
                        else before[1] * (scene.n_elements / before[0]) ** GROWTH)
            reason = skip_reason(spec, scene, model.n_free, estimate)
            if reason is None:
                isolate = scene.n_elements >= ISOLATE_FROM
                found = (run_isolated if isolate else run_caught)(
                    spec, scene, exact.contact_force, floor_s, quick)
                if "skip_reason" in found:
                    reason = found["skip_reason"]
                    if reason.startswith("timed out"):  # the next size would take longer
                        previous[case.family, spec] = (scene.n_elements, TIMEOUT)
                else:
                    row.update(found)
                    if "seconds" in found:
                        previous[case.family, spec] = (scene.n_elements, found["seconds"])
            if reason is not None:
                row.update({"outcome": "skipped", "skip_reason": reason})
            rows.append(row)
            progress.step(f"{case.name}: {spec.label}")
            if row.get("first_seconds", 0.0) > 3.0:
                print(f"slow: {case.name}: {spec.label}: {row['first_seconds']:.1f} s",
                      file=sys.stderr, flush=True)
    progress.close()
    return rows, case_rows


def conditioning(model: contactqp.Model) -> dict[str, float | None]:
    """What describes a case to the QP world (as fclib describes its problems): the stiffness
    contrast (largest over smallest element stiffness), the 2-norm condition numbers of K
    and of the contact operator W = C K⁻¹ Cᵀ (dense, so up to CONDITION_LIMIT unknowns; None
    beyond), and W's rank."""
    k = model.layout.element_stiffness
    out: dict[str, float | None] = {"stiffness_contrast": float(k.max() / k.min()),
                                    "cond_K": None, "cond_W": None, "rank_W": None}
    if model.floating:  # K singular, W undefined (a bar held by contact alone)
        out["cond_K"] = float("inf")
    elif model.n_free <= CONDITION_LIMIT and model.n_contacts <= CONDITION_LIMIT:
        out["cond_K"] = float(np.linalg.cond(model.K.toarray()))
        W, *_ = contact_lcp(model)
        out["cond_W"] = float(np.linalg.cond(W)) if W.size else None
        out["rank_W"] = int(np.linalg.matrix_rank(W)) if W.size else 0
    return out


def best_table(rows: list[dict[str, Any]], case_rows: list[dict[str, Any]]) -> str:
    lines = [("| case | elements | contacts | contrast | cond K | cond W | floor "
              "| fastest verified (time, / floor, error) "
              "| most accurate verified (error, time) |"), "|---" * 9 + "|"]
    for case in case_rows:
        described = (f"| {case['case']} | {case['elements']} | {case['contacts']} | "
                     f"{_number(case.get('stiffness_contrast'))} | "
                     f"{_number(case.get('cond_K'))} | {_number(case.get('cond_W'))} | "
                     f"{_time(case['floor_seconds'])} |")
        ran = [r for r in rows if r["case"] == case["case"] and r["outcome"] == "verified"]
        if not ran:
            lines.append(f"{described} none | none |")
            continue
        fastest = min(ran, key=lambda r: r["seconds"])
        exact = min(ran, key=lambda r: (r["force_error"], r["seconds"]))
        lines.append(
            f"{described} {fastest['label']}: {_time(fastest['seconds'])}, "
            f"{fastest['ratio']:.1f}×, {fastest['force_error']:.1e} | {exact['label']}: "
            f"{exact['force_error']:.1e}, {_time(exact['seconds'])} |")
    return "\n".join(lines) + "\n"


def failure_table(rows: list[dict[str, Any]]) -> str:
    """Every run that is not verified, with why (the check's message, or why it was skipped):
    the stability map's cells, a table away."""
    lines = ["| case | run | outcome | force error / F | why |", "|---|---|---|---|---|"]
    for r in rows:
        if r["outcome"] == "verified":
            continue
        why = r.get("skip_reason") or r.get("message") or r.get("status", "")
        error = r.get("force_error")
        lines.append(f"| {r['case']} | {r['label']} | {r['outcome']} | "
                     f"{'–' if error is None else f'{error:.1e}'} | "
                     f"{str(why).replace('|', '/')[:160]} |")
    return "\n".join(lines) + "\n"


def _number(value: float | None) -> str:
    return "–" if value is None else f"{value:.2g}"


def _time(seconds: float) -> str:
    if seconds < 1e-3:
        return f"{seconds * 1e6:.0f} µs"
    return f"{seconds * 1e3:.1f} ms" if seconds < 1.0 else f"{seconds:.2f} s"


def write(rows: list[dict[str, Any]], case_rows: list[dict[str, Any]], out: Path,
          quick: bool) -> None:
    out.mkdir(parents=True, exist_ok=True)
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / "runs.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, columns)
        writer.writeheader()
        writer.writerows(rows)
    document = {"machine": machine(), "quick": quick, "wrong_above": WRONG,
                "cases": case_rows, "runs": rows}
    (out / "runs.json").write_text(json.dumps(document, indent=1, default=_plain))
    (out / "best.md").write_text(best_table(rows, case_rows))
    (out / "failures.md").write_text(failure_table(rows))
    import charts  # matplotlib only when writing
    import profiles

    charts.draw_all(rows, case_rows, out, WRONG)
    profiles.write(rows, out, TIMEOUT)


def _plain(value: Any) -> Any:
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(f"not JSON: {value!r}")


def main(quick: bool, out: Path) -> None:
    """Run the matrix, write its outputs to ``out`` and print the best run per case."""
    start = time.perf_counter()
    rows, case_rows = run(quick)
    write(rows, case_rows, out, quick)
    counts = {name: sum(r["outcome"] == name for r in rows) for name in OUTCOMES}
    print(best_table(rows, case_rows))
    print(f"{len(rows)} runs in {time.perf_counter() - start:.0f} s: " +
          ", ".join(f"{n} {name}" for name, n in counts.items()))
    print(f"written: {out}/runs.csv, runs.json, best.md, failures.md, profiles.md, "
          f"{', '.join(CHARTS)}")


CHARTS = ("speed_accuracy.png", "time_vs_elements.png", "penalty.png", "stability_map.png",
          "profiles.png")
PNG = b"\x89PNG\r\n\x1a\n"


def check_outputs(out: Path) -> list[str]:
    """Problems found in a matrix output folder (empty when it is complete and parses)."""
    problems = []
    document = json.loads((out / "runs.json").read_text())
    runs = document["runs"]
    with open(out / "runs.csv", newline="") as handle:
        table = list(csv.DictReader(handle))
    if not runs or len(table) != len(runs):
        problems.append(f"runs.json has {len(runs)} runs, runs.csv {len(table)}")
    if {r["case"] for r in runs} != {c["case"] for c in document["cases"]}:
        problems.append("runs and cases name different cases")
    for r in runs:
        if r["outcome"] not in OUTCOMES:
            problems.append(f"unknown outcome {r['outcome']!r} in {r['case']}: {r['label']}")
        elif r["outcome"] == "skipped" and not r.get("skip_reason"):
            problems.append(f"skipped without a reason: {r['case']}: {r['label']}")
        elif "seconds" in r and not (r["seconds"] > 0 and r["ratio"] > 0):
            problems.append(f"no time: {r['case']}: {r['label']}")
    if not any(r["outcome"] == "verified" for r in runs):
        problems.append("no verified run")
    for name in CHARTS:
        path = out / name
        if not path.is_file() or path.read_bytes()[:8] != PNG or path.stat().st_size < 5000:
            problems.append(f"{name} is missing or not a PNG chart")
    if "| case |" not in (out / "best.md").read_text():
        problems.append("best.md has no table")
    if "| case | run |" not in (out / "failures.md").read_text():
        problems.append("failures.md has no table")
    if "| setting |" not in (out / "profiles.md").read_text():
        problems.append("profiles.md has no table")
    return problems
