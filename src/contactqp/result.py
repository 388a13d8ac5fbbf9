"""The Result of a solve: what a method returns (a :class:`Solution`: u and λ), every other
quantity derived from those two alone, the same way for every method, and the independent
check (:mod:`contactqp.check`) beside what the solver itself claimed."""

from __future__ import annotations

import dataclasses
import html
import json
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from contactqp import formatting
from contactqp.check import GUARANTEE, TOLERANCES, Check, Tolerances, check_model
from contactqp.check.chain import chain_bounds, sized
from contactqp.methods.base import Solution
from contactqp.model import (
    ContactModel,
    Layout,
    element_forces,
    link_forces,
    penetration,
    support_reactions,
)
from contactqp.scene import Scene

TOUCHING = 1e-12  # a penetration within this of U is round-off: the contact touches


class Reported:
    """What a scene's Result and a problem's (:class:`~contactqp.ProblemResult`) say alike:
    the label, the verdict, JSON. Needs ``method``, ``solver``, ``verified``, ``physical``
    and ``to_dict``."""

    @property
    def label(self) -> str:
        """method (and solver where it says more), e.g. 'penalty' or 'qp/osqp'."""
        return self.method if self.solver == self.method else f"{self.method}/{self.solver}"

    def _verdict(self) -> str:
        return ("verified" if self.verified else "NOT verified") + (
            "" if self.physical else ", a contact pulls")

    def to_json(self, indent: int | None = 2) -> str:
        """:meth:`to_dict` as JSON text (no NaN: a non-finite number is null)."""
        return json.dumps(self.to_dict(), indent=indent, allow_nan=False)


def claim_warnings(solution: Solution, verified: bool) -> list[str]:
    """A solver that claimed success where the check fails: the line that says so."""
    if solution.claimed_success and not verified:
        return [f"{solution.solver} reported {solution.status!r} but the check failed"]
    return []


