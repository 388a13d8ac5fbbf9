"""Every method on one scene, side by side (:func:`compare`), against the exact reference
where there is one: one :class:`Run` per method and contact kind."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from contactqp.errors import ContactqpError, ProblemError, SceneError
from contactqp.methods import CONTACT_KINDS
from contactqp.methods.penalty import TEXTBOOK_PENALTY
from contactqp.methods.qp import available_qp_solvers
from contactqp.model import contact_forces_on_nodes, largest
from contactqp.problem import Problem, frictionless
from contactqp.progress import as_progress, counter
from contactqp.reference import reference
from contactqp.result import Result
from contactqp.scene import Scene
from contactqp.solve import as_target, solve

ROUND_OFF = 1e-12  # relative: a force error (of the force) or a force (of F) below it is round-off
# A study keeps every run's Result: at 10⁶ elements compare took 5.2 GB and 53 s, the penalty
# sweep 2.9 GB and 45 s (default_scene(10⁶), a shared 2-core machine), growing in proportion;
# at the 10⁷ a scene may have, compare grew past 24 GB and was killed
MAX_STUDY_ELEMENTS = 1_000_000


def study_size(scene: Scene | Problem, study: str) -> Scene | Problem:
    """``scene`` if ``study`` can hold its answers (:data:`MAX_STUDY_ELEMENTS` elements, or a
    problem's dofs), else a SceneError, before anything is solved."""
    frictionless(scene, study)
    if isinstance(scene, Problem):
        if scene.n > MAX_STUDY_ELEMENTS:
            raise ProblemError(f"the problem has {scene.n} dofs; {study} keeps every run's "
                               f"answer in memory and takes at most {MAX_STUDY_ELEMENTS}: "
                               "solve it by one method (contactqp solve)")
        return scene
    if scene.n_elements > MAX_STUDY_ELEMENTS:
        raise SceneError(f"bar: the scene has {scene.n_elements} elements; {study} keeps every "
                         f"run's answer in memory and takes at most {MAX_STUDY_ELEMENTS}: solve "
                         "it by one method (contactqp solve), or with fewer elements")
    return scene


@dataclass(frozen=True, eq=False)
class Run:
    """One row of a comparison: a Result, or the error that stopped the method; with the
    exact contact forces (N, one per contact row) where the comparison has them.

    Attributes
    ----------
    label : str
        The method and its options as the table names them (``"penalty ε=1e+14"``).
    contact : str
        ``"inequality"`` or ``"equality"``.
    result : Result or None
        The checked answer; None where the method could not solve the scene.
    error : str
        Why the method could not solve the scene ("" where it did).
    exact_force : numpy.ndarray or None
        The exact contact forces, where the comparison has them.
    """

    label: str
    contact: str
    result: Result | None
    error: str = ""
    exact_force: np.ndarray | None = None

    @property
    def exact_error(self) -> float | None:
        """The largest error of the contact force on any node against the exact reference
        (N): max abs(λ − λ_exact) where each node has one contact row. Per node, since where
        contacts close a loop only the force on each node is unique. None without a result
        or a reference."""
        if self.result is None or self.exact_force is None:
            return None
        difference = self.result.contact_force - self.exact_force
        if self.result.layout is None:
            return largest(difference)
        return largest(contact_forces_on_nodes(self.result.layout, difference))


def method_runs(scene: Scene | Problem | None = None) -> list[tuple[str, dict]]:
    """(method, options) of every run in a comparison, one per installed solver; the penalty
    at its default ε and, on a scene, at the textbook's 1e14 N/m (in the scene's units) and
    Nitsche's method (a problem's matrices carry no traction for it)."""
    problem = isinstance(scene, Problem)
    metre = 1.0 if scene is None or problem else scene.unit.metre
    runs: list[tuple[str, dict]] = [("lagrange", {}), ("penalty", {})]
    if not problem:
        runs.append(("penalty", {"penalty": TEXTBOOK_PENALTY * metre}))
    runs += [("augmented", {}), ("lemke", {}), ("pgs", {}), ("pgs", {"relaxation": 1.5}),
             ("semismooth_newton", {}), ("semismooth_newton", {"ncp": "fischer-burmeister"})]
    if not problem:
        runs.append(("nitsche", {}))
    for info in available_qp_solvers():
        if info.available:
            runs.append(("qp", {"backend": info.backend, "solver": info.solver}))
    return runs


NCP_LABELS = {"fischer-burmeister": "FB", "min": "min"}  # short enough for a table's row


def run_label(method: str, options: dict) -> str:
    """e.g. 'lagrange', 'penalty', 'penalty ε=1e+14', 'pgs ω=1.5', 'semismooth_newton FB'
    (Fischer–Burmeister), 'qp/osqp/osqp'."""
    if method == "penalty" and "penalty" in options:
        return f"penalty ε={options['penalty']:.0e}"
    if method == "pgs" and "relaxation" in options:
        return f"pgs ω={options['relaxation']:g}"
    if method == "semismooth_newton" and "ncp" in options:
        return f"{method} {NCP_LABELS.get(options['ncp'], options['ncp'])}"
    return "/".join([method, *(str(v) for v in options.values() if v)])


def exact_reference(scene: Scene | Problem) -> np.ndarray | None:
    """The exact unilateral contact forces of ``scene`` (:func:`contactqp.reference.reference`,
    N, one per contact row), or None for a scene beyond its reach (more than
    ``MAX_EXACT_NODES`` nodes unless it is one bar with walls only) and for a problem (whose
    answers each carry their own distance to the exact one)."""
    if isinstance(scene, Problem):
        return None
    try:
        return reference(scene).contact_force
    except SceneError:
        return None


def compare(scene: Scene | Problem | str | None = None,
            contacts: tuple[str, ...] = CONTACT_KINDS, progress: Any = None) -> list[Run]:
    """Solve ``scene`` (a Scene, a scene file's path, or None for the default scene) by every
    method and every installed QP solver, for each contact kind; the inequality runs carry the
    exact contact forces (:func:`exact_reference`) where there are some. A method that cannot
    solve the scene is a Run with its error. :func:`contactqp.report.table` prints the runs.

    Parameters
    ----------
    scene : Scene, Problem, str, os.PathLike or None
        The scene or the problem, the path of a scene file or of a problem's files (an
        ``.npz`` bundle, a folder of Matrix Market files), or None for the default scene.
    contacts : tuple of str
        The contact kinds to run, ``("inequality", "equality")`` by default.
    progress : bool or callable, optional
        True: a line on stderr each second of a comparison longer than a second; a
        callable: ``progress(done, total)`` after each run (:mod:`contactqp.progress`).

    Returns
    -------
    list of Run
        One per method (and QP backend/solver) and contact kind, in the order the table shows.

    Raises
    ------
    OptionError
        ``scene`` is neither a Scene, a path nor None.
    SceneError
        A scene file that cannot be read or holds bad values, or more than
        :data:`MAX_STUDY_ELEMENTS` elements.
    """
    scene = study_size(as_target(scene), "compare")
    report = as_progress(progress, "compare")
    exact = exact_reference(scene) if "inequality" in contacts else None
    runs = method_runs(scene)
    advance = counter(report, len(runs) * len(contacts))
    rows = []
    for contact in contacts:
        known = exact if contact == "inequality" else None  # the reference is unilateral
        for method, options in runs:
            label = run_label(method, options)
            try:
                result = solve(scene, method, contact, **options)
            except ContactqpError as error:
                rows.append(Run(label, contact, None, str(error), known))
            else:
                rows.append(Run(label, contact, result, "", known))
            advance()
    return rows
