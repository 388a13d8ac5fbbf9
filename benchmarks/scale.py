"""The scaling of the general path on the Hertz models: time against dofs at a fixed contact
fraction, and time against the rows in contact at fixed dofs, in 2D and 3D (issue 39).

    python benchmarks/scale.py [--quick] [--out DIR] [--cache DIR] [--sweeps dofs2d,rows3d]
                               [--timeout S] [--budget S]

Models (contactqp.fem, scikit-fem; R = 10 mm, E = 210 GPa, ν = 0.3, contact zone 0.5 mm):

    dofs2d  the Hertz cylinder pushed down by δ = 10 µm (a ≈ 0.41 of the zone: the contact
            fraction fixed) on meshes refined in fine and growth together, 10⁴ to 9·10⁵ dofs
    dofs3d  the Hertz sphere, δ = 10 µm (a ≈ 0.63 of the zone), on the levels of
            benchmarks/hertz3d.py, 5·10³ to 2.4·10⁵ dofs (level 5 builds in about 2 minutes)
    rows2d  one cylinder mesh (3.3·10⁵ dofs, 10 272 rows, the finest 6.25 nm at the lowest
            point), δ from 6·10⁻⁵ µm to 40 µm: 88 to 10 236 rows in contact (at 40 µm the
            contact passes the zone: every row of it holds)
    rows3d  one sphere mesh, δ from 1 µm to 20 µm: 10² rows in contact to most of its rows

Runs on each: contactqp.solve by lagrange, lagrange with engine="amg" (column "lagrange
(amg)": K by conjugate gradients with pyamg's multigrid, contactqp.model.iterative; refused
where pyamg is not installed), semismooth_newton, pgs (its sweeps in its cell;
it forms the dense W, and is refused past that size), penalty, augmented and qp (its default
backend), end to end (model, method, check); and Clarabel, OSQP and PIQP called directly
(through qpsolvers, at their default settings) on the same QP written on the free dofs,
minimise ½ xᵀK_ff x + (K_fp u_p − f_f)ᵀx subject to C_f x ≤ g − C_p u_p, timed from the
Problem's arrays to the solver's answer; each peer's answer is then judged by the same check,
contactqp.check(problem, u, contact_force), outside its time. With ``--runs`` naming
clarabel_tight, osqp_tight or piqp_tight, the same peer is called again with its tolerances
tightened a decade at a time (TIGHTER: 1e-5 to 1e-10; OSQP polishing its answer) until the
check verifies its answer: the run's time is that of the loosest verified setting (timed as
every run), ``tolerance`` the setting and ``ladder_seconds`` the whole search; a peer that no
setting verifies is recorded with the last one's reason. Each run goes to a forked child
stopped after TIMEOUT s or FLOOR_TIMES times the case's floor, the longer (a peer's run
CHECK_ALLOWANCE s more, for the check of its answer); a run stopped so is not started again on
the sweep's larger cases, and no run starts once the whole run's BUDGET is spent (each skip
with its reason).

The floor of each mesh: the fastest factor-and-solve of K on the free dofs available here,
measured in the same run: SuperLU with COLAMD, SuperLU with minimum degree in symmetric mode,
qdldl's LDLᵀ (with AMD), and where installed CHOLMOD through cvxopt or cholespy and PARDISO
through pypardiso (benchmarks/candidates.py; benchmarks/factorisations.py compares them). Where
that floor takes under PAIRED_UNDER s, the fastest candidate is timed again in each run's
process, once before the run and once after each of its passes, and the run's ratio is to the
median of those (``paired_floor_seconds``; ``mesh_ratio``: to the mesh's floor): on this VM
the machine's speed drifts by a third over minutes, and a floor timed before a mesh's runs was
1.0 s in one run and 1.4 s in the next. Elsewhere the ratio is to the mesh's floor.

Built problems are kept in the cache folder (default DIR/problems) as .npz, so a second run
does not mesh again. Writes scale.json, table.md, time_vs_dofs.png and time_vs_rows.png to DIR
(default benchmarks/out/scale); ``--redraw DIR/scale.json`` writes the table and the charts
again from the data. ``--quick``: the smallest cases, under two minutes.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import statistics
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

import contactqp
from candidates import factor_and_solve
from cases import in_child, machine

TIMEOUT = {False: 60.0, True: 10.0}  # s per run (full, --quick)
BUDGET = {False: 2400.0, True: 75.0}  # s: no run starts after this much of the whole run
FLOOR_TIMES = 10.0  # ... or this many times the case's floor, where that is longer
REPEATS = ((0.5, 9), (2.0, 3))  # a run (or a floor) whose first call takes under 0.5 s is
# timed as the median of 9 calls, under 2 s of 3, else once: on this VM a 50 ms run moves by
# a third from call to call (0.042-0.067 s for lagrange at 8 754 dofs, one process, quiet)
PAIRED_UNDER = 5.0  # s: a mesh whose floor takes less has it timed again beside each run
CHECK_ALLOWANCE = 60.0  # s more for a peer's run: the check of its answer, outside its time
ZONE, APPROACH = 0.5, 0.01  # mm: the contact zone's (half-)width, δ
METHODS = ("lagrange", "lagrange_amg", "semismooth_newton", "pgs", "penalty", "augmented", "qp")
ENGINES = {"lagrange_amg": ("lagrange", "amg")}  # a run's method and engine, where not direct
SHORT = {"semismooth_newton": "ssn", "lagrange_amg": "lagrange (amg)"}  # the table's columns
PEERS = ("clarabel", "osqp", "piqp")
TIGHT = ("clarabel_tight", "osqp_tight", "piqp_tight")  # the peers, tightened until verified
TIGHTER = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)  # the tolerances a tightened peer tries
SETTINGS = {  # each peer's tolerances at t, as qpsolvers passes them on
    "clarabel": lambda t: {"tol_gap_abs": t, "tol_gap_rel": t, "tol_feas": t,
                           "tol_ktratio": t},
    "osqp": lambda t: {"eps_abs": t, "eps_rel": t, "polish": True, "max_iter": 10**6},
    "piqp": lambda t: {"eps_abs": t, "eps_rel": t}}
FLOOR_CANDIDATES = {  # benchmarks/candidates.py's names: the floor's
    "superlu_colamd": "SuperLU COLAMD", "superlu_mmd": "SuperLU MMD symmetric",
    "qdldl": "qdldl LDLT", "cvxopt": "CHOLMOD (cvxopt)", "cholespy": "CHOLMOD (cholespy)",
    "pardiso": "PARDISO (pypardiso)"}


@dataclass(frozen=True)
class Mesh:
    """One model's mesh: 2D (the cylinder, fine = ZONE / n) or 3D (the sphere)."""

    dimension: int
    fine: float
    growth: float

    @property
    def key(self) -> str:
        return f"{self.dimension}d_fine{self.fine:.6g}_growth{self.growth:.6g}"

    def build(self) -> contactqp.Problem:
        from contactqp.fem import cylinder_on_flat, sphere_on_flat

        builder = cylinder_on_flat if self.dimension == 2 else sphere_on_flat
        return builder(zone=ZONE, fine=self.fine, growth=self.growth, approach=APPROACH).problem


