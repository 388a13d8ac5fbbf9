"""Several solves of one scene, compared: every method side by side, and the penalty sweep."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.builders import (
    DEFAULT_DIAMETERS,
    DEFAULT_GAP,
    DEFAULT_LENGTH,
    DEFAULT_LOAD,
    DEFAULT_MODULUS,
    default_scene,
)
from contactqp.errors import ContactqpError
from contactqp.methods import CONTACT_KINDS
from contactqp.methods.penalty import TEXTBOOK_PENALTY
from contactqp.methods.qp import available_qp_solvers
from contactqp.result import Result, plain
from contactqp.scene import Load, Scene
from contactqp.solve import as_scene, solve

SWEEP_PENALTIES = (1.0,) + tuple(10.0 ** k for k in range(5, 21))  # N/m: 1, 1e5, 1e6 … 1e20


def sweep_penalties(scene: Scene) -> tuple[float, ...]:
    """:data:`SWEEP_PENALTIES` (N/m) in the scene's units (force per length): the same
    physical sweep in every unit system."""
    return tuple(eps * scene.unit.metre for eps in SWEEP_PENALTIES)


@dataclass(frozen=True)
class Run:
    """One row of a comparison: a Result, or the error that stopped the method."""

    label: str
    contact: str
    result: Result | None
    error: str = ""


def method_runs(scene: Scene | None = None) -> list[tuple[str, dict]]:
    """(method, options) of every run in a comparison, one per installed solver; the penalty
    at its default ε and at the textbook's 1e14 N/m (in the scene's units)."""
    metre = 1.0 if scene is None else scene.unit.metre
    runs: list[tuple[str, dict]] = [("lagrange", {}), ("penalty", {}),
                                    ("penalty", {"penalty": TEXTBOOK_PENALTY * metre}),
                                    ("augmented", {}), ("lemke", {}), ("pgs", {}),
                                    ("pgs", {"relaxation": 1.5}), ("semismooth_newton", {}),
                                    ("semismooth_newton", {"ncp": "fischer-burmeister"}),
                                    ("nitsche", {})]
    for info in available_qp_solvers():
        if info.available:
            runs.append(("qp", {"backend": info.backend, "solver": info.solver}))
    return runs


def run_label(method: str, options: dict) -> str:
    """e.g. 'lagrange', 'penalty', 'penalty ε=1e+14', 'pgs ω=1.5', 'qp/osqp/OSQP'."""
    if method == "penalty" and "penalty" in options:
        return f"penalty ε={options['penalty']:.0e}"
    if method == "pgs" and "relaxation" in options:
        return f"pgs ω={options['relaxation']:g}"
    return "/".join([method, *(str(v) for v in options.values() if v)])


def compare(scene: Scene | None = None, contacts: tuple[str, ...] = CONTACT_KINDS) -> list[Run]:
    """Solve ``scene`` by every method (and every installed QP solver) for each contact kind."""
    scene = as_scene(scene)
    rows = []
    for contact in contacts:
        for method, options in method_runs(scene):
            label = run_label(method, options)
            try:
                rows.append(Run(label, contact, solve(scene, method, contact, **options)))
            except ContactqpError as error:
                rows.append(Run(label, contact, None, str(error)))
    return rows


@dataclass(frozen=True)
class PenaltySweep:
    """Penalty and augmented-Lagrangian solves over a range of ε against the Lagrange solution.

    ``force_error`` is the largest relative contact-force error against Lagrange (NaN where the
    solve failed); ``augmented_error`` and ``augmented_iterations`` the same for the augmented
    method at the same ε. ``best`` is the index of the penalty's smallest error: the sweep
    converges up to it, and beyond it round-off takes over.
    """

    penalties: np.ndarray
    runs: tuple[Run, ...]
    reference: Result
    force_error: np.ndarray
    penetration: np.ndarray
    best: int
    augmented_runs: tuple[Run, ...]
    augmented_error: np.ndarray
    augmented_iterations: np.ndarray

    def to_dict(self) -> dict:
        """The JSON form of ``contactqp penalty-sweep --json``."""
        def forces(runs: tuple[Run, ...], key: str) -> list:
            return [None if r.result is None else getattr(r.result, key) for r in runs]

        return plain({
            "penalty": self.penalties, "units": self.reference.scene.units,
            "contact_force": forces(self.runs, "contact_force"),
            "penetration": forces(self.runs, "penetration"),
            "force_error": self.force_error,
            "verified": [r.result is not None and r.result.verified for r in self.runs],
            "reference_contact_force": self.reference.contact_force,
            "converged_up_to": self.penalties[self.best],
            "augmented_force_error": self.augmented_error,
            "augmented_iterations": self.augmented_iterations,
            "augmented_verified": [r.result is not None and r.result.verified
                                   for r in self.augmented_runs],
        })

    def summary(self) -> str:
        if not np.any(np.isfinite(self.force_error)):
            return "no penalty solve succeeded"
        if not np.any(self.reference.contact_force):
            return ("no contact carries a force here (every ε gives the free answer): nothing "
                    "to converge")
        best = self.penalties[self.best]
        unit = self.reference.scene.unit.stiffness
        text = (f"converges up to ε = {best:.0e} {unit} (force error "
                f"{self.force_error[self.best]:.1e})")
        after = self.force_error[self.best + 1:]
        if after.size:
            worst = np.nanmax(after) if np.any(np.isfinite(after)) else np.nan
            text += (f"; beyond it round-off takes over (error grows to {worst:.1e} by "
                     f"ε = {self.penalties[-1]:.0e} {unit})")
        else:
            text += "; still converging at the largest ε"
        return text


def _sweep_runs(scene: Scene, method: str, penalties: tuple[float, ...], contact: str,
                reference: Result) -> tuple[tuple[Run, ...], np.ndarray]:
    """One run of ``method`` per ε, and each run's relative force error against ``reference``."""
    scale = max(float(np.abs(reference.contact_force).max(initial=0.0)), 1e-300)
    runs, errors = [], []
    for eps in penalties:
        label = f"{method} ε={eps:.0e}"
        try:
            result = solve(scene, method, contact, penalty=eps)
        except ContactqpError as error:
            runs.append(Run(label, contact, None, str(error)))
            errors.append(np.nan)
            continue
        runs.append(Run(label, contact, result))
        difference = np.abs(result.contact_force - reference.contact_force).max(initial=0.0)
        errors.append(float(difference) / scale)
    return tuple(runs), np.array(errors)


