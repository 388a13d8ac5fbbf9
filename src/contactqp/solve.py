"""The one pipeline: scene → model → formulation → method → checked Result.

:func:`solve` is what users call; :func:`solve_model` is the part after the model, which the
load path (contactqp.curve) calls with a model it has factored once.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from contactqp.builders import default_scene
from contactqp.errors import OptionError, ProblemError, SceneError, SolverError
from contactqp.feasibility import equality_conflict
from contactqp.feasibility.rows import row_conflict
from contactqp.methods import Method, checked_options, hull
from contactqp.methods.base import Solution
from contactqp.model import Condensed, Model, condensed_model, scene_model
from contactqp.model.chain.floating import unheld_bars
from contactqp.model.sparse import problem_model
from contactqp.problem import Problem
from contactqp.problem_files import load_problem
from contactqp.result import Result, make_result
from contactqp.scene import Scene
from contactqp.scene_io import load_scene


def is_problem_path(path: Any) -> bool:
    """Whether ``path`` names a problem's files (an ``.npz`` bundle or a folder of Matrix
    Market files), not a scene file."""
    return bool(path) and (str(path).endswith(".npz") or Path(path).is_dir())


def as_target(target: Scene | Problem | str | os.PathLike | None) -> Scene | Problem:
    """What to solve: a Scene or a Problem as it is; a path, the problem (``.npz`` bundle,
    folder of Matrix Market files) or the scene file (TOML) it names; None, the default
    scene."""
    if isinstance(target, Problem):
        return target
    if isinstance(target, (str, os.PathLike)) and is_problem_path(target):
        return load_problem(target)
    return as_scene(target)


def as_scene(scene: Scene | str | os.PathLike | None) -> Scene:
    """The scene to solve: the default scene for None, a scene file read for a path."""
    if scene is None:
        return default_scene()
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(scene)
    if not isinstance(scene, Scene):
        raise OptionError(f"scene must be a contactqp.Scene, a scene file's path or None, "
                          f"got {type(scene).__name__}")
    return scene


AUTO_CONDENSE = 16  # formulation="auto" condenses a scene with at most this many contact nodes
AUTO_CONDENSE_NODES = 512  # ... and at least this many free nodes (below, condensing costs more)


def solve(scene: Scene | Problem | str | os.PathLike | None = None, method: str = "lagrange",
          contact: str = "inequality", formulation: str = "auto",
          **options: Any) -> Result:
    """Solve a scene (or a user's own model) by one method and return the checked Result.

    Parameters
    ----------
    scene : Scene, Problem, str, os.PathLike or None
        The scene, the path of a scene file (read by :func:`contactqp.load_scene`), or None
        for the default scene (:func:`contactqp.default_scene`); or a
        :class:`contactqp.Problem` (K, f, C, g: every method but nitsche; the formulation
        stays "auto"). Either way the same :class:`~contactqp.result.Result`.
    method : str
        One of :data:`contactqp.METHODS`: "lagrange", "penalty", "augmented", "qp", "lemke",
        "pgs", "semismooth_newton" or "nitsche".
    contact : str
        "inequality" (unilateral: a wall may only push; the default) or "equality" (the
        textbook form: each contact node sits on its wall).
    formulation : str
        "auto" (the default: "condensed" where the method takes it, the scene has at most
        AUTO_CONDENSE contact nodes and at least AUTO_CONDENSE_NODES free nodes, and the
        method is not Lagrange with its hull active set, else "full"; the same answer, and the
        Result's options say which ran), "full" (every free node an unknown), "condensed" (the
        method sees only the nodes that carry contacts, a chain again, and every displacement
        is recovered by statics: :func:`contactqp.model.chain.condensed`) or "strain" (lagrange and
        qp only: the element elongations are unknowns too, tied to the displacements by
        equality rows whose multipliers are the element forces:
        :func:`contactqp.model.elongation_rows`).
    **options
        The method's options (:data:`contactqp.methods.METHODS` names each), in the scene's
        units. "lagrange": ``max_iterations``, ``active_set`` ("hull" or "passed").
        "penalty": ``penalty`` (ε, force per length; default 1e6 × the stiffness the walls
        see, :func:`contactqp.model.wall_stiffness`), ``max_iterations``. "augmented":
        ``penalty`` (default 100 × the stiffness the walls see, 1e-4 of the penalty
        method's default), ``tolerance`` (default 1e-10: an update that changes λ by less
        than this times max(‖λ‖, ‖P‖) ends it), ``max_iterations`` (default 100 updates;
        past them the last iterate comes back with ``claimed_success`` False). "qp":
        ``backend`` ("clarabel" (default), "osqp", "cvxpy" or "qpsolvers"), ``solver`` (None:
        the backend's default), ``accuracy`` ("default" or "high"), ``scale`` (default
        True), ``verbose`` (default False): see :mod:`contactqp.methods.qp`. "lemke":
        ``max_iterations`` (pivots). "pgs": ``relaxation`` (ω in (0, 2), default 1),
        ``tolerance``, ``max_iterations``. "semismooth_newton": ``ncp`` ("min" or
        "fischer-burmeister"), ``tolerance``, ``max_iterations``. "nitsche": ``gamma0``
        (default 100), ``theta`` (1, 0 or −1), ``max_iterations``.

    Returns
    -------
    Result
        The answer and its independent check (:class:`~contactqp.result.Result`:
        ``verified``, ``physical``, ``summary()``, ``to_json()``).

    Raises
    ------
    OptionError
        A bad method, contact, formulation or option (one line naming it and its value),
        equality contact that ties a node twice, or a method that does not take the scene
        (Nitsche on an interior wall).
    SceneError
        A scene file that cannot be read, or a scene that is not valid.
    SolverNotAvailable
        The QP backend or solver asked for is not installed (the message says how to add it).
    SolverError
        The method could not produce an answer (a singular system, a loop that does not end).
    """
    if isinstance(scene, (str, os.PathLike)) and is_problem_path(scene):
        scene = load_problem(scene)
    if isinstance(scene, Problem):
        return solve_problem(scene, method, contact, formulation, options)
    scene, spec, options = checked_call(scene, method, contact, formulation, options)
    start = time.perf_counter()
    model = scene_model(scene)  # built once per scene object
    built = time.perf_counter()
    formulation = chosen_formulation(model, spec, formulation, contact)
    solution = solve_model(model, spec, contact, formulation, options)
    solved = time.perf_counter()
    options = {**options, "formulation": formulation} if formulation != "full" else options
    return make_result(model, solution, method=method, contact=contact, options=options,
                       timings={"build": built - start, "solve": solved - built})


def solve_problem(problem: Problem, method: Any, contact: Any, formulation: Any,
                  options: dict[str, Any]) -> Result:
    """:func:`solve` for a user's problem: its model (built once per Problem,
    :func:`~contactqp.model.sparse.problem_model`), the method's own refusal where it does not
    take it, the solve and its check. A solve with ``contact="equality"`` that fails (a
    SolverError, or an answer the check does not verify) on rows that, held on their gaps, no
    u meets all at once ends in a ProblemError naming them
    (:mod:`contactqp.feasibility.rows`)."""
    spec, options = checked_options(method, contact, formulation, options)
    if formulation != "auto":
        raise OptionError(f"formulation={formulation!r} applies to bar scenes; a Problem "
                          "is solved as given (formulation='auto')")
    start = time.perf_counter()
    model = problem_model(problem)
    refusal = spec.accepts(model, contact, options)
    if refusal:
        raise OptionError(refusal)
    built = time.perf_counter()
    # every row held on its gap: a conflict the Problem, checking its rows by their kinds, did
    # not look for
    held = contact == "equality" and not problem.equality.all()
    try:
        solution = solve_model(model, spec, solve_kind(model, contact), "full", options)
    except SolverError:
        if held:
            _refuse_rows_that_leave_no_u(problem)
        raise
    solved = time.perf_counter()
    result = make_result(model, solution, method=spec.name, contact=contact, options=options,
                         timings={"build": built - start, "solve": solved - built})
    if held and not result.verified:
        _refuse_rows_that_leave_no_u(problem)
    return result


def solve_kind(model: Any, contact: str) -> str:
    """Rows that are all equalities are solved as equality contact."""
    return "equality" if model.n_contacts and model.equality.all() else contact


def _refuse_rows_that_leave_no_u(problem: Problem) -> None:
    """After a failed solve with every row held on its gap (``contact="equality"``), which
    the problem's own check of its rows (by their kinds) did not cover: a ProblemError naming
    rows that no u meets all at once, if there are such."""
    conflict = row_conflict(problem.C, problem.g, np.ones(problem.m, dtype=bool),
                            problem.names)
    if conflict:
        raise ProblemError(conflict)


def checked_call(scene: Scene | str | os.PathLike | None, method: Any, contact: Any,
                 formulation: Any, options: dict[str, Any]) -> tuple[Scene, Method, dict]:
    """(the scene, the method, its options checked) for :func:`solve` and
    :func:`contactqp.prepare`; an OptionError for bad options or for equality contact that
    ties a node twice."""
    scene = as_scene(scene)
    spec, options = checked_options(method, contact, formulation, options)
    if contact == "equality":
        conflict = equality_conflict(scene)
        if conflict:
            raise OptionError(conflict)
    unheld = unheld_bars(scene, contact)
    if unheld:
        raise SceneError(unheld)
    return scene, spec, options


def chosen_formulation(model: Model, spec: Method, formulation: str,
                       contact: str = "inequality") -> str:
    """The formulation "auto" stands for (:func:`solve`); any other is kept. Condensing costs
    one solve with K per contact node and leaves the method a problem in those nodes alone: it
    pays on a long bar with few contact nodes, and not on a short one, nor for Lagrange where
    its hull active set applies (statics on the full chain in O(n)). Measured (tapered bar,
    one wall, median of 5): augmented, penalty and qp reach parity between 256 and 1024
    elements and are 2.5-20x faster condensed at 16 384; lagrange is 1.2-1.7x faster full at
    every size from 4 to 10⁶ elements (72 ms against 85 ms at 10⁶)."""
    if formulation != "auto":
        return formulation
    C = model.C
    if ("condensed" not in spec.formulations or model.n_free < AUTO_CONDENSE_NODES
            or model.floating  # condensing solves with K, singular there
            or not 0 < C.nnz <= 2 * AUTO_CONDENSE
            or np.unique(C.indices).size > AUTO_CONDENSE):
        return "full"
    if spec.name == "lagrange" and hull.applies(model, contact):
        return "full"
    return "condensed"


def solve_model(model: Model, spec: Method, contact: str, formulation: str,
                options: dict[str, Any], condensed: Condensed | None = None) -> Solution:
    """Solve a model by a method (options already checked) in a formulation; with
    ``formulation="condensed"`` on ``condensed`` when given (else the model is condensed
    here). The Solution's displacements are always the full model's free nodes."""
    if formulation == "strain":
        return spec.solve(model, contact, formulation="strain", **options)
    if formulation != "condensed":
        return spec.solve(model, contact, **options)
    condensed = condensed_model(model) if condensed is None else condensed
    if condensed.n_free:
        solution = spec.solve(condensed, contact, **options)
    else:  # no contacts: nothing left to solve, u = K⁻¹P
        solution = Solution(np.zeros(0), np.zeros(0), solver=spec.name,
                            status="solved (no contact unknowns)")
    return Solution(condensed.displacements(solution.contact_force), solution.contact_force,
                    solution.solver, solution.iterations, solution.status,
                    solution.claimed_success, solution.info)


__all__ = ["AUTO_CONDENSE", "AUTO_CONDENSE_NODES", "as_scene", "as_target", "checked_call",
           "chosen_formulation", "is_problem_path", "solve", "solve_kind", "solve_model",
           "solve_problem"]
