"""Every way of solving a scene, behind one function: ``solve(scene, method, contact, **options)``.

Each method is a function ``(model, contact, **options) -> Solution``; :func:`solve` builds the
model, times the method, and turns its Solution into a checked Result.
"""

from __future__ import annotations

import functools
import inspect
import os
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
from contactqp.scene import Scene, load_scene, seed_scene

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
    if not isinstance(method, str) or method not in METHODS:
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
    """Equality contact ties every contact row: a support or one wall fixes a node, a bar
    contact ties two nodes. Two ties between the same nodes (walls on both sides of one node,
    two walls on nodes a bar contact ties, a loop of bar contacts) over-determine them: the
    saddle-point system is singular. An OptionError names the ties that close the loop."""
    parent: dict[int, int] = {}

    def root(node: int) -> int:
        while parent.get(node, node) != node:
            node = parent[node]
        return node

    ties: list[tuple[int, int, str]] = []  # accepted ties: (node, node, name); -1 is "held"
    supports = set(scene.support_nodes.tolist())
    rows = [(-1, scene.global_node(w.bar, w.node), f"wall[{i}] (node {w.node})")
            for i, w in enumerate(scene.walls)]
    rows += [(scene.global_node(c.bar_a, c.node_a), scene.global_node(c.bar_b, c.node_b),
              f"contact[{i}]") for i, c in enumerate(scene.contacts)]
    for a, b, name in rows:
        a, b = (-1 if a in supports else a), (-1 if b in supports else b)
        if root(a) == root(b):
            loop = _tie_path(ties, a, b)
            raise OptionError(
                f"contact='equality' cannot hold {name} together with {', '.join(loop)}: they "
                "fix the same nodes twice; use contact='inequality'"
            )
        parent[root(a)] = root(b)
        ties.append((a, b, name))


def _tie_path(ties: list[tuple[int, int, str]], start: int, goal: int) -> list[str]:
    """The names of the ties on the path from ``start`` to ``goal`` (breadth first)."""
    neighbours: dict[int, list[tuple[int, str]]] = {}
    for a, b, name in ties:
        neighbours.setdefault(a, []).append((b, name))
        neighbours.setdefault(b, []).append((a, name))
    came: dict[int, tuple[int, str] | None] = {start: None}
    queue = [start]
    for node in queue:
        for following, name in neighbours.get(node, []):
            if following not in came:
                came[following] = (node, name)
                queue.append(following)
    path, node = [], goal
    while came.get(node) is not None:
        node, name = came[node]
        path.append(name)
    return path[::-1] or ["a support"]


def as_scene(scene: Scene | str | os.PathLike | None) -> Scene:
    """The scene to solve: the default scene for None, a scene file read for a path."""
    if scene is None:
        return seed_scene()
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(scene)
    if not isinstance(scene, Scene):
        raise OptionError(f"scene must be a contactqp.Scene, a scene file's path or None, "
                          f"got {type(scene).__name__}")
    return scene


def solve(scene: Scene | str | os.PathLike | None = None, method: str = "lagrange", contact: str = "inequality",
          formulation: str = "full", **options: Any) -> Result:
    """Solve a scene (the default scene when None) by ``method`` with ``contact``
    "inequality" (unilateral, the default) or "equality" (the textbook form).

    ``scene``: a Scene, the path of a scene file (read by :func:`contactqp.load_scene`), or
    None for the default scene.

    Methods and their options: "lagrange" (max_iterations), "penalty" (penalty ε, force per
    length in the scene's units, default 1e8 × the stiffness the walls see; max_iterations),
    "augmented" (penalty, default 100 × the stiffness the walls see; tolerance, default
    1e-10; max_iterations), "qp" (backend "clarabel" (default), "osqp", "cvxpy" or
    "qpsolvers"; solver, None for the backend's default; accuracy "default" or "high"; scale,
    default True; verbose, default False: see :mod:`contactqp.methods.qp`).

    ``formulation``: "full" (every free node an unknown), "condensed" (K factored once, the
    method sees only the nodes that carry walls, every displacement recovered from the same
    factorisation; see :func:`contactqp.model.condense`) or "strain" (lagrange and qp only:
    the element elongations are unknowns too, tied to the displacements by equality rows
    whose multipliers are the element forces; see :func:`contactqp.model.elongation_rows`).
    Returns a checked :class:`Result`.
    """
    scene = as_scene(scene)
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


__all__ = ["CONTACT_KINDS", "FORMULATIONS", "METHODS", "as_scene", "check_equality_is_possible",
           "method_options", "solve", "takes_strain"]
