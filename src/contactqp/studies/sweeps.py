"""One method over its parameter: the penalty sweep (the penalty and the augmented Lagrangian
method over ε, against Lagrange multipliers) and Nitsche's sweep (over γ₀, for each θ)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from contactqp._validate import positive_values
from contactqp.builders import default_scene
from contactqp.errors import ContactqpError, OptionError
from contactqp.model import largest
from contactqp.model.sparse import problem_model
from contactqp.problem import Problem
from contactqp.progress import as_progress, counter
from contactqp.result import Result, plain
from contactqp.scene import Load, Scene
from contactqp.solve import as_scene, as_target, solve
from contactqp.studies.comparison import ROUND_OFF, Run, study_size

SWEEP_PENALTIES = (1.0,) + tuple(10.0 ** k for k in range(5, 21))  # N/m: 1, 1e5, 1e6 … 1e20


PROBLEM_SWEEP = tuple(10.0 ** k for k in range(-6, 15))  # of a problem's stiffest row


def sweep_penalties(scene: Scene | Problem) -> tuple[float, ...]:
    """:data:`SWEEP_PENALTIES` (N/m) in the scene's units (force per length): the same
    physical sweep in every unit system. A problem's (whose units are the user's):
    :data:`PROBLEM_SWEEP` times the stiffness its stiffest row sees, c_iᵀK c_i/(c_iᵀc_i)²."""
    if isinstance(scene, Problem):
        stiffest = float(np.max(problem_model(scene).row_stiffness, initial=0.0)) or 1.0
        return tuple(float(eps * stiffest) for eps in PROBLEM_SWEEP)
    return tuple(eps * scene.unit.metre for eps in SWEEP_PENALTIES)


def _stiffness_unit(result: Result) -> str:
    force, length = result.model.units
    return f"{force}/{length}" if force and length else ""


@dataclass(frozen=True)
class PenaltySweep:
    """Penalty and augmented-Lagrangian solves over a range of ε against the Lagrange solution.

    ``force_error`` is the largest relative contact-force error against Lagrange (NaN where the
    solve failed) and ``penetration`` the largest penetration; ``augmented_error`` and
    ``augmented_iterations`` the same for the augmented method at the same ε (its
    penetration, and whether it stopped at its update cap: :attr:`augmented_penetration`,
    :attr:`augmented_capped`). ``best`` is the index of the penalty's smallest error: the
    sweep converges up to it, and beyond it round-off takes over.
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

    @property
    def augmented_penetration(self) -> np.ndarray:
        """The augmented method's largest penetration at each ε (NaN where it failed)."""
        return _largest_penetration(self.augmented_runs)

    @property
    def augmented_capped(self) -> np.ndarray:
        """Where the augmented method stopped at its update cap (``max_iterations``) and
        returned its last iterate (the solver's own claim of success is False)."""
        return np.array([r.result is not None and not r.result.claimed_success
                         for r in self.augmented_runs], dtype=bool)

    @property
    def carries_force(self) -> bool:
        """Whether any contact carries force in the Lagrange answer (more than round-off,
        :data:`ROUND_OFF`·F): without one there is nothing for ε to converge to."""
        scale = self.reference.force_scale
        return largest(self.reference.contact_force) > ROUND_OFF * scale

    @property
    def converged_up_to(self) -> float | None:
        """The ε of the penalty's smallest force error, or None where there is nothing to
        converge (no contact carries force, or no solve succeeded)."""
        if not (self.carries_force and np.any(np.isfinite(self.force_error))):
            return None
        return float(self.penalties[self.best])

    def to_dict(self) -> dict:
        """The JSON form of ``contactqp penalty-sweep --json``: per ε the penalty's and the
        augmented method's contact forces, penetrations, force errors and verdicts (None
        where a solve failed)."""
        def of(runs: tuple[Run, ...], key: str) -> list:
            return [None if r.result is None else getattr(r.result, key) for r in runs]

        def verified(runs: tuple[Run, ...]) -> list:
            return [r.result is not None and r.result.verified for r in runs]

        return plain({
            "penalty": self.penalties,
            "units": (self.reference.scene.units if self.reference.scene is not None
                      else self.reference.problem.units),
            "contact_force": of(self.runs, "contact_force"),
            "penetration": of(self.runs, "penetration"),
            "force_error": self.force_error,
            "verified": verified(self.runs),
            "failed": [r.error or None for r in self.runs],
            "reference_contact_force": self.reference.contact_force,
            "converged_up_to": self.converged_up_to,
            "augmented_contact_force": of(self.augmented_runs, "contact_force"),
            "augmented_penetration": of(self.augmented_runs, "penetration"),
            "augmented_force_error": self.augmented_error,
            "augmented_iterations": self.augmented_iterations,
            "augmented_capped": self.augmented_capped,
            "augmented_verified": verified(self.augmented_runs),
            "augmented_failed": [r.error or None for r in self.augmented_runs],
            "summary": self.summary(),
        })

    def summary(self) -> str:
        """Where the penalty converges and where round-off takes over; on a second line, where
        the augmented method is verified and where it stops at its update cap."""
        if not np.any(np.isfinite(self.force_error)):
            return "no penalty solve succeeded"
        if not self.carries_force:
            return ("no contact carries a force here (every ε gives the free answer): nothing "
                    "to converge")
        return f"penalty: {self._penalty_summary()}\n{self._augmented_summary()}"

    def _penalty_summary(self) -> str:
        unit = _stiffness_unit(self.reference)
        if np.nanmax(self.force_error) <= ROUND_OFF:  # exact throughout: nothing converges
            return (f"every ε gives the Lagrange force (force error at most "
                    f"{np.nanmax(self.force_error):.1e})")
        error = self.force_error[self.best]
        text = f"converges up to ε = {self.penalties[self.best]:.0e} {unit} (force error {error:.1e})"
        after = self.force_error[self.best + 1:]
        if not after.size:
            return text + "; still converging at the largest ε"
        worst = np.nanmax(after) if np.any(np.isfinite(after)) else np.nan
        if worst > error:
            text += (f"; beyond it round-off takes over (error grows to {worst:.1e} by "
                     f"ε = {self.penalties[-1]:.0e} {unit})")
        return text

    def _augmented_summary(self) -> str:
        verified = np.array([r.result is not None and r.result.verified
                             for r in self.augmented_runs], dtype=bool)
        unit = _stiffness_unit(self.reference)
        text = "augmented Lagrangian: "
        if verified.all():
            text += "verified at every ε"
        elif not verified.any():
            text += "verified at no ε"
        else:
            i = int(np.flatnonzero(verified)[0])
            text += (f"verified from ε = {self.penalties[i]:.0e} {unit} "
                     f"({self.augmented_iterations[i]} updates there)")
            if not verified[i:].all():
                text += " but not at every ε above it"
        capped = self.augmented_capped
        if capped.any():
            cap = int(self.augmented_iterations[capped].max())
            text += (f"; stopped at its cap of {cap} updates at {int(capped.sum())} ε "
                     f"(up to {self.penalties[capped].max():.0e} {unit})")
        return text


