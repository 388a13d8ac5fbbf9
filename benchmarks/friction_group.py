"""Friction by every method and every installed QP backend: time against one sparse
factor-and-solve of K, the error against an exact answer found without the method.

    python benchmarks/run.py --cases friction [--quick] [--out DIR]

Cases (docs/friction.md has the closed forms; ``--quick`` runs the small ones, marked *):

- **bed 2D** (Tresca, no normal rows; :mod:`contactqp.friction.bed`): a bar (EA = 1, L = 1)
  on a bed of τ = 1 per length pulled by F = 0.5, 100* and 1000 elements. x_s = F/τ falls on
  a node, so the closed form is the discrete answer at the nodes: |u| = τ(x_s − x)²/(2EA),
  and the axial force N = F − τx is exact at every element's midpoint, so node j's friction
  force is N(x_j − h/2) − N(x_j + h/2) (F − N(h/2) at the loaded end).
- **bed 3D** (Tresca, d = 2: a disc per contact): the same bar with two displacements per
  node and the same stiffness along both (K ⊗ I₂, a chain of isotropic springs), pulled by F
  at 30° to its axis: the answer is the 2D one along the pull, u = u_bed·e and λ_T = λ_bed·e;
  40* and 160 elements.
- **cattaneo tresca / coulomb** (:mod:`contactqp.friction.cattaneo`): two mirrored
  plane-strain cylinders (R = 10, E = 210e3, ν = 0.3) pressed to a/R ≈ 0.03 (solved once,
  Coulomb μ = 0.3, by lagrange: the state every run starts from, ``previous=``), then sheared
  by moving the caps to Q/μP ≈ 0.5: under Tresca with s = μλ_N of the pressed state, and
  under Coulomb. Three meshes: coarse (elements a/6 along the strip growing by 1.0 away from
  it: 932 dofs, 25 pairs; the Tresca one is --quick's), medium (a/8, 0.3: 3 320 dofs, 25
  pairs) and fine (a/25, 0.1: 28 340 dofs, 97 pairs). The exact answer: the equations of the sets the exact route
  found (which pairs are closed, which stick, which way the others slip) solved here by one
  SuperLU solve of the saddle-point system [[K, Gᵀ], [G_set, ...]] and every inequality of
  the law checked here, with no code of contactqp's routes or check; the closed form
  c/a = √(1 − Q/(μP)) read beside it (a mesh-level check of the physics, not of the solver).
- **block*, cycling, non-unique** (Coulomb, one node on a flat; :mod:`contactqp.friction
  .examples`), each in closed form: a block pulled past μP slides on the flat (u = (0.4, 0),
  λ = (2, 1)); the fixed point cycles where the one answer is u = (0.4, 0), λ = (1.2, 3.6);
  three exact answers (open, stick, slip), a run judged against the nearest.

Runs: every method of contactqp's registry (:data:`contactqp.methods.METHODS`) and of the
friction methods (:mod:`contactqp.friction.methods`: cone, relaxed), and ``qp`` by every
installed backend and solver (:func:`contactqp.available_qp_solvers`), plus ``dual=True``
(the box QP in the forces) for every qpsolvers solver, each at its defaults. A method that
refuses the law says why in one line (recorded); an exception that is not contactqp's is
recorded as such (a library bug). Each run on a case of ISOLATE_FROM free dofs or more goes
to a forked child stopped after TIMEOUT s; a dense solver past DENSE_LIMIT unknowns, and a
run whose time extrapolated from the previous case of its family (time ~ dofs^GROWTH)
passes BUDGET, are skipped with the reason. Clarabel runs on one thread here
(:func:`one_rayon_thread`: its thread pool does not survive a fork), as every floor does.

Per run: the wall time of ``contactqp.solve(problem, method, previous=...)`` on a new
Problem (its friction model and K's factorisation inside the timing), the median of a few
repeats after a first call when that call is fast, as a ratio to the floor (one SuperLU
factor-and-solve of K on the free dofs, the faster ordering, benchmarks/hertz.py) measured
in the same run; the largest error of the forces (λ_N and λ_T) against the exact answer over
the check's force scale F and over the largest exact force, and of u over the largest exact
|u|; whether that error is within the bound the Result states; and the outcome as in
benchmarks/matrix.py (right: within 1e-5·F). Writes runs.json, table.md and
speed_accuracy.png (this group's chart, apart from the matrix's) to DIR/friction.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import contactqp
from cases import in_child, machine
from contactqp.errors import ContactqpError, SolverError
from contactqp.friction import examples
from contactqp.friction.bed import bed_displacement, frictional_bed
from contactqp.friction.methods import COULOMB_METHODS, TRESCA_METHODS
from contactqp.friction.qp import DENSE_LIMIT, POSITIVE_DEFINITE_ONLY
from contactqp.methods import METHODS
from contactqp.methods import qp as qpmod
from fem2d import chart, floor, short_reason
from matrix import WRONG, outcome

TIMEOUT = {False: 45.0, True: 2.0}  # s per run (full, --quick)
BUDGET = {False: 40.0, True: 3.0}  # s: an extrapolated time past this is skipped
GROWTH = 1.5  # time ~ free dofs^GROWTH from one case of a family to the next
ISOLATE_FROM = 500  # free dofs from which a run goes to a forked child (a time limit)
ROUND_OFF = 1e-12  # of F: the exact answers' own round-off, allowed beside a stated bound
ACCEPT = 1e-9  # of the force / length scale: an inequality the exact answer may miss by
R, E, NU, MU = 10.0, 210e3, 0.3, 0.3  # the cylinders (benchmarks/friction.py)
APPROACH, SHIFT = 0.0377, 0.008767  # cap motions: a/R ≈ 0.03, then Q/μP ≈ 0.5


@dataclass(frozen=True)
class Exact:
    """An exact answer: the forces λ = (λ_N, λ_T row by row), u where known, and where it
    comes from; ``miss`` is the largest of its own inequalities' misses (0 for a closed
    form), over the force and length scales."""

    forces: np.ndarray
    u: np.ndarray
    source: str
    miss: float = 0.0


@dataclass(frozen=True)
class Built:
    """A case ready to run: the Problem's arrays (a new Problem per timed call), the state
    the increment starts from, its exact answers (a run is judged by the nearest) and what
    the physics reads from a Result (x_s, c/a)."""

    arrays: dict[str, Any]
    exact: tuple[Exact, ...]
    previous: contactqp.Result | None = None
    reading: Callable[[contactqp.Result], dict[str, float]] = field(default=lambda _: {})
    note: str = ""

    def problem(self) -> contactqp.Problem:
        return contactqp.Problem(**self.arrays)


@dataclass(frozen=True)
class Case:
    name: str
    family: str  # cases of a family at growing sizes share the budget's extrapolation
    build: Callable[[], Built]
    quick: bool


# ------------------------------------------------------------------ the cases

def bed(elements: int, d: int = 1, angle: float = 30.0) -> Built:
    """The bar on the bed (module docstring), in 2D (d = 1) or with a disc per node (d = 2,
    pulled at ``angle`` degrees to the bar)."""
    found = frictional_bed(elements=elements)
    F, tau, EA, N = found.force, found.tau, found.axial_stiffness, elements
    h = found.length / N
    direction = np.array([1.0]) if d == 1 else np.array([math.cos(math.radians(angle)),
                                                         math.sin(math.radians(angle))])
    K1 = sp.diags([np.r_[1.0, np.full(N - 1, 2.0), 1.0], np.full(N, -1.0), np.full(N, -1.0)],
                  [0, -1, 1]) * (EA / h)
    f1 = np.zeros(N + 1)
    f1[0] = -F
    arrays = {"K": sp.kron(K1, sp.identity(d), format="csr"),
              "f": np.kron(f1, direction), "C": np.zeros((0, d * (N + 1))), "g": [],
              "T": sp.kron(sp.eye(N, N + 1), sp.identity(d), format="csr"),
              "slip_bound": found.slip_bound, "prescribed": np.arange(d * N, d * (N + 1))}

    def axial(x: np.ndarray) -> np.ndarray:
        return np.clip(F - tau * x, 0.0, None)

    x = found.x[:N]
    # node j's friction force, along the slip (−e: the pull's way): N's drop across the node
    drop = np.where(x == 0.0, F - axial(x + h / 2), axial(x - h / 2) - axial(x + h / 2))
    u = np.kron(bed_displacement(found.x, F, tau, EA), direction)
    exact = Exact(-np.kron(drop, direction), u, "closed form (x_s on a node)")

    def reading(result: contactqp.Result) -> dict[str, float]:
        pull_out = float(np.linalg.norm(result.u[:d]))
        return {"slip_length_error": math.sqrt(2.0 * EA * pull_out / tau) / (F / tau) - 1.0}

    note = (f"x_s = F/τ = {F / tau:g} L on a node; K {'⊗ I₂, pulled at 30°' if d == 2 else ''}"
            .rstrip())
    return Built(arrays, (exact,), reading=reading, note=note)


def cattaneo(fine: float, growth: float, law: str) -> Built:
    """The cylinders sheared from the pressed state, under ``law`` (module docstring)."""
    from contactqp.friction.cattaneo import cattaneo_cylinders, measure

    a = 0.03 * R
    cylinders = cattaneo_cylinders(R, E, NU, zone=1.25 * a, fine=a / fine, growth=growth)
    pressed = contactqp.solve(contactqp.Problem(**cylinders.arrays, mu=MU,
                                                prescribed_values=cylinders.cap_values(
                                                    APPROACH, 0.0)))
    friction = ({"mu": MU} if law == "coulomb"
                else {"slip_bound": MU * pressed.contact_force})
    arrays = {**cylinders.arrays, **friction,
              "prescribed_values": cylinders.cap_values(APPROACH, SHIFT)}
    problem = contactqp.Problem(**arrays)
    route = contactqp.solve(problem, "lagrange", previous=pressed)
    exact = exact_on_sets(problem, pressed.u, route)

    def reading(result: contactqp.Result) -> dict[str, float]:
        answer = SimpleNamespace(normal_force=result.contact_force,
                                 friction_force=result.friction_force, stick=result.stick)
        found = measure(cylinders, answer, MU)
        return {"Q_over_muP": found.tangential / (MU * found.load),
                "stick_ratio": found.stick / found.hertz_half_width,
                "stick_ratio_error": found.stick_ratio_error}

    note = (f"pressed by lagrange (verified: {pressed.verified}); the exact route's "
            f"{int(route.stick.sum())} sticking and {int((~route.stick).sum())} slipping pairs "
            f"give the sets")
    return Built(arrays, (exact,), previous=pressed, reading=reading, note=note)


def on_flat(example: Callable[[], tuple[Any, float]], answers: dict[str, tuple]) -> Built:
    """One node on a flat (:mod:`contactqp.friction.examples`) with its exact answers:
    name -> (u, λ_N, λ_T)."""
    model, mu = example()
    arrays = {"K": model.K, "f": model.load, "C": model.C, "g": model.gap, "T": model.T,
              "mu": mu}
    exact = tuple(Exact(np.array([lam_N, lam_T], dtype=float), np.array(u, dtype=float),
                        f"closed form ({name})") for name, (u, lam_N, lam_T) in answers.items())
    return Built(arrays, exact, note=f"μ = {mu:g}; {len(exact)} exact "
                                     f"answer{'s' if len(exact) > 1 else ''}")


CASES = (  # in each family the smallest first: a case extrapolates the previous one's times
    Case("block", "block", lambda: on_flat(examples.sliding_block,
                                           {"slide": ((0.4, 0.0), 2.0, 1.0)}), True),
    Case("cycling", "cycling", lambda: on_flat(examples.cycling_fixed_point,
                                               {"slip": ((0.4, 0.0), 1.2, 3.6)}), False),
    Case("non-unique", "non-unique", lambda: on_flat(
        examples.nonunique_coulomb, {"open": ((8 / 3, 1 / 3), 0.0, 0.0),
                                     "stick": ((0.0, 0.0), 1.0, 2.5),
                                     "slip": ((1.0, 0.0), 0.5, 1.5)}), False),
    Case("bed 2D 100", "bed 2D", lambda: bed(100), True),
    Case("bed 2D 1000", "bed 2D", lambda: bed(1000), False),
    Case("bed 3D 40", "bed 3D", lambda: bed(40, d=2), True),
    Case("bed 3D 160", "bed 3D", lambda: bed(160, d=2), False),
    Case("cattaneo tresca coarse", "cattaneo tresca", lambda: cattaneo(6, 1.0, "tresca"), True),
    Case("cattaneo tresca medium", "cattaneo tresca", lambda: cattaneo(8, 0.3, "tresca"), False),
    Case("cattaneo tresca fine", "cattaneo tresca", lambda: cattaneo(25, 0.1, "tresca"), False),
    Case("cattaneo coulomb coarse", "cattaneo coulomb", lambda: cattaneo(6, 1.0, "coulomb"),
         False),
    Case("cattaneo coulomb medium", "cattaneo coulomb", lambda: cattaneo(8, 0.3, "coulomb"),
         False),
    Case("cattaneo coulomb fine", "cattaneo coulomb", lambda: cattaneo(25, 0.1, "coulomb"),
         False),
)


def exact_on_sets(problem: contactqp.Problem, previous_u: np.ndarray,
                  found: contactqp.Result) -> Exact:
    """The exact answer of a 2D increment on ``found``'s sets, solved and checked here.

    Unknowns (u on the free dofs, λ_N, λ_T); rows: equilibrium K u − f + Cᵀλ_N + Tᵀλ_T = 0;
    per contact closed: C_i u = g_i, open: λ_N,i = 0; stick: T_i(u − u_prev) = 0, slip:
    λ_T,i = σ_i s_i (Tresca) or σ_i μ_i λ_N,i (Coulomb; an open contact's λ_T is 0), σ_i the
    side ``found`` slips to. One SuperLU solve; then the law's inequalities: λ_N ≥ 0 where
    closed, the gap ≥ 0 where open, |λ_T,i| within the bound where it sticks, and the slip
    along σ where it slips. Their largest miss, over the force scale (the largest |f| on the
    free dofs and exact force) or the length scale (the largest |u|), is ``miss``.
    """
    n, m = problem.n, problem.contacts
    free = np.setdiff1d(np.arange(n), problem.prescribed)
    up = np.zeros(n)
    up[problem.prescribed] = problem.prescribed_values
    K, C, T = sp.csr_array(problem.K), sp.csr_array(problem.C), sp.csr_array(problem.T)
    closed = found.state != "open"
    stick = found.stick & (closed | (problem.friction == "tresca"))
    side = np.sign(found.friction_force[:, 0])
    coulomb = problem.friction == "coulomb"
    bound = problem.mu if coulomb else problem.slip_bound
    Kf, Cf, Tf = K[free][:, free], C[:, free], T[:, free]
    eye = sp.identity(m, format="csr")
    normal = sp.vstack([sp.hstack([Cf[closed], sp.csr_array((closed.sum(), 2 * m))]),
                        sp.hstack([sp.csr_array(((~closed).sum(), free.size)),
                                   eye[~closed], sp.csr_array(((~closed).sum(), m))])])
    slipping = ~stick
    friction_on_lam_N = sp.diags(-side * bound if coulomb else np.zeros(m)).tocsr()
    tangential = sp.vstack([sp.hstack([Tf[stick], sp.csr_array((stick.sum(), 2 * m))]),
                            sp.hstack([sp.csr_array((slipping.sum(), free.size)),
                                       friction_on_lam_N[slipping], eye[slipping]])])
    matrix = sp.vstack([sp.hstack([Kf, Cf.T, Tf.T]), normal, tangential], format="csc")
    rhs = np.concatenate([
        problem.f[free] - (K @ up)[free], (problem.g - C @ up)[closed], np.zeros((~closed).sum()),
        (T @ (previous_u - up))[stick],
        np.zeros(slipping.sum()) if coulomb else (side * bound)[slipping]])
    solution = refined(sp.csr_array(matrix), rhs)
    u = up.copy()
    u[free] = solution[:free.size]
    lam_N, lam_T = solution[free.size:free.size + m], solution[free.size + m:]
    forces = np.concatenate([lam_N, lam_T])
    force_scale = max(np.abs(problem.f[free] - (K @ up)[free]).max(initial=0.0),
                      np.abs(forces).max())
    length = max(np.abs(u).max(), np.finfo(float).tiny)
    limit = bound * lam_N if coulomb else bound
    slip = T @ (u - previous_u)
    misses = [np.clip(-lam_N[closed], 0.0, None).max(initial=0.0) / force_scale,
              np.clip(-(problem.g - C @ u)[~closed], 0.0, None).max(initial=0.0) / length,
              np.clip(np.abs(lam_T) - limit, 0.0, None)[stick].max(initial=0.0) / force_scale,
              np.clip(-side * slip, 0.0, None)[slipping].max(initial=0.0) / length]
    source = "the exact route's sets, solved by SuperLU and checked here"
    return Exact(forces, u, source, float(max(misses)))


def refined(matrix: sp.csr_array, rhs: np.ndarray, steps: int = 4) -> np.ndarray:
    """x with matrix @ x = rhs: one SuperLU factorisation, then steps of iterative refinement
    with the residual in extended precision (np.longdouble). The plain solve left the
    cylinders' stick forces 3e-7 off (cond × round-off; 5e-11 of F), the refined one agrees
    with the exact route to 2e-12, within its stated bound."""
    factor = spla.splu(sp.csc_matrix(matrix))
    x = factor.solve(rhs).astype(np.longdouble)
    rows = np.repeat(np.arange(matrix.shape[0]), np.diff(matrix.indptr))
    data, target = matrix.data.astype(np.longdouble), rhs.astype(np.longdouble)
    for _ in range(steps):
        product = np.zeros(matrix.shape[0], dtype=np.longdouble)
        np.add.at(product, rows, data * x[matrix.indices])
        x += factor.solve(np.asarray(target - product, dtype=float))
    return np.asarray(x, dtype=float)


# ------------------------------------------------------------------ the runs

@dataclass(frozen=True)
class Run:
    label: str
    method: str
    options: tuple[tuple[str, Any], ...] = ()

    @property
    def dense(self) -> bool:
        """A backend that takes the primal QP's n x n matrix dense (the dual's is k x k, the
        rows' forces: small). qpsolvers' dense ones refuse past DENSE_LIMIT themselves."""
        return dict(self.options).get("backend") == "cvxpy" and (
            "cvxpy", dict(self.options)["solver"]) in qpmod.DENSE_SOLVERS


def runs() -> list[Run]:
    """Every method (the registry's, then friction's own) and every installed QP backend and
    solver, at their defaults; the dual box QP by every qpsolvers solver whose default is
    the primal."""
    found = [Run(name, name) for name in dict.fromkeys([*METHODS, *TRESCA_METHODS,
                                                        *COULOMB_METHODS]) if name != "qp"]
    duals = []
    for info in qpmod.available_qp_solvers():
        if not info.available:
            print(f"skipped: qp {info.backend}/{info.solver} is not installed ({info.install})")
            continue
        label = (f"qp {info.backend}" if info.backend == info.solver
                 else f"qp {info.backend}/{info.solver}")
        options = (("backend", info.backend), ("solver", info.solver))
        found.append(Run(label, "qp", options))
        if info.backend == "qpsolvers" and info.solver not in POSITIVE_DEFINITE_ONLY:
            duals.append(Run(f"{label} dual", "qp", (*options, ("dual", True))))
    return found + duals


def timed(built: Built, run: Run, quick: bool) -> tuple[contactqp.Result, float]:
    """The Result and the median time of solve on a new Problem each call (a first call,
    then repeats if it was fast)."""
    def call() -> tuple[contactqp.Result, float]:
        problem = built.problem()  # outside the timing; its model and factor inside
        start = time.perf_counter()
        result = contactqp.solve(problem, run.method, previous=built.previous,
                                 **dict(run.options))
        return result, time.perf_counter() - start

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # solvers' own warnings: the check decides
        result, first = call()
        repeats = (1 if first < 0.1 else 0) if quick else (
            3 if first < 0.3 else 1 if first < 1.0 else 0)
        times = [call()[1] for _ in range(repeats)]
    return result, statistics.median(times or [first])


def measure(built: Built, run: Run, base: float, quick: bool) -> dict[str, Any]:
    """One run's row: time, errors, outcome; a refusal (contactqp's one line) is recorded,
    a SolverError flagged, any other exception recorded as raised (not contactqp's)."""
    try:
        result, seconds = timed(built, run, quick)
    except SolverError as error:
        return {"outcome": "flagged", "why": f"raised: {error}"}
    except ContactqpError as error:
        return {"outcome": "refused", "why": f"{type(error).__name__}: {error}"}
    except Exception as error:  # noqa: BLE001 (recorded: a foreign error is a library bug)
        return {"outcome": "raised", "why": f"{type(error).__module__}.{type(error).__name__}:"
                                            f" {str(error).splitlines()[0] if str(error) else ''}"}
    forces = np.concatenate([result.contact_force, result.friction_force.ravel()])
    nearest = min(built.exact, key=lambda e: float(np.abs(forces - e.forces).max()))
    error = float(np.abs(forces - nearest.forces).max())
    F = result.force_scale
    u_error = float(np.abs(result.u - nearest.u).max()) / float(np.abs(nearest.u).max(
        initial=0.0) or 1.0)
    accepted = bool(result.verified and result.physical)
    force_error = error / F if math.isfinite(error) else math.inf
    return {"seconds": seconds, "ratio": seconds / base,
            "check_ratio": result.timings.get("check", math.nan) / base,
            "force_error": force_error,
            "force_error_largest": error / float(np.abs(nearest.forces).max() or 1.0),
            "u_error": u_error, "nearest": nearest.source,
            "bound_over_F": result.force_error_bound / F,
            "within_bound": bool(error <= result.force_error_bound + ROUND_OFF * F),
            "verified": accepted, "claimed_success": bool(result.claimed_success),
            "status": str(result.status), "iterations": int(result.iterations),
            "states": {s: int(np.count_nonzero(result.state == s))
                       for s in ("open", "stick", "slip")},
            "force_scale": F, **reading(built, result),
            "outcome": outcome(accepted, bool(result.claimed_success), force_error <= WRONG),
            "why": "" if accepted else result.message.splitlines()[0][:200]}


def reading(built: Built, result: contactqp.Result) -> dict[str, Any]:
    """What the case's physics reads from the Result (x_s, c/a), or why it could not."""
    try:
        return built.reading(result)
    except (ValueError, ZeroDivisionError, IndexError) as error:
        return {"reading": f"not read: {error}"}


def isolated(timeout: float, *args: Any) -> dict[str, Any]:
    """measure() in a forked child, stopped after ``timeout`` s (:func:`cases.in_child`)."""
    found = in_child(timeout, measure, *args)
    return found or {"outcome": "skipped", "why": f"time limit: stopped after {timeout:.0f} s"}


def skip_reason(run: Run, n_free: int, estimate: float | None, quick: bool) -> str | None:
    if run.dense and n_free > DENSE_LIMIT:
        return f"dense solver: {n_free} unknowns > {DENSE_LIMIT}"
    if estimate is not None and estimate > BUDGET[quick]:
        return f"over budget: about {estimate:.0f} s, from the previous case"
    return None


def run_case(case: Case, quick: bool, previous: dict[tuple[str, str], tuple[int, float]]
             ) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The case's description and one row per run; ``previous`` ((family, label) -> (free
    dofs, seconds)) carries each run's time to the family's next case."""
    built = case.build()
    problem = built.problem()
    n_free = problem.n - problem.prescribed.size
    base = floor(problem)
    exact = built.exact[0]
    described = {"case": case.name, "law": problem.friction, "d": problem.d + 1,
                 "dofs": problem.n, "free_dofs": n_free, "contacts": problem.contacts,
                 "rows": problem.m + problem.T.shape[0], "floor_seconds": base,
                 "largest_exact_force": max(float(np.abs(e.forces).max()) for e in built.exact),
                 "exact": [e.source for e in built.exact],
                 "exact_miss": max(e.miss for e in built.exact), "note": built.note}
    if described["exact_miss"] > ACCEPT:  # its sets' equations solved, its law not met
        print(f"{case.name}: the exact answer misses its inequalities by "
              f"{described['exact_miss']:.1e}: the errors below are against it all the same")
    print(f"{case.name}: {problem.n} dofs, {problem.contacts} contacts "
          f"({problem.friction}, {problem.d + 1}D), floor {base * 1e3:.2f} ms; exact: "
          f"{exact.source} (miss {described['exact_miss']:.1e})")
    rows = []
    for run in runs():
        before = previous.get((case.family, run.label))
        estimate = None if before is None else before[1] * (n_free / before[0]) ** GROWTH
        reason = skip_reason(run, n_free, estimate, quick)
        if reason:
            found = {"outcome": "skipped", "why": reason}
        else:
            began = time.perf_counter()
            found = (isolated(TIMEOUT[quick], built, run, base, quick)
                     if n_free >= ISOLATE_FROM else measure(built, run, base, quick))
            found["wall_seconds"] = time.perf_counter() - began  # repeats, fork, all
        if "seconds" in found:
            previous[case.family, run.label] = (n_free, found["seconds"])
        elif found["why"].startswith("time limit"):
            previous[case.family, run.label] = (n_free, TIMEOUT[quick])
        rows.append({"case": case.name, "run": run.label, "method": run.method, **found})
        print(f"  {line(rows[-1])}", flush=True)
    described["force_scale"] = next((r["force_scale"] for r in rows if "force_scale" in r),
                                    math.nan)
    return described, rows


# ------------------------------------------------------------------ the outputs

def line(row: dict[str, Any]) -> str:
    if "seconds" not in row:
        return f"{row['run']:30s} {row['outcome']}: {row['why'][:110]}"
    return (f"{row['run']:30s} {row['ratio']:9.2f} x floor  error {row['force_error']:.1e} F"
            f"  {row['outcome']}{'' if row['within_bound'] else '  (error past its bound)'}")


def cell(row: dict[str, Any]) -> str:
    """A run on one case: time / floor · force error / F · outcome (! where the error is
    past the bound the Result states)."""
    if "seconds" not in row:
        return f"{row['outcome']} ({reason(row['why'])})"
    verdict = row["outcome"] if row["outcome"] != "verified" else "**verified**"
    past = "" if row["within_bound"] else " !"
    return f"{row['ratio']:.3g}× · {row['force_error']:.0e} · {verdict}{past}"


def reason(why: str) -> str:
    """Why a run has no time, in a few words (the whole line is in runs.json)."""
    for key, words in (("does not take friction", "no friction law"),
                       ("solves the LCP", "normal contact's LCP"),
                       ("nitsche needs", "needs tractions"),
                       ("one of Coulomb's methods", "Coulomb's only"),
                       ("Coulomb in 2D only", "2D only"), ("friction in 2D only", "2D only"),
                       ("second-order cone", "no cones (3D)"),
                       ("positive definite", "needs a PD Hessian"),
                       ("is a dense solver", "dense, too many unknowns")):
        if key in why:
            return words
    return short_reason(why)


def table(cases: list[dict[str, Any]], rows: list[dict[str, Any]]) -> str:
    """Markdown: the cases, then one line per run and one column per case."""
    lines = [("| case | law, dim | dofs | contacts | floor | F / largest exact force | exact "
              "answer | lagrange's reading |"), "|---" * 8 + "|"]
    for c in cases:
        ours = next(r for r in rows if r["case"] == c["case"] and r["run"] == "lagrange")
        dofs = f"{c['dofs']:,}".replace(",", " ")
        lines.append(f"| {c['case']} | {c['law']}, {c['d']}D | {dofs} | {c['contacts']} | "
                     f"{c['floor_seconds'] * 1e3:.3g} ms | "
                     f"{c['force_scale'] / c['largest_exact_force']:.3g} | "
                     f"{'; '.join(dict.fromkeys(c['exact']))} (miss {c['exact_miss']:.0e}) | "
                     f"{physics(ours)} |")
    head = " | ".join(c["case"] for c in cases)
    lines += ["", summary(cases, rows), f"| run | {head} |", "|---" * (len(cases) + 1) + "|"]
    for label in dict.fromkeys(r["run"] for r in rows):
        found = {r["case"]: r for r in rows if r["run"] == label}
        lines.append(f"| {label} | " + " | ".join(cell(found[c["case"]]) for c in cases) + " |")
    counts = {name: sum(r["outcome"] == name for r in rows) for name in
              dict.fromkeys(r["outcome"] for r in rows)}
    past = sum("within_bound" in r and not r["within_bound"] for r in rows)
    return ("\n".join(lines) + "\n\nEach cell: time end to end / the floor (one SuperLU "
            "factor-and-solve of K, same run) · largest force error against the exact answer "
            f"/ F · outcome (right: within {WRONG:.0e}·F); ! the error is past the bound the "
            "Result states. " + ", ".join(f"{n} {name}" for name, n in counts.items())
            + f"; {past} past their stated bound.\n")


def summary(cases: list[dict[str, Any]], rows: list[dict[str, Any]]) -> str:
    """Markdown: per case, lagrange, qp at its defaults (Clarabel), the fastest and the most
    accurate verified run (time / floor, force error / F), and the outcomes."""
    lines = [("| case | floor | lagrange | qp (Clarabel) | fastest verified | most accurate "
              "verified | verified / ran |"), "|---" * 7 + "|"]
    for c in cases:
        ran = {r["run"]: r for r in rows if r["case"] == c["case"]}
        verified = [r for r in ran.values() if r["outcome"] == "verified"]
        timed = [r for r in ran.values() if "seconds" in r]
        best = [f"{r['run']}: {r['ratio']:.3g}×, {r['force_error']:.0e}" for r in (
            min(verified, key=lambda r: r["seconds"]),
            min(verified, key=lambda r: (r["force_error"], r["seconds"])))] if verified else [
            "none", "none"]
        lines.append(f"| {c['case']} | {c['floor_seconds'] * 1e3:.3g} ms | "
                     f"{cell(ran['lagrange'])} | {cell(ran['qp clarabel'])} | "
                     f"{' | '.join(best)} | {len(verified)} / {len(timed)} |")
    return "\n".join(lines) + "\n"


def physics(row: dict[str, Any]) -> str:
    if "slip_length_error" in row:
        return f"x_s {row['slip_length_error']:+.1e}"
    if "stick_ratio" in row:
        closed = math.sqrt(max(1.0 - row["Q_over_muP"], 0.0))
        return (f"Q/μP {row['Q_over_muP']:.3f}, c/a {row['stick_ratio']:.3f} against "
                f"√(1 − Q/μP) = {closed:.3f} ({100 * row['stick_ratio_error']:+.1f} %)")
    return f"u error {row['u_error']:.0e}" if "u_error" in row else "–"


FAMILIES = {"lagrange": "tab:blue", "semismooth Newton": "tab:cyan", "penalty": "tab:orange",
            "augmented": "tab:green", "cone": "tab:pink", "relaxed": "tab:olive",
            "qp, direct": "tab:red", "qp cvxpy": "tab:brown", "qp qpsolvers": "tab:gray",
            "qp qpsolvers, dual": "tab:purple", "other": "k"}


def family(row: dict[str, Any]) -> str:
    if row["method"] != "qp":
        name = row["method"].replace("semismooth_newton", "semismooth Newton")
        return name if name in FAMILIES else "other"
    backend = row["run"].split()[1].split("/")[0]
    if backend in ("cvxpy", "qpsolvers"):
        return f"qp {backend}" + (", dual" if row["run"].endswith(" dual") else "")
    return "qp, direct"


@contextmanager
def one_rayon_thread() -> Iterator[None]:
    """RAYON_NUM_THREADS=1 while the group runs, as it was after. Clarabel 0.11 (at its
    default max_threads) solves larger problems on a rayon thread pool, and a forked child
    of a process that started that pool hangs in its next such solve (the pool's threads
    are not forked): lagrange's restart from the reduced dual (a 200-contact bed) did. With
    one thread there is no pool: Clarabel runs on one thread, as every floor does."""
    before = os.environ.get("RAYON_NUM_THREADS")
    os.environ["RAYON_NUM_THREADS"] = "1"
    try:
        yield
    finally:
        if before is None:
            del os.environ["RAYON_NUM_THREADS"]
        else:
            os.environ["RAYON_NUM_THREADS"] = before


def draw(cases: list[dict[str, Any]], rows: list[dict[str, Any]], path: Path) -> None:
    """The group's speed–accuracy chart (fem2d's chart with this group's families)."""
    drawn = {family(r) for r in rows if "seconds" in r}
    chart(cases, rows, path, {name: colour for name, colour in FAMILIES.items() if name in drawn},
          family, "Friction: every method and QP solver, time against force error against the "
          "exact answer", "the exact answer")


