"""A bar scene handed over as a user's problem: the chain's K, f, C, g over every node, the
supports as prescribed dofs (held at 0). Solving it as a :class:`~contactqp.Problem` gives the
scene's answer (tests/test_handover.py): the two front ends meet in the same methods."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp.model.chain.layout_names import Layout
from contactqp.model.chain.numbering import layout_of
from contactqp.problem import Problem
from contactqp.scene import Scene, row_names


def problem_from_scene(scene: Scene | Layout) -> Problem:
    """A bar scene as a :class:`~contactqp.Problem`: K over every node (the element
    stiffnesses along the chain), f (the nodal loads, distributed loads lumped as the chain
    lumps them), C and g (a wall's ±1, a bar contact's +1 at node a and −1 at node b: an end
    at a support touches a prescribed dof, whose support then carries the contact's force,
    as the scene's does), the supports as prescribed dofs at 0, the rows named as the scene
    names them, each node's x along its bar as the coordinates (so that the problem's size,
    their extent, is the longest bar, as the scene's); a frictional bed as Tresca friction on
    its bar's nodes (:func:`bed_friction`).

    Parameters
    ----------
    scene : Scene or Layout
        The scene (or its layout).

    Returns
    -------
    Problem
        Its K, f, C, g; ``contactqp.solve(problem)`` gives the scene's answer (a bar held
        by contact alone gives a singular K, which only the QP methods take).

    Raises
    ------
    ProblemError
        Two rows of the scene that are the same constraint (two walls on one side of a node
        with the same gap).
    """
    layout = scene if isinstance(scene, Layout) else layout_of(scene)
    scene = layout.scene
    n, k = layout.n_nodes, layout.link_stiffness  # k: 0 between bars
    diagonal = np.zeros(n)
    diagonal[:-1] += k
    diagonal[1:] += k
    K = sp.csr_array(sp.diags_array([-k, diagonal, -k], offsets=[-1, 0, 1]))
    rows = layout.rows
    C = sp.csr_array((rows.coefficient, (rows.row, rows.node)), shape=(rows.gap.size, n))
    return Problem(K, np.asarray(layout.nodal_loads, dtype=float), C, rows.gap,
                   prescribed=np.sort(layout.support_nodes), names=row_names(scene),
                   units=f"{scene.unit.force}, {scene.unit.length}", name=scene.name,
                   coordinates=np.concatenate([bar.node_x for bar in scene.bars])[:, None],
                   **bed_friction(layout))


def bed_friction(layout: Layout) -> dict:
    """The frictional beds of a scene as a problem's friction: one contact per node of a bar
    on a bed (no normal row), its tangential row reading the node's displacement, its Tresca
    slip bound τ times the node's tributary length (half of each element beside it); {} for
    a scene without a bed."""
    scene = layout.scene
    if not scene.beds:
        return {}
    nodes, bounds = [], []
    for bed in scene.beds:
        lengths = scene.bars[bed.bar].lengths
        tributary = np.zeros(lengths.size + 1)
        tributary[:-1] += lengths / 2.0
        tributary[1:] += lengths / 2.0
        nodes.append(layout.node_offsets[bed.bar] + np.arange(tributary.size))
        bounds.append(float(bed.tau) * tributary)
    node = np.concatenate(nodes)
    T = sp.csr_array((np.ones(node.size), (np.arange(node.size), node)),
                     shape=(node.size, layout.n_nodes))
    return {"T": T, "slip_bound": np.concatenate(bounds)}


__all__ = ["bed_friction", "problem_from_scene"]
