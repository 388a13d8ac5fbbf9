"""Many cases of one prepared scene, solved and checked together (:meth:`Prepared.solve_many`).

A batch of cases is one scene: the prepared scene's bars repeated once per case, each copy
with its case's load values and gaps (:func:`tiled_scene`). Its exact answer is every case's
exact answer side by side, so it is checked as any scene is, by the one check
(:mod:`contactqp.check`), in one pass over all the cases.

- **Solving.** Lagrange multipliers and the penalty, with few contact rows
  (:func:`contactqp.methods.load_cases.fits`), solve every case at once from one factorisation of
  K (:mod:`contactqp.methods.load_cases`). Every other method, and a scene with many contact rows,
  is solved case by case, each case a :meth:`Prepared.solve`.
- **Each case's verdict.** The check of the whole batch bounds the error of every force and
  displacement of every case by one number each (N and m) and gives each residual as one
  largest value. A case is verified when these, measured against its own force and
  displacement scales F and U (the same rule as :attr:`contactqp.model.Model.force_scale`),
  are within :data:`contactqp.check.TOLERANCES` (with 0.1 % to spare, for the round-off of
  sums over the other cases): then its error is within its own guarantee. Any other case is
  checked alone (:meth:`Batch.__getitem__`); if that fails too, or its active set did not
  settle, it is solved again on its own (a single-case solve that raises leaves the batch's
  answer, flagged, and the error in :attr:`Batch.failures`). So :attr:`Batch.residuals` are,
  for the cases verified together, the batch's largest residuals in the case's own scales (at
  least the case's own, up to that round-off: 1e-9); ``batch[i]`` is case i's Result, checked
  alone, with its own residuals.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from contactqp.check import TOLERANCES, natural_map
from contactqp.errors import ContactqpError, SceneError, SolverError
from contactqp.methods import load_cases as many
from contactqp.methods.base import Solution
from contactqp.model import (
    Model,
)
from contactqp.model.base import ScaleTerms, displacement_scale, force_scale
from contactqp.model.chain import layout_of
from contactqp.progress import Progress
from contactqp.result import Checked, Result, checked, make_result
from contactqp.scene import Scene
from contactqp.scene.scene import side_by_side

# a contactqp.many.prepared.Prepared: read here (its scene, model, method and options), never
# imported, since it imports this module to solve its batches
Prepared = Any

SPARE = 0.999  # a case verified together has its residuals within this × the tolerances


def tiled_scene(scene: Scene, cases: int) -> Scene:
    """``scene`` repeated ``cases`` times as one scene
    (:func:`contactqp.scene.scene.side_by_side`): the copies' bars one after another, each
    copy's supports, loads, walls and bar contacts on its own bars (all the copies' walls, one
    :class:`Walls` read as arrays, then all their bar contacts, case after case)."""
    return side_by_side(scene, cases)


def tiled_values(scene: Scene, loads: np.ndarray, gaps: np.ndarray) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """The tiled scene's load values and gaps (:meth:`Scene.with_values` order) from the
    cases' (cases x loads, cases x gaps, each in the prepared scene's order)."""
    points, walls = len(scene.loads), len(scene.walls)
    return (np.concatenate((loads[:, :points].ravel(), loads[:, points:].ravel())),
            np.concatenate((gaps[:, :walls].ravel(), gaps[:, walls:].ravel())))


def per_case_rows(values: np.ndarray, walls: int, cases: int) -> np.ndarray:
    """A tiled scene's per-row values (all walls, then all bar contacts) as cases x rows."""
    return np.hstack((values[: walls * cases].reshape(cases, walls),
                      values[walls * cases:].reshape(cases, -1)))


def tiled_rows(values: np.ndarray, walls: int) -> np.ndarray:
    """cases x rows back to the tiled scene's row order (:func:`per_case_rows`)."""
    return np.concatenate((values[:, :walls].ravel(), values[:, walls:].ravel()))