@dataclass(frozen=True, eq=False)
class Result(Reported):
    """Everything one solve found, in physical words, with its independent check: the same
    Result for a bar scene and for a user's own model (a :class:`~contactqp.Problem`); what
    only bars have (element forces, stresses) is there where the model has it, None
    elsewhere.

    Attributes
    ----------
    u : the displacement of every node (a scene: bar after bar, supports included) or every dof
        (a problem: the prescribed ones at their values).
    contact_force : one per contact row, positive when the row pushes (acts as −Cᵀλ); a
        scene's rows are its walls in scene order, then its bar contacts.
    reactions : one per support (a scene, in scene order, +x) or prescribed dof (a problem):
        the force it applies.
    penetration : C u − g per row, positive past the gap.
    element_force, stress : a scene's: the axial force and stress of each element, bar after
        bar, tension positive (None for a problem).
    stress_ratio : largest abs(stress) over the yield stress (None without a yield stress or
        a bar).
    model : the model solved (``scene``, ``layout``: a scene's; ``problem``: a problem's).
    residuals, verified, physical, message : the independent check (:func:`contactqp.check`).
    force_error_bound : every contact force and reaction is within this of the exact answer
        (force units).
    displacement_error_bound : every displacement is within this of the exact answer.
    force_scale, displacement_scale : F and U, the model's scales the residuals and the
        guarantee are relative to (:mod:`contactqp.model.base`).
    status, claimed_success, iterations : what the method said, recorded and not trusted.
    time : wall time of the whole solve (s); timings splits it into build (the model), solve
        (the method) and check (this Result's quantities and its check).
    info : what the method reported beyond u and λ (e.g. a QP's scales and the solver's own
        timings; in the strain formulation ``element_force``, the tie rows' multipliers).
    friction : "tresca" or "coulomb" for a problem with friction (None without; then the four
        below are None too).
    friction_force : m x d, per contact the friction force λ_T (force), acting on the dofs as
        −Tᵀλ_T: along the slip, so that on the body it opposes it.
    slip : m x d, T(u − u_prev): the slip of this increment (length).
    stick : per contact, True where it does not slip in this increment.
    state : per contact "open", "stick" or "slip".
    """

    model: ContactModel
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
    element_force: np.ndarray | None = None
    stress: np.ndarray | None = None
    stress_ratio: float | None = None
    friction: str | None = None
    friction_force: np.ndarray | None = None
    slip: np.ndarray | None = None
    stick: np.ndarray | None = None
    state: np.ndarray | None = None

    @property
    def scene(self) -> Scene | None:
        """The scene solved (None for a problem)."""
        return self.model.scene if self.model.layout is not None else None

    @property
    def layout(self) -> Layout | None:
        """The scene's numbering and arrays (:class:`~contactqp.model.Layout`; None for a
        problem)."""
        return self.model.layout

    @property
    def problem(self) -> Any:
        """The user's problem solved (None for a scene)."""
        return getattr(self.model, "problem", None)

    @property
    def names(self) -> tuple[str, ...]:
        """Each contact row's name."""
        return self.model.row_names

    def _units(self) -> tuple[str, str]:
        force, length = self.model.units
        return (f" {force}" if force else ""), (f" {length}" if length else "")

    def __repr__(self) -> str:
        """One line: method, contact, verdict, the largest contact force."""
        return f"<Result {self.label}, {self.contact} contact, {self._verdict()}, {self._largest()}>"

    def _largest(self) -> str:
        """'largest contact force 175870.4536 N on wall[0]' (or 'no contacts')."""
        if not self.contact_force.size:
            return "no contacts"
        i = formatting.largest_entry(self.contact_force)
        return (f"largest contact force {formatting.force(self.contact_force[i], self.force_scale)}"
                f"{self._units()[0]} on {self.names[i]}")

    def _guarantee(self) -> str:
        """What ``verified`` says of this answer, or why it is not verified."""
        force, length = self._units()
        if not self.verified:
            return f"NOT verified: {self.message}"
        if self.friction is not None:
            return f"verified: {self.message}"
        return (f"verified: every contact force and reaction is within "
                f"{formatting.number(self.force_error_bound, '.1e')}{force}, every "
                f"displacement within {formatting.number(self.displacement_error_bound, '.1e')}"
                f"{length} of the exact answer (the check's bounds; at most "
                f"{GUARANTEE[0]:.0e}·F and {GUARANTEE[1]:.0e}·U, F = "
                f"{formatting.number(self.force_scale, '.4g')}{force}, U = "
                f"{formatting.number(self.displacement_scale, '.4g')}{length})")

    def _forces(self, most: int = 8) -> str:
        """The contact forces that carry force (more than 1e-5·F), the largest first, at most
        ``most`` of them."""
        return formatting.carrying_forces(self.contact_force, self.names, self.force_scale,
                                          most)

    def _penetration(self) -> str:
        i = int(np.argmax(self.penetration))
        depth = formatting.number(self.penetration[i], ".3g")
        touching = abs(self.penetration[i]) <= TOUCHING * self.displacement_scale
        state = "touching" if touching else ("past its gap" if self.penetration[i] > 0 else "open")
        return f"{depth}{self._units()[1]} at {self.names[i]} ({state})"

    def _what(self) -> str:
        """The first line of the summary: the scene, or the problem and its size."""
        if self.scene is not None:
            return f"scene: {self.scene.name} ({self.scene.units})"
        problem = self.problem
        units = f", {problem.units}" if problem.units else ""
        friction = (f", {problem.friction} friction on {problem.contacts} contacts"
                    if self.friction is not None else "")
        return (f"problem: {problem.name or 'unnamed'} ({problem.n} dofs, {problem.m} contact "
                f"rows, {problem.prescribed.size} prescribed{friction}{units})")

    def _reactions(self) -> str:
        force, _ = self._units()
        if self.scene is not None:
            return (f"support reactions{force and ' (' + force.strip() + ')'}: " + ", ".join(
                f"support[{i}] {formatting.force(r, self.force_scale)}"
                for i, r in enumerate(self.reactions)))
        return (f"reactions: total {formatting.force(float(self.reactions.sum()), self.force_scale)}"
                f"{force} over {self.reactions.size} prescribed dofs")

    def summary(self) -> str:
        """A few lines a person reads: the scene or problem, the method, whether the answer is
        verified and what that guarantees, the contact forces, the largest penetration, the
        reactions, the residuals and the warnings (stress beyond yield)."""
        force, _ = self._units()
        residuals = ", ".join(f"{name.replace('_', ' ')} {formatting.number(value, '.1e')}"
                              for name, value in self.residuals.items() if value is not None)
        lines = [self._what(),
                 f"method: {self.label}, {self.contact} contact, {1e3 * self.time:.2f} ms",
                 self._guarantee()]
        if self.contact_force.size:
            lines += [f"contact forces{force and ' (' + force.strip() + ')'}: {self._forces()}",
                      f"largest penetration: {self._penetration()}"]
        if self.friction is not None:
            from contactqp.friction.answer import friction_lines  # scipy.linalg on first use

            lines += friction_lines(self.friction, self.state, self.friction_force, self.slip,
                                    force.strip(), self._units()[1].strip())
        if self.reactions.size:
            lines.append(self._reactions())
        lines.append(f"residuals (of F and U): {residuals}")
        if not self.physical:
            lines.append("non-physical: a contact pulls (the negative forces above), which a "
                         "rigid wall cannot; equality contact holds each row on its gap")
        lines += [f"warning: {w}" for w in self.warnings]
        return formatting.wrap("\n".join(lines))

    def _repr_html_(self) -> str:
        """A small table for notebooks: the summary's numbers, one row each."""
        force, _ = self._units()
        what = self.scene.name if self.scene is not None else (self.problem.name or "unnamed")
        rows = [("scene" if self.scene is not None else "problem", what),
                ("method", f"{self.label}, {self.contact} contact"),
                ("verified", self._verdict()), ("contact force", self._largest()),
                ("largest residual", formatting.number(max(
                    (v for v in self.residuals.values() if v is not None), default=0.0), ".1e")),
                ("force error bound", f"{formatting.number(self.force_error_bound, '.1e')}{force}"),
                ("time", f"{1e3 * self.time:.2f} ms")]
        if self.contact_force.size:
            rows.insert(4, ("largest penetration", self._penetration()))
        rows += [("warning", w) for w in self.warnings]
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                       f"<td style='text-align:left'>{html.escape(v)}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (plain floats and lists): "scene" and "units" name a scene,
        "problem" and "units" a problem; "element_force", "stress" and "stress_ratio" where
        the model has bars."""
        if self.scene is not None:
            named = {"scene": self.scene.name, "units": self.scene.units}
        else:
            named = {"problem": self.problem.name, "units": self.problem.units}
        bars = ({"element_force": plain(self.element_force), "stress": plain(self.stress),
                 "stress_ratio": self.stress_ratio} if self.element_force is not None else {})
        if self.friction is not None:
            bars.update(friction=self.friction, friction_force=plain(self.friction_force),
                        slip=plain(self.slip), stick=plain(self.stick),
                        state=plain(self.state))
        return {
            **named, "method": self.method, "solver": self.solver,
            "contact": self.contact, "options": plain(self.options),
            "u": plain(self.u), "contact_force": plain(self.contact_force),
            "reactions": plain(self.reactions), "penetration": plain(self.penetration),
            **bars, "residuals": plain(self.residuals),
            "verified": self.verified, "physical": self.physical, "message": self.message,
            "force_error_bound": plain(self.force_error_bound),
            "displacement_error_bound": plain(self.displacement_error_bound),
            "force_scale": self.force_scale, "displacement_scale": self.displacement_scale,
            "status": self.status, "claimed_success": self.claimed_success,
            "iterations": self.iterations, "time": self.time, "timings": plain(self.timings),
            "warnings": list(self.warnings), "info": plain(self.info),
        }


ProblemResult = Result  # its former name, for one release (the CHANGELOG says so)


def plain(value: Any) -> Any:
    """numpy → Python, non-finite floats → None (JSON has no NaN): every JSON contactqp writes
    goes through this."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    return value