def _largest_penetration(runs: tuple[Run, ...]) -> np.ndarray:
    return np.array([np.nan if r.result is None else float(r.result.penetration.max(initial=0.0))
                     for r in runs])


def _sweep_runs(scene: Scene, method: str, penalties: tuple[float, ...], contact: str,
                reference: Result, advance: Callable[[], None]
                ) -> tuple[tuple[Run, ...], np.ndarray]:
    """One run of ``method`` per ε, and each run's relative force error against ``reference``;
    ``advance()`` after each."""
    scale = max(float(np.abs(reference.contact_force).max(initial=0.0)), 1e-300)
    runs, errors = [], []
    for eps in penalties:
        label = f"{method} ε={eps:.0e}"
        try:
            result = solve(scene, method, contact, penalty=eps)
        except ContactqpError as error:
            advance()
            runs.append(Run(label, contact, None, str(error)))
            errors.append(np.nan)
            continue
        advance()
        runs.append(Run(label, contact, result))
        difference = np.abs(result.contact_force - reference.contact_force).max(initial=0.0)
        errors.append(float(difference) / scale)
    return tuple(runs), np.array(errors)


def penalty_sweep(scene: Scene | Problem | None = None,
                  penalties: tuple[float, ...] | None = None,
                  contact: str = "inequality", progress: Any = None) -> PenaltySweep:
    """Penetration and contact force of the penalty method (and of the augmented Lagrangian
    method with the same ε) for each ε in ``penalties`` (force per length in the scene's
    units; default :func:`sweep_penalties`, 1 and 1e5 … 1e20 N/m).

    Parameters
    ----------
    scene : Scene, Problem, a path of either, or None
        The scene or the problem (None: the default scene).
    penalties : tuple of float, optional
        The values of ε, force per length in the scene's or problem's units (default
        :func:`sweep_penalties`).
    contact : str
        ``"inequality"`` (default) or ``"equality"``.
    progress : bool or callable, optional
        True: a line on stderr each second of a sweep longer than a second; a callable:
        ``progress(done, total)`` after each solve (:mod:`contactqp.progress`).

    Returns
    -------
    PenaltySweep
        Per ε the penalty's and the augmented method's runs, force errors against Lagrange and
        penetrations; ``summary()`` says where the penalty stops converging.

    Raises
    ------
    OptionError
        A bad contact kind or ε.
    SceneError
        A scene of more than :data:`MAX_STUDY_ELEMENTS` elements.
    SolverError
        The Lagrange solution the sweep compares with cannot be computed.
    """
    scene = study_size(as_target(scene), "the penalty sweep")
    penalties = sweep_penalties(scene) if penalties is None else positive_values(
        "penalties", penalties, "ε, force per length", OptionError)
    advance = counter(as_progress(progress, "penalty sweep"), 2 * len(penalties))
    reference = solve(scene, "lagrange", contact)
    runs, errors = _sweep_runs(scene, "penalty", penalties, contact, reference, advance)
    augmented, augmented_errors = _sweep_runs(scene, "augmented", penalties, contact, reference,
                                              advance)
    depths = _largest_penetration(runs)
    iterations = np.array([0 if r.result is None else r.result.iterations for r in augmented])
    best = int(np.nanargmin(errors)) if np.any(np.isfinite(errors)) else 0
    return PenaltySweep(np.array(penalties, dtype=float), runs, reference, errors, depths, best,
                        augmented, augmented_errors, iterations)


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