@dataclass(frozen=True)
class Case:
    sweep: str  # dofs2d, dofs3d, rows2d, rows3d
    mesh: Mesh
    approach: float  # mm
    runs_in: str  # "both", "full" or "quick": the runs it is part of


def level(k: int) -> Mesh:
    """The sphere of benchmarks/hertz3d.py's level k: every allowed size 2^(−k/2) level 0's."""
    return Mesh(3, 0.1 * 2.0 ** (-k / 2), 0.6 * 2.0 ** (-k / 2))


SMALL2D, SMALL3D = Mesh(2, ZONE / 50, 0.1), level(1)  # 8 754 and 5 106 dofs
ROWS2D = Mesh(2, ZONE / 80000, 0.2)  # 330 752 dofs, 10 272 rows (finest at x = 0)
ROWS2D_APPROACHES = (6e-8, 1e-6, 1e-5, 1e-4, 0.04)  # mm: 88 to 10 236 rows in contact
ROWS3D = Mesh(3, 0.02, 0.6)  # 16 233 dofs, 985 rows
CASES = (
    Case("dofs2d", SMALL2D, APPROACH, "both"),
    *(Case("dofs2d", Mesh(2, ZONE / n, growth), APPROACH, "full")
      for n, growth in ((160, 0.05), (640, 0.03), (2000, 0.02))),
    Case("dofs3d", SMALL3D, APPROACH, "both"),
    *(Case("dofs3d", level(k), APPROACH, "full") for k in (2, 3, 4, 5)),
    *(Case("rows2d", ROWS2D, approach, "full") for approach in ROWS2D_APPROACHES),
    *(Case("rows3d", ROWS3D, approach, "full") for approach in (1.7e-3, 5e-3, 0.02)),
    # --quick: the rows sweeps' logic on the small meshes, at two loads each
    *(Case("rows2d", SMALL2D, approach, "quick") for approach in (1e-3, 0.03)),
    *(Case("rows3d", SMALL3D, approach, "quick") for approach in (3e-3, 0.02)),
)