def yield_warning(layout: Layout, stress: np.ndarray) -> tuple[float | None, list[str]]:
    """(largest |stress| / yield stress or None, the warning when it exceeds 1)."""
    yield_stress = layout.yield_stress
    if yield_stress is None:
        return None, []
    scene = layout.scene
    yields = {b.yield_stress for b in scene.bars}
    ratios = None
    if len(yields) == 1 and stress.size:  # every bar the same: two reductions, no |σ| array
        # (x/y is monotone in x, so the largest |σ| over y is the largest |σ|/y, bit for bit)
        ratio = max(float(np.fmax.reduce(stress)), -float(np.fmin.reduce(stress))) / yields.pop()
    else:
        ratios = np.abs(stress)
        ratio = float(np.fmax.reduce(np.divide(ratios, yield_stress, out=ratios)))
    if not ratio > 1.0:
        return ratio, []
    if ratios is None:  # only a warning needs the element
        ratios = np.abs(stress) / yield_stress
    e = int(np.flatnonzero(ratios == ratio)[0])  # nanargmax's element, without its NaN pass
    where = f"element {e}"
    if len(scene.bars) > 1:
        start = int(layout.elements[0][e])  # the element's first node, in global numbering
        bar = int(layout.node_bar[start])
        where = f"bar[{bar}] element {start - int(layout.node_offsets[bar])}"
    megapascal = scene.unit.pascal / 1e6  # MPa is a unit of SI and of mm-N-MPa alike
    warning = (f"stress beyond yield: {where} carries {stress[e] * megapascal:.1f} MPa, "
               f"{ratio:.2f} x the yield stress {yield_stress[e] * megapascal:.0f} MPa (a "
               "linear-elastic answer past yield)")
    return ratio, [warning]


