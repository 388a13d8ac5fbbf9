"""The Result of a user's problem: the same words as a scene's Result (u, contact_force,
reactions, penetration, the check, ``summary()``, ``to_json()``), without what only bars have
(element forces, stresses)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from contactqp import formatting
from contactqp.check import GUARANTEE, TOLERANCES, Tolerances
from contactqp.model.sparse import SparseModel
from contactqp.problem import Problem
from contactqp.problem_check import check_problem
from contactqp.result import TOUCHING, Reported, Solution, claim_warnings, plain


@dataclass(frozen=True, eq=False)
class ProblemResult(Reported):
    """Everything one solve of a :class:`~contactqp.Problem` found, with its independent check
    (:mod:`contactqp.problem_check`).

    Attributes
    ----------
    u : every dof's displacement (the prescribed ones at their values).
    contact_force : one per row of C, positive when the row pushes (acts as −Cᵀλ).
    reactions : one per prescribed dof: the force its support applies, (K u − f) there.
    penetration : C u − g per row, positive past the gap.
    residuals, verified, physical, message, force_error_bound, displacement_error_bound,
    force_scale, displacement_scale : the check, as for a scene (docs/howto/check.md).
    status, claimed_success, iterations : what the method said, recorded and not trusted.
    time, timings : wall time (s), split into build (the model: condensing and factorising
        K), solve (the method) and check.
    """

    problem: Problem
    model: SparseModel
    method: str
    solver: str
    contact: str
    options: dict[str, Any]
    u: np.ndarray
    contact_force: np.ndarray
    reactions: np.ndarray
    penetration: np.ndarray
    residuals: dict[str, float | None]
    verified: bool
    physical: bool
    message: str
    force_error_bound: float
    displacement_error_bound: float
    force_scale: float
    displacement_scale: float
    status: str
    claimed_success: bool
    iterations: int
    time: float
    timings: dict[str, float]
    warnings: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)

    def __repr__(self) -> str:
        return (f"<ProblemResult {self.label}, {self.contact} contact, {self._verdict()}, "
                f"{int(np.count_nonzero(formatting.carrying(self.contact_force, self.force_scale)))}"
                f" of {self.contact_force.size} rows push>")

    def _guarantee(self) -> str:
        if not self.verified:
            return f"NOT verified: {self.message}"
        units = f" ({self.problem.units})" if self.problem.units else ""
        return (f"verified: every contact force and reaction is within "
                f"{formatting.number(self.force_error_bound, '.1e')}, every displacement within "
                f"{formatting.number(self.displacement_error_bound, '.1e')} of the exact answer"
                f"{units} (measured against the exact answer on its contact set; at most "
                f"{GUARANTEE[0]:.0e}·F and {GUARANTEE[1]:.0e}·U, F = "
                f"{formatting.number(self.force_scale, '.4g')}, U = "
                f"{formatting.number(self.displacement_scale, '.4g')})")

    def _penetration(self) -> str:
        i = int(np.argmax(self.penetration))
        touching = abs(self.penetration[i]) <= TOUCHING * self.displacement_scale
        state = "touching" if touching else ("past its gap" if self.penetration[i] > 0 else "open")
        return f"{formatting.number(self.penetration[i], '.3g')} at {self.problem.names[i]} ({state})"

    def summary(self) -> str:
        """A few lines a person reads: the problem, the method, the verdict and what it
        guarantees, the contact forces, the largest penetration, the residuals."""
        problem = self.problem
        residuals = ", ".join(f"{name.replace('_', ' ')} {formatting.number(value, '.1e')}"
                              for name, value in self.residuals.items() if value is not None)
        units = f", {problem.units}" if problem.units else ""
        lines = [(f"problem: {problem.name or 'unnamed'} ({problem.n} dofs, {problem.m} contact "
                  f"rows, {problem.prescribed.size} prescribed{units})"),
                 f"method: {self.label}, {self.contact} contact, {1e3 * self.time:.2f} ms",
                 self._guarantee()]
        if self.contact_force.size:
            lines += [f"contact forces: {self._forces()}",
                      f"largest penetration: {self._penetration()}"]
        if self.reactions.size:
            lines.append(f"reactions: total {formatting.force(float(self.reactions.sum()), self.force_scale)}"
                         f" over {self.reactions.size} prescribed dofs")
        lines.append(f"residuals (of F and U): {residuals}")
        lines += [f"warning: {w}" for w in self.warnings]
        return formatting.wrap("\n".join(lines))

    def _forces(self, most: int = 6) -> str:
        return formatting.carrying_forces(self.contact_force, self.problem.names,
                                          self.force_scale, most)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (plain floats and lists; the keys of a scene's Result that
        apply to a problem)."""
        return {
            "problem": self.problem.name, "units": self.problem.units, "method": self.method,
            "solver": self.solver, "contact": self.contact, "options": plain(self.options),
            "u": plain(self.u), "contact_force": plain(self.contact_force),
            "reactions": plain(self.reactions), "penetration": plain(self.penetration),
            "residuals": plain(self.residuals), "verified": self.verified,
            "physical": self.physical, "message": self.message,
            "force_error_bound": plain(self.force_error_bound),
            "displacement_error_bound": plain(self.displacement_error_bound),
            "force_scale": self.force_scale, "displacement_scale": self.displacement_scale,
            "status": self.status, "claimed_success": self.claimed_success,
            "iterations": self.iterations, "time": self.time, "timings": plain(self.timings),
            "warnings": list(self.warnings), "info": plain(self.info),
        }