def problem_of(case: Case, cache: Path) -> contactqp.Problem:
    """The case's problem: its mesh built once (or read from the cache), pushed by its δ."""
    path = cache / f"{case.mesh.key}.npz"
    if path.exists():
        problem = contactqp.load_problem(path)
    else:
        problem = case.mesh.build()
        cache.mkdir(parents=True, exist_ok=True)
        contactqp.save_problem(problem, path)
    # the prescribed values are 0 on the symmetry planes and −δ on the cut: scaled to this δ
    return problem.with_values(prescribed_values=problem.prescribed_values
                               * (case.approach / APPROACH))


def free_dofs(problem: contactqp.Problem) -> np.ndarray:
    return np.setdiff1d(np.arange(problem.n), problem.prescribed)


def floors(problem: contactqp.Problem, repeats: int, limit: float) -> dict[str, float]:
    """Each factor-and-solve of K on the free dofs available here (seconds, the median of
    ``repeats``): SuperLU with COLAMD, SuperLU with minimum degree in symmetric mode (as
    benchmarks/hertz.py), qdldl's LDLᵀ with AMD (its upper triangle), and where installed
    CHOLMOD through cvxopt or cholespy and PARDISO through pypardiso; one not done within
    ``limit`` s is left out."""
    found = {}
    for name, job in floor_calls(problem).items():
        # each in a child stopped after the run's time limit: SuperLU at 9·10⁵ dofs takes
        # many minutes and gigabytes, and a floor past the limit is no floor
        seconds = in_child(limit, timed, job, repeats)
        if seconds is not None:
            found[name] = seconds
    return found


def floor_calls(problem: contactqp.Problem) -> dict[str, Any]:
    """Each floor candidate installed here as a call (FLOOR_CANDIDATES' labels): a
    factor-and-solve of K on the free dofs, K handed over beforehand."""
    free = free_dofs(problem)
    K = sp.csc_matrix(sp.csr_array(problem.K)[free][:, free])
    K.sort_indices()
    rhs = np.ones(free.size)
    calls = {}
    for name, label in FLOOR_CANDIDATES.items():
        try:
            factor, solve = factor_and_solve(name, K)
        except ImportError:  # not installed here
            continue
        calls[label] = (lambda factor=factor, solve=solve: solve(factor(), rhs))
    return calls


def timed(function: Any, repeats: int) -> float:
    """The median wall time of ``repeats`` calls (seconds), more where the first is short
    (:func:`repeats_after`)."""
    times = [seconds_of(function)]
    while len(times) < max(repeats, repeats_after(times[0])):
        times.append(seconds_of(function))
    return statistics.median(times)


def seconds_of(function: Any) -> float:
    """The wall time of one call (seconds)."""
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def repeats_after(first: float) -> int:
    """How many calls time a run or a floor whose first call took ``first`` s (REPEATS)."""
    return next((count for under, count in REPEATS if first < under), 1)


def reduced_qp(problem: contactqp.Problem) -> tuple[Any, ...]:
    """The QP on the free dofs (P, q, G, h) and what lifts its x back to u."""
    free, held = free_dofs(problem), problem.prescribed
    K, C = sp.csr_array(problem.K), sp.csc_array(problem.C)
    values = problem.prescribed_values
    P = sp.csc_matrix(K[free][:, free])
    q = K[free][:, held] @ values - problem.f[free]
    G = sp.csc_matrix(C[:, free])
    h = problem.g - C[:, held] @ values
    return P, q, G, h, free


