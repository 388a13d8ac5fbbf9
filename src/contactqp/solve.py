"""The one pipeline: scene → model → formulation → method → checked Result.

:func:`solve` is what users call; :func:`solve_model` is the part after the model, which the
load path (contactqp.curve) calls with a model it has factored once.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
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
from contactqp.model.chain import layout_of
from contactqp.model.chain.floating import unheld_bars
from contactqp.model.chain.to_problem import problem_from_scene
from contactqp.model.sparse import check_engine, problem_model
from contactqp.problem import Problem
from contactqp.problem_files import load_problem
from contactqp.result import Result, make_result, with_bar_quantities
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
          contact: str = "inequality", formulation: str = "auto", previous: Any = None,
          engine: str = "direct", **options: Any) -> Result:
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
    previous : Result or array, optional
        For a problem with friction (``T`` with ``mu`` or ``slip_bound``): the state this
        increment starts from (a Result of the same problem, or its u); the slip is measured
        from its u (:mod:`contactqp.friction.methods` has the methods and options that take
        friction; docs/friction.md). Default: from rest.
    engine : str
        How a Problem's model solves with K: "direct" (the default: K factorised once,
        :mod:`contactqp.model.factor`) or "amg" (conjugate gradients with pyamg's algebraic
        multigrid, for models whose factorisation does not fit in memory, 3D at 10⁶ dofs:
        :mod:`contactqp.model.iterative`; the extra ``contactqp[amg]``), for method
        "lagrange" (the others factorise a matrix of their own or form W, refused with the
        reason). The check solves with the same engine. Bar scenes and problems with friction
        take "direct" only.
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
        ``tolerance``, ``max_iterations``, ``max_rows`` (default 2 000: the rows up to which
        it forms W; more lifts its limits for a long run, 14 minutes at 10⁴ rows).
        "semismooth_newton": ``ncp`` ("min" or
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
        A bad method, contact, formulation, option or ``previous`` (one line naming it and
        its value), a method that does not take friction (one line saying why),
        equality contact that ties a node twice, or a method that does not take the scene
        (Nitsche on an interior wall).
    SceneError
        A scene file that cannot be read, or a scene that is not valid.
    SolverNotAvailable
        The QP backend or solver asked for is not installed (the message says how to add it).
    SolverError
        The method could not produce an answer (a singular system, a loop that does not end).
    """
    if isinstance(scene, (str, os.PathLike)):
        scene = as_target(scene)
    if not (isinstance(engine, str) and engine == "direct"):
        _check_engine(scene, engine)
    if isinstance(scene, Scene) and scene.beds:  # friction: solved as the scene's problem,
        # with the bar quantities of the scene's own numbering
        found = solve_friction_problem(problem_from_scene(scene), method, contact, formulation,
                                       previous, options)
        return with_bar_quantities(found, layout_of(scene))
    if isinstance(scene, Problem) and scene.T is not None:
        return solve_friction_problem(scene, method, contact, formulation, previous, options)
    if previous is not None:
        raise OptionError("previous applies to problems with friction (the slip is measured "
                          "from it); this one has none")
    if isinstance(scene, Problem):
        return solve_problem(scene, method, contact, formulation, options, engine)
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


ENGINE_METHODS = ("lagrange",)  # the methods engine="amg" runs


def _check_engine(target: Any, engine: Any) -> None:
    """An OptionError where ``engine`` is not one of ENGINES, or is not "direct" for a bar
    scene or a problem with friction."""
    check_engine(engine)
    if not isinstance(target, Problem) or target.T is not None:
        raise OptionError(f"engine={engine!r} applies to a Problem without friction; bar "
                          "scenes and friction solve with engine='direct'")


def solve_problem(problem: Problem, method: Any, contact: Any, formulation: Any,
                  options: dict[str, Any], engine: str = "direct") -> Result:
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
    if engine != "direct" and spec.name not in ENGINE_METHODS:
        raise OptionError(f"engine={engine!r} runs {', '.join(ENGINE_METHODS)} (sets of rows by "
                          f"projected conjugate gradients); {spec.name} factorises a matrix of "
                          "its own or forms W = C K⁻¹ Cᵀ a solve per row, which at the sizes "
                          "this engine is for does not fit or does not end: use "
                          "engine='direct'")
    model = problem_model(problem, engine)
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
    options = {**options, "engine": engine} if engine != "direct" else options
    result = make_result(model, solution, method=spec.name, contact=contact, options=options,
                         timings={"build": built - start, "solve": solved - built})
    if held and not result.verified:
        _refuse_rows_that_leave_no_u(problem)
    return result