TABLE_HEADER = [("method", ""), ("contact", ""), ("contact force", "(largest)"),
                ("penetration", "(largest)"), ("residual", ""), ("verified", ""),
                ("time", "(ms)"), ("note", "")]


def problem_table(results: list[ProblemResult]) -> str:
    """One row per result, the columns of the scenes' table that a problem has (no exact
    reference column: a problem's check measures its own distance to the exact answer)."""
    rows = []
    for r in results:
        forces = formatting.forces_summary(r.contact_force, r.force_scale)
        largest = max((v for v in r.residuals.values() if v is not None), default=0.0)
        rows.append([r.label, r.contact, forces,
                     formatting.number(float(np.max(r.penetration, initial=0.0)), ".3g"),
                     formatting.number(largest, ".1e"), "yes" if r.verified else "NO",
                     f"{1e3 * r.time:.2f}", "" if r.verified else r.message[:60]])
    return formatting.text_table(TABLE_HEADER, rows)


def make_problem_result(model: SparseModel, solution: Solution, *, method: str, contact: str,
                        options: dict[str, Any], timings: dict[str, float],
                        tolerances: Tolerances = TOLERANCES) -> ProblemResult:
    """The Result of a solution: every quantity from u and λ, then the check."""
    start = time.perf_counter()
    u_free = np.asarray(solution.u_free, dtype=float).reshape(-1)
    lam = np.asarray(solution.contact_force, dtype=float).reshape(-1)
    found = check_problem(model, u_free, lam, contact, tolerances)
    u = model.full_displacements(u_free)
    timings = {**timings, "check": time.perf_counter() - start}
    warnings = claim_warnings(solution, found.verified)
    return ProblemResult(
        problem=model.problem, model=model, method=method, solver=solution.solver,
        contact=contact, options=dict(options), u=u, contact_force=lam,
        reactions=model.reactions(u), penetration=model.problem.C @ u - model.g,
        residuals=found.residuals, verified=found.verified, physical=found.physical,
        message=found.message, force_error_bound=found.force_error_bound,
        displacement_error_bound=found.displacement_error_bound,
        force_scale=found.force_scale, displacement_scale=found.displacement_scale,
        status=solution.status, claimed_success=solution.claimed_success,
        iterations=solution.iterations, time=sum(timings.values()), timings=timings,
        warnings=tuple(warnings), info=dict(solution.info))


__all__ = ["ProblemResult", "make_problem_result", "problem_table"]
