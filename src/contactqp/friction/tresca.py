"""Tresca's friction (a given slip bound per contact): a convex problem, solved many ways.

min ½uᵀKu − fᵀu + Σ sᵢ‖Tᵢ(u − u_prev)‖ subject to C u ≤ g has one minimiser u (K positive
definite), and its KKT conditions are the friction law on the increment: ‖λ_T,i‖ ≤ sᵢ, zero
slip where the bound is not reached, the force along the slip (opposing it on the body) where
it slips. The methods:

- ``"active_set"``: the exact route. One factorisation of K gives the rows' flexibility W
  (:mod:`._factor`); the active-set rule on the forces (:mod:`.reduced`) finds the answer's
  sets and solves their equations, exact up to round-off; u = K⁻¹(f − Gᵀλ) by one solve. Where
  the rule does not settle it restarts from the dual solved by Clarabel (small and dense).
- ``"clarabel"``: the primal (:mod:`.qp`) by Clarabel directly, a QP in 2D, an SOCP in 3D; the
  friction forces are the duals of the rows on t.
- ``"cvxpy"``: the same model written in cvxpy (its default solver, or ``solver=``).
- any qpsolvers backend by name (``"osqp"``, ``"piqp"``, ``"proxqp"``, ``"highs"``,
  ``"cvxopt"``, ``"qpalm"``, ``"scs"``, ``"daqp"``, ``"quadprog"``, ``"ecos"``, or
  ``"qpsolvers:clarabel"``): the 2D primal, or with ``formulation="dual"`` the box QP in the
  forces (the default for quadprog and ECOS, which need a positive definite Hessian).
"""

from __future__ import annotations

import time

import numpy as np

from contactqp.errors import OptionError
from contactqp.friction.answer import FrictionAnswer, make_answer
from contactqp.friction.law import Law, tresca
from contactqp.friction.model import FrictionModel
from contactqp.friction.qp import (
    POSITIVE_DEFINITE_ONLY,
    reduced_socp,
    solve_clarabel,
    solve_cvxpy,
    solve_qpsolvers,
)
from contactqp.friction.reduced import QUICK_SETS, active_set

OWN_METHODS = ("active_set", "clarabel", "cvxpy")
OPTIONS = {
    "active_set": {"initial"},
    "clarabel": {"settings"},
    "cvxpy": {"settings"},
    "qpsolvers": {"settings", "formulation"},
}


def solve_tresca(model: FrictionModel, slip_bound, *, previous_u=None,
                 method: str = "active_set", options: dict | None = None) -> FrictionAnswer:
    """Solve an increment under Tresca's law.

    Parameters
    ----------
    model : FrictionModel
        K, f, C, g, T (:func:`~contactqp.friction.friction_model`).
    slip_bound : float or array, m
        sᵢ, the friction force each contact can carry before it slips (force); zero for a
        frictionless contact.
    previous_u : array, n, optional
        The state the increment starts from; the slip is T(u − previous_u). Default zero.
    method : str
        ``"active_set"`` (exact), ``"clarabel"``, ``"cvxpy"`` or a qpsolvers backend
        (module docstring).
    options : dict, optional
        ``active_set``: ``initial`` (forces λ to start from, e.g. the previous increment's
        ``answer.forces``). ``clarabel``, ``cvxpy``, backends: ``settings`` (passed to the
        solver). Backends: ``formulation`` (``"primal"`` or ``"dual"``).

    Returns
    -------
    FrictionAnswer

    Raises
    ------
    ProblemError
        A bound or ``previous_u`` of the wrong size, negative or not finite.
    OptionError
        An unknown method or option, or a backend that cannot take the problem (one line
        saying why).
    SolverError
        The method found no answer.
    """
    return solve_law(model, tresca(model, slip_bound), previous_u, method, options or {})


def solve_law(model: FrictionModel, law: Law, previous_u, method: str,
              options: dict) -> FrictionAnswer:
    """Tresca's problem for a law already made (the fixed point of Coulomb calls this)."""
    family = _family(method)
    unknown = set(options) - OPTIONS[family]
    if unknown:
        raise OptionError(f"options: {sorted(unknown)} unknown for {method!r}; it takes "
                          f"{sorted(OPTIONS[family])}")
    previous_u = model.previous(previous_u)
    start = time.perf_counter()
    if family == "active_set":
        return _active_set(model, law, previous_u, options, start)
    origin = model.slip_origin(previous_u)
    settings = dict(options.get("settings", {}))
    if family == "clarabel":
        u_free, forces, iterations, status, _ = solve_clarabel(model, law, origin, settings)
        info = {"formulation": "primal"}
        status = {"Solved": "solved", "AlmostSolved": "almost solved"}.get(status, status)
    elif family == "cvxpy":
        u_free, forces, iterations, status, _ = solve_cvxpy(model, law, origin, settings)
        info = {"formulation": "primal"}
        status = "solved" if status == "optimal" else status
    else:
        solver = method.removeprefix("qpsolvers:")
        default = "dual" if solver in POSITIVE_DEFINITE_ONLY else "primal"
        formulation = options.get("formulation", default)
        if formulation not in ("primal", "dual"):
            raise OptionError(f"formulation: {formulation!r}; it is 'primal' or 'dual'")
        u_free, forces, iterations, status, _ = solve_qpsolvers(
            model, law, origin, solver, formulation, settings)
        info = {"formulation": formulation}
    run = {"method": method, "status": status, "iterations": iterations,
           "seconds": time.perf_counter() - start, "info": info}
    return make_answer(model, law, u_free, forces, previous_u, run)


def _family(method: str) -> str:
    """Which route a method name takes, or a one-line refusal."""
    if not isinstance(method, str):
        raise OptionError(f"method: {method!r} is not a name")
    if method in OWN_METHODS:
        return method
    import qpsolvers

    if method.removeprefix("qpsolvers:") in qpsolvers.available_solvers:
        return "qpsolvers"
    raise OptionError(f"method: {method!r} unknown for Tresca; use one of {OWN_METHODS} or a "
                      f"QP backend ({', '.join(qpsolvers.available_solvers)})")


def _active_set(model: FrictionModel, law: Law, previous_u: np.ndarray, options: dict,
                start: float) -> FrictionAnswer:
    """The exact route (module docstring)."""
    b = model.reduced_rhs(previous_u)
    initial = options.get("initial")
    if initial is not None:
        initial = np.asarray(initial, dtype=float)
        if initial.shape != b.shape:
            raise OptionError(f"initial: shape {initial.shape}; it needs {b.size} forces")
    forces, sets, iterations, status = active_set(model, law, b, initial, max_sets=QUICK_SETS)
    info = {"start": "zero" if initial is None else "initial"}
    if status != "solved":  # the rule cycled or stalled: start again from the dual's answer
        info["restart"] = status
        forces, sets, more, status = active_set(model, law, b, reduced_socp(model, law, b))
        iterations += more
        info["start"] = "reduced dual by clarabel"
    run = {"method": "active_set", "status": status, "iterations": iterations,
           "seconds": time.perf_counter() - start, "info": info}
    return make_answer(model, law, model.displacement(forces), forces, previous_u, run,
                       sets if status == "solved" else None)
