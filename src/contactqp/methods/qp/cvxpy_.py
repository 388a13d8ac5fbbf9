"""QP backend: cvxpy, with any installed cvxpy solver that takes a QP.

The problem is written once per scene structure as a parametrised (DPP) problem and cached, so
a new load or gap only sets parameters and re-solves without re-canonicalising:

    minimise ½ quad_form(x, psd_wrap(K)) + p @ x[loaded]   subject to  C @ x <= gaps  (or ==)

Facts (cvxpy 1.9.3) that shape it:
- K is wrapped in ``cp.psd_wrap``: without it the PSD check densifies K (1e5 elements exhaust
  memory).
- The parameters are low-dimensional: p holds q at the loaded unknowns only, ``gaps`` one value
  per wall. cvxpy densifies the objective's coefficients as an (unknowns + 2) × (parameter
  entries + 1) array (``coeff_extractor.extract_quadratic_coeffs``): 74.5 GiB with a wall at
  every one of 1e5 nodes. So a vector is a parameter only while that array stays under
  ``DENSE_LIMIT`` entries (loads first, then gaps); otherwise it is a constant, its values are
  part of the cache key, and the Result's ``info["parameters"]`` says which are parameters.
- Rows are written ``C @ x <= gaps`` / ``C @ x == gaps``, expression on the left: with the
  parameter on the left the equality's dual changes sign.
- On a re-solve cvxpy turns OSQP's polishing off unless it is passed, so the accuracy table
  always passes it.
"""

from __future__ import annotations

import functools
import hashlib
import time
import warnings
from collections import OrderedDict
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import cvxpy as cp
import numpy as np
import scipy.sparse as sp
from cvxpy.reductions.solvers import defines

from contactqp.methods.qp.outcome import QPOutcome, vector_or_nan

if TYPE_CHECKING:
    from contactqp.methods.qp.problem import QPProblem

# Branch-and-bound wrappers of a solver that is listed anyway.
MIXED_INTEGER_ONLY = {"ECOS_BB", "GLPK_MI"}
# cvxpy runs ProxQP dense: its backend="sparse" path fails with the installed proxsuite
# (TypeError in proxqp.sparse.QP), so ProxQP is limited to small bars (qp.DENSE_SOLVERS).
CACHE_SIZE = 4  # scene structures kept (each holds its canonicalised problem)
DENSE_LIMIT = 2**25  # entries (256 MiB) of cvxpy's dense objective coefficients


def takes_qp(name: str) -> bool:
    """Whether the installed cvxpy solver ``name`` solves a QP: a QP solver, or a conic solver
    with a quadratic objective or second-order cones (cvxpy rewrites the QP for it)."""
    if name in MIXED_INTEGER_ONLY:
        return False
    if name in defines.SOLVER_MAP_QP:
        return True
    conic = defines.SOLVER_MAP_CONIC.get(name)
    return conic is not None and (
        conic.supports_quad_obj() or cp.constraints.SOC in conic.SUPPORTED_CONSTRAINTS
    )


@functools.cache
def installed_solvers() -> tuple[str, ...]:
    # cached: cvxpy looks for every solver's module on each call (milliseconds of imports)
    return tuple(name for name in cp.installed_solvers() if takes_qp(name))


def canonical(solver: str) -> str:
    return solver.upper()


@dataclass(frozen=True, eq=False)
class Structure:
    """A canonicalisable problem for one scene structure, with its parameters."""

    problem: cp.Problem
    x: cp.Variable
    loaded: np.ndarray
    loads: cp.Parameter | None
    gaps: cp.Parameter | None
    rows: cp.Constraint | None
    tie_rows: cp.Constraint | None = None

    @property
    def parameters(self) -> str:
        """Which vectors are cvxpy parameters (set on a re-solve) rather than constants."""
        names = [name for name, value in (("loads", self.loads), ("gaps", self.gaps))
                 if value is not None]
        return ", ".join(names) or "none"


_CACHE: OrderedDict[bytes, Structure] = OrderedDict()


def parametrised(n: int, n_loaded: int, n_rows: int) -> tuple[bool, bool]:
    """(loads, gaps): which vectors can be parameters with cvxpy's dense objective
    coefficients, (n + 2) × (parameter entries + 1), under ``DENSE_LIMIT`` entries."""
    loads = n_loaded > 0 and (n + 2) * (n_loaded + 1) <= DENSE_LIMIT
    gaps = n_rows > 0 and (n + 2) * (n_loaded * loads + n_rows + 1) <= DENSE_LIMIT
    return loads, gaps


