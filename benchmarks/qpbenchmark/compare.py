"""qpbenchmark's verdict against contactqp's, on the same solves of the contactqp test set.

    python benchmarks/qpbenchmark/export.py       # once
    python benchmarks/qpbenchmark/compare.py      # needs qpbenchmark (pip install qpbenchmark)

For every problem, installed solver and qpbenchmark setting (default, low, mid and high
accuracy, with qpbenchmark's own solver parameters and tolerances), the QP is solved once
through qpsolvers, as qpbenchmark solves it, and judged twice:

- qpbenchmark: success when the solver found a solution and its primal residual, dual residual
  and duality gap are all under the setting's tolerances;
- contactqp: the duals read as contact forces (λ = z, or F·z for a scaled problem), the primal
  as displacements (u = x, or U·x), checked by contactqp.check against the scene (verified or
  not), and compared with the exact contact forces (right: within 1e-5 of the scene's F);
  a 2D problem (exact.json names it by ``fem``: export.py builds it again with scikit-fem)
  is checked by contactqp's check for a problem (contactqp.check.on_set) the same way.

Writes results/compare.md: the counts, and every disagreement (a success whose force is wrong,
a failure whose force is right) with its numbers.
"""

from __future__ import annotations

import json
import sys
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
import qpsolvers

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from contactqp_test_set import ContactqpTestSet
from export import fem_problems

import contactqp
from contactqp.check.on_set import check_problem
from contactqp.model import element_forces, link_forces, support_reactions
from contactqp.model.sparse import build_sparse_model

PROBLEMS = HERE / "problems"


def judge(problem_name: str, exact: dict, scene: contactqp.Scene,
          solution: qpsolvers.Solution) -> tuple[bool, bool, float]:
    """(contactqp verified, right, force error / F) of a solution."""
    model = contactqp.build_model(scene)
    if solution.x is None or solution.z is None:
        return False, False, float("inf")
    lam = np.asarray(solution.z, dtype=float) * exact["force_scale"]
    u = model.full_displacements(np.asarray(solution.x, dtype=float)
                                 * exact["displacement_scale"])
    reactions = support_reactions(model.layout, link_forces(model.layout,
                                                            element_forces(model.layout, u)),
                                  lam)
    verdict = contactqp.check(model, u, lam, reactions, "inequality")
    error = float(np.abs(lam - np.asarray(exact["exact_duals"]) * exact["force_scale"]).max(
        initial=0.0)) / verdict.force_scale
    return verdict.verified, error <= contactqp.GUARANTEE[0], error


def judge_problem(exact: dict, problem: contactqp.Problem,
                  solution: qpsolvers.Solution) -> tuple[bool, bool, float]:
    """judge() for a 2D problem: x the free dofs (u = U·x), z the rows' forces (λ = F·z)."""
    if solution.x is None or solution.z is None:
        return False, False, float("inf")
    lam = np.asarray(solution.z, dtype=float) * exact["force_scale"]
    u_free = np.asarray(solution.x, dtype=float) * exact["displacement_scale"]
    verdict = check_problem(build_sparse_model(problem), u_free, lam)
    error = float(np.abs(lam - np.asarray(exact["exact_duals"]) * exact["force_scale"]).max(
        initial=0.0)) / verdict.force_scale
    return verdict.verified, error <= contactqp.GUARANTEE[0], error


def main() -> None:
    test_set = ContactqpTestSet()
    fem: dict[str, contactqp.Problem] | None = None  # the 2D problems, built when first met
    exact_all = json.loads((PROBLEMS / "exact.json").read_text())
    counts: Counter[tuple[bool, bool]] = Counter()
    disagreements = []
    solvers = sorted(test_set.solvers)
    for path in sorted(PROBLEMS.glob("*.npz"), key=lambda p: (p.stat().st_size, p.name)):
        name = path.stem
        exact = exact_all[name]
        if "fem" in exact:  # a 2D problem, built again (its K is not kept twice)
            fem = fem_problems() if fem is None else fem
            source: contactqp.Scene | contactqp.Problem = fem[exact["fem"]]
        else:
            source = contactqp.load_scene(PROBLEMS / f"{exact['scene']}.toml")
        problem = test_set.get_problem(name)  # as qpbenchmark hands it to each solver
        for solver in solvers:
            # converted for this solver only (qpbenchmark.utils.time_solve_problem): PIQP and
            # ProxQP pick their dense or sparse backend from the matrices they are given
            sparse_only = solver in qpsolvers.sparse_solvers and solver not in qpsolvers.dense_solvers
            qp = problem.to_sparse() if sparse_only else problem
            for settings, tolerance in test_set.tolerances.items():
                kwargs = test_set.solver_settings[settings][solver]
                if test_set.skip_solver_timeout(tolerance.runtime, qp, solver, settings):
                    counts[False, False] += 1  # a known timeout: a failure, with no force
                    continue
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        solution = qpsolvers.solve_problem(qp, solver=solver, **kwargs)
                    except Exception as error:  # noqa: BLE001 (qpbenchmark counts a failure)
                        solution = qpsolvers.Solution(qp)
                        solution.found = False
                        solution.extras = {"error": str(error)}
                residuals = [solution.primal_residual(), solution.dual_residual(),
                             solution.duality_gap()]
                success = bool(solution.found) and all(
                    r is not None and np.isfinite(r) and r < t for r, t in
                    zip(residuals, (tolerance.primal, tolerance.dual, tolerance.gap)))
                verified, right, error = (
                    judge_problem(exact, source, solution)
                    if isinstance(source, contactqp.Problem)
                    else judge(name, exact, source, solution))
                counts[success, right] += 1
                if success != right or verified != right:
                    disagreements.append((name, solver, settings, success, verified, right,
                                          error, residuals))
    lines = ["# qpbenchmark's success against contactqp's contact force", "",
             "| qpbenchmark | contact force | runs |", "|---|---|---|"]
    for (success, right), n in sorted(counts.items(), reverse=True):
        lines.append(f"| {'success' if success else 'failure'} | "
                     f"{'right' if right else 'wrong'} | {n} |")
    lines += ["", ("Every run where qpbenchmark's success and the force's rightness disagree "
              "(or contactqp's check disagrees with the force):"), "",
              ("| problem | solver | settings | qpbenchmark | contactqp check | force error / F "
              "| primal, dual residual, gap |"), "|---|---|---|---|---|---|---|"]
    for name, solver, settings, success, verified, right, error, residuals in disagreements:
        shown = ", ".join("–" if r is None else f"{r:.1e}" for r in residuals)
        lines.append(f"| {name} | {solver} | {settings} | "
                     f"{'success' if success else 'failure'} | "
                     f"{'verified' if verified else 'flagged'} | {error:.1e} | {shown} |")
    out = HERE / "results" / "compare.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:8]))
    print(f"{len(disagreements)} disagreements written to {out}")


if __name__ == "__main__":
    main()