def penalty_sweep(scene: Scene | None = None, penalties: tuple[float, ...] | None = None,
                  contact: str = "inequality") -> PenaltySweep:
    """Penetration and contact force of the penalty method (and of the augmented Lagrangian
    method with the same ε) for each ε in ``penalties`` (force per length in the scene's
    units; default :func:`sweep_penalties`, 1 and 1e5 … 1e20 N/m)."""
    scene = as_scene(scene)
    penalties = sweep_penalties(scene) if penalties is None else tuple(penalties)
    reference = solve(scene, "lagrange", contact)
    runs, errors = _sweep_runs(scene, "penalty", penalties, contact, reference)
    augmented, augmented_errors = _sweep_runs(scene, "augmented", penalties, contact, reference)
    depths = np.array([np.nan if r.result is None else float(r.result.penetration.max(initial=0.0))
                       for r in runs])
    iterations = np.array([0 if r.result is None else r.result.iterations for r in augmented])
    best = int(np.nanargmin(errors)) if np.any(np.isfinite(errors)) else 0
    return PenaltySweep(np.array(penalties, dtype=float), runs, reference, errors, depths, best,
                        augmented, augmented_errors, iterations)


def cone_compliance(a: float, b: float) -> float:
    """∫ₐᵇ dx / (E·A(x)) of the default scene's conical bar (m/N): 4(b − a)/(E·π·d(a)·d(b))."""
    d0, d1 = DEFAULT_DIAMETERS

    def diameter(x: float) -> float:
        return d0 + (d1 - d0) * x / DEFAULT_LENGTH

    return 4.0 * (b - a) / (DEFAULT_MODULUS * np.pi * diameter(a) * diameter(b))


