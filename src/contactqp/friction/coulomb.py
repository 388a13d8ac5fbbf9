"""Coulomb's friction (‖λ_T,i‖ ≤ μᵢλ_N,i): no minimum principle, answers that need not be
unique, so every method here says how it ended.

- ``"fixed_point"``: Tresca's problem with sᵢ = μᵢλ_N,i of the previous iterate (Panagiotopoulos'
  fixed point; Siconos' TFP), from the frictionless answer's λ_N, each Tresca problem by an
  exact or QP route (``tresca_method``). It contracts when μ times the coupling of friction
  into the normal forces is small; where it is not, it can cycle
  (:func:`~.examples.cycling_fixed_point`): ``history`` has max|Δs|/F per iteration and the
  status says ``"not converged"``.
- ``"cone"``: Acary and Cadoux's sequence of convex second-order cone programs. De Saxcé's
  bipotential writes Coulomb's law as a complementarity between the friction cone
  ‖λ_T‖ ≤ μλ_N and its dual taken at the modified velocity (gap + μ‖v‖, −v); with the shift
  σᵢ = μᵢ‖vᵢ‖ frozen, that is the KKT system of the convex SOCP

      min ½uᵀKu − fᵀu  s.t.  ‖Tᵢ(u − u_prev)‖ ≤ (gᵢ + σᵢ − Cᵢu)/μᵢ,

  whose duals (μᵢλ_N,i, λ_T,i) lie in the friction cone; σ is updated from the slip until it
  settles. In 2D the cone is a wedge and each problem a QP. Solved by Clarabel.
- ``"relaxed"``: that SOCP once with σ = 0: the convex relaxation of Anitescu and Tasora, and of
  MuJoCo. It is not Coulomb's law: a sliding contact opens by μ‖v‖ while it carries its normal
  force (:func:`~.examples.sliding_block`); ``info["separation"]`` reports the largest such gap.
- ``"active_set"``: the active-set rule of :mod:`.reduced` on Coulomb's sets directly (a
  semismooth Newton method; no convergence guarantee: the status says when it cycles). 2D
  only: in 3D the slip direction's equations need a globalisation this rule does not have (on
  a four-contact case it stalls on its first set), and the method says so.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from contactqp.errors import OptionError, SolverError
from contactqp.friction.answer import FrictionAnswer, force_scale, make_answer
from contactqp.friction.law import TRESCA, Law, coulomb
from contactqp.friction.model import FrictionModel
from contactqp.friction.qp import TIGHT
from contactqp.friction.reduced import active_set, join, split
from contactqp.friction.tresca import solve_law

METHODS = ("fixed_point", "cone", "relaxed", "active_set")
OPTIONS = {
    "fixed_point": {"tresca_method", "tresca_options", "max_iterations", "tolerance"},
    "cone": {"max_iterations", "tolerance", "settings"},
    "relaxed": {"settings"},
    "active_set": {"initial"},
}
TOLERANCE = 1e-10  # a fixed point settles when its iterate changes by less than this of F / U
MAX_ITERATIONS = 100


def solve_coulomb(model: FrictionModel, mu, *, previous_u=None, method: str = "fixed_point",
                  options: dict | None = None) -> FrictionAnswer:
    """Solve an increment under Coulomb's law.

    Parameters
    ----------
    model : FrictionModel
        K, f, C, g, T; Coulomb needs the normal rows C.
    mu : float or array, m
        μᵢ per contact (a zero is frictionless).
    previous_u : array, n, optional
        The increment's start; the slip is T(u − previous_u). Default zero.
    method : str
        ``"fixed_point"``, ``"cone"``, ``"relaxed"`` or ``"active_set"`` (module docstring).
    options : dict, optional
        ``fixed_point``: ``tresca_method`` (default ``"active_set"``), ``tresca_options``
        (that method's options), ``max_iterations``
        (100), ``tolerance`` (1e-10 of F). ``cone``: ``max_iterations``, ``tolerance`` (of U),
        ``settings`` (Clarabel's). ``relaxed``: ``settings``. ``active_set``: ``initial``.

    Returns
    -------
    FrictionAnswer
        ``status`` ``"converged"`` or ``"not converged"`` (fixed points), ``"solved"`` or the
        rule's ``"cycled"`` (active set), ``"relaxed"``; ``history`` per iteration.
    """
    law = coulomb(model, mu)
    options = dict(options or {})
    if method not in METHODS:
        raise OptionError(f"method: {method!r} unknown for Coulomb; use one of {METHODS}")
    unknown = set(options) - OPTIONS[method]
    if unknown:
        raise OptionError(f"options: {sorted(unknown)} unknown for {method!r}; it takes "
                          f"{sorted(OPTIONS[method])}")
    previous_u = model.previous(previous_u)
    if method == "fixed_point":
        return _fixed_point(model, law, previous_u, options)
    if method == "active_set":
        if model.d != 1:
            raise OptionError("method: 'active_set' takes Coulomb in 2D only (its 3D slip "
                              "directions need a globalisation it lacks); use 'fixed_point' "
                              "or 'cone'")
        start = time.perf_counter()
        forces, sets, iterations, status = active_set(
            model, law, model.reduced_rhs(previous_u), options.get("initial"))
        run = {"method": method, "status": status, "iterations": iterations,
               "seconds": time.perf_counter() - start}
        return make_answer(model, law, model.displacement(forces), forces, previous_u, run,
                           sets if status == "solved" else None)
    return _cones(model, law, previous_u, options, relaxed=method == "relaxed")


def _fixed_point(model: FrictionModel, law: Law, previous_u: np.ndarray,
                 options: dict) -> FrictionAnswer:
    """s ← μ λ_N(s) on Tresca's problem (module docstring)."""
    method = options.get("tresca_method", "active_set")
    given = dict(options.get("tresca_options", {}))
    limit = int(options.get("max_iterations", MAX_ITERATIONS))
    tolerance = float(options.get("tolerance", TOLERANCE))
    start = time.perf_counter()
    answer = solve_law(model, Law(TRESCA, np.zeros(model.contacts)), previous_u, method, given)
    bound = law.values * answer.normal_force
    history, inner = [], []
    status = "not converged"
    for _ in range(limit):
        warm = {"initial": answer.forces} if method == "active_set" else given
        answer = solve_law(model, Law(TRESCA, bound), previous_u, method, warm)
        inner.append(answer.iterations)
        following = law.values * answer.normal_force
        scale = force_scale(model, law, answer.forces)
        history.append(float(np.abs(following - bound).max(initial=0.0)) / scale)
        bound = following
        if history[-1] <= tolerance:
            status = "converged"
            break
    run = {"method": "fixed_point", "status": status, "iterations": len(history),
           "seconds": time.perf_counter() - start, "history": history,
           "info": {"tresca_method": method, "tresca_iterations": inner}}
    return make_answer(model, law, answer.u[model.free], answer.forces, previous_u, run)


def _cones(model: FrictionModel, law: Law, previous_u: np.ndarray, options: dict,
           relaxed: bool) -> FrictionAnswer:
    """Acary and Cadoux's sequence of SOCPs, or its first (the relaxation)."""
    limit = 1 if relaxed else int(options.get("max_iterations", MAX_ITERATIONS))
    tolerance = float(options.get("tolerance", TOLERANCE))
    settings = dict(options.get("settings", {}))
    origin = model.slip_origin(previous_u)
    shift = np.zeros(model.contacts)
    start = time.perf_counter()
    history, steps = [], 0
    status = "not converged"
    for _ in range(limit):
        u_free, forces, iterations = _cone_program(model, law, origin, shift, settings)
        steps += iterations
        slip = (model.T @ u_free - origin).reshape(model.contacts, model.d)
        following = law.values * np.linalg.norm(slip, axis=1)
        scale = max(float(np.abs(u_free).max(initial=0.0)), 1e-300)
        history.append(float(np.abs(following - shift).max(initial=0.0)) / scale)
        shift = following
        if history[-1] <= tolerance:
            status = "converged"
            break
    info = {"interior_point_iterations": steps}
    if relaxed:
        status = "relaxed"
        gaps = model.gap - model.C @ u_free
        lam_N, _ = split(model, forces)
        pushing = lam_N > 1e-9 * force_scale(model, law, forces)
        info["separation"] = float(gaps[pushing].max(initial=0.0))
    run = {"method": "relaxed" if relaxed else "cone", "status": status,
           "iterations": len(history), "seconds": time.perf_counter() - start,
           "history": history, "info": info}
    return make_answer(model, law, u_free, forces, previous_u, run)


def _cone_program(model: FrictionModel, law: Law, origin: np.ndarray, shift: np.ndarray,
                  settings: dict) -> tuple[np.ndarray, np.ndarray, int]:
    """One SOCP of the sequence (module docstring) by Clarabel: (u, λ, iterations).

    Clarabel's rows are s = b − A x in a cone. A frictionless contact is a plain row
    C_i u ≤ g_i. A frictional one is the cone (sᵢ₀, s_T) = ((gᵢ + σᵢ − Cᵢu)/μᵢ, cᵢ − Tᵢu):
    A = (Cᵢ/μᵢ; Tᵢ), and stationarity K u − f + Cᵢᵀ z₀/μᵢ + Tᵢᵀ z_T = 0 reads λ_N = z₀/μᵢ,
    λ_T = z_T, with ‖z_T‖ ≤ z₀ the friction cone.
    """
    import clarabel

    mu, d, m = law.values, model.d, model.contacts
    frictional = np.flatnonzero(law.frictional)
    plain = np.flatnonzero(~law.frictional)
    rows, rhs, cones = [], [], []
    if plain.size:
        rows.append(model.C[plain])
        rhs.append(model.gap[plain])
        cones.append(clarabel.NonnegativeConeT(plain.size))
    for i in frictional:
        rows += [model.C[[i]] / mu[i], model.T[d * i:d * i + d]]
        rhs += [np.array([(model.gap[i] + shift[i]) / mu[i]]), origin[d * i:d * i + d]]
        cones.append(clarabel.SecondOrderConeT(d + 1))
    options = clarabel.DefaultSettings()
    options.verbose = False
    for key, value in {**TIGHT["clarabel"], **settings}.items():
        setattr(options, key, value)
    found = clarabel.DefaultSolver(sp.csc_matrix(sp.triu(model.K)), -model.load,
                                   sp.csc_matrix(sp.vstack(rows)), np.concatenate(rhs),
                                   cones, options).solve()
    if str(found.status) not in ("Solved", "AlmostSolved"):
        raise SolverError(f"clarabel: the cone program of Coulomb's law ended {found.status}")
    z = np.asarray(found.z)
    lam_N, lam_T = np.zeros(m), np.zeros((m, d))
    lam_N[plain] = z[:plain.size]
    cone_z = z[plain.size:].reshape(frictional.size, d + 1)
    lam_N[frictional] = cone_z[:, 0] / mu[frictional]
    lam_T[frictional] = cone_z[:, 1:]
    return np.asarray(found.x), join(lam_N, lam_T), int(found.iterations)