def case_scales(model: Model, cases: int, free_displacement: np.ndarray, gaps: np.ndarray,
                flexibility: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F, U) of every case of a tiled model (:meth:`Prepared.tiled`: every case's rows
    with the case's own row stiffness), by the one rule of
    :mod:`contactqp.model.base` (``free_displacement`` per case: cases x free nodes; ``gaps``
    cases x rows), each term reduced over the case's own entries; and the tiled model's own F
    and U set by the same rule from the largest of every case's terms (the rule takes maxima:
    they are the tiled model's own, bit for bit, but for λ₀, whose step is per case). A batch
    holds no bar without a support (:func:`contactqp.methods.load_cases.fits`).
    ``flexibility``: W = C K⁻¹ Cᵀ of one case (the prepared model's), which gives each case's
    (Sp)ᵀW(Sp) without a solve."""
    layout, walls = model.layout, len(model.scene.walls) // cases
    largest = partial(many.row_reduce, np.maximum, initial=0.0)  # each case's largest
    # C u₀ − g, bit for bit the penetration of u₀ at every node (a support's 0 adds nothing)
    passed = model.C_times(free_displacement.ravel())
    passed -= model.g
    np.maximum(passed, 0.0, out=passed)
    weighted = passed * model.row_stiffness
    each = per_case_rows(weighted, walls, cases)
    flex = np.einsum("ci,ij,cj->c", each, flexibility, each)  # (Sp)ᵀW(Sp) of each case
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(flex > 0.0, per_case_rows(passed * weighted, walls, cases).sum(axis=1)
                      / flex, 0.0)
    contact = largest(np.abs(each)) * mu
    reactions = (layout.bar_loads if model.determinate is not None  # a bar's one support
                 else model.reactions_of(model.full_displacements(free_displacement.ravel()),
                                         np.zeros(model.n_contacts))).reshape(cases, -1)
    terms = {"loads": largest(np.abs(layout.nodal_loads.reshape(cases, -1))),
             "reactions": largest(np.abs(reactions)), "contact": contact,
             "unbalanced": np.zeros(cases), "free": largest(np.abs(free_displacement)),
             "passed": largest(per_case_rows(passed, walls, cases)),
             "widest": largest(gaps), "size": float(layout.longest_bar),
             "softest": float(model.band[0].min(initial=np.inf)) if model.band.size else 0.0}
    # the rule on every case at once (its terms numbers or arrays, one entry per case)
    per_case = ScaleTerms(**terms)
    U = np.array(np.broadcast_to(displacement_scale(per_case), (cases,)), dtype=float)
    F = np.array(np.broadcast_to(force_scale(per_case, U), (cases,)), dtype=float)
    arrays = [k for k, v in terms.items() if not isinstance(v, float)]
    tops = np.maximum.reduce([terms[k] for k in arrays], axis=1)  # NaN where a case's is
    whole = ScaleTerms(**{**terms, **dict(zip(arrays, tops.tolist()))})
    model.__dict__["_terms"] = whole
    model.__dict__["displacement_scale"] = U_all = float(displacement_scale(whole))
    model.__dict__["force_scale"] = float(force_scale(whole, U_all))
    return F, U


@dataclass(frozen=True, eq=False)
class Batch:
    """Many cases of a prepared scene (module docstring), one row per case in every array;
    ``batch[i]`` is case i's :class:`~contactqp.result.Result`.

    Attributes
    ----------
    u : cases x nodes (displacement). contact_force : cases x contact rows (force).
    reactions : cases x supports (force). penetration : cases x contact rows (length; > 0:
    past the wall). verified, physical : per case. residuals : each residual of the check per
    case (NaN where a contact kind has none). force_error_bound, displacement_error_bound,
    force_scale, displacement_scale : per case (force, length). iterations : per case.
    alone : the cases checked on their own (case -> its Result: the batch's answer or, where
    that failed, the case solved again alone; every case where the method does not solve
    cases together). failures : the cases whose single-case solve raised (case -> the error).
    time : the batch's seconds.
    """

    prepared: Prepared = field(repr=False)
    loads: np.ndarray | None = field(repr=False)
    gaps: np.ndarray | None = field(repr=False)
    u: np.ndarray
    contact_force: np.ndarray
    reactions: np.ndarray
    penetration: np.ndarray
    verified: np.ndarray
    physical: np.ndarray
    residuals: dict[str, np.ndarray]
    force_error_bound: np.ndarray
    displacement_error_bound: np.ndarray
    force_scale: np.ndarray
    displacement_scale: np.ndarray
    iterations: np.ndarray
    solver: str
    alone: dict[int, Result] = field(repr=False)
    failures: dict[int, str] = field(default_factory=dict)
    time: float = 0.0
    _results: dict[int, Result] = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return self.u.shape[0]

    def __getitem__(self, case: int) -> Result:
        case = range(len(self))[case]  # negative indices, and IndexError past the end
        if case in self.alone:
            return self.alone[case]
        if case not in self._results:
            self._results[case] = _checked_alone(
                self.prepared, self.loads, self.gaps, case,
                self.u[case][self.prepared.model.free], self.contact_force[case], self.solver,
                int(self.iterations[case]))
        return self._results[case]


def solve_batch(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
                cases: int, progress: Progress | None = None) -> Batch:
    """Every case of ``loads`` and ``gaps`` (None: the scene's own values in every case),
    solved and checked (module docstring); ``progress(done, cases)`` after each case solved
    alone, and at the end (:mod:`contactqp.progress`)."""
    start = time.perf_counter()
    scene = prepared.scene
    if not prepared.together:
        return _case_by_case(prepared, loads, gaps, cases, start, progress)
    tiled = prepared.tiled(cases)
    tiled_loads, tiled_gaps = tiled_values(scene, _values(loads, prepared.scene_loads, cases),
                                           _values(gaps, prepared.model.g, cases))
    try:
        # the loads' forces stay an array: the model and the check read them as one
        batch_scene = tiled.scene.with_values(None if loads is None else tiled_loads,
                                              None if gaps is None else tiled_gaps,
                                              load_objects=False)
    except ContactqpError:  # bad values: say which case, as the case alone says it
        for case in range(cases):
            _case_scene(prepared, loads, gaps, case)
        raise
    model = tiled.with_layout(layout_of(batch_scene))
    walls = len(scene.walls)
    gap_cases = per_case_rows(model.g, walls, cases)
    solved = many.solve_cases(prepared.model, prepared.contact, model.P.reshape(cases, -1),
                              gap_cases, penalty=prepared.penalty,
                              max_iterations=prepared.options.get("max_iterations"),
                              shared=prepared.flexibility)
    model.__dict__["free_displacement"] = solved.free_displacement.ravel()  # K⁻¹P, known
    solution = Solution(solved.u_free.ravel(), tiled_rows(solved.contact_force, walls),
                        prepared.method, int(solved.iterations.max(initial=0)),
                        "solved with the batch")
    # the tiled answer checked as one scene, without a natural map over every case's rows
    # (each case's is read from its rows) and without the stresses a Batch does not hold
    F, U = case_scales(model, cases, solved.free_displacement, gap_cases,
                       prepared.flexibility[1])
    together = checked(model, solution, prepared.contact, natural=False)
    lam = solved.contact_force
    residuals, names = _case_residuals(prepared, together, solved, gap_cases, F, U)
    verified = solved.settled & np.all(
        [residuals[name] <= SPARE * getattr(TOLERANCES, name) for name in names
         if together.check.residuals[name] is not None], axis=0)
    physical = many.row_reduce(np.minimum, lam, initial=0.0) >= -TOLERANCES.sign * F
    alone, failures = _alone_where_flagged(prepared, loads, gaps, solved, verified)
    batch = Batch(prepared, loads, gaps, np.array(together.u).reshape(cases, -1), lam.copy(),
                  np.array(together.reactions).reshape(cases, -1),
                  per_case_rows(together.penetration, walls, cases), verified, physical,
                  residuals, np.full(cases, together.check.force_error_bound),
                  np.full(cases, together.check.displacement_error_bound), F, U,
                  solved.iterations, prepared.method, alone, failures)
    for case, result in alone.items():
        _take(batch, case, result)
    # the batch's scene keeps its layout, which reads the scene back: a cycle that only the
    # garbage collector frees. Broken here (nothing outlives the call), the layout's arrays of
    # every case are freed on return, and the next batch reuses their memory
    batch_scene.__dict__.pop("layout", None)
    object.__setattr__(batch, "time", time.perf_counter() - start)
    if progress is not None:
        progress(cases, cases)
    return batch


def _case_residuals(prepared: Prepared, together: Checked, solved: many.CasesSolution,
                    gap_cases: np.ndarray, F: np.ndarray, U: np.ndarray
                    ) -> tuple[dict[str, np.ndarray], list[str]]:
    """Each case's residuals, relative to its own scales F and U (the batch's residuals are
    relative to the scales of all the cases together), and the names of the checked ones."""
    cases, walls = len(F), len(prepared.scene.walls)
    lam = solved.contact_force
    residuals = {}
    found = together.check
    names = [name for name in found.residuals if hasattr(TOLERANCES, name)]
    for name in names:
        value = found.residuals[name]
        scale = found.displacement_scale / U if name == "displacement" else (
            found.force_scale / F)
        residuals[name] = np.full(cases, np.nan) if value is None else value * scale
    residuals["natural_map"] = np.full(cases, np.nan)  # case by case, from the rows
    if found.residuals["natural_map"] is not None:
        free = gap_cases - (prepared.model.C @ solved.free_displacement.T).T
        residuals["natural_map"] = natural_map(
            lam, -per_case_rows(together.penetration, walls, cases), free,
            1.0 / np.sqrt(prepared.model.row_stiffness))
    return residuals, names


def _alone_where_flagged(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
                         solved: many.CasesSolution, verified: np.ndarray
                         ) -> tuple[dict[int, Result], dict[int, str]]:
    """The cases the batch's check flagged, each checked alone from the batch's answer and,
    where that fails too, solved alone: (case -> its Result, case -> why its solve failed)."""
    lam = solved.contact_force
    alone, failures = {}, {}
    for case in np.flatnonzero(~verified).tolist():
        own = None if not solved.settled[case] else _checked_alone(
            prepared, loads, gaps, case, solved.u_free[case], lam[case], prepared.method,
            int(solved.iterations[case]))
        if own is None or not own.verified:
            try:
                own = _alone(prepared, loads, gaps, case)
            except SolverError as error:  # the batch's answer stays, flagged
                failures[case] = str(error)
                if own is None:
                    own = _checked_alone(prepared, loads, gaps, case, solved.u_free[case],
                                         lam[case], prepared.method,
                                         int(solved.iterations[case]))
        alone[case] = own
    return alone, failures


def _case_scene(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
                case: int) -> Scene:
    """Case ``case``'s scene (or problem); for bad values the error a single case gives,
    naming the case."""
    try:
        return prepared.with_values(None if loads is None else loads[case],
                                    None if gaps is None else gaps[case])
    except ContactqpError as error:
        raise type(error)(f"case {case}: {error}") from None


def _checked_alone(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
                   case: int, u_free: np.ndarray, contact_force: np.ndarray, solver: str,
                   iterations: int) -> Result:
    """Case ``case``'s Result for the batch's answer (``u_free`` at the free nodes), checked
    alone."""
    scene = _case_scene(prepared, loads, gaps, case)
    model = (prepared.model if scene is prepared.scene
             else prepared.model.with_layout(layout_of(scene)))
    solution = Solution(u_free, contact_force, solver, iterations, "solved with the batch",
                        info={"batch": "every case at once"})
    return make_result(model, solution, method=prepared.method, contact=prepared.contact,
                       options=prepared.result_options, timings={})


def _alone(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
           case: int) -> Result:
    """Case ``case`` solved on its own (:meth:`Prepared.solve`); bad values name the case."""
    scene = _case_scene(prepared, loads, gaps, case)
    try:
        return prepared.solve_scene(scene)
    except SceneError as error:  # e.g. a load that pulls a bar held by contact alone away
        raise SceneError(f"case {case}: {error}") from None


def _values(values: np.ndarray | None, own: np.ndarray, cases: int) -> np.ndarray:
    return np.broadcast_to(own, (cases, own.size)) if values is None else values


ROW_FIELDS = ("u", "contact_force", "reactions", "penetration", "verified", "physical",
              "force_error_bound", "displacement_error_bound", "force_scale",
              "displacement_scale")  # a Result's quantities that a Batch holds one row of


def _row(result: Result) -> dict[str, Any]:
    """A case's row of every array of a Batch, from its own Result."""
    return {**{name: getattr(result, name) for name in ROW_FIELDS},
            "iterations": result.iterations or 0,
            "residuals": {name: np.nan if value is None else value
                          for name, value in result.residuals.items()}}


def _take(batch: Batch, case: int, result: Result) -> None:
    """Case ``case``'s row of every array from its own Result."""
    row = _row(result)
    for name, value in row.items():
        if name != "residuals":
            getattr(batch, name)[case] = value
    for name, value in row["residuals"].items():
        batch.residuals[name][case] = value


def _case_by_case(prepared: Prepared, loads: np.ndarray | None, gaps: np.ndarray | None,
                  cases: int, start: float, progress: Progress | None) -> Batch:
    results = {}
    for case in range(cases):
        results[case] = _alone(prepared, loads, gaps, case)
        if progress is not None:
            progress(case + 1, cases)
    rows = [_row(results[case]) for case in range(cases)]
    arrays = {name: np.array([row[name] for row in rows])
              for name in (*ROW_FIELDS, "iterations")}
    residuals = {name: np.array([row["residuals"][name] for row in rows])
                 for name in rows[0]["residuals"]}
    return Batch(prepared, loads, gaps, **arrays, residuals=residuals,
                 solver=results[0].solver, alone=results, time=time.perf_counter() - start)


__all__ = ["Batch", "case_scales", "solve_batch", "tiled_scene"]
