"""The pipeline for a user's own model: problem → sparse model → method → checked Result.

:func:`solve_problem` is what ``contactqp.solve(problem, method)`` calls. Each method that
needs no chain solves a problem (:data:`PROBLEM_METHODS`); Nitsche is refused with the reason.
A Problem's rows are checked by their kinds when it is made; a solve with
``contact="equality"`` that fails (a SolverError, or an answer the check does not verify) on
rows that, held on their gaps, no u meets all at once ends in a ProblemError naming them
(:mod:`contactqp.problem_feasibility`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from contactqp.errors import OptionError, ProblemError, SolverError
from contactqp.methods import checked_options, complementarity
from contactqp.methods import sparse as on_sparse
from contactqp.methods.schur import solve_schur
from contactqp.model.sparse import SparseModel, build_sparse_model
from contactqp.problem import Problem
from contactqp.problem_feasibility import conflicting_rows
from contactqp.problem_result import ProblemResult, make_problem_result
from contactqp.result import Solution

PROBLEM_METHODS: dict[str, Callable[..., Solution]] = {
    "lagrange": solve_schur,
    "penalty": on_sparse.solve_penalty,
    "augmented": on_sparse.solve_augmented,
    "qp": on_sparse.solve_qp,
    "lemke": complementarity.solve_lemke,
    "pgs": complementarity.solve_pgs,
    "semismooth_newton": complementarity.solve_semismooth_newton,
}
OPTIONS_NOT_FOR_PROBLEMS = {"lagrange": ("active_set",)}  # the chain's hull has no meaning here
NITSCHE = ("nitsche needs the traction σ(u)·n on the contact boundary, which the matrices K, "
           "f, C, g do not carry; use lagrange, penalty, augmented or qp")


def checked_problem_call(problem: Problem, method: Any, contact: Any, options: dict[str, Any]
                         ) -> dict[str, Any]:
    """The options checked as for a scene (one OptionError line for a bad one), and the
    methods a problem cannot take refused with the reason."""
    if method == "nitsche":
        raise OptionError(NITSCHE)
    _, checked = checked_options(method, contact, "auto", options)
    refused = [name for name in OPTIONS_NOT_FOR_PROBLEMS.get(method, ()) if name in checked]
    if refused:
        raise OptionError(f"option {refused[0]!r} of {method} applies to bar scenes only")
    if method in ("lemke", "pgs", "semismooth_newton") and problem.equality.any() and not (
            problem.equality.all()):
        raise OptionError(f"{method} solves the LCP of inequality rows (or the linear system of "
                          "equality rows), and this problem mixes both: use lagrange")
    return checked


def solve_problem(problem: Problem, method: str = "lagrange", contact: str = "inequality",
                  **options: Any) -> ProblemResult:
    """Solve a :class:`~contactqp.Problem` by ``method`` (as :func:`contactqp.solve` names
    them, their options the same) and check the answer (:mod:`contactqp.problem_check`).
    ``contact="equality"`` holds every row on its gap; otherwise each row's kind is the
    problem's (:attr:`~contactqp.Problem.kinds`)."""
    options = checked_problem_call(problem, method, contact, options)
    start = time.perf_counter()
    model = build_sparse_model(problem)
    built = time.perf_counter()
    # every row held on its gap: a conflict the Problem, checking its rows by their kinds, did
    # not look for
    held = contact == "equality" and not problem.equality.all()
    try:
        solution = solve_model(model, method, contact, options)
    except SolverError:
        if held:
            _refuse_rows_that_leave_no_u(problem)
        raise
    solved = time.perf_counter()
    result = make_problem_result(model, solution, method=method, contact=contact,
                                 options=options,
                                 timings={"build": built - start, "solve": solved - built})
    if held and not result.verified:
        _refuse_rows_that_leave_no_u(problem)
    return result


def _refuse_rows_that_leave_no_u(problem: Problem) -> None:
    """After a failed solve with every row held on its gap (``contact="equality"``), which
    the problem's own check of its rows (by their kinds) did not cover: a ProblemError naming
    rows that no u meets all at once, if there are such."""
    conflict = conflicting_rows(problem.C, problem.g, np.ones(problem.m, dtype=bool),
                                problem.names)
    if conflict:
        raise ProblemError(conflict)


def solve_model(model: SparseModel, method: str, contact: str, options: dict[str, Any]
                ) -> Solution:
    """Solve a sparse model by a method whose options are checked."""
    if model.equality.all() and model.n_contacts:
        contact = "equality"
    return PROBLEM_METHODS[method](model, contact, **options)


__all__ = ["NITSCHE", "PROBLEM_METHODS", "checked_problem_call", "solve_model",
           "solve_problem"]