def peer(problem: contactqp.Problem, solver: str, tolerance: float | None = None
         ) -> dict[str, Any]:
    """Clarabel, OSQP or PIQP on the same QP, timed, then judged by contactqp's check; at
    its default settings, or with its tolerances at ``tolerance`` (SETTINGS)."""
    import qpsolvers

    settings = {} if tolerance is None else SETTINGS[solver](tolerance)
    start = time.perf_counter()
    P, q, G, h, free = reduced_qp(problem)
    solution = qpsolvers.solve_problem(qpsolvers.Problem(P, q, G, h), solver=solver,
                                       **settings)
    seconds = time.perf_counter() - start
    if solution.x is None or solution.z is None:
        return {"seconds": seconds, "verified": False, "why": f"{solver}: no answer",
                "claimed_success": False}
    u = np.zeros(problem.n)
    u[free], u[problem.prescribed] = solution.x, problem.prescribed_values
    found = {"seconds": seconds, "claimed_success": bool(solution.found),
             "contact_force": np.asarray(solution.z)}
    start = time.perf_counter()
    try:
        check = contactqp.check(problem, u, solution.z)
    except contactqp.ContactqpError as error:  # no verdict: not verified
        return {**found, "verified": False, "why": f"the check raised: {error}"[:200]}
    return {**found, "check_seconds": time.perf_counter() - start,
            "verified": bool(check.verified and check.physical), "why": check.message[:200]}


def method(problem: contactqp.Problem, name: str) -> dict[str, Any]:
    """contactqp.solve by one method, end to end (its check included)."""
    start = time.perf_counter()
    name, engine = ENGINES.get(name, (name, "direct"))
    try:
        result = contactqp.solve(problem, name, engine=engine)
    except contactqp.ContactqpError as error:
        return {"refused": str(error)[:200]}
    return {"seconds": time.perf_counter() - start,
            "check_seconds": result.timings.get("check", float("nan")),
            "verified": bool(result.verified and result.physical),
            "claimed_success": bool(result.claimed_success), "why": result.message[:200],
            "iterations": int(result.iterations),
            "contact_force": np.asarray(result.contact_force)}


def run(problem: contactqp.Problem, label: str, floor: Any = None) -> dict[str, Any]:
    """One run, timed as the floor is: the median of as many runs as the first's time asks
    (:func:`repeats_after`; each on a copy of the problem as it came, with nothing of the runs
    before it kept: no model, no factorisation), so that a short run is not judged by its
    first pass through cold caches and fresh pages against a floor that is a median too.
    ``first_seconds``: the first run's time. ``floor`` (the mesh's fastest factor-and-solve,
    a call): timed once before the runs and once after each, in the same process, its median
    ``paired_floor_seconds`` (:func:`measure_case`)."""
    _LOOSEST.clear()  # a tightened peer searches its setting anew on each case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the solvers' own warnings: the check decides
        try:
            floors_seen: list[float] = []
            pair = (lambda: None) if floor is None else (
                lambda: floors_seen.append(seconds_of(floor)))
            pair()
            found = once(copy.copy(problem), label)
            times = [found.get("seconds", math.inf)]
            pair()
            for _ in range(repeats_after(times[0]) - 1):
                times.append(once(copy.copy(problem), label)["seconds"])
                pair()
            if len(times) > 1:
                found = {**found, "first_seconds": times[0],
                         "seconds": statistics.median(times)}
            if floors_seen:
                found["paired_floor_seconds"] = statistics.median(floors_seen)
            return found
        except Exception as error:  # noqa: BLE001 (a crash is a result here, with its reason)
            return {"refused": f"raised {type(error).__name__}: {error}"[:200]}


def once(problem: contactqp.Problem, label: str) -> dict[str, Any]:
    if label in TIGHT:
        return tightened(problem, label.removesuffix("_tight"))
    return peer(problem, label) if label in PEERS else method(problem, label)


_LOOSEST: dict[str, float] = {}  # a tightened peer's loosest verified tolerance, in its run


