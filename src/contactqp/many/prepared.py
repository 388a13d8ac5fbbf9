"""A scene prepared once and solved for many load cases and gaps.

:func:`prepare` checks the method's options, lays the scene out and builds its model (K, C, the
numbering) once; :meth:`Prepared.solve` then takes new load values and gaps and returns a
checked :class:`~contactqp.result.Result` as :func:`contactqp.solve` would for the scene with
those values, sharing everything that does not depend on them (:meth:`Scene.with_values`,
:meth:`Layout.with_values`, :meth:`Model.with_layout`). :meth:`Prepared.solve_many` solves a
batch of cases and returns them as a :class:`Batch` of arrays, every case checked.

The cases of a batch are solved and checked together where the method allows
(:mod:`contactqp.many.batch`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from contactqp._validate import value_array
from contactqp.errors import OptionError, SceneError
from contactqp.feasibility import equality_conflict
from contactqp.many.batch import Batch, solve_batch, tiled_rows, tiled_scene
from contactqp.methods import Method, checked_options, complementarity, load_cases
from contactqp.model import Model, build_model, scene_model
from contactqp.model.chain import layout_of
from contactqp.model.chain.floating import unheld_bars
from contactqp.model.chain.layout_names import TOPOLOGY
from contactqp.model.sparse import problem_model
from contactqp.problem import Problem, frictionless
from contactqp.problem_files import load_problem
from contactqp.progress import as_progress
from contactqp.result import Result, make_result
from contactqp.scene import MAX_ELEMENTS, Scene
from contactqp.solve import (
    checked_call,
    chosen_formulation,
    is_problem_path,
    solve_kind,
    solve_model,
)


@dataclass(frozen=True, eq=False)
class Prepared:
    """A scene or a problem, a method and its options, prepared for many solves (module
    docstring).

    Attributes
    ----------
    scene : the scene as prepared (its loads and gaps are the default values); None for a
        problem.
    method, contact, options : as given to :func:`prepare` (options checked).
    formulation : the formulation every solve uses ("auto" resolved on the scene).
    model : the model, whose K, C and numbering (a problem's: K's factorisation) every solve
        shares.
    problem : the problem as prepared (its f and g are the default values); None for a scene.
    """

    scene: Scene | None
    method: str
    contact: str
    formulation: str
    options: dict[str, Any]
    model: Any
    spec: Method = field(repr=False)
    _kept: dict[str, Any] = field(default_factory=dict, repr=False)  # made on first use
    problem: Problem | None = None

    @property
    def n_loads(self) -> int:
        """Load values a case gives: a scene's, one per point load, then one per distributed
        load; a problem's, f (one per dof)."""
        if self.problem is not None:
            return self.problem.n
        return len(self.scene.loads) + len(self.scene.distributed)

    @property
    def n_gaps(self) -> int:
        """Gaps a case gives: a scene's, one per wall, then one per bar contact; a problem's,
        g (one per row)."""
        return self.problem.m if self.problem is not None else self.scene.n_contacts

    @property
    def size(self) -> int:
        """What a case holds: a scene's elements, a problem's dofs."""
        return self.problem.n if self.problem is not None else self.scene.n_elements

    def with_values(self, loads: Any = None, gaps: Any = None) -> Scene | Problem:
        """The scene or problem with these load values and gaps (None: its own), checked."""
        if self.problem is not None:
            return self.problem.with_values(f=loads, g=gaps)
        return self.scene.with_values(loads, gaps)

    def solve(self, loads: Any = None, gaps: Any = None) -> Result:
        """The checked Result of the prepared scene or problem with these load values and gaps
        (None: its own), as :func:`contactqp.solve` gives it for that scene or problem."""
        start = time.perf_counter()
        return self.solve_scene(self.with_values(loads, gaps), start)

    def solve_scene(self, scene: Scene | Problem, start: float | None = None) -> Result:
        """:meth:`solve` for ``scene``, made by :meth:`with_values` (the same bars, supports,
        loads and contacts, or the same K and C; other values)."""
        start = time.perf_counter() if start is None else start
        if self.problem is not None:
            return self._solve_problem(scene, start)
        if self.contact == "equality" and (scene.walls is not self.scene.walls
                                           or scene.contacts is not self.scene.contacts):
            conflict = equality_conflict(scene)
            if conflict:
                raise OptionError(conflict)
        if self.model.floating and scene is not self.scene:  # new loads may not press them
            unheld = unheld_bars(scene, self.contact)
            if unheld:
                raise SceneError(unheld)
        model = self.model if scene is self.scene else self.model.with_layout(layout_of(scene))
        built = time.perf_counter()
        solution = solve_model(model, self.spec, self.contact, self.formulation, self.options)
        solved = time.perf_counter()
        return make_result(model, solution, method=self.method, contact=self.contact,
                           options=self.result_options,
                           timings={"build": built - start, "solve": solved - built})

    def _solve_problem(self, problem: Problem, start: float) -> Result:
        """:meth:`solve_scene` for a problem: its model shares the prepared one's
        factorisation (:meth:`~contactqp.model.sparse.SparseModel.with_values`)."""
        model = self.model if problem is self.problem else self.model.with_values(problem)
        built = time.perf_counter()
        solution = solve_model(model, self.spec, solve_kind(model, self.contact), "full",
                               self.options)
        solved = time.perf_counter()
        return make_result(model, solution, method=self.method, contact=self.contact,
                           options=self.result_options,
                           timings={"build": built - start, "solve": solved - built})

    @property
    def together(self) -> bool:
        """Whether a batch's cases are solved together on the contact rows with the
        flexibility W formed once (:mod:`contactqp.methods.load_cases`): Lagrange multipliers and
        the penalty, in the full or condensed formulation (the same answer), with few contact
        rows; a scene's only."""
        return (self.problem is None and self.method in ("lagrange", "penalty")
                and self.formulation in ("full", "condensed") and load_cases.fits(self.model)
                and self.options.get("active_set") != "passed")

    @property
    def flexibility(self) -> tuple[np.ndarray, np.ndarray]:
        """(K⁻¹Cᵀ, W = C K⁻¹ Cᵀ) of the scene
        (:func:`contactqp.methods.complementarity.flexibility`), formed on first use."""
        if "flexibility" not in self._kept:
            self._kept["flexibility"] = complementarity.flexibility(self.model)
        return self._kept["flexibility"]

    @property
    def penalty(self) -> float | None:
        """The penalty's ε as its method takes it (its option, else its default); None for
        any other method."""
        if self.method != "penalty":
            return None
        from contactqp.methods.penalty import default_penalty

        given = self.options.get("penalty")
        return default_penalty(self.model) if given is None else given

    def solve_many(self, loads: Any = None, gaps: Any = None, progress: Any = None) -> Batch:
        """Every case of ``loads`` (cases x :attr:`n_loads`) and ``gaps`` (cases x
        :attr:`n_gaps`), either None for the scene's own values; solved together where the
        method allows and every case checked (:mod:`contactqp.many.batch`).

        What a batch costs (the default scene, measured on a shared 2-core machine): solved
        together (Lagrange, the penalty), about 2–3 µs and 3 kB a case from 10³ cases up
        (10⁴ cases in 15–25 ms), after about 10 µs a case once, when a batch first has that
        many cases (the cases laid side by side, :meth:`tiled`); a scene with bar contacts
        adds about 0.2 ms a case (every case's gaps checked for a node left no position, by
        the constraint graph); case by case (every other method), a whole solve and a
        Result each, about 6 ms and 8 kB a case by PGS: 10⁶ cases take over an hour and
        8 GB. ``progress``: True for a line on stderr each
        second of a run longer than a second (cases done and the time left), or a callable
        ``progress(done, total)`` (:mod:`contactqp.progress`); by default nothing is
        printed. A batch holds every case's answer, and is solved together as one scene of
        every case's elements (:func:`contactqp.many.batch.tiled_scene`): cases times the
        scene's elements is at most :data:`contactqp.scene.MAX_ELEMENTS`."""
        report = as_progress(progress, "solve_many")
        load_cases = None if loads is None else value_array(
            "loads", loads, (-1, self.n_loads),
            "a row per case: one per point load, then one per distributed load", OptionError)
        gap_cases = None if gaps is None else value_array(
            "gaps", gaps, (-1, self.n_gaps),
            "a row per case: one per wall, then one per bar contact", OptionError)
        sizes = {len(a) for a in (load_cases, gap_cases) if a is not None}
        if len(sizes) > 1:
            raise OptionError(f"loads and gaps must have as many cases (rows), got "
                              f"{len(load_cases)} and {len(gap_cases)}")
        cases = sizes.pop() if sizes else 1
        if cases == 0:
            raise OptionError("loads and gaps must have at least one case (row), got none")
        most = MAX_ELEMENTS // max(self.size, 1)
        if cases > most:
            what = "dofs" if self.problem is not None else "elements"
            raise OptionError(f"loads and gaps have {cases} cases of {self.size} {what}; a "
                              f"batch takes at most {most} ({MAX_ELEMENTS} {what} in all): "
                              "solve it in parts")
        return solve_batch(self, load_cases, gap_cases, cases, report)

    @property
    def scene_loads(self) -> np.ndarray:
        """The own load values: a scene's point loads' forces, then its distributed loads'
        intensities; a problem's f."""
        if self.problem is not None:
            return np.array(self.problem.f)
        return np.array([p.force for p in self.scene.loads]
                        + [q.intensity for q in self.scene.distributed], dtype=float)

    @property
    def result_options(self) -> dict[str, Any]:
        """The options as every Result of this preparation shows them."""
        return (self.options if self.formulation == "full"
                else {**self.options, "formulation": self.formulation})

    def tiled(self, cases: int) -> Model:
        """The model of the scene repeated ``cases`` times (:func:`contactqp.many.batch.tiled_scene`),
        made once per number of cases (the last one kept)."""
        kept = self._kept
        if kept.get("cases") != cases:
            model = build_model(tiled_scene(self.scene, cases))
            # every case's rows see its K: the case's own row stiffness, bit for bit
            stiffness = tiled_rows(np.tile(self.model.row_stiffness, (cases, 1)),
                                   len(self.scene.walls))
            stiffness.flags.writeable = False
            model.__dict__["row_stiffness"] = stiffness
            for name in TOPOLOGY:  # made here once, shared by every batch's layout
                getattr(model.layout, name)
            kept.update(cases=cases, tiled=model)
        return kept["tiled"]


