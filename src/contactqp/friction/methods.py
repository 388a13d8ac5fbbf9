"""The methods :func:`contactqp.solve` runs on a Problem with friction, by the names it knows.

=====================  ==========================================  ===========================
method                 Tresca (``slip_bound``)                     Coulomb (``mu``)
=====================  ==========================================  ===========================
``"lagrange"``         the exact route: the active set on the      the fixed point s ← μλ_N(s),
                       multipliers (:mod:`.tresca`), exact up to   each Tresca problem by the
                       round-off                                   exact route (the default)
``"qp"``               one QP (2D) / SOCP (3D) by a backend        the fixed point, each
                       (``backend``, ``solver``, ``dual``); its    Tresca problem by that
                       duals are the friction forces               backend
``"cone"``             refused (Coulomb's)                         Acary–Cadoux's SOCPs
``"relaxed"``          refused (Coulomb's)                         the convex relaxation
                                                                   (Anitescu–Tasora, MuJoCo)
``"semismooth_newton"``  the exact route (as lagrange)             the active set on Coulomb's
                                                                   sets (2D only)
``"penalty"``          the penalty-regularised law (stiff springs, the return mapping;
                       :mod:`.penalty`), 2D and 3D; it leaves a penetration and a creep
``"augmented"``        that law with Uzawa's update of the multipliers (the augmented
                       Lagrangian), 2D and 3D, until they settle
=====================  ==========================================  ===========================

``lemke``, ``pgs`` and ``nitsche`` do not take friction: each refuses in one line
(:data:`REFUSED`). Options, each checked here in one line: ``qp``:
``backend`` ("clarabel", the default; "cvxpy"; "osqp"; "qpsolvers" with ``solver``),
``solver`` (a qpsolvers backend, or cvxpy's solver), ``dual`` (the box QP in the forces, for
backends that need a positive definite Hessian), ``settings`` (the backend's own);
Coulomb's ``lagrange``, ``qp`` and ``cone``: ``max_iterations`` (default 100), ``tolerance``
(default 1e-10: the change of the bound μλ_N, over F, that ends the fixed point);
``penalty``: ``penalty`` (one ε for every row, force/length); ``augmented``: ``penalty``,
``max_iterations`` and ``tolerance`` (of the change of the multipliers, over F).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from contactqp._validate import flag, positive_number, whole_number
from contactqp.errors import OptionError
from contactqp.friction.answer import FrictionAnswer
from contactqp.friction.coulomb import solve_coulomb
from contactqp.friction.model import FrictionModel
from contactqp.friction.tresca import solve_tresca

BACKENDS = ("clarabel", "cvxpy", "osqp", "qpsolvers")
TRESCA_METHODS = ("lagrange", "qp", "semismooth_newton", "penalty", "augmented")
COULOMB_METHODS = ("lagrange", "qp", "cone", "relaxed", "semismooth_newton", "penalty",
                   "augmented")
OPTIONS = {"lagrange": ("max_iterations", "tolerance"),
           "qp": ("backend", "solver", "dual", "settings", "max_iterations", "tolerance"),
           "cone": ("max_iterations", "tolerance"), "relaxed": (), "semismooth_newton": (),
           "penalty": ("penalty",), "augmented": ("penalty", "max_iterations", "tolerance")}
FIXED_POINT = ("lagrange", "qp", "cone")  # their max_iterations and tolerance: Coulomb's loop
USE = "use lagrange (exact), qp, cone or relaxed"
REFUSED = {
    "lemke": "lemke solves the LCP of normal contact; friction's law (a box or a disc, μλ_N "
             f"for Coulomb) is not that LCP; {USE}",
    "pgs": "pgs solves the LCP of normal contact; friction's law (a box or a disc, μλ_N for "
           f"Coulomb) is not that LCP; {USE}",
    "nitsche": "nitsche needs the traction σ(u)·n on the contact boundary, which a model of "
               f"matrices does not carry, and has no friction here; {USE}",
}


def checked_friction_options(law: str, method: Any, options: dict[str, Any]) -> dict[str, Any]:
    """``options`` for ``method`` on a problem with ``law`` ("tresca" or "coulomb"), each
    checked; an OptionError of one line for a method that does not take the law, or a bad
    option."""
    if isinstance(method, str) and method in REFUSED:
        raise OptionError(REFUSED[method])
    names = TRESCA_METHODS if law == "tresca" else COULOMB_METHODS
    if not isinstance(method, str) or method not in OPTIONS:
        raise OptionError(f"method must be one of {', '.join(names)} for a problem with "
                          f"friction ({law}); got {method!r}")
    if method not in names:
        raise OptionError(f"{method} is one of Coulomb's methods and this problem has "
                          "Tresca's slip_bound, one convex problem: use lagrange or qp")
    allowed = OPTIONS[method] if law == "coulomb" or method not in FIXED_POINT else tuple(
        name for name in OPTIONS[method] if name not in ("max_iterations", "tolerance"))
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        takes = ", ".join(allowed) or "no options"
        raise OptionError(f"option {unknown[0]!r} does not apply to {method} with {law} "
                          f"friction (it takes {takes})")
    return {key: _checked(key, value) for key, value in options.items()}


def _checked(key: str, value: Any) -> Any:
    if key == "backend" and value not in BACKENDS:
        raise OptionError(f"backend must be one of {', '.join(BACKENDS)} with friction; got "
                          f"{value!r}")
    if key == "solver" and value is not None and not isinstance(value, str):
        raise OptionError(f"solver must be a name (text), got {value!r}")
    if key == "dual":
        return flag("dual", value, OptionError)
    if key == "settings" and not isinstance(value, dict):
        raise OptionError(f"settings must be a dict of the backend's own settings, got "
                          f"{type(value).__name__}")
    if key == "max_iterations":
        count = whole_number("max_iterations", value, 1, error=OptionError)
        if count > 10**4:
            raise OptionError(f"max_iterations must be at most 10000 (Tresca solves), got "
                              f"{count}")
        return count
    if key == "tolerance":
        return positive_number("tolerance", value, "of the force scale F", OptionError)
    if key == "penalty":
        return positive_number("penalty", value, "force per length, e.g. N/m", OptionError)
    return value


def qp_route(options: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """(the friction package's method name, its options) for the ``qp`` options."""
    backend = options.get("backend", "clarabel")
    solver = options.get("solver")
    settings = dict(options.get("settings", {}))
    if backend == "cvxpy":
        return "cvxpy", {"settings": {**settings, **({"solver": solver} if solver else {})}}
    if backend == "clarabel":
        if solver not in (None, "clarabel"):
            raise OptionError(f"solver={solver!r} with backend='clarabel'; give "
                              "backend='qpsolvers' to choose a qpsolvers backend")
        if options.get("dual"):
            return "qpsolvers:clarabel", {"settings": settings, "formulation": "dual"}
        return "clarabel", {"settings": settings}
    name = "osqp" if backend == "osqp" else solver
    if not name:
        raise OptionError("backend='qpsolvers' needs solver= (a qpsolvers backend's name, "
                          "e.g. 'osqp', 'piqp', 'highs')")
    route: dict[str, Any] = {"settings": settings}
    if "dual" in options:
        route["formulation"] = "dual" if options["dual"] else "primal"
    return f"qpsolvers:{name}", route


def solve_friction(model: FrictionModel, law: str, values: np.ndarray, method: str,
                   options: dict[str, Any], previous_u: np.ndarray | None,
                   initial: np.ndarray | None = None) -> FrictionAnswer:
    """Solve one increment of a problem with friction by a method of this module's table
    (options already checked); ``initial``: forces to start the exact route from."""
    if method in ("penalty", "augmented"):
        from contactqp.friction.law import coulomb, tresca
        from contactqp.friction.penalty import solve_penalised

        made = tresca(model, values) if law == "tresca" else coulomb(model, values)
        return solve_penalised(model, made, previous_u, method == "augmented", options)
    if law == "tresca":
        if method == "qp":
            name, route = qp_route(options)
            return solve_tresca(model, values, previous_u=previous_u, method=name,
                                options=route)
        start = {} if initial is None or initial.size != model.rows.shape[0] else {
            "initial": initial}
        return solve_tresca(model, values, previous_u=previous_u, options=start)
    loop = {key: options[key] for key in ("max_iterations", "tolerance") if key in options}
    if method == "lagrange":
        return solve_coulomb(model, values, previous_u=previous_u, options=loop)
    if method == "qp":
        name, route = qp_route(options)
        return solve_coulomb(model, values, previous_u=previous_u, options={
            **loop, "tresca_method": name, "tresca_options": route})
    if method == "semismooth_newton":
        if model.d != 1:
            raise OptionError("semismooth_newton takes Coulomb in 2D only (its 3D slip "
                              "directions need a globalisation it lacks); use lagrange, qp "
                              "or cone")
        return solve_coulomb(model, values, previous_u=previous_u, method="active_set")
    return solve_coulomb(model, values, previous_u=previous_u, method=method, options=loop)


__all__ = ["BACKENDS", "COULOMB_METHODS", "REFUSED", "TRESCA_METHODS",
           "checked_friction_options", "qp_route", "solve_friction"]
