"""contactqp: contact mechanics of elastic bars written as constrained optimisation.

Scene → model (K, P, C, g) → method → checked Result. See the README for the conventions.
"""

from contactqp.curve import LoadPath, first_contact_factor, load_path
from contactqp.errors import (
    ContactqpError,
    OptionError,
    SceneError,
    SolverError,
    SolverNotAvailable,
)
from contactqp.methods import CONTACT_KINDS, METHODS, solve
from contactqp.methods.qp import QPProblem, available_qp_solvers, qp_problem
from contactqp.model import Model, build_model
from contactqp.result import GUARANTEE, TOLERANCES, Result, Tolerances, check
from contactqp.scene import (
    UNIT_SYSTEMS,
    Bar,
    BarContact,
    DistributedLoad,
    Load,
    Scene,
    Support,
    Units,
    Wall,
    convert_units,
    load_scene,
    minimal,
    scene_from_dict,
    scene_to_toml,
    seed_scene,
    wall_at_every_node,
)

__version__ = "0.1.0"

__all__ = [
    "CONTACT_KINDS", "GUARANTEE", "METHODS", "TOLERANCES", "UNIT_SYSTEMS", "Bar", "BarContact",
    "ContactqpError",
    "DistributedLoad", "Load", "LoadPath", "Model", "OptionError", "QPProblem", "Result", "Scene",
    "SceneError", "SolverError", "SolverNotAvailable", "Support", "Tolerances", "Units", "Wall",
    "__version__", "available_qp_solvers", "build_model", "check", "convert_units", "first_contact_factor",
    "load_path", "load_scene", "minimal", "qp_problem", "scene_from_dict", "scene_to_toml",
    "seed_scene", "solve", "wall_at_every_node",
]