@dataclass(frozen=True)
class Checked:
    """A solution's answer at every node or dof and its check (:func:`checked`): u, λ, the
    element forces (None without bars), the reactions, the penetration of every row, and the
    Check."""

    u: np.ndarray
    contact_force: np.ndarray
    element_force: np.ndarray | None
    reactions: np.ndarray
    penetration: np.ndarray
    check: Check


def checked(model: ContactModel, solution: Solution, contact: str,
            tolerances: Tolerances = TOLERANCES, natural: bool = True) -> Checked:
    """Derive every quantity from u and λ of a solution, then check it (``natural``: with the
    natural-map residual, :func:`contactqp.check.check_model`)."""
    lam = np.asarray(solution.contact_force, dtype=float).reshape(-1)
    if model.layout is None:  # no chain: the general certificate alone
        u_free = np.asarray(solution.u_free, dtype=float).reshape(-1)
        found = check_model(model, u_free, lam, contact, tolerances, natural=natural)
        u = model.full_displacements(u_free)
        pen = model.C @ u_free - model.g if found.penetration is None else found.penetration
        return Checked(u, lam, None, model.reactions_of(u, lam), pen, found)
    layout = model.layout
    u = solution.u_nodes
    if u is None or u.shape != (layout.n_nodes,):
        u = model.full_displacements(np.asarray(solution.u_free, dtype=float))
    forces = element_forces(layout, u)
    # reactions are what equilibrium at the supports needs (the force of the elements on each
    # side, less loads and contacts there); the check then tests every section of every bar
    links = link_forces(layout, forces)
    reactions = support_reactions(layout, links, lam)
    model, u, lam, reactions = sized(model, u, lam, reactions)
    u_free = model.free_part(u)
    found = check_model(model, u_free, lam, contact, tolerances, natural=natural,
                        chain=lambda pen: chain_bounds(model, u, lam, reactions, contact,
                                                       tolerances, forces, links, pen),
                        imbalance=model.largest_imbalance(u_free, lam, links))
    pen = penetration(layout, u) if found.penetration is None else found.penetration
    return Checked(u, lam, forces, reactions, pen, found)


def stresses(layout: Layout, forces: np.ndarray) -> tuple[np.ndarray, float | None, list[str]]:
    """(each element's stress, the largest |stress| / yield stress or None, the warning where
    it passes 1) of the element forces."""
    stress = forces / layout.areas
    ratio, warnings = yield_warning(layout, stress)
    return stress, ratio, warnings


def with_bar_quantities(result: Result, layout: Layout) -> Result:
    """``result`` (of a scene solved as its problem: a frictional bed) with the bar quantities
    its u gives: each element's force k_e (u_(e+1) − u_e) and stress, and the warning where a
    stress passes yield. The problem's dofs are the scene's nodes, in its numbering."""
    forces = element_forces(layout, result.u)
    stress, ratio, warnings = stresses(layout, forces)
    return dataclasses.replace(result, element_force=forces, stress=stress, stress_ratio=ratio,
                               warnings=result.warnings + tuple(warnings))


def make_result(model: ContactModel, solution: Solution, *, method: str, contact: str,
                options: dict[str, Any], timings: dict[str, float],
                tolerances: Tolerances = TOLERANCES) -> Result:
    """Build the Result of a solution: derive every quantity from u and λ, then check it."""
    start = time.perf_counter()
    done = checked(model, solution, contact, tolerances)
    found, forces = done.check, done.element_force
    stress, ratio, warnings = (None, None, []) if forces is None else stresses(model.layout,
                                                                             forces)
    timings = {**timings, "check": time.perf_counter() - start}
    warnings += claim_warnings(solution, found.verified)
    return Result(
        model=model, method=method, solver=solution.solver, contact=contact,
        options=dict(options), u=done.u, contact_force=done.contact_force,
        reactions=done.reactions, penetration=done.penetration, element_force=forces,
        stress=stress, stress_ratio=ratio, residuals=found.residuals, verified=found.verified,
        physical=found.physical, message=found.message,
        force_error_bound=found.force_error_bound,
        displacement_error_bound=found.displacement_error_bound,
        force_scale=found.force_scale, displacement_scale=found.displacement_scale,
        status=solution.status, claimed_success=solution.claimed_success,
        iterations=solution.iterations, time=sum(timings.values()), timings=timings,
        warnings=tuple(warnings), info=dict(solution.info),
    )


__all__ = ["Checked", "ProblemResult", "Reported", "Result", "Solution", "checked",
           "claim_warnings", "make_result", "plain", "with_bar_quantities"]
