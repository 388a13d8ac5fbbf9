"""Several solves of one scene, compared: every method side by side (against the exact
reference where there is one), and the penalty sweep.

- :mod:`~contactqp.studies.comparison`: every method on one scene (:func:`compare`, :class:`Run`);
- :mod:`~contactqp.studies.sweeps`: the penalty sweep and Nitsche's sweep;
- :mod:`~contactqp.studies.mesh`: mesh convergence of the default scene.
"""

from contactqp.studies.comparison import (
    MAX_STUDY_ELEMENTS,
    ROUND_OFF,
    Run,
    compare,
    exact_reference,
    method_runs,
    run_label,
    study_size,
)
from contactqp.studies.mesh import (
    MeshConvergence,
    cone_compliance,
    cone_contact_force,
    mesh_convergence,
)
from contactqp.studies.sweeps import (
    NITSCHE_GAMMA0,
    NITSCHE_THETAS,
    SWEEP_PENALTIES,
    TIP_LOAD,
    NitscheSweep,
    PenaltySweep,
    nitsche_scene,
    nitsche_sweep,
    penalty_sweep,
    sweep_penalties,
)

__all__ = [
    "MAX_STUDY_ELEMENTS",
    "NITSCHE_GAMMA0",
    "NITSCHE_THETAS",
    "ROUND_OFF",
    "SWEEP_PENALTIES",
    "TIP_LOAD",
    "MeshConvergence",
    "NitscheSweep",
    "PenaltySweep",
    "Run",
    "compare",
    "cone_compliance",
    "cone_contact_force",
    "exact_reference",
    "mesh_convergence",
    "method_runs",
    "nitsche_scene",
    "nitsche_sweep",
    "penalty_sweep",
    "run_label",
    "study_size",
    "sweep_penalties",
]
