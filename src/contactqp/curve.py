"""Load stepping: the force–displacement curve of a scene, per method.

:func:`load_path` scales every load (point and distributed) by factors from 0 to 1 and records,
per method, the displacement of the load point (:meth:`Layout.load_point`), the contact forces
and the penetrations, each step a checked Result. Nothing is rebuilt per step that does not
change with the loads:

each method is prepared once (:func:`contactqp.prepare`) and its steps are one batch
(:meth:`contactqp.Prepared.solve_many`): Lagrange multipliers and the penalty solve every step
at once from one factorisation of K; the augmented Lagrangian and the QP solvers step by step
(through cvxpy the parametrised (DPP) problem is built once per structure and re-solved with
new load parameters: its Result's ``info["cache"]`` says "hit").

With unilateral contact the curve has a kink where the first contact closes, at the load
factor t* = g / (C K⁻¹ P) of the first contact to close (:func:`first_contact_factor`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from contactqp._validate import whole_number
from contactqp.errors import ContactqpError, OptionError
from contactqp.many.prepared import prepare
from contactqp.model import Model, scene_model, wall_stiffness
from contactqp.model.chain.to_problem import problem_from_scene
from contactqp.model.sparse import problem_model
from contactqp.problem import Problem, frictionless
from contactqp.progress import Progress, as_progress
from contactqp.result import Result, plain
from contactqp.scene import MAX_ELEMENTS, Scene
from contactqp.solve import as_target, solve

# name -> (method, contact, options): unilateral contact, the textbook equality (which pulls
# before the wall is reached), the penalty, the augmented Lagrangian and a cvxpy QP; and
# (curve_methods) a soft penalty whose kink shows
CURVE_METHODS: dict[str, tuple[str, str, dict[str, Any]]] = {
    "lagrange": ("lagrange", "inequality", {}),
    "equality": ("lagrange", "equality", {}),
    "penalty": ("penalty", "inequality", {}),
    "augmented": ("augmented", "inequality", {}),
    "qp": ("qp", "inequality", {"backend": "cvxpy"}),
}
# with friction (a problem with T, or a scene with a frictional bed): the methods that take it,
# each step an increment from the last (contactqp.friction.methods)
FRICTION_CURVE_METHODS: dict[str, tuple[str, str, dict[str, Any]]] = {
    "lagrange": ("lagrange", "inequality", {}),
    "penalty": ("penalty", "inequality", {}),
    "augmented": ("augmented", "inequality", {}),
    "qp": ("qp", "inequality", {}),
}
DEFAULT_STEPS = 21
# 1001 steps of the default scene took 28 s (every curve method, a shared 2-core machine) and
# time grows in proportion: 10⁴ steps are minutes, 10⁸ would be years
MAX_STEPS = 10_000
SOFT_PENALTY_PER_STIFFNESS = 1.0  # ε of the soft penalty, times the stiffness the walls see


def curve_methods(scene: Scene | Model | Any) -> dict[str, tuple[str, str, dict[str, Any]]]:
    """:data:`CURVE_METHODS` plus "soft penalty": ε = the stiffness the contacts see
    (:func:`contactqp.model.wall_stiffness`; a problem's: its stiffest row's,
    c_iᵀK c_i/(c_iᵀc_i)²), so that its penetration, λ/ε, is as large as the displacement the
    contact prevents and the softer slope past the kink shows."""
    if isinstance(scene, Scene):
        scene = scene_model(scene)
    if scene.layout is None:  # a problem's model
        stiffest = float(np.max(scene.row_stiffness, initial=0.0))
        seen = stiffest if stiffest > 0.0 else None
    else:
        seen = wall_stiffness(scene)
    methods = dict(CURVE_METHODS)
    if seen is not None:
        methods["soft penalty"] = ("penalty", "inequality",
                                   {"penalty": SOFT_PENALTY_PER_STIFFNESS * seen})
    return methods


@dataclass(frozen=True)
class MethodPath:
    """One method's curve: per step the load point's displacement (m), one contact force (N)
    and one penetration (m) per contact row, and whether the step's Result was verified and
    physical (no wall pulls); with friction also the friction forces (steps x contacts x d)."""

    load_point_displacement: np.ndarray
    contact_force: np.ndarray  # steps x contact rows
    penetration: np.ndarray  # steps x contact rows
    verified: np.ndarray
    physical: np.ndarray
    results: tuple[Result, ...]
    friction_force: np.ndarray | None = None  # steps x contacts x d, with friction


@dataclass(frozen=True)
class LoadPath:
    """The curves of every method on one scene, on the same load factors.

    Attributes
    ----------
    scene : the scene stepped.
    load_factor : the factors (0 to 1) every load was multiplied by.
    load_node : the global node whose displacement the curves follow
        (:meth:`Layout.load_point`).
    methods : name -> the method's curve, for every method that ran.
    failed : name -> why the method has no curve on this scene (e.g. equality contact at a
        node between two walls, which it would fix twice); empty when every method ran.
    """

    scene: Scene | Problem
    load_factor: np.ndarray
    load_node: int
    methods: dict[str, MethodPath]
    failed: dict[str, str] = field(default_factory=dict)

    @property
    def where(self) -> str:
        """The point the curves follow, in words: "node 2" on one bar, "bar 1 node 2" on
        several, "dof 7" of a problem."""
        if isinstance(self.scene, Problem):
            return f"dof {self.load_node}"
        if len(self.scene.bars) == 1:
            return f"node {self.load_node}"
        layout = self.scene.layout
        bar = int(layout.node_bar[self.load_node])
        return f"bar {bar} node {self.load_node - int(layout.node_offsets[bar])}"

    def to_dict(self) -> dict[str, Any]:
        """The JSON form of ``contactqp curve --json``."""
        return {
            "scene": self.scene.name, "load_node": self.load_node,
            "load_factor": self.load_factor.tolist(),
            "methods": {name: {"load_point_displacement": plain(p.load_point_displacement),
                               "contact_force": plain(p.contact_force),
                               "penetration": plain(p.penetration),
                               "verified": p.verified.tolist(),
                               "physical": p.physical.tolist(),
                               **({} if p.friction_force is None
                                  else {"friction_force": plain(p.friction_force)})}
                        for name, p in self.methods.items()},
            "failed": dict(self.failed),
        }


def first_contact_factor(scene: Scene | Problem) -> float:
    """The load factor at which the first contact closes under the scene's loads, from the
    contact-free answer t·K⁻¹P: min over rows with (C K⁻¹ P)ᵢ > 0 of gᵢ / (C K⁻¹ P)ᵢ
    (inf when no load closes a contact); 0 where a bar is held by contact alone: its
    contacts carry load from the first.

    Parameters
    ----------
    scene : Scene or Problem
        The scene or problem, at its full loads (a problem's prescribed values scale with
        its loads).

    Returns
    -------
    float
        The load factor t* at which the first contact closes (inf if none does).

    Raises
    ------
    SceneError
        A scene whose model cannot be built (see :func:`contactqp.build_model`).
    """
    target = frictionless(as_target(scene), "first_contact_factor")
    if isinstance(target, Problem):
        model = problem_model(target)
        if model.singular:
            return 0.0
        closing = target.C @ model.full_displacements(model.free_displacement)
        gaps = target.g
    else:
        model = scene_model(target)
        if model.floating:
            return 0.0
        closing, gaps = model.C @ model.free_displacement, model.g
    reached = closing > 0.0
    return float(np.min(gaps[reached] / closing[reached], initial=np.inf))


def _factors(steps: Any, scene: Scene | Problem) -> np.ndarray:
    """``steps`` load factors from 0 to 1, a number the run can finish and hold: at most
    :data:`MAX_STEPS`, and steps times the scene's elements at most :data:`MAX_ELEMENTS` (a
    method's steps are one batch, :meth:`contactqp.Prepared.solve_many`)."""
    steps = whole_number("steps", steps, 2, error=OptionError, note=" (0 and 1 included)")
    size, what = ((scene.n, "a problem of {} dofs") if isinstance(scene, Problem)
                  else (scene.n_elements, "a scene of {} elements"))
    most = min(MAX_STEPS, MAX_ELEMENTS // max(size, 1))
    if steps > most:
        why = (f"contactqp steps a load path {MAX_STEPS} times at most" if most == MAX_STEPS
               else f"{what.format(size)} is stepped {most} times at most "
                    f"({MAX_ELEMENTS} in all)")
        raise OptionError(f"steps = {steps}: {why}")
    return np.linspace(0.0, 1.0, steps)


def load_path(scene: Scene | Problem | None = None, steps: int = DEFAULT_STEPS,
              methods: dict[str, tuple[str, str, dict[str, Any]]] | None = None,
              progress: Any = None) -> LoadPath:
    """The force–displacement curve of ``scene`` (default scene when None) at ``steps`` load
    factors from 0 to 1 (from 1/steps where a bar is held by contact alone), for each of ``methods`` (name -> (method, contact, options); default
    :func:`curve_methods`): each method prepared once and its steps solved as one batch
    (:meth:`contactqp.Prepared.solve_many`). A method that cannot solve the scene (its error,
    a :class:`~contactqp.errors.ContactqpError`) has no curve: :attr:`LoadPath.failed` says
    why, and the other methods are stepped all the same.

    Parameters
    ----------
    scene : Scene, Problem, a path of either, or None
        The scene (None: the default scene), or a problem: its loads f and prescribed values
        are stepped together, and the curve follows the dof with the largest load (where
        nothing loads it, its first prescribed dof). With friction (a problem with T, or a
        scene with a frictional bed, stepped as its problem) each step is an increment from
        the state the step before reached (``previous``: the slip is measured from there), by
        :data:`FRICTION_CURVE_METHODS` by default, and each curve has its friction forces.
    steps : int
        The number of load factors, 0 and 1 included (default 21).
    methods : dict, optional
        name -> (method, contact, options); default :func:`curve_methods`.
    progress : bool or callable, optional
        True: a line on stderr each second of a run longer than a second (steps done of
        every method's, and the time left); a callable: ``progress(done, total)`` as the
        steps are solved (:mod:`contactqp.progress`). Default: nothing is printed.

    Returns
    -------
    LoadPath
        The load factors, the load node and every method's curve (or why it has none).

    Raises
    ------
    OptionError
        ``steps`` is not a whole number from 2 to :data:`MAX_STEPS` (and at most
        :data:`MAX_ELEMENTS` over the scene's elements), or a method's options are bad.
    SceneError
        A scene whose loads leave a bar held by contact alone unheld.
    """
    scene = as_target(scene)
    if isinstance(scene, Scene) and scene.beds:  # friction: stepped as the scene's problem
        scene = problem_from_scene(scene)
    factors = _factors(steps, scene)
    report = as_progress(progress, "load path")
    friction = isinstance(scene, Problem) and scene.T is not None
    if friction:
        methods = FRICTION_CURVE_METHODS if methods is None else methods
    else:
        model = scene_model(scene) if isinstance(scene, Scene) else problem_model(scene)
        if model.singular:  # with no load nothing fixes where such a body is: start a step in
            factors = np.linspace(0.0, 1.0, factors.size + 1)[1:]
        methods = curve_methods(model) if methods is None else methods
    node = model.layout.load_point() if isinstance(scene, Scene) else _load_dof(scene)
    paths, failed = {}, {}
    total = factors.size * len(methods)
    for i, (name, (method, contact, options)) in enumerate(methods.items()):
        done = i * factors.size  # the steps of the methods before this one

        def step(solved: int, _: int, done: int = done) -> None:
            report(done + solved, total)

        try:
            stepped = _friction_path if friction else _method_path
            paths[name] = stepped(scene, factors, node, method, contact, options,
                                  None if report is None else step)
        except ContactqpError as error:
            failed[name] = str(error)
            if report is not None:
                report(done + factors.size, total)
    return LoadPath(scene, factors, node, paths, failed)


def _friction_path(problem: Problem, factors: np.ndarray, node: int, method: str,
                   contact: str, options: dict[str, Any], progress: Progress | None
                   ) -> MethodPath:
    """One method's curve on a problem with friction: its loads and prescribed values scaled
    together, each step an increment from the state the step before reached
    (:func:`contactqp.solve` with ``previous``; the slip of a step is measured from there)."""
    results: list[Result] = []
    previous = None
    for k, t in enumerate(factors):
        step = problem.with_values(f=t * problem.f, prescribed_values=t * problem.prescribed_values)
        previous = solve(step, method, contact, previous=previous, **options)
        results.append(previous)
        if progress is not None:
            progress(k + 1, factors.size)
    return _curve(results, node, friction=True)


def _curve(results: list[Result], node: int, friction: bool = False) -> MethodPath:
    """A method's curve from its steps' Results (``friction``: with their friction forces)."""
    return MethodPath(np.array([r.u[node] for r in results]),
                      np.array([r.contact_force for r in results]),
                      np.array([r.penetration for r in results]),
                      np.array([r.verified for r in results]),
                      np.array([r.physical for r in results]), tuple(results),
                      np.array([r.friction_force for r in results]) if friction else None)


def _load_dof(problem: Problem) -> int:
    """The dof a problem's curve follows: the largest load's, else the first prescribed."""
    if np.any(problem.f) or not problem.prescribed.size:
        return int(np.argmax(np.abs(problem.f))) if problem.n else 0
    return int(problem.prescribed[np.argmax(np.abs(problem.prescribed_values))])


def _method_path(scene: Scene | Problem, factors: np.ndarray, node: int, method: str,
                 contact: str, options: dict[str, Any], progress: Progress | None
                 ) -> MethodPath:
    """One method's curve: prepared once, its steps solved as one batch (a problem's step by
    step, its loads and prescribed values scaled together, K factorised once)."""
    prepared = prepare(scene, method, contact, **options)
    if isinstance(scene, Problem):
        results = []
        for k, t in enumerate(factors):
            step = scene.with_values(f=t * scene.f, prescribed_values=t * scene.prescribed_values)
            results.append(prepared.solve_scene(step))
            if progress is not None:
                progress(k + 1, factors.size)
        return _curve(results, node)
    batch = prepared.solve_many(loads=np.outer(factors, prepared.scene_loads), progress=progress)
    return MethodPath(batch.u[:, node], batch.contact_force, batch.penetration, batch.verified,
                      batch.physical, tuple(batch[step] for step in range(factors.size)))


__all__ = [
    "CURVE_METHODS",
    "DEFAULT_STEPS",
    "FRICTION_CURVE_METHODS",
    "MAX_STEPS",
    "LoadPath",
    "MethodPath",
    "curve_methods",
    "first_contact_factor",
    "load_path",
]