def tightened(problem: contactqp.Problem, solver: str) -> dict[str, Any]:
    """The peer at the loosest of TIGHTER whose answer the check verifies: searched on the
    run's first pass (``ladder_seconds``), that setting alone on its later passes."""
    if solver in _LOOSEST:
        return {**peer(problem, solver, _LOOSEST[solver]), "tolerance": _LOOSEST[solver]}
    spent = 0.0
    for tolerance in TIGHTER:
        found = peer(copy.copy(problem), solver, tolerance)
        spent += found["seconds"] + found.get("check_seconds", 0.0)
        if found["verified"]:
            _LOOSEST[solver] = tolerance
            break
    return {**found, "tolerance": tolerance, "ladder_seconds": spent}


def isolated(timeout: float, problem: contactqp.Problem, label: str, floor: Any = None
             ) -> dict[str, Any]:
    """run() in a forked child stopped after ``timeout`` s (:func:`cases.in_child`)."""
    try:
        found = in_child(timeout, run, problem, label, floor)
    except EOFError:  # the child died without an answer (a crash in compiled code)
        return {"refused": "the process died"}
    return found or {"skipped": f"time limit: stopped after {timeout:.0f} s"}


def rows_in_contact(force: np.ndarray) -> int:
    """The rows that push: a force above 10⁻⁶ of the largest (contactqp.fem's reading)."""
    return int(np.count_nonzero(force > 1e-6 * force.max(initial=0.0)))


def warm_up(problem: contactqp.Problem) -> None:
    """One call of each run on a small problem, so that no child pays a first import."""
    for label in (*METHODS, *PEERS):
        run(problem, label)
    floors(problem, 1, TIMEOUT[True])


@dataclass
class Progress:
    """What a run carries from case to case: the runs stopped at the time limit in each sweep
    (not started again on its larger cases), each mesh's floors (the rows sweeps' cases share
    a K), and the run's deadline."""

    limit: float  # s: a run is stopped after this long
    deadline: float  # time.perf_counter() past which no run starts
    stopped: set[tuple[str, str]] = field(default_factory=set)
    floors: dict[str, dict[str, float]] = field(default_factory=dict)

    def why_skip(self, case: Case, label: str) -> str | None:
        """Why the run is not started: it was stopped at the time limit on a smaller case of
        the sweep, or the run's budget is spent."""
        if (case.sweep, label) in self.stopped:
            return "time limit: stopped on a smaller case of the sweep"
        if time.perf_counter() > self.deadline:
            return "the run's time budget is spent"
        return None


def measure_case(case: Case, problem: contactqp.Problem, progress: Progress,
                 labels: tuple[str, ...] = (*METHODS, *PEERS)) -> dict[str, Any]:
    """The case's floors and one entry per run."""
    if case.mesh.key not in progress.floors:
        progress.floors[case.mesh.key] = floors(problem, 1 if problem.n > 2e5 else 3,
                                                progress.limit)
    found_floors = progress.floors[case.mesh.key]
    base = min(found_floors.values())
    described = {"sweep": case.sweep, "dimension": case.mesh.dimension, "dofs": problem.n,
                 "free_dofs": int(free_dofs(problem).size), "rows": problem.m,
                 "approach_mm": case.approach, "floors_seconds": found_floors,
                 "floor_seconds": base, "floor": min(found_floors, key=found_floors.get)}
    print(f"{case.sweep}: {problem.n} dofs, {problem.m} rows, δ = {case.approach * 1e3:g} µm, "
          f"floor {base:.3f} s ({described['floor']})", flush=True)
    runs, forces = {}, []
    # a run may take FLOOR_TIMES floors where that is past the limit: the largest meshes'
    # floors alone take tens of seconds
    limit = max(progress.limit, FLOOR_TIMES * base)
    described["timeout_seconds"] = limit
    # the floor again beside each run, in its process (PAIRED_UNDER): the machine's speed
    # drifts by a third over minutes, and the mesh's floor was timed before all its runs
    floor = floor_calls(problem)[described["floor"]] if base < PAIRED_UNDER else None
    for label in labels:
        reason = progress.why_skip(case, label)
        # a peer's limit is on its solve: its check, after, has CHECK_ALLOWANCE more; the
        # paired floors have up to 2 + 9 floors more
        allowed = (limit + (CHECK_ALLOWANCE if label in PEERS else 0.0)
                   + (len(TIGHTER) * (limit + CHECK_ALLOWANCE) if label in TIGHT else 0.0)
                   + (11.0 * base if floor is not None else 0.0))
        found = {"skipped": reason} if reason else isolated(allowed, problem, label, floor)
        if "seconds" in found:
            found["mesh_ratio"] = found["seconds"] / base
            found["ratio"] = found["seconds"] / found.get("paired_floor_seconds", base)
            if found["verified"]:
                forces.append(found["contact_force"])
        elif "time limit" in found.get("skipped", ""):
            progress.stopped.add((case.sweep, label))
        found.pop("contact_force", None)
        runs[label] = found
        print(f"  {line(label, found)}", flush=True)
    described["in_contact"] = rows_in_contact(forces[0]) if forces else None
    described["runs"] = runs
    return described