def solve_friction_problem(problem: Problem, method: Any, contact: Any, formulation: Any,
                           previous: Any, options: dict[str, Any]) -> Result:
    """:func:`solve` for a problem with friction: its friction model (built once per
    Problem), the method of :mod:`contactqp.friction.methods`, the friction check
    (:mod:`contactqp.friction.check`), the Result with the friction forces and states."""
    # imported here: scipy.linalg comes with the first solve that needs it, not at start-up
    from contactqp.friction.check import check as check_friction
    from contactqp.friction.law import coulomb, tresca
    from contactqp.friction.methods import checked_friction_options, solve_friction
    from contactqp.friction.model import problem_friction_model

    if contact != "inequality":
        raise OptionError(f"contact={contact!r}: friction takes unilateral contact "
                          "(contact='inequality')")
    if formulation != "auto":
        raise OptionError(f"formulation={formulation!r} applies to bar scenes; a Problem "
                          "is solved as given (formulation='auto')")
    options = checked_friction_options(problem.friction, method, options)
    previous_u, initial = _previous(problem, previous)
    start = time.perf_counter()
    model = problem_friction_model(problem)
    values = problem.mu if problem.friction == "coulomb" else problem.slip_bound
    built = time.perf_counter()
    answer = solve_friction(model, problem.friction, values, method, options, previous_u,
                            initial)
    solved = time.perf_counter()
    law = coulomb(model, values) if problem.friction == "coulomb" else tresca(model, values)
    found = check_friction(model, law, answer, previous_u)
    checked_at = time.perf_counter()
    return make_friction_result(problem, answer, found, method=method, options=options,
                                timings={"build": built - start, "solve": solved - built,
                                         "check": checked_at - solved})


@dataclass(frozen=True, eq=False)
class FrictionView:
    """What a Result reads of the model of a problem with friction (whose own model lives in
    :mod:`contactqp.friction`): its problem, names and units; no chain."""

    problem: Any
    layout: None = None

    @property
    def row_names(self) -> tuple[str, ...]:
        return self.problem.names

    @property
    def units(self) -> tuple[str, str]:
        return self.problem.unit_names


def make_friction_result(problem: Any, answer: Any, found: Any, *, method: str,
                         options: dict[str, Any], timings: dict[str, float]) -> Result:
    """The Result of a friction method's answer (:class:`~contactqp.friction.FrictionAnswer`)
    and its check (:class:`~contactqp.friction.FrictionCheck`): ``verified`` and the bounds
    are the friction check's; the reactions (K u − f + Cᵀλ_N + Tᵀλ_T at the prescribed dofs)
    and the penetration are derived from u and the forces."""
    lam_N = (answer.normal_force if answer.normal_force is not None else np.zeros(0))
    u = answer.u
    imbalance = (problem.K @ u - problem.f + problem.C.T @ lam_N
                 + problem.T.T @ answer.friction_force.ravel())
    F = found.residuals.force_scale
    residuals = {key: value for key, value in vars(found.residuals).items()
                 if key != "force_scale"}
    warnings = [f"{answer.method} reported {answer.status!r} but the check failed"] if (
        answer.converged and not found.verified) else []
    return Result(
        model=FrictionView(problem), method=method, solver=answer.method, contact="inequality",
        options=dict(options), u=u, contact_force=lam_N, reactions=imbalance[problem.prescribed],
        penetration=problem.C @ u - problem.g, residuals=residuals, verified=found.verified,
        physical=not bool(np.any(lam_N < -1e-6 * F)), message=found.verdict,
        force_error_bound=found.force_error_bound,
        displacement_error_bound=found.displacement_error_bound, force_scale=F,
        displacement_scale=found.displacement_scale, status=answer.status,
        claimed_success=answer.converged, iterations=answer.iterations,
        time=sum(timings.values()), timings=timings, warnings=tuple(warnings),
        info={**answer.info, **({"history": list(answer.history)} if answer.history else {})},
        friction=found.law, friction_force=answer.friction_force, slip=answer.slip,
        stick=answer.stick, state=answer.state)


def _previous(problem: Problem, previous: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(u of the state an increment starts from, the forces to start the exact route from)
    from ``previous``: a Result of a problem of the same size, or its u."""
    if previous is None:
        return None, None
    if isinstance(previous, Result):
        u = previous.u
        if previous.friction_force is None or u.shape != (problem.n,):
            raise OptionError(f"previous: a Result of {u.size} dofs "
                              f"{'with' if previous.friction else 'without'} friction; it "
                              f"must be an answer of this problem ({problem.n} dofs, friction)")
        forces = np.concatenate([previous.contact_force, previous.friction_force.ravel()])
        return u, forces
    try:
        u = np.asarray(previous, dtype=float)
    except (TypeError, ValueError):
        raise OptionError(f"previous must be a Result or the u it starts from, got "
                          f"{type(previous).__name__}") from None
    if u.shape != (problem.n,) or not np.all(np.isfinite(u)):
        raise OptionError(f"previous: an array of shape {u.shape}; it must be the {problem.n} "
                          "finite displacements the increment starts from")
    return u, None


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


__all__ = ["AUTO_CONDENSE", "AUTO_CONDENSE_NODES", "FrictionView", "as_scene", "as_target",
           "checked_call", "chosen_formulation", "is_problem_path", "make_friction_result",
           "solve", "solve_friction_problem", "solve_kind", "solve_model", "solve_problem"]