def _key(qp: QPProblem, loaded: np.ndarray) -> bytes:
    digest = hashlib.sha256(qp.contact.encode())
    ties = qp.ties if qp.ties is not None else sp.csc_array((0, qp.n))
    arrays = [np.array(qp.K.shape), qp.K.indptr, qp.K.indices, qp.K.data,
              qp.C.indptr, qp.C.indices, qp.C.data, ties.indptr, ties.indices, ties.data, loaded]
    loads, gaps = parametrised(qp.n, loaded.size, qp.g.size)
    arrays += [qp.q[loaded]] * (not loads) + [qp.g] * (not gaps)  # constants: their values
    for array in arrays:
        digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(b"|")
    return digest.digest()


def build_structure(K: sp.sparray, C: sp.sparray, q: np.ndarray, g: np.ndarray, contact: str,
                    ties: sp.sparray | None = None) -> Structure:
    """The DPP problem of a structure: parameters for the loads at q's nonzeros and for the
    gaps while they fit (``parametrised``), constants otherwise; the strain formulation's
    ``ties`` are constant rows ``T @ x == 0``."""
    n = K.shape[0]
    loaded = np.flatnonzero(q)
    x = cp.Variable(n)
    objective = 0.5 * cp.quad_form(x, cp.psd_wrap(sp.csc_matrix(K)))
    loads = gaps = rows = tie_rows = None
    loads_parameter, gaps_parameter = parametrised(n, loaded.size, C.shape[0])
    if loaded.size:
        loads = cp.Parameter(loaded.size) if loads_parameter else None
        objective = objective + (loads if loads_parameter else q[loaded]) @ x[loaded]
    constraints = []
    if ties is not None:
        tie_rows = sp.csr_matrix(ties) @ x == 0
        constraints.append(tie_rows)
    if C.shape[0]:
        gaps = cp.Parameter(C.shape[0]) if gaps_parameter else None
        Cx = sp.csr_matrix(C) @ x
        right = gaps if gaps_parameter else g
        rows = Cx <= right if contact == "inequality" else Cx == right
        constraints.append(rows)
    problem = cp.Problem(cp.Minimize(objective), constraints)
    return Structure(problem, x, loaded, loads, gaps, rows, tie_rows)


def structure(qp: QPProblem) -> tuple[Structure, bool]:
    """(the cached structure of ``qp``, whether it was already cached)."""
    loaded = np.flatnonzero(qp.q)
    key = _key(qp, loaded)
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key], True
    built = build_structure(qp.K, qp.C, qp.q, qp.g, qp.contact, qp.ties)
    _CACHE[key] = built
    while len(_CACHE) > CACHE_SIZE:
        _CACHE.popitem(last=False)
    return built, False


def clear_cache() -> None:
    _CACHE.clear()


def solve(qp: QPProblem, solver: str, settings: dict[str, Any],
          verbose: bool = False) -> QPOutcome:
    """Solve ``qp`` through cvxpy with ``solver``; ``settings`` go to the solver."""
    start = time.perf_counter()
    cached, hit = structure(qp)
    if cached.loads is not None:
        cached.loads.value = qp.q[cached.loaded]
    if cached.gaps is not None:
        cached.gaps.value = qp.g
    ready = time.perf_counter()
    with warnings.catch_warnings():
        # the status says so ("optimal_inaccurate", which claims nothing), and the check decides
        warnings.filterwarnings("ignore", message="Solution may be inaccurate")
        cached.problem.solve(solver=solver, warm_start=False, verbose=verbose, **settings)
    solved = time.perf_counter()
    stats = cached.problem.solver_stats
    status = str(cached.problem.status)
    parts = [(cached.tie_rows, qp.n_ties), (cached.rows, qp.g.size)]
    dual = np.concatenate([np.zeros(0)] + [vector_or_nan(row.dual_value, size)
                                           for row, size in parts if size])
    return QPOutcome(
        vector_or_nan(cached.x.value, qp.n), dual, status,
        claimed_success=status == cp.OPTIMAL, iterations=int(stats.num_iters or 0),
        info={"time_setup": (ready - start) + (cached.problem.compilation_time or 0.0),
              "time_solve": (solved - ready) - (cached.problem.compilation_time or 0.0),
              "time_solver": stats.solve_time, "cache": "hit" if hit else "miss",
              "parameters": cached.parameters},
    )