def line(label: str, found: dict[str, Any]) -> str:
    if "seconds" not in found:
        return f"{label:10s} {found.get('skipped') or 'refused: ' + found['refused']}"
    return (f"{label:10s} {found['seconds']:8.2f} s = {found['ratio']:7.2f} x floor, "
            f"verified {found['verified']}")


def cell(found: dict[str, Any], label: str = "") -> str:
    if "seconds" not in found:
        reason = found.get("skipped") or "refused"
        if "contact rows" in reason:  # a size refusal: say the size
            return "refused (size)"
        return ("time limit" if "time limit" in reason else "not run (budget)"
                if "budget" in reason else reason.split(":")[0])
    sweeps = f" ({found['iterations']:,} sweeps)" if label == "pgs" else ""
    setting = f" at {found['tolerance']:g}" if label in TIGHT else ""
    return f"{found['ratio']:.3g}×" + (" ✓" if found["verified"] else " ✗") + sweeps + setting


def table(cases: list[dict[str, Any]]) -> str:
    """Markdown: one line per case, each run's time over the floor and its verdict."""
    labels = (*METHODS, *PEERS, *(label for label in TIGHT
                                   if any(label in c["runs"] for c in cases)))
    head = ("| sweep | dofs | rows | in contact | floor (s) | "
            + " | ".join(SHORT.get(label, label) for label in labels) + " |")
    lines = [head, "|---" * (5 + len(labels)) + "|"]
    for c in cases:
        lines.append(f"| {c['sweep']} | {c['dofs']:,} | {c['rows']:,} | "
                     f"{c['in_contact'] if c['in_contact'] is not None else '–'} | "
                     f"{c['floor_seconds']:.3g} | "
                     + " | ".join(cell(c["runs"].get(label, {"skipped": "not run"}), label)
                                  for label in labels) + " |")
    return ("\n".join(lines).replace(",", " ") + "\n\nEach cell: time / the floor (the fastest "
            "factor-and-solve of K on the free dofs in the same run; where it takes under "
            f"{PAIRED_UNDER:g} s, timed again in the run's own process, before it and after "
            "each pass); ✓ verified by "
            "contactqp's check, ✗ not verified. contactqp's methods end to end with their "
            "check; Clarabel, OSQP and PIQP from the Problem's arrays to their answer, the "
            "check apart (…_tight: at the loosest of their tolerances 1e-5 … 1e-10 that "
            "verifies, its setting after the time).\n")


COLOURS = {"lagrange": "tab:blue", "lagrange_amg": "tab:pink", "semismooth_newton": "tab:cyan", "pgs": "tab:olive",
           "penalty": "tab:orange", "augmented": "tab:green",
           "qp": "tab:purple", "clarabel": "tab:red", "osqp": "tab:brown", "piqp": "tab:gray",
           "clarabel_tight": "salmon", "osqp_tight": "peru", "piqp_tight": "silver"}