def cone_contact_force() -> float:
    """The continuum contact force of the default scene (N): λ = (F·f(0, L/2) − g) / f(0, L)."""
    free_tip = DEFAULT_LOAD * cone_compliance(0.0, DEFAULT_LENGTH / 2)
    return (free_tip - DEFAULT_GAP) / cone_compliance(0.0, DEFAULT_LENGTH)


@dataclass(frozen=True)
class MeshConvergence:
    """Relative contact-force error of the default scene against the continuum, per mesh."""

    elements: np.ndarray
    errors: dict[str, np.ndarray]  # area rule -> |λ_h − λ| / λ
    exact_force: float


def mesh_convergence(elements: tuple[int, ...] = (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024)
                     ) -> MeshConvergence:
    """Solve the default scene on finer and finer meshes with both area rules."""
    exact = cone_contact_force()
    errors = {
        rule: np.array([abs(solve(default_scene(n, rule)).contact_force[0] - exact) / exact
                        for n in elements])
        for rule in ("midpoint", "exact")
    }
    return MeshConvergence(np.array(elements), errors, exact)


NITSCHE_GAMMA0 = tuple(10.0 ** k for k in range(9))  # γ₀ = 1, 10, … 1e8
NITSCHE_THETAS = (1.0, 0.0, -1.0)
TIP_LOAD = 2e5  # N: the load nitsche_sweep's default scene adds at the wall's node


@dataclass(frozen=True)
class NitscheSweep:
    """Nitsche's method over γ₀ for each θ against Lagrange: per θ (rows) and γ₀ (columns)
    the relative contact-force error, the largest penetration (NaN where the solve failed)
    and whether the answer was verified."""

    gamma0: np.ndarray
    thetas: tuple[float, ...]
    force_error: np.ndarray
    penetration: np.ndarray
    verified: np.ndarray
    reference: Result


def nitsche_scene() -> Scene:
    """The default scene with TIP_LOAD more at the wall's node: where the end node carries a
    load, Nitsche's answer is its own and γ₀ and θ decide how far (on the default scene
    itself it is the exact answer for every γ₀)."""
    scene = default_scene()
    wall = scene.walls[0]
    return Scene(scene.bars, scene.supports, (*scene.loads, Load(wall.node, TIP_LOAD)),
                 scene.walls, name=f"{scene.name}, {TIP_LOAD:.0f} N more at the wall's node",
                 units=scene.units)


def nitsche_sweep(scene: Scene | None = None,
                  gamma0: tuple[float, ...] = NITSCHE_GAMMA0) -> NitscheSweep:
    """Nitsche's method (θ = 1, 0, −1) at each γ₀ on ``scene`` (default
    :func:`nitsche_scene`), against Lagrange multipliers."""
    scene = nitsche_scene() if scene is None else as_scene(scene)
    reference = solve(scene, "lagrange")
    scale = max(float(np.abs(reference.contact_force).max(initial=0.0)), 1e-300)
    shape = (len(NITSCHE_THETAS), len(gamma0))
    error, depth = np.full(shape, np.nan), np.full(shape, np.nan)
    verified = np.zeros(shape, dtype=bool)
    for i, theta in enumerate(NITSCHE_THETAS):
        for j, g in enumerate(gamma0):
            try:
                result = solve(scene, "nitsche", gamma0=g, theta=theta)
            except ContactqpError:  # the symmetric form below its threshold
                continue
            error[i, j] = float(np.abs(result.contact_force
                                       - reference.contact_force).max(initial=0.0)) / scale
            depth[i, j] = float(result.penetration.max(initial=0.0))
            verified[i, j] = result.verified
    return NitscheSweep(np.array(gamma0), NITSCHE_THETAS, error, depth, verified, reference)