def prepare(scene: Scene | str | None = None, method: str = "lagrange",
            contact: str = "inequality", formulation: str = "auto",
            **options: Any) -> Prepared:
    """Prepare ``scene`` (a Scene, a scene file's path or None for the default scene) for many
    solves by ``method`` with ``contact`` and ``options`` as :func:`contactqp.solve` takes
    them: the options are checked, the scene laid out and its model built once.

    Parameters
    ----------
    scene : Scene, str, os.PathLike or None
        The scene, the path of a scene file, or None for the default scene.
    method : str
        One of :data:`contactqp.METHODS` (default ``"lagrange"``).
    contact : str
        ``"inequality"`` (unilateral, the default) or ``"equality"``.
    formulation : str
        ``"auto"`` (default), ``"full"``, ``"condensed"`` or ``"strain"``, as for
        :func:`contactqp.solve`.
    **options
        The method's options, as :func:`contactqp.solve` takes them.

    Returns
    -------
    Prepared
        Its :meth:`~Prepared.solve` and :meth:`~Prepared.solve_many` take new load values and
        gaps.

    Raises
    ------
    OptionError
        An unknown method, contact kind, formulation or option, or a bad option value.
    SceneError
        A scene file that cannot be read or holds bad values.
    """
    if isinstance(scene, (str, os.PathLike)) and is_problem_path(scene):
        scene = load_problem(scene)
    if isinstance(scene, Problem):
        frictionless(scene, "prepare")
        return _prepare_problem(scene, method, contact, formulation, options)
    scene, spec, options = checked_call(scene, method, contact, formulation, options)
    model = scene_model(scene)
    for name in TOPOLOGY:  # made once here, shared by every case's layout
        getattr(model.layout, name)
    return Prepared(scene, method, contact, chosen_formulation(model, spec, formulation, contact),
                    options, model, spec)


def _prepare_problem(problem: Problem, method: Any, contact: Any, formulation: Any,
                     options: dict[str, Any]) -> Prepared:
    """:func:`prepare` for a problem: its model built (and K factorised) once."""
    spec, options = checked_options(method, contact, formulation, options)
    if formulation != "auto":
        raise OptionError(f"formulation={formulation!r} applies to bar scenes; a Problem "
                          "is solved as given (formulation='auto')")
    model = problem_model(problem)
    refusal = spec.accepts(model, contact, options)
    if refusal:
        raise OptionError(refusal)
    return Prepared(None, spec.name, contact, "full", options, model, spec, problem=problem)


__all__ = ["Batch", "Prepared", "prepare"]
