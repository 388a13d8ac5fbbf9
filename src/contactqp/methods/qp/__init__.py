"""The QP method: the contact problem handed to a QP solver, whose dual values are the contact
forces.

    module         what it holds
    problem.py     the QP data of a model, scaled to order one (QPProblem, scales)
    settings.py    what accuracy="default" | "high" means per solver (one table)
    outcome.py     what every backend hands back (QPOutcome)
    clarabel_.py, osqp_.py, cvxpy_.py, qpsolvers_.py
                   one module per backend, one contract: installed_solvers(), canonical(name),
                   solve(qp, solver, settings, verbose) -> QPOutcome; imported on first use,
                   so that importing contactqp loads no solver

Every backend writes the stationarity condition K̂x + q̂ + Cᵀμ = 0 with its dual μ of the rows
(Clarabel: z of A x + s = b; OSQP: y of l <= A x <= u; cvxpy: ``dual_value`` of ``C @ x <= g``,
expression on the left; qpsolvers: z of G x <= h, y of A x = b), so μ is the contact force in
units of F for every one of them; the tests check each backend against Lagrange for a wall
that pushes and one that pulls.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

import numpy as np

from contactqp.errors import ContactqpError, OptionError, SolverNotAvailable
from contactqp.methods.base import Solution
from contactqp.methods.qp.outcome import QPOutcome, failed_outcome
from contactqp.methods.qp.problem import QPProblem, qp_from_model, qp_problem, scales
from contactqp.methods.qp.settings import ACCURACIES, accuracy_settings
from contactqp.model import Condensed, Model
from contactqp.progress import silenced

PIP_SOLVERS = 'pip install "contactqp[solvers]"'


@dataclass(frozen=True)
class Backend:
    """A QP backend: its module (imported on first use), the pip install that adds it, its
    default solver and every solver it can offer, with the pip package of each."""

    module: str
    pip: str
    default: str
    known: dict[str, str] = field(default_factory=dict)


BACKENDS: dict[str, Backend] = {
    "clarabel": Backend("contactqp.methods.qp.clarabel_", "pip install clarabel", "clarabel",
                        {"clarabel": "clarabel"}),
    "osqp": Backend("contactqp.methods.qp.osqp_", "pip install osqp", "osqp", {"osqp": "osqp"}),
    "cvxpy": Backend("contactqp.methods.qp.cvxpy_", "pip install cvxpy", "CLARABEL", {
        "CLARABEL": "clarabel", "OSQP": "osqp", "SCS": "scs", "ECOS": "ecos",
        "CVXOPT": "cvxopt", "PIQP": "piqp", "PROXQP": "proxsuite", "DAQP": "daqp",
        "HIGHS": "highspy", "QPALM": "qpalm"}),
    "qpsolvers": Backend("contactqp.methods.qp.qpsolvers_",
                         'pip install "qpsolvers[open_source_solvers]"', "clarabel", {
                             "clarabel": "clarabel", "osqp": "osqp", "scs": "scs",
                             "ecos": "ecos", "cvxopt": "cvxopt", "piqp": "piqp",
                             "proxqp": "proxsuite", "daqp": "daqp", "highs": "highspy",
                             "qpalm": "qpalm", "quadprog": "quadprog"}),
}
_LOADED: dict[str, ModuleType | None] = {}
MISSING: dict[str, str] = {}  # backend -> why it could not be imported

# Chosen by measurement (benchmarks/run.py --cases overhead,survey). Clarabel is a core
# dependency, and at "default" it was verified on every scene tried (the default scene, walls
# on both sides, 1e4 and 1e5 elements: λ within 1e-10, 5e-10 at 1e5), never claimed success
# when wrong, and is the fastest direct call (27 µs on the default scene, 19 ms at 1e4).
# Scaling on: in SI units HiGHS (7.6 % off), QPALM (1 %) and quadprog (no solution) fail on the
# default scene, and OSQP's high accuracy needs 17 s instead of 0.04 s at 1e4 elements; scaled,
# only ProxQP at its loose default tolerance did worse (1.7e-2 off against 1e-7 in SI).
DEFAULT_BACKEND = "clarabel"
DEFAULT_SCALE = True

# Solvers that turn K into a dense n x n matrix: refused above this many unknowns, where the
# dense matrix alone would take DENSE_LIMIT² · 8 bytes (200 MB) and the solve O(n³).
DENSE_LIMIT = 5000
DENSE_SOLVERS = {("qpsolvers", "daqp"), ("qpsolvers", "quadprog"), ("qpsolvers", "ecos"),
                 ("qpsolvers", "qpoases"), ("qpsolvers", "pyqpmad"), ("qpsolvers", "nppro"),
                 ("qpsolvers", "qpax"), ("cvxpy", "DAQP"), ("cvxpy", "PROXQP")}


def backend_module(name: str) -> ModuleType | None:
    """The module of backend ``name``, imported on first use; None when it cannot be."""
    if name not in _LOADED:
        try:
            _LOADED[name] = importlib.import_module(BACKENDS[name].module)
        except ImportError as error:
            _LOADED[name] = None
            MISSING[name] = str(error)
    return _LOADED[name]


def _backend(name: Any) -> ModuleType:
    if not isinstance(name, str) or name not in BACKENDS:
        raise OptionError(f"backend must be one of {', '.join(BACKENDS)}; got {name!r}")
    module = backend_module(name)
    if module is None:
        installed = [b for b in BACKENDS if backend_module(b) is not None]
        raise SolverNotAvailable(
            f"QP backend {name!r} is not installed ({MISSING.get(name, 'import failed')}); "
            f"{BACKENDS[name].pip} or {PIP_SOLVERS}. Installed backends: "
            f"{', '.join(installed) or 'none'}"
        )
    return module


def resolve_solver(backend: str, solver: str | None) -> tuple[ModuleType, str]:
    """(backend module, solver name in the backend's spelling); OptionError for an unknown
    name, SolverNotAvailable (with the pip install) for a known one that is not installed."""
    module = _backend(backend)
    known = BACKENDS[backend].known
    installed = module.installed_solvers()
    if solver is None:
        default = BACKENDS[backend].default
        if default in installed:
            return module, default
        if not installed:
            raise SolverNotAvailable(f"QP backend {backend!r} finds no solver it can use; "
                                     f"{PIP_SOLVERS}")
        return module, installed[0]
    if not isinstance(solver, str):
        raise OptionError(f"solver must be a solver name (str) or None, got {solver!r}")
    name = module.canonical(solver)
    if name in installed:
        return module, name
    if name in known:
        raise SolverNotAvailable(
            f"solver {solver!r} of backend {backend!r} is not installed; pip install "
            f"{known[name]} (or {PIP_SOLVERS}). Installed: {', '.join(installed) or 'none'}"
        )
    choices = sorted(set(known) | set(installed))
    raise OptionError(f"backend {backend!r} has no solver {solver!r}; choices: {', '.join(choices)}")


@dataclass(frozen=True)
class QPSolverInfo:
    """One backend/solver pair: whether it is installed and usable, and how to add it."""

    backend: str
    solver: str
    available: bool
    install: str


def available_qp_solvers() -> tuple[QPSolverInfo, ...]:
    """Every backend/solver pair contactqp knows, installed and usable or not, with the
    ``pip install`` that adds a missing one. Installed pairs come first. (Imports every
    backend.)

    Returns
    -------
    tuple of QPSolverInfo
        backend, solver, whether it is available, and the ``pip install`` that adds it.
    """
    rows = []
    for name, backend in BACKENDS.items():
        module = backend_module(name)
        installed = () if module is None else module.installed_solvers()
        rows += [QPSolverInfo(name, s, True, "") for s in installed]
        missing = backend.pip if module is None else None
        rows += [QPSolverInfo(name, s, False,
                              f"{missing or 'pip install ' + package} (or {PIP_SOLVERS})")
                 for s, package in backend.known.items() if s not in installed]
    return tuple(sorted(rows, key=lambda r: not r.available))


def guarded(solve: Any, qp: QPProblem, *args: Any, verbose: bool = False) -> QPOutcome:
    """Call a backend's solve; anything the solver raises becomes a failed outcome (the Result
    check then flags it). The library's own errors (user mistakes) pass through. Whatever the
    solver prints goes nowhere unless ``verbose`` (:func:`contactqp.progress.silenced`)."""
    try:
        if verbose:
            return solve(qp, *args)
        with silenced():
            return solve(qp, *args)
    except (KeyboardInterrupt, SystemExit, ContactqpError):
        raise
    except BaseException as error:  # noqa: BLE001 - Rust solvers panic with a BaseException
        return failed_outcome(qp.n, qp.g.size + qp.n_ties, f"raised {type(error).__name__}: {error}")


def attempted(module: ModuleType, backend: str, name: str, qp: QPProblem,
              settings: dict[str, Any], verbose: bool) -> QPOutcome:
    """The backend's outcome on ``qp`` (:func:`guarded`), or a failed outcome that says why
    it was not attempted: a solver that works on dense matrices, past DENSE_LIMIT unknowns
    (DAQP through cvxpy and ECOS through qpsolvers crashed the interpreter on a model of 10⁵
    dofs: a crash in a solver's C code cannot be caught, so it is not risked)."""
    if (backend, name) in DENSE_SOLVERS and qp.n > DENSE_LIMIT:
        return failed_outcome(
            qp.n, qp.g.size + qp.n_ties,
            f"not attempted: {name} works on dense matrices and this model has {qp.n} "
            f"unknowns (limit {DENSE_LIMIT}); clarabel, osqp and piqp take sparse ones")
    return guarded(module.solve, qp, name, settings, verbose, verbose=verbose)


def solve_qp(model: Model | Condensed, contact: str, *, backend: str = DEFAULT_BACKEND,
             solver: str | None = None, accuracy: str = "default",
             scale: bool = DEFAULT_SCALE, formulation: str = "full",
             verbose: bool = False) -> Solution:
    """Solve the contact problem as a QP with ``backend`` ("clarabel", "osqp", "cvxpy",
    "qpsolvers") and ``solver`` (a name the backend knows; None: its default), at
    ``accuracy`` "default" or "high" (:mod:`~contactqp.methods.qp.settings`), scaled or in the
    scene's own units (``scale``), as the QP in displacements (``formulation="full"``) or with
    element elongations ("strain"; the tie rows' multipliers, the element forces, go to
    ``info``). ``verbose``: let the solver print its progress (by default nothing is)."""
    module, name = resolve_solver(backend, solver)
    settings = accuracy_settings(name, accuracy, scaled=scale, backend=backend)
    start = time.perf_counter()
    qp = qp_from_model(model, contact, scale, formulation)
    built = time.perf_counter()
    label = backend if name == backend else f"{backend}/{name}"
    outcome = attempted(module, backend, name, qp, settings, verbose)
    dual = np.asarray(outcome.dual, dtype=float)  # of qp.rows(): the ties, then the contacts
    u_free, contact_force = qp.to_si(outcome.x, dual[qp.n_ties:])
    info = {"backend": backend, "solver": name, "accuracy": accuracy, "scale": bool(scale),
            "qp_unknowns": qp.n,
            "displacement_scale": qp.displacement_scale, "force_scale": qp.force_scale,
            "time_qp_data": built - start, **outcome.info}
    if qp.ties is not None:
        info["element_force"] = qp.force_scale * dual[: qp.n_ties]
    return Solution(u_free, contact_force, solver=label, iterations=int(outcome.iterations),
                    status=outcome.status, claimed_success=bool(outcome.claimed_success),
                    info=info)


__all__ = [
    "ACCURACIES",
    "BACKENDS",
    "DEFAULT_BACKEND",
    "DEFAULT_SCALE",
    "DENSE_LIMIT",
    "QPOutcome",
    "QPProblem",
    "QPSolverInfo",
    "attempted",
    "available_qp_solvers",
    "backend_module",
    "qp_from_model",
    "qp_problem",
    "resolve_solver",
    "scales",
    "solve_qp",
]
