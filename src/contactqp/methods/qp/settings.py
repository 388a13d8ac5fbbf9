"""What ``accuracy="default" | "high"`` means for each QP solver: one table, written once.

The scaled QP is O(1), so absolute and relative tolerances are mostly alike. "default" is the
solver's own default, written out so that every backend passes the same values (cvxpy would
substitute its own for some, e.g. OSQP 1e-5), with two changes: OSQP's polishing, on in both
(cheap, and passed explicitly because cvxpy turns it off on a re-solve); and Clarabel's
relative duality gap, 1e-12 where its own is 1e-8 (1e-14 at "high"). The objective of a model
loaded by prescribed motion is not O(1) after scaling (the pull of the prescribed dofs is in
it), and a gap relative to it let Clarabel stop 1.3e-2·F off on the 2D Hertz cylinder (19 214
dofs) and 9.6e-4·F off on the 3D sphere (12 930 dofs), 1e-5 and 1.5e-5 at a relative gap of
1e-10; at 1e-12 both are verified, 1.1e-7 and 1.5e-7 off, in 11 and 9 iterations against 8
and 7 (measured 2026-11-27). "high" is near what each solver reaches in double precision. :func:`accuracy_table` prints the table docs/howto/qp_solvers.md shows (a test
checks that they agree).
"""

from __future__ import annotations

from typing import Any

from contactqp.errors import OptionError

ACCURACIES = ("default", "high")