def chart(cases: list[dict[str, Any]], kind: str, path: Path) -> None:
    """Seconds against dofs (kind "dofs") or rows in contact ("rows"), log–log, 2D and 3D
    side by side; filled: verified, hollow: not verified; the floor as a black line."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12.0, 4.4), layout="constrained")
    axes = figure.subplots(1, 2)
    for ax, dimension in zip(axes, (2, 3)):
        chosen = [c for c in cases if c["sweep"] == f"{kind}{dimension}d"
                  and (kind == "dofs" or c["in_contact"])]
        x = [c["dofs"] if kind == "dofs" else c["in_contact"] for c in chosen]
        if not chosen:  # a sweep not run
            ax.axis("off")
            continue
        for label, colour in COLOURS.items():
            points = [(xi, c["runs"][label]) for xi, c in zip(x, chosen)
                      if "seconds" in c["runs"].get(label, {})]
            if not points:
                continue
            ax.plot([p[0] for p in points], [p[1]["seconds"] for p in points], "-",
                    color=colour, lw=1.0, label=label)
            for xi, found in points:
                ax.scatter(xi, found["seconds"], s=30, edgecolors=colour, linewidths=1.2,
                           facecolors=colour if found["verified"] else "none", zorder=3)
        ax.plot(x, [c["floor_seconds"] for c in chosen], "ks-", lw=2.0, ms=4, label="floor")
        ax.set(xscale="log", yscale="log", ylabel="seconds (log)",
               xlabel="dofs" if kind == "dofs" else "rows in contact")
        body = "cylinder" if dimension == 2 else "sphere"
        ax.set_title(f"{dimension}D Hertz {body}: " + (
            "time against dofs, contact fraction fixed" if kind == "dofs" else
            f"time against rows in contact, {chosen[0]['dofs']:,} dofs"), fontsize=9.5)
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    named = {}
    for ax in axes:
        named.update(zip(*reversed(ax.get_legend_handles_labels())))
    figure.legend(named.values(), named.keys(), loc="outside right upper", fontsize=8,
                  title="filled: verified\nhollow: not", title_fontsize=8)
    figure.savefig(path, dpi=110)


def write(cases: list[dict[str, Any]], out: Path) -> None:
    """table.md, time_vs_dofs.png and time_vs_rows.png of the cases, in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(table(cases))
    for kind in ("dofs", "rows"):
        chart(cases, kind, out / f"time_vs_{kind}.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="the smallest cases (< 2 min)")
    parser.add_argument("--out", default="benchmarks/out/scale", help="output folder")
    parser.add_argument("--cache", default="", help="built problems (default OUT/problems)")
    parser.add_argument("--sweeps", default="dofs2d,dofs3d,rows2d,rows3d")
    parser.add_argument("--runs", default=",".join((*METHODS, *PEERS)),
                        help="the runs to make on each case (the others are left out; "
                             "also " + ", ".join(TIGHT) + ")")
    parser.add_argument("--timeout", type=float, default=0.0,
                        help=f"s per run (default {TIMEOUT[False]:g}, --quick {TIMEOUT[True]:g})")
    parser.add_argument("--redraw", default="",
                        help="write the table and charts of this scale.json to OUT, and stop")
    parser.add_argument("--budget", type=float, default=0.0,
                        help=f"s for the whole run (default {BUDGET[False]:g}, --quick "
                             f"{BUDGET[True]:g}): no run starts after it")
    args = parser.parse_args()
    out = Path(args.out)
    if args.redraw:
        write(json.loads(Path(args.redraw).read_text())["cases"], out)
        return
    limit = args.timeout or TIMEOUT[args.quick]
    budget = args.budget or BUDGET[args.quick]
    cache = Path(args.cache) if args.cache else out / "problems"
    sweeps = args.sweeps.split(",")
    start = time.perf_counter()
    wanted = ("both", "quick" if args.quick else "full")
    chosen = [c for c in CASES if c.sweep in sweeps and c.runs_in in wanted]
    warm_up(problem_of(CASES[0], cache))
    progress = Progress(limit, start + budget)
    labels = tuple(label for label in (*METHODS, *PEERS, *TIGHT)
                   if label in args.runs.split(","))
    cases = [measure_case(c, problem_of(c, cache), progress, labels) for c in chosen]
    out.mkdir(parents=True, exist_ok=True)
    document = {"machine": machine(), "quick": args.quick, "timeout_seconds": limit,
                "budget_seconds": budget, "cases": cases}
    (out / "scale.json").write_text(json.dumps(document, indent=1))
    write(cases, out)
    print(table(cases))
    print(f"{len(cases)} cases in {time.perf_counter() - start:.0f} s; written: {out}/scale.json, "
          "table.md, time_vs_dofs.png, time_vs_rows.png")


if __name__ == "__main__":
    main()
