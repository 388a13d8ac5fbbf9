"""Every way of solving a scene, behind one function: ``solve(scene, method, contact, **options)``.

Each method is a function ``(model, contact, **options) -> Solution``; :func:`solve` builds the
model, times the method, and turns its Solution into a checked Result.
"""

from __future__ import annotations

import functools
import inspect
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from contactqp.errors import OptionError
from contactqp.methods.augmented import solve_augmented
from contactqp.methods.lagrange import solve_lagrange
from contactqp.methods.penalty import solve_penalty
from contactqp.methods.qp import solve_qp
from contactqp.model import CONTACT_KINDS, build_model, condense, contact_kind
from contactqp.result import Result, Solution, make_result
from contactqp.scene import Scene, seed_scene

FORMULATIONS = ("full", "condensed", "strain")

METHODS: dict[str, Callable[..., Solution]] = {
    "lagrange": solve_lagrange,
    "penalty": solve_penalty,
    "augmented": solve_augmented,
    "qp": solve_qp,
}


@functools.cache
def method_options(method: str) -> tuple[str, ...]:
    """The keyword options a method takes (``formulation`` is :func:`solve`'s own argument)."""
    parameters = inspect.signature(METHODS[method]).parameters.values()
    return tuple(p.name for p in parameters
                 if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name != "formulation")


def takes_strain(method: str) -> bool:
    """Whether a method solves the strain formulation (it needs exact equality rows)."""
    return "formulation" in inspect.signature(METHODS[method]).parameters


def validate(method: str, contact: str, options: dict[str, Any]) -> Callable[..., Solution]:
    """The function of ``method``, after checking it, ``contact`` and ``options`` (OptionError)."""
    if method not in METHODS:
        raise OptionError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    contact_kind(contact)
    allowed = method_options(method)
    for name in options:
        if name not in allowed:
            raise OptionError(
                f"method {method!r} has no option {name!r} (its options: {', '.join(allowed)})"
            )
    return METHODS[method]


def check_equality_is_possible(scene: Scene) -> None:
    """Equality contact ties a node to every wall it has: walls on both sides of one node
    would hold it at +gap and -gap at once."""
    sides: dict[int, int] = {}
    for i, wall in enumerate(scene.walls):
        node = scene.global_node(wall.bar, wall.node)
        if node in sides:
            raise OptionError(
                f"contact='equality' cannot hold node {wall.node} at wall[{sides[node]}] and "
                f"wall[{i}] at once; use contact='inequality'"
            )
        sides[node] = i


def solve(scene: Scene | None = None, method: str = "lagrange", contact: str = "inequality",
          formulation: str = "full", **options: Any) -> Result:
    """Solve a scene (the default scene when None) by ``method`` with ``contact``
    "inequality" (unilateral, the default) or "equality" (the textbook form).

    Methods and their options: "lagrange" (max_iterations), "penalty" (penalty ε in N/m,
    default 1e14; max_iterations), "augmented" (penalty, default 100 x max diag K; tolerance;
    max_iterations), "qp" (backend "clarabel" (default), "osqp", "cvxpy" or "qpsolvers";
    solver, None for the backend's default; accuracy "default" or "high"; scale, default True:
    see :mod:`contactqp.methods.qp`).

    ``formulation``: "full" (every free node an unknown), "condensed" (K factored once, the
    method sees only the nodes that carry walls, every displacement recovered from the same
    factorisation; see :func:`contactqp.model.condense`) or "strain" (lagrange and qp only:
    the element elongations are unknowns too, tied to the displacements by equality rows
    whose multipliers are the element forces; see :func:`contactqp.model.elongation_rows`).
    Returns a checked :class:`Result`.
    """
    scene = seed_scene() if scene is None else scene
    function = validate(method, contact, options)
    if formulation not in FORMULATIONS:
        raise OptionError(f"formulation must be one of {', '.join(FORMULATIONS)}; "
                          f"got {formulation!r}")
    if formulation == "strain" and not takes_strain(method):
        raise OptionError(
            f"formulation='strain' is solved by the methods "
            f"{', '.join(m for m in METHODS if takes_strain(m))}, not {method!r}: its tie rows "
            f"must hold exactly, and {method!r} enforces rows by a penalty"
        )
    if contact == "equality":
        check_equality_is_possible(scene)
    start = time.perf_counter()
    model = build_model(scene)
    built = time.perf_counter()
    if formulation == "condensed":
        condensed = condense(model)
        if condensed.model.n_free:
            solution = function(condensed.model, contact, **options)
        else:  # no contacts: nothing left to solve, u = K⁻¹P
            solution = Solution(np.zeros(0), np.zeros(0), solver=method,
                                status="solved (no contact unknowns)")
        solution = replace(solution, u_free=condensed.displacements(solution.contact_force))
    elif formulation == "strain":
        solution = function(model, contact, formulation="strain", **options)
    else:
        solution = function(model, contact, **options)
    solved = time.perf_counter()
    options = {**options, "formulation": formulation} if formulation != "full" else options
    return make_result(model, solution, method=method, contact=contact, options=options,
                       timings={"build": built - start, "solve": solved - built})


__all__ = ["CONTACT_KINDS", "FORMULATIONS", "METHODS", "check_equality_is_possible",
           "method_options", "solve", "takes_strain"]