def main(quick: bool, out: Path) -> None:
    """Run the group, write runs.json, table.md and speed_accuracy.png to ``out``."""
    start = time.perf_counter()
    previous: dict[tuple[str, str], tuple[int, float]] = {}
    cases, rows = [], []
    with one_rayon_thread():
        for case in (c for c in CASES if c.quick or not quick):
            began = time.perf_counter()
            described, found = run_case(case, quick, previous)
            described["seconds"] = time.perf_counter() - began
            print(f"{case.name}: {described['seconds']:.1f} s", flush=True)
            cases.append(described)
            rows += found
    out.mkdir(parents=True, exist_ok=True)
    document = {"machine": machine(), "quick": quick, "wrong_above": WRONG,
                "timeout_seconds": TIMEOUT[quick], "cases": cases, "runs": rows}
    (out / "runs.json").write_text(json.dumps(document, indent=1))
    (out / "table.md").write_text(table(cases, rows))
    draw(cases, rows, out / "speed_accuracy.png")
    print(table(cases, rows))
    print(f"{len(rows)} runs in {time.perf_counter() - start:.0f} s; written: {out}/runs.json, "
          "table.md, speed_accuracy.png")


def redraw(runs: Path, out: Path) -> None:
    """Write table.md and speed_accuracy.png again into ``out`` from a run's runs.json."""
    document = json.loads(runs.read_text())
    out.mkdir(parents=True, exist_ok=True)
    (out / "table.md").write_text(table(document["cases"], document["runs"]))
    draw(document["cases"], document["runs"], out / "speed_accuracy.png")


if __name__ == "__main__":  # python benchmarks/friction_group.py RUNS [OUT]: redraw
    import sys

    runs = Path(sys.argv[1])
    redraw(runs, Path(sys.argv[2]) if len(sys.argv) > 2 else runs.parent)