ACCURACY: dict[str, dict[str, dict[str, Any]]] = {
    "clarabel": {
        "default": {"tol_gap_abs": 1e-8, "tol_gap_rel": 1e-12, "tol_feas": 1e-8,
                    "tol_ktratio": 1e-6},
        "high": {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-14, "tol_feas": 1e-10,
                 "tol_ktratio": 1e-8},
    },
    "osqp": {
        "default": {"eps_abs": 1e-3, "eps_rel": 1e-3, "max_iter": 4000, "polishing": True},
        "high": {"eps_abs": 1e-9, "eps_rel": 1e-9, "max_iter": 100_000, "polishing": True,
                 "polish_refine_iter": 10},
    },
    "scs": {
        "default": {"eps_abs": 1e-4, "eps_rel": 1e-4, "max_iters": 100_000},
        "high": {"eps_abs": 1e-9, "eps_rel": 1e-9, "max_iters": 100_000},
    },
    "ecos": {
        "default": {"abstol": 1e-8, "reltol": 1e-8, "feastol": 1e-8},
        "high": {"abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10},
    },
    "cvxopt": {
        "default": {"abstol": 1e-7, "reltol": 1e-6, "feastol": 1e-7},
        "high": {"abstol": 1e-8, "reltol": 1e-8, "feastol": 1e-8},
    },
    "piqp": {
        "default": {"eps_abs": 1e-8, "eps_rel": 1e-9},
        "high": {"eps_abs": 1e-10, "eps_rel": 1e-11},
    },
    "proxqp": {
        "default": {"eps_abs": 1e-5, "eps_rel": 0.0},
        "high": {"eps_abs": 1e-10, "eps_rel": 0.0, "check_duality_gap": True,
                 "eps_duality_gap_abs": 1e-10, "eps_duality_gap_rel": 0.0},
    },
    "qpalm": {
        "default": {"eps_abs": 1e-4, "eps_rel": 1e-4},
        "high": {"eps_abs": 1e-10, "eps_rel": 1e-10},
    },
    "daqp": {
        "default": {"primal_tol": 1e-6, "dual_tol": 1e-12},
        "high": {"primal_tol": 1e-10, "dual_tol": 1e-12},
    },
    "highs": {
        "default": {"primal_feasibility_tolerance": 1e-7, "dual_feasibility_tolerance": 1e-7},
        "high": {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10,
                 "qp_regularization_value": 1e-12},
    },
    "quadprog": {"default": {}, "high": {}},
}

# Where one backend's rewrite of the QP needs other settings than the solver's entry above.
# qpsolvers hands ECOS a cone rewrite through a Cholesky factor of P: at 1e-10 the contact force
# stayed 3.9e-8 off on the condensed 1e6-element bar, at 1e-12 1.8e-10 (measured); cvxpy's
# rewrite for ECOS is right at 1e-10 (5e-9) and fails an open-gap equality scene at 1e-12.
BACKEND_ACCURACY: dict[tuple[str, str], dict[str, dict[str, Any]]] = {
    ("qpsolvers", "ecos"): {"high": {"abstol": 1e-12, "reltol": 1e-12, "feastol": 1e-12}},
}

# Settings added when contactqp has scaled the QP itself. Measured on a 1e4-element bar at
# "default": Clarabel's equilibration on top of ours 1.2e-8 off in λ, off 9e-11; at 1e5
# elements on: "AlmostSolved" 1.3e-4 off, off: "Solved" 5e-10 off in 6 iterations. OSQP's
# Ruiz scaling on: "solved" 2.5e-4 off (a false success), off: 5e-12 off.
PRESCALED: dict[str, dict[str, Any]] = {
    "clarabel": {"equilibrate_enable": False},
    "osqp": {"scaling": 0},
}


# Settings every accuracy gets, so that a solver that can loop without end stops: HiGHS's QP
# solver, with a Hessian only positive semidefinite (a bar held by contact alone) and
# "high"'s regularisation of 1e-12, ran on for over 15 minutes on a random scene of three bars
# (random_scenes seed 263, floating 0.6), through qpsolvers and through cvxpy alike; with a
# time limit it stops and says so ("not found", "user_limit"), and the check flags the answer.
ALWAYS: dict[str, dict[str, Any]] = {
    "highs": {"time_limit": 60.0},  # s; its largest legitimate solves here take under 40 s
}


def accuracy_settings(solver: str, accuracy: str, scaled: bool = False,
                      backend: str | None = None) -> dict[str, Any]:
    """The settings ``accuracy`` means for ``solver`` (any case) through ``backend`` (None: any;
    :data:`BACKEND_ACCURACY` overrides), plus :data:`PRESCALED` when contactqp has ``scaled``
    the QP.

    The scaled QP is O(1), so absolute and relative tolerances are alike. "default" is the
    solver's own default, written out so that every backend passes the same values (cvxpy
    would substitute its own for some, e.g. OSQP 1e-5); the one change is OSQP's polishing, on
    in both (cheap, and passed explicitly because cvxpy turns it off on a re-solve). "high" is
    near what each solver reaches in double precision.

    The values are :data:`ACCURACY` (:func:`accuracy_table` writes them as the table of docs/howto/qp_solvers.md).

    (a) cvxpy hands CVXOPT a cone rewrite of the QP, and CVXOPT fails there at 1e-9 on a
        six-element bar with four walls (measured).
    (b) Without the duality-gap test ProxQP stopped 2e-6 off in λ at eps_abs 1e-10 (measured);
        cvxpy passes only eps_abs and eps_rel on to ProxQP, so through cvxpy the gap is unchecked.
    (c) HiGHS regularises the Hessian by 1e-7 by default, which leaves ~1e-7 in λ (measured).
    (d) At 1e-12 Clarabel stops "AlmostSolved" on a 1e4-element bar, though 1e-10 right.
    (e) 1e-12 through qpsolvers (:data:`BACKEND_ACCURACY`).

    Every accuracy adds :data:`ALWAYS` (a time limit for a solver that can loop without end).

    With ``scale=True`` the QP is already scaled, and :data:`PRESCALED` turns off Clarabel's
    and OSQP's own equilibration (through every backend), which measured better.
    """
    if accuracy not in ACCURACIES:
        raise OptionError(f"accuracy must be one of {', '.join(ACCURACIES)}; got {accuracy!r}")
    name = solver.lower()
    settings = dict(ACCURACY.get(name, {}).get(accuracy, {}))
    settings.update(ALWAYS.get(name, {}))
    settings.update(BACKEND_ACCURACY.get((backend or "", name), {}).get(accuracy, {}))
    return {**settings, **PRESCALED.get(name, {})} if scaled else settings


def accuracy_table() -> str:
    """:data:`ACCURACY` as the markdown table of docs/howto/qp_solvers.md: solver, "default", "high"."""
    def cell(settings: dict[str, Any]) -> str:
        return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                         for k, v in settings.items()) or "its defaults"

    lines = ["| solver | `default` | `high` |", "|---|---|---|"]
    for solver, levels in ACCURACY.items():
        high = cell(levels["high"]) if levels["high"] else ""
        for (backend, name), extra in BACKEND_ACCURACY.items():
            if name == solver and "high" in extra:
                high += f" ({cell(extra['high'])} through {backend})"
        lines.append(f"| {solver} | {cell(levels['default'])} | {high} |")
    return "\n".join(lines)


__all__ = ["ACCURACIES", "ACCURACY", "ALWAYS", "BACKEND_ACCURACY", "PRESCALED", "accuracy_settings",
           "accuracy_table"]
