"""Contact as a quadratic programme, solved by any installed QP solver.

The QP of a scene, in the scaled unknowns x = D / U (U a displacement scale, m):

    minimise    ½ xᵀ K̂ x + q̂ᵀ x          K̂ = K / k,  q̂ = −P / F,  k = F / U (N/m)
    subject to  C x <= ĝ   (inequality)   ĝ = g / U
                C x  = ĝ   (equality)

It is Π = ½ DᵀKD − DᵀP divided by F·U, so the multiplier μ of each row is the contact force in
units of F: λ = F·μ. The convention is the model's: L = Π + λᵀ(C D − g), λ >= 0 the force with
which a wall pushes the bar. With ``scale=False``, U = 1 m and F = 1 N (the QP in SI units).

Scaling (:func:`scales`): k is the stiffness the loaded and walled nodes see together,
1 / ‖K⁻¹e‖∞ with e = 1 at those nodes; U = max(‖K⁻¹P‖∞, largest −gap), the displacement the
loads cause without walls or the largest initial penetration (both from one banded
factorisation; the gaps only when nothing loads the bar); F = k·U. Then q̂, ĝ and the expected multipliers are O(1), and k depends only on where loads
and walls are, so a new load or gap changes q̂ and ĝ alone (the cvxpy backend re-solves
without re-canonicalising).

Backends (one module each, one contract, a registry filled by try-import):

    ==========  =================================  ========================================
    backend     solvers                            duals used
    ==========  =================================  ========================================
    clarabel    clarabel (its own Python API)      z of A x + s = b, s in the cone
    osqp        osqp (its own Python API, 1.x)     y of l <= A x <= u
    cvxpy       every installed cvxpy solver that  ``constraint.dual_value`` of ``C @ x <= g``
                takes a QP (CLARABEL, OSQP, ...)   or ``C @ x == g``
    qpsolvers   every name in                      z of G x <= h, y of A x = b
                ``qpsolvers.available_solvers``
    ==========  =================================  ========================================

:data:`DUAL_SIGNS` holds, in this one place, the sign that turns each backend's dual into μ
(every one of them writes the stationarity condition K̂x + q̂ + Cᵀμ = 0, so all are +1; the
tests check each). :data:`ACCURACY` maps ``accuracy="default" | "high"`` to each solver's own
settings (the table is in :func:`accuracy_settings`); :data:`PRESCALED` turns off Clarabel's and
OSQP's own equilibration on data contactqp has scaled. Solvers that densify K are not run above
:data:`DENSE_LIMIT` unknowns; that, and anything a solver raises, gives a NaN Solution that
claims nothing, which the Result's check flags.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import math
import os
import sys
import time
from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ContactqpError, OptionError, SolverNotAvailable
from contactqp.methods._qp_outcome import QPOutcome, failed_outcome
from contactqp.model import Model, build_model, contact_kind, elongation_rows
from contactqp.result import Solution
from contactqp.scene import Scene

ACCURACIES = ("default", "high")
PIP_SOLVERS = 'pip install "contactqp[solvers]"'

# ---------------------------------------------------------------------------------------------
# The QP data


@dataclass(frozen=True, eq=False)
class QPProblem:
    """The QP of a scene in scaled units: minimise ½ xᵀKx + qᵀx subject to C x <= g
    (``contact="inequality"``) or C x = g (``"equality"``).

    Attributes
    ----------
    K : scaled stiffness K_SI / stiffness_scale (dimensionless), sparse symmetric, CSC.
    q : scaled linear term −P_SI / force_scale (dimensionless).
    C : constraint rows, one per wall (dimensionless, ±1), CSC.
    g : scaled right-hand sides gap / displacement_scale (dimensionless).
    contact : "inequality" or "equality".
    displacement_scale : U (m): the displacements are D = U·x.
    force_scale : F (N): the contact forces are λ = F·μ, μ the multipliers of the scaled QP
        with the convention L = ½ xᵀKx + qᵀx + μᵀ(C x − g).
    ties : the strain formulation's tie rows T x = 0 (B u − e = 0: each element's elongation
        e tied to the displacements u), or None. Then x = [u; e], K = diag(0, k_e / k) and
        the multipliers of the tie rows are the element forces in units of F.
    """

    K: sp.csc_array
    q: np.ndarray
    C: sp.csc_array
    g: np.ndarray
    contact: str
    displacement_scale: float = 1.0
    force_scale: float = 1.0
    ties: sp.csc_array | None = None

    @property
    def n_ties(self) -> int:
        """Number of tie rows (0 unless the strain formulation)."""
        return 0 if self.ties is None else int(self.ties.shape[0])

    @property
    def n_displacements(self) -> int:
        """Number of displacement unknowns: the first entries of x."""
        return self.n - self.n_ties

    def rows(self) -> sp.csc_array:
        """Every constraint row, the tie rows (= 0) first, then the contact rows (C x <= g or
        = g): what solvers that take one row matrix are given."""
        if self.ties is None:
            return self.C
        return sp.csc_array(sp.vstack((self.ties, self.C), format="csc"))

    def rows_rhs(self) -> np.ndarray:
        """The right-hand sides of :meth:`rows`: zero for the ties, then g."""
        return np.concatenate((np.zeros(self.n_ties), self.g))

    @cached_property
    def K_upper(self) -> sp.csc_array:
        """The upper triangle of K (CSC), as OSQP and Clarabel take it (by masking the index
        arrays: scipy's triu costs more than a small solve)."""
        K, n = self.K, self.n
        columns = np.repeat(np.arange(n), np.diff(K.indptr))
        keep = K.indices <= columns
        indptr = np.concatenate(([0], np.cumsum(np.bincount(columns[keep], minlength=n))))
        return sp.csc_array((K.data[keep], K.indices[keep], indptr), shape=K.shape)

    @property
    def stiffness_scale(self) -> float:
        """k = F / U (N/m): K_SI = k·K."""
        return self.force_scale / self.displacement_scale

    @property
    def n(self) -> int:
        """Number of unknowns (free nodes)."""
        return int(self.q.size)

    def to_si(self, x: np.ndarray, multipliers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(free-node displacements in m, contact forces in N) from the scaled solution x and
        the multipliers μ of the rows (convention above: μ >= 0 when a wall pushes)."""
        x = np.asarray(x, dtype=float).reshape(-1)[: self.n_displacements]
        mu = np.asarray(multipliers, dtype=float).reshape(-1)
        return self.displacement_scale * x, self.force_scale * mu

    def from_si(self, u_free: np.ndarray, contact_force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The inverse of :meth:`to_si`: (x, μ) from displacements (m) and forces (N)."""
        u = np.asarray(u_free, dtype=float).reshape(-1)
        lam = np.asarray(contact_force, dtype=float).reshape(-1)
        return u / self.displacement_scale, lam / self.force_scale


def scales(model: Model) -> tuple[float, float]:
    """(U, F): the displacement and force scales of a model's QP (module docstring), in the
    scene's units.

    k = 1 / ‖K⁻¹e‖∞, e = 1 at every loaded or walled free node: the stiffness of the bar as
    the loads and walls see it, from the scene's structure alone. U is the model's
    displacement scale (:attr:`contactqp.model.Model.displacement_scale`: ‖K⁻¹P‖∞, the free
    displacement, or the deepest press fit) rounded to a power of two of metres; F = k·U.
    Contact forces are then O(F): a wall with an open gap can only take what the loads bring.
    Open gaps are not a scale: a far wall's gap would shrink the loads below the solver's
    tolerance (measured: Clarabel "Solved" with 81 N on a 1 N load pulling away from a
    zero-gap wall, U set by a second wall 0.19 mm away). Without loads or walls k falls back
    to the largest diagonal of K.
    """
    e = np.zeros(model.n_free)
    e[np.flatnonzero(model.P)] = 1.0
    e[model.C.indices] = 1.0
    if e.any():
        k = 1.0 / float(np.abs(model.solve_K_and_loads(e)).max())
    else:
        k = float(model.K.diagonal().max())
    # U rounded to a power of two (of metres, so that a solver sees the same numbers whatever
    # the scene's units): then the scaled K does not change with the loads until U crosses a
    # power of two (a cvxpy re-solve along a load path finds its cached problem)
    U, metre = model.displacement_scale, model.scene.unit.metre
    U = math.ldexp(1.0, round(math.log2(U * metre))) / metre if math.isfinite(U) else U
    return U, k * U


def _flag(name: str, value: Any) -> bool:
    """A True/False option, else an OptionError naming it."""
    if not isinstance(value, (bool, np.bool_)):
        raise OptionError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _scale_option(scale: Any) -> bool:
    return _flag("scale", scale)


def qp_from_model(model: Model, contact: str = "inequality", scale: bool = True,
                  formulation: str = "full") -> QPProblem:
    """The QP data of a model (see :class:`QPProblem`), scaled by :func:`scales` or in SI;
    ``formulation`` "full" (x = u, Hessian K) or "strain" (x = [u; e], Hessian diag(0, k_e),
    tie rows B u − e = 0)."""
    contact_kind(contact)
    U, F = scales(model) if _scale_option(scale) else (1.0, 1.0)
    if formulation == "strain":
        return _strain_qp(model, contact, U, F)
    if formulation != "full":
        raise OptionError(f"QP formulation must be 'full' or 'strain'; got {formulation!r}")
    band = model.K_band
    K = _csc_from_band(band / (F / U)) if band is not None else sp.csc_array(model.K / (F / U))
    return QPProblem(
        K=K, q=-model.P / F, C=sp.csc_array(model.C), g=model.g / U, contact=contact,
        displacement_scale=U, force_scale=F,
    )


def _strain_qp(model: Model, contact: str, U: float, F: float) -> QPProblem:
    """The strain formulation: unknowns x = [u; e] (both in units of U), energy
    ½ Σ k_e e² (k_e = EA/L of each element), tie rows B u − e = 0 (:func:`elongation_rows`).
    The Hessian is diagonal; the bar's ill-conditioning (cond K ~ n²) moves into the rows."""
    B = elongation_rows(model)
    k = model.scene.stiffness / (F / U)
    n, m = model.n_free, k.size
    identity = sp.eye_array(m, format="csc")
    return QPProblem(
        K=sp.csc_array(sp.diags_array(np.concatenate((np.zeros(n), k))).tocsc()),
        q=np.concatenate((-model.P / F, np.zeros(m))),
        C=sp.csc_array(sp.hstack((model.C, sp.csr_array((model.n_contacts, m))), format="csc")),
        g=model.g / U, contact=contact, displacement_scale=U, force_scale=F,
        ties=sp.csc_array(sp.hstack((B, -identity), format="csc")),
    )


def _csc_from_band(band: np.ndarray) -> sp.csc_array:
    """The symmetric tridiagonal matrix of a lower band (diagonal; sub-diagonal) as CSC,
    built from its index arrays (no sparse conversions: the QP method's main fixed cost)."""
    n = band.shape[1]
    diagonal, sub = band[0], band[1, :-1]
    rows = np.stack((np.arange(n) - 1, np.arange(n), np.arange(n) + 1), axis=1)
    data = np.stack((np.concatenate(([0.0], sub)), diagonal, np.concatenate((sub, [0.0]))), axis=1)
    keep = (rows >= 0) & (rows < n)
    counts = keep.sum(axis=1)
    indptr = np.concatenate(([0], np.cumsum(counts)))
    return sp.csc_array((data[keep], rows[keep], indptr), shape=(n, n))


def qp_problem(scene: Scene, contact: str = "inequality", scale: bool = True,
               formulation: str = "full") -> QPProblem:
    """The QP of a scene, ready for any solver: minimise ½ xᵀKx + qᵀx s.t. C x <= g (or = g).

    With ``scale=True`` (the default, as for ``solve(method="qp")``) the data are
    non-dimensional; :meth:`QPProblem.to_si` maps a solution and its multipliers back to metres
    and newtons. With ``scale=False`` they are in SI units (K in N/m, q in N, g in m). A
    solver's own equilibration may be better off on the scaled data (see :data:`PRESCALED`).
    ``formulation="strain"`` gives the QP in displacements and element elongations
    (:func:`_strain_qp`).
    """
    return qp_from_model(build_model(scene), contact, scale, formulation)


# ---------------------------------------------------------------------------------------------
# Dual signs and accuracy: each in one place

# μ = DUAL_SIGNS[backend][contact] * (the backend's dual), μ the multiplier of L = Π̂ + μᵀ(Cx − g).
# clarabel: P x + q + Aᵀz = 0 with A x + s = b, s in the cone (z >= 0 on the nonnegative cone).
# osqp: P x + q + Aᵀy = 0, y > 0 where the upper bound u is active.
# cvxpy: f + yᵀ(C x − g) for ``C @ x <= g`` (y >= 0) and for ``C @ x == g``; written
#   ``g == C @ x`` it would flip, so the backend always writes the expression on the left.
# qpsolvers: P x + q + Gᵀz + Aᵀy = 0, z >= 0 for G x <= h, y for A x = b.
DUAL_SIGNS: dict[str, dict[str, float]] = {
    "clarabel": {"inequality": 1.0, "equality": 1.0},
    "osqp": {"inequality": 1.0, "equality": 1.0},
    "cvxpy": {"inequality": 1.0, "equality": 1.0},
    "qpsolvers": {"inequality": 1.0, "equality": 1.0},
}

ACCURACY: dict[str, dict[str, dict[str, Any]]] = {
    "clarabel": {
        "default": {"tol_gap_abs": 1e-8, "tol_gap_rel": 1e-8, "tol_feas": 1e-8, "tol_ktratio": 1e-6},
        "high": {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10,
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

        =========  ==========================================  ===================  ============
        solver     settings                                    "default"            "high"
        =========  ==========================================  ===================  ============
        clarabel   tol_gap_abs, tol_gap_rel, tol_feas           1e-8                   1e-10 (d)
                   tol_ktratio                                  1e-6                   1e-8
        osqp       eps_abs, eps_rel                             1e-3                   1e-9
                   max_iter; polishing                          4000; on               1e5; on
        scs        eps_abs, eps_rel; max_iters                  1e-4; 1e5              1e-9; 1e5
        ecos       abstol, reltol, feastol                      1e-8                   1e-10 (e)
        cvxopt     abstol, reltol, feastol                      1e-7, 1e-6, 1e-7       1e-8 (a)
        piqp       eps_abs, eps_rel                             1e-8, 1e-9             1e-10, 1e-11
        proxqp     eps_abs (eps_rel 0)                          1e-5                   1e-10
                   duality gap checked, eps_duality_gap_abs     off                    1e-10 (b)
        qpalm      eps_abs, eps_rel                             1e-4                   1e-10
        daqp       primal_tol (dual_tol 1e-12)                  1e-6                   1e-10
        highs      primal/dual_feasibility_tolerance            1e-7                   1e-10
                   qp_regularization_value                      1e-7                   1e-12 (c)
        quadprog   none (a dual active-set method, exact up to round-off)
        other      the solver's defaults for both
        =========  ==========================================  ===================  ============

    (a) cvxpy hands CVXOPT a cone rewrite of the QP, and CVXOPT fails there at 1e-9 on a
        six-element bar with four walls (measured).
    (b) Without the duality-gap test ProxQP stopped 2e-6 off in λ at eps_abs 1e-10 (measured);
        cvxpy passes only eps_abs and eps_rel on to ProxQP, so through cvxpy the gap is unchecked.
    (c) HiGHS regularises the Hessian by 1e-7 by default, which leaves ~1e-7 in λ (measured).
    (d) At 1e-12 Clarabel stops "AlmostSolved" on a 1e4-element bar, though 1e-10 right.
    (e) 1e-12 through qpsolvers (:data:`BACKEND_ACCURACY`).

    With ``scale=True`` the QP is already scaled, and :data:`PRESCALED` turns off Clarabel's
    and OSQP's own equilibration (through every backend), which measured better.
    """
    if accuracy not in ACCURACIES:
        raise OptionError(f"accuracy must be one of {', '.join(ACCURACIES)}; got {accuracy!r}")
    name = solver.lower()
    settings = dict(ACCURACY.get(name, {}).get(accuracy, {}))
    settings.update(BACKEND_ACCURACY.get((backend or "", name), {}).get(accuracy, {}))
    return {**settings, **PRESCALED.get(name, {})} if scaled else settings


# ---------------------------------------------------------------------------------------------
# The backend registry

# backend -> (module, pip install that adds it). Every backend module has the same contract:
#   NAME, DEFAULT_SOLVER, KNOWN_SOLVERS {solver: pip package}, installed_solvers() -> tuple,
#   canonical(solver) -> str, solve(qp, solver, settings) -> QPOutcome.
BACKEND_MODULES: dict[str, tuple[str, str]] = {
    "clarabel": ("contactqp.methods.qp_clarabel", "pip install clarabel"),
    "osqp": ("contactqp.methods.qp_osqp", "pip install osqp"),
    "cvxpy": ("contactqp.methods.qp_cvxpy", "pip install cvxpy"),
    "qpsolvers": ("contactqp.methods.qp_qpsolvers", 'pip install "qpsolvers[open_source_solvers]"'),
}
BACKENDS: dict[str, ModuleType | None] = {}
MISSING: dict[str, str] = {}  # backend -> why it could not be imported
for _name, (_module, _pip) in BACKEND_MODULES.items():
    try:
        BACKENDS[_name] = importlib.import_module(_module)
    except ImportError as _error:
        BACKENDS[_name] = None
        MISSING[_name] = str(_error)

# Chosen by measurement (benchmarks/qp_survey.py, benchmarks/qp_overhead.py). Clarabel is a
# core dependency, and at "default" it was verified on every scene tried (the default scene,
# walls on both sides, 1e4 and 1e5 elements: λ within 1e-10, 5e-10 at 1e5), never claimed
# success when wrong, and is the fastest direct call (27 µs on the default scene, 19 ms at 1e4).
# Scaling on: in SI units HiGHS (7.6 % off), QPALM (1 %) and quadprog (no solution) fail on the
# default scene, and OSQP's high accuracy needs 17 s instead of 0.04 s at 1e4 elements; scaled,
# only ProxQP at its loose default tolerance did worse (1.7e-2 off against 1e-7 in SI).
DEFAULT_BACKEND = "clarabel"
DEFAULT_SCALE = True

# Solvers that turn K into a dense n x n matrix: refused above this many unknowns, where the
# dense matrix alone would take DENSE_LIMIT² · 8 bytes (200 MB) and the solve O(n³).
DENSE_LIMIT = 5000
DENSE_SOLVERS = {("qpsolvers", "daqp"), ("qpsolvers", "quadprog"), ("qpsolvers", "ecos"),
                 ("cvxpy", "DAQP"), ("cvxpy", "PROXQP")}


@dataclass(frozen=True)
class QPSolverInfo:
    """One backend/solver pair: whether it is installed and usable, and how to add it."""

    backend: str
    solver: str
    available: bool
    install: str


def _backend(name: str) -> ModuleType:
    if name not in BACKEND_MODULES:
        raise OptionError(f"backend must be one of {', '.join(BACKEND_MODULES)}; got {name!r}")
    module = BACKENDS.get(name)
    if module is None:
        raise SolverNotAvailable(
            f"QP backend {name!r} is not installed ({MISSING.get(name, 'import failed')}); "
            f"{BACKEND_MODULES[name][1]} or {PIP_SOLVERS}. Installed backends: "
            f"{', '.join(b for b, m in BACKENDS.items() if m is not None) or 'none'}"
        )
    return module


def resolve_solver(backend: str, solver: str | None) -> tuple[ModuleType, str]:
    """(backend module, solver name in the backend's spelling); OptionError for an unknown
    name, SolverNotAvailable (with the pip install) for a known one that is not installed."""
    module = _backend(backend)
    installed = module.installed_solvers()
    if solver is None:
        if module.DEFAULT_SOLVER in installed:
            return module, module.DEFAULT_SOLVER
        if not installed:
            raise SolverNotAvailable(
                f"QP backend {backend!r} finds no solver it can use; {PIP_SOLVERS}"
            )
        return module, installed[0]
    if not isinstance(solver, str):
        raise OptionError(f"solver must be a solver name (str) or None, got {solver!r}")
    name = module.canonical(solver)
    if name in installed:
        return module, name
    if name in module.KNOWN_SOLVERS:
        raise SolverNotAvailable(
            f"solver {solver!r} of backend {backend!r} is not installed; "
            f"pip install {module.KNOWN_SOLVERS[name]} (or {PIP_SOLVERS}). "
            f"Installed: {', '.join(installed) or 'none'}"
        )
    choices = sorted(set(module.KNOWN_SOLVERS) | set(installed))
    raise OptionError(
        f"backend {backend!r} has no solver {solver!r}; choices: {', '.join(choices)}"
    )


def available_qp_solvers() -> tuple[QPSolverInfo, ...]:
    """Every backend/solver pair contactqp knows, installed and usable or not, with the
    ``pip install`` that adds a missing one. Installed pairs come first."""
    rows = []
    for backend, (_, pip) in BACKEND_MODULES.items():
        module = BACKENDS.get(backend)
        if module is None:
            known = _KNOWN_WITHOUT_MODULE.get(backend, (backend,))
            rows += [QPSolverInfo(backend, s, False, f"{pip} (or {PIP_SOLVERS})") for s in known]
            continue
        installed = module.installed_solvers()
        rows += [QPSolverInfo(backend, s, True, "") for s in installed]
        rows += [
            QPSolverInfo(backend, s, False, f"pip install {package} (or {PIP_SOLVERS})")
            for s, package in module.KNOWN_SOLVERS.items() if s not in installed
        ]
    return tuple(sorted(rows, key=lambda r: not r.available))


# The solvers a backend would offer, listed even when its own package is missing.
_KNOWN_WITHOUT_MODULE = {
    "cvxpy": ("CLARABEL", "OSQP", "SCS", "ECOS", "CVXOPT", "PIQP", "PROXQP", "DAQP", "HIGHS",
              "QPALM"),
    "qpsolvers": ("clarabel", "osqp", "scs", "ecos", "cvxopt", "piqp", "proxqp", "daqp",
                  "highs", "qpalm", "quadprog"),
}


# ---------------------------------------------------------------------------------------------
# The method


class _Sink(io.TextIOBase):
    """A text stream that keeps nothing."""

    def write(self, text: str) -> int:
        return len(text)


_SINK = _Sink()


@contextlib.contextmanager
def _silenced():
    """Nothing written to standard output or error gets out: from Python (OSQP's "Polishing
    not needed") nor from C (HiGHS's presolve notes on stderr), through file descriptors 1
    and 2 (a few microseconds)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        with contextlib.redirect_stdout(_SINK), contextlib.redirect_stderr(_SINK):
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for handle in (*saved, null):
            os.close(handle)


def guarded(solve: Any, qp: QPProblem, *args: Any, verbose: bool = False) -> QPOutcome:
    """Call a backend's solve; anything the solver raises becomes a failed outcome (the Result
    check then flags it). The library's own errors (user mistakes) pass through. Whatever the
    solver prints goes nowhere unless ``verbose`` (:func:`_silenced`: OSQP prints "Polishing
    not needed" and HiGHS presolve notes with their verbose flags off)."""
    try:
        if verbose:
            return solve(qp, *args)
        with _silenced():
            return solve(qp, *args)
    except (KeyboardInterrupt, SystemExit, ContactqpError):
        raise
    except BaseException as error:  # noqa: BLE001 - Rust solvers panic with a BaseException
        return failed_outcome(qp.n, qp.g.size + qp.n_ties, f"raised {type(error).__name__}: {error}")


def solve_qp(model: Model, contact: str, *, backend: str = DEFAULT_BACKEND,
             solver: str | None = None, accuracy: str = "default",
             scale: bool = DEFAULT_SCALE, formulation: str = "full",
             verbose: bool = False) -> Solution:
    """Solve the contact problem as a QP with ``backend`` ("clarabel", "osqp", "cvxpy",
    "qpsolvers") and ``solver`` (a name the backend knows; None: its default), at
    ``accuracy`` "default" or "high" (:func:`accuracy_settings`), scaled or in SI (``scale``),
    as the QP in displacements (``formulation="full"``) or with element elongations
    ("strain"; the tie rows' multipliers, the element forces in N, go to ``info``).
    ``verbose``: let the solver print its progress (by default nothing is printed)."""
    verbose = _flag("verbose", verbose)
    module, name = resolve_solver(backend, solver)
    settings = accuracy_settings(name, accuracy, scaled=_scale_option(scale), backend=backend)
    start = time.perf_counter()
    qp = qp_from_model(model, contact, scale, formulation)
    built = time.perf_counter()
    label = backend if name == backend else f"{backend}/{name}"
    if (backend, name) in DENSE_SOLVERS and qp.n > DENSE_LIMIT:
        outcome = failed_outcome(
            qp.n, qp.g.size + qp.n_ties,
            f"not attempted: {name} works on dense matrices and the bar has {qp.n} unknowns "
            f"(limit {DENSE_LIMIT})",
        )
    else:
        outcome = guarded(module.solve, qp, name, settings, verbose, verbose=verbose)
    sign = DUAL_SIGNS[backend][contact]
    dual = sign * np.asarray(outcome.dual, dtype=float)  # of qp.rows(): the ties, then the walls
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
    "ACCURACY",
    "BACKENDS",
    "BACKEND_ACCURACY",
    "DEFAULT_BACKEND",
    "DEFAULT_SCALE",
    "DUAL_SIGNS",
    "PRESCALED",
    "QPOutcome",
    "QPProblem",
    "QPSolverInfo",
    "available_qp_solvers",
    "qp_from_model",
    "qp_problem",
    "scales",
    "solve_qp",
]
