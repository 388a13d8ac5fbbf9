"""Several solves of one scene, compared: every method side by side, and the penalty sweep."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.errors import ContactqpError
from contactqp.methods import CONTACT_KINDS, solve
from contactqp.methods.penalty import DEFAULT_PENALTY
from contactqp.result import Result
from contactqp.scene import Scene, seed_scene

SWEEP_PENALTIES = (1.0,) + tuple(10.0 ** k for k in range(5, 21))  # N/m: 1, 1e5, 1e6 … 1e20


@dataclass(frozen=True)
class Run:
    """One row of a comparison: a Result, or the error that stopped the method."""

    label: str
    contact: str
    result: Result | None
    error: str = ""


def method_runs() -> list[tuple[str, dict]]:
    """(method, options) of every run in a comparison, one per installed solver."""
    runs: list[tuple[str, dict]] = [("lagrange", {}), ("penalty", {})]
    try:
        from contactqp.methods.qp import available_qp_solvers
    except ImportError:  # QP backends not part of this build
        return runs
    for backend, solver in available_qp_solvers():
        runs.append(("qp", {"backend": backend, "solver": solver}))
    return runs


def run_label(method: str, options: dict) -> str:
    """e.g. 'lagrange', 'penalty ε=1e+14', 'qp/osqp/OSQP'."""
    if method == "penalty":
        return f"penalty ε={options.get('penalty', DEFAULT_PENALTY):.0e}"
    return "/".join([method, *(str(v) for v in options.values() if v)])


def compare(scene: Scene | None = None, contacts: tuple[str, ...] = CONTACT_KINDS) -> list[Run]:
    """Solve ``scene`` by every method (and every installed QP solver) for each contact kind."""
    scene = seed_scene() if scene is None else scene
    rows = []
    for contact in contacts:
        for method, options in method_runs():
            label = run_label(method, options)
            try:
                rows.append(Run(label, contact, solve(scene, method, contact, **options)))
            except ContactqpError as error:
                rows.append(Run(label, contact, None, str(error)))
    return rows


@dataclass(frozen=True)
class PenaltySweep:
    """Penalty solves over a range of ε against the Lagrange solution of the same scene.

    ``force_error`` is the largest relative contact-force error against Lagrange (NaN where the
    solve failed). ``best`` is the index of the smallest error: the sweep converges up to it,
    and beyond it round-off takes over.
    """

    penalties: np.ndarray
    runs: tuple[Run, ...]
    reference: Result
    force_error: np.ndarray
    penetration: np.ndarray
    best: int

    def summary(self) -> str:
        best = self.penalties[self.best]
        text = (f"converges up to ε = {best:.0e} N/m (force error {self.force_error[self.best]:.1e})")
        after = self.force_error[self.best + 1:]
        if after.size:
            worst = np.nanmax(after) if np.any(np.isfinite(after)) else np.nan
            text += (f"; beyond it round-off takes over (error grows to {worst:.1e} by "
                     f"ε = {self.penalties[-1]:.0e})")
        else:
            text += "; still converging at the largest ε"
        return text


def penalty_sweep(scene: Scene | None = None, penalties: tuple[float, ...] = SWEEP_PENALTIES,
                  contact: str = "inequality") -> PenaltySweep:
    """Penetration and contact force of the penalty method for each ε in ``penalties``."""
    scene = seed_scene() if scene is None else scene
    reference = solve(scene, "lagrange", contact)
    scale = max(float(np.abs(reference.contact_force).max(initial=0.0)), 1e-300)
    runs, errors, depths = [], [], []
    for eps in penalties:
        try:
            result = solve(scene, "penalty", contact, penalty=eps)
        except ContactqpError as error:
            runs.append(Run(run_label("penalty", {"penalty": eps}), contact, None, str(error)))
            errors.append(np.nan)
            depths.append(np.nan)
            continue
        runs.append(Run(run_label("penalty", {"penalty": eps}), contact, result))
        errors.append(float(np.abs(result.contact_force - reference.contact_force).max(initial=0.0))
                      / scale)
        depths.append(float(result.penetration.max(initial=0.0)))
    errors_array = np.array(errors)
    best = int(np.nanargmin(errors_array)) if np.any(np.isfinite(errors_array)) else 0
    return PenaltySweep(np.array(penalties, dtype=float), tuple(runs), reference, errors_array,
                        np.array(depths), best)
