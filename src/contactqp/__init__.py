"""contactqp: contact mechanics of elastic bars written as constrained optimisation.

scene → model (K, P, C, g) → method → checked Result → report. The documentation (docs/)
gives the conventions and the architecture. Importing contactqp loads no QP solver and no matplotlib: a
backend is imported when it is first used, matplotlib when a chart is drawn
(:mod:`contactqp.plot`).

>>> import contactqp
>>> result = contactqp.solve()                  # the default scene, Lagrange multipliers
>>> print(result.summary())                     # doctest: +SKIP
>>> print(contactqp.table(contactqp.compare()))  # every method, one table  # doctest: +SKIP
"""

from contactqp.builders import (
    channel,
    convert_units,
    default_scene,
    flat_patch,
    minimal,
    obstacle,
    wall_at_every_node,
)
from contactqp.check import GUARANTEE, TOLERANCES, Tolerances, check
from contactqp.curve import LoadPath, first_contact_factor, load_path
from contactqp.errors import (
    ContactqpError,
    OptionError,
    ProblemError,
    SceneError,
    SolverError,
    SolverNotAvailable,
)
from contactqp.many.prepared import Batch, Prepared, prepare
from contactqp.methods import CONTACT_KINDS, FORMULATIONS, METHODS
from contactqp.methods.qp import QPProblem, available_qp_solvers, qp_problem
from contactqp.model import Layout, Model, build_model
from contactqp.model.chain.to_problem import problem_from_scene
from contactqp.problem import Problem
from contactqp.problem_files import load_problem, save_problem
from contactqp.report import detail_table, table
from contactqp.result import ProblemResult, Result
from contactqp.scene import (
    UNIT_SYSTEMS,
    Bar,
    BarContact,
    Bed,
    DistributedLoad,
    Load,
    Scene,
    Support,
    Units,
    Wall,
    Walls,
)
from contactqp.scene_io import load_scene, scene_from_dict, scene_to_toml
from contactqp.solve import solve
from contactqp.studies import Run, compare, penalty_sweep

__version__ = "0.1.0"

__all__ = [
    "CONTACT_KINDS", "FORMULATIONS", "GUARANTEE", "METHODS", "TOLERANCES", "UNIT_SYSTEMS", "Bar",
    "BarContact", "Batch", "Bed", "ContactqpError", "DistributedLoad", "Layout", "Load", "LoadPath",
    "Model", "OptionError", "Prepared", "Problem", "ProblemError", "ProblemResult", "QPProblem",
    "Result", "Run", "Scene", "SceneError", "SolverError", "SolverNotAvailable", "Support",
    "Tolerances", "Units", "Wall", "Walls", "__version__", "available_qp_solvers", "build_model",
    "channel", "check", "compare", "convert_units", "default_scene", "detail_table",
    "first_contact_factor", "flat_patch", "load_path", "load_problem", "load_scene", "minimal",
    "obstacle", "penalty_sweep", "prepare", "problem_from_scene", "qp_problem", "save_problem",
    "scene_from_dict", "scene_to_toml", "solve", "table", "wall_at_every_node",
]
